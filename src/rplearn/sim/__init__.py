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
module is imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
