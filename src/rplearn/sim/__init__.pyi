# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .antennas import MOUNTINGS as MOUNTINGS
from .antennas import AirframeLobe as AirframeLobe
from .antennas import AntennaSpec as AntennaSpec
from .antennas import GroundTruth as GroundTruth
from .antennas import Mounting as Mounting
from .antennas import NodeAntenna as NodeAntenna
from .antennas import antenna_from_name as antenna_from_name
from .antennas import load_ground_truth as load_ground_truth
from .config import EstimatorConfig as EstimatorConfig
from .config import FlightConfig as FlightConfig
from .config import RadioConfig as RadioConfig
from .config import SimulationConfig as SimulationConfig
from .config import renamed_nodes as renamed_nodes
from .flight import SimulationResult as SimulationResult
from .flight import simulate as simulate
from .flight import with_effects_off as with_effects_off
from .flight import write_simulation as write_simulation
from .gain_formulas import cosine_beam_dbi as cosine_beam_dbi
from .gain_formulas import half_wave_dipole_dbi as half_wave_dipole_dbi
from .gain_formulas import itu_f1336_omni_average_dbi as itu_f1336_omni_average_dbi
from .gain_formulas import itu_f1336_omni_peak_dbi as itu_f1336_omni_peak_dbi
from .gain_formulas import itu_f1336_sectoral_average_dbi as itu_f1336_sectoral_average_dbi
from .gain_formulas import itu_f1336_sectoral_peak_dbi as itu_f1336_sectoral_peak_dbi
from .presets import PRESET_NAMES as PRESET_NAMES
from .presets import make_preset as make_preset
from .reference import imperfect_reference as imperfect_reference
