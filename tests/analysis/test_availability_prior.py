"""Acceptance 1 of issue 28 with a reference pattern as prior: ``fit --prior``, then ``predict
--sensitivity``, on the planner's held-out flights.

Split from ``test_availability_calibration.py`` (whose docstring gives the measurements and
why item 1 is not met where it is not); its simulations (``held_out``, cached per session) and
scores are reused here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_availability_calibration import _RUNS, MIN_BIN, held_out, planner_flights, scores, skill

from rplearn.data.units import split_units
from rplearn.io.files import read_dataset

# --- a reference pattern as prior: `fit --prior`, then `predict --sensitivity` ------------------

#: (preset, how the prior's spread is set) on the planner's flights (``exact``: the near-exact
#: reference of :func:`prior_run`, its 0.5 dB stated): learned from the prior's
#: misfit to the learning flights (the default), or stated as the smooth error's RMS that
#: :func:`rplearn.sim.imperfect_reference` gives the reference (2 dB, a vendor's tolerance,
#: ``--prior-std 2``; its 10-deg mounting error is not in it, as a vendor's sheet would not say;
#: on ``ground`` only: on ``campaign`` it changes the figures by at most 0.04, module docstring).
PRIOR_CASES = [("paper", "learned"), ("campaign", "learned"), ("ground", "learned"), ("ground", "stated"),
               ("ground", "exact")]
#: The reference's smooth error [dB RMS] that ``--prior-std`` states (sim.reference's default).
STATED_PRIOR_STD_DB = 2.0
#: A near-exact reference's smooth error [dB RMS] (no mounting error), stated as ``--prior-std``.
EXACT_ERROR_DB = 0.5


def _invoke(args, cwd: Path) -> str:
    from typer.testing import CliRunner

    from rplearn.cli import app

    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(cwd)
        res = CliRunner().invoke(app, [str(a) for a in args], env={"COLUMNS": "400"})
    assert res.exit_code == 0, f"{args}: {res.output}"
    return res.output


_PRIOR_RUNS: dict[str, tuple] = {}
_PRIOR_SCORES: dict[tuple, tuple[float, float, int]] = {}


def prior_run(preset: str, tmp_path_factory) -> tuple:
    """The planner's case of ``preset`` (seed 0; the simulation of :func:`held_out` reused when
    ``ranging`` ran it) with what a user with a reference pattern runs: the simulator's imperfect
    reference of each antenna (a vendor's sheet or a chamber's: the true antenna turned 10 deg on
    its mount, plus a smooth 2-dB error; never the installed truth), ``rplearn reference``, then
    ``rplearn fit --order auto --prior NODE=ref.json`` with the spread learned (and, on
    ``ground``, stated: ``--prior-std 2``, and a near-exact reference). Returns
    (preset, folder, simulation, the fits' files by setting, the no-prior case of
    :func:`held_out`), once per preset and session."""
    from rplearn.sim import imperfect_reference

    if preset in _PRIOR_RUNS:
        return _PRIOR_RUNS[preset]
    flights = planner_flights(preset, 0)
    key = (preset, 0, tuple(u.label for u in flights))
    if key not in _RUNS:
        held_out(tmp_path_factory.mktemp(f"planner_{preset}"), preset, flights=flights)
    tmp, sim, _ = _RUNS[key]
    df = read_dataset(str(tmp / "m.parquet"))
    nodes = sorted(set(df["tx"]) | set(df["rx"]))
    _, test = split_units(df, None, None)
    df[df["unit"].isin(test)].reset_index(drop=True).to_parquet(tmp / "held_out.parquet")
    for n in nodes:
        imperfect_reference(sim.ground_truth, n, seed=0).to_csv(tmp / f"ref_{n}.csv", index=False)
    _invoke(["reference", *[f"{n}=ref_{n}.csv" for n in nodes], "-o", "ref.json"], tmp)
    priors = [a for n in nodes for a in ("--prior", f"{n}=ref.json")]
    fits = {"learned": "prior.json"}
    _invoke(["fit", "m.parquet", "--order", "auto", *priors, "-o", fits["learned"]], tmp)
    if preset == "ground":
        fits["stated"] = "stated.json"
        _invoke(["fit", "m.parquet", "--order", "auto", *priors, "--prior-std", STATED_PRIOR_STD_DB, "-o", fits["stated"]],
                tmp)
    if preset == "ground":  # a near-exact reference (0.5 dB smooth error, no mounting error), stated as such
        for n in nodes:
            imperfect_reference(sim.ground_truth, n, EXACT_ERROR_DB, 0.0, seed=0).to_csv(tmp / f"exact_{n}.csv", index=False)
        _invoke(["reference", *[f"{n}=exact_{n}.csv" for n in nodes], "-o", "exact_ref.json"], tmp)
        fits["exact"] = "exact.json"
        _invoke(["fit", "m.parquet", "--order", "auto", *[a for n in nodes for a in ("--prior", f"{n}=exact_ref.json")],
                 "--prior-std", EXACT_ERROR_DB, "-o", fits["exact"]], tmp)
    _PRIOR_RUNS[preset] = (preset, tmp, sim, fits, _RUNS[key][2])
    return _PRIOR_RUNS[preset]


def prior_scores(run, setting: str, q: int) -> tuple[float, float, int]:
    """(Brier skill, largest bin gap, number of bins) of ``predict --sensitivity`` with the
    prior fit of ``setting`` on the planner's flights, at the q-th percentile of their RSSI."""
    preset, tmp, _, fits, _ = run
    if (preset, setting, q) in _PRIOR_SCORES:
        return _PRIOR_SCORES[preset, setting, q]
    rssi = pd.read_parquet(tmp / "held_out.parquet", columns=["rssi_dbm"])["rssi_dbm"].to_numpy(np.float64)
    s = float(np.round(np.percentile(rssi, q))) - 0.5
    out = f"pred_{setting}_{q}.parquet"
    _invoke(["predict", fits[setting], "held_out.parquet", "-o", out, "--sensitivity", s], tmp)
    table = pd.read_parquet(tmp / out)
    p, up = table["availability"].to_numpy(np.float64), (table["rssi_dbm"].to_numpy(np.float64) >= s).astype(float)
    bins = np.minimum((p * 10).astype(int), 9)
    gaps = [abs(up[bins == b].mean() - p[bins == b].mean()) for b in range(10) if (bins == b).sum() >= MIN_BIN]
    _PRIOR_SCORES[preset, setting, q] = (skill(p, up), max(gaps), len(gaps))
    return _PRIOR_SCORES[preset, setting, q]


