"""Simulated calibration flights with known ground-truth patterns.

=================  =============================================================================
module             public names
=================  =============================================================================
``flight``         :func:`simulate` -> :class:`SimulationResult`, :func:`write_simulation`,
                   :func:`with_effects_off`
``config``         :class:`SimulationConfig` and its parts :class:`FlightConfig`,
                   :class:`EstimatorConfig`, :class:`RadioConfig`
``presets``        :func:`make_preset` (``paper``, ``trio``, ``smoke``), :data:`PRESET_NAMES`
``antennas``       :class:`GroundTruth`, :func:`load_ground_truth`, :class:`NodeAntenna`,
                   :class:`AntennaSpec`, :class:`Mounting`, :class:`AirframeLobe`,
                   :func:`antenna_from_name`
``gain_formulas``  ITU-R F.1336-5 patterns, half-wave dipole, cosine beam
=================  =============================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.sim import simulate``); its
module is imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # the simulator
    "SimulationResult": "flight",
    "simulate": "flight",
    "imperfect_reference": "reference",
    "with_effects_off": "flight",
    "write_simulation": "flight",
    # its configuration and presets
    "EstimatorConfig": "config",
    "FlightConfig": "config",
    "RadioConfig": "config",
    "SimulationConfig": "config",
    "PRESET_NAMES": "presets",
    "make_preset": "presets",
    # antennas and the ground truth
    "AirframeLobe": "antennas",
    "AntennaSpec": "antennas",
    "GroundTruth": "antennas",
    "MOUNTINGS": "antennas",
    "Mounting": "antennas",
    "NodeAntenna": "antennas",
    "antenna_from_name": "antennas",
    "load_ground_truth": "antennas",
    # gain formulas
    "cosine_beam_dbi": "gain_formulas",
    "half_wave_dipole_dbi": "gain_formulas",
    "itu_f1336_omni_average_dbi": "gain_formulas",
    "itu_f1336_omni_peak_dbi": "gain_formulas",
    "itu_f1336_sectoral_average_dbi": "gain_formulas",
    "itu_f1336_sectoral_peak_dbi": "gain_formulas",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
