"""Cholesky factors of a regularised normal matrix, for the order selection and the posteriors it reads.

The selection (:mod:`rplearn.core.lsq.selection`) solves the penalised normal equations of every
fold at many points, reads the variance inflation of a few from their inverses, and the
automatic fit reads posterior covariances at other smoothings (the near ties' own-pattern
posterior, the capped prior). All of it is one factor ``A = U^T U`` of a symmetric positive
definite matrix and then:

- :func:`factor_solve`: ``A^-1 b`` (two triangular solves);
- :func:`factor_inverse`: the whole ``A^-1`` from the factor (LAPACK ``potri``: a third of the
  work of an LU inverse, which ``numpy.linalg.inv`` does, and no second factorisation);
- :func:`constrained_inverse`: the top-left block of the inverse of the KKT matrix
  ``[[A, C^T], [C, 0]]`` (linear equality constraints, the gauge), ``A^-1 - Z (C Z)^-1 Z^T`` with
  ``Z = A^-1 C^T``: what :func:`rplearn.core.lsq.solver.solve` inverts the whole KKT matrix for.

They call scipy's LAPACK (numpy has no triangular solves) through the function pointers of
``scipy.linalg.cython_lapack`` with ``ctypes``, which lets go of the interpreter lock during the
call, so that the selection's folds are factorised on the statistics' two workers at once
(scipy's Python wrappers hold the lock: two threads then take turns). Where those pointers
cannot be had, scipy's wrappers do the same work. Callers keep them on one BLAS thread
(:func:`rplearn.core.threads.one_blas_thread`): an OpenBLAS pool of scipy's left spinning after a
call slows numpy's next factorisation on a 2-core machine. ``numpy.linalg.cholesky`` was also
slower on the sizes of these problems (measured on this kind of machine with one thread: 4.4 ms
against 2.1 ms at 512 columns, where the leading dimension is a power of two, 1.2 against 1.0 ms
at 450).
"""

from __future__ import annotations

import ctypes
import re
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

_INT = ctypes.POINTER(ctypes.c_int)
_DOUBLES = ctypes.c_void_p  # a double array's address
#: Argument types of the LAPACK routines used (Fortran calling convention: every argument by
#: reference) and their C signatures as scipy's capsules name them (``d``: double).
_SIGNATURES: dict[str, tuple[tuple[Any, ...], bytes]] = {
    "dpotrf": ((ctypes.c_char_p, _INT, _DOUBLES, _INT, _INT), b"void (char *, int *, d *, int *, int *)"),
    "dpotri": ((ctypes.c_char_p, _INT, _DOUBLES, _INT, _INT), b"void (char *, int *, d *, int *, int *)"),
    "dpotrs": ((ctypes.c_char_p, _INT, _INT, _DOUBLES, _INT, _DOUBLES, _INT, _INT),
               b"void (char *, int *, int *, d *, int *, d *, int *, int *)"),
}
#: Cython's name for scipy's ``d`` (double) type in a capsule's signature, or plain ``double``.
_DOUBLE_NAME = re.compile(rb"(?:__pyx_t_\w*_d|double) \*")
# local prototypes of the C API (setting restype/argtypes on ``ctypes.pythonapi``'s functions
# would change them for the whole process)
_capsule_name = ctypes.PYFUNCTYPE(ctypes.c_char_p, ctypes.py_object)(("PyCapsule_GetName", ctypes.pythonapi))
_capsule_pointer = ctypes.PYFUNCTYPE(ctypes.c_void_p, ctypes.py_object, ctypes.c_char_p)(
    ("PyCapsule_GetPointer", ctypes.pythonapi))


def _capsule_signature(name: bytes | None) -> bytes | None:
    """A capsule's C signature with Cython's double type written ``d`` (None stays None)."""
    return None if name is None else _DOUBLE_NAME.sub(b"d *", name)


@cache
def _routine(name: str) -> Any:
    """The LAPACK routine ``name`` of scipy's ``cython_lapack`` as a ctypes function that releases
    the interpreter lock while it runs, or None when it cannot be had.

    Parameters
    ----------
    name : str
        A key of :data:`_SIGNATURES` (``dpotrf``, ``dpotri`` or ``dpotrs``).

    Returns
    -------
    callable or None
        None also when the capsule's signature is not the one expected (another integer
        width, e.g. an ILP64 build: the callers then use scipy's wrappers).
    """
    argtypes, expected = _SIGNATURES[name]
    try:
        from scipy.linalg import cython_lapack

        capsule = cython_lapack.__pyx_capi__[name]
        signature = _capsule_name(capsule)
        if _capsule_signature(signature) != expected:
            return None
        address = _capsule_pointer(capsule, signature)
    except (ImportError, AttributeError, KeyError, ValueError):  # pragma: no cover - another scipy build
        return None
    return ctypes.CFUNCTYPE(None, *argtypes)(address) if address else None


def _int(value: int) -> Any:
    """A reference to a C ``int`` holding ``value`` (a Fortran argument, passed by reference).

    Parameters
    ----------
    value : int

    Returns
    -------
    ctypes reference
        Valid for the call it is passed to.
    """
    return ctypes.byref(ctypes.c_int(int(value)))


#: Columns whose multiples make the leading dimension a power-of-two stride in memory, where
#: the factorisation's column accesses collide in the cache (512 columns, SH-15 of two nodes:
#: 2.1 ms against 1.5 ms at 510 or 514): such matrices are factorised in a buffer with
#: :data:`_PAD` rows more.
_ALIASED = 64
_PAD = 8


