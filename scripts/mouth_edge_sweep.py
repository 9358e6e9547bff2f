"""Cradles on paper-r070 across the radius where the grasp's contact slides over the groove's
mouth edge (R = 111.257 mm: the default model, a cradle 5 mm deep centred 100 mm along the
paper's 10 mm wide fingers, 0.3 N·m).

Prints, for a line of cradle radii solved by ``evaluate_designs``: how many converged, and the
largest and mean step of the contact score between neighbours. With ``--branches`` it also
sweeps the radius up and down, each solve started from its neighbour's answer (as
``simulate_ramp`` does along torques), and compares both with the solve from rest: one branch
or two (a snap shows as a jump of the jaw angle, hysteresis as sweeps that disagree).

    python scripts/mouth_edge_sweep.py --low-mm 110 --high-mm 112.5 --count 200
    python scripts/mouth_edge_sweep.py --low-mm 111.2 --high-mm 111.32 --count 25 --branches
"""

from __future__ import annotations

import argparse

import numpy as np

from envs import Scene, evaluate_designs, simulate
from envs.scene import Design
from envs.solver.simulate import _Problem, _warm_start

PAPER = Scene.preset("paper-r070")
TORQUE_NM = 0.3
RADIUS_COLUMN = 7  # jaw_bottom_radius_m of a 10-wide design row (envs.model.jaw.JAW_FIELDS)


def cradle_designs(radii_m: np.ndarray) -> np.ndarray:
    """Design rows (B, 10) of the paper gripper with a cradle of each radius [m]."""
    g, disk = PAPER.gripper, PAPER.disk
    row = np.array([g.finger_length_m, g.rest_angle_rad, g.joint_offset_m, g.finger_width_m,
                    TORQUE_NM, disk.distance_m, 0.005, 0.11, 0.0, 0.1])
    designs = np.repeat(row[None], radii_m.size, axis=0)
    designs[:, RADIUS_COLUMN] = radii_m
    return designs


def _sweep(radii_m: np.ndarray) -> list[tuple[bool, float, float]]:
    """(converged, right jaw angle [rad], energy [J]) of each radius, each solve warm-started
    from the previous converged answer."""
    out = []
    prev = None
    for design in cradle_designs(radii_m):
        scene = Design.from_array(design).to_scene(PAPER.disk)
        rest = simulate(scene, TORQUE_NM)
        if prev is None:
            res = rest
        else:
            prob = _Problem(scene, TORQUE_NM, rest.n_triangles, rest.stiffness_rule,
                            np.pi / 2, rest.n_rings, rest.element, rest.model_scale,
                            rest.payload_n)
            res, _ = prob.solve(*_warm_start(prob, prev))
        out.append((res.converged, res.jaw_angles_rad[0], res.energy_j))
        prev = res if res.converged else prev
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--low-mm", type=float, default=110.0)
    parser.add_argument("--high-mm", type=float, default=112.5)
    parser.add_argument("--count", type=int, default=200)
    parser.add_argument("--branches", action="store_true",
                        help="also sweep up and down with warm starts")
    args = parser.parse_args()
    radii = np.linspace(args.low_mm, args.high_mm, args.count) * 1e-3
    out = evaluate_designs(cradle_designs(radii), PAPER.disk)
    steps = np.abs(np.diff(out["contact_score"]))
    print(f"{int(out['converged'].sum())} of {radii.size} converged; contact score "
          f"{out['contact_score'].min():.5f} to {out['contact_score'].max():.5f}, largest step "
          f"{steps.max():.3g}, mean step {steps.mean():.3g} ({steps.max() / steps.mean():.2f}x)")
    for i in np.flatnonzero(~out["converged"]):
        print(f"  R = {radii[i] * 1e3:.4f} mm: status {out['status'][i]}")
    if not args.branches:
        return
    up = _sweep(radii)
    down = _sweep(radii[::-1])[::-1]
    rest = [(r.converged, r.jaw_angles_rad[0], r.energy_j) for r in (
        simulate(Design.from_array(d).to_scene(PAPER.disk), TORQUE_NM)
        for d in cradle_designs(radii))]
    angle = np.array([[a[1] for a in s] for s in (up, down, rest)])
    energy = np.array([[a[2] for a in s] for s in (up, down, rest)])
    ok = all(a[0] for s in (up, down, rest) for a in s)
    print(f"up, down and from rest all converged: {ok}; jaw angles apart by at most "
          f"{np.ptp(angle, axis=0).max():.2e} rad, energies by {np.ptp(energy, axis=0).max():.2e} "
          f"J; the jaw angle over the line spans {np.ptp(angle[2]):.2e} rad")


if __name__ == "__main__":
    main()
