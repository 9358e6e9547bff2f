"""Calibration study: one stiffness scale against scale + contour stiffness ratio (N = 20).

For each paper disk (``paper-r050``, ``paper-r070``, ``paper-r100``) the PSM with ``N = 20`` is
calibrated on the FEM jaw-angle curve over :data:`envs.accuracy.PAPER_TORQUES_NM`, with

* ``fit="scale"``: the stiffness scale ``s`` alone (the paper's single coefficient), and
* ``fit="scale_and_ratio"``: ``s`` and ``SoftDisk.contour_stiffness_ratio`` (separate radial and
  contour scales),

each with the area rule ``van_gelder`` and the Poisson-aware ``cst_fit`` rule. Every fit is
checked on cases not used in it (the paper's "fit once, reuse"): the held-out torques
:data:`envs.accuracy.HELDOUT_TORQUES_NM` of the same disk and the two other paper disks with the
same parameters (so the fit on ``paper-r070`` gives the cross-object transfer to r = 0.05 and
0.10). The error is the relative error of the jaw closing angle ``theta_a0 - theta``; the target
of the accuracy issue is 2 % at every torque.

It also records, per disk, the geometric offset of the inscribed 20-gon: between two contour
points the polygon lies ``r (1 - cos(pi / N))`` inside the circle, to be compared with the rest
gap between the disk and the finger faces (the frictionless fan can rotate about its pinned
centre, and it does, so that the faces meet it between two contour points). As a diagnostic of
that geometric error (not a calibration offered by the package), the scale-only fit is repeated
with a PSM disk of the same centre and the equal-area radius
``r sqrt((2 pi / N) / sin(2 pi / N))`` (a plain scene change, checked by the same KKT test).

Writes ``out/calibration.json`` and ``out/calibration.png``.

Usage::

    python scripts/calibration.py [--out out] [--rules van_gelder cst_fit]
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
    CALIBRATION_FITS,
    HELDOUT_TORQUES_NM,
    PAPER_SCENES,
    PAPER_TORQUES_NM,
    calibrate,
    fem_reference,
    jsonable,
    paper_heldout_cases,
)
from envs.model.defaults import STIFFNESS_RULES  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate  # noqa: E402

N_TRIANGLES = 20
TARGET = 0.02
TRANSFER_FROM = "paper-r070"


def rest_gap_m(scene: Scene) -> float:
    """Gap between the undeformed disk and each finger face at rest [m]."""
    g, d = scene.gripper, scene.disk
    n = np.array([-math.cos(g.rest_angle_rad), math.sin(g.rest_angle_rad)])
    joint = np.array([g.joint_offset_m, 0.0])
    return float(n @ (d.center_m - joint) - g.finger_width_m / 2 - d.radius_m)


def kkt_accepts_ratio() -> bool:
    """Whether the solver's independent KKT check accepts a grasp with a contour ratio != 1."""
    scene = Scene.preset(TRANSFER_FROM).with_changes(stiffness_scale=1.9,
                                                     contour_stiffness_ratio=2.0)
    res = simulate(scene, 0.2, N_TRIANGLES, element="spring")
    return bool(res.kkt is not None and res.kkt.passed)


