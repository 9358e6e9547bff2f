"""Where the fan folds: the largest squeeze each mesh carries before a triangle turns over.

The van Gelder fan has no spring against turning a triangle (centre, q_i, q_i+1) over: past
some squeeze the equilibrium reached by ramping the torque has a folded triangle, which the
solver reports as not converged (``GraspResult.folded``: an equilibrium with an inverted
triangle, told apart from a failed solve that stopped on a folded iterate). This script ramps the
torque on each paper disk for several N and records the last unfolded state: its torque and
peak strain. ``--area-stiffness-scale c_A`` adds the area energy of the model family (any
c_A > 0 keeps every triangle's area positive: the ramp should then never fold). Writes
``out/fold_limit.json``.

Usage: ``python scripts/fold_limit.py [--ns 12 20 40 100 200] [--steps 40]
[--area-stiffness-scale 0.01]``
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from envs.scene import Scene
from envs.solver import simulate_ramp


def fold_limit(name: str, n: int, t_max: float, steps: int, area_scale: float = 0.0) -> dict:
    """Ramp 0 -> t_max; the last converged unfolded state and the first folded one."""
    scene = Scene.preset(name).with_changes(area_stiffness_scale=area_scale)
    torques = np.linspace(t_max / steps, t_max, steps)
    last, first_fold, failures = None, None, 0
    for res in simulate_ramp(scene, torques, n, element="spring"):
        if res.folded:
            first_fold = res
            break
        if res.converged:
            last = res
        else:
            failures += 1
    return {
        "scene": name, "n": n, "area_stiffness_scale": area_scale,
        "last_unfolded_torque_nm": None if last is None else last.torque_nm,
        "last_unfolded_peak_strain": None if last is None else last.peak_strain,
        "fold_torque_nm": None if first_fold is None else first_fold.torque_nm,
        "failed_steps": failures,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--ns", type=int, nargs="+", default=[12, 20, 40, 100, 200])
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--area-stiffness-scale", type=float, default=0.0,
                    help="c_A of the area energy (0: the paper's springs-only fan)")
    ap.add_argument("--out", default="out/fold_limit.json")
    args = ap.parse_args()
    t_max = {"paper-r050": 2.0, "paper-r070": 4.0, "paper-r100": 8.0}
    rows = []
    for name, tm in t_max.items():
        for n in args.ns:
            row = fold_limit(name, n, tm, args.steps, args.area_stiffness_scale)
            rows.append(row)
            strain = row["last_unfolded_peak_strain"]
            print(f"{name} N={n:4d}: unfolded up to T = {row['last_unfolded_torque_nm']} N·m "
                  f"(peak strain {strain if strain is None else round(strain, 3)}), "
                  f"folds at T = {row['fold_torque_nm']}, failed steps {row['failed_steps']}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
