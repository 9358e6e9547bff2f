"""Pluggable population evaluation: in-process, local processes or a Dask cluster.

:func:`envs.evaluate.evaluate_designs` cuts a population into chunks and calls
``executor.map(fn, chunks)``; every executor here returns the chunk results in order and
evaluates every chunk exactly once *in the result*: a chunk whose task fails (an exception, a
killed worker, a broken process pool) is resubmitted, up to ``max_retries`` times, so that no
evaluation is lost and none is counted twice.

- ``None`` (no executor): in-process batched evaluation, the default; the compiled solver runs
  the rows of a population in parallel threads.
- :class:`SerialExecutor`: chunks one after the other in this process (tests, debugging).
- :class:`ProcessExecutor`: a :class:`concurrent.futures.ProcessPoolExecutor` with the
  ``spawn`` start method (a fresh interpreter per worker; ``fork`` works too since the batch
  rows run on Python threads, :mod:`envs.parallel`); a pool broken by a dead worker is
  replaced.
- :class:`DaskExecutor`: chunks submitted to a ``distributed.Client`` (an existing cluster by
  address, or a :class:`distributed.LocalCluster` for ``"local"``); Dask is imported lazily.
- :class:`RetryingExecutor`: the retry loop, around anything with ``submit(fn, item)`` returning
  futures; the two executors above are built on it.

:func:`make_executor` turns the CLI options (``--dask``, ``--workers``) into one of these.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import multiprocessing
import os
import time
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from envs.validation import check_integer

__all__ = [
    "check_executor_options",
    "ChunkFailedError",
    "SerialExecutor",
    "RetryingExecutor",
    "ProcessExecutor",
    "DaskExecutor",
    "make_executor",
]

DEFAULT_MAX_RETRIES = 3
POLL_S = 0.002
DASK_HINT = "the Dask executor needs dask.distributed: pip install 'psm-grasp[dask]'"
# seconds to wait for a Dask scheduler: a running one answers in well under a second, and a
# wrong address should be reported before a user gives up on a silent command
DASK_CONNECT_TIMEOUT_S = 5.0


class ChunkFailedError(RuntimeError):
    """A chunk kept failing after every retry."""


def _writable(item: Any) -> Any:
    """Copies of read-only numpy arrays in a chunk (Dask may deserialize arrays read-only, and
    numba compiles a separate, possibly unsupported, specialization for read-only arrays)."""
    if isinstance(item, tuple):
        return tuple(_writable(v) for v in item)
    flags = getattr(item, "flags", None)
    if flags is not None and not flags.writeable:
        return item.copy()
    return item


class _ThreadLimited:
    """``fn`` run with the batch solver limited to ``threads`` threads (picklable).

    Several workers on one machine would otherwise each run one thread per core.
    """

    def __init__(self, fn: Callable[[Any], Any], threads: int | None) -> None:
        self.fn, self.threads = fn, threads

    def __call__(self, item: Any) -> Any:
        if self.threads is not None:
            from envs.parallel import set_solver_threads

            set_solver_threads(self.threads)
        return self.fn(_writable(item))


class SerialExecutor:
    """Evaluate chunks one after the other in this process.

    Also a minimal ``submit`` backend for :class:`RetryingExecutor` (returns finished futures).
    """

    n_workers = 1
    description = "serial"

    def submit(self, fn: Callable[[Any], Any], item: Any) -> concurrent.futures.Future:
        """Run ``fn(item)`` now; return a finished future (holding the exception if it raised)."""
        fut: concurrent.futures.Future = concurrent.futures.Future()
        try:
            fut.set_result(fn(item))
        except Exception as exc:  # the future carries it, as a pool's would
            fut.set_exception(exc)
        return fut

    def map(self, fn: Callable[[Any], Any], iterable: Iterable[Any]) -> list[Any]:
        """``[fn(item) for item in iterable]``."""
        return [fn(item) for item in iterable]

    def close(self) -> None:
        """Nothing to release."""


def _failed(fut: Any) -> BaseException | None:
    """The exception of a finished future, or None when it succeeded."""
    try:
        fut.result()
    except (Exception, asyncio.CancelledError, concurrent.futures.CancelledError) as exc:
        return exc
    return None


class RetryingExecutor:
    """``map`` over a ``submit`` backend, resubmitting every failed chunk.

    Parameters
    ----------
    backend
        Anything with ``submit(fn, item)`` returning a future with ``done()`` and ``result()``
        (a :mod:`concurrent.futures` executor, a dask ``Client``, ...).
    max_retries
        Resubmissions allowed per chunk and per ``map`` call, >= 0.
    n_workers
        Number of parallel workers behind ``backend`` (used to size chunks); default
        ``backend.n_workers`` or 1.
    description
        Shown in results (``OptimResult.executor``).

    Attributes
    ----------
    n_resubmitted
        Chunks resubmitted since construction (a failure count for reports and tests).
    """

    def __init__(self, backend: Any, *, max_retries: int = DEFAULT_MAX_RETRIES,
                 n_workers: int | None = None, description: str | None = None) -> None:
        if not callable(getattr(backend, "submit", None)):
            raise ValueError("backend must have a submit(fn, item) method")
        if isinstance(max_retries, bool) or int(max_retries) != max_retries or max_retries < 0:
            raise ValueError(f"max_retries must be an integer >= 0, got {max_retries!r}")
        self.backend = backend
        self.max_retries = int(max_retries)
        self._n_workers = n_workers
        self.description = description or f"retrying({type(backend).__name__})"
        self.n_resubmitted = 0

    @property
    def n_workers(self) -> int:
        """Parallel workers behind the backend."""
        if self._n_workers is not None:
            return int(self._n_workers)
        return int(getattr(self.backend, "n_workers", 1) or 1)

    def _submit(self, fn: Callable[[Any], Any], item: Any) -> Any:
        return self.backend.submit(fn, item)

    def map(self, fn: Callable[[Any], Any], iterable: Iterable[Any]) -> list[Any]:
        """Results of ``fn`` on every item, in order; failed chunks are resubmitted.

        Raises
        ------
        ChunkFailedError
            When a chunk failed ``max_retries + 1`` times (the last error is chained).
        """
        items = list(iterable)
        pending = {i: self._submit(fn, item) for i, item in enumerate(items)}
        attempts = dict.fromkeys(pending, 0)
        results: list[Any] = [None] * len(items)
        while pending:
            done = [i for i, fut in pending.items() if fut.done()]
            if not done:
                time.sleep(POLL_S)
                continue
            for i in done:
                fut = pending.pop(i)
                exc = _failed(fut)
                if exc is None:
                    results[i] = fut.result()
                    continue
                attempts[i] += 1
                if attempts[i] > self.max_retries:
                    for other in pending.values():
                        other.cancel()
                    raise ChunkFailedError(
                        f"chunk {i} failed {attempts[i]} times; last error: {exc!r}") from exc
                self.n_resubmitted += 1
                pending[i] = self._submit(fn, items[i])
        return results

    def close(self) -> None:
        """Close the backend if it can be closed."""
        close = getattr(self.backend, "close", None) or getattr(self.backend, "shutdown", None)
        if callable(close):
            close()


def _init_process_worker() -> None:
    # load the compiled kernels (from numba's cache) before the first task
    import envs.evaluate  # noqa: F401


class ProcessExecutor(RetryingExecutor):
    """Chunks on local worker processes (``spawn``), with retries and pool replacement.

    Parameters
    ----------
    n_workers
        Worker processes, >= 1 (default: the CPU count).
    threads_per_worker
        numba threads per worker (default 1: the processes share the cores).
    max_retries
        Resubmissions per chunk, >= 0.
    """

    def __init__(self, n_workers: int | None = None, *, threads_per_worker: int | None = 1,
                 max_retries: int = DEFAULT_MAX_RETRIES) -> None:
        n = (os.cpu_count() or 1) if n_workers is None else n_workers
        if isinstance(n, bool) or int(n) != n or n < 1:
            raise ValueError(f"n_workers must be an integer >= 1, got {n_workers!r}")
        self.threads_per_worker = threads_per_worker
        self._pool = self._new_pool(int(n))
        super().__init__(self, max_retries=max_retries, n_workers=int(n),
                         description=f"processes({int(n)})")

    @staticmethod
    def _new_pool(n: int) -> concurrent.futures.ProcessPoolExecutor:
        return concurrent.futures.ProcessPoolExecutor(
            max_workers=n, mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_process_worker)

    def submit(self, fn: Callable[[Any], Any], item: Any) -> concurrent.futures.Future:
        """Submit one chunk; a pool broken by a dead worker is replaced first."""
        task = _ThreadLimited(fn, self.threads_per_worker)
        try:
            return self._pool.submit(task, item)
        except concurrent.futures.process.BrokenProcessPool:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool(self.n_workers)
            return self._pool.submit(task, item)

    def close(self) -> None:
        """Shut the pool down."""
        self._pool.shutdown(wait=True, cancel_futures=True)


def _import_distributed():
    try:
        import distributed
    except ImportError as exc:
        raise ImportError(DASK_HINT) from exc
    return distributed


class DaskExecutor(RetryingExecutor):
    """Chunks as tasks on a Dask cluster, gathered in order, lost chunks resubmitted.

    Every chunk is submitted with ``pure=False`` (a fresh key per attempt), so a resubmission
    never reuses the failed task. Dask itself recomputes tasks of a worker that dies; a task that
    keeps killing workers ends as ``KilledWorker`` and is resubmitted here.

    Parameters
    ----------
    client
        A ``distributed.Client``.
    threads_per_task
        numba threads per task (default 1: Dask runs one task per worker thread).
    max_retries
        Resubmissions per chunk, >= 0.
    cluster
        A cluster started for this executor, closed with it.
    """

    def __init__(self, client: Any, *, threads_per_task: int | None = 1,
                 max_retries: int = DEFAULT_MAX_RETRIES, cluster: Any = None) -> None:
        self.client = client
        self.cluster = cluster
        self.threads_per_task = threads_per_task
        address = getattr(getattr(client, "scheduler", None), "address", None) or "?"
        super().__init__(self, max_retries=max_retries, description=f"dask({address})")

    @classmethod
    def connect(cls, address: str, *, timeout_s: float | None = None,
                **kwargs: Any) -> DaskExecutor:
        """Connect to a running scheduler, e.g. ``"tcp://10.0.0.5:8786"``.

        Raises
        ------
        ValueError
            When no scheduler answers at ``address`` within ``timeout_s`` seconds (default
            :data:`DASK_CONNECT_TIMEOUT_S`; Dask's own default waits 30 s, then fails with
            chained tracebacks).
        """
        distributed = _import_distributed()
        timeout_s = DASK_CONNECT_TIMEOUT_S if timeout_s is None else float(timeout_s)
        try:
            client = distributed.Client(address, timeout=f"{timeout_s}s")
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            # OSError: refused, unknown host, timed out (distributed raises OSError for all
            # three); ValueError and TypeError: a malformed address
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ValueError(f"dask = {address!r}: no Dask scheduler answered there within "
                             f"{timeout_s:g} s ({reason}); give the address of a running "
                             "scheduler (tcp://host:8786) or 'local'") from None
        return cls(client, **kwargs)

    @classmethod
    def local(cls, n_workers: int = 2, *, processes: bool = True, **kwargs: Any) -> DaskExecutor:
        """Start a :class:`distributed.LocalCluster` of ``n_workers`` one-thread workers."""
        if isinstance(n_workers, bool) or int(n_workers) != n_workers or n_workers < 1:
            raise ValueError(f"n_workers must be an integer >= 1, got {n_workers!r}")
        distributed = _import_distributed()
        cluster = distributed.LocalCluster(
            n_workers=int(n_workers), threads_per_worker=1, processes=processes,
            dashboard_address=None, silence_logs=40)
        return cls(distributed.Client(cluster), cluster=cluster, **kwargs)

    @property
    def n_workers(self) -> int:
        """Worker threads currently in the cluster (at least 1)."""
        workers = self.client.scheduler_info().get("workers", {})
        return max(1, sum(int(w.get("nthreads", 1)) for w in workers.values()))

    def submit(self, fn: Callable[[Any], Any], item: Any) -> Any:
        """Submit one chunk as a new task."""
        return self.client.submit(_ThreadLimited(fn, self.threads_per_task), item, pure=False,
                                  key=f"psm-grasp-chunk-{uuid.uuid4().hex}")

    def close(self) -> None:
        """Close the client, and the cluster if this executor started it."""
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


MAX_WORKERS_PER_CPU = 4  # local workers per core at most (--workers)


def max_workers() -> int:
    """The most local workers ``--workers`` may start: :data:`MAX_WORKERS_PER_CPU` per core."""
    return MAX_WORKERS_PER_CPU * (os.cpu_count() or 1)


def check_executor_options(dask: str | None = None, workers: int | None = None) -> None:
    """Validate the CLI's ``--dask`` and ``--workers`` without starting anything.

    Raises
    ------
    ValueError
        Naming the option and the user's value.
    """
    most = max_workers()
    if workers is not None:
        try:
            check_integer("workers", workers, 1, most)
        except ValueError as exc:
            raise ValueError(f"{exc} ({MAX_WORKERS_PER_CPU} per core of this machine's "
                             f"{os.cpu_count() or 1}: more local processes only compete for "
                             "them)") from None
    if dask is not None and not str(dask).strip():
        raise ValueError(f"dask must be 'local' or a scheduler address such as "
                         f"tcp://host:8786, got {dask!r}")


@contextlib.contextmanager
def make_executor(dask: str | None = None, workers: int | None = None) -> Iterator[Any]:
    """The executor of the CLI options, closed on exit.

    Parameters
    ----------
    dask
        ``None``: no Dask; ``"local"``: start a ``LocalCluster`` with ``workers`` workers
        (default 2); otherwise the address of a running scheduler.
    workers
        Without Dask: ``None`` or 1 evaluates in-process (batched, threads), more starts that
        many local processes.

    Yields
    ------
    None or an executor
        ``None`` means in-process batched evaluation.
    """
    check_executor_options(dask, workers)
    if dask is None and (workers is None or workers == 1):
        yield None
        return
    if dask is None:
        executor: Any = ProcessExecutor(int(workers))
    elif dask == "local":
        executor = DaskExecutor.local(2 if workers is None else int(workers))
    else:
        executor = DaskExecutor.connect(str(dask))
    try:
        yield executor
    finally:
        executor.close()