_REFERENCE_OFF = ("the reference, 2.7 dB RMS per antenna over the sphere, is off by {rms} dB RMS (joint, mean {mean}) "
                  "on these rows: its 10-deg mounting error moves the gimbal's shadow, where the learning flights looked "
                  "(the drone's end {d_band} dB there, the station's {g_band}; only their sum is seen), so the level is "
                  "matched where it is worst; and the held-out flights find the reference kept above the chosen order "
                  "worse there ({kept} against {cut} dB validation RMSE cut to {order}), so the fit cuts it to {order}. "
                  "A reference alone with its true RMS as spread scores {alone}")
#: The prior's cases (seed 0) where item 1 is not met, and why (measured; module docstring).
_PRIOR_NOT_MET: dict[tuple, str] = {
    ("paper", "learned", 10): "skill 0.157, bins off by 0.095 (without the prior 0.171, 0.088): the oracle itself "
                              "reaches only 0.201",
    ("paper", "learned", 30): "skill 0.302 but bins off by 0.057 (without the prior 0.324, 0.040): where the flights "
                              "looked the prior only adds its error (SH-14 chosen, SH-15 without it)",
    **{("campaign", setting, q): f"skill {sk}, bins off by {gap}: " + _REFERENCE_OFF.format(
        rms=7.05, mean="+5.3", d_band=-3.6, g_band="+4.1", order="SH-6", kept=5.81, cut=5.64, alone="0.279 / 0.150, bins 0.36 / 0.24")
       for (setting, q), (sk, gap) in {("learned", 10): (0.200, 0.253), ("learned", 30): (0.127, 0.345)}.items()},
    **{("ground", setting, q): f"skill {sk}, bins off by {gap}: " + _REFERENCE_OFF.format(
        rms=7.47, mean="+5.9", d_band=-3.7, g_band="+4.4", order="SH-5", kept=5.29, cut=4.32, alone="0.299 / 0.198, bins 0.23 / 0.23")
       for (setting, q), (sk, gap) in {("learned", 10): (0.131, 0.305), ("learned", 30): (0.107, 0.397),
                                       ("stated", 10): (0.152, 0.302), ("stated", 30): (0.084, 0.412)}.items()},
    **{("ground", "exact", q): f"skill {sk} (the oracle's {oracle}) but the worst bin off by {gap}: the near-exact "
                               "reference kept to SH-15 with a deviation of SH-2 fitted on the band"
       for q, sk, oracle, gap in ((10, 0.369, 0.379, 0.068), (30, 0.343, 0.364, 0.059))},
}


