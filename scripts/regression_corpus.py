"""Write the regression corpus that pins the solver's answers while code moves.

Stores in ``tests/data/regression_corpus.npz``:

* 1200 random designs of a fixed box in metres (:data:`CORPUS_LOW`, :data:`CORPUS_HIGH`: the
  design box of the package before it became relative to the object; about a third of its
  designs are invalid at rest, which pins the invalid-design penalty too) on the paper r = 0.07
  disk and 300 on each of r = 0.05 and r = 0.10 (N = 20), evaluated by
  :func:`envs.evaluate_designs`: status, converged flag, jaw angles, contacts, peak strain and
  reward of each row;
* every preset at four torques through :func:`envs.simulate` (N = 20, and N = 8 / 40 on
  paper-r070): converged flag, jaw angles, contour points and face forces;
* the default model (nh-quad, 40 points on 2 rings, its shipped calibration): 700 random designs
  of the object-relative box (:class:`envs.DesignBounds`) on the three paper disks, and every
  preset at three torques, with the same answers (keys ``default_*``), and for the designs
  also the peak compression, the contact score, the pin force, the required friction (the
  default payload, the weight plus a lift at 1 g, included), the payload and the grip. The
  ring meshes have their own kernels (element energies, the scalar banded factor), which these
  rows pin beside the fan's;
* shaped jaws with the default model: 240 random designs of the ``any`` jaw box (cradles,
  V-grooves and the rounded grooves between them, :class:`envs.DesignBounds` ``jaw="any"``) on
  the three paper disks, with the default model's design answers (keys ``jaw_*``).

``tests/test_regression.py`` recomputes every answer and compares. Rerun this script only for
an intended change of answers, and say in the commit which rows changed and why.

Usage: ``python scripts/regression_corpus.py [--out tests/data/regression_corpus.npz]``
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import envs
from envs.model.defaults import FOAM_DENSITY_KG_M3

SEED = 20261123
DESIGN_ROWS = {0.07: 1200, 0.05: 300, 0.10: 300}
PRESET_TORQUES_REL = (0.05, 0.2, 0.5, 1.0)  # of the preset's reference torque below
REFERENCE_TORQUE_NM = {"paper": 0.4, "forceps": 2e-3}
EXTRA_N = {"paper-r070": (8, 40)}
# lower and upper bound of each column of envs.scene.DESIGN_FIELDS [SI]
CORPUS_LOW = np.array([0.05, np.radians(15.0), 0.0, 0.002, 0.0, 0.0])
CORPUS_HIGH = np.array([0.30, np.radians(75.0), 0.05, 0.03, 1.0, 0.06])
DESIGN_KEYS = ("status", "converged", "jaw_angles_rad", "n_contacts", "peak_strain", "reward")
DEFAULT_SEED = 20261125
DEFAULT_DESIGN_ROWS = {"paper-r070": 300, "paper-r050": 200, "paper-r100": 200}
DEFAULT_TORQUES_REL = (0.2, 0.5, 1.0)  # of the preset's reference torque
DEFAULT_DESIGN_KEYS = DESIGN_KEYS + ("peak_compression", "contact_score", "pin_force_n",
                                     "required_friction", "payload_n", "grip_force_n")
JAW_SEED = 20261127
JAW_DESIGN_ROWS = {"paper-r070": 120, "paper-r050": 60, "paper-r100": 60}


def design_inputs() -> tuple[np.ndarray, np.ndarray]:
    """Designs (B, 6) and the radius of each row's disk (B,)."""
    rng = np.random.default_rng(SEED)
    rows, radii = [], []
    for radius, count in DESIGN_ROWS.items():
        action = rng.uniform(-1.0, 1.0, size=(count, 6))
        rows.append(CORPUS_LOW + 0.5 * (action + 1.0) * (CORPUS_HIGH - CORPUS_LOW))
        radii.append(np.full(count, radius))
    return np.concatenate(rows), np.concatenate(radii)


def evaluate_corpus_designs(designs: np.ndarray, radii: np.ndarray) -> dict[str, np.ndarray]:
    """Evaluate the corpus designs (each with its own disk) at N = 20."""
    # the paper's foam disks (their density sets the default payload the rows were stored with)
    disks = [envs.SoftDisk(float(r), 0.0, density_kg_m3=FOAM_DENSITY_KG_M3) for r in radii]
    return envs.evaluate_designs(designs, disks, n_triangles=20, element="spring")


def preset_cases() -> list[tuple[str, float, int]]:
    """(preset, torque [N·m], N) of every simulate case."""
    cases = []
    for name in sorted(envs.PRESETS):
        ref = REFERENCE_TORQUE_NM[name.split("-")[0]]
        for n in (20, *EXTRA_N.get(name, ())):
            cases.extend((name, rel * ref, n) for rel in PRESET_TORQUES_REL)
    return cases


def simulate_case(name: str, torque_nm: float, n: int):
    """The simulate answer of one case."""
    return envs.simulate(envs.Scene.preset(name), torque_nm, n, element="spring")


