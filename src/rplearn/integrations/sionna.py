"""Learned radiation patterns as Sionna RT antenna patterns (optional extra ``rplearn[sionna]``).

`Sionna RT <https://nvlabs.github.io/sionna/rt/>`_ (package ``sionna-rt``, 2.x) traces radio
paths through 3-D scenes. :func:`register_pattern` registers one node's learned pattern with
Sionna's documented API for custom antenna patterns (``register_antenna_pattern(name,
factory)``, the factory returning an ``AntennaPattern``), so that ``PlanarArray(num_rows=1,
num_cols=1, pattern=name)`` puts that drone's antenna into any scene; :func:`add_link` also
places the drones with rplearn's poses.

Conventions: rplearn -> Sionna RT
---------------------------------
=========================  ==========================================================================
quantity                   mapping
=========================  ==========================================================================
world frame                rplearn ENU (x east, y north, z up, metres) *is* Sionna's scene frame
                           (right-handed, z up, metres): positions are passed unchanged.
antenna frame              Sionna's antenna (local) frame *is* the drone's body frame FLU (x forward,
                           y left, z up): the pattern is the body-frame pattern, no mounting rotation.
angles                     Sionna evaluates a pattern at the zenith angle ``theta`` (from local +z)
                           and azimuth ``phi = atan2(y, x)`` (from local +x toward +y) of the
                           direction of departure (transmitter) or arrival, pointing back toward the
                           source (receiver). rplearn's azimuth and elevation of the same direction
                           (docs/conventions.md, paper eq. 3) are ``az = phi`` and ``el = pi/2 - theta``.
attitude                   Sionna's device ``orientation = (alpha, beta, gamma)`` rotates the antenna
                           frame into the scene frame by ``Rz(alpha) Ry(beta) Rx(gamma)`` (3GPP TR
                           38.901 eq. 7.1-4), the same matrix as rplearn's aerospace ``(yaw, pitch,
                           roll)`` in ENU/FLU (:func:`rplearn.core.geometry.quat_wxyz_from_euler`), so
                           ``(alpha, beta, gamma) = (yaw, pitch, roll)`` of the body -> world
                           quaternion (:func:`sionna_orientation`); a positive pitch lowers the nose.
gain                       rplearn's pattern ``G(az, el)`` is a power gain [dBi]; Sionna's pattern is
                           the far-field amplitude pair ``(C_theta, C_phi)`` with power gain
                           ``|C_theta|^2 + |C_phi|^2``. The registered pattern is vertically
                           polarised (Sionna's ``"V"``: slant angle 0, model ``tr38901_2``):
                           ``C_theta = 10^(G/20)``, ``C_phi = 0``, so its power gain is exactly
                           ``10^(G/10)``.
polarisation               rplearn's patterns are scalar: whatever polarisation the flown antennas
                           had is folded into the learned gains. Sionna projects the transmitted
                           field onto the receiving antenna's polarisation: with both ends polarised
                           along their body z axes and level drones (roll = pitch = 0, any yaw) the
                           two ``theta`` unit vectors along a line of sight coincide and Sionna's
                           line-of-sight path gain is rplearn's ``G_tx + G_rx`` plus free-space loss
                           ``20 log10(lambda / (4 pi d))``; tilted drones add Sionna's polarisation
                           mismatch ``10 log10((theta_tx . theta_rx)^2) <= 0``
                           (:func:`polarization_mismatch_db`), which rplearn does not model.
what is exported           Only the node's pattern. A model's environment term (log-distance
                           exponent, two-ray ground), its per-link electronics offsets and its
                           uncertainty are not: in Sionna the scene does the propagation. For a
                           two-node fit only the joint gain ``G_A + G_B`` is identified; each
                           pattern's level is the fit's gauge (``model.gauge``).
=========================  ==========================================================================

Evaluation inside Dr.Jit: the node's pattern is evaluated once with numpy on a regular grid of
``theta`` in [0, 180] deg and ``phi`` in [-180, 180] deg (``step_deg``, 0.5 deg by default), and
Sionna's calls interpolate it bilinearly in dB (``dr.gather`` on the table), then convert to
amplitude. For SH patterns up to SH-10 the interpolation error at 0.5 deg is about 0.01 dB or
less (a grid error bounded by ``step^2 / 8`` times the pattern's second derivative); any
pattern-like object (``nodes``, ``evaluate(node, az, el)``: a learned model, a reference pattern,
a simulation's ground truth) can be exported, of any basis.

Setup: Sionna RT runs on the CPU through Dr.Jit's LLVM backend, which needs a shared libLLVM.
On Debian 12 the system's LLVM 15 aborts in Dr.Jit's code generation and LLVM 14 is refused;
``apt-get install libllvm19`` works. This module sets ``DRJIT_LIBLLVM_PATH`` to Debian's
``libLLVM.so.19.1`` when that variable is unset and the library exists, before Sionna (and
Dr.Jit's backend) is first imported, and :func:`import_sionna_rt` turns a backend that cannot
start into one :class:`SionnaUnavailableError` naming the fix.
"""

