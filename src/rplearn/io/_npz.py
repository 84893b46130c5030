"""Reading a model's ``.npz`` sidecar only after checking what its arrays declare (for
:func:`rplearn.io.modelfile.read_sidecar`).

Each member of an ``.npz`` is a ``.npy`` file whose header declares a dtype and a shape; numpy
allocates what the header declares before it reads a byte of data, so a header declaring 6.4 GB
in a file of a few kilobytes is an ``_ArrayMemoryError`` (or minutes of swapping). Here every
header is read first: a numeric dtype, a shape whose bytes the member really holds (sidecars are
stored uncompressed), and the total within the work budget (:mod:`rplearn._budget`), else one
:class:`~rplearn.errors.ModelFileError` naming the file and the array.
"""

from __future__ import annotations

import math
import zipfile

import numpy as np

from rplearn._budget import Cost, check_work
from rplearn.errors import InputError, ModelFileError

#: Reading a sidecar: bytes in memory per byte declared, and seconds per byte (disk and checks).
LOAD_BYTES_PER_BYTE, LOAD_S_PER_BYTE = 1.0, 2e-9


def declared_bytes(side: str) -> dict[str, int]:
    """Bytes each array of the sidecar ``side`` declares, checked against what its member holds."""
    out: dict[str, int] = {}
    try:
        with zipfile.ZipFile(side) as zf:
            for info in zf.infolist():
                key = info.filename[:-4] if info.filename.endswith(".npy") else info.filename
                with zf.open(info) as fh:
                    version = np.lib.format.read_magic(fh)
                    if version == (1, 0):
                        shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
                    else:
                        shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
                    header = fh.tell()
                if dtype.kind not in "fiub" or dtype.hasobject:
                    raise ModelFileError(f"{side}: array {key!r} is not numeric")
                need = math.prod(int(n) for n in shape) * dtype.itemsize
                if need > info.file_size - header:
                    raise ModelFileError(
                        f"{side}: array {key!r} declares {need:,} bytes of shape {tuple(shape)} but holds "
                        f"{max(info.file_size - header, 0):,}: the sidecar is corrupt or was altered"
                    )
                out[key] = need
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise ModelFileError(f"{side}: not a readable sidecar ({exc})") from None
    return out


def check_sidecar_size(side: str) -> None:
    """Refuse a sidecar whose arrays declare more than they hold or than the work budget allows."""
    total = sum(declared_bytes(side).values())
    try:
        check_work(side, total, lambda n: Cost(memory_bytes=LOAD_BYTES_PER_BYTE * n, seconds=LOAD_S_PER_BYTE * n), "bytes of arrays", bounds=(0, total))
    except InputError as exc:
        raise ModelFileError(str(exc)) from None


__all__ = ["check_sidecar_size", "declared_bytes"]
