"""The gauge of a joint fit: how the one constant a two-sided link graph cannot identify is fixed.

When the links among some nodes form no odd cycle (one drone and one station, say), adding
``+c`` to one side's patterns and ``-c`` to the other's leaves every joint gain unchanged
(docs/conventions.md, "gauge"). A :class:`Gauge` says which constraint the solver adds for
each such group: equal sphere-mean gains on both sides (the default), or a known sphere-mean
gain of one node. It is a value, checked when made; the solver reads it as is.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.errors import InputError

#: The legacy text of the default gauge (model files, ``gauge=`` of the scikit-learn estimator).
EQUAL_MEAN = "equal-mean"


@check_types
@dataclass(frozen=True)
class Gauge:
    """How a fit fixes the constant a bipartite link graph cannot identify.

    Attributes
    ----------
    node : str or None
        None: both sides of every such group get the same sphere-mean gain (only pattern
        shapes and the joint level are identified). A node id: that node's sphere-mean gain is
        ``mean_gain_dbi``.
    mean_gain_dbi : float or None
        The known sphere-mean gain [dBi] of ``node`` (default 0 when a node is given); only
        with ``node``.

    Raises
    ------
    InputError
        ``gauge_dbi`` not finite or without a node, ``gauge_node`` not a non-empty text.
    """

    node: str | None = None
    mean_gain_dbi: float | None = None

    def __post_init__(self) -> None:
        if self.node is not None and (not isinstance(self.node, str) or not self.node):
            raise InputError(f"gauge_node: expected a node id, got {self.node!r}", param="gauge_node")
        if self.mean_gain_dbi is not None:
            try:
                value = float(self.mean_gain_dbi)
            except (TypeError, ValueError):
                value = float("nan")
            if not np.isfinite(value):
                raise InputError(f"gauge_dbi: expected a finite mean gain in dBi, got {self.mean_gain_dbi!r}",
                                 param="gauge_dbi")
            if self.node is None:
                raise InputError("gauge_dbi needs gauge_node (which node's mean gain it fixes)", param="gauge_dbi",
                                 related=("gauge_node",))
            object.__setattr__(self, "mean_gain_dbi", value)
        elif self.node is not None:
            object.__setattr__(self, "mean_gain_dbi", 0.0)

    @property
    def equal_mean(self) -> bool:
        """Whether both sides get the same sphere-mean gain (no node fixed)."""
        return self.node is None

    @classmethod
    def of(cls, value: Gauge | str | Mapping[str, Any] | None) -> Gauge:
        """A gauge from itself, None or ``"equal-mean"`` (the default), or the legacy mapping
        ``{"node": ID, "mean_gain_dbi": VALUE}``.

        Raises
        ------
        InputError
            (``param="gauge"``) for anything else.
        """
        if isinstance(value, Gauge):
            return value
        if value is None or (isinstance(value, str) and value == EQUAL_MEAN):
            return cls()
        if isinstance(value, Mapping) and "node" in value and set(value) <= {"node", "mean_gain_dbi"}:
            return cls(str(value["node"]), value.get("mean_gain_dbi", 0.0))
        raise InputError(f"gauge: expected 'equal-mean' or {{'node': ID, 'mean_gain_dbi': VALUE}}, got {value!r}",
                         param="gauge")

    def to_dict(self) -> str | dict[str, Any]:
        """The legacy form :meth:`of` reads: ``"equal-mean"`` or ``{"node", "mean_gain_dbi"}``."""
        if self.node is None:
            return EQUAL_MEAN
        return {"node": self.node, "mean_gain_dbi": float(self.mean_gain_dbi or 0.0)}


__all__ = ["EQUAL_MEAN", "Gauge"]