from __future__ import annotations

import logging
import math
import os
import platform
import sysconfig
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn._argtypes import check_types
from rplearn._budget import Cost, check_work
from rplearn.core.geometry import azimuth_elevation, euler_from_quat_wxyz, rotate_body_to_world, rotate_world_to_body
from rplearn.core.plausible import check_frequency_hz, check_same_band
from rplearn.errors import InputError, RplearnError
from rplearn.io.export import check_pattern_like

FloatArray = NDArray[np.float64]

logger = logging.getLogger(__name__)

#: How to install what this module needs.
SIONNA_INSTALL = "pip install 'rplearn[sionna]'"
#: Environment variable naming the libLLVM that Dr.Jit loads.
LLVM_PATH_VARIABLE = "DRJIT_LIBLLVM_PATH"
#: The oldest LLVM major version known to run Sionna RT's kernels here (14 is refused by Dr.Jit,
#: 15 aborts the process in its code generation).
MIN_LLVM_MAJOR = 16
#: The fix for a Dr.Jit that cannot start, as printed.
LLVM_FIX = (f"install LLVM 19 (apt-get install libllvm19) or set {LLVM_PATH_VARIABLE} to a "
            f"libLLVM.so of LLVM {MIN_LLVM_MAJOR} or newer")
#: Default grid step of the pattern table [deg].
DEFAULT_STEP_DEG = 0.5

__all__ = [
    "SceneLinkOptions",
    "SionnaUnavailableError",
    "add_link",
    "import_sionna_rt",
    "planar_array",
    "polarization_mismatch_db",
    "register_pattern",
    "sionna_orientation",
]


class SionnaUnavailableError(RplearnError, ImportError):
    """Sionna RT is not installed, or its Dr.Jit backend cannot start (the message names the fix)."""


def debian_libllvm19() -> str | None:
    """Path of Debian's LLVM 19 shared library (package ``libllvm19``), or None if absent."""
    arches = [sysconfig.get_config_var("MULTIARCH"), f"{platform.machine()}-linux-gnu"]
    for arch in dict.fromkeys(a for a in arches if a):
        path = f"/usr/lib/{arch}/libLLVM.so.19.1"
        if os.path.isfile(path):
            return path
    return None


def use_debian_libllvm19() -> str | None:
    """Point ``DRJIT_LIBLLVM_PATH`` at Debian's libLLVM 19 when it is unset and the library exists.

    Returns
    -------
    str or None
        The variable's value afterwards (None: unset, Dr.Jit searches on its own).
    """
    if not os.environ.get(LLVM_PATH_VARIABLE):
        path = debian_libllvm19()
        if path is not None:
            os.environ[LLVM_PATH_VARIABLE] = path
    return os.environ.get(LLVM_PATH_VARIABLE) or None


use_debian_libllvm19()  # before anyone imports Sionna: Dr.Jit reads it when its backend starts


