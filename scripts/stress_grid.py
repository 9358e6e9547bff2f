"""Stress grid of the model family: every paper disk, N 4..2000, rings 1..8, ramped to 40 % strain.

For each member (element, N contour points, M rings) and paper disk the torque is ramped
geometrically (x 1.25 a step from 0.02 N·m) with :func:`envs.simulate_ramp` until the peak
spring strain reaches ``--strain`` (default 0.40) or the torque cap. A member passes when every
step up to that strain converged (the independent check passed) with no folded triangle. The
disk's own scales are used (the grid tests robustness, not accuracy: the calibrated scales
change the torque that gives 40 % strain, not the path).

A second table measures cost scaling: one solve of ``paper-r070`` at 0.2 N·m from rest for N
in ``--scaling-ns``, compiled time per solve, and the ratio t(1000) / t(100) (target <= 12).

Writes ``out/stress_grid.json`` and prints one line per ramp.

Usage::

    python scripts/stress_grid.py [--element cst] [--ns 4 8 20 40 100 200 500 1000 2000]
                                  [--rings 1 2 3 4 6 8] [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.model.defaults import MAX_TRIANGLES_FAMILY  # noqa: E402
from envs.model.family import hybrid_disk, resolve_model  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate, simulate_ramp  # noqa: E402

SCENES = ("paper-r050", "paper-r070", "paper-r100")
FIRST_TORQUE_NM = 0.02
GROWTH = 1.25
TORQUE_CAP_NM = 40.0


def ramp_torques() -> np.ndarray:
    """The geometric torque ramp [N·m] up to the cap."""
    steps = int(math.ceil(math.log(TORQUE_CAP_NM / FIRST_TORQUE_NM) / math.log(GROWTH)))
    return FIRST_TORQUE_NM * GROWTH ** np.arange(steps + 1)


def stress_ramp(name: str, n: int, m: int, element: str, strain: float,
                hybrid: bool = False) -> dict:
    """Ramp one member on one disk to ``strain``; counts of failed and folded steps.
    ``hybrid``: the disk with the area energy of :func:`envs.model.family.hybrid_disk` (spring
    members: springs carry the shear modulus, the area energy the rest of the bulk)."""
    scene = Scene.preset(name)
    if hybrid:
        scene = Scene(scene.gripper, hybrid_disk(scene.disk))
    t0 = time.perf_counter()
    results = simulate_ramp(scene, ramp_torques(), n, n_rings=m, element=element,
                            until_peak_strain=strain)
    wall = time.perf_counter() - t0
    last = results[-1]
    reached = bool(last.converged and last.peak_strain >= strain)
    failed = [r for r in results if not r.converged]
    folded = [r for r in results if r.inverted_triangles > 0]
    # converged on a saddle: counted apart (the ramp leaves such a branch where it can)
    unstable = [r for r in results if r.converged and not r.stable]
    return {
        "scene": name, "n": n, "rings": m, "element": element,
        "steps": len(results), "failed_steps": len(failed), "folded_steps": len(folded),
        "unstable_steps": len(unstable),
        "reached_strain": reached,
        "passed": reached and not failed and not folded,
        "final_torque_nm": last.torque_nm, "final_peak_strain": last.peak_strain,
        "final_peak_log_strain": last.peak_log_strain,
        "first_failure": None if not failed else f"T = {failed[0].torque_nm:.4g}: "
                                                 f"{failed[0].message}",
        "iterations": int(sum(r.iterations for r in results)),
        "compiled_s": float(sum(r.solve_time_s for r in results)), "wall_s": wall,
    }


def scaling(ns: list[int], m: int, element: str, repeats: int = 3) -> list[dict]:
    """Compiled time of one solve from rest (paper-r070, 0.2 N·m) against N."""
    scene = Scene.preset("paper-r070")
    rows = []
    for n in ns:
        times, res = [], None
        for _ in range(repeats):
            res = simulate(scene, 0.2, n, n_rings=m, element=element)
            times.append(res.solve_time_s)
        rows.append({"n": n, "rings": m, "element": element, "converged": res.converged,
                     "iterations": res.iterations, "compiled_s": float(np.median(times))})
        print(f"scaling {element} M={m} N={n:5d}: {rows[-1]['compiled_s'] * 1e3:8.2f} ms, "
              f"{res.iterations} iterations, converged {res.converged}", flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--element", default="cst", choices=("spring", "cst", "nhquad"))
    ap.add_argument("--ns", type=int, nargs="+",
                    default=[4, 8, 20, 40, 100, 200, 500, 1000, 2000])
    ap.add_argument("--rings", type=int, nargs="+", default=[1, 2, 3, 4, 6, 8])
    ap.add_argument("--strain", type=float, default=0.40)
    ap.add_argument("--scaling-ns", type=int, nargs="+", default=[100, 200, 500, 1000, 2000])
    ap.add_argument("--scaling-rings", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="N 8, 20, 100 and rings 1, 2, 4")
    ap.add_argument("--hybrid", action="store_true",
                    help="spring members with the area energy (hybrid_disk); without it the "
                         "spring members are springs only and fold, as the paper's fan")
    ap.add_argument("--out", default="out/stress_grid.json")
    args = ap.parse_args(argv)
    if args.quick:
        args.ns, args.rings, args.scaling_ns = [8, 20, 100], [1, 2, 4], [100, 200]
    for n in args.ns + args.scaling_ns:
        if not 4 <= n <= MAX_TRIANGLES_FAMILY:
            ap.error(f"N = {n} outside 4..{MAX_TRIANGLES_FAMILY}")
    rings = [m for m in args.rings if not (args.element == "nhquad" and m < 2)]
    grid, skipped = [], []
    for m in rings:
        for n in args.ns:
            try:  # a member the family refuses (the springs-only fan beyond N = 500)
                resolve_model(n, m, args.element, False)
            except ValueError as exc:
                skipped.append({"n": n, "rings": m, "element": args.element,
                                "reason": str(exc)})
                print(f"{args.element} M={m} N={n:5d}: skipped ({exc})", flush=True)
                continue
            for name in SCENES:
                row = stress_ramp(name, n, m, args.element, args.strain, args.hybrid)
                grid.append(row)
                print(f"{args.element} M={m} N={n:5d} {name}: "
                      f"{'pass' if row['passed'] else 'FAIL'} steps {row['steps']:3d} "
                      f"failed {row['failed_steps']} folded {row['folded_steps']} "
                      f"unstable {row['unstable_steps']} "
                      f"T {row['final_torque_nm']:.3g} N·m strain "
                      f"{row['final_peak_strain']:.3f} ({row['wall_s']:.1f} s)"
                      + (f" first failure {row['first_failure']}" if row["first_failure"]
                         else ""), flush=True)
    scale = scaling([n for n in args.scaling_ns
                     if not any(k["n"] == n and k["rings"] == args.scaling_rings
                                for k in skipped)], args.scaling_rings, args.element)
    by_n = {r["n"]: r["compiled_s"] for r in scale}
    ratio = by_n[1000] / by_n[100] if 1000 in by_n and 100 in by_n else None
    passed = sum(r["passed"] for r in grid)
    summary = {"element": args.element, "strain": args.strain, "ramps": len(grid),
               "passed": passed, "folded_ramps": sum(r["folded_steps"] > 0 for r in grid),
               "skipped_members": len(skipped),
               "t1000_over_t100": ratio}
    print(f"passed {passed}/{len(grid)} ramps, folded ramps {summary['folded_ramps']}, "
          f"t(1000)/t(100) = {ratio if ratio is None else round(ratio, 1)} (target <= 12)")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"summary": summary, "grid": grid, "skipped": skipped,
                               "scaling": scale}, indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
