"""Datasets in many files, in one process or on a Dask cluster (``--dask``).

A fit needs only sufficient statistics (:mod:`rplearn.models.streamed`), which add up: each
part of a partitioned dataset (:mod:`rplearn.io.partitions`) is turned into its statistics
(:func:`~rplearn.models.streamed.part_statistics`) where it is read, the statistics are added
(:meth:`~rplearn.models.streamed.Accumulated.combined`) in a binary tree in the order of the
parts, and the small result is solved on the client. In one process
(:func:`rplearn.models.streamed.accumulate_parts`) the same per-part work runs one part after
the other, so both give the same model to rounding (about 1e-12 dB), and an automatic fit the
same drifting error (each unit's sums per 5-s block travel with its statistics and add up by
block, :mod:`rplearn.models.streamed`). This module is the Dask adaptor: the cluster, mapping
parts onto it, and the tree of additions.

``--dask local`` (``local:N`` for N workers; default 2) starts a
:class:`distributed.LocalCluster` of single-threaded worker processes for the command;
``--dask tcp://host:8786`` joins a running scheduler (its workers must have rplearn installed
and see the files: object storage URLs, or a shared disk).
"""

from __future__ import annotations

import os
import signal
import threading
import urllib.parse
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import pandas as pd

from rplearn._budget import Cost, check_work
from rplearn.data.row_copies import RowCopies, SourceHashes, refuse_copies
from rplearn.data.tables import link_samples
from rplearn.data.units import Stretches
from rplearn.errors import BadValueError, InputError
from rplearn.io.files import iter_parts
from rplearn.io.partitions import Part
from rplearn.models.base import Model
from rplearn.models.options import FitOptions
from rplearn.models.predict import check_model_band, uncovered_rows
from rplearn.models.spec import ModelSpec
from rplearn.models.streamed import PART_CHUNK_ROWS, Accumulated, part_statistics, units_and_nodes
from rplearn.models.streamed import accumulate_parts as accumulate_parts_here

#: How to install what ``--dask`` needs.
DASK_INSTALL = "pip install 'rplearn[dask]'"

Progress = Callable[[int, int], None]


#: Peak memory of one single-threaded local worker [bytes] (measured: 1.9 GB for ``--dask local:4``
#: fitting the fleet preset) and the seconds to start one.
LOCAL_WORKER_BYTES, LOCAL_WORKER_START_S = 475e6, 2.0
#: Schemes of scheduler addresses rplearn joins, and why the others are refused.
_SCHEMES = {
    "inproc": "an in-process address (inproc://) lives inside one Python process and cannot be reached from this command",
    "ucx": "ucx:// needs the UCX communication backend (pip install distributed-ucxx) and a UCX network",
    "tls": "tls:// needs certificates in dask's configuration (distributed.comm.tls.ca-file, .client.cert, .client.key)",
}


def local_workers_cost(workers: float) -> Cost:
    """What ``--dask local:N`` takes: :data:`LOCAL_WORKER_BYTES` and :data:`LOCAL_WORKER_START_S` a worker."""
    return Cost(memory_bytes=LOCAL_WORKER_BYTES * workers, seconds=LOCAL_WORKER_START_S * workers)


def _scheduler_address(address: str, text: str) -> str:
    """``scheme://host:port`` of a scheduler, checked without contacting it (one line naming --dask)."""
    scheme, _, rest = text.partition("://")
    scheme = scheme.lower()
    if scheme in ("inproc", "ucx", "tls"):
        ready = scheme == "tls" and _tls_configured() or scheme == "ucx" and _has_ucx()
        if not ready:
            raise InputError(f"--dask {address}: {_SCHEMES[scheme]}; give tcp://host:port", param="dask")
    elif scheme not in ("tcp", "ws", "wss"):
        raise BadValueError(f"--dask {address}: unknown scheme {scheme + '://'!r}; expected local, local:N or a scheduler "
                         "address tcp://host:port", param="dask")
    try:
        parts = urllib.parse.urlsplit(f"{scheme}://{rest}")
        host, _ = parts.hostname, parts.port  # .port raises on a port out of range
    except ValueError as exc:
        raise BadValueError(f"--dask {address}: not a scheduler address ({exc}); expected tcp://host:port", param="dask") from None
    if not host or parts.path not in ("", "/") or parts.query or parts.fragment or parts.username or parts.password:
        raise InputError(f"--dask {address}: not a scheduler address; expected {scheme}://host:port", param="dask")
    return f"{scheme}://{parts.netloc}"


