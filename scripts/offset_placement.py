"""Grasps of an object placed off the gripper's axis: cost, convergence and mirror symmetry.

Draws random designs from the default :class:`envs.DesignBounds` on the paper-r070 disk and a
random lateral offset ``x_c`` of the disk centre, uniform in ``[-f r, f r]`` (default f =
0.15), and evaluates every design twice with :func:`envs.evaluate_designs`: centred and
displaced (``offsets_x_m``), then once more displaced by ``-x_c`` (the mirror image). The
displaced object is held where it was placed (its centre stays fixed while the jaws close).

Reports, per model (the default model and the paper's fan): how many designs stay valid at rest
once displaced, the convergence rate of the valid ones, the solver's Newton iterations and the
wall time displaced vs. centred (on the designs valid both ways), and how closely the mirrored
placement mirrors the grasp (jaw angles swapped, same peak compression and reward). Numba is
warmed up before any timing. With ``--fem K``, the first K designs valid both ways are also
solved with the FEM reference (``fem_rings`` 12, the evaluator's default mesh), centred and
displaced, and the default model's closing angles (rest angle minus jaw angle) compared with
the FEM's. Writes ``out/offset_placement.json``.

Usage::

    python scripts/offset_placement.py [--designs 200] [--fraction 0.15] [--seed 0] [--fem 0]
                                       [--out out]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from envs import DesignBounds, evaluate_designs
from envs.scene import PRESETS

MODELS = {"default": {}, "fan": {"element": "spring"}}


def timed(designs: np.ndarray, disk, offsets, model: dict) -> tuple[dict, float]:
    """One evaluation and its wall time [s]."""
    t0 = time.perf_counter()
    out = evaluate_designs(designs, disk, offsets_x_m=offsets, **model)
    return out, time.perf_counter() - t0


def quantiles(values: np.ndarray) -> dict:
    """Mean, median and 90th percentile of a sample (empty: None)."""
    if values.size == 0:
        return {"mean": None, "median": None, "p90": None}
    return {"mean": float(np.mean(values)), "median": float(np.median(values)),
            "p90": float(np.percentile(values, 90))}


def run_model(designs: np.ndarray, disk, offsets: np.ndarray, model: dict) -> dict:
    """Centred, displaced and mirrored evaluations of the designs with one model."""
    evaluate_designs(designs[:2], disk, offsets_x_m=offsets[:2], **model)  # compile / load
    centred, t_centred = timed(designs, disk, 0.0, model)
    shifted, t_shifted = timed(designs, disk, offsets, model)
    mirrored, _ = timed(designs, disk, -offsets, model)
    valid = shifted["valid_at_rest"]
    both = valid & centred["converged"] & shifted["converged"]
    pair = shifted["converged"] & mirrored["converged"]
    jaw_err = np.abs(shifted["jaw_angles_rad"] - mirrored["jaw_angles_rad"][:, ::-1]).max(axis=1)
    comp_err = np.abs(shifted["peak_compression"] - mirrored["peak_compression"])
    reward_err = np.abs(shifted["reward"] - mirrored["reward"])
    return {
        "designs": int(designs.shape[0]),
        "valid_centred": int(centred["valid_at_rest"].sum()),
        "valid_displaced": int(valid.sum()),
        "converged_centred_of_valid": float(centred["converged"][centred["valid_at_rest"]].mean()),
        "converged_displaced_of_valid": float(shifted["converged"][valid].mean()),
        "not_converged_displaced": int((valid & ~shifted["converged"]).sum()),
        "holds_centred": int(centred["holds"].sum()),
        "holds_displaced": int(shifted["holds"].sum()),
        "iterations_centred": quantiles(centred["iterations"][both].astype(float)),
        "iterations_displaced": quantiles(shifted["iterations"][both].astype(float)),
        "time_centred_s": t_centred,
        "time_displaced_s": t_shifted,
        "mirror_pairs_converged": int(pair.sum()),
        "mirror_jaw_within_1e-6_rad": int((jaw_err[pair] <= 1e-6).sum()),
        "mirror_jaw_max_err_rad": float(jaw_err[pair].max(initial=0.0)),
        "mirror_compression_max_err": float(comp_err[pair].max(initial=0.0)),
        "mirror_reward_max_err": float(reward_err[pair].max(initial=0.0)),
    }


def closing_errors(designs: np.ndarray, disk, offsets) -> dict:
    """Relative difference of the default model's closing angles from the FEM's, over the
    fingers of the rows where both converged and the FEM closes by more than 1e-3 rad."""
    psm = evaluate_designs(designs, disk, offsets_x_m=offsets)
    fem = evaluate_designs(designs, disk, offsets_x_m=offsets, fidelity="fem")
    both = psm["converged"] & fem["converged"]
    rest = designs[both, 1, None]
    closing_fem = rest - fem["jaw_angles_rad"][both]
    closing_psm = rest - psm["jaw_angles_rad"][both]
    moved = closing_fem > 1e-3
    err = np.abs(closing_psm[moved] / closing_fem[moved] - 1.0)
    return {"rows_converged_both": int(both.sum()), "fingers_compared": int(moved.sum()),
            "closing_rel_err_median": float(np.median(err)) if err.size else None,
            "closing_rel_err_max": float(np.max(err)) if err.size else None}


def fem_comparison(designs: np.ndarray, disk, offsets: np.ndarray, count: int) -> dict:
    """The default model against the FEM on ``count`` designs valid at rest when displaced,
    centred and displaced."""
    valid = evaluate_designs(designs, disk, offsets_x_m=offsets)["valid_at_rest"]
    rows = np.flatnonzero(valid)[:count]
    return {"designs": int(rows.size), "fem_rings": 12,
            "centred": closing_errors(designs[rows], disk, 0.0),
            "displaced": closing_errors(designs[rows], disk, offsets[rows])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--designs", type=int, default=200)
    parser.add_argument("--fraction", type=float, default=0.15,
                        help="largest |x_c| in disk radii")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--fem", type=int, default=0,
                        help="designs also compared with the FEM reference (slow: ~1 s each)")
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    _, disk = PRESETS["paper-r070"]
    rng = np.random.default_rng(args.seed)
    designs = DesignBounds().sample(rng, args.designs, disk)
    offsets = rng.uniform(-args.fraction, args.fraction, args.designs) * disk.radius_m
    report = {
        "command": (f"python scripts/offset_placement.py --designs {args.designs} "
                    f"--fraction {args.fraction} --seed {args.seed} --fem {args.fem}"),
        "machine": platform.platform(),
        "object": "paper-r070",
        "offset_fraction_of_radius": args.fraction,
        "models": {name: run_model(designs, disk, offsets, model)
                   for name, model in MODELS.items()},
    }
    if args.fem > 0:
        report["fem"] = fem_comparison(designs, disk, offsets, args.fem)
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "offset_placement.json"
    path.write_text(json.dumps(report, indent=2))
    print(json.dumps(report, indent=2))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
