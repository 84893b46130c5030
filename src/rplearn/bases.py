"""Basis families turning directions (azimuth, elevation) into design-matrix blocks (paper Sec. IV-B to IV-E).

A radiation pattern is a linear combination ``G(az, el) = sum_i p_i f_i(az, el)`` [dBi]. Three
families are offered, sized as the paper labels them (DESIGN.md, "model sizes", counted per antenna):

- :class:`SphericalHarmonics` ``SH-L``: real orthonormal spherical harmonics of degrees
  0 .. L-1, ``L**2`` functions (SH-10 = 100). Computed by the standard stable three-term
  recurrence of fully normalised associated Legendre functions (no Condon-Shortley phase in
  the real functions) and Chebyshev recurrences for ``cos(m az)``, ``sin(m az)``.
- :class:`BasisGrid` ``BG-k``: Gaussian kernels of the great-circle angle ``theta`` to grid nodes,
  ``exp(-theta**2 / (2 sigma))`` exactly as the paper writes it (``2 sigma``, not ``2 sigma**2``),
  so ``sigma`` [rad^2] is the *variance* of the kernel in great-circle angle and
  ``sqrt(sigma)`` [rad] its angular standard deviation. Nodes lie on the paper's
  ``k`` elevations x ``2k`` azimuths cell-centred grid (BG-7 = 98), or on an equal-area
  Fibonacci lattice with the same count (the paper notes its grid over-represents the poles).
- :class:`Polynomial` ``P-k``: all monomials ``az**i el**j`` with ``i + j <= k``
  (``(k+1)(k+2)/2``; P-12 = 91). By default the same function space is spanned by products of
  Legendre polynomials ``P_i(az/pi) P_j(el/(pi/2))`` with ``i + j <= k``, which predicts the
  same but is far better conditioned; ``polynomial="monomial"`` gives the literal monomials.

Every basis writes its features into a caller-supplied buffer of shape ``(n_coef, n)``
(one row per function) so the solver can accumulate ``X^T X`` without copies.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn.errors import InputError, ModelFileError

FloatArray = NDArray[np.float64]


def _angles(az_rad: ArrayLike, el_rad: ArrayLike) -> tuple[FloatArray, FloatArray]:
    az = np.ascontiguousarray(az_rad, dtype=np.float64).ravel()
    el = np.ascontiguousarray(el_rad, dtype=np.float64).ravel()
    if az.shape != el.shape:
        raise InputError(f"azimuth and elevation differ in length ({az.size} vs {el.size})")
    return az, el


class Basis:
    """A family of functions on the sphere of directions; subclasses define the functions."""

    kind: str = ""
    #: True when :meth:`design_into` accepts samples of any shape, e.g. ``(2, n)`` for both ends
    #: of a link, writing ``out[:, ...]`` of shape ``(n_coef, *shape)``.
    stacked_samples: bool = False

    @property
    def n_coef(self) -> int:  # pragma: no cover - overridden
        raise NotImplementedError

    @property
    def label(self) -> str:  # pragma: no cover - overridden
        raise NotImplementedError

    def design_into(self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray) -> None:
        """Write features of ``n`` directions into ``out`` of shape ``(n_coef, n)``."""
        raise NotImplementedError  # pragma: no cover

    def design_t(self, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Transposed design block, shape ``(n_coef, n)`` (rows are basis functions)."""
        az, el = _angles(az_rad, el_rad)
        out = np.empty((self.n_coef, az.size))
        self.design_into(az, el, out)
        return out

    def design(self, az_rad: ArrayLike, el_rad: ArrayLike) -> FloatArray:
        """Design block ``X`` of shape ``(n, n_coef)``: ``X[i, j] = f_j(az_i, el_i)``."""
        return self.design_t(az_rad, el_rad).T

    def to_dict(self) -> dict[str, Any]:  # pragma: no cover - overridden
        raise NotImplementedError

    @cached_property
    def sphere_mean(self) -> FloatArray:
        """Area-weighted mean of every basis function over the sphere, shape ``(n_coef,)``.

        Computed by Gauss-Legendre quadrature in ``sin(el)`` and a uniform azimuth rule
        (exact for SH far beyond the degrees used here).
        """
        n_el, n_az = 96, 192
        x, w = np.polynomial.legendre.leggauss(n_el)  # x = sin(el), weights sum to 2
        el = np.arcsin(x)
        az = -np.pi + (np.arange(n_az) + 0.5) * (2 * np.pi / n_az)
        azg, elg = np.meshgrid(az, el)
        weights = np.repeat(w, n_az) / (2.0 * n_az)
        return self.design_t(azg.ravel(), elg.ravel()) @ weights


