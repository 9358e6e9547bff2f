"""Whether the compiled solver is in numba's on-disk cache; on a cold cache, a notice and a
compile split over two processes.

The first run after an install compiles the kernels (about a minute and a half on a 2-core
machine, one process) with no output of its own; the command-line entry points call
:func:`announce_compile` first so that a new user knows what the wait is, and it compiles the
solver's largest independent compile units in two processes at once (:func:`precompile`).

Why two processes: numba compiles in one thread, and a function it has cached is linked into a
caller compiled later (its callees are not compiled again). A spawned process compiles one
share of the units below into the cache while this one compiles the other (a unit calls only
units compiled before it: earlier in its own share, or at the head of the other share, in the
cache by the time it is reached); then this process compiles the batch entry over both
(``scripts/compile_profile.py`` shows where the time goes), so that the first solve after the
notice compiles nothing.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import subprocess
import sys
import threading
import warnings
from pathlib import Path

import numba
import numpy as np
from numba.core import types

__all__ = ["kernels_cached", "announce_compile", "precompile"]

# the batch and single-grasp entries: cached together with everything they call
_ENTRIES = (("driver", "solve_rows"), ("pipeline", "_finish_rows"))

# Compile units (module of envs.solver, function, argument types) that do not call one another,
# in two shares of about equal compile time. Argument types: f/i/b = float64/int64/bool
# scalars, with a digit: C-contiguous arrays of that many dimensions; a capital letter: a named
# tuple of _TUPLES. They must be the types the solver calls them with (tests/test_warmup.py
# checks that they add no specialization). The interior point's iterations (_ipm_core, last in
# the helper) call the Newton matrix compiled before them there and the curvature kernels of
# this process's share, in the cache by then (this share's first unit, the finish of a row,
# calls none of the solver); the curvature kernels in turn find the Newton matrix's callees
# in the cache. The batch entry is left with little of its own (scripts/compile_profile.py).
_HELPER_UNITS = (
    ("assembly", "_newton_matrix",
     "f1 i f1 i1 i1 i1 i1 i f1 f1 f1 f2 f2 f2 f1 f1 f2 i1 f b f1 f1 f2 i2 f2"),
    ("polish", "_polish_set", "f1 f1 i f1 f1 i1 i1 i1 i1 i f b1 i1 f1 b1 f b b"),
    ("ipm", "_ipm_core", "f1 f1 i f1 f1 i1 i1 i1 i1 i f f i1 W"),
)
_MAIN_UNITS = (
    ("pipeline", "_finish_rows",
     "i i f2 f2 i f2 f3 f4 f2 f2 f3 f3 f3 f4 f2 f3 i3 f2 f2 f2 i1 i2 b2 f2 f1 i1 f2"),
    ("assembly", "_drop_curvature", "f1 i f1 i1 i1 i1 i i2 f2 f2 i1 f2 f2 f2"),
    ("curvature", "_negative_curvature_step",
     "f1 i f1 i1 i1 i1 i1 i f1 f f2 f2 f2 f2 f2 f1 f1 f1 f1 f1 f1 f1 f1"),
    ("start", "_close_to_contact", "f1 i f1"),
    ("assembly", "_merit", "f1 i f1 i1 i1 i1 i f1"),
    ("assembly", "_stationarity", "f1 i f1 i1 i1 i1 i f1 f1 f1 f2 i1 f1"),
    ("contact", "_all_gaps", "f1 i f1 i1 i1 i1 f1"),
    ("candidates", "_initial_candidates", "f1 i f1 b2 b3 f2 f2"),
    ("candidates", "_grow_candidates", "f1 f1 i f1 b2 b3 b b"),
    ("driver", "_finish", "f1 i f1 i1 i1 i1 i f1 f1 f i f2 f3 f1 f1"),
    ("driver", "_escape", "f1 f1 i f1 i1 i1 i1 i i f1 f"),
)
# The named tuples among the units' arguments: (module of envs.solver, class, its fields'
# types in the codes above)
_TUPLES = {
    "W": ("ipm", "IpmWork", "f1 f1 f1 f1 f2 f2 f2 f2 f2 f1 f1 f1 f1 f1 f1 f1 f1 f1 f2 i1 f1 f2 "
                            "i2 f2 f1 f1 f1 f1 f1"),
}
# Compiled last, here, once both shares are in the cache: the batch entry (the drivers inline
# into it). Inside the notice rather than in the first solve, so that an
# optimizer's progress bar, its ETA and its evaluations per second start after the compile
_FINAL_UNITS = (
    ("driver", "solve_rows", "i i i f2 f1 f2 f3 f4 f2 b4 b3 f2"),
    # the scenario fast path's entry (a design's other placements from its nominal answer),
    # which every optimizer with a placement tolerance runs
    ("follow", "follow_rows", "i i i f2 f1 f2 f3 f4 f2 b4 b3 f2"),
)
_announced = False  # announce_compile has run its compile in this process
_lock = threading.Lock()
_SCALARS = {"f": types.float64, "i": types.int64, "b": types.boolean}
_DTYPES = {"f": np.float64, "i": np.int64, "b": np.bool_}


def unit_signature(spec: str) -> tuple:
    """The numba argument types of a unit's spec string (see ``_HELPER_UNITS``)."""
    return tuple(_arg_type(code) for code in spec.split())


