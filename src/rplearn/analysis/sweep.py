"""Model-order selection (paper Sec. V-C3, Fig. 10): test RMSE, AIC and LTD against the order."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
import scipy.linalg  # noqa: F401  (order selection solves through scipy: loaded before any BLAS limit, rplearn.core.threads)

from rplearn._argtypes import check_types
from rplearn._budget import Cost, check_work
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.selection import Selection, select_order_and_smoothing, validation_rmse
from rplearn.core.threads import blas_threads_for
from rplearn.data.tables import LinkSamples
from rplearn.errors import BadValueError, InputError
from rplearn.models.fit import evaluate_models, fit_model
from rplearn.models.spec import ModelSpec, check_model_size

Progress = Callable[[str], None]


def no_progress(_: str) -> None:
    """A progress callback that says nothing."""
    return None


@check_types
@dataclass
class SweepResult:
    """Test RMSE, AIC, LTD and condition number against the model order."""

    kind: str
    orders: list[int]
    rmse_db: list[float]
    aic: list[float]
    ltd_s: list[float]
    condition_number: list[float]
    n_params: list[int]

    #: Cross-validated RMSE [dB] of every order at the automatic choice's smoothing (SH sweeps
    #: with per-unit learning samples, see :func:`validation_sweep`), else None.
    validation_rmse_db: list[float] | None = None
    selection: Selection | None = None
    #: What the user should know about the data used (e.g. how a dataset without units was split).
    notes: list[str] = field(default_factory=list)

    @property
    def best_order(self) -> int:
        """Order with the lowest test RMSE."""
        return int(self.orders[int(np.argmin(self.rmse_db))])

    def summary(self) -> str:
        """The sweep as a text table, and the order of the lowest test RMSE."""
        text = f"{self.to_frame().to_string(index=False)}\nlowest test RMSE at order {self.best_order}"
        if self.selection is not None:
            sel = self.selection
            text += (f"\nautomatic choice (--order auto, {sel.method} on the learning units): order {sel.order}, "
                     f"smoothing {sel.smoothing:.1e}; cv_rmse_db is its validation curve at that smoothing")
        return text

    def to_frame(self) -> pd.DataFrame:
        """One row per order: parameters, test RMSE [dB], AIC, LTD [s], condition number."""
        return pd.DataFrame(
            {
                "order": self.orders,
                "n_params": self.n_params,
                "test_rmse_db": self.rmse_db,
                "aic": self.aic,
                "ltd_s": self.ltd_s,
                "condition_number": self.condition_number,
                **({"cv_rmse_db": self.validation_rmse_db} if self.validation_rmse_db is not None else {}),
            }
        )


def validation_sweep(unit_samples: dict[str, LinkSamples], orders: Sequence[int]) -> tuple[Selection, list[float]]:
    """The automatic choice (``fit --order auto``) among SH ``orders`` and its validation curve
    at the chosen smoothing, from per-unit statistics accumulated once at ``max(orders)``."""
    top = max(int(o) for o in orders)
    spec = ModelSpec("sh", top)
    nodes = next(iter(unit_samples.values())).nodes
    n = sum(len(s) for s in unit_samples.values())
    with blas_threads_for(n, spec.basis().n_coef * len(nodes)):  # the thread policy (rplearn.core.threads)
        return _validation_sweep(unit_samples, orders, spec, nodes)


def _validation_sweep(unit_samples: dict[str, LinkSamples], orders: Sequence[int], spec: ModelSpec,
                      nodes: Any) -> tuple[Selection, list[float]]:
    """:func:`validation_sweep` at the top order's ``spec``."""
    stats = {u: NormalEquations(spec.basis(), len(nodes)).add(s.directions, s.tx_index, s.rx_index, s.joint_gain_db)
             for u, s in unit_samples.items() if len(s)}
    total = NormalEquations(spec.basis(), len(nodes))
    for st in stats.values():
        total.merge(st)
    links = total.two_way_links()  # as the fits of the sweep: one offset per link logged both ways
    if links:
        stats = {u: st.with_shared(links) for u, st in stats.items()}
    make = lambda k: ModelSpec("sh", k).basis()  # noqa: E731
    selection = select_order_and_smoothing(stats, make, orders, spec.ridge_weight)
    return selection, validation_rmse(stats, make, orders, selection.smoothing, spec.ridge_weight)


#: Costs of one order of a sweep (``sweep --orders 1..18`` on the smoke dataset, 1,333 samples: about 4 s on
#: a loaded 2-core machine): seconds per sample and column, per column cubed
#: (the solve), and a fixed part per order.
SWEEP_S_PER_VALUE, SWEEP_S_PER_CUBE, SWEEP_S_PER_ORDER = 3e-8, 1e-9, 0.2


