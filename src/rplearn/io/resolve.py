"""One resolver of a command's input and output paths, before any work.

Every input a command reads is named by a *path spec*: a file, a comma-separated list, a glob,
a directory, an fsspec URL, any of them through symbolic links (:mod:`rplearn.io.partitions`).
:func:`input_files` turns the specs into the files they name, each identified by its device
and inode (:func:`rplearn.io.partitions.file_identity`), so that

- the same file named twice in one spec is refused naming both spellings
  (:func:`rplearn.io.partitions.dataset_parts`; :func:`distinct_inputs` for a command's
  repeated flags, such as ``sync --poses``), never read twice;
- every output (``-o``, ``--markdown``, ``--plot``, ``--connectivity``, ...) is checked
  against every file of every input (:func:`check_outputs`, through
  :func:`rplearn._atomic.check_output`), inside every dataset folder, against every glob a table
  output would match (it would join the dataset on the next run), and against the other
  outputs, with the parameter (the flag) that gave it named.
"""

from __future__ import annotations

import fnmatch
import glob
import os
from collections.abc import Iterable, Mapping, Sequence

from rplearn._argtypes import check_types
from rplearn._atomic import check_output
from rplearn.errors import InputError
from rplearn.io.partitions import TABLE_SUFFIXES, dataset_parts, file_identity, is_partitioned, is_url, refuse_repeated

__all__ = ["check_outputs", "distinct_inputs", "input_files"]


def _pieces(spec: str) -> list[str]:
    """The comma-separated pieces of a spec (one piece when the spec is an existing file)."""
    if "," in spec and not os.path.exists(spec):
        return [s.strip() for s in spec.split(",") if s.strip()]
    return [spec]


@check_types
def input_files(specs: Iterable[str | None]) -> list[str]:
    """Every local file and dataset folder the input specs name (see the module docstring).

    A spec that names a dataset in many files gives its folders and its files; a spec that
    cannot be resolved (a file that does not exist yet) is kept as written, so that the
    command that reads it says what is wrong with it. URLs other than ``file://`` are left out
    (an output is a local file).
    """
    found: list[str] = []
    for spec in specs:
        if not spec:
            continue
        spec = os.fspath(spec)
        if not is_partitioned(spec):
            found.append(spec)
            continue
        for piece in _pieces(spec):
            local = piece[len("file://"):] if piece.startswith("file://") else piece
            if is_url(local):
                continue
            if os.path.isdir(local):
                found.append(local)
            try:
                found += [p.path for p in dataset_parts(local)]
            except InputError:
                found.append(local)
    return found


def _globs(specs: Iterable[str | None]) -> list[str]:
    """The local glob pieces of the specs, as absolute patterns."""
    out = []
    for spec in specs:
        if spec and is_partitioned(os.fspath(spec)):
            out += [os.path.abspath(p) for p in _pieces(os.fspath(spec)) if not is_url(p) and glob.has_magic(p)]
    return out


@check_types
def check_outputs(outputs: Mapping[str, str | None], inputs: Iterable[str | None] = ()) -> None:
    """Refuse, before any work, an output that is an input, lies in an input dataset's folder,
    matches an input glob, or is another output; ``outputs`` maps each output's parameter name
    (named in the error, which the command line turns into its flag) to its path (None: not
    written).

    Raises
    ------
    InputError
        One line naming the output, the parameter and the input (or other output).
    """
    specs = [os.fspath(s) for s in inputs if s]
    files = input_files(specs)
    patterns = _globs(specs)
    given: dict[tuple[object, ...], tuple[str, str]] = {}
    for param, path in outputs.items():
        if not path:
            continue
        name = os.fspath(path)
        check_output(name, files, param=param)
        for pattern in patterns if name.lower().endswith(TABLE_SUFFIXES) else ():  # only tables join a dataset
            if fnmatch.fnmatch(os.path.abspath(name), pattern):
                raise InputError(f"{param}: {name} matches {pattern}, a dataset this command reads (the file would join "
                                 "it); write the output elsewhere", param=param)
        key = file_identity(name) if os.path.exists(name) else ("path", os.path.realpath(name))
        if key in given:
            other = given[key][0]
            raise InputError(f"{param}: {name} is also given as {other}; write each to its own file",
                             param=param, related=(other,))
        given[key] = (param, name)


@check_types
def distinct_inputs(paths: Sequence[str], param: str | None = None) -> None:
    """Refuse a file named twice among a command's inputs of one kind (``sync --poses a.tlog
    --poses ./a.tlog``; the files of the dataset specs among them included), naming both
    spellings."""
    files = [p for p in input_files(paths) if not os.path.isdir(p)]
    refuse_repeated(files, ", ".join(paths), param=param)
