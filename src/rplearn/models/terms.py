"""The link terms learned beside the patterns: the environment and the electronics offsets.

A fit may learn, with the patterns, a log-distance path-loss exponent (one shared column) and
one electronics offset per link logged in both directions (non-reciprocal radios, paper Sec.
V-B3), and may subtract a known two-ray ground reflection (:mod:`rplearn.core.environment`).
This module turns samples into the solver's inputs (:func:`regression_inputs`) and the
solver's shared coefficients into the model's fields and training summary
(:func:`shared_fields`).

Offsets are gauge-fixed like the pattern constant: the two directions of a link sum to zero,
their common part being the patterns' joint level (it cannot be told apart from it). A
direction learned alone, or never learned, is predicted with offset 0.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from rplearn.core.environment import PathLoss, log_distance_column
from rplearn.core.solver import JointSolution
from rplearn.data.tables import LinkSamples


def regression_inputs(samples: LinkSamples, path_loss: PathLoss) -> tuple[np.ndarray, np.ndarray | None]:
    """The observations the patterns are fitted to and the shared environment column.

    ``y`` is the observed joint gain less the known two-ray term (when chosen); the column is
    the log-distance regressor (when chosen), else None.
    """
    y = np.asarray(samples.joint_gain_db, np.float64)
    known = path_loss.known_db(samples.distance_m, samples.tx_z_m, samples.rx_z_m, samples.frequency_hz)
    if known is not None:
        y = y - known
    env = log_distance_column(samples.distance_m) if path_loss.learns_exponent else None
    return y, env


def directed_counts(samples: LinkSamples | Sequence[LinkSamples]) -> dict[str, int]:
    """Samples of every directed link ``"TX->RX"``, sorted."""
    parts = [samples] if isinstance(samples, LinkSamples) else list(samples)
    counts: dict[str, int] = {}
    for part in parts:
        names = np.asarray(part.nodes, dtype=object)
        code = part.tx_index.astype(np.int64) * len(part.nodes) + part.rx_index
        values, n = np.unique(code, return_counts=True)
        for v, c in zip(values, n):
            t, r = divmod(int(v), len(part.nodes))
            key = f"{names[t]}->{names[r]}"
            counts[key] = counts.get(key, 0) + int(c)
    return dict(sorted(counts.items()))


def shared_names(shared: Sequence[tuple[Any, ...]], nodes: Sequence[str]) -> tuple[str, ...]:
    """Model names of the solver's shared columns: ``"exponent"``, ``"offset:A->B"``."""
    out = []
    for col in shared:
        out.append("exponent" if col[0] == "exponent" else f"offset:{nodes[col[1]]}->{nodes[col[2]]}")
    return tuple(out)


def shared_fields(
    sol: JointSolution, nodes: Sequence[str], path_loss: PathLoss, counts: dict[str, int], covariance_scale: float = 1.0
) -> tuple[dict[str, Any], dict[str, Any]]:
    """``PatternSet`` keyword arguments (``path_loss``, ``shared_names``, ``shared_coef``) and the
    training summary's entries for the link terms of a solution.

    ``covariance_scale`` multiplies the variances reported (a selection's variance inflation).
    """
    names = shared_names(sol.shared, nodes)
    coef = np.asarray(sol.shared_coef, np.float64)
    pat = len(nodes) * (sol.coef.shape[1] if sol.coef.ndim == 2 else 0)
    var = np.diag(sol.covariance)[pat:] * covariance_scale if sol.covariance is not None else np.full(coef.size, np.nan)
    se = np.sqrt(np.maximum(var, 0.0))
    training: dict[str, Any] = {"path_loss": path_loss.to_dict(), "directions": counts}
    for j, name in enumerate(names):
        if name == "exponent":
            training["path_loss"].update(exponent=2.0 + float(coef[j]), exponent_se=float(se[j]),
                                         exponent_unexplained=float(sol.shared_unexplained[j]))
    offsets = {}
    for j, name in enumerate(names):
        if name.startswith("offset:"):
            a, b = name[len("offset:"):].split("->")
            offsets[f"{a}->{b}"] = {"offset_db": float(coef[j]), "se_db": float(se[j])}
            offsets[f"{b}->{a}"] = {"offset_db": -float(coef[j]), "se_db": float(se[j])}
    if offsets:
        training["link_offsets_db"] = offsets
    return {"path_loss": path_loss, "shared_names": names, "shared_coef": coef}, training


def terms_text(training: dict[str, Any]) -> list[str]:
    """Summary lines of a model's link terms (environment, exponent, offsets, directions)."""
    lines = []
    pl = PathLoss.from_dict(training.get("path_loss"))
    info = training.get("path_loss") or {}
    if pl.kind == "log-distance" and "exponent" in info:
        lines.append(f"path loss: log-distance, exponent {info['exponent']:.3f} +- {info['exponent_se']:.3f} "
                     f"(free space 2; d0 = 1 m)")
    elif pl.kind != "free":
        lines.append(f"path loss: {pl.describe()}")
    offsets = training.get("link_offsets_db") or {}
    if offsets:
        text = ", ".join(f"{k} {v['offset_db']:+.2f} +- {v['se_db']:.2f} dB" for k, v in sorted(offsets.items()))
        lines.append(f"electronics offsets (each link's two directions sum to 0): {text}")
    counts = training.get("directions") or {}
    alone = [k for k in counts if f"{k.split('->')[1]}->{k.split('->')[0]}" not in counts]
    if alone:
        lines.append(f"learned in one direction only: {', '.join(alone)} (the other direction is predicted as "
                     "reciprocal: offset 0)")
    return lines


__all__ = ["directed_counts", "regression_inputs", "shared_fields", "shared_names", "terms_text"]
