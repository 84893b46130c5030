"""Imperfect reference patterns of simulated antennas: what a vendor sheet or a chamber
measurement of a drone's antenna gives (for testing ``fit --prior`` and ``rplearn reference``).

The reference is the node's true pattern seen through a mounting error (the antenna rotated by
``mount_error_deg`` about the body's y axis) plus a smooth error field (a random spherical-harmonic
expansion of degrees 1-3, scaled to ``error_rms_db`` RMS over the grid), on a regular az-el grid,
as a body-frame CSV table (``az_deg, el_deg, gain_dbi``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from rplearn._argtypes import check_types
from rplearn.core.sh import SphericalHarmonics
from rplearn.errors import InputError
from rplearn.io.reference import mount_rotation


@check_types
def imperfect_reference(
    truth: Any, node: str, error_rms_db: float = 2.0, mount_error_deg: float = 10.0, seed: int = 0,
    step_deg: float = 3.0,
) -> pd.DataFrame:
    """A reference pattern of ``node`` with a smooth error and a mounting error (see the module docstring)."""
    if not (np.isfinite(step_deg) and 0.5 <= step_deg <= 30.0):
        raise InputError(f"step_deg: expected 0.5 to 30 degrees, got {step_deg!r}", param="step_deg")
    el, az = np.meshgrid(np.radians(np.arange(-90.0, 90.0 + 1e-9, step_deg)),
                         np.radians(np.arange(-180.0, 180.0, step_deg)), indexing="ij")
    az, el = az.ravel(), el.ravel()
    turned_az, turned_el = mount_rotation(az, el, (0.0, float(mount_error_deg), 0.0))
    gain = np.asarray(truth.evaluate(node, turned_az, turned_el), np.float64)
    basis = SphericalHarmonics(4)
    coef = np.random.default_rng(seed).normal(0.0, 1.0, basis.n_coef)
    coef[0] = 0.0
    err = basis.design(az, el) @ coef
    err *= float(error_rms_db) / max(float(np.sqrt(np.mean(err**2))), 1e-12)
    return pd.DataFrame({"az_deg": np.degrees(az), "el_deg": np.degrees(el), "gain_dbi": gain + err})


__all__ = ["imperfect_reference"]
