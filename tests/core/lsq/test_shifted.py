"""rplearn.core.lsq.shifted: the statistics of ``y - X t`` from those of ``y`` equal the
statistics accumulated from ``y - X t`` itself (issue 28: the order search on a prior's deviation)."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.bases import make_basis
from rplearn.core.geometry import Directions
from rplearn.core.lsq.normal_equations import NormalEquations
from rplearn.core.lsq.shifted import shifted_statistics


def _case(environment: bool, seed: int = 3):
    rng = np.random.default_rng(seed)
    n, n_nodes = 4000, 3
    basis = make_basis("sh", 5)
    az, el = rng.uniform(-np.pi, np.pi, (2, n)), np.arcsin(rng.uniform(-0.9, 0.9, (2, n)))
    d = Directions(az[0], el[0], az[1], el[1])
    tx = rng.integers(0, n_nodes, n)
    rx = (tx + rng.integers(1, n_nodes, n)) % n_nodes
    y = rng.normal(size=n) - 50.0 + 4.0 * np.cos(el[0])
    env = rng.uniform(-20.0, -10.0, n) if environment else None
    t = rng.normal(size=(n_nodes, basis.n_coef))
    ft, fr = basis.design(d.az_tx, d.el_tx), basis.design(d.az_rx, d.el_rx)
    xt = np.einsum("ij,ij->i", ft, t[tx]) + np.einsum("ij,ij->i", fr, t[rx])
    return basis, n_nodes, d, tx, rx, y, env, t, xt


@pytest.mark.parametrize("environment", [False, True])
def test_shifted_statistics_are_those_of_the_residuals(environment):
    basis, n_nodes, d, tx, rx, y, env, t, xt = _case(environment)
    normal = NormalEquations(basis, n_nodes, environment=environment).add(d, tx, rx, y, env)
    direct = NormalEquations(basis, n_nodes, environment=environment).add(d, tx, rx, y - xt, env)
    links = normal.two_way_links()
    for got, want in ((shifted_statistics(normal, t.ravel()), direct),
                      (shifted_statistics(normal.with_shared(links), t.ravel()), direct.with_shared(links))):
        scale = float(np.max(np.abs(want.rhs)))
        assert np.max(np.abs(got.rhs - want.rhs)) <= 1e-10 * scale
        assert got.yty == pytest.approx(want.yty, rel=1e-10)
        a, s = got.column_sums()
        b, r = want.column_sums()
        assert np.allclose(a, b, rtol=0, atol=1e-9 * np.max(np.abs(b))) and s == pytest.approx(r, rel=1e-10)
        assert got.env_y == pytest.approx(want.env_y, rel=1e-10, abs=1e-9)
        assert np.array_equal(got.gram, want.gram) or np.allclose(got.gram, want.gram, rtol=1e-12, atol=1e-9)
    # the statistics of y are unchanged, and a merge into the shifted copy never writes into them
    before = normal.gram.copy()
    shifted = shifted_statistics(normal, t.ravel())
    shifted.merge(NormalEquations(basis, n_nodes, environment=environment).add(d, tx, rx, y, env))
    assert np.array_equal(normal.gram, before)
    # shifted then appended equals appended then shifted (the shared columns read the shifted sums of y)
    late = shifted_statistics(normal, t.ravel()).with_shared(links)
    early = shifted_statistics(normal.with_shared(links), t.ravel())
    assert np.allclose(late.rhs, early.rhs, rtol=1e-12, atol=1e-9 * float(np.max(np.abs(early.rhs))))


def test_a_merge_into_the_shifted_statistics_leaves_the_originals_environment_sums():
    """Review 37: the shifted copy shared ``env_cross`` with the statistics it came from, so a
    merge (or add) into it wrote into the original's environment sums."""
    basis, n_nodes, d, tx, rx, y, env, t, _ = _case(True)
    normal = NormalEquations(basis, n_nodes, environment=True).add(d, tx, rx, y, env)
    before = normal.env_cross.copy()
    shifted = shifted_statistics(normal, t.ravel())
    shifted.merge(NormalEquations(basis, n_nodes, environment=True).add(d, tx, rx, y, env))
    shifted.add(d, tx, rx, y, env)
    np.testing.assert_array_equal(normal.env_cross, before)