def _arg_type(code: str):
    if code in _TUPLES:
        module, name, fields = _TUPLES[code]
        # the type numba gives an instance: a sample of one-element arrays of the field types
        sample = getattr(importlib.import_module(f"envs.solver.{module}"), name)(
            *(_sample(field) for field in fields.split()))
        return numba.typeof(sample)
    scalar = _SCALARS[code[0]]
    return types.Array(scalar, int(code[1:]), "C") if len(code) > 1 else scalar


def _sample(code: str) -> np.ndarray:
    """A C-contiguous array of an array code (``f2``: float64, two dimensions)."""
    return np.zeros((1,) * int(code[1:]), dtype=_DTYPES[code[0]])


def unit_dispatcher(module: str, name: str):
    """The numba dispatcher of a compile unit."""
    return getattr(importlib.import_module(f"envs.solver.{module}"), name)


def _compile_units(units) -> None:
    for module, name, spec in units:
        unit_dispatcher(module, name).compile(unit_signature(spec))


def _helper_command() -> list[str]:
    """The second process: a fresh interpreter (not multiprocessing's spawn, which would run
    the user's main module again) compiling ``_HELPER_UNITS``."""
    return [sys.executable, "-c", "from envs.solver.warmup import _HELPER_UNITS, _compile_units; "
            "_compile_units(_HELPER_UNITS)"]


def _helper_env() -> dict[str, str]:
    """This environment with the package's own root first on ``PYTHONPATH`` (the helper must
    compile the files this process runs, into the same cache)."""
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return env


def _cache_dir(module: str, name: str) -> Path:
    """Where numba keeps a compile unit's cache (next to the source, or numba's user-wide cache
    directory when the package's folder is not writable)."""
    return Path(unit_dispatcher(module, name).stats.cache_path)


def kernels_cached() -> bool:
    """True when numba's cache holds the solver's entry kernels (a warm start)."""
    return all(any(_cache_dir(module, name).glob(f"{module}.{name}-*.nbi"))
               for module, name in _ENTRIES)


def precompile() -> bool:
    """On a cold cache, compile the solver's largest independent units, one share in a second
    Python process and the other here, and wait for both; returns whether it compiled.

    Then, in this process, the batch entry (``_FINAL_UNITS``), which calls both shares. Without
    it the first solve compiles everything in one process; a failed helper costs nothing but
    the time (the first solve then compiles what is missing).
    """
    if kernels_cached():
        return False
    try:
        helper = subprocess.Popen(_helper_command(), env=_helper_env(),
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        helper = None
    try:
        _compile_units(_MAIN_UNITS)
    except Exception as exc:  # noqa: BLE001 - best effort: the first solve compiles the rest
        warnings.warn(f"psm-grasp: the cold-start compile split failed ({exc!r}); the first "
                      "solve compiles the kernels in one process", RuntimeWarning, stacklevel=2)
        if helper is not None:
            helper.kill()
        return True
    finally:
        if helper is not None:
            helper.wait()
    try:
        _compile_units(_FINAL_UNITS)
    except Exception as exc:  # noqa: BLE001 - best effort, as above
        warnings.warn(f"psm-grasp: the batch entry did not compile ahead of the first solve "
                      f"({exc!r}); the first solve compiles it", RuntimeWarning, stacklevel=2)
    return True


def announce_compile(stream=None) -> bool:
    """On a cold cache, print a notice on ``stream`` (default stderr) and :func:`precompile`;
    returns whether it did."""
    global _announced
    # once per process, and one thread at a time (evaluate_designs with a thread executor
    # starts several first solves at once): the first solve after it compiles what is left
    # and must not split the compile again because its entries are not cached yet
    with _lock:
        if _announced or kernels_cached():
            return False
        _announced = True
        # a worker of a process pool compiles in one process: a split per worker would run two
        # compiling processes per worker against one cache
        _notice_and_precompile(stream, split=multiprocessing.parent_process() is None)
    return True


def _new_lock() -> None:
    """A forked child's lock: the parent's may be held by a thread the child does not have."""
    global _lock
    _lock = threading.Lock()


os.register_at_fork(after_in_child=_new_lock)


def _notice_and_precompile(stream, split: bool = True) -> None:
    how = ("about a minute on a 2-core machine, two processes" if split
           else "about a minute and a half in this worker process")
    print(f"psm-grasp: compiling the solver's kernels (first run after an install: {how}; later "
          "runs load them in about a second) ...", file=stream or sys.stderr, flush=True)
    if split:
        precompile()
