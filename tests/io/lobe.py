"""An analytic pattern-like for the export tests (tests/io/test_export.py, test_msi.py)."""

from __future__ import annotations

import numpy as np

from rplearn.core.geometry import unit_vector


class Lobe:
    """Analytic pattern: ``peak_dbi + 10 (cos(angle to lobe) - 1)`` per node [dBi]."""

    def __init__(self, lobes_deg: dict[str, tuple[float, float]], peak_dbi: float = 6.0):
        self.lobes = {
            n: unit_vector(np.radians(a), np.radians(e)) for n, (a, e) in lobes_deg.items()
        }
        self.nodes = tuple(lobes_deg)
        self.peak_dbi = peak_dbi

    def evaluate(self, node, az_rad, el_rad):
        u = unit_vector(az_rad, el_rad)
        return self.peak_dbi + 10.0 * (np.clip(u @ self.lobes[node], -1.0, 1.0) - 1.0)
