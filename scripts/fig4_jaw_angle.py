"""Paper Fig. 4: jaw angle against torque, FEM against the PSM with N = 4, 12 and 20.

The PSM stiffness scale is calibrated on the FEM grasp of the r = 0.07 disk (``paper-r070``) over
the torque ramp :data:`envs.accuracy.PAPER_TORQUES_NM`, once with a fine PSM (``N = 60``, the
paper's procedure: calibrate with many elements, then coarsen) and once at ``N = 20``. The
calibrated models are then checked on cases not used in the fit: the held-out torques
:data:`envs.accuracy.HELDOUT_TORQUES_NM` (midpoints and two extrapolated torques) of the same
disk, and the two other paper disks (r = 0.05 and 0.10) with the scale fitted on r = 0.07.
Members of the model family (:data:`FAMILY`, ring meshes with the nh-quad element and their
shipped calibration, not refitted here) are drawn beside the fan.

Writes ``out/fig4_jaw_angle.png`` and ``out/fig4_jaw_angle.json``.

Usage::

    python scripts/fig4_jaw_angle.py [--out out]
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
    HELDOUT_TORQUES_NM,
    PAPER_TORQUES_NM,
    calibrate,
    closing_errors,
    fem_reference,
    jsonable,
    psm_curve,
)
from envs.accuracy.members import Member  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver import simulate_ramp  # noqa: E402

SCENE = "paper-r070"
OTHER_SCENES = ("paper-r050", "paper-r100")
N_PLOT = (4, 12, 20)
N_CAL_FINE = 60
DENSE_TORQUES_NM = tuple(np.round(np.linspace(0.0125, 0.75, 60), 10))
COLOURS = {4: "tab:red", 12: "tab:green", 20: "tab:blue"}
# members of the model family drawn beside the fan, with their shipped calibration (not refitted)
FAMILY = (Member(40, 2, "calibrated", "nhquad"), Member(48, 3, "calibrated", "nhquad"))
FAMILY_COLOURS = ("tab:purple", "tab:brown")


def family_curve(member: Member, scene: Scene, torques) -> dict:
    """Closing curve of a family member along a ramp (NaN where a step did not converge)."""
    res = simulate_ramp(member.scene(scene), sorted(torques), member.n_triangles,
                        n_rings=member.n_rings, element=member.element,
                        calibrated=False)
    ok = np.array([r.converged for r in res])
    angles = np.array([0.5 * sum(r.jaw_angles_rad) for r in res])
    return {"label": member.label, "torques_nm": np.array(sorted(torques)),
            "jaw_angles_rad": np.where(ok, angles, np.nan), "converged": ok}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    scene = Scene.preset(SCENE)
    th0 = scene.gripper.rest_angle_rad
    fem = fem_reference(scene, PAPER_TORQUES_NM)
    fem_held = fem_reference(scene, HELDOUT_TORQUES_NM)
    print(f"FEM {SCENE}: {len(fem.torques_nm)} torques ({fem.source}), "
          f"solve time {fem.solve_time_s:.1f} s (cached or not)")

    cal_fine = calibrate(scene, fem, N_CAL_FINE, xatol=1e-5)
    cal = {n: calibrate(scene, fem, n, xatol=1e-5) for n in N_PLOT}
    print(f"calibrated scale at N={N_CAL_FINE}: s = {cal_fine.scale:.4f} "
          f"(fit RMS {100 * cal_fine.rms_rel_error:.2f} %, "
          f"max {100 * cal_fine.max_rel_error:.2f} %, {cal_fine.fit.n_failed} failed solves)")

    curves = {}
    rows = []
    for n in N_PLOT:
        fixed = closing_errors(cal_fine.calibrated(scene), fem, n)
        own = cal[n].fit
        dense = psm_curve(cal_fine.calibrated(scene), DENSE_TORQUES_NM, n)
        curves[n] = dense
        rows.append({
            "n_triangles": n,
            "scale_fitted_at_n": cal[n].scale,
            "fixed_scale": {"rms_rel_error": fixed.rms_rel_error,
                            "max_rel_error": fixed.max_rel_error, "n_failed": fixed.n_failed,
                            "relative_errors": fixed.relative_errors},
            "own_scale": {"rms_rel_error": own.rms_rel_error, "max_rel_error": own.max_rel_error,
                          "n_failed": own.n_failed, "relative_errors": own.relative_errors},
        })
        print(f"N={n:3d}: scale fitted at N={N_CAL_FINE}: RMS {100 * fixed.rms_rel_error:6.2f} %,"
              f" max {100 * fixed.max_rel_error:6.2f} % | scale fitted at N={n} "
              f"(s = {cal[n].scale:.4f}): RMS {100 * own.rms_rel_error:6.2f} %, "
              f"max {100 * own.max_rel_error:6.2f} %")

    # held-out cases: other torques on the same disk, other disks with the r = 0.07 scale
    held = {}
    for label, c in (("N20_fit", cal[20]), (f"N{N_CAL_FINE}_fit", cal_fine)):
        entry = {"scale": c.scale, "n_triangles": c.n_triangles}
        rep = c.errors_on(scene, fem_held)
        entry["heldout_torques_same_disk"] = rep
        print(f"held-out torques on {SCENE} ({label}, s = {c.scale:.4f}, N = {c.n_triangles}): "
              f"RMS {100 * rep.rms_rel_error:.2f} %, max {100 * rep.max_rel_error:.2f} %")
        for other in OTHER_SCENES:
            osc = Scene.preset(other)
            rep = c.errors_on(osc, fem_reference(osc, PAPER_TORQUES_NM))
            entry[f"other_disk_{other}"] = rep
            print(f"  other disk {other}: RMS {100 * rep.rms_rel_error:.2f} %, "
                  f"max {100 * rep.max_rel_error:.2f} %, failed {rep.n_failed}")
        held[label] = entry

    family = {}
    for member in FAMILY:
        on_fem = family_curve(member, scene, fem.torques_nm)
        closing_fem = th0 - np.asarray(fem.jaw_angles_rad)
        rel = (th0 - on_fem["jaw_angles_rad"]) / closing_fem - 1.0
        family[member.label] = {"dense": family_curve(member, scene, DENSE_TORQUES_NM),
                                "relative_errors": rel,
                                "rms_rel_error": float(np.sqrt(np.nanmean(rel ** 2))),
                                "max_rel_error": float(np.nanmax(np.abs(rel)))}
        print(f"{member.label} (shipped calibration): RMS "
              f"{100 * family[member.label]['rms_rel_error']:.2f} %, max "
              f"{100 * family[member.label]['max_rel_error']:.2f} %")

    # figure: jaw angle between the fingers and the relative closing-angle error
    fig = Figure(figsize=(11, 4.6))
    ax, ax2 = fig.subplots(1, 2)
    ft = np.asarray(fem.torques_nm)
    ax.plot(ft, np.degrees(2 * np.asarray(fem.jaw_angles_rad)), "ko-", lw=2, ms=5,
            label=f"FEM ({fem.source})")
    fh = np.asarray(fem_held.torques_nm)
    ax.plot(fh, np.degrees(2 * np.asarray(fem_held.jaw_angles_rad)), "ks", mfc="none", ms=5,
            label="FEM, held-out torques")
    for n in N_PLOT:
        d = curves[n]
        ok = np.asarray(d.converged)
        tq = np.asarray(d.torques_nm)
        ang = np.degrees(2 * np.asarray(d.jaw_angles_rad))
        ax.plot(tq[ok], ang[ok], "-", color=COLOURS[n], label=f"PSM N = {n}")
        if (~ok).any():
            # mark the failed torques on the FEM curve
            fem_deg = np.degrees(2 * np.interp(tq[~ok], np.r_[ft, fh[fh > ft[-1]]],
                                               np.r_[fem.jaw_angles_rad,
                                                     np.asarray(fem_held.jaw_angles_rad)[
                                                         fh > ft[-1]]]))
            ax.plot(tq[~ok], fem_deg, "x", color=COLOURS[n], ms=8, mew=2,
                    label=f"N = {n}: not converged")
        fixed = closing_errors(cal_fine.calibrated(scene), fem, n)
        ax2.plot(ft, 100 * np.asarray(fixed.relative_errors), "o-", color=COLOURS[n],
                 label=f"N = {n}, s fitted at N = {N_CAL_FINE}")
        ax2.plot(ft, 100 * np.asarray(cal[n].fit.relative_errors), "s--", color=COLOURS[n],
                 mfc="none", label=f"N = {n}, s fitted at N = {n}")
    for (label, fam), col in zip(family.items(), FAMILY_COLOURS, strict=False):
        d = fam["dense"]
        ax.plot(d["torques_nm"], np.degrees(2 * d["jaw_angles_rad"]), "-", color=col, lw=1.5,
                label=f"family {label}")
        ax2.plot(ft, 100 * fam["relative_errors"], "v-", color=col,
                 label=f"{label} (shipped calibration)")
    ax.set_xlabel("actuation torque $T_a$ [N·m]")
    ax.set_ylabel("angle between the fingers [deg]")
    ax.set_title(f"{SCENE}: PSM with s = {cal_fine.scale:.3f} (fitted at N = {N_CAL_FINE})",
                 fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax2.set_yscale("symlog", linthresh=5.0)
    ax2.axhline(0, color="k", lw=0.8)
    ax2.axhspan(-2, 2, color="0.9", zorder=0, label="±2 %")
    ax2.set_xlabel("actuation torque $T_a$ [N·m]")
    ax2.set_ylabel("closing-angle error PSM / FEM - 1 [%] (symlog)")
    ax2.set_title("relative error of the jaw closing angle $\\theta_{a0}-\\theta$", fontsize=9)
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "fig4_jaw_angle.png", dpi=120)

    summary = {
        "scene": SCENE,
        "rest_angle_rad": th0,
        "fem": fem,
        "fem_heldout": fem_held,
        "calibration_fine": cal_fine,
        "calibration_per_n": {str(n): cal[n] for n in N_PLOT},
        "errors": rows,
        "heldout": held,
        "family": family,
        "dense_curves": {str(n): {"torques_nm": curves[n].torques_nm,
                                  "jaw_angles_rad": curves[n].jaw_angles_rad,
                                  "converged": curves[n].converged} for n in N_PLOT},
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "fig4_jaw_angle.json").write_text(json.dumps(jsonable(summary), indent=1))
    print(f"wrote {out / 'fig4_jaw_angle.png'} and .json in "
          f"{time.perf_counter() - t_start:.1f} s")
    return 0 if math.isfinite(cal_fine.scale) else 1


if __name__ == "__main__":
    raise SystemExit(main())
