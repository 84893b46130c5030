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

from rplearn.errors import InputError

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


def _square(matrix: FloatArray, param: str) -> FloatArray:
    """``matrix`` as a float64 array, checked to be a square matrix (the LAPACK calls read
    ``n x n`` values from its address).

    Raises
    ------
    InputError
        When it is not two-dimensional and square.
    """
    a = np.asarray(matrix, np.float64)
    if a.ndim != 2 or a.shape[0] != a.shape[1]:
        raise InputError(f"{param}: expected a square matrix, got shape {a.shape}", param=param)
    return a


def _lapack_info(routine: str, info: int) -> int:
    """``info`` of a LAPACK call, raising on an argument error (``info < 0``)."""
    if info < 0:
        raise ValueError(f"{routine}: argument {-info} is invalid")
    return info


def spd_factor(matrix: FloatArray, overwrite: bool = False) -> FloatArray | None:
    """The upper Cholesky factor of a symmetric positive definite matrix.

    Only the upper triangle of ``matrix`` is read (of its Fortran-ordered view: a C-ordered
    matrix is read as its transpose, the same for a symmetric one).

    Parameters
    ----------
    matrix : (n, n) float64 array
        Symmetric; non-finite entries give None (their factor would be meaningless).
    overwrite : bool
        The factor may take ``matrix``'s memory (a C- or Fortran-contiguous float64 matrix
        the caller no longer needs).

    Returns
    -------
    (n, n) float64 array or None
        ``U`` with ``matrix = U^T U``, Fortran-ordered (or a view of the leading rows of a
        taller buffer); its strict lower triangle is left as it was. None when ``matrix`` is
        not positive definite or its factor's diagonal is not finite (LAPACK reports success
        on an infinite diagonal, and some builds on a NaN one).

    Raises
    ------
    InputError
        When ``matrix`` is not square.
    """
    a = _square(matrix, "matrix")
    potrf = _routine("dpotrf")
    if potrf is None:  # scipy's wrapper (holds the interpreter lock)
        from scipy.linalg import lapack

        factor, code = lapack.dpotrf(a.T if a.flags.c_contiguous else a, lower=0, clean=0, overwrite_a=int(bool(overwrite)))
    else:
        factor = _fortran_owned(a, overwrite)
        n = factor.shape[0]
        info = ctypes.c_int(0)
        potrf(b"U", _int(n), factor.ctypes.data, _int(_lda(factor)), ctypes.byref(info))
        code = info.value
    if _lapack_info("dpotrf", code) != 0 or not np.all(np.isfinite(np.diagonal(factor))):
        return None
    return factor


def _factor_view(factor: FloatArray) -> FloatArray:
    """``factor`` (checked square) as a Fortran-ordered float64 matrix or a view of the leading
    rows of one, copied when it is neither."""
    f = _square(factor, "factor")
    if f.strides[0] != f.itemsize or (f.shape[0] > 1 and f.strides[1] < f.shape[0] * f.itemsize):
        f = np.asfortranarray(f)
    return f


def factor_solve(factor: FloatArray, rhs: FloatArray) -> FloatArray:
    """``A^-1 rhs`` from the factor of :func:`spd_factor` (two triangular solves).

    Parameters
    ----------
    factor : (n, n) float64 array
        :func:`spd_factor`'s ``U`` (``A = U^T U``; only its upper triangle is read).
    rhs : (n,) or (n, k) float64 array
        One right-hand side or ``k`` of them as columns.

    Returns
    -------
    float64 array of ``rhs``'s shape
        Fortran-ordered.

    Raises
    ------
    InputError
        When ``factor`` is not square or ``rhs`` has not ``n`` rows (or more than two dimensions).
    """
    f = _factor_view(factor)
    n = f.shape[0]
    b = np.asarray(rhs, np.float64)
    if b.ndim not in (1, 2) or b.shape[0] != n:
        raise InputError(f"rhs: expected {n} rows (one or more columns), got shape {b.shape}", param="rhs")
    potrs = _routine("dpotrs")
    if potrs is None:  # scipy's wrapper
        from scipy.linalg import lapack

        return np.asarray(lapack.dpotrs(f, b, lower=0)[0], np.float64)
    out = np.array(b, np.float64, order="F")
    nrhs = 1 if out.ndim == 1 else out.shape[1]
    info = ctypes.c_int(0)
    potrs(b"U", _int(n), _int(nrhs), f.ctypes.data, _int(_lda(f)), out.ctypes.data, _int(max(n, 1)), ctypes.byref(info))
    _lapack_info("dpotrs", info.value)
    return out


