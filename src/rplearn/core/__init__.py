"""The maths of rplearn, on numpy and scipy only: frames, the link budget, bases, the solver.

The least-squares engine is the subpackage :mod:`rplearn.core.lsq`, above the other modules
(it uses them; they never use it); its public names are exported here.

=====================  ==========================================================================
module                 public names
=====================  ==========================================================================
``geometry``           :class:`Directions`, :func:`link_directions`, :func:`direction_in_body`,
                       :func:`azimuth_elevation`, :func:`distance_m`, quaternion, Euler angle and
                       NED/ENU conversions
``link``               :func:`received_power_dbm` (paper eq. 1), :func:`free_space_path_loss_db`,
                       :func:`wavelength_m`, :func:`observed_joint_gain_db` (eq. 5)
``environment``        :class:`PathLoss` (``fit --path-loss``), :func:`log_distance_column`,
                       :func:`two_ray_excess_db`, :func:`reflection_coefficient`
``bases``, ``sh``      :class:`Basis`, :class:`SphericalHarmonics`, :class:`BasisGrid`,
                       :class:`Polynomial`, :func:`make_basis`, :func:`basis_from_dict`
``lsq``                the least-squares engine (a subpackage): :func:`fit_joint`, :func:`solve`,
                       :func:`identifiability`, :class:`FitReport`, :class:`JointSolution`,
                       :class:`NormalEquations` (streamed sufficient statistics)
``metrics``            :func:`score`, :class:`Scores`, :func:`rmse`, :func:`mae`, :func:`q95`,
                       :func:`aic`, :func:`condition_number`, :class:`Stopwatch`
=====================  ==========================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.core import fit_joint``);
its module is imported on first use (:mod:`rplearn._lazy`).
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # geometry: frames, attitudes, directions (paper eq. 3)
    "Directions": "geometry",
    "R_ENU_FROM_NED": "geometry",
    "R_FRD_FROM_FLU": "geometry",
    "attitude_from_thrust": "geometry",
    "azimuth_elevation": "geometry",
    "direction_in_body": "geometry",
    "distance_m": "geometry",
    "enu_to_ned": "geometry",
    "euler_from_quat_wxyz": "geometry",
    "great_circle_angle": "geometry",
    "link_directions": "geometry",
    "matrix_to_quat_wxyz": "geometry",
    "ned_to_enu": "geometry",
    "quat_enu_flu_to_ned_frd": "geometry",
    "quat_ned_frd_to_enu_flu": "geometry",
    "quat_wxyz_from_euler": "geometry",
    "quat_wxyz_from_euler_enu_flu_deg": "geometry",
    "quat_wxyz_from_euler_ned_frd_deg": "geometry",
    "quat_wxyz_from_yaw": "geometry",
    "quat_wxyz_multiply": "geometry",
    "quat_wxyz_to_matrix": "geometry",
    "rotate_body_to_world": "geometry",
    "rotate_world_to_body": "geometry",
    "slerp_wxyz": "geometry",
    "unit_vector": "geometry",
    "wrap_angle_rad": "geometry",
    "yaw_from_quat_wxyz": "geometry",
    # link budget (paper eqs. 1 and 5)
    "FAR_FIELD_WAVELENGTHS": "link",
    "SPEED_OF_LIGHT_M_S": "link",
    "check_far_field": "link",
    "free_space_path_loss_db": "link",
    "observed_joint_gain_db": "link",
    "received_power_dbm": "link",
    "wavelength_m": "link",
    # environment term beyond free space (fit --path-loss)
    "DEFAULT_RELATIVE_PERMITTIVITY": "environment",
    "PATH_LOSS_KINDS": "environment",
    "PathLoss": "environment",
    "log_distance_column": "environment",
    "reflection_coefficient": "environment",
    "two_ray_excess_db": "environment",
    # bases of pattern functions
    "BASIS_KINDS": "bases",
    "Basis": "basis_base",
    "BasisGrid": "bases",
    "Polynomial": "bases",
    "SphericalHarmonics": "sh",
    "basis_from_dict": "bases",
    "fibonacci_grid_nodes": "bases",
    "make_basis": "bases",
    "paper_grid_nodes": "bases",
    "sh_index": "sh",
    # joint least squares
    "DEFAULT_RIDGE": "lsq.solver",
    "Gauge": "gauge",
    "FitReport": "lsq.solution",
    "GaugeNote": "lsq.solution",
    "JointSolution": "lsq.solution",
    "NormalEquations": "lsq.normal_equations",
    "fit_joint": "lsq.solver",
    "identifiability": "lsq.solver",
    "link_components": "lsq.solver",
    "independent_spread_db": "lsq.solver",
    "solve": "lsq.solver",
    # metrics (paper Sec. V-C)
    "Scores": "metrics",
    "Stopwatch": "metrics",
    "aic": "metrics",
    "condition_number": "metrics",
    "mae": "metrics",
    "q95": "metrics",
    "rmse": "metrics",
    "score": "metrics",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
