"""The identifiability study of paper Sec. V-A: rank of the joint design for two and three antennas."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rplearn._argtypes import check_types
from rplearn.core.bases import SphericalHarmonics
from rplearn.core.geometry import Directions
from rplearn.core.lsq.solver import fit_joint, identifiability
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary

Progress = Callable[[str], None]


@check_types
@dataclass
class IdentifiabilityStudy:
    """Epsilon sweep of a two-antenna fit and the ranks of two- and three-antenna problems."""

    order: int
    epsilons: list[float]
    rmse_db: list[float]
    rank_cases: list[tuple[str, int, int]]
    two_node_patterns: PatternSet
    truth: Any

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": f"SH-{self.order}",
            "epsilon_sweep": [{"epsilon": e, "rmse_db": r} for e, r in zip(self.epsilons, self.rmse_db)],
            "ranks": [{"case": c, "columns": n, "rank": r} for c, n, r in self.rank_cases],
        }


@dataclass(frozen=True)
class _AntennaSet:
    """Surrogate antennas of the study: evaluate(node, az, el) like a ground truth."""

    antennas: Mapping[str, Any]

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(self.antennas)

    def evaluate(self, node: str, az_rad: np.ndarray, el_rad: np.ndarray) -> np.ndarray:
        return self.antennas[node].gain_dbi(az_rad, el_rad)


@check_types
def study_antennas() -> _AntennaSet:
    """The ITU-R F.1336-5 surrogates of the paper's Fig. 6: omni "O", sectoral "S", circular "C"."""
    from rplearn.sim.antennas import AntennaSpec, Mounting, NodeAntenna

    vertical = Mounting.named("vertical")
    return _AntennaSet(
        {
            "O": NodeAntenna(AntennaSpec("itu_omni_peak", g0_dbi=2.0, k=0.7), vertical, (), "ITU omni, 2 dBi"),
            "S": NodeAntenna(
                AntennaSpec("itu_sectoral_peak", g0_dbi=20.0, phi3_deg=45.0, theta3_deg=15.0), vertical, (), "ITU sectoral 45/15 deg, 20 dBi"
            ),
            "C": NodeAntenna(AntennaSpec("itu_omni_peak", g0_dbi=10.0, k=0.7), vertical, (), "ITU circular (omni) 10 dBi"),
        }
    )


@check_types
def identifiability_study(order: int = 8, n_samples: int = 20000, seed: int = 0) -> IdentifiabilityStudy:
    """Reproduce paper Sec. V-A with SH of degrees < ``order``.

    The paper's Fig. 6 reports 192 columns for three antennas, i.e. 64 per antenna: SH-8 in
    docs/conventions.md's labels (degrees 0..7), which is the default here.

    Pairwise transmissions at random directions between ITU antennas: with two antennas
    (C and S) the rank is one below the column count and +-epsilon on the two Y00 terms
    changes no prediction; with three antennas in a triangle the rank is full.
    """
    rng = np.random.default_rng(seed)
    ants = study_antennas()
    basis = SphericalHarmonics(order)

    def draw(pairs: np.ndarray, names: Sequence[str]) -> tuple[Directions, np.ndarray, np.ndarray, np.ndarray]:
        sel = pairs[rng.integers(0, len(pairs), n_samples)]
        az = rng.uniform(-np.pi, np.pi, (2, n_samples))
        el = np.arcsin(rng.uniform(-1, 1, (2, n_samples)))
        d = Directions(az[0], el[0], az[1], el[1])
        y = np.empty(n_samples)
        for t in range(len(names)):
            for r in range(len(names)):
                m = (sel[:, 0] == t) & (sel[:, 1] == r)
                if m.any():
                    y[m] = ants.evaluate(names[t], az[0][m], el[0][m]) + ants.evaluate(names[r], az[1][m], el[1][m])
        return d, sel[:, 0], sel[:, 1], y

    names2 = ["C", "S"]
    d, tx, rx, y = draw(np.array([[0, 1]]), names2)
    sol = fit_joint(d, tx, rx, y, 2, basis, names2)
    ft = basis.design(d.az_tx, d.el_tx)
    fr = basis.design(d.az_rx, d.el_rx)
    epsilons = [0.0] + [float(v) for v in np.logspace(-3, 6, 19)]
    rmses = []
    for eps in epsilons:
        c = sol.coef.copy()
        c[0, 0] += eps
        c[1, 0] -= eps
        rmses.append(float(np.sqrt(np.mean((ft @ c[0] + fr @ c[1] - y) ** 2))))
    names3 = ["O", "S", "C"]
    d3, tx3, rx3, _ = draw(np.array([[0, 1], [1, 2], [2, 0]]), names3)
    rep2 = sol.report
    rep3 = identifiability(d3, tx3, rx3, 3, basis, names3)
    patterns = PatternSet(basis, tuple(names2), sol.coef, gauge=[g.to_dict() for g in rep2.gauges], training=TrainingSummary.from_dict(rep2.to_dict()))
    cases = [("two antennas (C, S)", rep2.n_columns, rep2.rank), ("three antennas (O, S, C)", rep3.n_columns, rep3.rank)]
    return IdentifiabilityStudy(order, epsilons, rmses, cases, patterns, ants)
