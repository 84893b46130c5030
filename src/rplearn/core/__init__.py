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
                       :func:`wavelength_m`, :func:`far_field_limit_m`, :func:`observed_joint_gain_db` (eq. 5)
``environment``        :class:`PathLoss` (``fit --path-loss``), :func:`log_distance_column`,
                       :func:`two_ray_excess_db`, :func:`reflection_coefficient`
``bases``, ``sh``      :class:`Basis`, :class:`SphericalHarmonics`, :class:`BasisGrid`,
                       :class:`Polynomial`, :func:`make_basis`, :func:`basis_from_dict`
``lsq``                the least-squares engine (a subpackage): :func:`fit_joint`, :func:`solve`,
                       :func:`identifiability`, :class:`FitReport`, :class:`JointSolution`,
                       :class:`NormalEquations` (streamed sufficient statistics),
                       :class:`BlockSums`, :func:`correlated_ratio` (an error drifting over seconds)
``metrics``            :func:`score`, :class:`Scores`, :func:`rmse`, :func:`mae`, :func:`q95`,
                       :func:`aic`, :func:`condition_number`, :class:`Stopwatch`
=====================  ==========================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.core import fit_joint``);
its module is imported on first use (``__init__.pyi``, lazy_loader).
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
