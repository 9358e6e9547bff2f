"""Where a scenario batch's time goes, with and without the fast path of envs.solver.follow.

1. ``scenarios``: :func:`envs.scenarios.evaluate_scenarios` of ``--designs`` random designs of
   the design box on paper-r070 (the default model) under a 3 x 3 placement grid
   (``--placement-mm`` both ways), on one thread, each scenario from rest
   (``warm_start=False``) and from its design's nominal answer (``warm_start=True``),
   interleaved ``--repeats`` times; CPU seconds of each (the medians, and their ratio), split
   into the solves from rest (leaders and fallbacks), the fast path and the finish; how many
   followers the fast path settled, its Newton steps and the time of one; and how far the two
   answers lie apart (finger angles, converged rows of both).
2. ``neighbours`` (``--neighbours``): the same fast path for a batch of unrelated random designs,
   each of the last ``--batch - --leaders`` following the nearest (in the unit design box) of
   the first ``--leaders`` (:func:`envs.evaluate.evaluate_designs` with ``leaders=``), against
   the plain batch.

Usage: ``python scripts/scenario_profile.py [--designs 128] [--jaw straight] [--neighbours]
[--out out/x.json]``
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np

from envs.evaluate import DesignBounds, evaluate_designs
from envs.model.defaults import PAPER_TORSION_STIFFNESS_NM_PER_RAD
from envs.model.layout import I_ITERATIONS, I_STATUS
from envs.parallel import set_solver_threads
from envs.scenarios import Scenarios, evaluate_scenarios
from envs.scene import PRESETS
from envs.solver import follow
from envs.solver import pipeline as pl
from envs.solver.status import OK

DISK = PRESETS["paper-r070"][1]
COMMON = {"torsion_stiffness_nm_per_rad": PAPER_TORSION_STIFFNESS_NM_PER_RAD,
          "friction_coefficient": 0.5}


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


class _Timer:
    """CPU seconds of the pipeline's stages while installed; the fast path's info rows."""

    def __init__(self) -> None:
        self.seconds = {"from_rest": 0.0, "fast_path": 0.0, "finish": 0.0}
        self.infos: list[np.ndarray] = []
        self._saved = (pl._solve, pl.checked_solution, follow.follow_batch)

    def _wrap(self, key, fn):
        def timed(*args, **kwargs):
            t0 = time.process_time()
            out = fn(*args, **kwargs)
            self.seconds[key] += time.process_time() - t0
            if key == "fast_path":
                self.infos.append(args[-1].copy())
            return out
        return timed

    def __enter__(self):
        solve, finish, fast = self._saved
        pl._solve = self._wrap("from_rest", solve)
        pl.checked_solution = self._wrap("finish", finish)
        follow.follow_batch = self._wrap("fast_path", fast)
        return self

    def __exit__(self, *exc) -> None:
        pl._solve, pl.checked_solution, follow.follow_batch = self._saved


def _cpu(fn) -> tuple[float, object]:
    t0 = time.process_time()
    out = fn()
    return time.process_time() - t0, out


def scenarios(designs: np.ndarray, placement_m: float, repeats: int) -> dict:
    grid = Scenarios.of(placement_tolerance_m=placement_m)
    for warm in (False, True):  # load (or compile) and warm up
        evaluate_scenarios(designs[:2], DISK, grid, warm_start=warm, **COMMON)
    times: dict[bool, list[float]] = {False: [], True: []}
    tables: dict[bool, dict] = {}
    stages: dict[str, float] = {}
    infos: np.ndarray | None = None
    for _ in range(repeats):
        for warm in (False, True):
            with _Timer() as timer:
                seconds, table = _cpu(lambda warm=warm: evaluate_scenarios(
                    designs, DISK, grid, warm_start=warm, **COMMON).per_scenario)
            times[warm].append(seconds)
            tables[warm] = table
            if warm:
                stages = timer.seconds
                infos = np.concatenate(timer.infos) if timer.infos else np.zeros((0, 2))
    cold, warm = tables[False], tables[True]
    both = cold["converged"] & warm["converged"]
    gap = np.abs(cold["jaw_angles_rad"] - warm["jaw_angles_rad"]).max(axis=-1)[both]
    settled = infos[:, I_STATUS] == OK
    fast_steps = infos[:, I_ITERATIONS]
    independent, warm_s = statistics.median(times[False]), statistics.median(times[True])
    return {
        "grasps": int(cold["converged"].size),
        "independent_cpu_s": independent,
        "warm_cpu_s": warm_s,
        "independent_over_warm": independent / warm_s,
        "warm_stages_cpu_s": stages,
        "followers_tried": int(infos.shape[0]),
        "fast_path_settled": float(settled.mean()) if infos.shape[0] else 0.0,
        "fast_path_mean_steps_settled": float(fast_steps[settled].mean()) if settled.any()
        else 0.0,
        "fast_path_us_per_follower": 1e6 * stages.get("fast_path", 0.0) / max(1, infos.shape[0]),
        "fast_path_us_per_step": 1e6 * stages.get("fast_path", 0.0) / max(1.0, fast_steps.sum()),
        "independent_us_per_grasp": 1e6 * independent / cold["converged"].size,
        "converged_independent": int(cold["converged"].sum()),
        "converged_warm": int(warm["converged"].sum()),
        "max_jaw_angle_difference_rad": float(gap.max()) if gap.size else 0.0,
        "rows_differing_over_1e-9_rad": int((gap > 1e-9).sum()),
    }


def neighbours(designs: np.ndarray, n_leaders: int) -> dict:
    unit = (designs - designs.min(axis=0)) / np.maximum(np.ptp(designs, axis=0), 1e-300)
    leaders = np.full(len(designs), -1)
    dist = np.linalg.norm(unit[n_leaders:, None, :] - unit[None, :n_leaders, :], axis=2)
    leaders[n_leaders:] = np.argmin(dist, axis=1)
    evaluate_designs(designs[:4], DISK)
    evaluate_designs(designs[:4], DISK, leaders=[-1, 0, 0, 0])
    plain_s, _ = _cpu(lambda: evaluate_designs(designs, DISK))
    with _Timer() as timer:
        led_s, _ = _cpu(lambda: evaluate_designs(designs, DISK, leaders=leaders))
    infos = np.concatenate(timer.infos) if timer.infos else np.zeros((0, 2))
    return {
        "designs": len(designs),
        "leaders": n_leaders,
        "median_distance_to_leader": float(np.median(dist.min(axis=1))),
        "plain_cpu_s": plain_s,
        "with_leaders_cpu_s": led_s,
        "plain_over_with_leaders": plain_s / led_s,
        "fast_path_settled": float((infos[:, I_STATUS] == OK).mean()) if infos.size else 0.0,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--designs", type=int, default=128)
    parser.add_argument("--placement-mm", type=float, default=2.0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--neighbours", action="store_true")
    parser.add_argument("--batch", type=int, default=1024)
    parser.add_argument("--leaders", type=int, default=256)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jaw", default="straight", choices=("straight", "cradle", "vee", "any"),
                        help="the jaws of the placement batch's designs (grooved designs are "
                             "solved from rest in every scenario)")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    set_solver_threads(1)
    rng = np.random.default_rng(args.seed)
    out: dict = {"load_before": _load()}
    out["scenarios"] = scenarios(DesignBounds(jaw=args.jaw).sample(rng, args.designs, DISK),
                                 args.placement_mm * 1e-3, args.repeats)
    if args.neighbours:
        out["neighbours"] = neighbours(DesignBounds().sample(rng, args.batch, DISK),
                                       args.leaders)
    out["load_after"] = _load()
    print(json.dumps(out, indent=1))
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