def factor_inverse(factor: FloatArray) -> FloatArray:
    """The whole ``A^-1`` from the factor of :func:`spd_factor` (LAPACK ``potri``).

    Parameters
    ----------
    factor : (n, n) float64 array
        :func:`spd_factor`'s ``U`` (``A = U^T U``; only its upper triangle is read).

    Returns
    -------
    (n, n) float64 array
        Symmetric to the last bit.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the factor is singular (a zero on its diagonal).
    InputError
        When ``factor`` is not square.
    """
    inverse = factor_inverse_upper(factor)
    inverse += inverse.T  # the diagonal twice (exactly: a power of two) ...
    inverse[np.diag_indices_from(inverse)] *= 0.5  # ... and back
    return inverse


def factor_inverse_upper(factor: FloatArray) -> FloatArray:
    """The upper triangle of ``A^-1`` from the factor of :func:`spd_factor` (LAPACK ``potri``),
    zeros below: what :func:`factor_inverse` symmetrises, for sums over the whole inverse read
    off one triangle (:func:`symmetric_inner`) without forming it.

    Parameters
    ----------
    factor : (n, n) float64 array
        :func:`spd_factor`'s ``U`` (``A = U^T U``; only its upper triangle is read).

    Returns
    -------
    (n, n) float64 array
        ``triu(A^-1)``.

    Raises
    ------
    numpy.linalg.LinAlgError
        When the factor is singular (a zero on its diagonal).
    InputError
        When ``factor`` is not square.
    """
    f = _factor_view(factor)
    potri = _routine("dpotri")
    if potri is None:  # scipy's wrapper
        from scipy.linalg import lapack

        upper, code = lapack.dpotri(f, lower=0)
    else:
        upper = _fortran_copy(f)
        n = upper.shape[0]
        info = ctypes.c_int(0)
        potri(b"U", _int(n), upper.ctypes.data, _int(_lda(upper)), ctypes.byref(info))
        code = info.value
    if _lapack_info("dpotri", code) != 0:
        raise np.linalg.LinAlgError(f"dpotri: the factor is singular (info {code})")
    return np.triu(upper)  # the upper triangle of A^-1 (the rest of ``upper`` is the factor's)


def symmetric_inner(upper: FloatArray, matrix: FloatArray) -> float:
    """``sum(S * matrix)`` for the symmetric ``S`` whose upper triangle is ``upper`` (zeros below,
    :func:`factor_inverse_upper`) and a symmetric ``matrix``: ``tr(S matrix)``, from one
    triangle (twice the inner product with ``upper``, less the diagonal counted twice).

    Parameters
    ----------
    upper : (n, n) float64 array
        Upper triangular.
    matrix : (n, n) float64 array
        Symmetric.

    Returns
    -------
    float
    """
    return 2.0 * float(np.vdot(upper, matrix)) - float(np.diagonal(upper) @ np.diagonal(matrix))


#: Largest 1-norm condition number of the scaled KKT matrix a solve accepts (beyond it the
#: samples do not identify the model: :func:`rplearn.core.lsq.solver.solve` raises).
MAX_KKT_CONDITION = 1.0 / (1e3 * np.finfo(np.float64).eps)


