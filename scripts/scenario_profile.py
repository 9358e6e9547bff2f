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

3. ``where`` (``--objects FILE ...``): where the time of each object file's scenario batch
   goes (its own scenarios, e.g. the strawberry's 3 x 3 placements; its ranges, tolerance,
   strain limit, friction and payload, as ``psm-grasp optimize --object`` judges designs),
   for ``--designs`` random designs of each jaw of ``--jaws`` (``straight`` and ``any``: the
   shaped jaws), on one thread: the CPU seconds of the batch as the search runs it (the
   default ``warm_start=True``; the medians of ``--repeats``, each beside the same batch
   with every scenario from rest) split into the solves from rest, the fast path, the finish
   (metrics, the independent check, what the centre carries and the grip the payload needs,
   compiled) and the Python around them (packing, the contact and holding scores, the
   reward); then every grasp of the batch solved from rest alone (the best of two), by the
   contact its answer rests on (the faces only, a groove's mouth edge, a bar's corner): rows,
   share of the time, mean and median milliseconds, Newton iterations (interior point and
   polish) and the tail of grasps over :data:`TAIL_ITERATIONS` iterations; and each jaw's
   CPU seconds a design over the straight jaw's.

Usage: ``python scripts/scenario_profile.py [--designs 128] [--jaw straight] [--neighbours]
[--objects examples/objects/strawberry.toml ...] [--jaws straight any] [--out out/x.json]``
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
from envs.model.layout import I_ITERATIONS, I_STATUS, N_BAR_CORNERS
from envs.object_file import load_object
from envs.parallel import set_solver_threads
from envs.scenarios import Scenarios, evaluate_scenarios
from envs.scene import PRESETS
from envs.solver import follow
from envs.solver import pipeline as pl
from envs.solver.status import OK
from optim.problem import DesignProblem
from optim.run import problem_kwargs

DISK = PRESETS["paper-r070"][1]
COMMON = {"torsion_stiffness_nm_per_rad": PAPER_TORSION_STIFFNESS_NM_PER_RAD,
          "friction_coefficient": 0.5}


TAIL_ITERATIONS = 40  # a grasp solved from rest in more Newton iterations is the tail


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


def _object_problem(path: Path, jaw: str) -> tuple[DesignProblem, dict]:
    """The problem ``psm-grasp optimize --object path --jaw jaw`` solves, and the keyword
    arguments of :func:`evaluate_scenarios` it judges a design with."""
    obj = load_object(path)
    target, settings = problem_kwargs(None, obj, None, None, None, None, jaw=jaw)
    problem = DesignProblem(target, name=obj.name, **settings)
    if problem.scenarios is None:
        raise SystemExit(f"{path} has no scenarios (no ranges, no placement tolerance)")
    kwargs = {"torsion_stiffness_nm_per_rad": problem.torsion_stiffness_nm_per_rad,
              "friction_coefficient": problem.friction_coefficient,
              "strain_limits": problem.strain_limit, "payload_factors": problem.payload_factor,
              "weights": problem.weights, **problem.model.kwargs()}
    return problem, kwargs


def _contact_class(lam_corner: np.ndarray) -> np.ndarray:
    """Each answer's contact: a bar corner presses (``bar_corner``), else a groove's mouth
    edge (``mouth_edge``), else the faces alone (``faces``), from its corner forces (B, 2,
    N_CORNERS, N)."""
    bar = (lam_corner[:, :, :N_BAR_CORNERS] > 0.0).any(axis=(1, 2, 3))
    mouth = (lam_corner[:, :, N_BAR_CORNERS:] > 0.0).any(axis=(1, 2, 3))
    return np.where(bar, "bar_corner", np.where(mouth, "mouth_edge", "faces"))


def _rows_from_rest(n: int, prm: np.ndarray, xs: np.ndarray, lam: np.ndarray) -> dict:
    """Every row solved from rest alone (CPU seconds, the best of two), by contact class."""
    seconds = np.full(prm.shape[0], np.inf)
    iterations = np.zeros(prm.shape[0])
    lam_corner = None
    for _ in range(2):
        for b in range(prm.shape[0]):
            t0 = time.process_time()
            ans = pl._solve(n, prm[b : b + 1], xs[b : b + 1].copy(), lam[b : b + 1].copy())
            seconds[b] = min(seconds[b], time.process_time() - t0)
            iterations[b] = ans.infos[0, I_ITERATIONS]
            if lam_corner is None:
                lam_corner = np.zeros((prm.shape[0], *ans.lam_corner.shape[1:]))
            lam_corner[b] = ans.lam_corner[0]
    kind = _contact_class(lam_corner)
    total = seconds.sum()
    out = {"rows": int(prm.shape[0]), "cpu_s": float(total),
           "mean_iterations": float(iterations.mean())}
    for name in ("faces", "mouth_edge", "bar_corner"):
        rows = kind == name
        if not rows.any():
            continue
        tail = rows & (iterations > TAIL_ITERATIONS)
        out[name] = {
            "rows": int(rows.sum()), "share_of_time": float(seconds[rows].sum() / total),
            "mean_ms": 1e3 * float(seconds[rows].mean()),
            "median_ms": 1e3 * float(np.median(seconds[rows])),
            "mean_iterations": float(iterations[rows].mean()),
            "median_iterations": float(np.median(iterations[rows])),
            "tail_rows": int(tail.sum()),
            "tail_share_of_time": float(seconds[tail].sum() / total)}
    return out