# -------------------------------------------------------------------------------------------
# Spherical harmonics


def sh_index(degree: int, order: int) -> int:
    """Column of the real SH of degree ``l`` and order ``m`` (``-l <= m <= l``).

    Within degree ``l`` (columns ``l**2 .. (l+1)**2 - 1``) the order is ``m = 0``, then the
    cosine terms ``m = 1 .. l``, then the sine terms ``m = -1 .. -l``: ``l**2`` for ``m = 0``,
    ``l**2 + m`` for ``m > 0`` and ``l**2 + l - m`` for ``m < 0``. Grouping the cosine and sine
    rows lets the recurrence fill a whole degree with two array operations.
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
    benchmarks compare the recurrence with. Same functions and column order (:func:`sh_index`).
    """
    from scipy.special import sph_harm_y

    az, el = _angles(az_rad, el_rad)
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

    @cached_property
    def _coefs(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        L = self.order
        a = np.zeros((L, L))
        b = np.zeros((L, L))
        for m in range(L):
            for l in range(m + 2, L):
                a[l, m] = np.sqrt((4.0 * l * l - 1.0) / (l * l - m * m))
                b[l, m] = np.sqrt(((l - 1.0) ** 2 - m * m) / (4.0 * (l - 1.0) ** 2 - 1.0))
        mm = np.array([np.sqrt((2.0 * m + 1.0) / (2.0 * m)) if m > 0 else 0.0 for m in range(L)])
        return a, b, mm

    def design_into(self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray) -> None:
        # Vectorised over the order m: for every degree l the fully normalised associated
        # Legendre values of all m <= l come from those of l-1 and l-2 by the three-term
        # recurrence (m <= l-2) and the two diagonal steps (m = l-1, m = l), all in a few
        # array operations; the degree's cosine and sine rows are then written in one go each.
        L = self.order
        a, b, mm = self._coefs
        n = az_rad.shape  # any sample shape: (n,), or (2, n) for both ends of a link at once
        col = (slice(None),) + (None,) * len(n)  # broadcast a per-order coefficient over samples
        x = np.sin(el_rad)  # cos(colatitude)
        s = np.cos(el_rad)  # sin(colatitude) >= 0
        cos_m = np.empty((L, *n))  # sqrt(2) cos(m az)
        sin_m = np.empty((L, *n))  # sqrt(2) sin(m az)
        sqrt2 = np.sqrt(2.0)
        cos_m[0] = sqrt2
        sin_m[0] = 0.0
        if L > 1:
            np.cos(az_rad, out=cos_m[1])
            np.sin(az_rad, out=sin_m[1])
            two_cos = 2.0 * cos_m[1]
            cos_m[1] *= sqrt2
            sin_m[1] *= sqrt2
            for m in range(2, L):  # Chebyshev: c_m = 2 cos(az) c_{m-1} - c_{m-2}
                np.multiply(two_cos, cos_m[m - 1], out=cos_m[m])
                cos_m[m] -= cos_m[m - 2]
                np.multiply(two_cos, sin_m[m - 1], out=sin_m[m])
                sin_m[m] -= sin_m[m - 2]
        p_lm2 = np.empty((L, *n))
        p_lm1 = np.empty((L, *n))
        p_l = np.empty((L, *n))
        p_lm1[0] = 1.0 / np.sqrt(4.0 * np.pi)
        out[0] = p_lm1[0]
        for l in range(1, L):
            k = l - 1
            if k > 0:
                np.multiply(p_lm1[:k], x, out=p_l[:k])
                p_lm2[:k] *= b[l, :k][col]  # l-2 values are not needed after this step
                p_l[:k] -= p_lm2[:k]
                p_l[:k] *= a[l, :k][col]
            np.multiply(p_lm1[k], x, out=p_l[k])
            p_l[k] *= np.sqrt(2.0 * l + 1.0)
            np.multiply(p_lm1[k], s, out=p_l[l])
            p_l[l] *= mm[l]
            base = l * l
            out[base] = p_l[0]
            np.multiply(p_l[1 : l + 1], cos_m[1 : l + 1], out=out[base + 1 : base + l + 1])
            np.multiply(p_l[1 : l + 1], sin_m[1 : l + 1], out=out[base + l + 1 : base + 2 * l + 1])
            p_lm2, p_lm1, p_l = p_lm1, p_l, p_lm2

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "sh", "order": int(self.order)}

    @cached_property
    def sphere_mean(self) -> FloatArray:
        v = np.zeros(self.n_coef)
        v[0] = 1.0 / np.sqrt(4.0 * np.pi)
        return v