@check_types
def import_sionna_rt() -> Any:
    """The ``sionna.rt`` module, with Dr.Jit's backend started.

    Returns
    -------
    module
        ``sionna.rt``.

    Raises
    ------
    SionnaUnavailableError
        When ``sionna-rt`` (or Mitsuba, Dr.Jit) is not installed, when Dr.Jit's LLVM backend
        cannot start, or when it loaded an LLVM older than :data:`MIN_LLVM_MAJOR` (which aborts
        the process at the first ray-tracing kernel); the one-line message names the fix.
    """
    llvm = use_debian_libllvm19()
    try:
        from sionna import rt
    except ModuleNotFoundError as exc:
        missing = (exc.name or "").split(".")[0]
        if missing in ("sionna", "mitsuba", "drjit"):
            raise SionnaUnavailableError(f"the Sionna RT export needs sionna-rt, which is not installed "
                                         f"(no module {exc.name!r}): {SIONNA_INSTALL}") from None
        raise
    except ImportError as exc:
        if "LLVM" not in str(exc):
            raise
        where = f"{LLVM_PATH_VARIABLE}={llvm}" if llvm else f"{LLVM_PATH_VARIABLE} unset"
        raise SionnaUnavailableError(f"Sionna RT cannot start Dr.Jit's LLVM backend ({where}): {LLVM_FIX}") from None
    import drjit
    import mitsuba

    if str(mitsuba.variant()).startswith("llvm"):
        version = tuple(drjit.detail.llvm_version())
        if version and int(version[0]) < MIN_LLVM_MAJOR:
            found = ".".join(str(v) for v in version)
            raise SionnaUnavailableError(f"Dr.Jit loaded LLVM {found}, which crashes in its code generation: "
                                         f"{LLVM_FIX}, then restart Python")
    return rt


# -- frames --------------------------------------------------------------------------------------


@check_types
def sionna_orientation(quat_wxyz: ArrayLike) -> FloatArray:
    """Sionna's device orientation ``(alpha, beta, gamma)`` of rplearn attitudes [rad].

    Parameters
    ----------
    quat_wxyz : array_like, shape (4,) or (n, 4)
        Attitudes, body (FLU) -> world (ENU) quaternions ``(qw, qx, qy, qz)``.

    Returns
    -------
    ndarray, shape (3,) or (n, 3)
        ``(yaw, pitch, roll)`` [rad]: Sionna's rotation ``Rz(alpha) Ry(beta) Rx(gamma)`` of the
        antenna frame into the scene frame equals the quaternion's rotation.
    """
    roll, pitch, yaw = euler_from_quat_wxyz(quat_wxyz)
    return np.stack([yaw, pitch, roll], axis=-1)


def _theta_hat_world(quat_wxyz: FloatArray, direction_world: FloatArray) -> FloatArray:
    """World-frame unit vector ``theta_hat`` of an antenna (z = body z) toward unit directions."""
    az, el = azimuth_elevation(rotate_world_to_body(quat_wxyz, direction_world))
    theta = np.pi / 2 - el
    local = np.stack([np.cos(theta) * np.cos(az), np.cos(theta) * np.sin(az), -np.sin(theta)], axis=-1)
    return rotate_body_to_world(quat_wxyz, local)


@check_types
def polarization_mismatch_db(
    tx_position_xyz: ArrayLike,
    tx_quat_wxyz: ArrayLike,
    rx_position_xyz: ArrayLike,
    rx_quat_wxyz: ArrayLike,
) -> FloatArray:
    """What Sionna adds to rplearn's joint gain on a line of sight for vertically polarised
    antennas (:func:`register_pattern`'s default): ``10 log10((theta_tx . theta_rx)^2)`` [dB].

    ``theta_tx`` is the transmitter's zenith unit vector (its body z is the antenna axis) toward
    the receiver, ``theta_rx`` the receiver's toward the transmitter, both in the world frame.
    Zero for level drones (any yaw); negative for tilted ones.

    Parameters
    ----------
    tx_position_xyz, rx_position_xyz : array_like, shape (3,) or (n, 3)
        Positions, ENU [m].
    tx_quat_wxyz, rx_quat_wxyz : array_like, shape (4,) or (n, 4)
        Attitudes, body (FLU) -> world (ENU) quaternions.

    Returns
    -------
    ndarray, shape () or (n,)
        The mismatch [dB] (``-inf`` for crossed polarisations).
    """
    tx = np.asarray(tx_position_xyz, np.float64)
    rx = np.asarray(rx_position_xyz, np.float64)
    k = rx - tx
    norm = np.linalg.norm(k, axis=-1, keepdims=True)
    if np.any(~(norm > 0)):
        raise InputError("rx_position_xyz: a receiver is at its transmitter's position (no direction)",
                         param="rx_position_xyz")
    k = k / norm
    dot = np.sum(_theta_hat_world(np.asarray(tx_quat_wxyz, np.float64), k)
                 * _theta_hat_world(np.asarray(rx_quat_wxyz, np.float64), -k), axis=-1)
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.square(dot))