def default_design_inputs() -> tuple[np.ndarray, np.ndarray]:
    """Designs (B, 6) of the object-relative box and the preset name of each row's disk."""
    rng = np.random.default_rng(DEFAULT_SEED)
    rows, names = [], []
    for name, count in DEFAULT_DESIGN_ROWS.items():
        rows.append(envs.DesignBounds().sample(rng, count, envs.Scene.preset(name).disk))
        names.extend([name] * count)
    return np.concatenate(rows), np.array(names)


def jaw_design_inputs() -> tuple[np.ndarray, np.ndarray]:
    """Designs (B, 10) of the ``any`` jaw box and the preset name of each row's disk."""
    rng = np.random.default_rng(JAW_SEED)
    bounds = envs.DesignBounds(jaw="any")
    rows, names = [], []
    for name, count in JAW_DESIGN_ROWS.items():
        rows.append(bounds.sample(rng, count, envs.Scene.preset(name).disk))
        names.extend([name] * count)
    return np.concatenate(rows), np.array(names)


def evaluate_default_designs(designs: np.ndarray, names: np.ndarray) -> dict[str, np.ndarray]:
    """Evaluate designs with the default model, each on its preset's disk."""
    disks = [envs.Scene.preset(str(name)).disk for name in names]
    return envs.evaluate_designs(designs, disks)


def default_preset_cases() -> list[tuple[str, float]]:
    """(preset, torque [N·m]) of every default-model simulate case."""
    return [(name, rel * REFERENCE_TORQUE_NM[name.split("-")[0]])
            for name in sorted(envs.PRESETS) for rel in DEFAULT_TORQUES_REL]


def simulate_default_case(name: str, torque_nm: float):
    """The default model's simulate answer of one case."""
    return envs.simulate(envs.Scene.preset(name), torque_nm)


def _rows_data(prefix: str, designs: np.ndarray, disk_key: str, disks: np.ndarray,
               out: dict[str, np.ndarray], keys: tuple[str, ...], cases: list[tuple],
               results: list) -> dict[str, np.ndarray]:
    """One member's design rows (``<prefix>designs``, the disks under ``disk_key``, the
    answers ``<prefix>design_<key>``) and the common keys of its simulate cases
    (``<prefix>case_*``: names, torques, converged flags, jaw angles; points and forces are
    stored by the caller, ragged for the fan's several N)."""
    data = {f"{prefix}designs": designs, disk_key: disks}
    data.update({f"{prefix}design_{k}": out[k] for k in keys})
    data[f"{prefix}case_names"] = np.array([c[0] for c in cases])
    data[f"{prefix}case_torques_nm"] = np.array([c[1] for c in cases])
    data[f"{prefix}case_converged"] = np.array([r.converged for r in results])
    data[f"{prefix}case_jaw_angles_rad"] = np.array([r.jaw_angles_rad for r in results])
    return data


def fan_data() -> dict[str, np.ndarray]:
    """The fan's rows of the corpus."""
    designs, radii = design_inputs()
    cases = preset_cases()
    results = [simulate_case(*c) for c in cases]
    data = _rows_data("", designs, "radii", radii, evaluate_corpus_designs(designs, radii),
                      DESIGN_KEYS, cases, results)
    data["case_n"] = np.array([c[2] for c in cases])
    # ragged (N differs): stored flat with offsets
    data["case_points_m"] = np.concatenate([r.points_m.ravel() for r in results])
    data["case_face_forces_n"] = np.concatenate([r.contact_forces_n.ravel() for r in results])
    return data


def default_model_data() -> dict[str, np.ndarray]:
    """The default model's rows of the corpus (keys ``default_*``)."""
    designs, names = default_design_inputs()
    cases = default_preset_cases()
    results = [simulate_default_case(*c) for c in cases]
    data = _rows_data("default_", designs, "default_disks", names,
                      evaluate_default_designs(designs, names), DEFAULT_DESIGN_KEYS, cases,
                      results)
    data["default_case_points_m"] = np.array([r.points_m for r in results])
    data["default_case_interior_points_m"] = np.array([r.interior_points_m for r in results])
    data["default_case_face_forces_n"] = np.array([r.contact_forces_n for r in results])
    return data


def jaw_data() -> dict[str, np.ndarray]:
    """The shaped jaws' rows of the corpus (keys ``jaw_*``)."""
    designs, names = jaw_design_inputs()
    out = evaluate_default_designs(designs, names)
    data = {"jaw_designs": designs, "jaw_disks": names}
    data.update({f"jaw_design_{k}": out[k] for k in DEFAULT_DESIGN_KEYS})
    return data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="tests/data/regression_corpus.npz")
    args = parser.parse_args()
    data = {**fan_data(), **default_model_data(), **jaw_data()}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.out, **data)
    print(f"{args.out}: {data['designs'].shape[0]} designs "
          f"({int(data['design_converged'].sum())} converged), {data['case_n'].size} simulate "
          f"cases ({int(data['case_converged'].sum())} converged); default model: "
          f"{data['default_designs'].shape[0]} designs "
          f"({int(data['default_design_converged'].sum())} converged), "
          f"{data['default_case_names'].size} simulate cases "
          f"({int(data['default_case_converged'].sum())} converged); shaped jaws: "
          f"{data['jaw_designs'].shape[0]} designs "
          f"({int(data['jaw_design_converged'].sum())} converged)")


if __name__ == "__main__":
    main()
