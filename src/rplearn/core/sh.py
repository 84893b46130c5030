"""Real spherical harmonics: the paper's SH-``L`` basis of pattern functions.

:class:`SphericalHarmonics` ``SH-L``: real orthonormal spherical harmonics of degrees
0 .. L-1, ``L**2`` functions (SH-10 = 100), checked against ``scipy.special.sph_harm_y``
(:func:`real_sh_reference`). Computed as ``Q_lm(sin el) cos(el)^(m mod 2) cos|sin(m az)``:
the Legendre factors ``Q_lm`` of all (l, m) by one matrix product of fixed Chebyshev
coefficients (:func:`_sh_chebyshev_tables`) with ``T_j(sin el)``, and ``cos(m az)``,
``sin(m az)`` by Chebyshev recurrences (:func:`_sh_factors`). Up to order
:data:`SH_MOMENTS_MAX_ORDER` the Gram of the features can be rebuilt from a few moments per
sample (:func:`_sh_moment_tables`, :meth:`SphericalHarmonics.gram_from_moments`), which halves
the solver's work. Column order: :func:`sh_index`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn.core.basis_base import SLOT_DESIGN, Basis, FloatArray, checked_coef, chunk_directions, cos_sin_half_angle, flat_angles, matmul_into, scratch
from rplearn.errors import InputError


@check_types
def sh_index(degree: int, order: int) -> int:
    """Column of the real SH of degree ``l`` and order ``m`` (``-l <= m <= l``).

    Within degree ``l`` (columns ``l**2 .. (l+1)**2 - 1``) the order is ``m = 0``, then the
    cosine terms ``m = 1 .. l``, then the sine terms ``m = -1 .. -l``: ``l**2`` for ``m = 0``,
    ``l**2 + m`` for ``m > 0`` and ``l**2 + l - m`` for ``m < 0``. Grouping the cosine and sine
    rows keeps each degree's functions together; the fast computation uses its own
    :attr:`SphericalHarmonics.row_order`.
    """
    if abs(order) > degree:
        raise InputError(f"SH order m = {order} outside -l..l for degree l = {degree}")
    if order == 0:
        return degree * degree
    if order > 0:
        return degree * degree + order
    return degree * degree + degree - order


def real_sh_reference(order: int, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
    """Real SH design matrix built from ``scipy.special.sph_harm_y``, one (l, m) at a time.

    Slow (about 40x :class:`SphericalHarmonics`); the independent reference that tests and
    benchmarks compare the fast computation with. Same functions and column order (:func:`sh_index`).
    """
    from scipy.special import sph_harm_y

    az, el = flat_angles(az_rad, el_rad)
    theta = np.pi / 2 - el
    out = np.empty((az.size, order * order))
    for l in range(order):
        for m in range(-l, l + 1):
            if m == 0:
                v = sph_harm_y(l, 0, theta, az).real
            elif m > 0:
                v = np.sqrt(2) * (-1) ** m * sph_harm_y(l, m, theta, az).real
            else:
                v = np.sqrt(2) * (-1) ** m * sph_harm_y(l, -m, theta, az).imag
            out[:, sh_index(l, m)] = v
    return out


def legendre_factors(order: int, sin_el: ArrayLike) -> FloatArray:
    """The real SH at azimuth 0, ``Q_lm(x) cos(el)^m`` for ``m >= 0``, by the standard recurrence.

    Fully normalised associated Legendre functions of ``x = sin(el)`` (colatitude cosine)
    without the Condon-Shortley phase, times ``sqrt(2)`` for ``m > 0``: the columns
    :func:`sh_index` ``(l, m)``, ``m >= 0``, of :func:`real_sh_reference` at ``az = 0``
    (the ``m < 0`` columns are left zero, as they are there), to rounding. Numpy only, so that
    building a basis does not import ``scipy.special``.
    """
    x = np.asarray(sin_el, np.float64).ravel()
    s = np.sqrt(np.clip((1.0 - x) * (1.0 + x), 0.0, None))
    out = np.zeros((x.size, order * order))
    diag = np.full(x.size, 1.0 / np.sqrt(4.0 * np.pi))
    for m in range(order):
        if m > 0:
            diag = np.sqrt((2.0 * m + 1.0) / (2.0 * m)) * s * diag
        scale = np.sqrt(2.0) if m > 0 else 1.0
        out[:, sh_index(m, m)] = scale * diag
        prev2, prev = np.zeros_like(diag), diag
        for l in range(m + 1, order):
            a = np.sqrt((4.0 * l * l - 1.0) / (l * l - m * m))
            b = np.sqrt(((l - 1.0) ** 2 - m * m) / (4.0 * (l - 1.0) ** 2 - 1.0))
            cur = a * (x * prev - b * prev2)
            out[:, sh_index(l, m)] = scale * cur
            prev2, prev = prev, cur
    return out


@lru_cache(maxsize=32)
def _sh_chebyshev_tables(order: int) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp]]:
    """Chebyshev coefficients of the Legendre factors, and the row order they produce.

    For order ``m`` the real functions are ``Y_lm = Q_lm(x) w_m(az, el)`` with
    ``x = sin(el)``, ``w_m = cos(m az)`` (cosine rows) or ``sin(m az)`` (sine rows), times
    ``cos(el)`` when ``m`` is odd; ``Q_lm`` is then a polynomial of degree < ``order`` (the
    normalised associated Legendre function, with ``sqrt(2)`` folded in for ``m > 0``).
    Its coefficients in Chebyshev polynomials ``T_j(x)`` are found once by interpolation at
    ``order`` Chebyshev points of values from :func:`legendre_factors`. The sum of
    their magnitudes equals ``max |Q_lm|`` (8.2 at SH-10, 32 at SH-24, against
    ``max |Y_lm|`` of 1.2 and 2.4): features stay within 1e-14 (SH-10) to 3e-13 (SH-50) of
    scipy's, but a Gram rebuilt from moments (:meth:`SphericalHarmonics.gram_from_moments`)
    carries that factor squared in its rounding.

    Returns ``(coef, rows, natural)``: ``coef`` of shape (order (order + 1) / 2, order) for
    the ``m >= 0`` rows; ``rows[r]`` the column (:func:`sh_index`) held by row ``r`` of
    :meth:`SphericalHarmonics.design_rows_into`; ``natural`` its inverse permutation.
    """
    L = order
    nodes = np.cos(np.pi * (np.arange(L) + 0.5) / L)  # x = sin(el) at Chebyshev points
    values = legendre_factors(L, nodes)  # az = 0: sine rows vanish
    vander = np.polynomial.chebyshev.chebvander(nodes, L - 1)
    cos_el = np.sqrt((1.0 - nodes) * (1.0 + nodes))
    rows = [sh_index(l, m) for m in range(L) for l in range(m, L)]
    odd = np.array([m % 2 for m in range(L) for _ in range(m, L)], bool)
    q = values[:, rows]
    q[:, odd] /= cos_el[:, None]
    coef = np.asarray(np.linalg.solve(vander, q).T, np.float64)
    rows += [sh_index(l, -m) for m in range(1, L) for l in range(m, L)]
    row_order = np.array(rows, np.intp)
    natural = np.argsort(row_order)
    for shared in (coef, row_order, natural):  # cached and shared by every instance
        shared.setflags(write=False)
    return coef, row_order, natural


@lru_cache(maxsize=32)
def _sh_sum_tables(order: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """For every feature row of :meth:`SphericalHarmonics.design_rows_into`: the row of the
    Chebyshev coefficients of its Legendre factor, and its moment column (``m`` for ``cos(m az)``,
    ``2 order - 1 + m`` for ``sin(m az)``; :meth:`SphericalHarmonics.moment_shape`)."""
    L = order
    m_cos = np.array([m for m in range(L) for _ in range(m, L)], np.intp)
    sine = np.flatnonzero(m_cos > 0)  # the sine rows follow, in the order of their cosine rows
    rows = np.concatenate([np.arange(m_cos.size), sine]).astype(np.intp)
    columns = np.concatenate([m_cos, (2 * L - 1) + m_cos[sine]]).astype(np.intp)
    for shared in (rows, columns):
        shared.setflags(write=False)
    return rows, columns


def _add_moments(cheb: FloatArray, trig: FloatArray, moments: FloatArray,
                 segments: NDArray[np.intp] | tuple[NDArray[np.intp], ...] | None = None) -> None:
    """``moments[...] += cheb @ trig^T`` over the last (sample) axis, per leading sample index;
    with ``segments`` (bounds of consecutive sample ranges), per range: ``moments[..., j, :, :]``
    sums samples ``segments[j]:segments[j + 1]``; with a tuple of bounds, one per sample row,
    ``moments`` is a matching tuple of arrays."""
    if segments is not None:
        for idx in np.ndindex(*cheb.shape[1:-1]):
            c, t = cheb[(slice(None), *idx)], trig[(slice(None), *idx)]
            if isinstance(segments, tuple):  # ranges (and moments) of their own per sample row
                bounds, out = segments[idx[0]], moments[idx[0]]
            else:
                bounds, out = segments, moments[idx]
            for j in np.flatnonzero(np.diff(bounds)):
                a, b = bounds[j], bounds[j + 1]
                out[j] += c[:, a:b] @ t[:, a:b].T
        return
    if cheb.ndim == 2:
        moments += cheb @ trig.T
    elif cheb.ndim == 3:
        for i in range(cheb.shape[1]):
            moments[i] += cheb[:, i] @ trig[:, i].T
    else:
        for idx in np.ndindex(*cheb.shape[1:-1]):
            moments[idx] += cheb[(slice(None), *idx)] @ trig[(slice(None), *idx)].T


def _sh_factors(az_rad: FloatArray, el_rad: FloatArray, n_cheb: int, n_trig: int) -> tuple[FloatArray, FloatArray]:
    """The factors every real SH is made of, in this thread's scratch slots 0 and 1.

    Returns ``cheb`` of shape ``(n_cheb, *shape)``, ``T_j(sin el)``, and ``trig`` of shape
    ``(2 n_trig, *shape)``: ``cos(m az)`` for ``m < n_trig``, then ``sin(m az)``, each times
    ``cos(el)`` when ``m`` is odd. The sines and cosines of the angles come from one tangent
    each (:func:`cos_sin_half_angle`), the rest from Chebyshev recurrences.
    """
    shape = az_rad.shape  # any sample shape: (n,), or (2, n) for both ends of a link at once
    x, cos_el = cos_sin_half_angle(el_rad)[::-1]  # x = sin(el), cos(el) >= 0
    cheb = scratch(0, (n_cheb, *shape))
    cheb[0] = 1.0
    if n_cheb > 1:
        cheb[1] = x
        two_x = 2.0 * x
        for j in range(2, n_cheb):  # T_j = 2 x T_{j-1} - T_{j-2}
            np.multiply(two_x, cheb[j - 1], out=cheb[j])
            cheb[j] -= cheb[j - 2]
    trig = scratch(1, (2 * n_trig, *shape))
    cos_m, sin_m = trig[:n_trig], trig[n_trig:]
    cos_m[0] = 1.0
    sin_m[0] = 0.0
    if n_trig > 1:
        cos_m[1], sin_m[1] = cos_sin_half_angle(az_rad)
        two_cos = 2.0 * cos_m[1]
        for m in range(2, n_trig):  # Chebyshev: c_m = 2 cos(az) c_{m-1} - c_{m-2}
            np.multiply(two_cos, cos_m[m - 1], out=cos_m[m])
            np.multiply(two_cos, sin_m[m - 1], out=sin_m[m])
            cos_m[m] -= cos_m[m - 2]
            sin_m[m] -= sin_m[m - 2]
        cos_m[1::2] *= cos_el
        sin_m[1::2] *= cos_el
    return cheb, trig


#: Highest SH order whose Gram the solver builds from moments (see ``moment_shape``).
SH_MOMENTS_MAX_ORDER = 24


@dataclass(frozen=True)
class _MomentTables:
    """See :func:`_sh_moment_tables`."""

    lam_cols: NDArray[np.intp]  # (pairs * L * L, 4): the moments (plain, then odd-odd) summed into each Lambda entry
    lam_weights: FloatArray  # (pairs * L * L, 4): their weights
    coef_a: FloatArray  # (pairs, L, L) Chebyshev coefficients of the first block, zero-padded
    coef_b_t: FloatArray  # (pairs, L, L) same for the second block, transposed
    dest: NDArray[np.intp]  # flat index in the Gram of every block entry kept
    src: NDArray[np.intp]  # its flat index in the (pairs, L, L) blocks


@lru_cache(maxsize=4)
def _sh_moment_tables(order: int) -> _MomentTables:
    """Tables turning moments into the Gram of the SH features (:meth:`SphericalHarmonics.gram_from_moments`).

    Rows of one order ``m`` and one kind (cosine or sine) form a block sharing the azimuth
    factor ``w_m`` (with ``cos(el)`` for odd ``m``); for blocks ``A <= B`` the Gram block is
    ``C_A Lambda C_B^T`` with ``C`` the rows' Chebyshev coefficients and ``Lambda[j, k]`` the sum
    over samples of ``T_j T_k w_a w_b``. Products reduce to the moments by
    ``T_j T_k = (T_{j+k} + T_{|j-k|}) / 2``, ``cos^2(el) T_J = T_J / 2 - (T_{J+2} + T_{|J-2|}) / 4``
    (both orders odd) and the product-to-sum rules of cosines and sines: ``Lambda`` is a sparse
    linear map of the moments, four terms per entry (gathered and summed: no sparse library).
    """
    L = order
    coef, _, _ = _sh_chebyshev_tables(order)
    n_cos = coef.shape[0]
    n_cheb, n_trig = 2 * L + 1, 2 * L - 1
    n_cols = 2 * n_trig
    n_coef = L * L
    # blocks: (order m, is_sine, first row, number of rows, first row of its coefficients)
    blocks = [(0, False, 0, L, 0)]
    first = L
    for m in range(1, L):
        blocks.append((m, False, first, L - m, first))
        first += L - m
    first_sin = n_cos
    for m in range(1, L):
        coef_row = blocks[m][4]
        blocks.append((m, True, first_sin, L - m, coef_row))
        first_sin += L - m
    c_pad = np.zeros((len(blocks), L, L))
    for i, (_, _, _, rows, coef_row) in enumerate(blocks):
        c_pad[i, :rows] = coef[coef_row : coef_row + rows]
    j, k = np.meshgrid(np.arange(L), np.arange(L), indexing="ij")
    j_sum, j_diff = (j + k).ravel(), np.abs(j - k).ravel()
    pair_a: list[Any] = []
    pair_b, map_cols, map_vals, dest, src = [], [], [], [], []
    for ia, (a, sine_a, first_a, rows_a, _) in enumerate(blocks):
        for ib in range(ia, len(blocks)):
            b, sine_b, first_b, rows_b, _ = blocks[ib]
            sgn = float(np.sign(a - b))
            if not sine_a and not sine_b:  # cos a cos b = (cos(a-b) + cos(a+b)) / 2
                terms = [(1.0, abs(a - b)), (1.0, a + b)]
            elif sine_a and sine_b:  # sin a sin b = (cos(a-b) - cos(a+b)) / 2
                terms = [(1.0, abs(a - b)), (-1.0, a + b)]
            elif sine_a:  # sin a cos b = (sin(a+b) + sin(a-b)) / 2
                terms = [(1.0, n_trig + a + b), (sgn, n_trig + abs(a - b))]
            else:  # cos a sin b = (sin(a+b) - sin(a-b)) / 2
                terms = [(1.0, n_trig + a + b), (-sgn, n_trig + abs(a - b))]
            base = int(a % 2 == 1 and b % 2 == 1) * n_cheb * n_cols
            pair = len(pair_a)
            map_cols.append(np.stack([base + jj * n_cols + col for _, col in terms for jj in (j_sum, j_diff)], axis=1))
            map_vals.append(np.repeat([[w / 4.0 for w, _ in terms for _ in (0, 1)]], L * L, axis=0))
            pair_a.append(ia)
            pair_b.append(ib)
            ra, rb = np.meshgrid(np.arange(rows_a), np.arange(rows_b), indexing="ij")
            dest.append(((first_a + ra) * n_coef + first_b + rb).ravel())
            src.append((pair * L * L + ra * L + rb).ravel())
    return _MomentTables(
        lam_cols=np.concatenate(map_cols).astype(np.intp),
        lam_weights=np.concatenate(map_vals),
        coef_a=c_pad[pair_a],
        coef_b_t=np.ascontiguousarray(c_pad[pair_b].transpose(0, 2, 1)),
        dest=np.concatenate(dest),
        src=np.concatenate(src),
    )


def _sh_series(order: int, coef_rows: FloatArray) -> FloatArray:
    """Chebyshev series in ``sin(el)`` of patterns, one per azimuth factor of :func:`_sh_factors`.

    ``coef_rows`` (k, order**2) in :attr:`SphericalHarmonics.row_order`; returns (k, 2 order,
    order): rows ``m`` (cosine of ``m az``) and ``order + m`` (sine; row ``order`` is zero).
    """
    L = order
    coef, _, _ = _sh_chebyshev_tables(order)
    n_cos = coef.shape[0]
    series = np.zeros((coef_rows.shape[0], 2 * L, L))
    series[:, 0] = coef_rows[:, :L] @ coef[:L]
    r, q = L, n_cos
    for m in range(1, L):
        n = L - m
        series[:, m] = coef_rows[:, r : r + n] @ coef[r : r + n]
        series[:, L + m] = coef_rows[:, q : q + n] @ coef[r : r + n]
        r += n
        q += n
    return series


@check_types
@dataclass(frozen=True)
class SphericalHarmonics(Basis):
    """Real orthonormal spherical harmonics of degrees ``0 .. order-1`` (paper's SH-``order``).

    With colatitude ``theta = pi/2 - el`` and longitude ``phi = az``, and ``Y_l^m`` scipy's
    complex harmonics (Condon-Shortley phase included), the real functions are
    ``Y_l0 = Y_l^0``, ``Y_lm = sqrt(2) (-1)^m Re Y_l^m`` for ``m > 0`` and
    ``Y_lm = sqrt(2) (-1)^m Im Y_l^|m|`` for ``m < 0``; they are orthonormal over the sphere,
    so ``Y_00 = 1 / sqrt(4 pi)`` is the isotropic term.
    """

    order: int = 10
    kind: str = field(default="sh", init=False)
    stacked_samples: bool = field(default=True, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if int(self.order) != self.order or self.order < 1:
            raise InputError(f"SH order must be a positive integer (degrees 0..order-1), got {self.order!r}")

    @property
    def n_coef(self) -> int:
        return self.order * self.order

    @property
    def label(self) -> str:
        return f"SH-{self.order}"

    @property
    def _tables(self) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp]]:
        return _sh_chebyshev_tables(self.order)

    @property
    def degrees(self) -> NDArray[np.intp]:
        """Degree ``l`` of every coefficient (columns ``l**2 .. (l+1)**2 - 1``)."""
        return np.repeat(np.arange(self.order), 2 * np.arange(self.order) + 1)

    def roughness(self, power: float = 2.0) -> FloatArray:
        """``(l (l + 1))^power`` for the coefficient of degree ``l``; 0 for the constant.

        The harmonics are eigenfunctions of the Laplace-Beltrami operator with eigenvalue
        ``-l (l + 1)`` and orthonormal, so ``sum_j w_j c_j^2`` is ``integral |grad f|^2`` over the
        sphere for ``power = 1`` and ``integral (Laplacian f)^2`` for ``power = 2`` (the penalty of
        spherical smoothing splines, Wahba 1981, and the degree-dependent regularisation of
        geodesy's harmonic fits). The mean gain (degree 0) is not penalised, except by plain
        ridge (``power = 0``: every weight 1), which ``fit --prior`` uses to shrink toward a
        reference pattern's absolute level too.
        """
        l = self.degrees.astype(np.float64)
        return (l * (l + 1.0)) ** float(power)

    @property
    def row_order(self) -> NDArray[np.intp]:
        # Grouped by order m: all m = 0 rows, the cosine rows (m = 1, then 2, ...), the sine rows.
        return self._tables[1]

    def design_rows_into(
        self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray, moments: FloatArray | None = None,
        segments: NDArray[np.intp] | tuple[NDArray[np.intp], ...] | None = None,
    ) -> None:
        """Features in :attr:`row_order`; optionally also accumulate the Gram moments.

        ``moments``, of shape ``(*lead, *moment_shape)`` where ``lead`` is every sample axis but
        the last (``()`` for 1-D samples, ``(2,)`` for both ends of a link), receives ``+=``
        the sums over samples that :meth:`gram_from_moments` turns into ``F F^T``. With
        ``segments`` (``k + 1`` increasing bounds from 0 to the number of samples), the moments
        are kept per range of samples: shape ``(*lead, k, *moment_shape)``; or, for samples
        ``(2, n)``, a tuple of two bounds arrays and ``moments`` a tuple of two arrays
        ``(k_i, *moment_shape)``: each row's ranges of its own.
        """
        # All values come from cheap array operations: the sines and cosines of the angles from
        # one tangent each (numpy's float64 tan is vectorised, sin and cos are not: 7x faster),
        # the Legendre factors of all (l, m) from one matrix product with Chebyshev polynomials,
        # and each order's block of rows from one broadcast product with cos or sin(m az).
        L = self.order
        coef, _, _ = self._tables
        n_cheb, n_trig = (L, L) if moments is None else (2 * L + 1, 2 * L - 1)
        cheb, trig = _sh_factors(az_rad, el_rad, n_cheb, n_trig)
        n_cos = coef.shape[0]
        matmul_into(coef, cheb[:L], out[:n_cos])
        cos_m, sin_m = trig[:n_trig], trig[n_trig:]
        r, q = L, n_cos
        for m in range(1, L):
            k = L - m
            np.multiply(out[r : r + k], sin_m[m], out=out[q : q + k])
            out[r : r + k] *= cos_m[m]
            r += k
            q += k
        if moments is not None:
            _add_moments(cheb, trig, moments, segments)

    @property
    def moment_shape(self) -> tuple[int, int] | None:  # type: ignore[override]
        """Shape of the moments :meth:`gram_from_moments` needs (see :meth:`design_rows_into`).

        ``None`` above order :data:`SH_MOMENTS_MAX_ORDER`, whose tables grow as ``8 order**4``
        (45 MB at 24) while a plain rank-k update is then no worse a use of the time.

        ``mu[J, c] = sum_i T_J(sin el_i) cos(el_i)^(M mod 2) cos(M az_i)`` for column ``c = M``
        and the same with ``sin(M az_i)`` for ``c = (2 order - 1) + M``, ``J <= 2 order``,
        ``M <= 2 order - 2``: everything a product of two features can contain.
        """
        if self.order > SH_MOMENTS_MAX_ORDER:
            return None
        return (2 * self.order + 1, 2 * (2 * self.order - 1))

    def gram_from_moments(self, moments: FloatArray) -> FloatArray:
        """``F F^T`` of the features (rows in :attr:`row_order`) from their moments.

        Exact (no quadrature): equal to the Gram of the feature rows up to rounding (4e-15 of
        its largest entry, measured for orders 1-13), at the cost of
        ``(2 order + 1) x (4 order - 2)`` sums per sample instead of ``order**4 / 2``.
        The rounding is larger than a direct sum's: in a two-node SH-10 Gram the exact zero
        eigenvalue (the unidentifiable constant) comes out at 2.6e-15 of the largest against
        1e-16 directly, for 200 thousand or 2 million samples; the solver's rank tolerance
        (``columns x eps`` of the largest eigenvalue, 4.4e-14) is 15 times above it, and 35 to
        100 times at SH-15 to SH-24.
        """
        if self.moment_shape is None:
            raise TypeError(f"{self.label} is above SH-{SH_MOMENTS_MAX_ORDER}: no Gram moments")
        tables = _sh_moment_tables(self.order)
        L = self.order
        mu = np.asarray(moments, np.float64)
        # moments of cos^2(el) T_J (used when both orders are odd), rows J <= 2 L - 2
        mu_odd = np.zeros_like(mu)
        J = np.arange(2 * L - 1)
        mu_odd[: 2 * L - 1] = 0.5 * mu[J] - 0.25 * mu[J + 2] - 0.25 * mu[np.abs(J - 2)]
        every = np.concatenate([mu.ravel(), mu_odd.ravel()])
        lam = np.einsum("ij,ij->i", every[tables.lam_cols], tables.lam_weights).reshape(-1, L, L)
        blocks = tables.coef_a @ lam @ tables.coef_b_t
        flat = np.zeros(self.n_coef * self.n_coef)
        flat[tables.dest] = blocks.ravel()[tables.src]
        gram = flat.reshape(self.n_coef, self.n_coef)
        upper = np.triu(gram)
        return upper + np.triu(gram, 1).T

    def sums_from_moments(self, moments: FloatArray) -> FloatArray:
        """The sums of the features over the samples (``F 1``, rows in :attr:`row_order`) from
        their moments, shape ``(..., n_coef)`` for moments ``(..., *moment_shape)``.

        Exact: a feature is ``sum_J coef[J] T_J(sin el)`` times ``cos(m az)`` or ``sin(m az)``
        (times ``cos(el)`` for odd ``m``), and the moments hold the sums of exactly these
        products (``J < order``, ``M = m``), so a range of samples' feature sums come with its
        Gram moments, from no pass of their own.
        """
        if self.moment_shape is None:
            raise TypeError(f"{self.label} is above SH-{SH_MOMENTS_MAX_ORDER}: no Gram moments")
        coef_rows, columns = _sh_sum_tables(self.order)
        coef = self._tables[0]
        mu = np.asarray(moments, np.float64)[..., : self.order, :][..., columns]  # (..., L, n_coef)
        return np.einsum("...jr,rj->...r", mu, coef[coef_rows])

    def evaluate(self, coef: ArrayLike, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        # A pattern is sum_m [sum_l c_lm Q_lm(x)] w_m: one Chebyshev series per azimuth factor,
        # so 2 order rows per direction are computed instead of order**2 features.
        az, el = flat_angles(az_rad, el_rad)
        c = checked_coef(coef, self.n_coef)
        L = self.order
        lead = c.shape[:-1]
        c_rows = c.reshape(-1, self.n_coef)[:, self.row_order]
        series = _sh_series(self.order, c_rows)  # (k, 2 L, L)
        k = series.shape[0]
        flat = series.reshape(k * 2 * L, L)
        out = np.empty((k, az.size))
        step = chunk_directions(2 * L * k)
        for s in range(0, az.size, step):
            e = min(az.size, s + step)
            cheb, trig = _sh_factors(az[s:e], el[s:e], L, L)
            per_factor = (flat @ cheb).reshape(k, 2 * L, e - s)
            per_factor *= trig
            per_factor.sum(axis=1, out=out[:, s:e])
        return out.reshape(*lead, az.size)

    def design_into(self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray) -> None:
        # Through a reused chunk-sized buffer in row_order, scattered into the natural rows:
        # no temporary as large as ``out``.
        if az_rad.ndim != 1:
            rows = np.empty_like(out)
            self.design_rows_into(az_rad, el_rad, rows)
            out[self.row_order] = rows
            return
        for part, rows in self.feature_chunks(az_rad, el_rad, SLOT_DESIGN):
            out[self.row_order, part] = rows

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "sh", "order": int(self.order)}

    @cached_property
    def sphere_mean(self) -> FloatArray:
        v = np.zeros(self.n_coef)
        v[0] = 1.0 / np.sqrt(4.0 * np.pi)
        return v