# -- the pattern as a table ------------------------------------------------------------------------


def _grid(step_deg: float) -> tuple[int, int]:
    """Numbers of ``theta`` and ``phi`` grid lines for a step [deg] (both ends included)."""
    if not (math.isfinite(step_deg) and 0.01 <= step_deg <= 10.0):
        raise InputError(f"step_deg: expected a grid step from 0.01 to 10 deg, got {step_deg!r}", param="step_deg")
    n_theta = math.ceil(180.0 / step_deg) + 1
    n_phi = 2 * (n_theta - 1) + 1
    return n_theta, n_phi


#: What one value of a pattern table takes: its angles, the gain and Sionna's float32 copy
#: [bytes], and the evaluation of a learned pattern [s].
TABLE_VALUE_BYTES, TABLE_VALUE_S = 48.0, 3e-7


def pattern_table_cost(step_deg: float) -> Cost:
    """What :func:`pattern_table` takes at ``step_deg`` [deg]."""
    n_theta = math.ceil(180.0 / step_deg) + 1
    values = float(n_theta) * (2 * (n_theta - 1) + 1)
    return Cost(memory_bytes=TABLE_VALUE_BYTES * values, seconds=TABLE_VALUE_S * values)


def pattern_table(model: Any, node: str, step_deg: float = DEFAULT_STEP_DEG) -> FloatArray:
    """A node's gain on Sionna's angle grid [dBi]: ``table[i, j]`` at ``theta_i``, ``phi_j``.

    ``theta_i = i * 180 / (n_theta - 1)`` deg from the antenna's +z (body up), ``phi_j = -180 +
    j * 360 / (n_phi - 1)`` deg from +x (body forward) toward +y (left); ``az = phi``,
    ``el = 90 deg - theta``. The step is at most ``step_deg``.

    Parameters
    ----------
    model : pattern-like
        A learned pattern model (``PatternSet``) or any object with ``nodes`` and
        ``evaluate(node, az_rad, el_rad)`` [dBi].
    node : str
    step_deg : float

    Returns
    -------
    ndarray, shape (n_theta, n_phi)
    """
    check_pattern_like(model)
    if str(node) not in [str(n) for n in model.nodes]:
        raise InputError(f"node: unknown node {str(node)!r}; the model knows {', '.join(map(str, model.nodes))}",
                         param="node")
    n_theta, n_phi = _grid(float(step_deg))
    check_work("step_deg", float(step_deg), pattern_table_cost, "deg", integer=False, bounds=(0.01, 10.0), falling=True)
    theta = np.linspace(0.0, np.pi, n_theta)
    phi = np.linspace(-np.pi, np.pi, n_phi)
    az, el = np.meshgrid(phi, np.pi / 2 - theta)
    table = np.asarray(model.evaluate(str(node), az, el), np.float64).reshape(n_theta, n_phi)
    if not np.all(np.isfinite(table)):
        raise InputError(f"node {node!r}: the pattern is not finite everywhere on the sphere", param="node")
    return table


