# Public names of rplearn.core: read by type checkers and IDEs, and by lazy_loader.attach_stub in
# __init__.py, which imports each name's module on first use. Only `from .module import name as
# name` lines here (tests/test_public_api.py).

from .geometry import (
    Directions as Directions,
    R_ENU_FROM_NED as R_ENU_FROM_NED,
    R_FRD_FROM_FLU as R_FRD_FROM_FLU,
    attitude_from_thrust as attitude_from_thrust,
    azimuth_elevation as azimuth_elevation,
    direction_in_body as direction_in_body,
    distance_m as distance_m,
    enu_to_ned as enu_to_ned,
    euler_from_quat_wxyz as euler_from_quat_wxyz,
    great_circle_angle as great_circle_angle,
    link_directions as link_directions,
    matrix_to_quat_wxyz as matrix_to_quat_wxyz,
    ned_to_enu as ned_to_enu,
    quat_enu_flu_to_ned_frd as quat_enu_flu_to_ned_frd,
    quat_ned_frd_to_enu_flu as quat_ned_frd_to_enu_flu,
    quat_wxyz_from_euler as quat_wxyz_from_euler,
    quat_wxyz_from_euler_enu_flu_deg as quat_wxyz_from_euler_enu_flu_deg,
    quat_wxyz_from_euler_ned_frd_deg as quat_wxyz_from_euler_ned_frd_deg,
    quat_wxyz_from_yaw as quat_wxyz_from_yaw,
    quat_wxyz_multiply as quat_wxyz_multiply,
    quat_wxyz_to_matrix as quat_wxyz_to_matrix,
    rotate_body_to_world as rotate_body_to_world,
    rotate_world_to_body as rotate_world_to_body,
    slerp_wxyz as slerp_wxyz,
    unit_vector as unit_vector,
    wrap_angle_rad as wrap_angle_rad,
    yaw_from_quat_wxyz as yaw_from_quat_wxyz,
)
from .link import (
    FAR_FIELD_WAVELENGTHS as FAR_FIELD_WAVELENGTHS,
    SPEED_OF_LIGHT_M_S as SPEED_OF_LIGHT_M_S,
    check_far_field as check_far_field,
    free_space_path_loss_db as free_space_path_loss_db,
    observed_joint_gain_db as observed_joint_gain_db,
    received_power_dbm as received_power_dbm,
    wavelength_m as wavelength_m,
)
from .environment import (
    DEFAULT_RELATIVE_PERMITTIVITY as DEFAULT_RELATIVE_PERMITTIVITY,
    PATH_LOSS_KINDS as PATH_LOSS_KINDS,
    PathLoss as PathLoss,
    log_distance_column as log_distance_column,
    reflection_coefficient as reflection_coefficient,
    two_ray_excess_db as two_ray_excess_db,
)
from .bases import (
    BASIS_KINDS as BASIS_KINDS,
    BasisGrid as BasisGrid,
    Polynomial as Polynomial,
    basis_from_dict as basis_from_dict,
    fibonacci_grid_nodes as fibonacci_grid_nodes,
    make_basis as make_basis,
    paper_grid_nodes as paper_grid_nodes,
)
from .basis_base import (
    Basis as Basis,
)
from .sh import (
    SphericalHarmonics as SphericalHarmonics,
    sh_index as sh_index,
)
from .solver import (
    DEFAULT_RIDGE as DEFAULT_RIDGE,
    FitReport as FitReport,
    GaugeNote as GaugeNote,
    JointSolution as JointSolution,
    fit_joint as fit_joint,
    identifiability as identifiability,
    independent_spread_db as independent_spread_db,
    link_components as link_components,
    solve as solve,
)
from .normal_equations import (
    NormalEquations as NormalEquations,
)
from .metrics import (
    Scores as Scores,
    Stopwatch as Stopwatch,
    aic as aic,
    condition_number as condition_number,
    mae as mae,
    q95 as q95,
    rmse as rmse,
    score as score,
)
