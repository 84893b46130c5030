"""Joint least-squares identification of one radiation pattern per node (paper Sec. IV-B, V-A).

Each signal sample ``i`` names its transmitter ``t_i`` and receiver ``r_i`` and observes the joint
gain ``y_i = G_t(az_tx_i, el_tx_i) + G_r(az_rx_i, el_rx_i) + noise`` (paper eq. 5). With every
pattern a linear combination of the same basis, ``G_n = f(az, el) . p_n``, the row of sample
``i`` in the design matrix holds ``f(az_tx, el_tx)`` in the block of node ``t_i``,
``f(az_rx, el_rx)`` in the block of ``r_i`` and zeros elsewhere (the paper's Sec. V-A matrix).

The solver never forms the design matrix: it accumulates the sufficient statistics
``X^T X``, ``X^T y``, ``y^T y`` and ``n`` chunk by chunk (:class:`NormalEquations`), so memory
does not grow with the number of samples, then solves the ridge-regularised normal equations.

Identifiability (paper Sec. V-A, DESIGN.md). A constant can move between the two ends of a
link: ``G_t + c`` and ``G_r - c`` predict the same. In a connected group of nodes whose link
graph is bipartite (two nodes, or an even cycle) this leaves exactly one free constant,
``+c`` on one side of the bipartition and ``-c`` on the other; a link graph with an odd cycle
(a triangle) fixes it. The solver does not leave this to the ridge: for every bipartite
component it adds one explicit linear constraint (the *gauge*), by default "both sides have the
same mean gain over the sphere" (``gauge="equal-mean"``), or "node N has mean gain V dBi over
the sphere" (``gauge={"node": N, "mean_gain_dbi": V}``) when one antenna's level is known. The
fit report names the gauge of every component.
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rplearn.core.bases import Basis
from rplearn.errors import IdentifiabilityError, InputError
from rplearn.core.geometry import Directions

FloatArray = NDArray[np.float64]

#: Default ridge weight lambda added to the diagonal of X^T X (absolute, like the paper's
#: kappa = 50 and scikit-learn's ``alpha``). Identifiability is handled by the gauge, so the
#: ridge only guards against directions the flight did not cover: against the diagonal of
#: X^T X of a well-covered flight (about n / (4 pi) = 4,500 for SH and 56,000 samples) it
#: changes no prediction measurably (paper replica: SH-10 test RMSE 4.481 dB with 1e-6 or 1),
#: while on a single short unit it keeps SH-10 from extrapolating to 1,323 dB RMSE (7.8 dB).
DEFAULT_RIDGE = 1.0
#: Condition numbers above this get a warning in the fit report.
CONDITION_WARNING = 1e4

#: Samples per feature sub-chunk (fits the CPU cache) and per accumulation block.
FEATURE_CHUNK = 4096
BLOCK_SAMPLES = 65536


_BUFFERS = threading.local()


def _block_buffer(size: int) -> FloatArray:
    """A float64 scratch buffer of at least ``size`` values, reused by later fits in this thread.

    Fresh memory is slow on first touch (one page fault per 4 KiB; measured 20-30 ms for the
    52 MB block of an SH-10 fit on this kind of machine), so the block buffer is kept.
    """
    buf = getattr(_BUFFERS, "block", None)
    if buf is None or buf.size < size:
        _BUFFERS.block = None  # let the old one go first
        buf = np.empty(size)
        buf.fill(0.0)  # pay the page faults now, once, not inside the first rank-k update
        _BUFFERS.block = buf
    return buf[:size]


def block_rows(basis: Basis) -> int:
    """Rows of the accumulation block of :func:`link_statistics` for this basis."""
    return 2 * basis.n_coef + 1


def reserve_block_buffer(basis: Basis, n_samples: int) -> None:
    """Allocate (and touch) this thread's block buffer for a fit of ``n_samples`` samples.

    Called before a timed fit so that its learning time does not include the one-off page
    faults of the buffer (measured 0.2 s for the first SH-10 fit of the paper's 56k samples).
    """
    _block_buffer(block_rows(basis) * max(1, min(int(n_samples), BLOCK_SAMPLES)))


def _fill_features(
    basis: Basis,
    buf: FloatArray,
    az_tx: FloatArray,
    el_tx: FloatArray,
    az_rx: FloatArray,
    el_rx: FloatArray,
    moments: FloatArray | None,
) -> None:
    """Write tx features into rows ``0 .. p-1`` and rx features into rows ``p+1 .. 2p`` of ``buf``.

    Rows are in the basis's :attr:`~rplearn.core.bases.Basis.row_order`; row ``p`` is left for the
    observations. Works in cache-sized chunks; a basis that accepts stacked samples computes
    both ends of a chunk in one pass, through a (p, 2, chunk) strided view of the two row
    groups, and adds to ``moments[0]`` (tx) and ``moments[1]`` (rx) when given.
    """
    p = basis.n_coef
    n = az_tx.size
    if basis.stacked_samples:
        az_both = np.stack([az_tx, az_rx])
        el_both = np.stack([el_tx, el_rx])
    for s in range(0, n, FEATURE_CHUNK):
        e = min(n, s + FEATURE_CHUNK)
        view = buf[:, s:e]
        if basis.stacked_samples:
            both = np.lib.stride_tricks.as_strided(
                view, shape=(p, 2, e - s), strides=(view.strides[0], (p + 1) * view.strides[0], view.strides[1])
            )
            basis.design_rows_into(az_both[:, s:e], el_both[:, s:e], both, moments)
        else:
            basis.design_rows_into(az_tx[s:e], el_tx[s:e], view[:p])
            basis.design_rows_into(az_rx[s:e], el_rx[s:e], view[p + 1 :])


def link_statistics(
    basis: Basis, az_tx: FloatArray, el_tx: FloatArray, az_rx: FloatArray, el_rx: FloatArray, y: FloatArray
) -> FloatArray:
    """``Z^T Z`` with ``Z = [f(tx directions), y, f(rx directions)]`` over samples of one link.

    A ``(2p + 1, 2p + 1)`` matrix, features in the basis's row order: the tx and rx blocks of
    ``X^T X``, ``X^T y`` and ``y^T y``. Per block of :data:`BLOCK_SAMPLES` samples, written
    into this thread's reused buffer, either one symmetric rank-k update of all ``2p + 1``
    rows, or, for a basis with Gram moments (SH), only the product ``[f_tx; y] [y; f_rx]^T``
    (half the work): the two diagonal blocks then come from the moments.
    """
    az_tx, el_tx, az_rx, el_rx, y = (np.ascontiguousarray(a, np.float64).ravel() for a in (az_tx, el_tx, az_rx, el_rx, y))
    p = basis.n_coef
    k = block_rows(basis)
    n = az_tx.size
    use_moments = basis.moment_shape is not None and basis.stacked_samples
    moments = np.zeros((2, *basis.moment_shape)) if use_moments else None
    total = np.zeros((k, k))
    block = _block_buffer(k * max(1, min(n, BLOCK_SAMPLES)))  # grows to the largest block seen
    for start in range(0, n, BLOCK_SAMPLES):
        stop = min(n, start + BLOCK_SAMPLES)
        buf = block[: k * (stop - start)].reshape(k, stop - start)
        part = slice(start, stop)
        _fill_features(basis, buf, az_tx[part], el_tx[part], az_rx[part], el_rx[part], moments)
        buf[p] = y[part]
        if moments is None:
            total += buf @ buf.T
        else:
            total[: p + 1, p:] += buf[: p + 1] @ buf[p:].T
    if moments is not None:
        total[p:, : p + 1] = total[: p + 1, p:].T
        total[:p, :p] = basis.gram_from_moments(moments[0])
        total[p + 1 :, p + 1 :] = basis.gram_from_moments(moments[1])
    return total


@dataclass
class NormalEquations:
    """Sufficient statistics of the joint least-squares problem, accumulated chunk by chunk.

    Parameters
    ----------
    basis : Basis
        The basis shared by all nodes.
    n_nodes : int
        Number of nodes (patterns) in the problem.
    """

    basis: Basis
    n_nodes: int
    gram: FloatArray = field(init=False)
    rhs: FloatArray = field(init=False)
    yty: float = field(init=False, default=0.0)
    n_samples: int = field(init=False, default=0)
    link_counts: dict[tuple[int, int], int] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        if self.n_nodes < 2:
            raise InputError(f"a link problem needs at least 2 nodes, got {self.n_nodes}")
        self.gram = np.zeros((self.n_columns, self.n_columns))
        self.rhs = np.zeros(self.n_columns)
        # link_statistics orders rows [tx features, y, rx features], features in the basis's
        # row order; this index puts them back as [tx, rx, y] in the natural column order.
        p = self.basis.n_coef
        rows = self.basis.row_order
        natural = np.arange(p) if rows is None else np.argsort(rows)
        self._natural = np.concatenate([natural, natural + p + 1, [p]])

    @property
    def n_columns(self) -> int:
        return self.basis.n_coef * self.n_nodes

    def add(
        self,
        directions: Directions,
        tx_index: ArrayLike,
        rx_index: ArrayLike,
        joint_gain_db: ArrayLike | None = None,
    ) -> "NormalEquations":
        """Accumulate a chunk of samples.

        Parameters
        ----------
        directions : Directions
            ``az_tx, el_tx, az_rx, el_rx`` of every sample [rad].
        tx_index, rx_index : array_like of int
            Node index of the transmitter and receiver of every sample.
        joint_gain_db : array_like, optional
            Observed joint gain [dB] (paper eq. 5); omitted for an identifiability check only.
        """
        az_tx, el_tx, az_rx, el_rx = (np.ascontiguousarray(a, np.float64).ravel() for a in directions)
        tx = np.asarray(tx_index).ravel()
        rx = np.asarray(rx_index).ravel()
        n = az_tx.size
        y = np.zeros(n) if joint_gain_db is None else np.ascontiguousarray(joint_gain_db, np.float64).ravel()
        for name, arr in (("el_tx", el_tx), ("az_rx", az_rx), ("el_rx", el_rx), ("tx_index", tx), ("rx_index", rx), ("joint_gain_db", y)):
            if arr.size != n:
                raise InputError(f"{name} has {arr.size} values, az_tx has {n}")
        for name, arr in (("az_tx", az_tx), ("el_tx", el_tx), ("az_rx", az_rx), ("el_rx", el_rx), ("joint_gain_db", y)):
            if not np.all(np.isfinite(arr)):
                raise InputError(f"{name}: {int(np.sum(~np.isfinite(arr)))} NaN or infinite value(s)")
        if n == 0:
            return self
        if np.any(tx < 0) or np.any(rx < 0) or np.any(tx >= self.n_nodes) or np.any(rx >= self.n_nodes):
            raise InputError(f"node index out of range 0..{self.n_nodes - 1}")
        if np.any(tx == rx):
            raise InputError("a sample has the same node as transmitter and receiver")
        pair_code = tx.astype(np.int64) * self.n_nodes + rx
        if pair_code.min() == pair_code.max():  # one link direction: no grouping needed
            codes = pair_code[:1]
        else:
            codes = np.unique(pair_code)
        for code in codes:
            t, r = divmod(int(code), self.n_nodes)
            sel = slice(None) if codes.size == 1 else (pair_code == code)
            self._add_pair(t, r, az_tx[sel], el_tx[sel], az_rx[sel], el_rx[sel], y[sel])
        self.n_samples += n
        return self

    def _add_pair(
        self, t: int, r: int, az_tx: FloatArray, el_tx: FloatArray, az_rx: FloatArray, el_rx: FloatArray, y: FloatArray
    ) -> None:
        p = self.basis.n_coef
        bt = slice(t * p, (t + 1) * p)
        br = slice(r * p, (r + 1) * p)
        n = az_tx.size
        key = (min(t, r), max(t, r))
        self.link_counts[key] = self.link_counts.get(key, 0) + n
        # Both nodes' blocks of X^T X, X^T y and y^T y from one pass over the samples.
        block = link_statistics(self.basis, az_tx, el_tx, az_rx, el_rx, y)
        block = block[np.ix_(self._natural, self._natural)]
        self.gram[bt, bt] += block[:p, :p]
        self.gram[br, br] += block[p : 2 * p, p : 2 * p]
        self.gram[bt, br] += block[:p, p : 2 * p]
        self.gram[br, bt] += block[p : 2 * p, :p]
        self.rhs[bt] += block[:p, 2 * p]
        self.rhs[br] += block[p : 2 * p, 2 * p]
        self.yty += float(block[2 * p, 2 * p])

    def merge(self, other: "NormalEquations") -> "NormalEquations":
        """Add another accumulator's statistics (same basis and node count) into this one."""
        if other.basis != self.basis or other.n_nodes != self.n_nodes:
            raise InputError("cannot merge normal equations of different bases or node counts")
        self.gram += other.gram
        self.rhs += other.rhs
        self.yty += other.yty
        self.n_samples += other.n_samples
        for k, v in other.link_counts.items():
            self.link_counts[k] = self.link_counts.get(k, 0) + v
        return self


# -------------------------------------------------------------------------------------------
# Link graph


def link_components(n_nodes: int, links: Iterable[tuple[int, int]]) -> list[tuple[list[int], list[int] | None]]:
    """Connected components of the link graph and, for bipartite ones, their two sides.

    Returns
    -------
    list of (nodes, side_b)
        ``side_b`` is the list of nodes on the second side of the bipartition, or ``None``
        when the component has an odd cycle (absolute gains identifiable).
    """
    adj: dict[int, set[int]] = {i: set() for i in range(n_nodes)}
    for a, b in links:
        adj[a].add(b)
        adj[b].add(a)
    color = [-1] * n_nodes
    out = []
    for start in range(n_nodes):
        if color[start] != -1:
            continue
        color[start] = 0
        comp = [start]
        bipartite = True
        queue = deque([start])
        while queue:
            u = queue.popleft()
            for v in adj[u]:
                if color[v] == -1:
                    color[v] = 1 - color[u]
                    comp.append(v)
                    queue.append(v)
                elif color[v] == color[u]:
                    bipartite = False
        comp.sort()
        out.append((comp, [v for v in comp if color[v] == 1] if bipartite else None))
    return out


# -------------------------------------------------------------------------------------------
# Reports and solutions


@dataclass(frozen=True)
class GaugeNote:
    """How the free constant of one bipartite component was fixed."""

    nodes: tuple[str, ...]
    side_a: tuple[str, ...]
    side_b: tuple[str, ...]
    rule: str
    text: str

    def to_dict(self) -> dict[str, Any]:
        return {"nodes": list(self.nodes), "side_a": list(self.side_a), "side_b": list(self.side_b), "rule": self.rule, "text": self.text}


@dataclass(frozen=True)
class FitReport:
    """Numerical health of a fit (paper Sec. V-A, V-C).

    Attributes
    ----------
    n_samples : int
    n_columns : int
        Columns of the joint design matrix (``n_nodes * n_coef``).
    rank : int
        Numerical rank of the design matrix (singular values above
        ``s_max * sqrt(n_columns * eps)``, judged on ``X^T X``).
    null_dim : int
        ``n_columns - rank``.
    condition_number : float
        Largest / smallest non-zero singular value of the design matrix.
    expected_null_dim : int
        Free constants the link graph predicts (one per bipartite component).
    gauges : tuple of GaugeNote
    ridge : float
    rmse_db : float
        Training RMSE [dB].
    singular_values : ndarray
        All singular values of the design matrix, descending.
    """

    n_samples: int
    n_columns: int
    rank: int
    null_dim: int
    condition_number: float
    expected_null_dim: int
    gauges: tuple[GaugeNote, ...]
    ridge: float
    rmse_db: float
    singular_values: FloatArray = field(repr=False)
    warnings: tuple[str, ...] = ()

    @property
    def decoupled(self) -> bool:
        """True when the only unidentified directions are the gauge constants."""
        return self.null_dim == self.expected_null_dim

    def to_dict(self) -> dict[str, Any]:
        return {
            "n_samples": self.n_samples,
            "n_columns": self.n_columns,
            "rank": self.rank,
            "null_dim": self.null_dim,
            "expected_null_dim": self.expected_null_dim,
            "condition_number": self.condition_number,
            "ridge": self.ridge,
            "rmse_db": self.rmse_db,
            "gauges": [g.to_dict() for g in self.gauges],
            "warnings": list(self.warnings),
        }


@dataclass(frozen=True)
class JointSolution:
    """Coefficients of every node's pattern and the fit's report.

    ``coef[k]`` are the coefficients of node ``k``; ``covariance`` is the estimated covariance
    of all coefficients (``n_columns x n_columns``, gauge-constrained), from the residual
    variance; it gives the standard error of any pattern value or prediction.
    """

    coef: FloatArray
    covariance: FloatArray
    residual_variance_db2: float
    report: FitReport


def spectrum_report(gram: FloatArray) -> tuple[FloatArray, int, float]:
    """Singular values of X (from X^T X), numerical rank and condition number."""
    eig = np.linalg.eigvalsh(gram)[::-1]
    eig = np.clip(eig, 0.0, None)
    sv = np.sqrt(eig)
    if sv.size == 0 or sv[0] == 0:
        return sv, 0, float("inf")
    tol = sv[0] * np.sqrt(gram.shape[0] * np.finfo(np.float64).eps)
    rank = int(np.sum(sv > tol))
    cond = float(sv[0] / sv[rank - 1]) if rank > 0 else float("inf")
    return sv, rank, cond


def fit_warnings(label: str, n_columns: int, rank: int, n_gauges: int, cond: float, ridge: float) -> list[str]:
    """Plain-language warnings about a fit whose samples barely identify the model."""
    out = []
    if n_columns - rank > n_gauges:
        out.append(
            f"{n_columns - rank - n_gauges} direction(s) of {label} are not identified by the samples "
            f"(rank {rank} of {n_columns}); the ridge ({ridge:g}) decides them: add headings or lower the order"
        )
    if cond > CONDITION_WARNING:
        out.append(
            f"condition number {cond:.3g}: the flight left directions (nearly) uncovered, and predictions "
            "there are extrapolations; check the coverage, add headings, or lower the order"
        )
    return out


def _gauge_constraints(
    basis: Basis,
    n_nodes: int,
    node_names: Sequence[str],
    components: list[tuple[list[int], list[int] | None]],
    gauge: str | Mapping[str, Any],
) -> tuple[FloatArray, FloatArray, list[GaugeNote]]:
    p = basis.n_coef
    mean = basis.sphere_mean
    rows, values, notes = [], [], []
    fixed_node = None
    if isinstance(gauge, Mapping):
        if "node" not in gauge:
            raise InputError("gauge: expected 'equal-mean' or {'node': ID, 'mean_gain_dbi': VALUE}")
        if str(gauge["node"]) not in node_names:
            raise InputError(f"gauge: unknown node {gauge['node']!r}; nodes are {', '.join(node_names)}")
        fixed_node = node_names.index(str(gauge["node"]))
        fixed_value = float(gauge.get("mean_gain_dbi", 0.0))
    elif gauge != "equal-mean":
        raise InputError(f"gauge: expected 'equal-mean' or {{'node': ID, 'mean_gain_dbi': V}}, got {gauge!r}")
    if fixed_node is not None:
        for comp, side_b in components:
            if fixed_node in comp and side_b is None:
                raise InputError(
                    f"gauge: node {node_names[fixed_node]} is in a group whose links form an odd cycle, so its "
                    "absolute gain is already identified; fit without a gauge node"
                )
    for comp, side_b in components:
        if side_b is None or len(comp) < 2:
            continue
        side_a = [v for v in comp if v not in side_b]
        names = tuple(node_names[v] for v in comp)
        sa = tuple(node_names[v] for v in side_a)
        sb = tuple(node_names[v] for v in side_b)
        row = np.zeros(n_nodes * p)
        if fixed_node is not None and fixed_node in comp:
            row[fixed_node * p : (fixed_node + 1) * p] = mean
            rows.append(row)
            values.append(fixed_value)
            text = (
                f"links among {', '.join(names)} form no odd cycle, so one constant is unidentifiable "
                f"(+c on {', '.join(sa)}, -c on {', '.join(sb)}); fixed by setting the sphere-mean gain "
                f"of {node_names[fixed_node]} to {fixed_value:g} dBi"
            )
            notes.append(GaugeNote(names, sa, sb, f"fixed-mean:{node_names[fixed_node]}={fixed_value:g}", text))
        else:
            for v in side_a:
                row[v * p : (v + 1) * p] += mean / len(side_a)
            for v in side_b:
                row[v * p : (v + 1) * p] -= mean / len(side_b)
            rows.append(row)
            values.append(0.0)
            text = (
                f"links among {', '.join(names)} form no odd cycle, so one constant is unidentifiable "
                f"(+c on {', '.join(sa)}, -c on {', '.join(sb)}); fixed by giving both sides the same "
                "mean gain over the sphere (only pattern shapes and the joint level are identified)"
            )
            notes.append(GaugeNote(names, sa, sb, "equal-mean", text))
    if rows:
        return np.array(rows), np.array(values), notes
    return np.zeros((0, n_nodes * p)), np.zeros(0), notes


def solve(
    normal: NormalEquations,
    node_names: Sequence[str] | None = None,
    ridge: float = DEFAULT_RIDGE,
    gauge: str | Mapping[str, Any] = "equal-mean",
    min_samples_per_coef: float = 1.0,
) -> JointSolution:
    """Solve accumulated normal equations with a ridge and explicit gauge constraints.

    Minimises ``||X p - y||^2 + ridge ||p||^2`` subject to one gauge constraint per bipartite
    component of the link graph (see module docstring), through the KKT system
    ``[[X^T X + ridge I, C^T], [C, 0]] [p; mu] = [X^T y; d]``.

    Raises
    ------
    IdentifiabilityError
        Fewer samples than columns (times ``min_samples_per_coef``), a node without samples,
        or a singular system (coverage too poor for the basis; raise the ridge).
    """
    n_nodes = normal.n_nodes
    names = list(node_names) if node_names is not None else [str(i) for i in range(n_nodes)]
    if len(names) != n_nodes:
        raise InputError(f"{len(names)} node names for {n_nodes} nodes")
    if not (np.isfinite(ridge) and ridge >= 0):
        raise InputError(f"ridge must be a non-negative number, got {ridge!r}")
    pcols = normal.n_columns
    if normal.n_samples < min_samples_per_coef * pcols:
        raise IdentifiabilityError(
            f"{normal.n_samples} samples cannot identify {pcols} coefficients "
            f"({n_nodes} nodes x {normal.basis.label}); fly longer or choose a smaller model"
        )
    seen = set()
    for a, b in normal.link_counts:
        seen.update((a, b))
    missing = [names[i] for i in range(n_nodes) if i not in seen]
    if missing:
        raise IdentifiabilityError(f"node(s) {', '.join(missing)} appear in no sample; their patterns cannot be learned")
    components = link_components(n_nodes, normal.link_counts.keys())
    cmat, cval, notes = _gauge_constraints(normal.basis, n_nodes, names, components, gauge)
    sv, rank, cond = spectrum_report(normal.gram)
    k = cmat.shape[0]
    kkt = np.zeros((pcols + k, pcols + k))
    kkt[:pcols, :pcols] = normal.gram
    kkt[np.arange(pcols), np.arange(pcols)] += ridge
    kkt[:pcols, pcols:] = cmat.T
    kkt[pcols:, :pcols] = cmat
    rhs = np.concatenate([normal.rhs, cval])
    # Scale rows/columns for a better-conditioned factorisation.
    scale = 1.0 / np.sqrt(np.maximum(np.abs(np.diag(kkt))[:pcols], 1e-300))
    full_scale = np.concatenate([scale, np.ones(k)])
    kkt_s = kkt * full_scale[:, None] * full_scale[None, :]
    # numpy's LAPACK (not scipy's): a second OpenBLAS thread pool would wait for numpy's
    # spinning threads after the big rank-k update and make this small inverse 40x slower.
    try:
        kinv_s = np.linalg.inv(kkt_s)
    except np.linalg.LinAlgError:
        kinv_s = np.full((pcols + k, pcols + k), np.nan)
    finite = bool(np.all(np.isfinite(kinv_s)))
    cond_1 = float(np.abs(kkt_s).sum(axis=0).max() * np.abs(kinv_s).sum(axis=0).max()) if finite else np.inf
    if not finite or cond_1 > 1.0 / (1e3 * np.finfo(np.float64).eps):
        raise IdentifiabilityError(
            f"the samples do not identify {normal.basis.label} for {n_nodes} nodes: design rank {rank} of "
            f"{pcols} columns, {pcols - rank} free direction(s) but only {k} gauge constant(s); "
            "add samples over the uncovered directions, choose a smaller model, or raise the ridge"
        )
    kinv = kinv_s * full_scale[:, None] * full_scale[None, :]
    sol = kinv @ rhs
    coef = sol[:pcols]
    sse = max(normal.yty - 2.0 * coef @ normal.rhs + coef @ normal.gram @ coef, 0.0)
    dof = max(normal.n_samples - min(rank, pcols), 1)
    resid_var = sse / dof
    # Covariance of the constrained estimate: top-left block of the inverse KKT matrix,
    # sandwiched with X^T X when a ridge is present.
    a = kinv[:pcols, :pcols]
    cov = resid_var * (a @ normal.gram @ a.T) if ridge > 0 else resid_var * a
    cov = 0.5 * (cov + cov.T)
    report = FitReport(
        n_samples=normal.n_samples,
        n_columns=pcols,
        rank=rank,
        null_dim=pcols - rank,
        condition_number=cond,
        expected_null_dim=k,
        gauges=tuple(notes),
        ridge=float(ridge),
        rmse_db=float(np.sqrt(sse / normal.n_samples)),
        singular_values=sv,
        warnings=tuple(fit_warnings(normal.basis.label, pcols, rank, k, cond, ridge)),
    )
    return JointSolution(coef.reshape(n_nodes, normal.basis.n_coef), cov, float(resid_var), report)


def fit_joint(
    directions: Directions,
    tx_index: ArrayLike,
    rx_index: ArrayLike,
    joint_gain_db: ArrayLike,
    n_nodes: int,
    basis: Basis,
    node_names: Sequence[str] | None = None,
    ridge: float = DEFAULT_RIDGE,
    gauge: str | Mapping[str, Any] = "equal-mean",
    chunk_size: int = 1_000_000,
) -> JointSolution:
    """Fit one pattern per node from link samples (paper Sec. IV-B and V-A).

    Parameters
    ----------
    directions : Directions
        ``az_tx, el_tx, az_rx, el_rx`` [rad] of every sample (paper eq. 3).
    tx_index, rx_index : array_like of int
        Node index of the transmitter and the receiver of every sample.
    joint_gain_db : array_like
        Observed joint gain [dB] (paper eq. 5).
    n_nodes : int
        Number of nodes.
    basis : Basis
        Pattern basis shared by all nodes.
    node_names : sequence of str, optional
        Names used in reports and gauge notes.
    ridge : float
        Ridge weight added to the diagonal of ``X^T X`` (default :data:`DEFAULT_RIDGE`).
    gauge : "equal-mean" or dict
        How the free constant of a two-node (bipartite) problem is fixed.
    chunk_size : int
        Samples accumulated per step.
    """
    normal = NormalEquations(basis, n_nodes)
    tx = np.asarray(tx_index)
    rx = np.asarray(rx_index)
    y = np.asarray(joint_gain_db, np.float64)
    n = y.size
    for s in range(0, max(n, 1), chunk_size):
        e = min(n, s + chunk_size)
        normal.add(Directions(*(np.asarray(d)[s:e] for d in directions)), tx[s:e], rx[s:e], y[s:e])
    return solve(normal, node_names, ridge=ridge, gauge=gauge)


def identifiability(
    directions: Directions,
    tx_index: ArrayLike,
    rx_index: ArrayLike,
    n_nodes: int,
    basis: Basis,
    node_names: Sequence[str] | None = None,
) -> FitReport:
    """Rank, null-space dimension and condition number a set of directions gives a model.

    Used to check a flight plan before flying (no signal needed).
    """
    normal = NormalEquations(basis, n_nodes)
    normal.add(directions, tx_index, rx_index, None)
    names = list(node_names) if node_names is not None else [str(i) for i in range(n_nodes)]
    components = link_components(n_nodes, normal.link_counts.keys())
    expected = sum(1 for comp, side_b in components if side_b is not None and len(comp) > 1)
    notes = _gauge_constraints(basis, n_nodes, names, components, "equal-mean")[2]
    sv, rank, cond = spectrum_report(normal.gram)
    return FitReport(
        n_samples=normal.n_samples,
        n_columns=normal.n_columns,
        rank=rank,
        null_dim=normal.n_columns - rank,
        condition_number=cond,
        expected_null_dim=expected,
        gauges=tuple(notes),
        ridge=0.0,
        rmse_db=float("nan"),
        singular_values=sv,
    )
