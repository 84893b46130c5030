"""The penalty's unit: from the Gram matrix or from its diagonal (a nested order's, read off the
larger problem's), the same bits."""

from __future__ import annotations

import numpy as np

from rplearn.core.lsq.penalty import nested_columns, penalty_scale, penalty_scale_of_diagonal
from rplearn.core.sh import SphericalHarmonics


def test_the_unit_from_the_diagonal_is_the_unit_of_the_sub_block():
    rng = np.random.default_rng(0)
    big, small = SphericalHarmonics(5), SphericalHarmonics(3)
    x = rng.standard_normal((400, 2 * big.n_coef + 1))  # two nodes and one shared column
    gram = x.T @ x
    idx = nested_columns(big, small, 2)
    assert penalty_scale_of_diagonal(np.diag(gram)[idx]) == penalty_scale(gram[np.ix_(idx, idx)])
    assert penalty_scale_of_diagonal(np.diag(gram)[: 2 * big.n_coef]) == penalty_scale(gram, 2 * big.n_coef)


def test_without_positive_columns_the_unit_is_one():
    assert penalty_scale_of_diagonal(np.zeros(0)) == 1.0
    assert penalty_scale_of_diagonal(np.zeros(4)) == 1.0
    assert penalty_scale(np.zeros((3, 3))) == 1.0
