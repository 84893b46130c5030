"""Model specifications: a family (sh, bg, poly, mean, knn) and its hyper-parameters, parsed from
the paper's labels (``sh-10``, ``bg-7``, ``p-12``, ``nn-400``, ``m``)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.bases import BG_GRIDS, make_basis
from rplearn.core.lsq.solver import DEFAULT_RIDGE
from rplearn.errors import BadValueError, InputError

if TYPE_CHECKING:
    from rplearn.core.basis_base import Basis


MODEL_KINDS = ("sh", "bg", "poly", "mean", "knn")


_DEFAULT_ORDER = {"sh": 10, "bg": 7, "poly": 12, "knn": 400}


_ALIASES = {"m": "mean", "p": "poly", "nn": "knn", "bucketized": "bg"}


#: Default ridge per family (see :data:`rplearn.core.lsq.solver.DEFAULT_RIDGE`; the paper used 50).
DEFAULT_RIDGE_BY_KIND = {"sh": DEFAULT_RIDGE, "poly": DEFAULT_RIDGE, "bg": DEFAULT_RIDGE, "mean": 0.0, "knn": 0.0}


@check_types
def default_ridge(kind: str) -> float:
    """Default ridge weight of a model family (see :data:`DEFAULT_RIDGE_BY_KIND`)."""
    return DEFAULT_RIDGE_BY_KIND.get(kind, DEFAULT_RIDGE)


@check_types
@dataclass(frozen=True)
class ModelSpec:
    """A model family and its hyper-parameters.

    Attributes
    ----------
    kind : {"sh", "bg", "poly", "mean", "knn"}
    order : int or None
        SH-L, BG-k, P-k order, or k of NN-k.
    ridge : float or None
        Ridge weight of the pattern models; None picks :func:`default_ridge` of the kind.
    sigma_rad2 : float
        BG kernel variance [rad^2].
    grid : {"paper", "fibonacci"}
        BG node layout.
    smoothing : float
        Relative weight of the smoothness penalty (:mod:`rplearn.core.lsq.selection`); 0: none.
    """

    kind: str
    order: int | None = None
    ridge: float | None = None
    sigma_rad2: float = 0.5
    grid: str = "paper"
    smoothing: float = 0.0

    def __post_init__(self) -> None:
        ridge = default_ridge(self.kind) if self.ridge is None else self.ridge
        object.__setattr__(self, "ridge", ridge)
        if not (np.isfinite(ridge) and ridge >= 0):
            raise InputError(f"ridge must be a non-negative number, got {self.ridge!r}", param="ridge")
        if self.kind != "mean" and (self.order is None or int(self.order) != self.order or int(self.order) < 1):
            raise InputError(f"model {self.kind}: order must be a positive integer, got {self.order!r}", param="order")
        if not (np.isfinite(self.smoothing) and self.smoothing >= 0):
            raise InputError(f"smoothing must be a non-negative number, got {self.smoothing!r}", param="smoothing")
        if self.kind == "bg" and self.grid not in BG_GRIDS:  # before any data is read (the basis checks it again)
            raise BadValueError(f"BG grid must be {' or '.join(map(repr, BG_GRIDS))}, got {self.grid!r}", param="grid")

    @classmethod
    def parse(cls, text: str, **options: Any) -> ModelSpec:
        """Parse ``"sh-10"``, ``"SH10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``, ``"knn"``..."""
        m = re.fullmatch(r"\s*([a-zA-Z]+)[-_ ]?(\d+)?\s*", str(text))
        if not m:
            raise BadValueError(f"unknown model {text!r}; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400)", param="model")
        kind = _ALIASES.get(m.group(1).lower(), m.group(1).lower())
        if kind not in MODEL_KINDS:
            raise BadValueError(f"unknown model {text!r}; expected one of {', '.join(MODEL_KINDS)} (e.g. sh-10, nn-400)", param="model")
        order = int(m.group(2)) if m.group(2) else options.pop("order", None)
        options.pop("order", None)
        if kind != "mean" and order is None:
            order = _DEFAULT_ORDER[kind]
        return cls(kind, None if kind == "mean" else int(order), **{k: v for k, v in options.items() if v is not None})

    @property
    def label(self) -> str:
        """The paper's label: M, NN-400, SH-10, P-12, BG-7."""
        return {"mean": "M", "knn": f"NN-{self.order}", "sh": f"SH-{self.order}", "poly": f"P-{self.order}", "bg": f"BG-{self.order}"}[self.kind]

    @property
    def n_coef(self) -> int:
        """Coefficients per antenna (0 for the baselines): SH-L L^2, BG-k 2 k^2, P-k (k+1)(k+2)/2."""
        k = int(self.order or 0)
        return {"sh": k * k, "bg": 2 * k * k, "poly": (k + 1) * (k + 2) // 2}.get(self.kind, 0)

    @property
    def decouples(self) -> bool:
        return self.kind in ("sh", "bg", "poly")

    @property
    def ridge_weight(self) -> float:
        """The ridge weight (the kind's default when ``ridge`` was None)."""
        return default_ridge(self.kind) if self.ridge is None else float(self.ridge)

    def basis(self) -> Basis:
        if self.order is None:
            raise InputError(f"model {self.kind}: no basis without an order", param="order")
        if self.kind == "bg":
            return make_basis("bg", self.order, sigma_rad2=self.sigma_rad2, grid=self.grid)
        return make_basis(self.kind, self.order)


@check_types
def check_fit_options(
    spec: ModelSpec,
    *,
    order: int | None = None,
    ridge: float | None = None,
    sigma_rad2: float | None = None,
    grid: str | None = None,
    model: str | None = None,
) -> None:
    """Refuse model options (flags of ``rplearn fit``) the chosen model would silently ignore,
    or that contradict it. How the model is learned is checked by
    :class:`rplearn.models.options.FitOptions`.

    Parameters
    ----------
    spec : ModelSpec
        The parsed model.
    order, ridge, sigma_rad2, grid
        The options as the user gave them (None: not given).
    model : str, optional
        The model text as given (e.g. ``"sh-10"``), for messages.

    Raises
    ------
    InputError
        Naming the first offending parameter (``param``); messages start with the names of
        the offending parameters.
    """
    given = {"ridge": ridge, "sigma_rad2": sigma_rad2, "grid": grid}
    if spec.kind in ("mean", "knn"):
        unused = [k for k, v in given.items() if v is not None]
        if spec.kind == "mean" and order is not None:
            unused.append("order")
        if unused:
            raise InputError(f"{', '.join(unused)}: not used by {spec.label}, a baseline without patterns", param=unused[0])
    elif spec.kind != "bg":
        unused = [k for k in ("sigma_rad2", "grid") if given[k] is not None]
        if unused:
            raise InputError(f"{', '.join(unused)}: used by BG models only, not by {spec.label}", param=unused[0])
    if order is not None and spec.order is not None and int(order) != spec.order:
        raise InputError(
            f"order {order} contradicts the model {model or spec.label}, which sets the order {spec.order}", param="order"
        )


#: Largest joint system a fit may build: its Gram matrix is n_columns^2 float64 values
#: (16,384 columns: 2 GiB).
MAX_COLUMNS = 16_384


def _largest_order(kind: str, max_coef: int) -> int:
    """The largest order of ``kind`` with at most ``max_coef`` coefficients per antenna."""
    k = 0
    while ModelSpec(kind, k + 1).n_coef <= max_coef:
        k += 1
    return k


def check_model_size(spec: ModelSpec, n_samples: int, n_nodes: int, source: str = "the learning data") -> None:
    """Refuse, before any work, a pattern model larger than its samples can identify or than
    memory can hold.

    A joint fit has ``n_nodes * spec.n_coef`` unknowns; it needs at least as many samples, and
    its normal equations at most :data:`MAX_COLUMNS` columns.

    Raises
    ------
    InputError
        (``param="order"``) naming the largest order that fits.
    """
    if not spec.decouples:
        return
    columns = int(n_nodes) * spec.n_coef
    limit = min(int(n_samples), MAX_COLUMNS)
    if columns > limit:
        why = f"the {n_samples:,} samples of {source} can identify" if limit == n_samples else (
            f"the {MAX_COLUMNS:,} a fit can hold in memory")
        best = _largest_order(spec.kind, limit // max(int(n_nodes), 1))
        least = ModelSpec(spec.kind, 1)
        fits = (f"the largest {spec.kind} order that fits is {best}" if best >= 1 else
                f"no {spec.kind} order fits ({least.label} alone needs {int(n_nodes) * least.n_coef:,})")
        raise InputError(
            f"order {spec.order}: {spec.label} for {n_nodes} antennas has {columns:,} coefficients, more than "
            f"{why}; {fits}",
            param="order",
        )
