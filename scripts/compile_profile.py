"""Where a cold start's compilation goes: numba's compile time per function, with its LLVM share.

Runs the first batch evaluation of the demo's path (8 random designs, default model, paper-r070)
and records numba's compile events: for each compiled function its own time (its callees'
compilations taken out) and the part of it spent in LLVM (machine code), then the inclusive time
of the entry kernels and their largest callees. Meaningful only on an empty cache::

    make clean-cache && python scripts/compile_profile.py [--top 30] [--specializations]
    make clean-cache && python scripts/compile_profile.py --split

``--split`` first runs the cold-start split of :mod:`envs.solver.warmup` unit by unit: the CPU
time of each unit in this process, the helper process's CPU time and when it ended, then the
batch entry compiled over both shares (the critical path is the longer share plus the entry).

Why it exists: numba gives every compiled function a module of its own with its callees'
subtree linked in (so a layer of wrappers re-emits the subtree), and types an
``inline="always"`` helper again at every call site; this shows which of the two a change moves.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from pathlib import Path

from numba.core import event

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

COMPILE = "numba:compile"
LLVM = "numba:llvm_lock"


class _Recorder(event.Listener):
    """Start/end times of numba's events, with the nesting depth of each kind."""

    def __init__(self) -> None:
        self.stacks: dict[str, list] = collections.defaultdict(list)
        self.records: list[tuple[str, object, float, float, int]] = []

    def on_start(self, ev) -> None:
        self.stacks[ev.kind].append((ev.data, time.perf_counter()))

    def on_end(self, ev) -> None:
        data, start = self.stacks[ev.kind].pop()
        self.records.append((ev.kind, data, start, time.perf_counter(), len(self.stacks[ev.kind])))


def _name(data) -> str:
    if isinstance(data, dict) and "dispatcher" in data:
        func = data["dispatcher"].py_func
        return f"{func.__module__}.{func.__qualname__}"
    return str(data)[:60]


def _inside(inner, outer) -> bool:
    return inner[2] >= outer[2] and inner[3] <= outer[3]


def _print_specializations(comp) -> None:
    """Functions compiled more than once (one compilation per argument typing), with each
    typing's own compile time: a second typing of the same kernel is compile work that one
    signature would save."""
    by_name: dict[str, list] = collections.defaultdict(list)
    for r in comp:
        if isinstance(r[1], dict) and "args" in r[1]:
            by_name[_name(r[1])].append(r)
    repeated = {k: v for k, v in by_name.items() if len(v) > 1}
    print(f"functions compiled for more than one typing: {len(repeated)}")
    for name, recs in sorted(repeated.items(), key=lambda kv: -len(kv[1])):
        print(f"  {len(recs)}x {name}")
        for r in recs:
            print(f"      {r[3] - r[2]:6.2f} s  ({', '.join(map(str, r[1]['args']))})")


def _timed_units(units, start: float) -> None:
    from envs.solver import warmup

    for module, name, spec in units:
        wall, cpu = time.perf_counter(), time.process_time()
        warmup.unit_dispatcher(module, name).compile(warmup.unit_signature(spec))
        print(f"{time.perf_counter() - start:8.1f} s  {name}: {time.process_time() - cpu:5.1f} s "
              f"CPU ({time.perf_counter() - wall:5.1f} s wall)", flush=True)


def _split_timeline() -> None:
    """:func:`envs.solver.warmup.precompile`, step by step with its times."""
    import resource
    import subprocess

    from envs.solver import warmup

    start, cpu = time.perf_counter(), time.process_time()
    helper = subprocess.Popen(warmup._helper_command(), env=warmup._helper_env())
    print("compile split: this process's share (the helper compiles "
          f"{', '.join(u[1] for u in warmup._HELPER_UNITS)})")
    _timed_units(warmup._MAIN_UNITS, start)
    shared = time.process_time() - cpu
    helper.wait()
    helper_cpu = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(f"{time.perf_counter() - start:8.1f} s  helper ended: "
          f"{helper_cpu.ru_utime + helper_cpu.ru_stime:5.1f} s CPU; this share {shared:5.1f} s CPU")
    _timed_units(warmup._FINAL_UNITS, start)
    print(f"split done in {time.perf_counter() - start:.1f} s, this process "
          f"{time.process_time() - cpu:.1f} s CPU")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=30, help="functions listed")
    ap.add_argument("--split", action="store_true",
                    help="time the two-process compile split unit by unit first")
    ap.add_argument("--specializations", action="store_true",
                    help="also list every function compiled for more than one argument typing")
    args = ap.parse_args()
    rec = _Recorder()
    for kind in (COMPILE, LLVM):
        event.register(kind, rec)
    import numpy as np

    from envs.evaluate import DesignBounds, evaluate_designs
    from envs.scene import Scene

    if args.split:
        _split_timeline()
    t0 = time.perf_counter()
    disk = Scene.preset("paper-r070").disk
    evaluate_designs(DesignBounds().sample(np.random.default_rng(0), 8, disk), disk)
    total = time.perf_counter() - t0
    comp = [r for r in rec.records if r[0] == COMPILE]
    llvm = [r for r in rec.records if r[0] == LLVM and r[4] == 0]
    own: dict[str, float] = collections.defaultdict(float)
    own_llvm: dict[str, float] = collections.defaultdict(float)
    for r in comp:
        children = sum(c[3] - c[2] for c in comp if c[4] == r[4] + 1 and _inside(c, r))
        own[_name(r[1])] += (r[3] - r[2]) - children
    for lk in llvm:
        holders = [c for c in comp if _inside(lk, c)]
        if holders:
            own_llvm[_name(max(holders, key=lambda c: c[2])[1])] += lk[3] - lk[2]
    print(f"first batch evaluation {total:.1f} s; compiling {sum(own.values()):.1f} s over "
          f"{len(own)} functions ({len(comp)} compilations), LLVM {sum(own_llvm.values()):.1f} s")
    print("   own [s]  LLVM [s]  function")
    for name, sec in sorted(own.items(), key=lambda kv: -kv[1])[:args.top]:
        print(f"{sec:10.2f} {own_llvm[name]:9.2f}  {name}")
    if args.specializations:
        _print_specializations(comp)
    print("inclusive [s] of the entries and their callees over 2 s:")
    for r in sorted(comp, key=lambda r: r[2]):
        if r[4] <= 3 and r[3] - r[2] > 2.0:
            print(f"{'   ' * r[4]}{r[3] - r[2]:8.2f}  {_name(r[1])}")


if __name__ == "__main__":
    main()