# -------------------------------------------------------------------------------------------
# Basis grid (paper's "BG")


def paper_grid_nodes(order: int) -> tuple[FloatArray, FloatArray]:
    """The paper's k x 2k azimuth-elevation grid, cell-centred (no duplicated pole nodes) [rad]."""
    k = int(order)
    el = -np.pi / 2 + (np.arange(k) + 0.5) * (np.pi / k)
    az = -np.pi + (np.arange(2 * k) + 0.5) * (np.pi / k)
    azg, elg = np.meshgrid(az, el)
    return azg.ravel(), elg.ravel()


def fibonacci_grid_nodes(count: int) -> tuple[FloatArray, FloatArray]:
    """``count`` nearly equal-area nodes on the sphere (Fibonacci lattice) [rad]."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    golden = np.pi * (3.0 - np.sqrt(5.0))
    az = np.mod(golden * i + np.pi, 2 * np.pi) - np.pi
    return az, np.arcsin(z)


@dataclass(frozen=True)
class BasisGrid(Basis):
    """Gaussian kernels on grid nodes, ``exp(-theta**2 / (2 sigma))`` (paper's BG-``order``).

    Parameters
    ----------
    order : int
        ``k``: the grid has ``k`` elevations x ``2k`` azimuths (``2 k**2`` nodes).
    sigma_rad2 : float
        The paper's ``sigma`` [rad^2]: the variance of the kernel in great-circle angle
        (its standard deviation is ``sqrt(sigma)`` rad). The paper used about 0.5.
    grid : {"paper", "fibonacci"}
        Node layout: the paper's azimuth-elevation grid, or an equal-area Fibonacci lattice
        with the same number of nodes.
    """

    order: int = 7
    sigma_rad2: float = 0.5
    grid: str = "paper"
    kind: str = field(default="bg", init=False)

    def __post_init__(self) -> None:
        if int(self.order) != self.order or self.order < 1:
            raise InputError(f"BG order must be a positive integer, got {self.order!r}")
        if not (np.isfinite(self.sigma_rad2) and self.sigma_rad2 > 0):
            raise InputError(f"BG sigma_rad2 must be positive, got {self.sigma_rad2!r}")
        if self.grid not in ("paper", "fibonacci"):
            raise InputError(f"BG grid must be 'paper' or 'fibonacci', got {self.grid!r}")

    @property
    def n_coef(self) -> int:
        return 2 * self.order * self.order

    @property
    def label(self) -> str:
        return f"BG-{self.order}"

    @cached_property
    def nodes_rad(self) -> tuple[FloatArray, FloatArray]:
        """Azimuth and elevation of the grid nodes [rad]."""
        if self.grid == "paper":
            return paper_grid_nodes(self.order)
        return fibonacci_grid_nodes(self.n_coef)

    @cached_property
    def _node_vectors(self) -> FloatArray:
        az, el = self.nodes_rad
        ce = np.cos(el)
        return np.stack([ce * np.cos(az), ce * np.sin(az), np.sin(el)], axis=1)  # (p, 3)

    def design_into(self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray) -> None:
        ce = np.cos(el_rad)
        u = np.stack([ce * np.cos(az_rad), ce * np.sin(az_rad), np.sin(el_rad)])  # (3, n)
        np.matmul(self._node_vectors, u, out=out)
        np.clip(out, -1.0, 1.0, out=out)
        np.arccos(out, out=out)
        np.square(out, out=out)
        out *= -1.0 / (2.0 * self.sigma_rad2)
        np.exp(out, out=out)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "bg", "order": int(self.order), "sigma_rad2": float(self.sigma_rad2), "grid": self.grid}


# -------------------------------------------------------------------------------------------
# Polynomial (paper's "P")


def total_degree_exponents(order: int) -> list[tuple[int, int]]:
    """All ``(i, j)`` with ``i + j <= order``, ordered by total degree then ``j``."""
    return [(d - j, j) for d in range(order + 1) for j in range(d + 1)]


@dataclass(frozen=True)
class Polynomial(Basis):
    """Polynomials in azimuth and elevation of total degree ``<= order`` (paper's P-``order``).

    Parameters
    ----------
    order : int
        Highest total degree ``k``; ``(k+1)(k+2)/2`` functions.
    polynomial : {"legendre", "monomial"}
        ``"legendre"`` (default): ``P_i(az/pi) P_j(el/(pi/2))``; ``"monomial"``:
        ``(az/pi)**i (el/(pi/2))**j``. Both span the paper's space of all ``az**i el**j`` with
        ``i + j <= k`` (the scaling of the variables changes no prediction) and so predict the
        same; Legendre products keep the normal equations far better conditioned.
    """

    order: int = 12
    polynomial: str = "legendre"
    kind: str = field(default="poly", init=False)

    def __post_init__(self) -> None:
        if int(self.order) != self.order or self.order < 0:
            raise InputError(f"P order must be a non-negative integer, got {self.order!r}")
        if self.polynomial not in ("legendre", "monomial"):
            raise InputError(f"polynomial must be 'legendre' or 'monomial', got {self.polynomial!r}")

    @property
    def n_coef(self) -> int:
        return (self.order + 1) * (self.order + 2) // 2

    @property
    def label(self) -> str:
        return f"P-{self.order}"

    def _powers(self, t: FloatArray) -> FloatArray:
        k = self.order
        out = np.empty((k + 1, t.size))
        out[0] = 1.0
        if k >= 1:
            out[1] = t
        for n in range(2, k + 1):
            if self.polynomial == "legendre":
                out[n] = ((2 * n - 1) * t * out[n - 1] - (n - 1) * out[n - 2]) / n
            else:
                out[n] = out[n - 1] * t
        return out

    def design_into(self, az_rad: FloatArray, el_rad: FloatArray, out: FloatArray) -> None:
        pu = self._powers(az_rad / np.pi)
        pv = self._powers(el_rad / (np.pi / 2))
        for c, (i, j) in enumerate(total_degree_exponents(self.order)):
            np.multiply(pu[i], pv[j], out=out[c])

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "poly", "order": int(self.order), "polynomial": self.polynomial}


# -------------------------------------------------------------------------------------------

BASIS_KINDS = ("sh", "bg", "poly")


def make_basis(kind: str, order: int, **options: Any) -> Basis:
    """Build a basis by name: ``"sh"``, ``"bg"`` or ``"poly"`` (also ``"p"``) of a given order.

    Examples
    --------
    >>> make_basis("sh", 10).n_coef
    100
    >>> make_basis("bg", 7, sigma_rad2=0.5).n_coef
    98
    >>> make_basis("poly", 12).n_coef
    91
    """
    k = str(kind).lower()
    try:
        if k == "sh":
            return SphericalHarmonics(int(order), **options)
        if k == "bg":
            return BasisGrid(int(order), **options)
        if k in ("poly", "p"):
            return Polynomial(int(order), **options)
    except TypeError as exc:
        raise InputError(f"basis {kind!r}: bad option ({exc})") from None
    raise InputError(f"unknown basis {kind!r}; expected one of {', '.join(BASIS_KINDS)}")


def basis_from_dict(spec: dict[str, Any]) -> Basis:
    """Rebuild a basis from :meth:`Basis.to_dict` output (used by model files)."""
    if not isinstance(spec, dict) or "kind" not in spec or "order" not in spec:
        raise ModelFileError(f"basis: expected an object with 'kind' and 'order', got {spec!r}")
    options = {k: v for k, v in spec.items() if k not in ("kind", "order")}
    try:
        return make_basis(spec["kind"], spec["order"], **options)
    except InputError as exc:
        raise ModelFileError(f"basis: {exc}") from None