def _interpolating_pattern(table: FloatArray) -> Any:
    """Sionna's vertically polarised pattern function ``v(theta, phi) -> Complex2f`` of a table."""
    import drjit as dr
    import mitsuba as mi

    n_theta, n_phi = table.shape
    values = mi.Float(np.ascontiguousarray(table, np.float32).ravel())
    d_theta = math.pi / (n_theta - 1)
    to_amplitude = math.log(10.0) / 20.0  # 10^(G/20) = exp(G ln10 / 20)

    def v_pattern(theta: Any, phi: Any) -> Any:
        t = dr.clip(theta / d_theta, 0.0, n_theta - 1.0)
        i0 = dr.minimum(mi.UInt32(dr.floor(t)), n_theta - 2)
        ft = t - mi.Float(i0)
        turns = (phi + math.pi) / (2.0 * math.pi)  # wrap any phi into [-pi, pi)
        p = (turns - dr.floor(turns)) * (n_phi - 1.0)
        j0 = dr.minimum(mi.UInt32(dr.floor(p)), n_phi - 2)
        fp = p - mi.Float(j0)
        base = i0 * n_phi + j0
        g00 = dr.gather(mi.Float, values, base)
        g01 = dr.gather(mi.Float, values, base + 1)
        g10 = dr.gather(mi.Float, values, base + n_phi)
        g11 = dr.gather(mi.Float, values, base + n_phi + 1)
        gain_db = (1.0 - ft) * ((1.0 - fp) * g00 + fp * g01) + ft * ((1.0 - fp) * g10 + fp * g11)
        # mitsuba types its variant classes as object; without the extra installed it is Any (no error to ignore)
        return mi.Complex2f(dr.exp(gain_db * to_amplitude), 0.0)  # type: ignore[operator,unused-ignore]

    return v_pattern


# -- registration and scenes ---------------------------------------------------------------------


@check_types
def register_pattern(
    model: Any,
    node: str,
    name: str | None = None,
    step_deg: float = DEFAULT_STEP_DEG,
) -> str:
    """Register a node's learned pattern as a Sionna RT antenna pattern.

    Uses Sionna's ``register_antenna_pattern(name, factory)``; the factory takes Sionna's usual
    keywords ``polarization`` (default ``"V"``, the only one whose power gain is rplearn's gain
    in every direction) and ``polarization_model`` (default ``"tr38901_2"``). Registering a name
    again replaces the earlier pattern. Only the pattern goes to Sionna (not the model's
    environment term nor its link offsets): see the module's conventions.

    Parameters
    ----------
    model : pattern-like
        A learned pattern model (``PatternSet``, e.g. ``fit_model(...).model`` or
        ``load_model(path)``) or any object with ``nodes`` and ``evaluate(node, az, el)`` [dBi].
    node : str
        The node whose antenna to register.
    name : str, optional
        Name to register under; ``"rplearn-<node>"`` by default.
    step_deg : float
        Grid step of the interpolated table [deg].

    Returns
    -------
    str
        The registered name, for ``PlanarArray(..., pattern=name)``.

    Raises
    ------
    InputError
        For a model without per-node patterns, an unknown node or a bad step.
    SionnaUnavailableError
        When Sionna RT cannot be imported or started (see :func:`import_sionna_rt`).
    """
    table = pattern_table(model, node, step_deg)
    registered = f"rplearn-{node}" if name is None else str(name)
    if not registered:
        raise InputError("name: expected a non-empty pattern name", param="name")
    rt = import_sionna_rt()
    v_pattern = _interpolating_pattern(table)

    def factory(*, polarization: str = "V", polarization_model: str = "tr38901_2") -> Any:
        return rt.PolarizedAntennaPattern(v_pattern=v_pattern, polarization=polarization,
                                          polarization_model=polarization_model)

    rt.register_antenna_pattern(registered, factory)
    logger.debug("registered node %s as Sionna antenna pattern %r (%d x %d table)", node, registered, *table.shape)
    return registered


@check_types
def planar_array(model: Any, node: str, polarization: str = "V", step_deg: float = DEFAULT_STEP_DEG) -> Any:
    """A one-element Sionna ``PlanarArray`` carrying a node's learned pattern.

    Registers the pattern (:func:`register_pattern`, default name) and returns
    ``PlanarArray(num_rows=1, num_cols=1, pattern=name, polarization=polarization)``, to set as a
    scene's ``tx_array`` or ``rx_array``.
    """
    rt = import_sionna_rt()
    name = register_pattern(model, node, step_deg=step_deg)
    return rt.PlanarArray(num_rows=1, num_cols=1, pattern=name, polarization=polarization)


