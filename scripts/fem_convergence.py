"""Validate the finite-element grasp reference (``envs.fem``) and write ``out/fem_validation.json``.

Two checks:

1. Hertz line contact: the disk of ``paper-r070`` squeezed between two rigid plates, at the load
   giving a Hertz compression ``delta / r = 1e-3`` (and ``1e-2``), for several contact element
   sizes, in plane strain and plane stress; relative error of the FEM compression to
   ``delta = 2 P / (pi E*) (2 ln(4 r / b) - 1)``.
2. Mesh convergence of the grasp of ``paper-r070`` at three torques on meshes with
   ``r / h = 6, 12 (default), 24`` (and 48 with ``--fine``): jaw angle, contact force and peak
   strain, with the relative change from the previous mesh. The wall time of a 20-step torque
   ramp on the default mesh is recorded as well.

Usage::

    python scripts/fem_convergence.py [--fine] [--out out/fem_validation.json]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs import fem  # noqa: E402
from envs.scene import Scene, SoftDisk  # noqa: E402

TORQUES_NM = (0.05, 0.2, 0.5)


def _load_for(disk: SoftDisk, rel_compression: float, plane: str) -> float:
    r, e = disk.radius_m, disk.youngs_modulus_pa
    return brentq(
        lambda p: fem.hertz_line_compression(disk, p, plane) / r - rel_compression,
        1e-9 * e * r,
        1e-2 * e * r,
    )


def hertz_study(disk: SoftDisk) -> list[dict]:
    """FEM plate compression against Hertz for a few loads, planes and contact mesh sizes."""
    rows = []
    for plane in ("strain", "stress"):
        e_star = disk.youngs_modulus_pa / (1 - disk.poisson_ratio**2)
        if plane == "stress":
            e_star = disk.youngs_modulus_pa
        for rel in (1e-3, 1e-2):
            load = _load_for(disk, rel, plane)
            b = math.sqrt(4 * load * disk.radius_m / (math.pi * e_star))
            hertz = fem.hertz_line_compression(disk, load, plane)
            for factor in (4.0, 1.0, 0.125):
                t0 = time.perf_counter()
                delta = fem.fem_plate_compression(disk, load, mesh_size_m=factor * b, plane=plane)
                rows.append(
                    {
                        "plane": plane,
                        "load_n_per_m": load,
                        "hertz_half_width_m": b,
                        "contact_mesh_size_m": factor * b,
                        "mesh_size_over_b": factor,
                        "delta_hertz_m": hertz,
                        "delta_fem_m": delta,
                        "delta_over_r": delta / disk.radius_m,
                        "relative_error": delta / hertz - 1,
                        "time_s": time.perf_counter() - t0,
                    }
                )
    return rows


def convergence_study(scene: Scene, rings_list: list[int]) -> list[dict]:
    """Grasp at ``TORQUES_NM`` on successively refined meshes."""
    rows = []
    previous = None
    for rings in rings_list:
        t0 = time.perf_counter()
        results = fem.fem_grasp(
            scene, TORQUES_NM, mesh_size_m=scene.disk.radius_m / rings, cache=False
        )
        elapsed = time.perf_counter() - t0
        for i, res in enumerate(results):
            row = {
                "rings": rings,
                "n_elements": res.n_elements,
                "n_dofs": res.n_dofs,
                "torque_nm": res.torque_nm,
                "converged": res.converged,
                "jaw_angle_rad": res.jaw_angles_rad[0],
                "jaw_angle_asymmetry_rad": res.jaw_angles_rad[0] - res.jaw_angles_rad[1],
                "contact_force_n": res.contact_forces_n[0],
                "peak_strain": res.peak_strain,
                "max_penetration_m": res.max_penetration_m,
                "newton_iterations": res.newton_iterations,
                "wall_time_all_torques_s": elapsed,
            }
            if previous is not None:
                prev = previous[i]
                row["angle_change_vs_previous"] = res.jaw_angles_rad[0] / prev.jaw_angles_rad[0] - 1
                row["force_change_vs_previous"] = (
                    res.contact_forces_n[0] / prev.contact_forces_n[0] - 1
                )
                row["strain_change_vs_previous"] = res.peak_strain / prev.peak_strain - 1
            rows.append(row)
        previous = results
    return rows


def ramp_timing(scene: Scene, steps: int = 20) -> dict:
    """Wall time of a ``steps``-torque ramp up to 0.5 N·m on the default mesh."""
    torques = np.linspace(0.5 / steps, 0.5, steps)
    t0 = time.perf_counter()
    results = fem.fem_grasp(scene, torques, cache=False)
    elapsed = time.perf_counter() - t0
    return {
        "steps": steps,
        "max_torque_nm": 0.5,
        "n_elements": results[0].n_elements,
        "n_dofs": results[0].n_dofs,
        "all_converged": all(r.converged for r in results),
        "newton_iterations": int(sum(r.newton_iterations for r in results)),
        "wall_time_s": elapsed,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fine", action="store_true", help="also run r/h = 48 (slow)")
    parser.add_argument("--out", default="out/fem_validation.json", help="output JSON path")
    args = parser.parse_args(argv)

    scene = Scene.preset("paper-r070")
    hertz = hertz_study(scene.disk)
    print("Hertz line contact (disk between two plates), paper-r070 disk")
    print(
        f"{'plane':>6} {'delta/r':>8} {'h/b':>6} {'FEM delta [m]':>14} {'Hertz [m]':>11} "
        f"{'error':>8} {'time':>6}"
    )
    for row in hertz:
        print(
            f"{row['plane']:>6} {row['delta_over_r']:8.1e} {row['mesh_size_over_b']:6.3g} "
            f"{row['delta_fem_m']:14.6e} {row['delta_hertz_m']:11.4e} "
            f"{100 * row['relative_error']:+7.3f}% {row['time_s']:5.2f}s"
        )

    rings_list = [6, 12, 24] + ([48] if args.fine else [])
    conv = convergence_study(scene, rings_list)
    print("\nMesh convergence, paper-r070 grasp (plane strain)")
    print(
        f"{'r/h':>4} {'elems':>6} {'T [N m]':>8} {'theta [rad]':>12} {'d theta':>9} "
        f"{'F [N]':>8} {'d F':>8} {'peak eps':>9} {'d eps':>8}"
    )
    for row in conv:

        def pct(key: str, row: dict = row) -> str:
            return f"{100 * row[key]:+7.3f}%" if key in row else f"{'':>8}"

        print(
            f"{row['rings']:4d} {row['n_elements']:6d} {row['torque_nm']:8.3f} "
            f"{row['jaw_angle_rad']:12.7f} {pct('angle_change_vs_previous')} "
            f"{row['contact_force_n']:8.4f} {pct('force_change_vs_previous')} "
            f"{row['peak_strain']:9.4f} {pct('strain_change_vs_previous')}"
        )

    timing = ramp_timing(scene)
    print(
        f"\n20-step ramp to 0.5 N·m on the default mesh ({timing['n_elements']} elements, "
        f"{timing['n_dofs']} unknowns): {timing['wall_time_s']:.2f} s, "
        f"{timing['newton_iterations']} Newton iterations, converged={timing['all_converged']}"
    )

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "fem_version": fem.FEM_VERSION,
                "scene": "paper-r070",
                "hertz": hertz,
                "mesh_convergence": conv,
                "ramp_timing": timing,
            },
            indent=2,
        )
    )
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
