"""The one work budget (rplearn._budget): refusals name the parameter, what it needs, and the
value that fits, found on the cost model; the budget comes from the environment."""

from __future__ import annotations

import math

import pytest

from rplearn._budget import Budget, Cost, budget, check_work, size_text, time_text
from rplearn.errors import InputError

LIMITS = Budget(memory_bytes=1000.0, seconds=10.0)


def test_a_value_within_the_budget_returns_its_cost():
    assert check_work("n", 7, lambda n: Cost(memory_bytes=100.0 * n), "items", limits=LIMITS) == Cost(700.0)


def test_the_largest_whole_value_that_fits_is_named():
    with pytest.raises(InputError, match=r"^n: 1,000,000 items would take about .* of memory .*; the largest that fits is 10 items$") as err:
        check_work("n", 1_000_000, lambda n: Cost(memory_bytes=100.0 * n), "items", limits=LIMITS)
    assert err.value.param == "n"
    with pytest.raises(InputError, match="the largest that fits is 3 items"):  # 3 s each: 9 s fits, 12 s does not
        check_work("n", 50, lambda n: Cost(seconds=3.0 * n), "items", limits=LIMITS)


def test_a_step_names_the_smallest_that_fits():
    with pytest.raises(InputError, match=r"step: 0\.001 deg would take about 2.78 h .*; use a step of at least 1 deg$"):
        check_work("step", 1e-3, lambda s: Cost(seconds=10.0 / s), "deg", integer=False, bounds=(1e-6, 90.0), falling=True, limits=LIMITS)


def test_nothing_fits_is_said():
    with pytest.raises(InputError, match="no value of n fits"):
        check_work("n", 5, lambda n: Cost(memory_bytes=1e9), "items", limits=LIMITS)


def test_disk_is_checked_against_the_outputs_folder(tmp_path):
    limits = Budget(1e30, 1e30, str(tmp_path / "new" / "folder"))  # the nearest existing parent counts
    assert 0 < limits.disk_bytes() < math.inf
    with pytest.raises(InputError, match="of disk"):
        check_work("n", 10, lambda n: Cost(disk_bytes=1e30 * n), "files", limits=limits)


def test_the_budget_comes_from_the_environment(monkeypatch):
    monkeypatch.setenv("RPLEARN_MAX_MEMORY", "2G")
    monkeypatch.setenv("RPLEARN_MAX_SECONDS", "30")
    assert budget() == Budget(2 * 2**30, 30.0)
    monkeypatch.delenv("RPLEARN_MAX_MEMORY")
    monkeypatch.delenv("RPLEARN_MAX_SECONDS")
    default = budget()
    assert default.seconds == 300.0 and 0 < default.memory_bytes < math.inf
    for name, bad in (("RPLEARN_MAX_MEMORY", "lots"), ("RPLEARN_MAX_MEMORY", "-1"), ("RPLEARN_MAX_SECONDS", "nan")):
        monkeypatch.setenv(name, bad)
        with pytest.raises(InputError, match=name):
            budget()
        monkeypatch.delenv(name)


def test_sizes_and_times_read_well():
    assert size_text(1.5 * 2**30) == "1.5 GiB" and size_text(512) == "512 B"
    assert time_text(45) == "45 s" and time_text(600) == "10 min" and time_text(3 * 86400) == "3 days"
