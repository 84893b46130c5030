"""rplearn: learn drone-with-antenna radiation patterns from calibration flights.

The method follows Hert et al., "Orientation matters" (see README): the joint gain of a
radio link is split into one radiation pattern per drone-with-antenna, each a linear
combination of basis functions of the direction (azimuth, elevation) in the drone's body
frame, identified by linear least squares over signal samples of a calibration flight.
"""

from __future__ import annotations

from rplearn._version import __version__
from rplearn.errors import RplearnError

__all__ = ["RplearnError", "__version__"]
