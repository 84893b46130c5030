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
register_pattern``); its module is imported on first use (:mod:`rplearn._lazy`), and the other
tool's package only when a function needs it, so that a missing extra is one clear error.
"""

from __future__ import annotations

from rplearn._lazy import lazy_exports

_NAMES: dict[str, str] = {
    # Sionna RT (optional extra rplearn[sionna])
    "SionnaUnavailableError": "sionna",
    "add_link": "sionna",
    "import_sionna_rt": "sionna",
    "planar_array": "sionna",
    "polarization_mismatch_db": "sionna",
    "register_pattern": "sionna",
    "sionna_orientation": "sionna",
}

__all__ = sorted(_NAMES)
__getattr__, __dir__ = lazy_exports(__name__, _NAMES)
