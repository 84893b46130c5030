"""Model specifications: a family (sh, bg, poly, mean, knn) and its hyper-parameters, parsed from
the paper's labels (``sh-10``, ``bg-7``, ``p-12``, ``nn-400``, ``m``)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn.core.bases import make_basis
from rplearn.core.solver import DEFAULT_RIDGE
from rplearn.errors import InputError


MODEL_KINDS = ("sh", "bg", "poly", "mean", "knn")


_DEFAULT_ORDER = {"sh": 10, "bg": 7, "poly": 12, "knn": 400}


_ALIASES = {"m": "mean", "p": "poly", "nn": "knn", "bucketized": "bg"}


#: Default ridge per family (see :data:`rplearn.core.solver.DEFAULT_RIDGE`; the paper used 50).
DEFAULT_RIDGE_BY_KIND = {"sh": DEFAULT_RIDGE, "poly": DEFAULT_RIDGE, "bg": DEFAULT_RIDGE, "mean": 0.0, "knn": 0.0}


def default_ridge(kind: str) -> float:
    """Default ridge weight of a model family (see :data:`DEFAULT_RIDGE_BY_KIND`)."""
    return DEFAULT_RIDGE_BY_KIND.get(kind, DEFAULT_RIDGE)


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
    """

    kind: str
    order: int | None = None
    ridge: float | None = None
    sigma_rad2: float = 0.5
    grid: str = "paper"

    def __post_init__(self) -> None:
        if self.ridge is None:
            object.__setattr__(self, "ridge", default_ridge(self.kind))
        if not (np.isfinite(self.ridge) and self.ridge >= 0):
            raise InputError(f"ridge must be a non-negative number, got {self.ridge!r}")
        if self.kind != "mean" and (self.order is None or int(self.order) < 1):
            raise InputError(f"model {self.kind}: order must be a positive integer, got {self.order!r}")

    @classmethod
    def parse(cls, text: str, **options: Any) -> "ModelSpec":
        """Parse ``"sh-10"``, ``"SH10"``, ``"bg-7"``, ``"p-12"``, ``"nn-400"``, ``"m"``, ``"knn"``..."""
        m = re.fullmatch(r"\s*([a-zA-Z]+)[-_ ]?(\d+)?\s*", str(text))
        if not m:
            raise InputError(f"unknown model {text!r}; expected one of sh, bg, poly, mean, knn (e.g. sh-10, nn-400)")
        kind = _ALIASES.get(m.group(1).lower(), m.group(1).lower())
        if kind not in MODEL_KINDS:
            raise InputError(f"unknown model {text!r}; expected one of {', '.join(MODEL_KINDS)} (e.g. sh-10, nn-400)")
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
    def decouples(self) -> bool:
        return self.kind in ("sh", "bg", "poly")

    def basis(self):
        if self.kind == "bg":
            return make_basis("bg", self.order, sigma_rad2=self.sigma_rad2, grid=self.grid)
        return make_basis(self.kind, self.order)
