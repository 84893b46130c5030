"""Plausible link budgets: is what a fit learned physically possible, and if not, which input is wrong.

The observed joint gain (paper eq. 5) is ``rssi - tx_power + FSPL(distance, frequency)``: every
input of it a user gives or a reader guesses (``--tx-power``, ``--rssi-scale``,
``--frequency``, the station's place) moves what the fit learns. A wrong input does not make a
fit fail; it makes its numbers impossible. This module compares a fitted pattern model and its
learning samples with physical ranges and returns :class:`BudgetFinding` values, each naming
the input most likely wrong and by how much. ``fit`` prints them as warnings and stores them in
the model (``training["budget"]``).

Checks
------
- **Joint level** of each link (median observed joint gain ``G_tx + G_rx`` over its samples):
  within :data:`JOINT_LEVEL_RANGE_DB`. Outside, the transmit power or the RSSI scale is off by
  about ``level - JOINT_LEVEL_TYPICAL_DB``; when the frequency given is no common band and the
  difference is what a common band would give (``20 log10`` of their ratio), the frequency too.
- **Sphere-mean gain** (in linear power: the antenna's efficiency) of each node whose mean is
  identified (in no gauge: a swarm with odd cycles of links), within
  :data:`PATTERN_MEAN_RANGE_DBI`.
- **Distance trend** of each link: the slope of the joint gain against ``10 log10 d`` (an
  apparent path-loss exponent, free space 2) within :data:`EXPONENT_RANGE` when the distance
  varies by at least :data:`MIN_DISTANCE_SPREAD_DB`; outside, the distances are likely wrong
  (the station's place) or the environment is not free space.
- **Link offsets** (``fit`` with link offsets): the two directions of one link differ by at
  most :data:`LINK_OFFSET_LIMIT_DB`; beyond, the two radios' transmit powers or RSSI
  calibrations differ.

With ``rssi_scale="relative"`` (uncalibrated radios) absolute levels carry no meaning: the
level and sphere-mean checks are skipped, the distance trend and the offsets still checked.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.bases import fibonacci_grid_nodes
from rplearn.data.tables import LinkSamples, link_samples

#: Sphere-mean gain of one small drone or station antenna [dBi], averaged in linear power.
#: Upper bound: radiated power cannot exceed input power, so the sphere mean of the linear gain
#: of a passive antenna is its efficiency, at most 1 (0 dBi); +3 dB allows for an RSSI
#: calibration tolerance. Lower bound: a small antenna of at least ~10% efficiency (cable,
#: mismatch and frame losses included). (The mean of the dB pattern is no such bound: deep
#: nulls and frame shadows pull it 5-10 dB below the power mean; the ``trio`` simulator's patch
#: averages -11 dB in dB but -2 dBi in power.)
PATTERN_MEAN_RANGE_DBI: tuple[float, float] = (-10.0, 3.0)

#: A typical power-mean gain of a small antenna on a drone [dBi] (about 70% efficiency), from
#: which "by how much" a node's mean is off is measured.
PATTERN_MEAN_TYPICAL_DBI: float = -1.5

#: Joint level of a link, ``G_tx + G_rx`` at the directions flown (the median over its samples)
#: [dB]: two antennas each between -10 dBi (a small antenna's weak side) and +3 dBi (about the
#: peak of a dipole or a small drone antenna, 2-3 dBi).
JOINT_LEVEL_RANGE_DB: tuple[float, float] = (-20.0, 6.0)

#: A typical joint level [dB]: two near-omnidirectional antennas of about -2 dBi each toward
#: one another (a dipole's dB-mean is -0.5 dBi; frame, cable and mismatch losses of 1-3 dB).
#: "By how much" an input is off is measured from here.
JOINT_LEVEL_TYPICAL_DB: float = -4.0

#: Largest difference [dB] between the two directions of one link: the channel is reciprocal,
#: so the directions differ only by the two radios' transmit-power tolerances (about +-1.5 dB
#: each) and RSSI calibrations (about +-1.5 dB each).
LINK_OFFSET_LIMIT_DB: float = 6.0

#: Apparent path-loss exponents a link may show [1]: free space is 2, a ground reflection far
#: beyond its break point 4; below 1 or above 4 the distances themselves are likely wrong.
EXPONENT_RANGE: tuple[float, float] = (1.0, 4.0)

#: Distance spread [dB of 10 log10(d90 / d10)] below which no trend is judged (a hover).
MIN_DISTANCE_SPREAD_DB: float = 3.0

#: Common carrier frequencies of drone radios [Hz]: a level off by 20 log10 of the ratio of two
#: of them is what a wrong ``--frequency`` gives.
RADIO_BANDS_HZ: tuple[float, ...] = (433e6, 868e6, 915e6, 2.44e9, 5.8e9)

#: A frequency within this fraction of a common band is that band, and is not doubted.
BAND_TOLERANCE: float = 0.05

#: How close [dB] a level's error must come to a band ratio to name ``--frequency`` (only when
#: the frequency given is none of :data:`RADIO_BANDS_HZ`).
BAND_MATCH_DB: float = 2.5

#: Sphere directions to average a pattern over.
SPHERE_NODES: int = 2000


@check_types
@dataclass(frozen=True)
class BudgetFinding:
    """One implausible part of a link budget and the input most likely at fault.

    Attributes
    ----------
    check : {"level", "pattern-mean", "distance", "offset"}
    subject : str
        The link (``a<->b``) or node it concerns.
    value : float
        What was found: a level [dB], a sphere mean [dBi], an exponent [1] or a difference [dB].
    bounds : tuple of float
        The plausible range of ``value``.
    inputs : tuple of str
        The inputs most likely wrong, most likely first (``--tx-power``, ``--rssi-scale``,
        ``--frequency``, ``the station's place``, ...).
    off_by_db : float or None
        By about how much [dB] (signed: positive when the given input is too high), where it
        can be said.
    text : str
        One line for the user.
    """

    check: str
    subject: str
    value: float
    bounds: tuple[float, float]
    inputs: tuple[str, ...]
    off_by_db: float | None
    text: str

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["bounds"], out["inputs"] = list(self.bounds), list(self.inputs)
        return out


@check_types
@dataclass(frozen=True)
class LinkSummary:
    """What a link's samples say about its budget (both directions together).

    Attributes
    ----------
    a, b : str
        The two nodes.
    n : int
    level_db : float
        Median observed joint gain [dB].
    distance_m : tuple of float
        10th and 90th percentile of the distance [m].
    exponent : float
        Apparent path-loss exponent: 2 minus the slope of the joint gain against ``10 log10 d``
        (each direction about its own median).
    frequency_hz : float or None
        Median carrier frequency [Hz].
    """

    a: str
    b: str
    n: int
    level_db: float
    distance_m: tuple[float, float]
    exponent: float
    frequency_hz: float | None

    @property
    def name(self) -> str:
        return f"{self.a}<->{self.b}"

    @property
    def distance_spread_db(self) -> float:
        lo, hi = self.distance_m
        return float(10 * np.log10(hi / lo)) if lo > 0 else 0.0


@check_types
def link_summaries(samples: LinkSamples, min_samples: int = 10) -> list[LinkSummary]:
    """One :class:`LinkSummary` per pair of nodes with at least ``min_samples`` samples."""
    g = np.asarray(samples.joint_gain_db, np.float64)
    d = np.asarray(samples.distance_m, np.float64)
    tx, rx = np.asarray(samples.tx_index), np.asarray(samples.rx_index)
    lo, hi = np.minimum(tx, rx), np.maximum(tx, rx)
    n_nodes = max(len(samples.nodes), 1)
    # one integer per unordered pair (np.unique of the rows of a 2-column array sorts them as
    # opaque bytes: 20 times slower); the pairs come out in the same (lo, hi) order
    codes, group = np.unique(lo.astype(np.int64) * n_nodes + hi, return_inverse=True)
    pairs = np.stack([codes // n_nodes, codes % n_nodes], axis=1)
    group = np.asarray(group).ravel()
    order = np.argsort(group, kind="stable")
    bounds = np.searchsorted(group[order], np.arange(len(pairs) + 1))
    out = []
    for (i, j), a, b in zip(pairs.tolist(), bounds[:-1], bounds[1:]):  # one pass per link, not per row
        sel = order[a:b]
        if sel.size < min_samples:
            continue
        gl, dl, forward = g[sel], d[sel], tx[sel] == i
        centred = gl.copy()
        for way in (forward, ~forward):
            if way.any():
                centred[way] -= np.median(gl[way])
        x = 10 * np.log10(dl)
        x = x - x.mean()
        slope = float(x @ centred / (x @ x)) if x @ x > 0 else 0.0
        f = None if samples.frequency_hz is None else float(np.median(np.asarray(samples.frequency_hz)[sel]))
        out.append(LinkSummary(str(samples.nodes[i]), str(samples.nodes[j]), int(sel.size), float(np.median(gl)),
                               (float(np.percentile(dl, 10)), float(np.percentile(dl, 90))), 2.0 - slope, f))
    return out


def sphere_means_dbi(model: Any, nodes: Sequence[str]) -> dict[str, float]:
    """Mean of each node's pattern over the sphere in linear power [dBi] (equal-area directions):
    the antenna's efficiency, for a passive antenna at most 0 dBi."""
    az, el = fibonacci_grid_nodes(SPHERE_NODES)
    return {n: float(10 * np.log10(np.mean(10 ** (np.asarray(model.evaluate(n, az, el), np.float64) / 10))))
            for n in nodes}


def _band_hint(off_db: float, frequency_hz: float | None) -> str | None:
    """The carrier frequency that would explain a level ``off_db`` too low (or high), if any."""
    if not frequency_hz or any(abs(frequency_hz / band - 1) < BAND_TOLERANCE for band in RADIO_BANDS_HZ):
        return None  # a common band given: believed (two bands' ratio matching an error is a coincidence)
    for band in RADIO_BANDS_HZ:
        ratio_db = 20 * np.log10(band / frequency_hz)
        if abs(ratio_db) > BAND_MATCH_DB and abs(-ratio_db - off_db) <= BAND_MATCH_DB:
            return f"{band / 1e6:g} MHz"
    return None


def _level_finding(link: LinkSummary) -> BudgetFinding | None:
    lo, hi = JOINT_LEVEL_RANGE_DB
    if lo <= link.level_db <= hi:
        return None
    off = link.level_db - JOINT_LEVEL_TYPICAL_DB  # negative: the joint gain reads low
    inputs = ["--tx-power", "--rssi-scale"]
    band = _band_hint(off, link.frequency_hz)
    if band:
        inputs.append("--frequency")
    direction = "too high" if off < 0 else "too low"
    text = (f"link budget of {link.name}: its joint gain G_tx + G_rx is {link.level_db:+.1f} dB at "
            f"{link.distance_m[0]:.0f}-{link.distance_m[1]:.0f} m, outside the {lo:+.0f}..{hi:+.0f} dB two small "
            f"antennas allow: the transmit power given (--tx-power) is probably {direction} by about {abs(off):.0f} dB "
            f"(at least {min(abs(link.level_db - lo), abs(link.level_db - hi)):.0f} dB), or the RSSI is not in dBm "
            "(--rssi-scale; relative for uncalibrated radios)")
    if band and link.frequency_hz:
        text += (f", or the radio is on {band}, not {link.frequency_hz / 1e6:g} MHz (--frequency: "
                 f"{abs(off):.0f} dB is the free-space loss between the two)")
    return BudgetFinding("level", link.name, link.level_db, JOINT_LEVEL_RANGE_DB, tuple(inputs), -off, text)


def _distance_finding(link: LinkSummary) -> BudgetFinding | None:
    lo, hi = EXPONENT_RANGE
    if link.distance_spread_db < MIN_DISTANCE_SPREAD_DB or lo <= link.exponent <= hi:
        return None
    how = "faster" if link.exponent > 2 else "slower"
    text = (f"link budget of {link.name}: the joint gain changes with distance {how} than free space allows "
            f"(apparent path-loss exponent {link.exponent:.1f} over {link.distance_m[0]:.0f}-{link.distance_m[1]:.0f} m, "
            f"plausible {lo:g}..{hi:g}; free space 2): the distances are likely wrong, check the station's place "
            "(--station LAT,LON,ALT) and the position source, or learn the environment (--path-loss log-distance)")
    return BudgetFinding("distance", link.name, link.exponent, EXPONENT_RANGE, ("the station's place", "--path-loss"),
                         None, text)


def _offset_findings(offsets: Sequence[Mapping[str, Any]]) -> list[BudgetFinding]:
    out = []
    seen: set[frozenset[str]] = set()
    for o in offsets:
        pair = frozenset((str(o["tx"]), str(o["rx"])))
        if pair in seen:
            continue
        seen.add(pair)
        value, se = float(o["offset_db"]), float(o.get("se_db", 0.0))
        diff = 2 * abs(value)
        if diff <= LINK_OFFSET_LIMIT_DB or diff <= 2 * 3 * se:
            continue
        high, low = (o["tx"], o["rx"]) if value > 0 else (o["rx"], o["tx"])
        text = (f"link budget of {high}<->{low}: {high}->{low} reads {diff:.1f} dB above {low}->{high} (two radios "
                f"of one link differ by at most {LINK_OFFSET_LIMIT_DB:g} dB): {high}'s transmit power is about "
                f"{diff:.0f} dB higher than given relative to {low}'s (tx_power_dbm per direction, --tx-power), or "
                f"{low}'s RSSI reads {diff:.0f} dB high (its --rssi-scale or calibration)")
        out.append(BudgetFinding("offset", f"{high}<->{low}", diff, (-LINK_OFFSET_LIMIT_DB, LINK_OFFSET_LIMIT_DB),
                                 ("--tx-power", "--rssi-scale"), diff, text))
    return out


@check_types
def budget_findings(
    links: Sequence[LinkSummary],
    sphere_means: Mapping[str, float] | None = None,
    offsets: Sequence[Mapping[str, Any]] = (),
    relative: bool = False,
) -> list[BudgetFinding]:
    """Every implausible part of a fit's link budget (see the module docstring).

    Parameters
    ----------
    links : sequence of LinkSummary
        From the learning samples (:func:`link_summaries`).
    sphere_means : mapping of node to float, optional
        Sphere-mean gain [dBi] of the nodes whose mean is identified (in no gauge).
    offsets : sequence of mapping
        The model's ``training["link_offsets_db"]`` (``tx``, ``rx``, ``offset_db``, ``se_db``).
    relative : bool
        RSSI on an uncalibrated scale: no level or sphere-mean finding.
    """
    out: list[BudgetFinding] = []
    if not relative:
        out += [f for f in map(_level_finding, links) if f is not None]
        lo, hi = PATTERN_MEAN_RANGE_DBI
        for node, mean in (sphere_means or {}).items():
            if not lo <= mean <= hi:
                off = mean - PATTERN_MEAN_TYPICAL_DBI
                out.append(BudgetFinding(
                    "pattern-mean", node, mean, PATTERN_MEAN_RANGE_DBI, ("--tx-power", "--rssi-scale"), -2 * off,
                    f"link budget of {node}: its pattern's sphere-mean gain (in power) is {mean:+.1f} dBi, outside the "
                    f"{lo:+.0f}..{hi:+.0f} dBi a small passive antenna allows: the transmit power or the RSSI scale "
                    f"(--tx-power, --rssi-scale) is probably {'too high' if off < 0 else 'too low'} by about "
                    f"{2 * abs(off):.0f} dB on every link of {node} (each end of a link carries half of such an error)"))
    out += [f for f in map(_distance_finding, links) if f is not None]
    out += _offset_findings(offsets)
    return out


@check_types
def check_fit_budget(model: Any, samples: LinkSamples, relative: bool = False) -> list[BudgetFinding]:
    """The findings of a fitted pattern model on its learning samples, also stored in its training
    summary (``training["budget"]``, and each text in ``training["warnings"]``)."""
    if getattr(model, "kind", None) != "patterns":
        return []
    training = model.training
    gauged = {str(n) for g in training.gauges or () for n in g.get("nodes", [])}
    free = [n for n in model.nodes if n not in gauged]
    findings = budget_findings(link_summaries(samples), sphere_means_dbi(model, free) if free else None,
                               training.link_offsets_db or [], relative)
    model.training = training.replace(budget=[f.to_dict() for f in findings],
                                      warnings=(*(training.warnings or ()), *(f.text for f in findings)))
    return findings


@check_types
def check_dataset_budget(model: Any, part: pd.DataFrame, source: str = "dataset") -> list[BudgetFinding]:
    """:func:`check_fit_budget` on the learning rows of a matched dataset; their ``rssi_scale``
    column (``sync --rssi-scale relative``) says whether levels mean anything."""
    if getattr(model, "kind", None) != "patterns":
        return []
    relative = "rssi_scale" in part.columns and bool((part["rssi_scale"].astype(str).str.lower() == "relative").any())
    return check_fit_budget(model, link_samples(part, source, nodes=model.nodes), relative)


__all__ = [
    "BAND_MATCH_DB", "BAND_TOLERANCE", "BudgetFinding", "EXPONENT_RANGE", "JOINT_LEVEL_RANGE_DB",
    "JOINT_LEVEL_TYPICAL_DB", "LINK_OFFSET_LIMIT_DB", "LinkSummary", "MIN_DISTANCE_SPREAD_DB",
    "PATTERN_MEAN_RANGE_DBI", "PATTERN_MEAN_TYPICAL_DBI", "RADIO_BANDS_HZ", "SPHERE_NODES", "budget_findings",
    "check_dataset_budget", "check_fit_budget", "link_summaries", "sphere_means_dbi",
]