def kkt_condition(matrix: FloatArray, constraints: FloatArray, inverse: FloatArray, z_over_s: FloatArray,
                  s_inverse: FloatArray) -> float:
    """The 1-norm condition number of the KKT matrix ``K = [[A, C^T], [C, 0]]`` scaled as
    :func:`rplearn.core.lsq.solver.solve` scales it (rows and columns of ``A`` by
    ``1/sqrt(|diag A|)``), from the blocks of its inverse.

    Parameters
    ----------
    matrix : (n, n) float64 array
        ``A``.
    constraints : (k, n) float64 array
        ``C``.
    inverse : (n, n) float64 array
        The top-left block ``M`` of ``K^-1``.
    z_over_s : (n, k) float64 array
        Its top-right block ``Z S^-1`` (``Z = A^-1 C^T``, ``S = C Z``).
    s_inverse : (k, k) float64 array
        ``S^-1`` (the bottom-right block is ``-S^-1``).

    Returns
    -------
    float
        ``||D K D||_1 ||(D K D)^-1||_1``; infinite when a block is not finite.
    """
    d = 1.0 / np.sqrt(np.maximum(np.abs(np.diag(matrix)), 1e-300))
    cd = np.abs(constraints * d[None, :])
    # the column sums of |D A D| and |D^-1 M D^-1| as d_j (d^T |A|)_j and (d^-1^T |M|)_j / d_j
    # (d > 0): one product each, no scaled copy of either matrix
    norm = max(float((d * (d @ np.abs(matrix)) + cd.sum(axis=0)).max()),
               float(cd.sum(axis=1).max()) if cd.shape[0] else 0.0)
    zs = np.abs(z_over_s / d[:, None])
    inverse_norm = max(float(((1.0 / d) @ np.abs(inverse) / d + zs.sum(axis=1)).max()),
                       float((zs.sum(axis=0) + np.abs(s_inverse).sum(axis=0)).max()) if cd.shape[0] else 0.0)
    condition = norm * inverse_norm
    return condition if np.isfinite(condition) else float("inf")


def constrained_inverse(matrix: FloatArray, constraints: FloatArray, max_condition: float = MAX_KKT_CONDITION) -> FloatArray | None:
    """The top-left block ``M`` of the inverse of the KKT matrix ``[[matrix, C^T], [C, 0]]``.

    ``M = A^-1 - Z (C Z)^-1 Z^T`` with ``Z = A^-1 C^T``, from one Cholesky factor of ``A``.

    Parameters
    ----------
    matrix : (n, n) float64 array
        ``A``, symmetric positive definite.
    constraints : (k, n) float64 array
        ``C``, one row per constraint (any shape of ``k * n`` values; ``k`` may be 0).
    max_condition : float
        The largest condition number of the scaled KKT matrix accepted (:func:`kkt_condition`;
        by default the solve's, :data:`MAX_KKT_CONDITION`).

    Returns
    -------
    (n, n) float64 array or None
        ``M``, symmetric to the last bit. None when ``matrix`` is not positive definite, or
        the KKT matrix is singular or conditioned worse than ``max_condition`` (constraints
        dependent on each other or on ``A``'s null space, or ``A`` itself near singular).

    Raises
    ------
    InputError
        When ``matrix`` is not square.
    """
    a = _square(matrix, "matrix")
    factor = spd_factor(a)
    if factor is None:
        return None
    inverse = factor_inverse(factor)
    c = np.asarray(constraints, np.float64).reshape(-1, inverse.shape[0])
    if not c.shape[0]:
        fine = kkt_condition(a, c, inverse, np.zeros((inverse.shape[0], 0)), np.zeros((0, 0))) <= max_condition
        return inverse if fine else None
    z = inverse @ c.T
    s = c @ z
    s = 0.5 * (s + s.T)
    try:
        correction = z @ np.linalg.solve(s, z.T)
        s_inverse = np.asarray(np.linalg.inv(s), np.float64)
    except np.linalg.LinAlgError:
        return None
    out = inverse - 0.5 * (correction + correction.T)
    if not np.all(np.isfinite(out)) or kkt_condition(a, c, out, z @ s_inverse, s_inverse) > max_condition:
        return None
    return out


__all__ = ["MAX_KKT_CONDITION", "constrained_inverse", "factor_inverse", "factor_inverse_upper", "factor_solve", "kkt_condition",
           "spd_factor", "symmetric_inner"]
