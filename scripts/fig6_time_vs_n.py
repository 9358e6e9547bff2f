"""Paper Fig. 6: solve time against the number of triangles (r = 0.07 disk).

For the compiled Newton solver: the wall time of one solve from rest (``simulate``; median of
``--repeats`` runs) and the time per torque of a 10-torque loading ramp (``simulate_ramp``), for
N = 4 ... 500 (MAX_TRIANGLES). For the baselines, one solve from rest under a time limit: SLSQP
up to N = 60 and Nelder-Mead (the paper's method) up to N = 8 only, since it does not converge
within any affordable limit. The FEM cost per torque of the reference ramps (default and coarse
mesh) is drawn for comparison. The PSM uses the stiffness scale fitted on the FEM at N = 20.
Members of the model family (:data:`FAMILY`: rings with the nh-quad or constant-strain element)
are timed from rest for N = 8 ... 2000 beside the fan (wall and compiled time per solve).

It also runs :func:`envs.accuracy.choose_n_triangles` on the three paper disks (torques 0.05 to
0.5 N·m, reference N = 160) for tolerances of 1 % (the default), 2 % and 5 %, and reports the
time per solve saved against the fixed fine N = 160.

Writes ``out/fig6_time_vs_n.png`` and ``out/fig6_time_vs_n.json``.

Usage::

    python scripts/fig6_time_vs_n.py [--out out] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.accuracy import (  # noqa: E402
    PAPER_SCENES,
    PAPER_TORQUES_NM,
    calibrate,
    choose_n_triangles,
    fem_reference,
    jsonable,
    psm_curve,
)
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate  # noqa: E402

SCENE = "paper-r070"
TORQUE_NM = 0.25
N_NEWTON = (4, 6, 8, 12, 16, 20, 24, 32, 40, 60, 80, 120, 160, 240, 400, 500)
N_SLSQP = (4, 6, 8, 12, 16, 20, 24, 32, 40, 60)
N_NM = (4, 8)
SLSQP_LIMIT_S = 20.0
NM_LIMIT_S = 10.0
CHOICE_RANGE_NM = (0.05, 0.5)
CHOICE_TOLERANCES = (0.01, 0.02, 0.05)
# members of the model family timed beside the paper's fan: (element, rings) over N_FAMILY
FAMILY = (("nhquad", 2), ("nhquad", 3), ("cst", 3))
N_FAMILY = (8, 12, 20, 32, 40, 48, 64, 100, 200, 500, 1000, 2000)
FAMILY_STYLE = ("tab:green", "tab:olive", "tab:purple", "tab:brown")
STYLE = {"newton": ("tab:blue", "o"), "newton-ramp": ("tab:cyan", "^"),
         "slsqp": ("tab:orange", "s"), "nelder-mead": ("tab:red", "D")}


def _time_single(scene: Scene, n: int, method: str, repeats: int, limit: float,
                 n_rings: int = 1, element: str = "spring") -> dict:
    times, compiled, res = [], [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = simulate(scene, TORQUE_NM, n, method, time_limit_s=limit, n_rings=n_rings,
                       element=element)
        times.append(time.perf_counter() - t0)
        compiled.append(res.solve_time_s)
    return {"n_triangles": n, "method": method, "n_rings": n_rings, "element": element,
            "time_s": float(np.median(times)), "compiled_s": float(np.median(compiled)),
            "times_s": times, "converged": bool(res.converged), "message": res.message,
            "iterations": int(res.iterations),
            "kkt_force_residual_rel": res.kkt.force_residual_rel if res.kkt else None,
            "kkt_moment_residual_rel": res.kkt.moment_residual_rel if res.kkt else None}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--repeats", type=int, default=3, help="repeats of each Newton solve")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    base = Scene.preset(SCENE)
    fem = fem_reference(base, PAPER_TORQUES_NM)
    fem_coarse = fem_reference(base, PAPER_TORQUES_NM, mesh_size_m=base.disk.radius_m / 6)
    scene = calibrate(base, fem, 20, xatol=1e-3).calibrated(base)
    simulate(scene, TORQUE_NM, 20, element="spring")  # load the compiled kernels before timing
    print(f"{SCENE}, T = {TORQUE_NM} N·m, s = {scene.disk.stiffness_scale:.4f}")

    rows = []
    for n in N_NEWTON:
        row = _time_single(scene, n, "newton", args.repeats, 30.0)
        ramp = psm_curve(scene, PAPER_TORQUES_NM, n)
        row["ramp_time_per_torque_s"] = ramp.time_per_solve_s
        row["ramp_failed"] = ramp.n_failed
        rows.append(row)
        print(f"newton      N={n:5d}: {1e3 * row['time_s']:9.2f} ms from rest "
              f"({'ok' if row['converged'] else 'FAILED: ' + row['message'][:50]}), ramp "
              f"{1e3 * ramp.time_per_solve_s:8.2f} ms/torque ({ramp.n_failed} failed)")
    for element, m in FAMILY:
        # the family's shipped calibration changes the scale, not the cost: the paper disk as is
        for n in N_FAMILY:
            row = _time_single(base, n, "newton", args.repeats, 30.0, m, element)
            row["method"] = f"{element} M={m}"
            rows.append(row)
            print(f"{element:6s} M={m} N={n:5d}: {1e3 * row['time_s']:9.2f} ms wall, "
                  f"{1e3 * row['compiled_s']:9.2f} ms compiled "
                  f"({'ok' if row['converged'] else 'FAILED: ' + row['message'][:50]})")
    for n in N_SLSQP:
        row = _time_single(scene, n, "slsqp", 1, SLSQP_LIMIT_S)
        rows.append(row)
        print(f"slsqp       N={n:5d}: {1e3 * row['time_s']:9.2f} ms "
              f"({'ok' if row['converged'] else 'not converged: ' + row['message'][:60]})")
    for n in N_NM:
        row = _time_single(scene, n, "nelder-mead", 1, NM_LIMIT_S)
        rows.append(row)
        print(f"nelder-mead N={n:5d}: {1e3 * row['time_s']:9.2f} ms "
              f"({'ok' if row['converged'] else 'not converged: ' + row['message'][:60]})")

    choices = {}
    for name in PAPER_SCENES:
        sc0 = Scene.preset(name)
        sc = calibrate(sc0, fem_reference(sc0, PAPER_TORQUES_NM), 20, xatol=1e-3).calibrated(sc0)
        choices[name] = {}
        for tol in CHOICE_TOLERANCES:
            ch = choose_n_triangles(sc, CHOICE_RANGE_NM, tol, full_table=True)
            choices[name][str(tol)] = ch
            print(f"choose_n_triangles {name} (s = {sc.disk.stiffness_scale:.3f}), tol "
                  f"{100 * tol:g} %: N = {ch.n_triangles} "
                  f"({'within' if ch.within_tolerance else 'NOT within'} tolerance), "
                  f"{1e3 * ch.time_per_solve_s:.1f} ms/solve vs "
                  f"{1e3 * ch.reference_time_per_solve_s:.1f} ms at N = {ch.reference_n} "
                  f"(x{ch.speedup:.1f}); median converged solve {1e3 * ch.median_solve_s:.1f} "
                  f"vs {1e3 * ch.reference_median_solve_s:.1f} ms (x{ch.median_speedup:.1f}); "
                  f"reference N per torque {list(ch.reference_ns)}")
        table = choices[name][str(CHOICE_TOLERANCES[0])].rows
        for row in table:
            print(f"    N={row.n_triangles:3d}: closing {100 * row.closing_rel_error:7.2f} %, "
                  f"peak strain {100 * row.strain_rel_error:7.2f} %, failed {row.n_failed}, "
                  f"retried {row.n_retried}, {1e3 * row.time_per_solve_s:7.1f} ms/solve")

    fem_cost = {
        "default": fem.solve_time_s / len(PAPER_TORQUES_NM),
        "coarse_r_over_6": fem_coarse.solve_time_s / len(PAPER_TORQUES_NM),
    }

    fig = Figure(figsize=(7, 5))
    ax = fig.add_subplot()
    for method in ("newton", "slsqp", "nelder-mead"):
        col, mk = STYLE[method]
        sel = [r for r in rows if r["method"] == method]
        ns = np.array([r["n_triangles"] for r in sel])
        ts = np.array([r["time_s"] for r in sel])
        ok = np.array([r["converged"] for r in sel])
        ax.plot(ns, ts, "-", color=col, alpha=0.6)
        ax.plot(ns[ok], ts[ok], mk, color=col, label=f"{method} (one solve from rest)")
        if (~ok).any():
            ax.plot(ns[~ok], ts[~ok], mk, color=col, mfc="none", ms=9,
                    label=f"{method}: not converged")
        if method == "newton":
            col2, mk2 = STYLE["newton-ramp"]
            rt = np.array([r["ramp_time_per_torque_s"] for r in sel])
            ax.plot(ns, rt, mk2 + "--", color=col2, ms=5, label="newton, per torque of a ramp")
    for (element, m), col in zip(FAMILY, FAMILY_STYLE, strict=False):
        sel = [r for r in rows if r["method"] == f"{element} M={m}"]
        ns = np.array([r["n_triangles"] for r in sel])
        ts = np.array([r["time_s"] for r in sel])
        ok = np.array([r["converged"] for r in sel])
        ax.plot(ns, ts, "-", color=col, alpha=0.6)
        ax.plot(ns[ok], ts[ok], "v", color=col, label=f"family: {element}, {m} rings")
        if (~ok).any():
            ax.plot(ns[~ok], ts[~ok], "v", color=col, mfc="none", ms=9)
    for label, cost, ls in (("FEM r/12 (per torque of a ramp)", fem_cost["default"], "-"),
                            ("FEM r/6 (per torque of a ramp)", fem_cost["coarse_r_over_6"], ":")):
        ax.axhline(cost, color="k", ls=ls, lw=1, label=label)
    ax.axhline(NM_LIMIT_S, color="tab:red", ls="--", lw=0.6)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("contour points N (the fan's triangles)")
    ax.set_ylabel("wall time [s]")
    ax.set_title(f"{SCENE}, T = {TORQUE_NM} N·m; hollow: failed the independent KKT check "
                 "(tol 1e-8) or hit the time limit", fontsize=8)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "fig6_time_vs_n.png", dpi=120)

    summary = {
        "scene": SCENE,
        "torque_nm": TORQUE_NM,
        "stiffness_scale": scene.disk.stiffness_scale,
        "rows": rows,
        "fem_time_per_torque_s": fem_cost,
        "choose_n_triangles": {"torque_range_nm": CHOICE_RANGE_NM, "choices": choices},
        "time_limits_s": {"slsqp": SLSQP_LIMIT_S, "nelder-mead": NM_LIMIT_S},
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "fig6_time_vs_n.json").write_text(json.dumps(jsonable(summary), indent=1))
    print(f"FEM per torque: default {fem_cost['default']:.2f} s, coarse "
          f"{fem_cost['coarse_r_over_6']:.2f} s")
    print(f"wrote {out / 'fig6_time_vs_n.png'} and .json in "
          f"{time.perf_counter() - t_start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
