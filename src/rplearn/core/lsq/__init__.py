"""The joint least-squares engine of :mod:`rplearn.core` (paper Sec. IV-B, V-A).

Its public names are exported by :mod:`rplearn.core` (``from rplearn.core import fit_joint``);
this package lists none of its own. It may import the maths modules at the top of
``rplearn.core`` (geometry, bases, links), which never import it (tests/test_architecture.py).
"""

from __future__ import annotations

__all__: list[str] = []
