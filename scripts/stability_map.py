"""Where each solver fails: a grid of N x torque x radius for Newton, SLSQP, Nelder-Mead and FEM.

Every PSM cell is one independent solve from rest (``envs.solver.simulate``, as the design
environment does) of a paper disk whose stiffness scale was fitted on the FEM at N = 20 (the
fan) or of the preset disk (members of the model family, :data:`FAMILY_METHODS`: ring meshes
with the nh-quad element, N up to 2000). For each
cell the script records whether the result passed the independent KKT check (``converged``), the
largest relative KKT residual (force or moment) and the wall time. The baselines get small grids
and time limits (SLSQP 10 s, Nelder-Mead 5 s). The FEM (physical modulus, no scale) is solved as
one ramp through the torques per mesh (r / 6 and r / 12); its "N" axis is the number of rings and
it has no KKT residual (converged or not only).

Writes ``out/stability_map.png`` (residual and failures), ``out/stability_map_time.png`` (wall
time) and ``out/stability_map.json``.

Usage::

    python scripts/stability_map.py [--out out] [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.colors import ListedColormap, LogNorm
from matplotlib.figure import Figure

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.accuracy import (  # noqa: E402
    PAPER_SCENES,
    PAPER_TORQUES_NM,
    calibrate,
    fem_reference,
    jsonable,
)
from envs.fem import fem_grasp  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate  # noqa: E402

TORQUES_NM = (0.02, 0.1, 0.25, 0.5, 1.0)
GRIDS = {
    "newton": (4, 6, 8, 12, 16, 20, 32, 40, 60, 100, 160, 240, 400, 500),
    "slsqp": (4, 8, 12, 20, 32),
    "nelder-mead": (4, 8),
    "fem": (6, 12),  # rings of the FEM mesh
}
# members of the model family (method key -> element, rings), on the preset disks as they are
# (their shipped calibration changes the scale, not where a solver fails)
FAMILY_METHODS = {"nhquad-2": ("nhquad", 2), "nhquad-3": ("nhquad", 3)}
FAMILY_GRID = (8, 12, 20, 32, 40, 48, 64, 100, 200, 500, 1000, 2000)
GRIDS.update({key: FAMILY_GRID for key in FAMILY_METHODS})
TORQUES_BY_METHOD = {"nelder-mead": (0.1, 0.5)}
NEAR_MISS = 1e-5  # a failed cell whose KKT residual is below this is a near miss of the 1e-8 check
TIME_LIMIT_S = {"newton": 30.0, "slsqp": 10.0, "nelder-mead": 5.0}


def _psm_cell(scene: Scene, method: str, n: int, torque: float) -> dict:
    t0 = time.perf_counter()
    if method in FAMILY_METHODS:
        element, rings = FAMILY_METHODS[method]
        res = simulate(scene, torque, n, n_rings=rings, element=element)
    else:
        res = simulate(scene, torque, n, method, time_limit_s=TIME_LIMIT_S[method],
            element="spring")
    wall = time.perf_counter() - t0
    kkt = res.kkt
    resid = max(kkt.force_residual_rel, kkt.moment_residual_rel) if kkt else math.nan
    return {"converged": bool(res.converged), "kkt_residual": float(resid), "time_s": wall,
            "stable": bool(res.stable), "message": res.message,
            "folded": res.folded}


def _fem_cells(scene: Scene, rings: int, torques: tuple[float, ...]) -> list[dict]:
    t0 = time.perf_counter()
    results = fem_grasp(scene, list(torques), mesh_size_m=scene.disk.radius_m / rings)
    wall = time.perf_counter() - t0
    return [{"converged": bool(r.converged), "kkt_residual": math.nan,
             "time_s": float(r.solve_time_s), "message": r.message,
             "from_cache": bool(r.from_cache), "ramp_wall_time_s": wall} for r in results]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--quick", action="store_true", help="smaller grids (smoke test)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    grids = {m: (g[::3] if args.quick else g) for m, g in GRIDS.items()}

    scenes = {}
    for name in PAPER_SCENES:
        base = Scene.preset(name)
        cal = calibrate(base, fem_reference(base, PAPER_TORQUES_NM), 20, xatol=1e-3)
        scenes[name] = cal.calibrated(base)
        print(f"{name}: s = {cal.scale:.4f}")
    # compiled kernels loaded before timing
    simulate(scenes[PAPER_SCENES[0]], 0.1, 20, element="spring")

    cells: dict[str, dict[str, list[list[dict]]]] = {}
    for method, ns in grids.items():
        torques = TORQUES_BY_METHOD.get(method, TORQUES_NM)
        cells[method] = {}
        for name, scene in scenes.items():
            table = []  # [torque][n]
            if method == "fem":
                cols = [_fem_cells(scene, rings, torques) for rings in ns]
                table = [[cols[j][i] for j in range(len(ns))] for i in range(len(torques))]
            else:
                sc = Scene.preset(name) if method in FAMILY_METHODS else scene
                for t in torques:
                    table.append([_psm_cell(sc, method, n, t) for n in ns])
            cells[method][name] = table
            nfold = sum(c.get("folded", False) for row in table for c in row)
            nfail = sum(not c["converged"] for row in table for c in row) - nfold
            print(f"{method:12s} {name}: {nfail}/{len(torques) * len(ns)} cells failed, "
                  f"{nfold} folded, {sum(c['time_s'] for row in table for c in row):.1f} s")

    # summary of failures
    failures = {}
    for method, per_scene in cells.items():
        torques = TORQUES_BY_METHOD.get(method, TORQUES_NM)
        lst = []
        folded = 0
        for name, table in per_scene.items():
            for i, t in enumerate(torques):
                for j, n in enumerate(grids[method]):
                    c = table[i][j]
                    if c.get("folded", False):
                        folded += 1  # an equilibrium outside the model's range, not a failure
                    elif not c["converged"]:
                        lst.append({"scene": name, "torque_nm": t,
                                    "rings" if method == "fem" else "n_triangles": n,
                                    "kkt_residual": c["kkt_residual"],
                                    "message": c["message"][:120]})
        total = len(per_scene) * len(torques) * len(grids[method])
        near = sum(1 for c in lst if c["kkt_residual"] <= NEAR_MISS)
        failures[method] = {"failed": len(lst), "folded": folded, "total": total,
                            "near_miss_residual_below_1e-5": near, "cells": lst}

    # figures: one row per method, one column per disk
    methods = list(grids)
    for kind in ("residual", "time"):
        fig = Figure(figsize=(13, 2.4 * len(methods) + 0.6), layout="constrained")
        axes = fig.subplots(len(methods), len(PAPER_SCENES), squeeze=False)
        for a, method in enumerate(methods):
            torques = TORQUES_BY_METHOD.get(method, TORQUES_NM)
            ns = grids[method]
            for b, name in enumerate(PAPER_SCENES):
                ax = axes[a][b]
                table = cells[method][name]
                if kind == "residual":
                    val = np.array([[c["kkt_residual"] for c in row] for row in table])
                    val = np.where(np.isfinite(val), np.clip(val, 1e-16, 1.0), np.nan)
                    if method == "fem":
                        # the FEM has no KKT residual: plain grey cells, not a fake residual
                        # drawn in the residual colour map
                        im = None
                        ax.imshow(np.zeros(val.shape), origin="lower", aspect="auto",
                                  cmap=ListedColormap(["0.85"]), vmin=0.0, vmax=1.0)
                    else:
                        im = ax.imshow(val, origin="lower", aspect="auto", cmap="viridis",
                                       norm=LogNorm(1e-16, 1.0))
                else:
                    val = np.array([[c["time_s"] for c in row] for row in table])
                    im = ax.imshow(np.clip(val, 1e-3, 100), origin="lower", aspect="auto",
                                   cmap="magma", norm=LogNorm(1e-3, 100))
                fold = np.array([[c.get("folded", False) for c in row] for row in table])
                fail = np.array([[not c["converged"] for c in row] for row in table]) & ~fold
                yy, xx = np.nonzero(fail)
                ax.plot(xx, yy, "x", color="red", ms=9, mew=2.2)
                yy, xx = np.nonzero(fold)
                ax.plot(xx, yy, "o", mfc="none", color="orange", ms=8, mew=1.8)
                ax.set_xticks(range(len(ns)))
                ax.set_xticklabels([str(n) for n in ns], fontsize=7)
                ax.set_yticks(range(len(torques)))
                ax.set_yticklabels([f"{t:g}" for t in torques], fontsize=7)
                r = scenes[name].disk.radius_m
                ax.set_title(f"{method}, r = {r:.2f} m: {int(fail.sum())}/{fail.size} failed"
                             + (f", {int(fold.sum())} folded" if fold.any() else ""), fontsize=8)
                if b == 0:
                    ax.set_ylabel("torque [N·m]", fontsize=8)
                ax.set_xlabel("FEM rings" if method == "fem" else "N", fontsize=8)
            if kind == "residual":
                label = "max rel. KKT residual"
            else:
                label = "wall time [s]" + (" (FEM: per torque of the ramp)" if method == "fem"
                                           else "")
            if im is not None:
                fig.colorbar(im, ax=list(axes[a]), shrink=0.9, label=label)
            else:
                axes[a][-1].text(1.03, 0.5, "FEM: no KKT residual\n(grey: solved cell)",
                                 transform=axes[a][-1].transAxes, fontsize=8, va="center")
        fig.suptitle("red x: not converged (failed the independent KKT check, solver failure or "
                     "time limit); orange o: folded fan (an inverted triangle: the squeeze is "
                     "beyond the model's range)", fontsize=9)
        name = "stability_map.png" if kind == "residual" else "stability_map_time.png"
        fig.savefig(out / name, dpi=110)

    summary = {
        "torques_nm": TORQUES_NM,
        "torques_by_method": {m: TORQUES_BY_METHOD.get(m, TORQUES_NM) for m in methods},
        "grids": grids,
        "time_limits_s": TIME_LIMIT_S,
        "stiffness_scales": {n: s.disk.stiffness_scale for n, s in scenes.items()},
        "cells": cells,
        "failures": failures,
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "stability_map.json").write_text(json.dumps(jsonable(summary), indent=1))
    print("failures per method:")
    for method, f in failures.items():
        print(f"  {method:12s}: {f['failed']}/{f['total']} failed, of which "
              f"{f['near_miss_residual_below_1e-5']} with a KKT residual <= {NEAR_MISS:g}; "
              f"{f['folded']} folded")
        for c in f["cells"][:40]:
            key = "rings" if method == "fem" else "n_triangles"
            print(f"      {c['scene']} T={c['torque_nm']:<5g} {key}={c[key]:<5d} "
                  f"{c['message'][:70]}")
    print(f"wrote {out / 'stability_map.png'}, stability_map_time.png and .json in "
          f"{time.perf_counter() - t_start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
