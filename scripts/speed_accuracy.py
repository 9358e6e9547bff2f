"""Accuracy against speed: every (method, N) of the PSM and the FEM at its own cost.

Case: the r = 0.07 paper disk at three torques (0.1, 0.25, 0.5 N·m). Reference: the FEM on a
fine mesh (r / 24). The PSM stiffness scale is fitted once on that reference (at N = 60, started
from the N = 20 fit) and used by every method and N. Accuracy of a point = RMS over the torques
of the relative error of the jaw closing angle ``theta_a0 - theta`` against the reference; cost =
wall time per torque of a loading ramp through the three torques (``simulate_ramp``, median of
3 runs for Newton up to N = 80; for the baselines each torque is an independent solve from rest,
under a time limit). The answer a
method returns is scored even when it failed the independent KKT check (hollow markers); the
Pareto front (filled line) is computed over the points whose every solve passed it. The FEM
points are the coarser meshes (r / 4, r / 6, r / 12) against the r / 24 reference, with the cost
per torque of their ramp.

The model family's members are drawn beside them with their own scales, *not* refitted on this
reference: the paper's fan at s = 1, spring ring meshes with the hybrid scales derived from E and
nu, and constant-strain and nh-quad ring meshes (the default model is nh-quad 40 x 2) with their
shipped calibration (fitted on the three paper disks over 0.05-0.5 N·m; ``envs.model.family``).

MuJoCo's points (``scripts/peer_mujoco.py``: a 2-D flex per mesh size, wall time from rest to
rest per torque, scored against the same reference) are drawn when ``--mujoco`` names an
existing file (default ``out/peer_mujoco.json``; skipped when it is absent).
``--replot`` redraws the chart from an existing ``out/speed_accuracy.json`` without solving.

Writes ``out/speed_accuracy.png`` and ``out/speed_accuracy.json``.

Usage::

    python scripts/speed_accuracy.py [--out out] [--mujoco out/peer_mujoco.json] [--replot]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.accuracy import (  # noqa: E402
    calibrate,
    fem_reference,
    jsonable,
    pareto_front,
    psm_curve,
)
from envs.accuracy.members import Member  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate  # noqa: E402
from envs.solver.simulate import simulate_ramp  # noqa: E402

SCENE = "paper-r070"
TORQUES_NM = (0.1, 0.25, 0.5)
REF_RINGS = 24
FEM_RINGS = (4, 6, 12)
N_BY_METHOD = {
    "newton": (4, 6, 8, 10, 12, 16, 20, 24, 32, 40, 60, 80, 120, 160, 240),
    "slsqp": (4, 6, 8, 12, 16, 20, 24, 32, 40, 60),
    "nelder-mead": (4, 8),
}
TIME_LIMIT_S = {"newton": 30.0, "slsqp": 20.0, "nelder-mead": 10.0}
Y_CLIP = 300.0  # [%] errors above are drawn at the top of the chart
NEWTON_REPEATS = 3  # timing repeats (median) of the Newton ramps up to N = 80
STYLE = {"newton": ("tab:blue", "o"), "slsqp": ("tab:orange", "s"),
         "nelder-mead": ("tab:red", "D"), "fem": ("k", "P"),
         "fan s=1": ("0.45", "v"), "rings: springs": ("tab:cyan", "^"),
         "rings: cst": ("tab:brown", "*"),
         "rings: nh-quad (default 40 x 2)": ("tab:green", "h")}
FAMILY = (Member(20, 1), Member(40, 1), Member(20, 2, "hybrid"), Member(20, 3, "hybrid"),
          Member(24, 4, "hybrid"), Member(32, 6, "hybrid"), Member(20, 3, "calibrated", "cst"),
          Member(20, 4, "calibrated", "cst"), Member(24, 4, "calibrated", "cst"),
          Member(24, 6, "calibrated", "cst"), Member(32, 6, "calibrated", "cst"),
          Member(48, 8, "calibrated", "cst"), Member(32, 2, "calibrated", "nhquad"),
          Member(40, 2, "calibrated", "nhquad"), Member(48, 3, "calibrated", "nhquad"),
          Member(56, 4, "calibrated", "nhquad"), Member(80, 6, "calibrated", "nhquad"))


def _family_method(member: Member) -> str:
    if member.n_rings == 1:
        return "fan s=1"
    if member.element == "nhquad":
        return "rings: nh-quad (default 40 x 2)"
    return "rings: cst" if member.element == "cst" else "rings: springs"


def family_point(base: Scene, member: Member, ref_angles: np.ndarray) -> dict:
    """A member of the family at its own scales: error and wall time per torque of its ramp
    (median of 3)."""
    scene = member.scene(base)
    times, out = [], None
    for _ in range(3):
        t0 = time.perf_counter()
        out = simulate_ramp(scene, TORQUES_NM, member.n_triangles, n_rings=member.n_rings,
                            element=member.element, calibrated=False)
        times.append((time.perf_counter() - t0) / len(TORQUES_NM))
    angles = np.array([float(np.mean(g.jaw_angles_rad)) for g in out])
    rms, mx = _closing_error(base.gripper.rest_angle_rad, ref_angles, angles)
    failed = sum(not g.converged for g in out)
    return {"method": _family_method(member), "member": member.label,
            "n_triangles": member.n_triangles, "n_rings": member.n_rings,
            "time_per_torque_s": float(np.median(times)),
            "compiled_per_torque_s": float(np.mean([g.solve_time_s for g in out])),
            "rms_rel_error": rms, "max_rel_error": mx, "all_converged": failed == 0,
            "n_failed": failed}
MUJOCO_STYLE = ("tab:purple", "X")


def _closing_error(th0: float, ref_angles: np.ndarray, angles: np.ndarray) -> tuple[float, float]:
    rel = (th0 - angles) / (th0 - ref_angles) - 1.0
    return float(np.sqrt(np.mean(rel**2))), float(np.max(np.abs(rel)))


def mujoco_points(path: Path) -> list[dict]:
    """MuJoCo's points from ``scripts/peer_mujoco.py``'s JSON (empty when the file is absent)."""
    if not path.is_file():
        return []
    data = json.loads(path.read_text())
    return [{"method": "mujoco", "rings": m["rings"], "n_triangles": m.get("n_triangles"),
             "time_per_torque_s": m["time_per_torque_s"],
             "rms_rel_error": m["rms_rel_error"] if m["rms_rel_error"] is not None else math.nan,
             "all_converged": bool(m["all_ok"])}
            for m in data.get("meshes", []) if m.get("time_per_torque_s") is not None]


def draw_chart(points: list[dict], front: list[int], title: str, path: Path,
               peers: list[dict] = ()) -> None:
    """The chart: every point, the Pareto front (indices into ``points``) and peer points."""
    fig = Figure(figsize=(11, 5.5))
    ax = fig.add_subplot()
    styles = dict(STYLE, mujoco=MUJOCO_STYLE) if peers else STYLE
    every = list(points) + list(peers)
    for method, (col, mk) in styles.items():
        sel = [p for p in every if p["method"] == method]
        for p in sel:
            e = 100 * p["rms_rel_error"]
            y = min(max(e, 1e-3), Y_CLIP) if math.isfinite(e) else Y_CLIP
            ax.plot(p["time_per_torque_s"], y, mk, color=col,
                    mfc=col if p["all_converged"] else "none", ms=7)
            lab = (f"r/{p['rings']}" if method in ("fem", "mujoco")
                   else f"{p['n_triangles']}x{p['n_rings']}" if p.get("n_rings")
                   else str(p["n_triangles"]))
            if y >= Y_CLIP:
                lab += " (off scale)"
            ax.annotate(lab, (p["time_per_torque_s"], y), textcoords="offset points",
                        xytext=(4, 3), fontsize=6, color=col)
        label = {"fem": "FEM (vs r/24)",
                 "mujoco": "MuJoCo 2-D flex, to rest (labels: mesh r/rings)",
                 "newton": "fan, newton (scale fitted here)",
                 "fan s=1": "fan, paper's s = 1 (labels N x M)",
                 "rings: springs": "rings: springs + area, hybrid scales (no fit)",
                 "rings: cst": "rings: CST, shipped scale (fit on paper disks)",
                 }.get(method, method)
        ax.plot([], [], mk, color=col, label=label)
    fx = [points[i]["time_per_torque_s"] for i in front]
    fy = [100 * points[i]["rms_rel_error"] for i in front]
    ax.step(fx, fy, where="post", color="tab:green", lw=2, alpha=0.7, label="Pareto front")
    ax.plot([], [], "o", color="0.5", mfc="none", label="failed KKT check / time limit")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per torque [s]")
    ax.set_ylabel("jaw closing-angle error vs FEM r/24 [%] (RMS over 3 torques)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # outside: no point hidden
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _title(scale: float) -> str:
    return f"{SCENE}, T = {TORQUES_NM} N·m, PSM scale {scale:.3f} (labels: N)"


def replot(out: Path, mujoco_json: Path) -> int:
    """Redraw the chart from ``out/speed_accuracy.json`` (no solving)."""
    data = json.loads((out / "speed_accuracy.json").read_text())
    points = data["points"]
    for p in points:
        if p["rms_rel_error"] is None:
            p["rms_rel_error"] = math.nan
    front = [i for i, p in enumerate(points) if p.get("pareto")]
    front.sort(key=lambda i: points[i]["time_per_torque_s"])
    peers = mujoco_points(mujoco_json)
    draw_chart(points, front, _title(data["calibration"]["scale"]), out / "speed_accuracy.png",
               peers)
    print(f"redrew {out / 'speed_accuracy.png'} ({len(peers)} MuJoCo points)")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--mujoco", default=None,
                        help="peer_mujoco.py's JSON to add MuJoCo's points from (default: "
                        "OUT/peer_mujoco.json, if it exists)")
    parser.add_argument("--replot", action="store_true",
                        help="redraw from OUT/speed_accuracy.json without solving")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    mujoco_json = Path(args.mujoco) if args.mujoco else out / "peer_mujoco.json"
    if args.replot:
        return replot(out, mujoco_json)
    t_start = time.perf_counter()

    base = Scene.preset(SCENE)
    th0 = base.gripper.rest_angle_rad
    r = base.disk.radius_m
    ref = fem_reference(base, TORQUES_NM, mesh_size_m=r / REF_RINGS)
    if len(ref.torques_nm) != len(TORQUES_NM):
        raise RuntimeError(f"FEM reference failed at {ref.dropped_torques_nm}")
    ref_angles = np.asarray(ref.jaw_angles_rad)
    cal20 = calibrate(base, ref, 20, xatol=1e-3)
    cal = calibrate(cal20.calibrated(base), ref, 60, xatol=1e-3, step_factor=1.1,
                    grid_points=7)
    scene = cal.calibrated(base)
    simulate(scene, TORQUES_NM[0], 20, element="spring")  # compiled kernels loaded before timing
    print(f"{SCENE}: reference {ref.source} ({ref.solve_time_s / len(TORQUES_NM):.2f} s/torque),"
          f" PSM scale s = {cal.scale:.4f} fitted at N = 60")

    points = []
    for method, ns in N_BY_METHOD.items():
        for n in ns:
            reps = NEWTON_REPEATS if method == "newton" and n <= 80 else 1
            runs = [psm_curve(scene, TORQUES_NM, n, method, time_limit_s=TIME_LIMIT_S[method])
                    for _ in range(reps)]
            curve = runs[0]
            t_med = float(np.median([c.time_per_solve_s for c in runs]))
            angles = np.array([float(np.mean(g.jaw_angles_rad)) for g in curve.results])
            rms, mx = _closing_error(th0, ref_angles, angles)
            p = {"method": method, "n_triangles": n, "time_per_torque_s": t_med,
                 "rms_rel_error": rms, "max_rel_error": mx, "all_converged": curve.n_failed == 0,
                 "n_failed": curve.n_failed, "messages": curve.messages}
            points.append(p)
            print(f"{method:12s} N={n:4d}: {1e3 * p['time_per_torque_s']:9.2f} ms/torque, "
                  f"RMS {100 * rms:8.2f} %, max {100 * mx:8.2f} %"
                  f"{'' if p['all_converged'] else f'  ({curve.n_failed} not converged)'}")
    for member in FAMILY:
        p = family_point(base, member, ref_angles)
        points.append(p)
        print(f"{member.label:28s}: {1e3 * p['time_per_torque_s']:9.2f} ms/torque, RMS "
              f"{100 * p['rms_rel_error']:8.2f} %, max {100 * p['max_rel_error']:8.2f} %")
    for rings in FEM_RINGS:
        fr = fem_reference(base, TORQUES_NM, mesh_size_m=r / rings)
        ok = len(fr.torques_nm) == len(TORQUES_NM)
        angles = np.asarray(fr.jaw_angles_rad) if ok else np.full(len(TORQUES_NM), np.nan)
        rms, mx = _closing_error(th0, ref_angles, angles)
        p = {"method": "fem", "rings": rings, "n_triangles": None,
             "time_per_torque_s": fr.solve_time_s / len(TORQUES_NM), "rms_rel_error": rms,
             "max_rel_error": mx, "all_converged": ok, "n_failed": len(fr.dropped_torques_nm)}
        points.append(p)
        print(f"fem r/{rings:<3d}        : {1e3 * p['time_per_torque_s']:9.2f} ms/torque, "
              f"RMS {100 * rms:8.3f} %, max {100 * mx:8.3f} %")

    usable = [i for i, p in enumerate(points) if p["all_converged"]]
    front_local = pareto_front([points[i]["time_per_torque_s"] for i in usable],
                               [points[i]["rms_rel_error"] for i in usable])
    front = [usable[i] for i in front_local]
    for i in front:
        points[i]["pareto"] = True

    peers = mujoco_points(mujoco_json)
    draw_chart(points, front, _title(cal.scale), out / "speed_accuracy.png", peers)

    summary = {
        "scene": SCENE,
        "torques_nm": TORQUES_NM,
        "reference": ref,
        "calibration": cal,
        "points": points,
        "pareto_front": [points[i] for i in front],
        "mujoco_points": peers,
        "time_limits_s": TIME_LIMIT_S,
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "speed_accuracy.json").write_text(json.dumps(jsonable(summary), indent=1))
    print("Pareto front (time per torque, RMS error):")
    for i in front:
        p = points[i]
        lab = (f"fem r/{p['rings']}" if p["method"] == "fem"
               else p.get("member") or f"{p['method']} N={p['n_triangles']}")
        print(f"  {lab:16s} {1e3 * p['time_per_torque_s']:9.2f} ms  "
              f"{100 * p['rms_rel_error']:7.3f} %")
    print(f"wrote {out / 'speed_accuracy.png'} and .json in "
          f"{time.perf_counter() - t_start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
