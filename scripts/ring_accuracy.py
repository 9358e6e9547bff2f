"""Accuracy and cost of the model family's ring meshes against the FEM reference.

For members of the family (:data:`envs.accuracy.members.DEFAULT_MEMBERS` and a few more: the
paper's fan with s = 1, spring ring meshes with the physics-derived hybrid scales of
:func:`envs.model.family.hybrid_scales` (no fit), constant-strain ring meshes with their
shipped scale :data:`envs.model.family.CST_SCALES` (fitted on the paper disks only)), ramps
each disk through :data:`envs.accuracy.PAPER_TORQUES_NM` and prints the closing-angle
error ``(theta_a0 - theta)_PSM / (theta_a0 - theta)_FEM - 1`` (RMS, mean, max) on the three
paper disks and on held-out disks (other radii, moduli and Poisson ratios), beside the compiled
solve time per torque and the wall time a user sees. The issue's targets: 2 % RMS and 4 % max
on held-out disks at <= 1 ms compiled per torque. Beside the angle, the peak deformation the
reward uses: the largest principal log strain per triangle outside twice the hub radius against
the FEM's same measure (relative error, RMS over the torques), and the contact measure: the
fraction of the contour in contact (contour points for the PSM, rim nodes for the FEM).

Writes ``out/ring_accuracy.json``.

``--aspect-sweep`` instead measures where spring ring meshes stop being a model of the
material: the hybrid spring members for M = 2-8 rings and N = 8-500 contour points on paper-r070
and -r050 (the bound :data:`envs.model.defaults.MAX_SPRING_CELL_ASPECT` lifted for this run
only), their RMS closing-angle error against cell aspect; writes ``out/spring_aspect.json``
(about two minutes once the FEM references are cached).

Usage::

    python scripts/ring_accuracy.py [--out out] [--quick | --aspect-sweep]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.accuracy import PAPER_SCENES, PAPER_TORQUES_NM, fem_reference  # noqa: E402
from envs.accuracy.heldout import heldout_scenes  # noqa: E402
from envs.accuracy.members import DEFAULT_MEMBERS, Member  # noqa: E402
from envs.model import family  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver.simulate import simulate_ramp  # noqa: E402

MEMBERS = DEFAULT_MEMBERS + (Member(32, 4, "hybrid"), Member(32, 6, "hybrid"),
                             Member(24, 6, "calibrated", "cst"))
QUICK_MEMBERS = (Member(20, 1), Member(20, 3, "hybrid"), Member(20, 3, "calibrated", "cst"))


def fem_measures(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The FEM's peak log strain, contact fraction and peak compression at the paper torques
    (its disk cache)."""
    from envs.fem import fem_grasp
    from envs.fem.designs import fem_metrics

    results = fem_grasp(scene.with_changes(stiffness_scale=1.0), list(PAPER_TORQUES_NM))
    # rim nodes of the P2 mesh: 6 k^2 elements on k rings, 6 k rim edges, two nodes each
    rings = round((results[0].n_elements / 6) ** 0.5)
    rim_nodes = 2 * 6 * rings
    strain = np.array([r.peak_strain if r.converged else np.nan for r in results])
    contact = np.array([sum(r.contact_node_counts) / rim_nodes for r in results])
    r = scene.disk.radius_m
    compression = fem_metrics(results, r, scene.disk.distance_m + r)["peak_compression"]
    return strain, contact, compression


