"""Basis families turning directions (azimuth, elevation) into design-matrix blocks (paper Sec. IV-B to IV-E).

A radiation pattern is a linear combination ``G(az, el) = sum_i p_i f_i(az, el)`` [dBi]. Three
families are offered, sized as the paper labels them (docs/conventions.md, "model sizes", counted per antenna):

- :class:`SphericalHarmonics` ``SH-L``: real orthonormal spherical harmonics of degrees
  0 .. L-1, ``L**2`` functions (SH-10 = 100), checked against ``scipy.special.sph_harm_y``.
  Computed as ``Q_lm(sin el) cos(el)^(m mod 2) cos|sin(m az)``: the Legendre factors ``Q_lm``
  of all (l, m) by one matrix product of fixed Chebyshev coefficients with ``T_j(sin el)``,
  and ``cos(m az)``, ``sin(m az)`` by Chebyshev recurrences.
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
(one row per function) so the solver can accumulate ``X^T X`` without copies. The base class
:class:`Basis` and the buffers the families share live in :mod:`rplearn.core.basis_base`, the
spherical harmonics in :mod:`rplearn.core.sh`; both classes can be imported from here too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.basis_base import Basis, FloatArray
from rplearn.core.sh import SphericalHarmonics
from rplearn.errors import BadValueError, InputError, ModelFileError

__all__ = [
    "BASIS_KINDS",
    "BG_GRIDS",
    "Basis",
    "BasisGrid",
    "Polynomial",
    "SphericalHarmonics",
    "basis_from_dict",
    "fibonacci_grid_nodes",
    "make_basis",
    "paper_grid_nodes",
    "total_degree_exponents",
]


# -------------------------------------------------------------------------------------------
# Basis grid (paper's "BG")

#: The node grids of a BG basis: the paper's, or a Fibonacci lattice.
BG_GRIDS = ("paper", "fibonacci")


@check_types
def paper_grid_nodes(order: int) -> tuple[FloatArray, FloatArray]:
    """The paper's k x 2k azimuth-elevation grid, cell-centred (no duplicated pole nodes) [rad]."""
    k = int(order)
    el = -np.pi / 2 + (np.arange(k) + 0.5) * (np.pi / k)
    az = -np.pi + (np.arange(2 * k) + 0.5) * (np.pi / k)
    azg, elg = np.meshgrid(az, el)
    return azg.ravel(), elg.ravel()


@check_types
def fibonacci_grid_nodes(count: int) -> tuple[FloatArray, FloatArray]:
    """``count`` nearly equal-area nodes on the sphere (Fibonacci lattice) [rad]."""
    i = np.arange(count) + 0.5
    z = 1.0 - 2.0 * i / count
    golden = np.pi * (3.0 - np.sqrt(5.0))
    az = np.mod(golden * i + np.pi, 2 * np.pi) - np.pi
    return az, np.arcsin(z)


@check_types
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
            raise InputError(f"BG order must be a positive integer, got {self.order!r}", param="order")
        if not (np.isfinite(self.sigma_rad2) and self.sigma_rad2 > 0):
            raise InputError(f"BG sigma_rad2 must be positive, got {self.sigma_rad2!r}", param="sigma_rad2")
        if self.grid not in BG_GRIDS:
            raise BadValueError(f"BG grid must be {' or '.join(map(repr, BG_GRIDS))}, got {self.grid!r}", param="grid")

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


@check_types
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


@check_types
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


@check_types
def basis_from_dict(spec: dict[str, Any]) -> Basis:
    """Rebuild a basis from :meth:`Basis.to_dict` output (used by model files)."""
    if not isinstance(spec, dict) or "kind" not in spec or "order" not in spec:
        raise ModelFileError(f"basis: expected an object with 'kind' and 'order', got {spec!r}")
    options = {k: v for k, v in spec.items() if k not in ("kind", "order")}
    try:
        return make_basis(spec["kind"], spec["order"], **options)
    except InputError as exc:
        raise ModelFileError(f"basis: {exc}") from None
