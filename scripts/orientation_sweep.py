"""Does an optimized design hold its object at every orientation of its tolerance?

Reads a run of ``psm-grasp optimize`` (its ``*_result.json`` in OUT_DIR), takes its best design
and its object (an outline with an orientation tolerance ``+- dpsi``), and evaluates the design
through the API (:func:`envs.evaluate.evaluate_designs`, each orientation its own independent
solve from rest, not the run's scenario set) at ``--points`` orientations evenly spaced over
``[psi - dpsi, psi + dpsi]``, the object's centroid held where it was placed. Prints a row per
orientation (holds, peak compression against the strain limit, required friction, reward) and
exits 0 when the design holds within the strain limit at every one, 1 otherwise.

Usage::

    python scripts/orientation_sweep.py OUT_DIR [--points 7] [--fem]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.evaluate import evaluate_designs  # noqa: E402
from envs.scenarios import Scenario, place  # noqa: E402
from envs.scene import design_row  # noqa: E402
from optim.charts import disk_of, model_of  # noqa: E402
from optim.result import OptimResult  # noqa: E402
from optim.verify import find_result  # noqa: E402


def sweep(result: OptimResult, points: int, fidelity: str = "psm") -> dict:
    """The run's best design at ``points`` orientations over its object's tolerance."""
    obj = result.object
    disk = disk_of(obj)
    tolerance = float((obj.get("scenarios") or {}).get("orientation_tolerance_rad", 0.0))
    turns = np.linspace(-tolerance, tolerance, points) if tolerance > 0 else np.zeros(1)
    cases = [Scenario({}, label=f"{math.degrees(t):+.1f} deg", dpsi_rad=float(t))
             for t in turns]
    design = design_row(result.best_design)
    rows, disks, _, _ = place(np.repeat(design[None, :], len(cases), axis=0), disk,
                              float(obj["friction_coefficient"]), cases)
    kwargs = {} if fidelity == "fem" else model_of(obj)
    out = evaluate_designs(rows, disks, strain_limits=obj["strain_limit"],
                           friction_coefficients=obj["friction_coefficient"],
                           payload_factors=obj.get("payload_factor", 0.0),
                           torsion_stiffness_nm_per_rad=obj["torsion_stiffness_nm_per_rad"],
                           fidelity=fidelity, **kwargs)
    limit = float(obj["strain_limit"])
    table = [{"orientation_deg": math.degrees(disk.orientation_rad + t),
              "holds": bool(out["holds"][i]),
              "peak_compression": float(out["peak_compression"][i]),
              "within_strain_limit": bool(out["peak_compression"][i] <= limit),
              "required_friction": float(out["required_friction"][i]),
              "reward": float(out["reward"][i])} for i, t in enumerate(turns)]
    return {"object": obj.get("name"), "strain_limit": limit, "fidelity": fidelity,
            "design": result.best_design, "orientations": table,
            "holds_everywhere": all(r["holds"] and r["within_strain_limit"] for r in table)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--result", default=None, help="the result file's name in OUT_DIR")
    ap.add_argument("--points", type=int, default=7)
    ap.add_argument("--fem", action="store_true", help="also evaluate with the FEM")
    args = ap.parse_args(argv)
    path = find_result(args.out_dir, args.result)
    result = OptimResult.from_json(path)
    reports = [sweep(result, args.points)]
    if args.fem:
        reports.append(sweep(result, args.points, "fem"))
    for rep in reports:
        print(f"{rep['object']} ({rep['fidelity']}), strain limit {rep['strain_limit']:g}:")
        print("  orientation  holds  peak compr.  req. friction  reward")
        for r in rep["orientations"]:
            print(f"  {r['orientation_deg']:+9.1f}°  {'yes' if r['holds'] else 'no ':>5}  "
                  f"{r['peak_compression']:11.4f}  {r['required_friction']:13.3f}  "
                  f"{r['reward']:.4f}")
        print(f"  holds within the strain limit at every orientation: "
              f"{'yes' if rep['holds_everywhere'] else 'NO'}")
    (Path(args.out_dir) / "orientation_sweep.json").write_text(json.dumps(reports, indent=1)
                                                               + "\n")
    return 0 if all(rep["holds_everywhere"] for rep in reports) else 1


if __name__ == "__main__":
    sys.exit(main())
