"""Fit the model family's calibration scale once against the FEM on the paper disks.

For each constant-strain member (N contour points, M rings) the one scale ``s`` of its
triangles' energy (the disk's ``stiffness_scale``) is fitted to the FEM closing angle of the
three paper disks over :data:`envs.accuracy.PAPER_TORQUES_NM` (least squares of the relative
error), then checked unchanged on the held-out disks of ``scripts/ring_accuracy.py`` (other
radii, moduli and Poisson ratios). On coarse linear triangles the nearly incompressible
material locks (too stiff): ``s`` below 1 says by how much. The printed table is what
:data:`envs.model.family.CST_SCALES` ships.

Writes ``out/calibrate_family.json``.

Usage::

    python scripts/calibrate_family.py [--out out] [--quick]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from ring_accuracy import heldout_scenes  # noqa: E402

from envs.accuracy import PAPER_SCENES, PAPER_TORQUES_NM, fem_reference  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver.simulate import simulate_ramp  # noqa: E402

MEMBERS = ((20, 3), (20, 4), (24, 4), (24, 6), (32, 6), (48, 8))
QUICK_MEMBERS = ((20, 3),)


def errors(scene: Scene, ref, n: int, m: int, scale: float) -> np.ndarray:
    """Relative closing-angle errors of a constant-strain member at a scale (NaN: failed)."""
    model = scene.with_changes(stiffness_scale=scale)
    out = simulate_ramp(model, list(ref.torques_nm), n, n_rings=m, element="cst")
    th0 = scene.gripper.rest_angle_rad
    psm = th0 - np.array([np.mean(r.jaw_angles_rad) if r.converged else np.nan for r in out])
    return psm / (th0 - np.asarray(ref.jaw_angles_rad)) - 1.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--quick", action="store_true", help="one member (smoke test)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fit = {name: Scene.preset(name) for name in PAPER_SCENES}
    held = heldout_scenes()
    refs = {k: fem_reference(v, PAPER_TORQUES_NM) for k, v in (fit | held).items()}
    rows = []
    for n, m in QUICK_MEMBERS if args.quick else MEMBERS:
        t0 = time.perf_counter()

        def cost(log_s, n=n, m=m):
            e = np.concatenate([errors(sc, refs[k], n, m, float(np.exp(log_s)))
                                for k, sc in fit.items()])
            return float(np.mean(e**2)) if np.all(np.isfinite(e)) else 1e3

        res = minimize_scalar(cost, bounds=(np.log(0.7), np.log(1.3)), method="bounded",
                              options={"xatol": 1e-3})
        scale = float(np.exp(res.x))
        per = {k: errors(sc, refs[k], n, m, scale) for k, sc in (fit | held).items()}
        held_err = np.concatenate([per[k] for k in held])
        fit_err = np.concatenate([per[k] for k in fit])
        row = {"n_triangles": n, "n_rings": m, "element": "cst", "stiffness_scale": scale,
               "fit_rms": float(np.sqrt(np.mean(fit_err**2))),
               "fit_max": float(np.max(np.abs(fit_err))),
               "heldout_rms": float(np.sqrt(np.mean(held_err**2))),
               "heldout_rms_worst_disk": float(max(np.sqrt(np.mean(per[k] ** 2)) for k in held)),
               "heldout_max": float(np.max(np.abs(held_err))),
               "per_disk": {k: v.tolist() for k, v in per.items()},
               "fit_seconds": time.perf_counter() - t0}
        rows.append(row)
        print(f"CST N = {n:3d}, M = {m}: s = {scale:.4f}; paper RMS {100 * row['fit_rms']:.2f} % "
              f"(max {100 * row['fit_max']:.2f} %); held-out RMS {100 * row['heldout_rms']:.2f} "
              f"% (worst disk {100 * row['heldout_rms_worst_disk']:.2f} %, max "
              f"{100 * row['heldout_max']:.2f} %)", flush=True)
    (out / "calibrate_family.json").write_text(json.dumps({
        "torques_nm": list(PAPER_TORQUES_NM), "fitted_on": list(PAPER_SCENES),
        "heldout": list(held), "members": rows}, indent=1))
    print(f"wrote {out / 'calibrate_family.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
