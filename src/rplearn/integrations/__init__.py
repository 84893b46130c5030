"""Bridges to other tools: learned patterns used where other software simulates radio links.

=============  =================================================================================
module         public names
=============  =================================================================================
``sionna``     :func:`register_pattern` (a node's learned pattern as a Sionna RT antenna
               pattern), :func:`planar_array`, :func:`add_link`, :func:`sionna_orientation`,
               :func:`polarization_mismatch_db`, :func:`import_sionna_rt`,
               :class:`SionnaUnavailableError`; needs the optional extra
               ``pip install 'rplearn[sionna]'``
=============  =================================================================================

Every name of ``__all__`` can be imported from here (``from rplearn.integrations import
register_pattern``); its module is imported on first use (``__init__.pyi``, lazy_loader), and the other
tool's package only when a function needs it, so that a missing extra is one clear error.
"""

from __future__ import annotations

import lazy_loader

# The public names are those of __init__.pyi, each imported on first use.
__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