def _lda(a: FloatArray) -> int:
    """The leading dimension of a Fortran-ordered matrix or a view of its leading rows."""
    return max(int(a.strides[1]) // a.itemsize if a.shape[1] > 1 else a.shape[0], 1)


def _fortran_owned(matrix: FloatArray, overwrite: bool) -> FloatArray:
    """``matrix`` (square, symmetric: a C-ordered one is its own transpose) as a writable
    Fortran-ordered float64 array (or a view of the leading rows of one, :data:`_ALIASED`):
    itself when ``overwrite`` allows and its memory serves, else a copy."""
    a = np.asarray(matrix, np.float64)
    fortran = a.T if a.flags.c_contiguous else a
    n = fortran.shape[0]
    if overwrite and fortran.flags.f_contiguous and fortran.flags.writeable and not (n >= _ALIASED and n % _ALIASED == 0):
        return fortran
    return _fortran_copy(fortran)


def _fortran_copy(matrix: FloatArray) -> FloatArray:
    """A Fortran-ordered copy of a square ``matrix``, in a buffer :data:`_PAD` rows taller when
    its size is a multiple of :data:`_ALIASED` (the copy is then a view of the buffer's leading rows)."""
    n = matrix.shape[0]
    if n >= _ALIASED and n % _ALIASED == 0:
        view = np.empty((n + _PAD, n), order="F")[:n]
        view[...] = matrix
        return view
    return np.array(matrix, np.float64, order="F")


def spd_factor(matrix: FloatArray, overwrite: bool = False) -> FloatArray | None:
    """The upper Cholesky factor ``U`` (``matrix = U^T U``, Fortran-ordered; the strict lower
    triangle is left as it was) of a symmetric positive definite ``matrix``, or None when it is
    not positive definite. Only one triangle of ``matrix`` is read. ``overwrite``: the factor
    may take ``matrix``'s memory (a C- or Fortran-contiguous float64 matrix the caller no longer needs).
    """
    potrf = _routine("dpotrf")
    if potrf is None:  # pragma: no cover - scipy's wrapper (holds the interpreter lock)
        from scipy.linalg import lapack

        a = np.asarray(matrix, np.float64)
        factor, info = lapack.dpotrf(a.T if a.flags.c_contiguous else a, lower=0, clean=0, overwrite_a=int(bool(overwrite)))
        return factor if info == 0 else None
    factor = _fortran_owned(matrix, overwrite)
    n = factor.shape[0]
    info = ctypes.c_int(0)
    potrf(b"U", _int(n), factor.ctypes.data, _int(_lda(factor)), ctypes.byref(info))
    return factor if info.value == 0 else None


def factor_solve(factor: FloatArray, rhs: FloatArray) -> FloatArray:
    """``A^-1 rhs`` from the factor of :func:`spd_factor` (one vector or the columns of a matrix)."""
    potrs = _routine("dpotrs")
    if potrs is None:  # pragma: no cover - scipy's wrapper
        from scipy.linalg import lapack

        return np.asarray(lapack.dpotrs(factor, rhs, lower=0)[0], np.float64)
    f = np.asarray(factor, np.float64)
    if f.strides[0] != f.itemsize:  # not (a view of the leading rows of) a Fortran-ordered matrix
        f = np.asfortranarray(f)
    out = np.array(rhs, np.float64, order="F", ndmin=1)
    n = f.shape[0]
    nrhs = 1 if out.ndim == 1 else out.shape[1]
    info = ctypes.c_int(0)
    potrs(b"U", _int(n), _int(nrhs), f.ctypes.data, _int(_lda(f)), out.ctypes.data, _int(max(n, 1)), ctypes.byref(info))
    if info.value != 0:  # pragma: no cover - only on an argument error
        raise ValueError(f"dpotrs: argument {-info.value} is invalid")
    return out


def factor_inverse(factor: FloatArray) -> FloatArray:
    """The whole ``A^-1`` (symmetric to the last bit) from the factor of :func:`spd_factor`."""
    potri = _routine("dpotri")
    if potri is None:  # pragma: no cover - scipy's wrapper
        from scipy.linalg import lapack

        upper, code = lapack.dpotri(factor, lower=0)
    else:
        upper = _fortran_copy(np.asarray(factor, np.float64))
        n = upper.shape[0]
        info = ctypes.c_int(0)
        potri(b"U", _int(n), upper.ctypes.data, _int(_lda(upper)), ctypes.byref(info))
        code = info.value
    if code != 0:
        raise np.linalg.LinAlgError(f"dpotri: the factor is singular (info {code})")
    inverse = np.triu(upper)  # the upper triangle of A^-1 (the rest of ``upper`` is the factor's)
    inverse += inverse.T  # the diagonal twice (exactly: a power of two) ...
    inverse[np.diag_indices_from(inverse)] *= 0.5  # ... and back
    return inverse


def constrained_inverse(matrix: FloatArray, constraints: FloatArray) -> FloatArray | None:
    """The top-left block ``M`` of the inverse of ``[[matrix, C^T], [C, 0]]`` (``C`` =
    ``constraints``, one row per constraint, of full row rank): ``A^-1 - Z (C Z)^-1 Z^T`` with
    ``Z = A^-1 C^T``, symmetric to the last bit; None when ``matrix`` is not positive definite
    (or the constraints are dependent on it)."""
    factor = spd_factor(matrix)
    if factor is None:
        return None
    inverse = factor_inverse(factor)
    c = np.asarray(constraints, np.float64).reshape(-1, inverse.shape[0])
    if not c.shape[0]:
        return inverse
    z = inverse @ c.T
    s = c @ z
    s = 0.5 * (s + s.T)
    try:
        correction = z @ np.linalg.solve(s, z.T)
    except np.linalg.LinAlgError:
        return None
    out = inverse - 0.5 * (correction + correction.T)
    return out if np.all(np.isfinite(out)) else None


__all__ = ["constrained_inverse", "factor_inverse", "factor_solve", "spd_factor"]
