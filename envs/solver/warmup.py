"""Whether the compiled solver is in numba's on-disk cache, and a notice when it is not.

The first run after an install compiles the kernels (minutes on a 2-core machine) with no
output of its own; the command-line entry points call :func:`announce_compile` first so that a
new user knows what the wait is.
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["kernels_cached", "announce_compile"]

# the batch and single-grasp entries: cached together with everything they call
_ENTRIES = ("driver.solve_rows-*.nbi", "pipeline._finish_rows-*.nbi")


def kernels_cached() -> bool:
    """True when numba's cache holds the solver's entry kernels (a warm start)."""
    cache = Path(__file__).resolve().parent / "__pycache__"
    return all(any(cache.glob(pattern)) for pattern in _ENTRIES)


def announce_compile(stream=None) -> bool:
    """Print a notice on ``stream`` (default stderr) when the kernels will be compiled by the
    first solve; returns whether it did."""
    if kernels_cached():
        return False
    print("psm-grasp: compiling the solver's kernels (first run after an install: about 2 "
          "minutes on a 2-core machine; later runs load them in about a second) ...",
          file=stream or sys.stderr, flush=True)
    return True