def member_errors(scene: Scene, ref, member: Member, fem=None) -> dict:
    """Closing-angle errors and times of one member on one disk (with the FEM's peak strain
    and contact fraction ``fem``, their errors too)."""
    t0 = time.perf_counter()
    out = simulate_ramp(member.scene(scene), list(ref.torques_nm), member.n_triangles,
                        n_rings=member.n_rings, element=member.element,
                        calibrated=False)
    wall = time.perf_counter() - t0
    th0 = scene.gripper.rest_angle_rad
    fem_closing = th0 - np.asarray(ref.jaw_angles_rad)
    psm = th0 - np.array([np.mean(r.jaw_angles_rad) for r in out])
    err = psm / fem_closing - 1.0
    extra = {}
    if fem is not None:
        strain = np.array([r.peak_log_strain for r in out])
        contact = np.array([sum(r.n_contacts) / member.n_triangles for r in out])
        s_err = strain / fem[0] - 1.0
        compression = np.array([r.peak_compression for r in out])
        c_err = compression / fem[2] - 1.0
        extra = {"peak_log_strain": strain.tolist(), "fem_peak_log_strain": fem[0].tolist(),
                 "strain_rms": float(np.sqrt(np.nanmean(s_err**2))),
                 "peak_compression": compression.tolist(),
                 "fem_peak_compression": fem[2].tolist(),
                 "compression_rms": float(np.sqrt(np.nanmean(c_err**2))),
                 "contact_fraction": contact.tolist(), "fem_contact_fraction": fem[1].tolist()}
    return extra | {
        "converged": int(sum(r.converged for r in out)), "torques": len(out),
        "rms": float(np.sqrt(np.mean(err**2))), "mean": float(np.mean(err)),
        "max": float(np.max(np.abs(err))), "errors": err.tolist(),
        "compiled_ms_per_torque": 1e3 * float(np.mean([r.solve_time_s for r in out])),
        "wall_ms_per_torque": 1e3 * wall / len(out),
    }


ASPECT_SCENES = ("paper-r070", "paper-r050")
ASPECT_RINGS = (2, 3, 4, 6, 8)
ASPECT_NS = (8, 12, 16, 20, 24, 32, 40, 64, 100, 200, 500)


