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

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.environment import PathLoss, log_distance_column
from rplearn.data.tables import LinkSamples
from rplearn.errors import InputError
from rplearn.models.options import FitOptions
from rplearn.models.training import TrainingSummary

if TYPE_CHECKING:
    from rplearn.core.lsq.solver import JointSolution


@check_types
def regression_inputs(samples: LinkSamples, options: FitOptions) -> tuple[np.ndarray, np.ndarray | None]:
    """The observations the patterns are fitted to and the shared environment column.

    ``y`` is the observed joint gain less the known two-ray term (when ``options.path_loss``
    chooses it); the column is the log-distance regressor (when chosen), else None.
    """
    path_loss = options.path_loss
    y = np.asarray(samples.joint_gain_db, np.float64)
    known = path_loss.known_db(samples.distance_m, samples.tx_z_m, samples.rx_z_m, samples.frequency_hz)
    if known is not None:
        y = y - known
    env = log_distance_column(samples.distance_m) if path_loss.learns_exponent else None
    return y, env


@check_types
def directed_counts(samples: LinkSamples | Sequence[LinkSamples]) -> dict[tuple[str, str], int]:
    """Samples of every directed link ``(tx, rx)``, sorted."""
    parts = [samples] if isinstance(samples, LinkSamples) else list(samples)
    counts: dict[tuple[str, str], int] = {}
    for part in parts:
        names = [str(n) for n in part.nodes]
        code = part.tx_index.astype(np.int64) * len(names) + part.rx_index
        values, n = np.unique(code, return_counts=True)
        for v, c in zip(values, n):
            t, r = divmod(int(v), len(names))
            key = (names[t], names[r])
            counts[key] = counts.get(key, 0) + int(c)
    return dict(sorted(counts.items()))


def statistics_counts(directed: Mapping[tuple[int, int], np.ndarray], nodes: Sequence[str]) -> dict[tuple[str, str], int]:
    """:func:`directed_counts` from accumulated statistics (``NormalEquations.directed``)."""
    return {(str(nodes[t]), str(nodes[r])): int(round(float(v[-2]))) for (t, r), v in sorted(directed.items())}


def offset_name(tx: str, rx: str) -> str:
    """Model name of the offset column of the link ``tx -> rx`` (``+value`` on it)."""
    return f"offset:{tx}->{rx}"


def split_offset_name(name: str, nodes: Sequence[str]) -> tuple[str, str]:
    """``(tx, rx)`` of an offset column name, for node ids that may themselves contain ``->``.

    Raises
    ------
    InputError
        When no split (or more than one) names two known nodes.
    """
    if not name.startswith("offset:"):
        raise InputError(f"shared column {name!r}: expected 'exponent' or 'offset:TX->RX'", param="shared_names")
    body = name[len("offset:"):]
    known = {str(n) for n in nodes}
    splits = []
    start = body.find("->")
    while start >= 0:
        a, b = body[:start], body[start + 2:]
        if a in known and b in known:
            splits.append((a, b))
        start = body.find("->", start + 1)
    if len(splits) != 1:
        raise InputError(f"shared column {name!r}: expected 'offset:TX->RX' of two known nodes "
                         f"({', '.join(sorted(known))})", param="shared_names")
    return splits[0]


def shared_names(shared: Sequence[tuple[Any, ...]], nodes: Sequence[str]) -> tuple[str, ...]:
    """Model names of the solver's shared columns: ``"exponent"``, ``"offset:A->B"``."""
    return tuple("exponent" if col[0] == "exponent" else offset_name(nodes[col[1]], nodes[col[2]]) for col in shared)


def shared_fields(
    sol: JointSolution, nodes: Sequence[str], options: FitOptions, counts: Mapping[tuple[str, str], int],
    covariance_scale: float = 1.0,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """``PatternSet`` keyword arguments (``path_loss``, ``shared_names``, ``shared_coef``) and the
    training summary's entries for the link terms of a solution fitted with ``options``.

    ``covariance_scale`` multiplies the variances reported (a selection's variance inflation).
    """
    names = shared_names(sol.shared, nodes)
    coef = np.asarray(sol.shared_coef, np.float64)
    pat = sol.coef.size
    var = np.diag(sol.covariance)[pat:] * covariance_scale if sol.covariance is not None else np.full(coef.size, np.nan)
    se = np.sqrt(np.maximum(var, 0.0))
    path_loss = options.path_loss
    training: dict[str, Any] = {
        "path_loss": path_loss.to_dict(),
        "directions": [{"tx": a, "rx": b, "samples": int(n)} for (a, b), n in counts.items()],
    }
    offsets = []
    for j, (name, col) in enumerate(zip(names, sol.shared)):
        if name == "exponent":
            training["path_loss"].update(exponent=2.0 + float(coef[j]), exponent_se=float(se[j]),
                                         exponent_unexplained=float(sol.shared_unexplained[j]))
        else:
            a, b = str(nodes[col[1]]), str(nodes[col[2]])
            offsets += [{"tx": a, "rx": b, "offset_db": float(coef[j]), "se_db": float(se[j])},
                        {"tx": b, "rx": a, "offset_db": -float(coef[j]), "se_db": float(se[j])}]
    if offsets:
        training["link_offsets_db"] = offsets
    return {"path_loss": path_loss, "shared_names": names, "shared_coef": coef}, training


def learned_directions(training: TrainingSummary | Mapping[str, Any]) -> set[tuple[str, str]] | None:
    """The directed links ``(tx, rx)`` a model learned from (None when its file does not say)."""
    rows = TrainingSummary.from_dict(training).directions
    if not isinstance(rows, list):
        return None
    try:
        return {(str(r["tx"]), str(r["rx"])) for r in rows}
    except (KeyError, TypeError):
        return None


@check_types
def terms_text(training: TrainingSummary | Mapping[str, Any]) -> list[str]:
    """Summary lines of a model's link terms (environment, exponent, offsets, directions)."""
    training = TrainingSummary.from_dict(training)
    lines = []
    info = training.path_loss or {}
    pl = PathLoss.from_dict(info)
    if pl.kind == "log-distance" and "exponent" in info:
        lines.append(f"path loss: log-distance, exponent {info['exponent']:.3f} +- {info['exponent_se']:.3f} "
                     f"(free space 2; d0 = 1 m)")
    elif pl.kind != "free":
        lines.append(f"path loss: {pl.describe()}")
    offsets = training.link_offsets_db or []
    if offsets:
        text = ", ".join(f"{o['tx']}->{o['rx']} {o['offset_db']:+.2f} +- {o['se_db']:.2f} dB" for o in offsets)
        lines.append(f"electronics offsets (each link's two directions sum to 0): {text}")
    learned = learned_directions(training) or set()
    alone = sorted((a, b) for a, b in learned if (b, a) not in learned)
    if alone:
        lines.append(f"learned in one direction only: {', '.join(f'{a}->{b}' for a, b in alone)} (the other direction "
                     "is predicted as reciprocal: offset 0)")
    return lines


__all__ = ["directed_counts", "learned_directions", "offset_name", "regression_inputs", "shared_fields", "shared_names",
           "split_offset_name", "statistics_counts", "terms_text"]
