"""Sizes are checked before any work: models larger than their samples, grids, steps (issue 10)."""

from __future__ import annotations

import time

import pytest

from rplearn.analysis.headings import check_heading_tables, yaw_grid_deg
from rplearn.analysis.swarm import check_link_rows
from rplearn.errors import InputError
from rplearn.io.export import grid_angles_deg
from rplearn.models.spec import MAX_COLUMNS, ModelSpec, check_model_size


@pytest.mark.parametrize("text, n_coef", [("sh-10", 100), ("bg-7", 98), ("p-12", 91), ("m", 0), ("nn-400", 0)])
def test_model_sizes_follow_the_paper(text, n_coef):
    assert ModelSpec.parse(text).n_coef == n_coef


def test_a_model_larger_than_its_samples_is_refused_with_the_largest_that_fits():
    with pytest.raises(InputError, match="largest sh order that fits is 18") as err:
        check_model_size(ModelSpec.parse("sh-1000"), 665, 2, "d.parquet")
    assert err.value.param == "order" and "2,000,000 coefficients" in str(err.value)
    check_model_size(ModelSpec.parse("sh-18"), 665, 2)  # 648 unknowns from 665 samples: allowed
    with pytest.raises(InputError, match="16,384 a fit can hold in memory"):
        check_model_size(ModelSpec.parse("bg-100"), 10**9, 2)
    assert 2 * ModelSpec.parse("sh-90").n_coef <= MAX_COLUMNS


def test_fine_grids_and_steps_are_refused_before_allocation():
    for call in (lambda: grid_angles_deg(0.001), lambda: yaw_grid_deg(1e-6),
                 lambda: check_link_rows(10**8, 2, 1e-9), lambda: check_heading_tables(30, 0.1)):
        started = time.perf_counter()
        with pytest.raises(InputError):
            call()
        assert time.perf_counter() - started < 1.0
    check_heading_tables(30, 5.0)
    check_link_rows(1000, 30, 1.0)
