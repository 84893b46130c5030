# Public names of rplearn.integrations: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .sionna import (
    SionnaUnavailableError as SionnaUnavailableError,
    add_link as add_link,
    import_sionna_rt as import_sionna_rt,
    planar_array as planar_array,
    polarization_mismatch_db as polarization_mismatch_db,
    register_pattern as register_pattern,
    sionna_orientation as sionna_orientation,
)
