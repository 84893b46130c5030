"""rplearn: learn drone-with-antenna radiation patterns from calibration flights.

The method follows Zoula, Bonilla Licea, Faigl, Navrátil and Saska, "Orientation Matters:
Learning Radiation Patterns of Multi-Rotor UAVs In-Flight to Enhance Communication
Availability Modeling", arXiv:2604.02827, doi:10.48550/arXiv.2604.02827 (CITATION.cff): the
joint gain of a radio link is split into one radiation pattern per drone-with-antenna, each a
linear combination of basis functions of the direction (azimuth, elevation) in the drone's body
frame, identified by linear least squares over signal samples of a calibration flight.

The package is layered, bottom to top (ARCHITECTURE.md): :mod:`rplearn.core` (frames, link
budget, bases, solver, metrics), :mod:`rplearn.data` (canonical tables, pose-signal matching,
units), :mod:`rplearn.io` (log readers, table and model files, export), :mod:`rplearn.plan`
(calibration trajectories), :mod:`rplearn.sim` (simulated flights), :mod:`rplearn.models`
(patterns and baselines, fit, evaluate, load), :mod:`rplearn.analysis` (order sweep,
identifiability, headings, swarms), :mod:`rplearn.viz` (figures, report). Each subpackage
lists its public names in ``__all__``; the most used ones, every error class and
:func:`~rplearn.workflows.demo.run_demo` (the paper's whole evaluation) can also be imported
from here::

    from rplearn import ModelSpec, fit_model, read_table, samples_of

Names are resolved on first use (``__init__.pyi``, lazy_loader): ``import rplearn`` imports neither
pandas, scikit-learn nor matplotlib.
"""

from __future__ import annotations

import lazy_loader

from rplearn._version import __version__ as __version__

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