def aspect_sweep(out: Path) -> None:
    """RMS closing-angle error of the hybrid spring ring members against their cell aspect
    (:func:`envs.model.family.spring_cell_aspect`), beyond the accepted range too."""
    bound = family.MAX_SPRING_CELL_ASPECT
    family.MAX_SPRING_CELL_ASPECT = float("inf")  # measure past the bound, this process only
    rows = []
    try:
        for name in ASPECT_SCENES:
            scene = Scene.preset(name)
            ref = fem_reference(scene, PAPER_TORQUES_NM)
            for m in ASPECT_RINGS:
                for n in ASPECT_NS:
                    if m >= 6 and n > 200:
                        continue  # minutes a ramp, and the trend is clear by N = 200
                    res = member_errors(scene, ref, Member(n, m, "hybrid"))
                    aspect = family.spring_cell_aspect(n, m)
                    rows.append({"scene": name, "n_triangles": n, "n_rings": m,
                                 "aspect": aspect, "accepted": 1 / bound <= aspect <= bound}
                                | {k: res[k] for k in ("rms", "mean", "max", "converged",
                                                       "torques", "compiled_ms_per_torque")})
                    print(f"{name} M={m} N={n:4d} aspect {aspect:6.2f}: RMS "
                          f"{100 * res['rms']:5.2f} %, mean {100 * res['mean']:6.2f} %, max "
                          f"{100 * res['max']:5.2f} %, converged {res['converged']}/"
                          f"{res['torques']}", flush=True)
    finally:
        family.MAX_SPRING_CELL_ASPECT = bound
    for accepted in (True, False):
        sel = [r["rms"] for r in rows if r["accepted"] == accepted and r["n_triangles"] >= 20]
        print(f"N >= 20, aspect {'within' if accepted else 'outside'} "
              f"[{1 / bound:.1f}, {bound:.1f}]: RMS {100 * min(sel):.1f}-{100 * max(sel):.1f} %, "
              f"median {100 * float(np.median(sel)):.1f} % ({len(sel)} members x disks)")
    (out / "spring_aspect.json").write_text(json.dumps({
        "torques_nm": list(PAPER_TORQUES_NM), "max_spring_cell_aspect": bound, "rows": rows},
        indent=1))
    print(f"wrote {out / 'spring_aspect.json'}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--quick", action="store_true", help="three members (smoke test)")
    parser.add_argument("--aspect-sweep", action="store_true",
                        help="spring ring members' error against their cell aspect")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.aspect_sweep:
        aspect_sweep(out)
        return 0
    scenes = {name: Scene.preset(name) for name in PAPER_SCENES} | heldout_scenes()
    refs = {}
    for name, scene in scenes.items():
        t0 = time.perf_counter()
        refs[name] = fem_reference(scene, PAPER_TORQUES_NM)
        print(f"FEM {name}: {time.perf_counter() - t0:.1f} s", flush=True)
    # compile outside the timings
    for element in ("spring", "cst"):
        simulate_ramp(scenes["paper-r070"], [0.1], 20, n_rings=2, element=element)
    fem = {name: fem_measures(scenes[name]) for name in PAPER_SCENES}
    rows = []
    for member in QUICK_MEMBERS if args.quick else MEMBERS:
        per = {name: member_errors(scene, refs[name], member, fem.get(name))
               for name, scene in scenes.items()}
        held = [v for k, v in per.items() if k not in PAPER_SCENES]
        row = {
            "member": member.label, "n_triangles": member.n_triangles,
            "n_rings": member.n_rings, "element": member.element, "scales": member.scales,
            "paper_rms_max": max(per[k]["rms"] for k in PAPER_SCENES),
            "paper_max": max(per[k]["max"] for k in PAPER_SCENES),
            "heldout_rms_max": max(v["rms"] for v in held),
            "heldout_max": max(v["max"] for v in held),
            "compiled_ms_per_torque": float(np.mean([v["compiled_ms_per_torque"]
                                                     for v in per.values()])),
            "wall_ms_per_torque": float(np.mean([v["wall_ms_per_torque"]
                                                 for v in per.values()])),
            "all_converged": all(v["converged"] == v["torques"] for v in per.values()),
            "disks": per,
        }
        rows.append(row)
        print(f"{member.label:28s}: paper RMS <= {100 * row['paper_rms_max']:5.1f} % "
              f"(max {100 * row['paper_max']:5.1f} %), held-out RMS <= "
              f"{100 * row['heldout_rms_max']:5.1f} % (max {100 * row['heldout_max']:5.1f} %), "
              f"{row['compiled_ms_per_torque']:6.2f} ms compiled / "
              f"{row['wall_ms_per_torque']:6.2f} ms wall per torque, "
              f"all converged: {row['all_converged']}", flush=True)
        print("    peak compression (the reward's deformation) and peak log strain vs FEM "
              "(RMS of the relative error): " + ", ".join(
                  f"{k[-4:]} {100 * per[k]['compression_rms']:.1f} % / "
                  f"{100 * per[k]['strain_rms']:.0f} %" for k in PAPER_SCENES)
            + "; contour fraction in contact at 0.5 N·m, PSM/FEM: " + ", ".join(
                f"{k[-4:]} {per[k]['contact_fraction'][-1]:.2f}/"
                f"{per[k]['fem_contact_fraction'][-1]:.2f}" for k in PAPER_SCENES), flush=True)
        worst = max(per, key=lambda k: per[k]["max"])
        print(f"    worst disk {worst}: errors by torque "
              f"{np.round(100 * np.asarray(per[worst]['errors']), 1).tolist()} %", flush=True)
    (out / "ring_accuracy.json").write_text(json.dumps({
        "torques_nm": list(PAPER_TORQUES_NM),
        "targets": {"heldout_rms": 0.02, "heldout_max": 0.04, "compiled_ms_per_torque": 1.0},
        "fem": {k: {"source": v.source, "solve_time_s": v.solve_time_s,
                    "torques": len(v.torques_nm)} for k, v in refs.items()},
        "members": rows,
    }, indent=1))
    print(f"wrote {out / 'ring_accuracy.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
