"""Cholesky factors of the selection and the posteriors: the same numbers as numpy's solves and
inverses, at sizes whose leading dimension would alias (multiples of 64) and others, and the
interpreter lock let go during the LAPACK calls."""

from __future__ import annotations

import numpy as np
import pytest

from rplearn.core.lsq.solver_cholesky import constrained_inverse, factor_inverse, factor_inverse_upper, factor_solve, spd_factor, symmetric_inner


def _spd(rng, p, condition=1e6):
    q, _ = np.linalg.qr(rng.standard_normal((p, p)))
    a = (q * np.geomspace(1.0, condition, p)) @ q.T
    return 0.5 * (a + a.T)


def _relative(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("p", [1, 7, 64, 130, 256, 301])
def test_solves_and_inverses_equal_numpys(p):
    rng = np.random.default_rng(p)
    a = _spd(rng, p)
    factor = spd_factor(a)
    assert factor is not None
    np.testing.assert_allclose(np.triu(factor).T @ np.triu(factor), a, rtol=0, atol=1e-12 * np.abs(a).max())
    b, many = rng.standard_normal(p), rng.standard_normal((p, 3))
    # condition 1e6: 1e-10 of the solution's size leaves room for rounding
    assert _relative(factor_solve(factor, b), np.linalg.solve(a, b)) < 1e-9
    assert _relative(factor_solve(factor, many), np.linalg.solve(a, many)) < 1e-9
    inverse = factor_inverse(factor)
    assert np.array_equal(inverse, inverse.T)
    assert _relative(inverse, np.linalg.inv(a)) < 1e-9


@pytest.mark.parametrize("p", [1, 7, 130, 301])
def test_sums_over_the_inverse_are_read_off_its_upper_triangle(p):
    """``factor_inverse_upper`` is the upper triangle of ``factor_inverse`` (zeros below), and
    ``symmetric_inner`` of it with a symmetric matrix is ``tr(A^-1 M)`` of the whole inverse."""
    rng = np.random.default_rng(40 + p)
    a = _spd(rng, p, condition=1e4)
    factor = spd_factor(a)
    assert factor is not None
    upper, whole = factor_inverse_upper(factor), factor_inverse(factor)
    assert np.array_equal(upper, np.triu(whole))
    x = rng.standard_normal((2 * p, p))
    m = x.T @ x
    m = 0.5 * (m + m.T)
    assert symmetric_inner(upper, m) == pytest.approx(float(np.sum(whole * m)), rel=1e-12)
    assert symmetric_inner(upper, m) == pytest.approx(float(np.trace(np.linalg.solve(a, m))), rel=1e-8)


def test_a_well_conditioned_system_agrees_to_1e_10():
    rng = np.random.default_rng(3)
    a = _spd(rng, 512, condition=1e3)  # 512: factorised in a padded buffer
    b = rng.standard_normal(512)
    factor = spd_factor(a.copy(), overwrite=True)
    assert _relative(factor_solve(factor, b), np.linalg.solve(a, b)) < 1e-10
    assert _relative(factor_inverse(factor), np.linalg.inv(a)) < 1e-10


def test_the_matrix_is_left_alone_unless_it_may_be_overwritten():
    a = _spd(np.random.default_rng(4), 20)
    kept = a.copy()
    spd_factor(a)
    assert np.array_equal(a, kept)


def test_a_matrix_that_is_not_positive_definite_has_no_factor():
    a = np.diag([1.0, -1.0, 2.0])
    assert spd_factor(a) is None
    assert constrained_inverse(a, np.ones((1, 3))) is None


@pytest.mark.parametrize("k", [0, 1, 3])
def test_the_constrained_inverse_is_the_kkt_inverse_block(k):
    rng = np.random.default_rng(10 + k)
    p = 40
    a = _spd(rng, p, condition=1e4)
    c = rng.standard_normal((k, p))
    kkt = np.block([[a, c.T], [c, np.zeros((k, k))]])
    expected = np.linalg.inv(kkt)[:p, :p]
    got = constrained_inverse(a, c)
    assert np.array_equal(got, got.T)
    assert _relative(got, expected) < 1e-10
    if k:
        np.testing.assert_allclose(c @ got, 0.0, atol=1e-10 * np.abs(got).max())  # the constraints hold


def test_the_lapack_calls_let_go_of_the_interpreter_lock():
    """The routines are ctypes C functions (CFUNCTYPE, not PYFUNCTYPE), which release the
    interpreter lock during the call: the selection factorises its folds on two workers at once
    (scipy's own wrappers hold the lock)."""
    import ctypes

    from rplearn.core.lsq.solver_cholesky import _routine

    for name in ("dpotrf", "dpotri", "dpotrs"):
        routine = _routine(name)
        assert isinstance(routine, ctypes._CFuncPtr)
        assert not routine._flags_ & ctypes._FUNCFLAG_PYTHONAPI  # PYFUNCTYPE would hold the lock


@pytest.mark.parametrize("p", [5, 64, 130])
def test_scipys_wrappers_give_the_same_numbers(monkeypatch, p):
    """Where the capsules cannot be had, scipy's wrappers (the same LAPACK) do the work: equal."""
    from rplearn.core.lsq import solver_cholesky as sc

    rng = np.random.default_rng(20 + p)
    a, c = _spd(rng, p), rng.standard_normal((2, p))
    b, many = rng.standard_normal(p), rng.standard_normal((p, 3))

    def run():
        factor = sc.spd_factor(a)
        return (np.triu(factor), sc.factor_solve(factor, b), sc.factor_solve(factor, many),
                sc.factor_inverse(factor), sc.constrained_inverse(a, c), sc.spd_factor(np.diag([1.0, -1.0])))

    through_capsules = run()
    monkeypatch.setattr(sc, "_routine", lambda name: None)
    through_wrappers = run()
    for got, expected in zip(through_wrappers[:-1], through_capsules[:-1]):
        assert np.array_equal(got, expected)
    assert through_wrappers[-1] is None and through_capsules[-1] is None


def test_a_capsule_of_another_signature_gives_no_routine(monkeypatch):
    """An ILP64 build (64-bit integers) or any other signature: scipy's wrappers instead."""
    from rplearn.core.lsq import solver_cholesky as sc

    assert sc._routine.__wrapped__("dpotrf") is not None  # this build's signature is the expected one
    monkeypatch.setattr(sc, "_capsule_name", lambda capsule: b"void (char *, int64_t *, double *, int64_t *, int64_t *)")
    assert sc._routine.__wrapped__("dpotrf") is None


def test_the_process_wide_c_api_prototypes_are_left_alone(monkeypatch):
    import ctypes

    from rplearn.core.lsq import solver_cholesky as sc

    for fn in (ctypes.pythonapi.PyCapsule_GetName, ctypes.pythonapi.PyCapsule_GetPointer):
        monkeypatch.setattr(fn, "restype", ctypes.c_int)
        monkeypatch.setattr(fn, "argtypes", None)
    assert sc._routine.__wrapped__("dpotrs") is not None
    for fn in (ctypes.pythonapi.PyCapsule_GetName, ctypes.pythonapi.PyCapsule_GetPointer):
        assert fn.restype is ctypes.c_int and fn.argtypes is None


@pytest.mark.parametrize("shape", [(3,), (3, 4), (2, 2, 2)])
def test_a_matrix_that_is_not_square_is_refused(shape):
    from rplearn.errors import InputError

    with pytest.raises(InputError, match="matrix: expected a square matrix"):
        spd_factor(np.ones(shape))
    with pytest.raises(InputError, match="factor: expected a square matrix"):
        factor_solve(np.ones(shape), np.ones(3))
    with pytest.raises(InputError, match="factor: expected a square matrix"):
        factor_inverse(np.ones(shape))


@pytest.mark.parametrize("rhs_shape", [(4,), (2,), (4, 2), (3, 1, 1), ()])
def test_a_right_hand_side_of_other_rows_is_refused(rhs_shape):
    from rplearn.errors import InputError

    factor = spd_factor(_spd(np.random.default_rng(6), 3))
    with pytest.raises(InputError, match="rhs: expected 3 rows"):
        factor_solve(factor, np.ones(rhs_shape))


def test_a_factor_of_another_layout_or_type_gives_the_same_solution():
    rng = np.random.default_rng(7)
    a = _spd(rng, 9)
    b = rng.standard_normal(9)
    factor = spd_factor(a)
    expected = factor_solve(factor, b)
    assert np.array_equal(factor_solve(np.ascontiguousarray(factor), b), expected)  # C-ordered: copied
    assert np.array_equal(factor_solve(np.eye(3, dtype=int) * 2, [4, 2, 8]), [1.0, 0.5, 2.0])  # integers: float64
    assert np.array_equal(factor_solve(factor, list(b)), expected)


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_a_non_finite_diagonal_has_no_factor(bad):
    a = np.diag([1.0, 2.0, 3.0])
    a[1, 1] = bad
    assert spd_factor(a) is None
    assert constrained_inverse(a, np.ones((1, 3))) is None


def test_an_argument_error_is_raised_not_read_as_indefinite(monkeypatch):
    from rplearn.core.lsq import solver_cholesky as sc

    def invalid(*args):  # LAPACK's answer to an invalid argument: info = -(its position)
        args[-1]._obj.value = -4

    monkeypatch.setattr(sc, "_routine", lambda name: invalid)
    a = _spd(np.random.default_rng(8), 4)
    with pytest.raises(ValueError, match="dpotrf: argument 4 is invalid"):
        sc.spd_factor(a)
    with pytest.raises(ValueError, match="dpotri: argument 4 is invalid"):
        sc.factor_inverse(np.eye(4))


@pytest.mark.parametrize("k", [0, 1, 3])
def test_the_kkt_condition_is_the_solves(k):
    """The 1-norm condition of the scaled KKT matrix from the blocks of its inverse: the
    number :func:`rplearn.core.lsq.solver.solve` computes from the whole inverse."""
    from rplearn.core.lsq.solver_cholesky import kkt_condition

    rng = np.random.default_rng(30 + k)
    p = 25
    a = _spd(rng, p, condition=1e5) * np.geomspace(1.0, 100.0, p)[:, None] * np.geomspace(1.0, 100.0, p)[None, :]
    c = rng.standard_normal((k, p))
    kkt = np.block([[a, c.T], [c, np.zeros((k, k))]])
    scale = np.concatenate([1.0 / np.sqrt(np.diag(a)), np.ones(k)])
    kkt_s = kkt * scale[:, None] * scale[None, :]
    expected = np.linalg.cond(kkt_s, 1)
    inverse = np.linalg.inv(kkt)
    s_inverse = -inverse[p:, p:]
    assert kkt_condition(a, c, inverse[:p, :p], inverse[:p, p:], s_inverse) == pytest.approx(expected, rel=1e-6)


def test_dependent_constraints_or_a_near_singular_matrix_give_no_inverse():
    rng = np.random.default_rng(31)
    a = _spd(rng, 12, condition=1e3)
    row = rng.standard_normal(12)
    assert constrained_inverse(a, np.vstack([row, row + 1e-15 * rng.standard_normal(12)])) is None
    assert constrained_inverse(a, np.vstack([row, row])) is None
    assert constrained_inverse(a, row[None, :]) is not None
    near = np.array([[1.0, 1.0 - 1e-14], [1.0 - 1e-14, 1.0]])  # positive definite, condition 2e14
    assert spd_factor(near) is not None
    assert constrained_inverse(near, np.zeros((0, 2))) is None
    assert constrained_inverse(near, np.zeros((0, 2)), max_condition=np.inf) is not None