def _tls_configured() -> bool:
    try:
        import dask

        return bool(dask.config.get("distributed.comm.tls.ca-file", None))
    except ImportError:
        return False


def _has_ucx() -> bool:
    import importlib.util

    return importlib.util.find_spec("distributed_ucxx") is not None or importlib.util.find_spec("ucp") is not None


def parse_dask(address: str) -> tuple[str, int | str]:
    """``("local", workers)`` or ``("remote", address)`` from a ``--dask`` value: a local
    cluster within the work budget (:func:`local_workers_cost`, :mod:`rplearn._budget`), or a
    scheduler address whose scheme rplearn can use, checked before any work."""
    text = str(address).strip()
    if text == "local" or text.startswith("local:"):
        count = text.partition(":")[2] or "2"
        if not count.isdigit() or not 1 <= int(count) <= 256:
            raise BadValueError(f"--dask: expected local or local:N with N workers (1 to 256), got {address!r}", param="dask")
        check_work("dask", int(count), local_workers_cost, "local workers", bounds=(1, 256))
        return "local", int(count)
    if "://" in text and text.partition("://")[2]:
        return "remote", _scheduler_address(address, text)
    raise BadValueError(f"--dask: expected local, local:N or a scheduler address such as tcp://host:8786, got {address!r}",
                     param="dask")


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise InputError(f"--dask needs dask[distributed], which is not installed: {DASK_INSTALL}", param="dask") from None
    return distributed


#: Loggers of the cluster's machinery, silenced once the command's work is done: a connection
#: closed while the cluster stops is normal then, not an error to show (``CommClosedError``).
_SHUTDOWN_LOGGERS = ("distributed", "tornado", "asyncio")


