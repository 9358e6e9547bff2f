"""How accurate the point-spring model is on objects that are not disks: PSM against FEM.

Nothing here was fitted to an outline: the default model (nh-quad, N = 40, M = 2, its scale
fitted on the paper disks) is compared with the finite-element reference (the disk mesh mapped
onto the outline, :mod:`envs.fem`) on held-out outlines:

1. **Closing angle** (``--angles``; the default model and the 96 x 6 member):
   ellipses 1.5:1, 2:1 and 3:1, a rounded rectangle
   (5:3, corners half the short side) and the two measured outlines of ``examples/objects``
   (a rounded package and an irregular slice), each at orientations 0, 45 and 90 degrees, at
   the paper disks' equivalent radius 70 mm and material (E 100 kPa, nu 0.45, t 10 mm), on the
   paper's gripper placed with the paper disk's rest clearance, over the calibration torques
   0.05-0.5 N.m. The error is the calibration's: the relative error of the closing angle
   ``theta_a0 - theta`` (mean of the two fingers), RMS and largest over the torques.
2. **Reward ranking** (``--ranking``): ``--designs`` random designs of the default design box
   on three objects (the issue's ellipse 2:1, 20 x 10 mm, 0.2 MPa, t 20 mm, across and along the
   jaws, and the irregular slice), scored by :func:`envs.evaluate.evaluate_designs` at both
   fidelities (the default model and the 96 x 6 member that ranks and reports optima): the
   Spearman rank correlation of the rewards (valid designs converged at both), the best
   design's FEM rank and the reward error.

Writes ``out/outline_accuracy.json``, ``out/outline_accuracy.png`` (closing angles) and
``out/outline_ranking.png`` (reward ranking).

Usage::

    python scripts/outline_accuracy.py [--angles] [--ranking] [--designs 40] [--workers 2]
                                       [--quick]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from fidelity import rank_agreement  # noqa: E402

from envs.accuracy.paper import PAPER_TORQUES_NM  # noqa: E402
from envs.accuracy.reference import fem_reference  # noqa: E402
from envs.evaluate import DesignBounds, evaluate_designs  # noqa: E402
from envs.object_file import load_object  # noqa: E402
from envs.objects import Ellipse, RoundedRectangle, as_object  # noqa: E402
from envs.scene import (  # noqa: E402
    Scene,
    design_from_relative,
    placement_support,
    relative_from_design,
)
from envs.solver import simulate_ramp  # noqa: E402

EXAMPLES = ROOT / "examples" / "objects"
ORIENTATIONS_DEG = (0.0, 45.0, 90.0)
# the members compared: the default model and the finer one that reports optima
MEMBERS = {"default": {}, "96x6": {"n_triangles": 96, "n_rings": 6}}
# every case is solved turned by this much [rad], which breaks an exactly symmetric scene's
# symmetry (see closing_case)
PERTURB_RAD = 1e-3


def outlines() -> dict:
    """The held-out outlines of part 1, dimensionless (scaled to the paper disk's r_eq)."""
    return {
        "ellipse 1.5:1": Ellipse(1.5),
        "ellipse 2:1": Ellipse(2.0),
        "ellipse 3:1": Ellipse(3.0),
        "rounded rectangle 5:3": RoundedRectangle(5.0 / 3.0, 0.5),
        "measured package": load_object(EXAMPLES / "soft_package.toml").disk.outline,
        "measured slice": load_object(EXAMPLES / "pebble_slice.toml").disk.outline,
    }


def paper_scene(outline, orientation_deg: float) -> Scene:
    """The paper gripper with an outline of the paper disk's area and material, placed with
    the paper disk's rest clearance (its faces clear the outline as they clear the disk)."""
    paper = Scene.preset("paper-r070")
    g, d = paper.gripper, paper.disk
    row = np.array([g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m,
                    0.0, d.distance_m])
    rel = relative_from_design(row, d.radius_m, d.torque_unit_nm)
    obj = as_object(d, outline, math.radians(orientation_deg))
    placed = design_from_relative(rel, obj.radius_m, obj.torque_unit_nm,
                                  placement_support(obj))
    return Scene(g, replace(obj, distance_m=float(placed[5])))


def closing_case(scene: Scene, members: dict) -> dict:
    """The model members' closing angles against the FEM's over the calibration torques.

    Both on the scene turned by :data:`PERTURB_RAD`: an elongated outline squeezed
    symmetrically may buckle into a turned grasp past a bifurcation (the symmetric answer is
    then unstable); the point-spring ramp finds the stable grasp by itself, the FEM's Newton
    ramp keeps an exactly symmetric scene symmetric. The symmetric FEM answer is recorded
    beside it (``fem_symmetric_closing_rad``).
    """
    turned = Scene(scene.gripper, replace(scene.disk, orientation_rad=scene.disk.orientation_rad
                                          + PERTURB_RAD))
    t0 = time.perf_counter()
    ref = fem_reference(turned, PAPER_TORQUES_NM)
    fem_s = time.perf_counter() - t0
    symmetric = fem_reference(scene, PAPER_TORQUES_NM)
    th0 = scene.gripper.rest_angle_rad
    out = {"torques_nm": list(ref.torques_nm), "fem_closing_rad": [
        th0 - a for a in ref.jaw_angles_rad], "fem_s": fem_s,
        "fem_dropped": list(ref.dropped_torques_nm),
        "fem_symmetric_closing_rad": [th0 - a for a in symmetric.jaw_angles_rad]}
    for label, kw in members.items():
        out[label] = _member_errors(turned, ref, kw)
    return out


def _member_errors(scene: Scene, ref, kw: dict) -> dict:
    """A member's closing angles along the reference's torques and its relative errors."""
    torques = np.array(ref.torques_nm)
    ramp = simulate_ramp(scene, torques, **kw)
    th0 = scene.gripper.rest_angle_rad
    fem = th0 - np.array(ref.jaw_angles_rad)
    psm = np.array([th0 - np.mean(r.jaw_angles_rad) if r.converged else math.nan
                    for r in ramp])
    rel = psm / fem - 1.0
    ok = np.isfinite(rel)
    return {"psm_closing_rad": psm.tolist(), "relative_errors": rel.tolist(),
            "rms": float(np.sqrt(np.mean(rel[ok] ** 2))) if ok.any() else math.nan,
            "max": float(np.max(np.abs(rel[ok]))) if ok.any() else math.nan,
            "psm_failed": int((~ok).sum())}


def mesh_convergence(rings=(12, 18, 24), torque_nm: float = 0.3) -> dict:
    """The FEM reference itself on finer meshes: the closing angle at ``torque_nm`` of the 3:1
    ellipse across the jaws (its pointed ends against the faces) and the 2:1 ellipse at 45
    degrees (turned about its hub), each turned by :data:`PERTURB_RAD`."""
    from envs.fem import fem_grasp

    out = {}
    for name, shape, deg in (("ellipse 3:1, 0 deg", Ellipse(3.0), 0.0),
                             ("ellipse 2:1, 45 deg", Ellipse(2.0), 45.0)):
        scene = paper_scene(shape, deg + math.degrees(PERTURB_RAD))
        th0 = scene.gripper.rest_angle_rad
        closing = {}
        for m in rings:
            res = fem_grasp(scene, [0.05, 0.1, 0.2, torque_nm],
                            mesh_size_m=scene.disk.radius_m / m)
            closing[str(m)] = (th0 - float(np.mean(res[-1].jaw_angles_rad))
                               if res[-1].converged else math.nan)
        finest = closing[str(rings[-1])]
        print(f"FEM mesh convergence, {name} at {torque_nm:g} N.m: " + ", ".join(
            f"{m} rings {100 * (v / finest - 1):+.2f} %" for m, v in closing.items()),
            flush=True)
        out[name] = closing
    return {"torque_nm": torque_nm, "closing_rad_by_rings": out}


def run_angles(quick: bool) -> dict:
    cases = {}
    shapes = outlines()
    members = dict(MEMBERS)
    if quick:
        shapes = {k: shapes[k] for k in ("ellipse 2:1", "measured slice")}
        members = {"default": {}}
    for name, shape in shapes.items():
        for deg in (ORIENTATIONS_DEG[::2] if quick else ORIENTATIONS_DEG):
            label = f"{name}, {deg:g} deg"
            entry = closing_case(paper_scene(shape, deg), members)
            cases[label] = entry
            sym = np.array(entry["fem_symmetric_closing_rad"])
            ref = np.array(entry["fem_closing_rad"])
            split = " (the symmetric FEM answer is unstable: turned grasp)" if (
                sym.size == ref.size and np.nanmax(np.abs(sym / ref - 1.0)) > 0.01) else ""
            print(f"{label}{split}: " + "; ".join(
                f"{m} RMS {100 * entry[m]['rms']:.2f} % max {100 * entry[m]['max']:.2f} %"
                for m in members), flush=True)
    summary = {m: _summary(cases, m) for m in members}
    for m, s in summary.items():
        print(f"all outlines, {m}: closing angle RMS {100 * s['rms_all']:.2f} %, max "
              f"{100 * s['max_all']:.2f} %, worst case RMS {100 * s['worst_case_rms']:.2f} %")
    return {"cases": cases, "summary": summary, "perturb_rad": PERTURB_RAD,
            "fem_mesh_convergence": mesh_convergence((12, 18) if quick else (12, 18, 24))}


def _summary(cases: dict, member: str) -> dict:
    """RMS and largest relative error of a member over every case, and per outline."""
    rel = np.concatenate([np.asarray(c[member]["relative_errors"]) for c in cases.values()])
    rel = rel[np.isfinite(rel)]
    by_shape: dict[str, list[float]] = {}
    for label, c in cases.items():
        by_shape.setdefault(label.split(",")[0], []).extend(
            v for v in c[member]["relative_errors"] if math.isfinite(v))
    return {"rms_all": float(np.sqrt(np.mean(rel**2))), "max_all": float(np.abs(rel).max()),
            "worst_case_rms": max(c[member]["rms"] for c in cases.values()),
            "by_shape_rms": {k: float(np.sqrt(np.mean(np.square(v))))
                             for k, v in by_shape.items()}}


def ranking_objects() -> dict:
    """The objects of part 2 (the issue's ellipse across and along the jaws, the slice)."""
    return {"ellipse 2:1 across": load_object(EXAMPLES / "grape_across.toml").disk,
            "ellipse 2:1 along": load_object(EXAMPLES / "grape_along.toml").disk,
            "measured slice": load_object(EXAMPLES / "pebble_slice.toml").disk}


def run_ranking(n: int, seed: int, executor) -> dict:
    out = {}
    for name, obj in ranking_objects().items():
        designs = DesignBounds().sample(np.random.default_rng(seed), n, obj)
        t0 = time.perf_counter()
        fem = evaluate_designs(designs, obj, fidelity="fem", executor=executor,
                               strain_limits=0.08, friction_coefficients=0.6)
        fem_s = time.perf_counter() - t0
        entry = {"fem_s": fem_s, "valid_at_rest": int(fem["valid_at_rest"].sum()),
                 "fem_converged": int((fem["converged"] & fem["valid_at_rest"]).sum()),
                 "fem_reward": fem["reward"].tolist()}
        for label, kw in MEMBERS.items():
            psm = evaluate_designs(designs, obj, strain_limits=0.08, friction_coefficients=0.6,
                                   **kw)
            rows = np.flatnonzero(fem["valid_at_rest"] & fem["converged"] & psm["converged"])
            entry[label] = {**rank_agreement(psm, fem, rows), "rows": rows.tolist(),
                            "psm_reward": psm["reward"].tolist()}
            rho = entry[label].get("spearman_reward")
            print(f"{name}, {label}: {rows.size} designs, Spearman reward "
                  f"{'n/a' if rho is None else f'{rho:.3f}'}, FEM rank of the PSM's best "
                  f"{entry[label].get('fem_rank_of_psm_best')}, reward error mean "
                  f"{entry[label].get('reward_error_mean', math.nan):.4f}, designs held at one "
                  f"fidelity only {entry[label].get('tier_flips')} (FEM {fem_s:.0f} s)",
                  flush=True)
        out[name] = entry
    return out


def chart(result: dict, out: Path) -> list[Path]:
    """The closing angles in ``out/outline_accuracy.png`` and the reward ranking in
    ``out/outline_ranking.png``, each where its part ran: the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    written = []
    if "angles" in result:
        fig, ax = plt.subplots(figsize=(5.2, 4.2))
        cases = result["angles"]["cases"]
        labels = list(cases)
        members = [m for m in MEMBERS if m in cases[labels[0]]]
        height = 0.8 / len(members)
        for j, m in enumerate(members):
            y = np.arange(len(labels)) + (j - 0.5 * (len(members) - 1)) * height
            ax.barh(y, [100 * cases[c][m]["rms"] for c in labels], height, color=f"C{j}",
                    label=f"{m} RMS")
            ax.plot([100 * cases[c][m]["max"] for c in labels], y, "k|", ms=6)
        ax.axvline(3.0, color="C3", lw=0.8, ls="--", label="3 % (|: max)")
        ax.set_yticks(range(len(labels)), labels, fontsize=6)
        ax.invert_yaxis()
        ax.set_xlabel("closing-angle error vs FEM [%]")
        ax.set_title("closing angle on held-out outlines", fontsize=9)
        ax.legend(fontsize=7)
        written.append(_save(fig, out / "outline_accuracy.png"))
    ranking = result.get("ranking", {})
    if ranking:
        fig, axes = plt.subplots(1, len(ranking), figsize=(4.6 * len(ranking), 4.2),
                                 squeeze=False)
        for ax, (name, entry) in zip(axes[0], ranking.items(), strict=True):
            title = []
            for j, label in enumerate(m for m in MEMBERS if m in entry):
                rows = np.asarray(entry[label]["rows"], dtype=int)
                fem = np.asarray(entry["fem_reward"])[rows]
                psm = np.asarray(entry[label]["psm_reward"])[rows]
                ax.scatter(fem, psm, s=12, color=f"C{j}", label=label)
                if rows.size:
                    lo, hi = min(fem.min(), psm.min()), max(fem.max(), psm.max())
                    ax.plot([lo, hi], [lo, hi], color="0.6", lw=0.8)
                rho = entry[label].get("spearman_reward")
                title.append(f"{label} {rho:.3f}" if rho is not None else label)
            ax.legend(fontsize=7)
            ax.set_title(f"{name}: Spearman " + ", ".join(title), fontsize=8)
            ax.set_xlabel("FEM reward")
            ax.set_ylabel("PSM reward")
        written.append(_save(fig, out / "outline_ranking.png"))
    return written


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--angles", action="store_true", help="part 1 only (closing angles)")
    ap.add_argument("--ranking", action="store_true", help="part 2 only (reward ranking)")
    ap.add_argument("--designs", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=None,
                    help="FEM of part 2 in this many processes (default: in process)")
    ap.add_argument("--quick", action="store_true",
                    help="two outlines at two orientations, 8 designs")
    ap.add_argument("--out", default="out")
    args = ap.parse_args(argv)
    both = not (args.angles or args.ranking)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    result: dict = {"command": "python scripts/outline_accuracy.py " + " ".join(
        argv if argv is not None else sys.argv[1:])}
    if both or args.angles:
        result["angles"] = run_angles(args.quick)
    if both or args.ranking:
        executor = None
        if args.workers:
            from optim.executors import ProcessExecutor

            executor = ProcessExecutor(args.workers)
        try:
            result["ranking"] = run_ranking(8 if args.quick else args.designs, args.seed,
                                            executor)
        finally:
            if executor is not None:
                executor.close()
    (out / "outline_accuracy.json").write_text(json.dumps(result, indent=1) + "\n")
    figures = chart(result, out)
    print(f"wrote {out / 'outline_accuracy.json'} and " + ", ".join(map(str, figures)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
