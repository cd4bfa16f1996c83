"""The execution seam: serial, a local process pool or a Dask cluster behind one Executor.

Work goes in chunks of sources. Each chunk is one task; the parent writes its result as a part
file (atomically, named by chunk number) as soon as it arrives, and merges the parts in source
order at the end, so the output does not depend on which worker ran what or when. A rerun with
``resume`` reuses every part whose fingerprint (options, catalog, chunk contents) matches.

Every task first calls :func:`worker_setup` (malloc tuning) in its own process and runs in the
offline astropy scope (:func:`offline_task`): this works the same for a pool, a Dask worker and
the serial path, never downloads anything and leaves the worker's astropy set-up as it was.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import hashlib
import itertools
import json
import math
import os
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from ucbplan.errors import InputError, OutputExistsError, UcbplanError, shorten
from ucbplan.io import write_output

T = TypeVar("T")
#: ``progress(sources_done, sources_total)``.
Progress = Callable[[int, int], None]
#: glibc mallopt parameters.
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
#: Trim/mmap thresholds set in workers (glibc's dynamic maximum for the mmap threshold).
MALLOC_THRESHOLD_BYTES = 32 * 1024 * 1024
_SETUP_DONE = False


def tune_malloc() -> bool:
    """Undo a low ``MALLOC_TRIM_THRESHOLD_`` (Dask's nanny sets 64 KiB) with glibc ``mallopt``.

    A fixed trim threshold switches off glibc's dynamic mmap threshold, so every numpy temporary
    above 128 KiB is mmap'd, zero-filled and unmapped again (~40 % CPU in allocation-heavy code).
    Setting the mmap and trim thresholds to 32 MiB restores reuse of freed memory; memory stays
    bounded because chunks are streamed. Skipped when ``UCBPLAN_MALLOC_TUNE=0`` (benchmarks) or
    not on glibc. Returns whether it was applied.
    """
    if os.environ.get("UCBPLAN_MALLOC_TUNE", "1") == "0":
        return False
    name = ctypes.util.find_library("c")
    if not name:
        return False
    try:
        libc = ctypes.CDLL(name)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    ok = mallopt(_M_MMAP_THRESHOLD, MALLOC_THRESHOLD_BYTES)
    ok &= mallopt(_M_TRIM_THRESHOLD, 2 * MALLOC_THRESHOLD_BYTES)
    return bool(ok)


def worker_setup() -> None:
    """Per-process set-up before any work: malloc tuning (each task enters the offline astropy
    scope itself, :func:`ucbplan.offline.offline`)."""
    global _SETUP_DONE
    if _SETUP_DONE:
        return
    if "MALLOC_TRIM_THRESHOLD_" in os.environ:
        tune_malloc()
    _SETUP_DONE = True


def offline_task(task: Callable[[list[Any]], T], items: list[Any]) -> T:
    """``task(items)`` in the offline astropy scope, wherever it runs (pool, Dask, serial)."""
    from ucbplan.offline import offline

    with offline():
        return task(items)


def source_seed(global_seed: int, source_id: str) -> int:
    """Seed of one source from (global seed, source id): independent of chunking and workers."""
    key = hashlib.sha256(f"{int(global_seed)}\x00{source_id}".encode()).digest()
    return int.from_bytes(key[:8], "little") >> 1


class SerialExecutor(Executor):
    """An :class:`~concurrent.futures.Executor` that runs each task at submission (no processes)."""

    def submit(self, fn: Callable[..., T], /, *args: Any, **kwargs: Any) -> Future[T]:
        fut: Future[T] = Future()
        try:
            fut.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # handed to the caller through the future, like a pool
            fut.set_exception(exc)
        return fut


#: Address schemes of a Dask scheduler.
_SCHEMES = ("tcp://", "tls://", "inproc://", "ucx://")
#: Batch systems ``--cluster`` starts Dask workers on (dask-jobqueue class names).
CLUSTERS = {"slurm": "SLURMCluster", "pbs": "PBSCluster"}


@dataclass(frozen=True, slots=True)
class ExecutorSpec:
    """Where to run: ``workers`` local processes (1 = serial), a Dask ``scheduler`` address, or
    a Dask ``cluster`` of ``jobs`` batch jobs started with dask-jobqueue (``slurm``, ``pbs``)."""

    workers: int = 1
    scheduler: str | None = None
    cluster: str | None = None
    jobs: int = 2

    def __post_init__(self) -> None:
        """Check the options before any work (one line each, naming the option)."""
        if self.workers < 1:
            raise InputError(f"workers: expected >= 1, got {self.workers}")
        if self.scheduler and not self.scheduler.startswith(_SCHEMES):
            raise InputError(
                "scheduler: expected an address like tcp://HOST:8786, got "
                f"{shorten(self.scheduler)}"
            )
        if self.cluster is None:
            return
        if self.scheduler:
            raise InputError("`cluster` and `scheduler`: give one of them, not both")
        if self.cluster.strip().lower() not in CLUSTERS:
            raise InputError(
                f"cluster: expected {' or '.join(CLUSTERS)}, got {shorten(self.cluster)}; for "
                "another batch system start a Dask scheduler yourself and pass `scheduler` "
                "tcp://HOST:PORT"
            )
        if self.jobs < 1:
            raise InputError(f"jobs: expected >= 1, got {self.jobs}")

    def describe(self) -> str:
        """One line for logs (not written into outputs: they are identical everywhere)."""
        if self.cluster:
            return f"Dask on {self.jobs} {self.cluster} job(s) (dask-jobqueue)"
        if self.scheduler:
            return f"Dask cluster at {self.scheduler}"
        return "serial" if self.workers <= 1 else f"{self.workers}-process pool"


@contextmanager
def open_executor(spec: ExecutorSpec) -> Iterator[tuple[Executor, int]]:
    """The executor of ``spec`` and its number of task slots; shut down on exit.

    Raises
    ------
    InputError
        ``--workers`` < 1, ``--scheduler`` with ``--cluster``, Dask or dask-jobqueue not
        installed, an unknown batch system, or the scheduler not reachable.
    """
    if spec.cluster:
        with _jobqueue_executor(spec.cluster, spec.jobs) as pair:
            yield pair
        return
    if spec.scheduler:
        with _dask_executor(spec.scheduler) as pair:
            yield pair
        return
    if spec.workers == 1:
        yield SerialExecutor(), 1
        return
    import multiprocessing

    ctx = multiprocessing.get_context("forkserver")
    pool = ProcessPoolExecutor(spec.workers, mp_context=ctx, initializer=worker_setup)
    try:
        yield pool, spec.workers
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _client_class() -> Any:
    try:
        from distributed import Client
    except ImportError:
        raise InputError(
            "scheduler/cluster need Dask distributed: pip install 'ucbplan[dask]'"
        ) from None
    return Client


@contextmanager
def _client_executor(client: Any, min_slots: int = 1) -> Iterator[tuple[Executor, int]]:
    """A Dask client's executor and slots (worker threads; ``min_slots`` while none are up)."""
    try:
        client.run(worker_setup)
        info = client.scheduler_info()
        slots = sum(int(w.get("nthreads", 1)) for w in info.get("workers", {}).values())
        yield client.get_executor(pure=False), max(slots, min_slots, 1)
    finally:
        client.close()


@contextmanager
def _dask_executor(address: str) -> Iterator[tuple[Executor, int]]:
    client_cls = _client_class()
    try:
        client = client_cls(address, timeout=30, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise InputError(
            f"scheduler: cannot reach {shorten(address)} ({shorten(exc)}); is the scheduler up?"
        ) from None
    with _client_executor(client) as pair:
        yield pair


def jobqueue_cluster_class(name: str) -> Any:
    """The dask-jobqueue cluster class of ``--cluster NAME`` (``slurm`` or ``pbs``).

    Raises
    ------
    InputError
        Unknown batch system, or dask-jobqueue not installed (one line each).
    """
    key = name.strip().lower()
    if key not in CLUSTERS:
        raise InputError(
            f"cluster: expected {' or '.join(CLUSTERS)}, got {shorten(name)}; for another "
            "batch system start a Dask scheduler yourself and pass `scheduler` tcp://HOST:PORT"
        )
    _client_class()
    try:
        import dask_jobqueue
    except ImportError:
        raise InputError(
            "cluster needs dask-jobqueue: pip install dask-jobqueue (and set cores, memory, "
            "queue in ~/.config/dask/jobqueue.yaml; see docs/population.md)"
        ) from None
    return getattr(dask_jobqueue, CLUSTERS[key])


@contextmanager
def _jobqueue_executor(name: str, jobs: int) -> Iterator[tuple[Executor, int]]:
    cluster_cls = jobqueue_cluster_class(name)
    client_cls = _client_class()
    try:
        cluster = cluster_cls()  # cores, memory, queue … from the dask-jobqueue config file
    except (ValueError, TypeError, KeyError) as exc:
        raise InputError(
            f"cluster {name}: dask-jobqueue could not configure the cluster "
            f"({shorten(' '.join(str(exc).split()), 160)}); set cores and memory in "
            "~/.config/dask/jobqueue.yaml (docs/population.md)"
        ) from None
    with cluster:
        cluster.scale(jobs=jobs)
        client = client_cls(cluster, set_as_default=False)
        with _client_executor(client, min_slots=jobs) as pair:
            yield pair


def default_chunk(n_sources: int, slots: int, seconds_per_source: float) -> int:
    """Sources per task: ≥ ~1 s of work each, but at least ``2 × slots`` tasks for small runs."""
    per_second = max(1, math.ceil(1.0 / max(seconds_per_source, 1e-6)))
    spread = max(1, math.ceil(n_sources / (2 * max(slots, 1))))
    return max(1, min(per_second, spread))


def _fingerprint(kind: str, options: dict[str, Any], catalog_sha256: str, chunk: int) -> str:
    doc = {"kind": kind, "options": options, "catalog": catalog_sha256, "chunk": chunk}
    return hashlib.sha256(json.dumps(doc, sort_keys=True, default=str).encode()).hexdigest()


def _part_path(folder: Path, index: int) -> Path:
    return folder / f"part-{index:06d}.json"


def _load_part(path: Path, fingerprint: str, ids: list[str]) -> list[dict[str, Any]] | None:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(doc, dict) or doc.get("fingerprint") != fingerprint:
        return None
    if doc.get("ids") != ids or not isinstance(doc.get("rows"), list):
        return None
    return list(doc["rows"])


def _dump(doc: dict[str, Any], handle: Any) -> None:
    handle.write(json.dumps(doc, allow_nan=True))


def prepare_parts(folder: Path, *, resume: bool, overwrite: bool) -> None:
    """Create the parts folder; refuse to mix with an earlier run unless resuming or overwriting.

    Raises
    ------
    OutputExistsError
        The folder holds parts and neither ``resume`` nor ``overwrite`` is set.
    """
    folder.mkdir(parents=True, exist_ok=True)
    old = sorted(folder.glob("part-*.json"))
    if old and not resume:
        if not overwrite:
            raise OutputExistsError(
                f"{folder}: holds {len(old)} part file(s) of an earlier run; add `resume` to "
                "reuse them or `overwrite` to start again"
            )
        for p in old:
            p.unlink()


class _Parts:
    """The chunks of one run: their bounds, the run's fingerprint and the part file of each."""

    def __init__(self, folder: Path, fingerprint: str, ids: Sequence[str], chunk: int) -> None:
        n = len(ids)
        self.folder, self.fingerprint, self.ids = folder, fingerprint, ids
        self.bounds = [(s, min(s + chunk, n)) for s in range(0, n, chunk)]

    def ids_of(self, k: int) -> list[str]:
        a, b = self.bounds[k]
        return list(self.ids[a:b])

    def reuse(self) -> dict[int, list[dict[str, Any]]]:
        """Rows of every chunk whose part file matches this run (``resume``)."""
        found = {}
        for k, (a, b) in enumerate(self.bounds):
            rows = _load_part(_part_path(self.folder, k), self.fingerprint, self.ids_of(k))
            if rows is not None and len(rows) == b - a:
                found[k] = rows
        return found

    def save(self, k: int, rows: list[dict[str, Any]]) -> None:
        """Check the rows of chunk ``k`` and write them as its part file (atomic)."""
        a, b = self.bounds[k]
        if len(rows) != b - a:
            raise UcbplanError(f"chunk {k}: {len(rows)} rows for {b - a} sources")
        doc = {"fingerprint": self.fingerprint, "ids": self.ids_of(k), "rows": rows}
        write_output(_part_path(self.folder, k), functools.partial(_dump, doc), overwrite=True)


def _stream(
    task: Callable[[Sequence[Any]], list[dict[str, Any]]],
    items: Sequence[Any],
    chunks: _Parts,
    results: dict[int, list[dict[str, Any]]],
    executor: Executor,
    window: int,
    progress: Progress | None,
) -> None:
    """Run the chunks not in ``results`` with at most ``window`` in flight; save each part as
    it arrives and add its rows to ``results``."""
    n = len(items)
    done = sum(len(rows) for rows in results.values())
    if progress is not None:
        progress(done, n)
    it = iter([k for k in range(len(chunks.bounds)) if k not in results])
    pending: dict[Future[list[dict[str, Any]]], int] = {}
    try:
        while True:
            for k in itertools.islice(it, max(0, window - len(pending))):
                a, b = chunks.bounds[k]
                pending[executor.submit(offline_task, task, list(items[a:b]))] = k
            if not pending:
                break
            finished, _ = wait(list(pending), return_when=FIRST_COMPLETED)
            for fut in finished:
                k = pending.pop(fut)
                rows = fut.result()
                chunks.save(k, rows)
                results[k] = rows
                done += len(rows)
                if progress is not None:
                    progress(done, n)
    finally:
        for fut in pending:
            fut.cancel()


def run_chunks(
    task: Callable[[Sequence[Any]], list[dict[str, Any]]],
    items: Sequence[Any],
    ids: Sequence[str],
    *,
    chunk: int,
    executor: Executor,
    slots: int,
    parts: Path,
    kind: str,
    options: dict[str, Any],
    catalog_sha256: str,
    resume: bool = False,
    progress: Progress | None = None,
) -> tuple[list[dict[str, Any]], int]:
    """Run ``task`` over ``items`` in chunks; part files in ``parts``; rows in item order.

    Parameters
    ----------
    task : callable
        Picklable ``task(chunk_items) -> rows`` (one dict per item, in order); it must call
        :func:`worker_setup` first.
    ids : sequence of str
        Identifier per item (part files record them; resume checks them).
    chunk : int
        Items per task.
    slots : int
        Tasks kept in flight is twice this (streaming keeps memory bounded).
    parts : Path
        Folder of part files (made by :func:`prepare_parts`).
    kind, options, catalog_sha256
        Fingerprint of the run: a part of another run is recomputed, never reused.

    Returns
    -------
    rows, int
        All rows in item order and the number of chunks reused from earlier parts.
    """
    if chunk < 1:
        raise InputError(f"chunk: expected >= 1, got {chunk}")
    chunks = _Parts(parts, _fingerprint(kind, options, catalog_sha256, chunk), ids, chunk)
    results = chunks.reuse() if resume else {}
    reused = len(results)
    _stream(task, items, chunks, results, executor, max(2, 2 * slots), progress)
    return [row for k in range(len(chunks.bounds)) for row in results[k]], reused


def remove_parts(folder: Path) -> None:
    """Delete the part files and the folder if it is then empty (after a successful merge)."""
    for p in folder.glob("part-*.json"):
        p.unlink()
    try:
        folder.rmdir()
    except OSError:
        pass


class Rate:
    """Sources per second and ETA from progress calls (for the CLI's progress line)."""

    def __init__(self) -> None:
        self.t0 = time.perf_counter()
        self.first: int | None = None

    def eta(self, done: int, total: int) -> tuple[float, float]:
        """(rate [sources/s], ETA [s]) counting only sources computed in this run."""
        if self.first is None:
            self.first = done
            self.t0 = time.perf_counter()
            return 0.0, math.nan
        dt = time.perf_counter() - self.t0
        rate = (done - self.first) / dt if dt > 0 else 0.0
        return rate, (total - done) / rate if rate > 0 else math.nan
