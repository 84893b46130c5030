# Public names of rplearn.sim: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .flight import (
    SimulationResult as SimulationResult,
    simulate as simulate,
    with_effects_off as with_effects_off,
    write_simulation as write_simulation,
)
from .reference import (
    imperfect_reference as imperfect_reference,
)
from .config import (
    EstimatorConfig as EstimatorConfig,
    FlightConfig as FlightConfig,
    RadioConfig as RadioConfig,
    SimulationConfig as SimulationConfig,
)
from .presets import (
    PRESET_NAMES as PRESET_NAMES,
    make_preset as make_preset,
)
from .antennas import (
    AirframeLobe as AirframeLobe,
    AntennaSpec as AntennaSpec,
    GroundTruth as GroundTruth,
    MOUNTINGS as MOUNTINGS,
    Mounting as Mounting,
    NodeAntenna as NodeAntenna,
    antenna_from_name as antenna_from_name,
    load_ground_truth as load_ground_truth,
)
from .gain_formulas import (
    cosine_beam_dbi as cosine_beam_dbi,
    half_wave_dipole_dbi as half_wave_dipole_dbi,
    itu_f1336_omni_average_dbi as itu_f1336_omni_average_dbi,
    itu_f1336_omni_peak_dbi as itu_f1336_omni_peak_dbi,
    itu_f1336_sectoral_average_dbi as itu_f1336_sectoral_average_dbi,
    itu_f1336_sectoral_peak_dbi as itu_f1336_sectoral_peak_dbi,
)
