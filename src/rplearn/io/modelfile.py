"""The JSON model-file envelope shared by every model type (docs/conventions.md: versioned, no pickle).

A model file is ``{"schema": "rplearn.model", "schema_version": V, "type": T, "sha256": H,
"model": PAYLOAD}`` where ``H`` is the SHA-256 of the canonical JSON of ``PAYLOAD`` (sorted keys,
no spaces), so truncation and tampering are detected. ``T`` is ``"patterns"`` (a
:class:`~rplearn.models.patterns.PatternSet`), ``"mean"`` or ``"knn"`` (baselines).

Large arrays (a k-NN model's training samples, a swarm's covariance) go into a binary sidecar
beside the model file, named in the payload with its SHA-256 (:func:`write_model_with_sidecar`);
such a file is schema version 2, which an rplearn that cannot read sidecars refuses instead of
silently dropping the arrays. Files without a sidecar stay version 1.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn._atomic import atomic_open
from rplearn.errors import ModelFileError
from rplearn.io._npz import check_sidecar_size

MODEL_SCHEMA = "rplearn.model"
MODEL_SCHEMA_VERSION = 1
#: The version of a model file whose payload names a binary sidecar.
SIDECAR_SCHEMA_VERSION = 2
MODEL_TYPES = ("patterns", "mean", "knn")


def _canonical_text(payload: Mapping[str, Any]) -> str:
    """The canonical JSON text of a payload: keys sorted, no spaces, no NaN."""
    return json.dumps(payload, sort_keys=True, separators=(",", ":"), allow_nan=False)


def digest(payload: Mapping[str, Any]) -> str:
    """SHA-256 of the canonical JSON text of a payload."""
    return hashlib.sha256(_canonical_text(payload).encode("utf-8")).hexdigest()


def jsonable(obj: Any) -> Any:
    """Plain JSON values from numpy scalars/arrays and tuples (NaN and inf become None)."""
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        if _finite_floats(obj):
            return list(obj)
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _array_jsonable(obj)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def _finite_floats(values: list[Any] | tuple[Any, ...]) -> bool:
    """Whether every element is a finite Python float (a row of a matrix already turned into a
    list), so that :func:`jsonable` may copy it as it is rather than visit each element."""
    return (bool(values) and all(type(v) is float for v in values)
            and bool(np.isfinite(np.fromiter(values, np.float64, len(values))).all()))


def _array_jsonable(values: np.ndarray) -> Any:
    """:func:`jsonable` of an array without visiting its elements one by one in Python: nested
    lists of plain floats, ints or bools (non-finite floats as None), the same values as the
    element-wise conversion."""
    if values.dtype.kind in "biu":
        return values.tolist()
    if values.dtype.kind == "f":
        finite = np.isfinite(values)
        if finite.all():
            return values.tolist()
        marked = values.astype(object)
        marked[~finite] = None
        return marked.tolist()
    return jsonable(values.tolist())


def reproducible() -> bool:
    """Whether outputs must be reproducible byte for byte (``SOURCE_DATE_EPOCH`` is set, as in
    reproducible builds)."""
    return bool(os.environ.get("SOURCE_DATE_EPOCH"))


@check_types
def write_model_file(path: str | os.PathLike[str], model_type: str, payload: Mapping[str, Any]) -> None:
    """Write a checksummed model file atomically.

    The learning wall time (``training.ltd_s``, the paper's LTD) is part of the checksummed
    payload; when ``SOURCE_DATE_EPOCH`` is set it is left out, so that the same inputs and
    options give a byte-identical file (its provenance time is then that epoch too).
    """
    if model_type not in MODEL_TYPES:
        raise ValueError(f"unknown model type {model_type!r}")
    payload = jsonable(payload)
    if reproducible() and isinstance(payload.get("training"), dict):
        payload["training"].pop("ltd_s", None)
    canonical = _canonical_text(payload)
    head = {
        "schema": MODEL_SCHEMA,
        "schema_version": SIDECAR_SCHEMA_VERSION if "sidecar" in payload else MODEL_SCHEMA_VERSION,
        "type": model_type,
        "sha256": hashlib.sha256(canonical.encode("utf-8")).hexdigest(),
    }
    # the payload's canonical text (the one its checksum is of) is written as it is: encoding a
    # model of a few MB (a covariance) once more, indented, took as long again
    text = json.dumps(head, indent=1)[:-2] + _PAYLOAD_LEAD + canonical + "\n}\n"
    with atomic_open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def _no_constant(name: str) -> Any:
    """JSON has no NaN or Infinity; a model file that holds one was not written by rplearn."""
    raise ValueError(f"{name} is not a JSON number")


@check_types
def read_model_file(path: str | os.PathLike[str]) -> tuple[str, dict[str, Any]]:
    """Read and verify a model file; return ``(type, payload)``.

    Raises
    ------
    ModelFileError
        One line naming the file: missing, not JSON (truncated or corrupt), another schema,
        an unsupported version or type, or a checksum mismatch (modified after writing).
    """
    name = os.fspath(path)
    if not os.path.exists(name):
        raise ModelFileError(f"{name}: no such model file")
    try:
        with open(name, encoding="utf-8") as fh:
            text = fh.read()
        doc = json.loads(text, parse_constant=_no_constant)
    except ValueError as exc:  # JSONDecodeError, UnicodeDecodeError, NaN/Infinity (see _no_constant)
        from rplearn.io.sniff import not_a_model_hint

        hint = not_a_model_hint(name)
        if hint:  # a dataset or a raw log: say what it is, not how its bytes fail to decode
            raise ModelFileError(f"{name}: {hint}") from None
        raise ModelFileError(f"{name}: not a valid JSON model file (truncated or corrupt: {exc})") from None
    except RecursionError:  # json's decoder recurses per nesting level: a file of many '[' is not a model
        raise ModelFileError(f"{name}: not a valid JSON model file (nested too deeply to be one)") from None
    except OSError as exc:
        raise ModelFileError(f"{name}: cannot read ({exc.strerror})") from None
    if not isinstance(doc, dict) or doc.get("schema") != MODEL_SCHEMA:
        raise ModelFileError(f"{name}: not an rplearn model file (field 'schema' must be {MODEL_SCHEMA!r})")
    if doc.get("schema_version") not in (MODEL_SCHEMA_VERSION, SIDECAR_SCHEMA_VERSION):
        raise ModelFileError(
            f"{name}: schema_version {doc.get('schema_version')!r} is not supported (expected {MODEL_SCHEMA_VERSION} "
            f"or {SIDECAR_SCHEMA_VERSION})"
        )
    model_type = doc.get("type", "patterns")
    if model_type not in MODEL_TYPES:
        raise ModelFileError(f"{name}: field 'type' is {model_type!r}; expected one of {', '.join(MODEL_TYPES)}")
    payload = doc.get("model")
    if not isinstance(payload, dict):
        raise ModelFileError(f"{name}: field 'model' is missing")
    if not _written_text_matches(text, doc.get("sha256")) and doc.get("sha256") != digest(payload):
        raise ModelFileError(f"{name}: checksum mismatch: the file was modified after it was written")
    return model_type, payload


#: What :func:`write_model_file` writes between the envelope and the payload's canonical text.
_PAYLOAD_LEAD = ',\n "model": '


def _written_text_matches(text: str, sha256: Any) -> bool:
    """Whether the file's text holds, as :func:`write_model_file` lays it out, a payload text
    whose SHA-256 is ``sha256``: then the payload is the one checksummed, and it need not be
    encoded again to be checked (about as long as writing it: 0.3 s for a covariance of 250,000
    values). Any other layout (a file re-indented by hand) is checked through :func:`digest`."""
    start = text.find(_PAYLOAD_LEAD)
    if not isinstance(sha256, str) or start < 0 or not text.endswith("\n}\n"):
        return False
    body = text[start + len(_PAYLOAD_LEAD):-3]
    return hashlib.sha256(body.encode("utf-8")).hexdigest() == sha256




#: A model file's binary sidecar is named after it and the start of its own SHA-256
#: (``m.json`` -> ``m.json.<12 hex digits>.npz``), so that a new save never overwrites the
#: sidecar the previous model file still names. A save removes no other file than the sidecar
#: the model file it replaces names under that very name (:func:`owned_sidecar`): never a
#: user's ``m.json.npz`` or ``m.json.0123456789ab.npz`` that no model file names.
SIDECAR_SUFFIX = ".npz"


def sidecar_path(path: str | os.PathLike[str], sha256: str) -> str:
    """The binary sidecar of model file ``path`` whose contents have this SHA-256."""
    return f"{os.fspath(path)}.{sha256[:12]}{SIDECAR_SUFFIX}"


def named_sidecar(path: str | os.PathLike[str]) -> str | None:
    """The sidecar a model file names (its path), or None."""
    _, payload = read_model_file(path)
    entry = payload.get("sidecar")
    if not isinstance(entry, Mapping) or not isinstance(entry.get("file"), str):
        return None
    return os.path.join(os.path.dirname(os.path.abspath(os.fspath(path))), entry["file"])


def owned_sidecar(path: str | os.PathLike[str]) -> str | None:
    """The sidecar that the model file at ``path`` owns: the one its (checksummed) envelope names,
    under the name a save gives it (``<file>.<its sha256[:12]>.npz`` beside it); None when there
    is no such file, or ``path`` is no readable model file (then no file is anyone's to remove)."""
    try:
        _, payload = read_model_file(path)
    except (ModelFileError, OSError):
        return None
    entry = payload.get("sidecar")
    if not isinstance(entry, Mapping) or not isinstance(entry.get("sha256"), str) or not isinstance(entry.get("file"), str):
        return None
    expected = os.path.basename(sidecar_path(os.path.basename(os.fspath(path)), entry["sha256"]))
    if entry["file"] != expected or not re.fullmatch(r"[0-9a-f]{64}", entry["sha256"]):
        return None
    return os.path.join(os.path.dirname(os.path.abspath(os.fspath(path))), expected)


def _file_sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _write_sidecar(path: str, arrays: Mapping[str, np.ndarray]) -> tuple[str, str]:
    """Write the arrays beside model file ``path`` into a new hidden temporary file, as an
    uncompressed ``.npz`` of plain numeric arrays (numpy's format, no pickle); return the
    temporary file and its SHA-256 (the name it is given: :func:`sidecar_path`)."""
    import tempfile
    import zipfile

    for key, value in arrays.items():
        if np.asarray(value).dtype.kind not in "fiub":
            raise ValueError(f"sidecar array {key!r} is not numeric")
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as raw:
            # numpy's .npz layout, written here with a fixed time stamp per entry (np.savez
            # stamps the current time), so that the same model gives the same bytes and name
            with zipfile.ZipFile(raw, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
                for key, value in arrays.items():
                    info = zipfile.ZipInfo(f"{key}.npy", date_time=(1980, 1, 1, 0, 0, 0))
                    with zf.open(info, "w", force_zip64=True) as fh:
                        np.lib.format.write_array(fh, np.ascontiguousarray(value), allow_pickle=False)
            raw.flush()
            os.fsync(raw.fileno())
        os.chmod(tmp, 0o644)
        return tmp, _file_sha256(tmp)
    except BaseException:
        _remove(tmp)
        raise


def _remove(path: str | None) -> None:
    """Remove a file if it is there (another save may have removed it first)."""
    if path is None:
        return
    try:
        os.remove(path)
    except OSError:
        pass


@contextmanager
def _folder_lock(folder: str) -> Iterator[None]:
    """Hold an exclusive advisory lock (``flock``) on a folder: saves of model files into one
    folder replace a model file and its sidecars one at a time, so that concurrent saves to
    one path leave one whole model with its own sidecar. No lock file is created (the folder
    itself is locked); where ``flock`` is missing (Windows) or refused, saves go unlocked."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        yield
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            pass
        yield
    finally:
        os.close(fd)  # releases the lock


def _sidecars_beside(path: str) -> bool:
    """Whether the folder of model file ``path`` holds a file named as a sidecar of it
    (:func:`sidecar_path`: ``<file>.<12 hex digits>.npz``)."""
    folder, base = os.path.split(os.path.abspath(path))
    pattern = re.compile(re.escape(base) + r"\.[0-9a-f]{12}" + re.escape(SIDECAR_SUFFIX))
    try:
        with os.scandir(folder) as entries:
            return any(pattern.fullmatch(e.name) for e in entries)
    except OSError:
        return True  # not listable: read the model file as before


def write_model_with_sidecar(path: str | os.PathLike[str], model_type: str, payload: Mapping[str, Any],
                             arrays: Mapping[str, np.ndarray] | None) -> None:
    """Write a model file and, when ``arrays`` are given, its binary sidecar, so that a failure
    at any point leaves the previous model file and the sidecar it names intact, and a save
    removes no file but the sidecar of the model file it replaces.

    The output is checked first and the sidecar written to a temporary file (the long part);
    then, holding the folder's lock (:func:`_folder_lock`), the sidecar the current model file
    owns is noted (:func:`owned_sidecar`), the new sidecar gets its content-addressed name,
    the model file naming it is replaced atomically, and only then is the noted sidecar
    removed (unless it is the new one).
    """
    from rplearn._atomic import check_output

    name = check_output(path)
    folder = os.path.dirname(os.path.abspath(name))
    payload = dict(payload)
    tmp: str | None = None
    try:
        if arrays:
            tmp, checksum = _write_sidecar(name, arrays)
        with _folder_lock(folder):
            # the current model file is read (verified whole) only where a sidecar of it may be:
            # without a new sidecar and with none beside it, there is nothing to keep or remove
            previous = owned_sidecar(name) if tmp is not None or _sidecars_beside(name) else None
            target = None
            if tmp is not None:
                target = os.path.abspath(sidecar_path(name, checksum))  # as owned_sidecar spells it
                os.replace(tmp, target)
                tmp = None
                payload["sidecar"] = {"file": os.path.basename(target), "sha256": checksum}
            try:
                write_model_file(name, model_type, payload)
            except BaseException:
                if target is not None and target != previous:  # the new sidecar belongs to no model file
                    _remove(target)
                raise
            if previous is not None and previous != target:
                _remove(previous)
    finally:
        _remove(tmp)


def read_sidecar(model_path: str | os.PathLike[str], entry: Any) -> dict[str, np.ndarray]:
    """The arrays of a model file's sidecar, checked against the checksum its payload records.

    Raises
    ------
    ModelFileError
        Naming the sidecar: a malformed entry (a name that is not a file beside the model), a
        missing, truncated, tampered or non-numeric file.
    """
    name = os.fspath(model_path)
    if not isinstance(entry, Mapping) or not isinstance(entry.get("file"), str) or not isinstance(entry.get("sha256"), str):
        raise ModelFileError(f"{name}: field 'sidecar' must give 'file' and 'sha256'")
    if not os.path.isfile(name):
        raise ModelFileError(f"{name}: the model keeps arrays in a sidecar ({entry['file']}); read it from its file "
                             "(load_model(path), or from_dict(payload, source=path))")
    file = entry["file"]
    if os.path.basename(file) != file or file in ("", ".", ".."):
        raise ModelFileError(f"{name}: sidecar {file!r} must be a file name beside the model file")
    side = os.path.join(os.path.dirname(os.path.abspath(name)), file)
    if not os.path.isfile(side):
        raise ModelFileError(f"{side}: the model file's sidecar is missing (keep {file} beside {os.path.basename(name)})")
    if _file_sha256(side) != entry["sha256"]:
        raise ModelFileError(f"{side}: checksum mismatch: the sidecar was modified or does not belong to {name}")
    check_sidecar_size(side)  # what its arrays declare, before numpy allocates it
    try:
        with np.load(side, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (ValueError, OSError, EOFError) as exc:
        raise ModelFileError(f"{side}: not a readable sidecar ({exc})") from None
    for k, v in arrays.items():
        if v.dtype.kind not in "fiub":
            raise ModelFileError(f"{side}: array {k!r} is not numeric")
    return arrays