def summarize(cal) -> dict:
    """Flat row of a calibration: parameters, fitted and held-out errors."""
    row = {
        "fit_mode": cal.fit_mode,
        "stiffness_rule": cal.stiffness_rule,
        "scale": cal.scale,
        "contour_stiffness_ratio": cal.contour_stiffness_ratio,
        "fit_rms_rel_error": cal.rms_rel_error,
        "fit_max_rel_error": cal.max_rel_error,
        "fit_n_failed": cal.fit.n_failed,
        "evaluations": cal.evaluations,
        "fit_time_s": cal.fit_time_s,
        "heldout": {},
    }
    for label, rep in cal.heldout.items():
        row["heldout"][label] = {"rms_rel_error": rep.rms_rel_error,
                                 "max_rel_error": rep.max_rel_error, "n_failed": rep.n_failed}
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--rules", nargs="+", default=list(STIFFNESS_RULES),
                        choices=STIFFNESS_RULES, help="stiffness rules to compare")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    kkt_ok = kkt_accepts_ratio()
    if not kkt_ok:
        print("WARNING: the KKT check rejects contour_stiffness_ratio != 1 (envs/check.py does not "
              "apply it yet): two-parameter fits will see failed solves")

    disks = {}
    cals = {}
    diagnostic = {}
    for name in PAPER_SCENES:
        scene = Scene.preset(name)
        fem = fem_reference(scene, PAPER_TORQUES_NM)
        cases = paper_heldout_cases(name)
        r = scene.disk.radius_m
        entry = {
            "radius_m": r,
            "rest_gap_m": rest_gap_m(scene),
            "polygon_recess_m": r * (1 - math.cos(math.pi / N_TRIANGLES)),
            "fem": fem,
            "fem_heldout_torques": cases[f"{name} held-out torques"][1],
            "calibrations": [],
        }
        for rule in args.rules:
            for fit in CALIBRATION_FITS:
                cal = calibrate(scene, fem, N_TRIANGLES, fit=fit, stiffness_rule=rule,
                                xatol=1e-5, heldout=cases)
                cals[(name, rule, fit)] = cal
                row = summarize(cal)
                row["calibration"] = cal
                entry["calibrations"].append(row)
                held = " | ".join(f"{k}: RMS {100 * v['rms_rel_error']:.2f} % max "
                                  f"{100 * v['max_rel_error']:.2f} %"
                                  for k, v in row["heldout"].items())
                print(f"{name} {rule:10s} {fit:15s} s = {cal.scale:.4f} "
                      f"rho_c = {cal.contour_stiffness_ratio:.4g}: fit RMS "
                      f"{100 * cal.rms_rel_error:.2f} % max {100 * cal.max_rel_error:.2f} % "
                      f"(failed {cal.fit.n_failed}, {cal.evaluations} ramps, "
                      f"{cal.fit_time_s:.0f} s) | {held}", flush=True)
        # diagnostic: the same scale-only fit with an equal-area polygon (same centre)
        rp = r * math.sqrt((2 * math.pi / N_TRIANGLES) / math.sin(2 * math.pi / N_TRIANGLES))
        psc = scene.with_changes(radius_m=rp, distance_m=scene.disk.distance_m + r - rp)
        own_held = cases[f"{name} held-out torques"][1]
        cal = calibrate(psc, fem, N_TRIANGLES, xatol=1e-5, heldout={"held-out torques":
                                                                    (psc, own_held)})
        diagnostic[name] = {"psm_radius_m": rp, **summarize(cal)}
        print(f"{name} diagnostic, equal-area radius {rp / r:.4f} r, scale only: s = "
              f"{cal.scale:.4f}, fit RMS {100 * cal.rms_rel_error:.2f} % max "
              f"{100 * cal.max_rel_error:.2f} %, held-out torques RMS "
              f"{100 * cal.heldout_rms_rel_error:.2f} % max "
              f"{100 * cal.heldout_max_rel_error:.2f} %", flush=True)
        disks[name] = entry

    # the 2 % target: every torque of the fit and of the same disk's held-out torques
    target = {}
    for (name, rule, fit), cal in cals.items():
        own = cal.heldout[f"{name} held-out torques"]
        worst = max(cal.max_rel_error, own.max_rel_error)
        target[f"{name} {rule} {fit}"] = {"worst_rel_error": worst, "met": bool(worst <= TARGET)}
    met_any = {
        f"{rule} {fit}": all(target[f"{n} {rule} {fit}"]["met"] for n in PAPER_SCENES)
        for rule in args.rules for fit in CALIBRATION_FITS
    }

    # figure: relative closing-angle error against torque, fitted (lines) and held-out (markers)
    fig = Figure(figsize=(13, 4.2))
    axes = fig.subplots(1, len(PAPER_SCENES), sharey=True)
    styles = {("van_gelder", "scale"): ("tab:blue", "-"),
              ("van_gelder", "scale_and_ratio"): ("tab:red", "-"),
              ("cst_fit", "scale"): ("tab:green", "--"),
              ("cst_fit", "scale_and_ratio"): ("tab:orange", "--")}
    for ax, name in zip(axes, PAPER_SCENES, strict=True):
        for rule in args.rules:
            for fit in CALIBRATION_FITS:
                cal = cals[(name, rule, fit)]
                colour, ls = styles[(rule, fit)]
                ax.plot(cal.fit.torques_nm, 100 * np.asarray(cal.fit.relative_errors, float),
                        ls, marker="o", ms=3, color=colour,
                        label=f"{rule}, {fit}: s = {cal.scale:.3f}, "
                              f"rho_c = {cal.contour_stiffness_ratio:.3g}")
                own = cal.heldout[f"{name} held-out torques"]
                ax.plot(own.torques_nm, 100 * np.asarray(own.relative_errors, float), "x",
                        color=colour, ms=5)
        ax.axhspan(-100 * TARGET, 100 * TARGET, color="0.9", zorder=0)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_title(f"{name} (N = {N_TRIANGLES}; x: held-out torques)", fontsize=9)
        ax.set_xlabel("actuation torque $T_a$ [N·m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6)
    axes[0].set_ylabel("closing-angle error PSM / FEM - 1 [%]")
    fig.tight_layout()
    fig.savefig(out / "calibration.png", dpi=120)

    summary = {
        "n_triangles": N_TRIANGLES,
        "torques_nm": PAPER_TORQUES_NM,
        "heldout_torques_nm": HELDOUT_TORQUES_NM,
        "target_rel_error": TARGET,
        "target_definition": "max |closing_psm / closing_fem - 1| over the fitted torques and "
                             "the same disk's held-out torques",
        "kkt_check_accepts_contour_ratio": kkt_ok,
        "transfer_fitted_on": TRANSFER_FROM,
        "target": target,
        "target_met_for_all_disks": met_any,
        "disks": disks,
        "diagnostic_equal_area_radius": diagnostic,
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "calibration.json").write_text(json.dumps(jsonable(summary), indent=1))
    print("target (2 % on fitted and held-out torques of each disk) met for all disks:", met_any)
    print(f"wrote {out / 'calibration.json'} and .png in {time.perf_counter() - t_start:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