@contextmanager
def _children_ignore_sigint() -> Iterator[None]:
    """Start processes that ignore SIGINT (the disposition survives their exec): Ctrl-C in a
    terminal reaches the whole process group, and the workers would each print a traceback;
    this process stops them itself."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _close_quietly(thing: Any) -> None:
    """Close a client or cluster, its shutdown chatter (closed connections, pending tasks) unlogged."""
    import logging

    for name in _SHUTDOWN_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)
    try:
        thing.close()
    except Exception:  # noqa: BLE001 - a connection already closed: the cluster is gone either way
        pass


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


@contextmanager
def _environment_kept() -> Iterator[None]:
    """This process's environment as it was before the block, put back on exit (variables set
    inside removed, changed ones restored)."""
    saved = dict(os.environ)
    try:
        yield
    finally:
        for name in set(os.environ) - set(saved):
            del os.environ[name]
        os.environ.update(saved)


@contextmanager
def dask_client(address: str) -> Iterator[Any]:
    """A :class:`distributed.Client` for a ``--dask`` value, closed (and its local cluster
    stopped) on exit, quietly (also on Ctrl-C: the local workers ignore SIGINT, this process
    stops them)."""
    kind, where = parse_dask(address)
    distributed = _distributed()
    import logging

    import dask

    for name in ("distributed", "dask"):  # the cluster's chatter would bury the command's output
        logging.getLogger(name).setLevel(logging.WARNING)

    # Single-threaded BLAS in each worker: the workers are the parallelism.
    env = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    # distributed's nanny sets these in this process's own environment before it spawns a worker
    # (os.environ.update, never undone): every process this one starts afterwards would run
    # single-threaded BLAS with a fixed PYTHONHASHSEED; this process's environment is put back
    with _environment_kept(), dask.config.set({"distributed.nanny.pre-spawn-environ": env}):
        if kind == "local":
            try:
                with _children_ignore_sigint():
                    cluster = distributed.LocalCluster(n_workers=int(where), threads_per_worker=1, processes=True,
                                                       dashboard_address=":0", silence_logs=logging.CRITICAL)
            except Exception as exc:  # noqa: BLE001 - anything distributed raises: one line
                raise InputError(f"--dask {address}: cannot start a local cluster ({_one_line(exc)})", param="dask") from None
            try:
                client = distributed.Client(cluster)
                try:
                    yield client
                finally:
                    _close_quietly(client)
            finally:
                _close_quietly(cluster)
        else:
            try:
                client = distributed.Client(str(where), timeout="20s")
            except Exception as exc:  # noqa: BLE001 - OSError, TimeoutError, ValueError, CommClosedError...: one line
                raise InputError(f"--dask {where}: cannot reach the scheduler ({_one_line(exc)})", param="dask") from None
            try:
                yield client
            finally:
                _close_quietly(client)


def _tree_reduce(client: Any, futures: list[Any], merge: Callable[[Any, Any], Any]) -> Any:
    """Merge futures pairwise, level by level, keeping their order (left before right)."""
    while len(futures) > 1:
        pairs = [client.submit(merge, futures[i], futures[i + 1], pure=False) for i in range(0, len(futures) - 1, 2)]
        futures = pairs + ([futures[-1]] if len(futures) % 2 else [])
    return futures[0]


def _merge_accumulated(a: Accumulated, b: Accumulated) -> Accumulated:
    """``a`` then ``b`` as a task: it must not change its inputs (the stored results of other
    tasks, which Dask may reuse when it recomputes after a lost worker)."""
    return a.combined(b)


def _watch(client: Any, futures: list[Any], progress: Progress | None) -> None:
    if progress is None:
        return
    from distributed import as_completed

    for done, _ in enumerate(as_completed(futures), start=1):
        progress(done, len(futures))


def map_parts(function: Callable[..., Any], parts: Sequence[Part], client: Any = None, progress: Progress | None = None,
              **kwargs: Any) -> list[Any]:
    """``function(part, **kwargs)`` of every part, in order: here, or on the cluster."""
    if client is None:
        out = []
        for k, part in enumerate(parts):
            out.append(function(part, **kwargs))
            if progress is not None:
                progress(k + 1, len(parts))
        return out
    futures = client.map(function, list(parts), pure=False, **kwargs)
    _watch(client, futures, progress)
    return client.gather(futures)


def part_index(part: Part) -> pd.DataFrame:
    """Rows per ``(unit, tx, rx, frequency_hz)`` of one part (:func:`rplearn.models.streamed.units_and_nodes`)."""
    return units_and_nodes(iter_parts([part], PART_CHUNK_ROWS, columns=("tx", "rx", "unit", "frequency_hz")))


def dataset_index(parts: Sequence[Part], client: Any = None) -> tuple[pd.DataFrame, list[pd.DataFrame]]:
    """The index of the whole dataset (rows per unit and link direction) and of each part."""
    each = map_parts(part_index, parts, client)
    labelled = ["unit" in e.columns for e in each]
    if any(labelled) and not all(labelled):
        bare = parts[labelled.index(False)].path
        raise InputError(f"{bare}: field unit is missing, but other files of the dataset have it (e.g. "
                         f"{parts[labelled.index(True)].path}); label every file's rows, or none", param="dataset")
    every = pd.concat(each, ignore_index=True)
    keys = [c for c in every.columns if c != "n"]
    whole = every.groupby(keys, sort=True, dropna=False)["n"].sum().reset_index() if len(every) else every
    return whole, each


def accumulate_parts(
    parts: Sequence[Part], spec: ModelSpec, nodes: Sequence[str], units: Sequence[str] | None,
    options: FitOptions, stretches: Stretches | None = None, client: Any = None, progress: Progress | None = None,
) -> Accumulated:
    """The statistics of every part, added in order (see the module docstring), with the
    environment term of ``options``: one accumulator per unit when ``options.auto`` (the folds
    of the automatic choice), else one for all learning rows; on the cluster of ``client``, or
    without one in this process (:func:`rplearn.models.streamed.accumulate_parts`).

    ``stretches`` (of a single flight, :func:`learning_times`) label each row by its stretch of
    time wherever the part that holds it is read."""
    units = None if units is None else list(units)
    if client is None:
        return accumulate_parts_here(parts, spec, list(nodes), units, options.auto, stretches, options, progress)
    kwargs = dict(spec=spec, nodes=list(nodes), units=units, by_unit=options.auto, stretches=stretches,
                  options=options)
    futures = client.map(part_statistics, list(parts), pure=False, **kwargs)
    root = _tree_reduce(client, list(futures), _merge_accumulated)
    _watch(client, futures, progress)
    return root.result()


def _part_times(part: Part, units: Sequence[str] | None) -> np.ndarray:
    times = []
    for chunk in iter_parts([part], PART_CHUNK_ROWS, columns=("t", "unit")):
        if units:
            chunk = chunk[chunk["unit"].astype(str).isin(set(units)).to_numpy()] if "unit" in chunk.columns else chunk.iloc[:0]
        times.append(pd.to_numeric(chunk["t"], errors="coerce").to_numpy(np.float64) if "t" in chunk.columns
                     else np.zeros(0))
    return np.concatenate(times) if times else np.zeros(0)


def learning_times(parts: Sequence[Part], units: Sequence[str] | None, client: Any = None) -> np.ndarray:
    """The times [s] of the learning rows (of ``units``; all without) of every part, to cut a
    single flight into its stretches of time (:class:`rplearn.data.units.Stretches`)."""
    each = map_parts(_part_times, parts, client, units=None if units is None else list(units))
    return np.concatenate(each) if each else np.zeros(0)


def _part_predictions(part: Part, models: Sequence[Model], units: Sequence[str] | None
                      ) -> tuple[np.ndarray, list[np.ndarray], list[int | None], RowCopies]:
    observed: list[np.ndarray] = []
    predicted: list[list[np.ndarray]] = [[] for _ in models]
    uncovered: list[int | None] = [None] * len(models)
    hashes = SourceHashes(part.path)
    for chunk in iter_parts([part], PART_CHUNK_ROWS):
        if hashes.add(chunk):  # a copy: the dataset is refused (predict_parts), nothing more to score
            continue
        if units:
            chunk = chunk[chunk["unit"].astype(str).isin(set(units)).to_numpy()] if "unit" in chunk.columns else chunk.iloc[:0]
        if chunk.empty:
            continue
        samples = link_samples(chunk, part.path)
        observed.append(np.asarray(samples.joint_gain_db, np.float64))
        for k, model in enumerate(models):
            if samples.frequency_hz is not None:
                check_model_band(model, samples.frequency_hz, part.path)
            predicted[k].append(np.asarray(model.predict_gain(samples), np.float64))
            n = uncovered_rows(model, samples)
            if n is not None:
                uncovered[k] = (uncovered[k] or 0) + n

    def cat(xs: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(xs) if xs else np.zeros(0)

    return cat(observed), [cat(p) for p in predicted], uncovered, hashes.finish()


def predict_parts(
    parts: Sequence[Part], models: Sequence[Model], units: Sequence[str] | None, client: Any = None,
    progress: Progress | None = None,
) -> tuple[np.ndarray, list[np.ndarray], list[int | None]]:
    """Observed joint gains [dB] of the chosen units of every part, each model's predictions
    of them, and per model the samples outside its coverage (None without a coverage grid).

    A row that repeats an earlier row in every column, in its own part or another (a dataset
    written twice, parts that overlap), is refused with the message of the whole-dataset check
    (:mod:`rplearn.data.row_copies`): scored twice, it would weigh double in every score."""
    if client is not None:
        [models] = client.scatter([list(models)], broadcast=True, hash=False)
    results = map_parts(_part_predictions, parts, client, progress, models=models, units=units)
    refuse_copies([r[3] for r in results])
    n_models = len(results[0][1]) if results else 0
    observed = np.concatenate([r[0] for r in results])
    predictions = [np.concatenate([r[1][k] for r in results]) for k in range(n_models)]
    uncovered: list[int | None] = []
    for k in range(n_models):
        counts = [r[2][k] for r in results if r[2][k] is not None]
        uncovered.append(int(sum(counts)) if counts else None)
    return observed, predictions, uncovered


def selected_rows(index: pd.DataFrame, units: Sequence[str] | None) -> int:
    """Rows of the chosen units in an index (:func:`dataset_index`)."""
    if not len(index):
        return 0
    if not units:
        return int(index["n"].sum())
    if "unit" not in index.columns:
        return 0
    return int(index.loc[index["unit"].astype(str).isin([str(u) for u in units]), "n"].sum())


def worker_peak_rss_bytes(client: Any) -> dict[str, int]:
    """Peak resident memory of each worker process [bytes] (Linux: ``VmHWM``, which, unlike
    ``ru_maxrss``, does not keep the parent's high-water mark across fork and exec)."""
    def peak() -> int:
        with open("/proc/self/status") as fh:
            return next(int(line.split()[1]) for line in fh if line.startswith("VmHWM")) * 1024

    return {str(k): int(v) for k, v in client.run(peak).items()}


def cluster_summary(client: Any) -> str:
    """``N workers, T threads`` of a client's cluster."""
    info = client.scheduler_info()
    workers = info.get("workers", {})
    threads = sum(int(w.get("nthreads", 0)) for w in workers.values())
    return f"{len(workers)} worker(s), {threads} thread(s) at {info.get('address', '?')}"


__all__ = ["DASK_INSTALL", "PART_CHUNK_ROWS", "accumulate_parts", "cluster_summary", "dask_client", "dataset_index",
           "map_parts", "parse_dask", "part_index", "predict_parts", "selected_rows", "worker_peak_rss_bytes"]
