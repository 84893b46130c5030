"""The copy rule of radio reports judged as they arrive (rplearn.io.tlog_copies) against the
offline rule over the whole log (rplearn.io.mavlink_phases.repeated_readings)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.io.mavlink_phases import repeated_readings
from rplearn.io.tlog_copies import ReportCopies


def _reports(seed: int, copies: bool, n: int = 3000) -> np.ndarray:
    """Reports ~0.5 s apart (jittered, on a microsecond clock at a UNIX epoch), readings drawn
    from few values (chance coincidences); with ``copies`` each repeated 2-6 ms later."""
    rng = np.random.default_rng(seed)
    t = 1.767e9 + np.cumsum(rng.uniform(0.3, 0.7, n))
    values = np.column_stack([rng.integers(100, 104, n), np.full(n, 255), rng.integers(0, 3, (n, 4))]).astype(float)
    if copies:
        t = np.concatenate([t, t + rng.uniform(0.002, 0.006, n)])
        values = np.concatenate([values, values])
    rows = np.column_stack([np.round(t * 1e6) / 1e6, values])
    return rows[np.lexsort(rows.T[::-1])]


@pytest.mark.parametrize("copies", [False, True], ids=["no-copies", "copies"])
def test_reports_judged_in_pieces_are_judged_as_the_whole_log_judges_them(copies):
    rows = _reports(0, copies)
    offline, period = repeated_readings(rows[:, 0], rows[:, 1:])
    assert offline.any() == copies
    running = ReportCopies()
    rng = np.random.default_rng(1)
    cuts = np.sort(rng.choice(np.arange(1, len(rows)), 40, replace=False))
    gaps = np.concatenate([running.add(part) for part in np.split(rows, cuts)])
    q_lo, q_hi, systematic = rule = running.rule()
    assert systematic is copies and q_lo <= 0.25 * period < q_hi < 1.01 * q_lo
    copy, uncertain = ReportCopies.verdicts(gaps, rule)
    assert uncertain.sum() <= 2
    np.testing.assert_array_equal(copy[~uncertain], offline[~uncertain])


def test_reports_left_behind_are_counted_when_the_rule_reverses_their_verdict():
    running = ReportCopies()
    gaps = running.add(_reports(2, copies=True))
    rule = running.rule()
    running.behind(gaps, rule)
    assert running.reversed_behind(rule) == 0
    copied = int(ReportCopies.verdicts(gaps, rule)[0].sum())
    assert running.reversed_behind((rule[0], rule[1], False)) == copied  # copies no longer systematic
    assert running.reversed_behind((rule[0], rule[1], False)) == 0


def test_the_state_is_a_few_bins_and_the_readings_of_the_last_seconds():
    running = ReportCopies()
    rows = _reports(3, copies=True, n=20_000)
    sizes = []
    for part in np.array_split(rows, 10):
        running.add(part)
        sizes.append(running.sizes())
    assert sizes[-1]["copies.bins"] == sizes[1]["copies.bins"]
    assert max(s["copies.seen"] for s in sizes) < 150  # values seen in the last 30 s