def _poses(position_xyz: ArrayLike, quat_wxyz: ArrayLike, what: str) -> tuple[FloatArray, FloatArray]:
    """Positions (n, 3) and attitudes (n, 4) of one end, one of them broadcast to the other's n."""
    p = np.atleast_2d(np.asarray(position_xyz, np.float64))
    q = np.atleast_2d(np.asarray(quat_wxyz, np.float64))
    if p.ndim != 2 or p.shape[1] != 3 or not np.all(np.isfinite(p)):
        raise InputError(f"{what}_position_xyz: expected finite (n, 3) ENU positions [m], got shape {p.shape}",
                         param=f"{what}_position_xyz")
    if q.ndim != 2 or q.shape[1] != 4 or not np.all(np.isfinite(q)) or np.any(np.linalg.norm(q, axis=1) == 0):
        raise InputError(f"{what}_quat_wxyz: expected finite non-zero (n, 4) quaternions (qw, qx, qy, qz), "
                         f"got shape {q.shape}", param=f"{what}_quat_wxyz")
    if len(p) != len(q) and 1 not in (len(p), len(q)):
        raise InputError(f"{what}_quat_wxyz: {len(q)} attitudes for {len(p)} positions", param=f"{what}_quat_wxyz")
    n = max(len(p), len(q))
    return np.broadcast_to(p, (n, 3)), np.broadcast_to(q, (n, 4))


@check_types
@dataclass(frozen=True)
class SceneLinkOptions:
    """How :func:`add_link` puts a link into a Sionna scene (besides the nodes and their poses).

    Attributes
    ----------
    frequency_hz : float, optional
        Carrier [Hz]; the model's ``frequency_hz`` by default.
    step_deg : float
        Grid step of the pattern tables [deg].
    prefix : str
        Prefix of the device names (to add more poses of the same link to a scene; another
        link needs another scene, since a scene's transmitters share one antenna array).

    Raises
    ------
    InputError
        On the first invalid option, naming it (``param``).
    """

    frequency_hz: float | None = None
    step_deg: float = DEFAULT_STEP_DEG
    prefix: str = ""

    def __post_init__(self) -> None:
        for name in ("frequency_hz", "step_deg"):
            value = getattr(self, name)
            if (value is not None or name == "step_deg") and not _positive(value):
                raise InputError(f"{name}: expected a positive finite number, got {value!r}", param=name)
        if self.frequency_hz is not None:
            check_frequency_hz(float(self.frequency_hz), "frequency_hz")
        if not isinstance(self.prefix, str):
            raise InputError(f"prefix: expected a string, got {self.prefix!r}", param="prefix")


def _positive(value: Any) -> bool:
    """A positive finite real number (not a bool)."""
    return (isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
            and math.isfinite(float(value)) and float(value) > 0)


