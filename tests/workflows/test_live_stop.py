"""``rplearn live``'s spread stop: read over the sphere by default, over the covered directions
only with a coverage target, and never off a fit at the search's largest smoothing."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from rplearn.core.lsq.selection import MAX_SMOOTHING, at_smoothing_cap
from rplearn.errors import InputError
from rplearn.sim import simulate
from rplearn.workflows.live import LiveOptions, replay_session
from rplearn.workflows.live_status import LiveStatus, page_rows, spread_text


@pytest.fixture(scope="module")
def smoke() -> tuple[pd.DataFrame, pd.DataFrame]:
    r = simulate("smoke", seed=0)
    return r.pose_log, r.signal_log.drop(columns=["unit"])


def _replay(smoke, tmp_path, **kw):
    pose, sig = smoke
    seen: list[tuple[float, dict, dict, list]] = []

    def update(status):
        if status.spread_db:
            seen.append((status.elapsed_s, dict(status.spread_db), dict(status.sphere_spread_db), list(status.notes)))

    outcome = replay_session(pose, sig, str(tmp_path / "m.json"), LiveOptions(refit_s=5.0, **kw), on_update=update)
    return outcome, seen


def test_until_spread_reads_the_sphere(smoke, tmp_path):
    # the smoke flight never brings its sphere below 2 dB (3.5-3.9 dB at its end): it ends with the logs,
    # where the covered directions' spread is 1.2-1.6 dB after 15 s of its 76 s
    outcome, seen = _replay(smoke, tmp_path, until_spread_db=2.0)
    assert outcome.status.stopped == "end of the logs"
    assert min(outcome.status.sphere_spread_db.values()) > 2.0 > max(outcome.status.spread_db.values())
    # a target it reaches ends it there, said with what it was read over
    outcome, seen = _replay(smoke, tmp_path, until_spread_db=4.5)
    assert "every node's spread over the sphere below 4.5 dB" in outcome.status.stopped
    assert max(outcome.status.sphere_spread_db.values()) < 4.5
    assert outcome.status.elapsed_s < seen[-1][0] + 1e-9 and outcome.status.learned < len(smoke[1])
    assert all(max(sphere.values()) >= 4.5 for _, _, sphere, _ in seen[:-1])


def test_the_covered_spread_needs_a_coverage_target():
    with pytest.raises(InputError, match="over the covered directions needs a coverage target too") as err:
        LiveOptions(until_spread_db=2.0, spread_over="covered")
    assert err.value.param == "until_coverage_pct"
    with pytest.raises(InputError, match="spread_over: expected sphere or covered"):
        LiveOptions(spread_over="everywhere")
    LiveOptions(until_spread_db=2.0, spread_over="covered", until_coverage_pct=5.0)  # both given: taken
    LiveOptions(spread_over="covered")  # no spread target: nothing to read it over


def test_a_fit_at_the_largest_smoothing_ends_no_session(smoke, tmp_path):
    # the first refit (5 s, 189 samples) takes the largest smoothing: its covered spread read 0.00 dB and
    # ended the session at once; now it is not known (inf, with a note) and the session goes on
    outcome, seen = _replay(smoke, tmp_path, until_spread_db=2.0, spread_over="covered", until_coverage_pct=0.5)
    first_t, first_covered, first_sphere, first_notes = seen[0]
    assert math.isinf(max(first_covered.values())) and math.isinf(max(first_sphere.values()))
    assert any("not known yet: the fit took the largest smoothing" in n for n in first_notes)
    assert outcome.status.elapsed_s > first_t
    assert "every node's spread over the covered directions below 2 dB" in outcome.status.stopped
    assert all(math.isfinite(v) and v < 2.0 for v in outcome.status.spread_db.values())
    assert not any(n.startswith("spread: ") for n in outcome.status.notes)
    # the page draws no spread map the table calls not known
    from rplearn.viz.live_page import write_live_page

    for known in (True, False):
        page = (tmp_path / f"page_{known}.html")
        write_live_page(str(page), "live", [], [], outcome.fitted.model, spread_known=known)
        text = page.read_text()
        assert ("alt='spread maps'" in text) is known and ("Not known yet" in text) is not known
        assert "alt='coverage maps'" in text


def test_at_smoothing_cap():
    assert at_smoothing_cap(MAX_SMOOTHING) and not at_smoothing_cap(MAX_SMOOTHING / 10.0)
    assert not at_smoothing_cap(0.0) and not at_smoothing_cap(10.0)


def test_a_spread_not_known_reads_so_in_the_view():
    assert spread_text(math.inf) == "not known yet" and spread_text(1.234) == "1.23 dB"
    status = LiveStatus(spread_db={"A": math.inf}, sphere_spread_db={"A": math.inf}, coverage_pct={"A": 3.0})
    _, nodes = page_rows(status)
    assert nodes[1] == ["A", "3.0%", "not known yet", "not known yet"]
    assert "spread not known yet covered, not known yet sphere" in status.summary()