def _starts_from_rest(run) -> tuple:
    """The arguments (N, packed parameters, start states and face multipliers) of the one
    solve from rest that ``run()`` makes (a batch with ``warm_start=False``)."""
    captured: list = []
    solve = pl._solve

    def capture(n, prm, xs, lam):
        captured.append((n, prm.copy(), xs.copy(), lam.copy()))
        return solve(n, prm, xs, lam)

    pl._solve = capture
    try:
        run()
    finally:
        pl._solve = solve
    if len(captured) != 1:
        raise RuntimeError(f"expected one solve from rest, got {len(captured)}")
    return captured[0]


def where(paths: list[Path], jaws: list[str], n_designs: int, repeats: int, seed: int) -> dict:
    """Where each object's scenario batch spends its time, by jaw (see the module's 3.)."""
    out: dict = {}
    for path in paths:
        per_jaw: dict = {}
        for jaw in jaws:
            problem, kwargs = _object_problem(path, jaw)
            rng = np.random.default_rng(seed)
            designs = problem.to_physical(rng.uniform(-1.0, 1.0, (n_designs, problem.n_var)))

            def batch(warm: bool, designs=designs, problem=problem, kwargs=kwargs):
                return evaluate_scenarios(designs, problem.disk, problem.scenarios,
                                          warm_start=warm, **kwargs)

            batch(True)  # load (or compile) and warm up
            times, rest_times, stages, infos = [], [], {}, np.zeros((0, 2))
            for _ in range(repeats):
                rest_times.append(_cpu(lambda batch=batch: batch(False))[0])
                with _Timer() as timer:
                    seconds, table = _cpu(lambda batch=batch: batch(True))
                times.append(seconds)
                stages, infos = timer.seconds, (np.concatenate(timer.infos) if timer.infos
                                                else np.zeros((0, 2)))
            cpu = statistics.median(times)
            rest_cpu = statistics.median(rest_times)
            stages = dict(stages, python=max(0.0, times[-1] - sum(stages.values())))
            starts = _starts_from_rest(lambda batch=batch: batch(False))
            per_jaw[jaw] = {
                "designs": n_designs, "scenarios": len(table.scenarios),
                "cpu_s": cpu, "ms_per_design": 1e3 * cpu / n_designs,
                "every_scenario_from_rest_cpu_s": rest_cpu,
                "from_rest_over_warm": rest_cpu / cpu,
                "stages_cpu_s": stages,
                "followers_tried": int(infos.shape[0]),
                "fast_path_settled": float((infos[:, I_STATUS] == OK).mean())
                if infos.shape[0] else 0.0,
                "from_rest": _rows_from_rest(*starts)}
        if "straight" in per_jaw:
            for row in per_jaw.values():
                row["cpu_over_straight"] = row["cpu_s"] / per_jaw["straight"]["cpu_s"]
        out[str(path)] = per_jaw
    return out


def _print_where(result: dict) -> None:
    """The breakdown of :func:`where` as lines a reader compares at a glance."""
    for path, per_jaw in result.items():
        for jaw, row in per_jaw.items():
            st = row["stages_cpu_s"]
            print(f"{Path(path).stem} {jaw}: {row['ms_per_design']:.2f} ms CPU a design "
                  f"({row['scenarios']} scenarios; {row.get('cpu_over_straight', 1.0):.2f}x "
                  f"straight; every scenario from rest: {row['from_rest_over_warm']:.2f}x "
                  f"the time); from rest {st['from_rest']:.3f} s, fast path "
                  f"{st['fast_path']:.3f} s ({row['fast_path_settled']:.0%} of "
                  f"{row['followers_tried']} settled), finish {st['finish']:.3f} s, Python "
                  f"{st['python']:.3f} s")
            rest = row["from_rest"]
            for name in ("faces", "mouth_edge", "bar_corner"):
                if name in rest:
                    c = rest[name]
                    print(f"  from rest, {name}: {c['rows']} grasps, {c['share_of_time']:.0%} "
                          f"of the time, {c['mean_ms']:.2f} ms mean ({c['median_ms']:.2f} "
                          f"median), {c['mean_iterations']:.1f} iterations "
                          f"({c['median_iterations']:.0f} median); {c['tail_rows']} over "
                          f"{TAIL_ITERATIONS}: {c['tail_share_of_time']:.0%} of the time")


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
    parser.add_argument("--objects", type=Path, nargs="*", default=[],
                        help="object files whose own scenario batches to break down (where "
                             "the time goes, by jaw) instead of the placement batch")
    parser.add_argument("--jaws", nargs="+", default=["straight", "any"],
                        choices=("straight", "cradle", "vee", "any"))
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    set_solver_threads(1)
    rng = np.random.default_rng(args.seed)
    out: dict = {"load_before": _load()}
    if args.objects:
        out["where"] = where(args.objects, args.jaws, args.designs, args.repeats, args.seed)
        out["load_after"] = _load()
        _print_where(out["where"])
        print(f"load {out['load_before']} -> {out['load_after']}")
        if args.out is not None:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps(out, indent=1))
        return
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
