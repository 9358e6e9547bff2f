"""The rows of a batch on Python threads, each running a compiled kernel that releases the GIL.

Why not numba's ``parallel=True``: a parallel loop compiles the whole solver a second time into
its gufunc (~18 s of a first run's ~130 s of compilation) and starts numba's OpenMP pool, which
is not fork-safe. A ``nogil`` kernel over a range of rows, called from a few threads that take
small blocks of rows from a shared counter, gives the same dynamic schedule (solve times vary by
100x between rows) for a few microseconds a block.
"""

from __future__ import annotations

import itertools
import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import numba

from .validation import check_integer

__all__ = ["run_rows", "set_solver_threads", "solver_threads", "ROWS_PER_TASK"]

ROWS_PER_TASK = 8  # largest block of rows a thread takes at once
_lock = threading.Lock()
_state: dict = {"threads": None, "pool": None, "size": 0}


def solver_threads() -> int:
    """Threads a batch runs on: :func:`set_solver_threads`, else numba's configured count
    (``NUMBA_NUM_THREADS``, by default the number of cores)."""
    threads = _state["threads"]
    return threads if threads is not None else max(1, int(numba.config.NUMBA_NUM_THREADS))


def set_solver_threads(threads: int | None) -> None:
    """Limit the threads of a batch (``None``: back to the default), e.g. one per worker
    process when several processes share the cores."""
    _state["threads"] = None if threads is None else check_integer("threads", threads, 1, 4096)


def _pool(size: int) -> ThreadPoolExecutor:
    with _lock:
        if _state["pool"] is None or _state["size"] != size:
            if _state["pool"] is not None:
                _state["pool"].shutdown(wait=False)
            _state["pool"] = ThreadPoolExecutor(size, thread_name_prefix="psm-grasp-rows")
            _state["size"] = size
        return _state["pool"]


def _forget_pool() -> None:
    # a forked child has none of the parent's threads: it starts its own pool when needed
    _state["pool"], _state["size"] = None, 0


os.register_at_fork(after_in_child=_forget_pool)


def run_rows(kernel: Callable, n_rows: int, *args) -> None:
    """Call ``kernel(start, stop, *args)`` over blocks covering rows ``0 .. n_rows - 1``.

    ``kernel`` is a ``nogil`` compiled function that handles rows ``start <= b < stop`` and
    touches no other row's data. The calling thread works too, alone (no pool) for one row or
    one thread; an exception of any block is raised here after every block has finished.
    """
    threads = min(solver_threads(), n_rows)
    if threads <= 1:
        kernel(0, n_rows, *args)
        return
    block = max(1, min(ROWS_PER_TASK, n_rows // (4 * threads)))
    counter = itertools.count()  # next() is atomic under the GIL

    def work() -> None:
        while True:
            start = next(counter) * block
            if start >= n_rows:
                return
            kernel(start, min(start + block, n_rows), *args)

    futures = [_pool(threads - 1).submit(work) for _ in range(threads - 1)]
    try:
        work()
    finally:
        for f in futures:
            f.result()
