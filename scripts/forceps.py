"""Paper Figs. 9 and 10 (model side): the six forceps grasps and torque against jaw opening.

The forceps presets ``forceps-a`` ... ``forceps-f`` (paper Tables 3 and 4: TPU disks, s = 0.033,
rest angle 15 deg and k_f = 1e-3 N·m/rad chosen by the presets) are loaded along a torque ramp
with N = 20 (``simulate_ramp``). For each scene the drawn grasp is the first converged torque of
the ramp whose peak strain reaches 8 % (a visible squeeze); when the ramp never gets there
converged, the last converged torque is drawn and the title and JSON say so. Several of these
scenes press the finger tip corner into the disk, where the Newton solver often does not converge
yet; every failure is recorded, never hidden.

Fig. 10 (model side): the torque that actually loads the object, ``T_a - k_f (theta_a0 -
theta)`` (the finger spring's share subtracted, as in the paper; the reaction of the closed-jaw
stop is subtracted too, so a disk out of reach carries no torque), against the jaw opening angle
``theta_R + theta_L``, over the converged points of each ramp.

Writes ``out/forceps_grasps.png``, ``out/forceps_torque_opening.png`` and ``out/forceps.json``.

Usage::

    python scripts/forceps.py [--out out] [--n 20]
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

from envs.accuracy import jsonable, psm_curve  # noqa: E402
from envs.render import draw_grasp  # noqa: E402
from envs.scene import Scene  # noqa: E402

TAGS = "abcdef"
TORQUES_NM = tuple(np.round(np.linspace(0.00075, 0.03, 40), 8))
VISIBLE_STRAIN = 0.08


def _describe(res) -> str:
    """Short description of a converged grasp (contacts, tip corner, closed stop)."""
    parts = [f"contacts {res.n_contacts[0]}/{res.n_contacts[1]}"]
    if float(np.sum(res.corner_forces_n)) > 0:
        parts.append(f"corner force {float(np.sum(res.corner_forces_n[:, 0])):.2g} N")
    if float(np.max(np.abs(res.stop_torques_nm))) > 0:
        parts.append("jaws on the closed stop")
    return ", ".join(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--n", type=int, default=20, help="number of triangles")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    data = {}
    for tag in TAGS:
        name = f"forceps-{tag}"
        scene = Scene.preset(name)
        g = scene.gripper
        curve = psm_curve(scene, TORQUES_NM, args.n)
        conv = np.asarray(curve.converged)
        res = curve.results
        ok_idx = np.flatnonzero(conv)
        visible = [i for i in ok_idx if res[i].peak_strain >= VISIBLE_STRAIN]
        if visible:
            target = int(visible[0])
            drawn = target
            note = f"first converged torque with peak strain >= {VISIBLE_STRAIN:.0%}"
        else:
            target = len(TORQUES_NM) - 1
            below = [i for i in ok_idx if i <= target]
            drawn = int(below[-1]) if below else -1
            note = (f"no converged torque reaches {VISIBLE_STRAIN:.0%} peak strain; drawn: the "
                    "last converged torque of the ramp" if drawn >= 0
                    else "no torque of the ramp converged")
        opening = np.array([math.degrees(sum(r.jaw_angles_rad)) for r in res])
        theta = np.array([np.mean(r.jaw_angles_rad) for r in res])
        stop = np.array([float(np.mean(r.stop_torques_nm)) for r in res])
        net = (np.asarray(TORQUES_NM) - g.torsion_stiffness_nm_per_rad * (g.rest_angle_rad - theta)
               - stop)
        data[name] = {
            "scene": scene, "curve": curve, "drawn": drawn, "note": note,
            "opening_deg": opening, "net_torque_nm": net,
        }
        n_before = sum(1 for k in range(max(drawn, 0)) if not conv[k])
        if drawn >= 0 and n_before and "first converged" in note:
            note += f" ({n_before} smaller torques of the ramp did not converge)"
        data[name]["note"] = note
        first_fail = next((float(TORQUES_NM[i]) for i in range(len(conv)) if not conv[i]), None)
        desc = _describe(res[drawn]) if drawn >= 0 else "-"
        print(f"{name}: r = {1e3 * scene.disk.radius_m:.1f} mm, d1 = "
              f"{1e3 * scene.disk.distance_m:.0f} mm: {int(conv.sum())}/{len(conv)} torques "
              f"converged (first failure at T = {first_fail}), drawn T = "
              f"{TORQUES_NM[drawn] if drawn >= 0 else None} N·m ({note}); {desc}; "
              f"{curve.wall_time_s:.1f} s")

    # Fig. 9: the six grasps
    fig = Figure(figsize=(13, 9.5), layout="constrained")
    axes = fig.subplots(2, 3)
    for ax, (name, d) in zip(axes.ravel(), data.items(), strict=True):
        scene, res, i = d["scene"], d["curve"].results, d["drawn"]
        if i < 0:
            draw_grasp(ax, scene, None, title=f"{name}: no converged solve")
            continue
        r = res[i]
        conv = d["curve"].converged
        n_before = sum(1 for k in range(i) if not conv[k])
        if "first converged" in d["note"]:
            extra = f"\n({n_before} smaller torques not converged)" if n_before else ""
        else:
            extra = "\nlast converged torque; larger ones not converged"
        if float(np.max(np.abs(r.stop_torques_nm))) > 0 and not r.contact_mask.any():
            extra += "\njaws closed on the stop: the disk is beyond the tips"
        title = (f"{name}: T = {1e3 * TORQUES_NM[i]:.2f} mN·m, opening "
                 f"{d['opening_deg'][i]:.1f} deg,\npeak strain {r.peak_strain:.2f}{extra}")
        draw_grasp(ax, scene, r, title=title)
        c = scene.disk.center_m
        rr = scene.disk.radius_m
        ax.set_xlim(c[0] - 2.2 * rr, c[0] + 2.2 * rr)
        ax.set_ylim(c[1] - 2.2 * rr, c[1] + 2.0 * rr)
        ax.ticklabel_format(style="sci", scilimits=(-3, 3))
    fig.suptitle(f"Forceps grasps (PSM, N = {args.n}, s = 0.033, TPU E = 29 MPa)", fontsize=10)
    fig.savefig(out / "forceps_grasps.png", dpi=110)

    # Fig. 10, model side
    fig2 = Figure(figsize=(7.5, 5), layout="constrained")
    ax = fig2.add_subplot()
    for name, d in data.items():
        conv = np.asarray(d["curve"].converged)
        line, = ax.plot(d["opening_deg"][conv], 1e3 * d["net_torque_nm"][conv], "o-", ms=3,
                        label=f"{name} ({int(conv.sum())}/{len(conv)} converged)")
        i = d["drawn"]
        if i >= 0:
            ax.plot(d["opening_deg"][i], 1e3 * d["net_torque_nm"][i], "*", ms=13,
                    color=line.get_color(), mec="k")
    ax.set_xlabel("jaw opening angle $\\theta_R + \\theta_L$ [deg]")
    ax.set_ylabel("torque on the object $T_a - k_f(\\theta_{a0}-\\theta)$ - stop [mN·m]")
    ax.set_title("model torque vs jaw opening (converged points; star: grasp drawn in Fig. 9)",
                 fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig2.savefig(out / "forceps_torque_opening.png", dpi=120)

    summary = {
        "n_triangles": args.n,
        "torques_nm": TORQUES_NM,
        "visible_strain": VISIBLE_STRAIN,
        "scenes": {
            name: {
                "radius_m": d["scene"].disk.radius_m,
                "distance_m": d["scene"].disk.distance_m,
                "stiffness_scale": d["scene"].disk.stiffness_scale,
                "converged": d["curve"].converged,
                "messages": d["curve"].messages,
                "jaw_opening_deg": d["opening_deg"],
                "net_torque_nm": d["net_torque_nm"],
                "peak_strain": [r.peak_strain for r in d["curve"].results],
                "drawn_index": d["drawn"],
                "drawn_torque_nm": TORQUES_NM[d["drawn"]] if d["drawn"] >= 0 else None,
                "drawn_description": _describe(d["curve"].results[d["drawn"]])
                if d["drawn"] >= 0 else None,
                "note": d["note"],
                "wall_time_s": d["curve"].wall_time_s,
            }
            for name, d in data.items()
        },
        "wall_time_s": time.perf_counter() - t_start,
    }
    (out / "forceps.json").write_text(json.dumps(jsonable(summary), indent=1))
    print(f"wrote {out / 'forceps_grasps.png'}, forceps_torque_opening.png and forceps.json in "
          f"{time.perf_counter() - t_start:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
