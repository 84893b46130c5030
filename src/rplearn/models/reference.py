"""Reference patterns (measured or vendor) as models: ``rplearn reference``.

Each node's reference gains (:func:`rplearn.io.reference.read_reference_pattern`, body frame
after the mount) are expanded in spherical harmonics by penalised least squares: the smoothest
expansion (squared-Laplacian penalty, :mod:`rplearn.core.lsq.selection`) that passes through the
measured points, so that a pattern given on a few cuts (MSI) stays smooth between them. The
result is a :class:`~rplearn.models.patterns.PatternSet`, so that predict, links, orient, plot,
export and the report use it as they use a learned model, and ``fit --prior`` can shrink a
learned pattern toward it.

A reference states no uncertainty: its coefficient covariance is zero and its training RMSE is
the expansion's residual against the reference points (``training["rmse_db"]``); the model's
``training["reference"]`` names the files and mounts.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rplearn._budget import Cost, check_work
from rplearn.core.lsq.selection import DEFAULT_PENALTY_POWER, penalty_scale
from rplearn.core.plausible import describe_band, frequency_bands
from rplearn.core.sh import SphericalHarmonics
from rplearn.errors import InputError
from rplearn.io.reference import ReferenceSamples
from rplearn.models.patterns import PatternSet
from rplearn.models.training import TrainingSummary

#: SH order of a reference model (degrees 0..19): resolves features of about 180/20 = 9 degrees.
REFERENCE_ORDER = 20
#: Relative smoothing of the expansion: small, so that it passes through the reference points.
REFERENCE_SMOOTHING = 1e-7


def expansion_cost(n_directions: float, order: int = REFERENCE_ORDER) -> Cost:
    """What :func:`expand_reference` takes for ``n_directions`` directions: the design matrix
    and two products of its size (8 bytes a value), and its Gram (about 2 ns a multiply-add)."""
    cols = order * order
    return Cost(memory_bytes=24.0 * n_directions * cols + 1e8, seconds=1.0 + 2e-9 * n_directions * cols * cols)


def expand_reference(samples: ReferenceSamples, order: int = REFERENCE_ORDER,
                     smoothing: float = REFERENCE_SMOOTHING) -> tuple[np.ndarray, float]:
    """SH coefficients of one reference pattern and the RMS residual at its points [dB]."""
    check_work(samples.source, len(samples), lambda n: expansion_cost(n, order), "directions (a coarser grid fits)",
               bounds=(1, len(samples)))
    basis = SphericalHarmonics(order)
    x = basis.design(samples.az_rad, samples.el_rad)
    g = x.T @ x
    w = basis.roughness(DEFAULT_PENALTY_POWER)
    scale = penalty_scale(g)
    a = g + np.diag(smoothing * scale * w + 1e-12 * scale)
    coef = np.linalg.solve(a, x.T @ samples.gain_dbi)
    resid = x @ coef - samples.gain_dbi
    return coef, float(np.sqrt(np.mean(resid**2)))


def reference_model(
    patterns: Mapping[str, ReferenceSamples],
    mounts: Mapping[str, Any] | None = None,
    order: int = REFERENCE_ORDER,
    provenance: Mapping[str, Any] | None = None,
) -> PatternSet:
    """A pattern set holding each node's reference pattern.

    Parameters
    ----------
    patterns : mapping of node to ReferenceSamples
    mounts : mapping of node to (roll, pitch, yaw) [deg], optional
        Recorded in the model (the samples are already mounted).
    order : int
        SH order of the expansion.
    """
    if not patterns:
        raise InputError("patterns: give at least one node's reference pattern", param="patterns")
    nodes = tuple(sorted(str(n) for n in patterns))
    coefs, residuals = [], {}
    freqs: list[float] = []
    for n in nodes:
        c, r = expand_reference(patterns[n], order)
        coefs.append(c)
        residuals[n] = r
        freq = patterns[n].frequency_hz
        if freq is not None:
            freqs.append(freq)
    basis = SphericalHarmonics(order)
    p = basis.n_coef
    training: dict[str, Any] = {
        "rmse_db": float(np.sqrt(np.mean([r**2 for r in residuals.values()]))),
        "n_samples": int(sum(len(patterns[n]) for n in nodes)),
        "reference": {n: {"source": patterns[n].source, "mount_rpy_deg": list((mounts or {}).get(n, (0.0, 0.0, 0.0))),
                          "expansion_rmse_db": residuals[n]} for n in nodes},
        "warnings": [],
    }
    if freqs:
        bands = frequency_bands(freqs)
        if len(bands) > 1:
            stated = {n: float(f) for n in nodes if (f := patterns[n].frequency_hz) is not None}
            listed = ", ".join(f"{n} ({patterns[n].source}) at {describe_band(f, f)}" for n, f in stated.items())
            raise InputError(f"patterns: the antennas are of {len(bands)} bands ({listed}); one model holds one band, "
                             "so make one reference model per band", param="patterns")
        training["frequency_hz"] = float(np.median(freqs))
    model = PatternSet(basis=basis, nodes=nodes, coef=np.array(coefs), covariance=np.zeros((len(nodes) * p, len(nodes) * p)),
                       gauge=[], training=TrainingSummary.from_dict(training))
    model.provenance = {**dict(provenance or {}), "model": f"reference {basis.label}"}
    return model


__all__ = ["REFERENCE_ORDER", "expand_reference", "reference_model"]
