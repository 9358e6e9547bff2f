"""Fit the model family's calibration scale once against the FEM on the paper disks.

``--element nhquad`` (the nh-quad members): one scale per ring count M, fitted over several N
at once (:data:`NHQUAD_FITS`), since the prototype found it independent of N and nu; it is
checked per (N, M) on the held-out disks. The printed table is what
:data:`envs.model.family.NHQUAD_SCALES` ships.

``--element cst``: for each constant-strain member (N contour points, M rings) the one scale
``s`` of its
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

from envs.accuracy import PAPER_SCENES, PAPER_TORQUES_NM, fem_reference  # noqa: E402
from envs.accuracy.heldout import heldout_scenes  # noqa: E402
from envs.scene import Scene  # noqa: E402
from envs.solver.simulate import simulate_ramp  # noqa: E402

MEMBERS = ((20, 3), (20, 4), (24, 4), (24, 6), (32, 6), (48, 8))
QUICK_MEMBERS = ((20, 3),)
# nh-quad: rings -> contour point counts fitted together (a cell about as wide as it is deep)
NHQUAD_FITS = {2: (32, 40, 48), 3: (40, 48, 56), 4: (48, 56, 64), 6: (64, 80, 96)}
QUICK_NHQUAD = {2: (40,)}


def errors(scene: Scene, ref, n: int, m: int, scale: float, element: str = "cst"
           ) -> np.ndarray:
    """Relative closing-angle errors of a member at a scale (NaN: failed)."""
    model = scene.with_changes(stiffness_scale=scale)
    out = simulate_ramp(model, list(ref.torques_nm), n, n_rings=m, element=element,
                        calibrated=False)
    th0 = scene.gripper.rest_angle_rad
    psm = th0 - np.array([np.mean(r.jaw_angles_rad) if r.converged else np.nan for r in out])
    return psm / (th0 - np.asarray(ref.jaw_angles_rad)) - 1.0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="output folder")
    parser.add_argument("--quick", action="store_true", help="one member (smoke test)")
    parser.add_argument("--element", default="nhquad", choices=("nhquad", "cst"))
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fit = {name: Scene.preset(name) for name in PAPER_SCENES}
    held = heldout_scenes()
    refs = {k: fem_reference(v, PAPER_TORQUES_NM) for k, v in (fit | held).items()}
    if args.element == "nhquad":
        return fit_nhquad(QUICK_NHQUAD if args.quick else NHQUAD_FITS, fit, held, refs, out)
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


def _member_row(n: int, m: int, element: str, scale: float, fit: dict, held: dict, refs: dict
                ) -> dict:
    """Errors of one member at a scale on the paper and the held-out disks."""
    per = {k: errors(sc, refs[k], n, m, scale, element) for k, sc in (fit | held).items()}
    held_err = np.concatenate([per[k] for k in held])
    fit_err = np.concatenate([per[k] for k in fit])
    return {"n_triangles": n, "n_rings": m, "element": element, "stiffness_scale": scale,
            "fit_rms": float(np.sqrt(np.mean(fit_err**2))),
            "fit_max": float(np.max(np.abs(fit_err))),
            "heldout_rms": float(np.sqrt(np.mean(held_err**2))),
            "heldout_rms_worst_disk": float(max(np.sqrt(np.mean(per[k] ** 2)) for k in held)),
            "heldout_max": float(np.max(np.abs(held_err))),
            "failed": int(sum(np.isnan(v).sum() for v in per.values())),
            "per_disk": {k: v.tolist() for k, v in per.items()}}


def fit_nhquad(fits: dict[int, tuple[int, ...]], fit: dict, held: dict, refs: dict,
               out: Path) -> int:
    """One scale per ring count, least squares over its contour counts and the paper disks."""
    rows = []
    for m, ns in fits.items():
        t0 = time.perf_counter()

        def cost(log_s, m=m, ns=ns):
            e = np.concatenate([errors(sc, refs[k], n, m, float(np.exp(log_s)), "nhquad")
                                for n in ns for k, sc in fit.items()])
            return float(np.mean(e**2)) if np.all(np.isfinite(e)) else 1e3

        res = minimize_scalar(cost, bounds=(np.log(0.6), np.log(1.3)), method="bounded",
                              options={"xatol": 1e-3})
        scale = float(np.exp(res.x))
        print(f"nh-quad M = {m}: s = {scale:.4f} (fitted over N = {ns}, RMS "
              f"{100 * np.sqrt(res.fun):.2f} %, {time.perf_counter() - t0:.0f} s)", flush=True)
        for n in ns:
            row = _member_row(n, m, "nhquad", scale, fit, held, refs)
            row["fitted_over_n"] = list(ns)
            rows.append(row)
            print(f"    N = {n:3d}: paper RMS {100 * row['fit_rms']:.2f} % (max "
                  f"{100 * row['fit_max']:.2f} %); held-out RMS {100 * row['heldout_rms']:.2f} "
                  f"% (worst disk {100 * row['heldout_rms_worst_disk']:.2f} %, max "
                  f"{100 * row['heldout_max']:.2f} %), failed {row['failed']}", flush=True)
    (out / "calibrate_family_nhquad.json").write_text(json.dumps({
        "torques_nm": list(PAPER_TORQUES_NM), "fitted_on": list(PAPER_SCENES),
        "heldout": list(held), "members": rows}, indent=1))
    print(f"wrote {out / 'calibrate_family_nhquad.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
