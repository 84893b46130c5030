# Public names of this package: read by type checkers and IDEs, and by lazy_loader.attach_stub
# in __init__.py, which imports each name's module on first use. Only `from .module import name
# as name` lines here (tests/test_public_api.py).

from .sionna import SceneLinkOptions as SceneLinkOptions
from .sionna import SionnaUnavailableError as SionnaUnavailableError
from .sionna import add_link as add_link
from .sionna import import_sionna_rt as import_sionna_rt
from .sionna import planar_array as planar_array
from .sionna import polarization_mismatch_db as polarization_mismatch_db
from .sionna import register_pattern as register_pattern
from .sionna import sionna_orientation as sionna_orientation
