"""Model-order selection (paper Sec. V-C3, Fig. 10): test RMSE, AIC and LTD against the order."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
import pandas as pd

from rplearn.data.tables import LinkSamples
from rplearn.models.fit import evaluate_models, fit_model
from rplearn.models.spec import ModelSpec

Progress = Callable[[str], None]


def no_progress(_: str) -> None:
    """A progress callback that says nothing."""
    return None


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

    @property
    def best_order(self) -> int:
        """Order with the lowest test RMSE."""
        return int(self.orders[int(np.argmin(self.rmse_db))])

    def summary(self) -> str:
        """The sweep as a text table, and the order of the lowest test RMSE."""
        return f"{self.to_frame().to_string(index=False)}\nlowest test RMSE at order {self.best_order}"

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
            }
        )


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
    consecutive orders (None: run every order).
    """
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
