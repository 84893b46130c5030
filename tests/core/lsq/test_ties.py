"""rplearn.core.lsq.ties (issue 24, acceptance 5): the points the held-out units cannot tell from
the best, which the choice takes the least smoothed of and the own-pattern spread averages."""

from __future__ import annotations

import numpy as np

from rplearn.core.lsq.selection_result import CurvePoint
from rplearn.core.lsq.ties import WITHIN_NOISE_FRACTION, tied_points


class _Points:
    """The parts of the evaluator the ties read: per-unit held-out squared errors and inflations."""

    def __init__(self, fold_sse, n=1000, cv=True):
        self.cv, self.n = cv, n
        self.fold_sse = {k: np.asarray(v, float) for k, v in fold_sse.items()}
        self.folds = [None] * len(next(iter(fold_sse.values())))
        self.asked = []

    def inflation(self, order, smoothing):
        self.asked.append((order, smoothing))
        return 2.0 + order + smoothing


def _points(ev):
    return [CurvePoint(o, s, float(np.sqrt(ev.fold_sse[(o, s)].sum() / ev.n))) for o, s in ev.fold_sse]


def test_three_units_tie_the_points_within_noise_with_their_inflations():
    ev = _Points({(8, 1e-4): [100.0, 100.0, 100.0],   # the best
                  (8, 1e-5): [101.0, 99.5, 100.2],    # within noise
                  (9, 1e-5): [100.9, 99.6, 100.3],    # within noise
                  (8, 0.0): [110.0, 110.0, 110.0]})   # worse in every unit
    pts = _points(ev)
    ties = tied_points(ev, pts[0], pts[::-1])
    assert ties[0] == (8, 1e-4, 2.0 + 8 + 1e-4)  # the best first, whatever the order given
    assert {t[:2] for t in ties} == {(8, 1e-4), (8, 1e-5), (9, 1e-5)}
    assert all(t[2] == 2.0 + t[0] + t[1] for t in ties)


def test_two_units_tie_the_points_within_the_cap_of_the_best_mean_square():
    """No standard error from two units: the cap alone says which points the units cannot exclude."""
    inside = 100.0 * (1.0 + 0.9 * WITHIN_NOISE_FRACTION)
    outside = 100.0 * (1.0 + 1.1 * WITHIN_NOISE_FRACTION)
    ev = _Points({(4, 1e-5): [50.0, 50.0], (5, 3e-5): [inside / 2, inside / 2], (4, 3e-6): [outside / 2, outside / 2]})
    pts = _points(ev)
    assert [t[:2] for t in tied_points(ev, pts[0], pts)] == [(4, 1e-5), (5, 3e-5)]


def test_no_held_out_units_no_ties():
    ev = _Points({(4, 1e-5): [50.0]}, cv=False)
    assert tied_points(ev, _points(ev)[0], _points(ev)) == [] and ev.asked == []