def sweep_cost(kind: str, orders: Sequence[int], n_samples: int, n_nodes: int, top: float) -> Cost:
    """What fitting and testing every order of ``orders`` up to ``top`` takes."""
    seconds, memory = 0.0, 0.0
    for order in orders:
        if order > top:
            break
        cols = n_nodes * ModelSpec(kind, int(order)).n_coef
        seconds += SWEEP_S_PER_ORDER + SWEEP_S_PER_VALUE * n_samples * cols + SWEEP_S_PER_CUBE * cols**3
        memory = max(memory, 32.0 * cols * cols + 24.0 * min(n_samples, 1 << 16) * cols)
    return Cost(memory_bytes=memory + 2e8, seconds=seconds)


def order_bounds(orders: Sequence[int]) -> tuple[int, int]:
    """The smallest and largest of ``orders``: a range's at once (``sweep --orders 1..100000000``
    is one, never made into a list: the samples refuse its largest order before any pass over
    it), else by one pass."""
    if isinstance(orders, range) and len(orders):
        return (orders[0], orders[-1]) if orders.step > 0 else (orders[-1], orders[0])
    values = [int(o) for o in orders]
    return min(values), max(values)


def _identifiable(kind: str, orders: Sequence[int], n_samples: int, n_nodes: int) -> list[int]:
    """The orders the samples can identify (all of them when none can: :func:`check_sweep` says why)."""
    kept = []
    for order in orders:
        try:
            check_model_size(ModelSpec(kind, int(order)), n_samples, n_nodes)
        except InputError:
            continue
        kept.append(int(order))
    return kept or [int(o) for o in orders]


def check_sweep(kind: str, orders: Sequence[int], n_samples: int, n_nodes: int) -> None:
    """Refuse, before any fit, orders whose largest the samples cannot identify or that would
    not fit in the work budget (:mod:`rplearn._budget`), naming the largest order that does."""
    ordered = orders if isinstance(orders, range) and orders.step > 0 else sorted({int(o) for o in orders})
    try:
        check_model_size(ModelSpec(kind, ordered[-1]), n_samples, n_nodes)
    except InputError as exc:
        raise InputError(f"orders: {exc}", param="orders") from None
    check_work("orders", ordered[-1], lambda top: sweep_cost(kind, ordered, n_samples, n_nodes, top), "(largest order)",
               bounds=(ordered[0], ordered[-1]))


#: The models a sweep runs over their order: the pattern models, whose order is their size
#: (the number of coefficients, which AIC counts). A k-NN model's "order" would be its k, and
#: its AIC would count every training sample as a parameter.
SWEPT_KINDS = ("sh", "bg", "poly")


def check_sweep_kind(kind: str) -> None:
    """Refuse a model a sweep does not run over its order (:data:`SWEPT_KINDS`)."""
    if kind not in SWEPT_KINDS:
        raise BadValueError(f"model: expected {', '.join(SWEPT_KINDS[:-1])} or {SWEPT_KINDS[-1]} (a pattern model swept by "
                            f"its order), got {kind!r}", param="model")


@check_types
def order_sweep(
    learn: LinkSamples,
    test: LinkSamples,
    kind: str = "sh",
    orders: Sequence[int] = tuple(range(3, 21)),
    stop_after_rises: int | None = 3,
    progress: Progress = no_progress,
) -> SweepResult:
    """Fit models of increasing order on ``learn`` and score each on ``test``.

    Stops early once the test error has risen above its minimum for ``stop_after_rises``
    consecutive orders, and then leaves out the orders the samples cannot identify (None: run
    every order, and refuse one the samples cannot identify).
    """
    check_sweep_kind(kind)
    if not orders or order_bounds(orders)[0] < 1:
        raise InputError(f"orders: expected positive orders, got {list(orders)!r}", param="orders")
    if stop_after_rises is not None:  # a sweep that stops by itself ends where the samples end
        orders = _identifiable(kind, orders, len(learn), len(learn.nodes))
    check_sweep(kind, orders, len(learn), len(learn.nodes))
    out = SweepResult(kind, [], [], [], [], [], [])
    rises = 0
    for order in orders:
        spec = ModelSpec(kind, int(order))
        fitted = fit_model(learn, spec)
        row = evaluate_models([fitted], test)[0]
        out.orders.append(int(order))
        out.rmse_db.append(row.rmse_db)
        out.aic.append(row.aic)
        out.ltd_s.append(row.ltd_s)
        out.condition_number.append(fitted.condition_number)
        out.n_params.append(fitted.n_params)
        progress(f"{spec.label}: test RMSE {row.rmse_db:.3f} dB")
        rises = rises + 1 if row.rmse_db > min(out.rmse_db) else 0
        if stop_after_rises is not None and rises >= stop_after_rises:
            break
    return out