@check_types
def add_link(
    scene: Any,
    model: Any,
    tx_node: str,
    rx_node: str,
    tx_pose: tuple[ArrayLike, ArrayLike],
    rx_pose: tuple[ArrayLike, ArrayLike],
    options: SceneLinkOptions | None = None,
) -> tuple[list[Any], list[Any]]:
    """Put the drones of a link into a Sionna scene with their learned antennas and poses.

    Sets the scene's carrier frequency, its ``tx_array`` to ``tx_node``'s pattern and its
    ``rx_array`` to ``rx_node``'s (Sionna RT 2.x gives every transmitter of a scene the one
    ``tx_array``, every receiver the one ``rx_array``), and adds one transmitter and one
    receiver per pose, named ``f"{prefix}tx{i}"`` and ``f"{prefix}rx{i}"``. Sionna's path
    solver then traces every transmitter to every receiver (``paths.a`` has shape
    ``[n_rx, 1, n_tx, 1, n_paths]`` for these one-element arrays).

    Parameters
    ----------
    scene : sionna.rt.Scene
        E.g. ``sionna.rt.load_scene()`` (empty) or a scene file.
    model : pattern-like
        See :func:`register_pattern`.
    tx_node, rx_node : str
        Nodes of the model whose patterns the transmitters and receivers carry.
    tx_pose, rx_pose : (position_xyz, quat_wxyz)
        Positions, ENU [m] (Sionna's scene frame), shape (3,) or (n, 3); attitudes, body (FLU)
        -> world (ENU) quaternions ``(qw, qx, qy, qz)``, shape (4,) or (n, 4).
    options : SceneLinkOptions, optional
        Carrier, pattern grid step and device name prefix (default ``SceneLinkOptions()``).

    Returns
    -------
    transmitters, receivers : list
        The ``sionna.rt.Transmitter`` and ``sionna.rt.Receiver`` objects added.

    Raises
    ------
    InputError
        Without a frequency, for bad poses (checked before the scene is touched), or when the
        scene already holds another link.

    Examples
    --------
    >>> add_link(scene, model, "A", "B", ([0, 0, 20], [1, 0, 0, 0]), ([40, 10, 25], [1, 0, 0, 0]))  # doctest: +SKIP
    """
    options = SceneLinkOptions() if options is None else options
    frequency_hz, step_deg, prefix = options.frequency_hz, options.step_deg, options.prefix
    tx_position_xyz, tx_quat_wxyz = _pose_pair(tx_pose, "tx")
    rx_position_xyz, rx_quat_wxyz = _pose_pair(rx_pose, "rx")
    f = getattr(model, "frequency_hz", None) if frequency_hz is None else frequency_hz
    if f is None or not (math.isfinite(float(f)) and float(f) > 0):
        raise InputError(f"frequency_hz: expected a positive carrier frequency in Hz (the model states none), got {f!r}",
                         param="frequency_hz")
    check_frequency_hz(float(f), "frequency_hz")
    learned = getattr(model, "frequency_hz", None)
    if frequency_hz is not None and learned is not None:
        check_same_band(float(frequency_hz), float(learned), "frequency_hz", f"the {getattr(model, 'label', 'pattern')} model")
    tx_p, tx_q = _poses(tx_position_xyz, tx_quat_wxyz, "tx")
    rx_p, rx_q = _poses(rx_position_xyz, rx_quat_wxyz, "rx")
    link = (id(model), str(tx_node), str(rx_node), float(f), float(step_deg))
    held = getattr(scene, "_rplearn_link", None)
    if held is not None and held != link:
        raise InputError(f"this Sionna scene already holds the link {held[1]} -> {held[2]}: every transmitter of a "
                         "scene shares one tx_array and every receiver one rx_array, so one scene holds one link "
                         "(more poses of it are fine); use another scene", param="scene")
    rt = import_sionna_rt()
    scene.frequency = float(f)
    scene.tx_array = planar_array(model, tx_node, step_deg=step_deg)
    scene.rx_array = planar_array(model, rx_node, step_deg=step_deg)
    scene._rplearn_link = link
    return (_add(scene, rt.Transmitter, f"{prefix}tx", tx_p, tx_q),
            _add(scene, rt.Receiver, f"{prefix}rx", rx_p, rx_q))


def _pose_pair(pose: Any, what: str) -> tuple[ArrayLike, ArrayLike]:
    """``(position_xyz, quat_wxyz)`` of one end, or an error naming ``{what}_pose``."""
    if isinstance(pose, (str, bytes)) or not hasattr(pose, "__len__") or len(pose) != 2:
        raise InputError(f"{what}_pose: expected a pair (position_xyz, quat_wxyz), got {pose!r}", param=f"{what}_pose")
    return pose[0], pose[1]


def _add(scene: Any, kind: Any, stem: str, positions: FloatArray, quats: FloatArray) -> list[Any]:
    devices = []
    for i, (p, o) in enumerate(zip(positions, sionna_orientation(quats))):
        device = kind(name=f"{stem}{i}", position=[float(v) for v in p], orientation=[float(v) for v in o])
        scene.add(device)
        devices.append(device)
    return devices