@pytest.mark.slow
@pytest.mark.parametrize("q", [10, 30])
@pytest.mark.parametrize(("preset", "setting"), PRIOR_CASES, ids=["-".join(c) for c in PRIOR_CASES])
def test_item_1_on_the_planners_flights_with_a_reference_prior(preset, setting, q, request, tmp_path_factory):
    """Item 1 on the planner's flights (seed 0) of availability that ``predict --sensitivity``
    writes with a model that ``fit --prior`` learned from the learning flights and the
    simulator's imperfect reference patterns (:func:`prior_run`)."""
    if (preset, setting, q) in _PRIOR_NOT_MET:
        request.applymarker(pytest.mark.xfail(strict=True, raises=AssertionError,
                                              reason=f"issue 28 item 1 not met: {_PRIOR_NOT_MET[preset, setting, q]}"))
    brier_skill, gap, n_bins = prior_scores(prior_run(preset, tmp_path_factory), setting, q)
    assert n_bins >= 2 and gap <= 0.05 and brier_skill >= 0.3, (preset, setting, q, brier_skill, gap)


@pytest.mark.slow
@pytest.mark.parametrize("q", [10, 30])
@pytest.mark.parametrize("preset", ["campaign", "ground"])
def test_a_reference_prior_corrects_most_of_what_the_learning_flights_never_saw(preset, q, tmp_path_factory):
    """Where item 1 is far without a prior (the planner's flights on ``ground`` and
    ``campaign``), the imperfect reference lifts the skill by at least 0.5 and brings the worst
    bin at least 0.1 closer. Measured, seeds 0 / 1 / 2 (q10, q30): skill +2.0 +0.9 / +3.9 +1.6 /
    +2.1 +1.2 (``ground``), +2.7 +1.4 / +3.3 +1.4 / +2.8 +1.4 (``campaign``); the worst bin
    0.15-0.63 closer."""
    run = prior_run(preset, tmp_path_factory)
    own_skill, own_gap = scores(run[4], q)[:2]
    prior_skill, prior_gap, _ = prior_scores(run, "learned", q)
    assert prior_skill >= own_skill + 0.5 and prior_gap <= own_gap - 0.1, (preset, q, own_skill, prior_skill, own_gap, prior_gap)


@pytest.mark.slow
def test_a_near_exact_reference_prior_gives_near_the_oracles_skill(tmp_path_factory):
    """With a reference 0.5 dB RMS from the truth (no mounting error) and that stated as its
    tolerance, availability on ``ground``'s planner flights (seed 0) reaches item 1's skill at
    q10 and q30: the reference is what a planner flying where the learning flights never looked
    needs, and the fit keeps its degrees above the chosen order (:mod:`rplearn.models.auto_prior`).

    Measured (seed 0): skill 0.369 / 0.343, bins off by 0.068 / 0.059, against the oracle's
    0.379 / 0.364. The held-out units found the reference kept to SH-15 (tapered; deviation
    SH-2, validation 4.273 dB) better than cut to the chosen order (SH-4, 4.298 dB), so it was
    kept. Cut to SH-4, as the fit did before, it scored 0.137 / 0.061 (bins 0.31 / 0.37). Seeds
    1 and 2 (not run here): seed 1 kept (deviation SH-3, 4.303 against 4.295 dB, within noise),
    0.250 / 0.453, bins 0.175 / 0.041 (oracle 0.282 / 0.473); seed 2 cut (4.344 against 4.308 dB,
    worse beyond noise), 0.163 / 0.255 as before."""
    run = prior_run("ground", tmp_path_factory)
    got = [prior_scores(run, "exact", q)[0] for q in (10, 30)]
    assert min(got) >= 0.3, got
