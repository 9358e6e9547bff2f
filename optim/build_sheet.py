"""A design a builder can use: the gripper in millimetres, its spring and torque in SI units.

:func:`build_sheet` turns an optimization's best design (a dict in SI units, the columns of
:data:`envs.scene.DESIGN_FIELDS`) and its object into a table a workshop reads: the finger
outline and the placement of joints and object in millimetres in the gripper frame (origin
midway between the joints, x to the right, y up along the symmetry axis, as in the model), the
rest angle in degrees, the joint spring in N·m/rad and the actuation torque in N·m.
:func:`write_build_sheet` writes it as JSON and CSV with a dimensioned drawing.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Arc, Circle, Polygon

from envs.render import finger_polygon
from envs.scene import DESIGN_FIELDS

__all__ = ["build_sheet", "write_build_sheet", "drawing_figure"]

MM = 1e3
# (key, unit, description) of the sheet's scalar rows, in this order
ROWS: tuple[tuple[str, str, str], ...] = (
    ("finger_length_mm", "mm", "finger length l, joint axis to tip"),
    ("finger_width_mm", "mm", "finger width w (gripping face w/2 from the finger's axis)"),
    ("rest_angle_deg", "deg", "rest angle of each finger from the symmetry axis"),
    ("joint_offset_mm", "mm", "joint distance d3 from the symmetry axis"),
    ("joint_spacing_mm", "mm", "distance between the two joints, 2 d3"),
    ("object_distance_mm", "mm", "d1: joints' line to the nearest point of the object"),
    ("object_centre_y_mm", "mm", "object centre above the joints' line, d1 + r"),
    ("object_diameter_mm", "mm", "object diameter 2 r"),
    ("torque_nm", "N·m", "actuation torque on each finger"),
    ("torsion_stiffness_nm_per_rad", "N·m/rad", "torsion spring at each joint (opens the jaw)"),
    ("torsion_stiffness_nmm_per_deg", "N·mm/deg", "the same spring per degree"),
)


# the sheet lists a finger's corners joint end (back, face), then tip end (face, back): the
# order of envs.render.finger_polygon's corners 0, 3, 2, 1
_SHEET_CORNERS = (0, 3, 2, 1)


def _finger_outline_mm(length: float, angle: float, offset: float, width: float,
                       side: int) -> list[list[float]]:
    """Corners of a finger bar at rest [mm]: joint end (back, face), tip end (face, back);
    side 0 right, 1 left (the drawings' own finger, :func:`envs.render.finger_polygon`)."""
    corners = finger_polygon(length, angle, offset, width, side)
    return [[round(float(v) * MM, 4) for v in corners[k]] for k in _SHEET_CORNERS]


def build_sheet(design: dict[str, float], obj: dict[str, Any],
                metrics: dict[str, Any] | None = None) -> dict[str, Any]:
    """The design as a builder needs it.

    Parameters
    ----------
    design
        A design in SI units (keys of :data:`envs.scene.DESIGN_FIELDS`).
    obj
        The object (``radius_m`` and, where known, ``name``, ``torsion_stiffness_nm_per_rad``
        and the material fields), as in :attr:`optim.result.OptimResult.object`.
    metrics
        The design's grasp metrics (jaw angles, forces, ...), copied in where present.

    Returns
    -------
    dict
        ``rows`` (the scalar quantities of :data:`ROWS`), ``finger_outline_mm`` (the corners
        of the right and left finger at rest), ``joints_mm``, ``object_centre_mm``, ``object``
        and, with metrics, ``grasp`` (closing angles in degrees, contact forces in N, peak
        compression).
    """
    missing = [k for k in DESIGN_FIELDS if k not in design]
    if missing:
        raise ValueError(f"design is missing {missing}")
    if "torsion_stiffness_nm_per_rad" not in obj or "radius_m" not in obj:
        raise ValueError("obj needs radius_m and torsion_stiffness_nm_per_rad")
    ln, th0, d3, w, torque, d1 = (float(design[k]) for k in DESIGN_FIELDS)
    r, kf = float(obj["radius_m"]), float(obj["torsion_stiffness_nm_per_rad"])
    values = {
        "finger_length_mm": ln * MM, "finger_width_mm": w * MM,
        "rest_angle_deg": math.degrees(th0), "joint_offset_mm": d3 * MM,
        "joint_spacing_mm": 2 * d3 * MM, "object_distance_mm": d1 * MM,
        "object_centre_y_mm": (d1 + r) * MM, "object_diameter_mm": 2 * r * MM,
        "torque_nm": torque, "torsion_stiffness_nm_per_rad": kf,
        "torsion_stiffness_nmm_per_deg": kf * MM * math.pi / 180.0,
    }
    sheet: dict[str, Any] = {
        "object": {k: obj.get(k) for k in ("name", "radius_m", "youngs_modulus_pa",
                                           "poisson_ratio", "thickness_m", "strain_limit")},
        "rows": [{"quantity": key, "value": values[key], "unit": unit, "meaning": text}
                 for key, unit, text in ROWS],
        "frame": "origin midway between the joints, x to the right, y up the symmetry axis "
                 "towards the object; fingers at rest",
        "joints_mm": [[d3 * MM, 0.0], [-d3 * MM, 0.0]],
        "object_centre_mm": [0.0, (d1 + r) * MM],
        "finger_outline_mm": {"right": _finger_outline_mm(ln, th0, d3, w, 0),
                              "left": _finger_outline_mm(ln, th0, d3, w, 1)},
    }
    if metrics:
        grasp = {}
        if metrics.get("jaw_angles_rad") is not None:
            grasp["closed_angles_deg"] = [math.degrees(float(a))
                                          for a in metrics["jaw_angles_rad"]]
        for key in ("total_force_n", "peak_compression", "contact_score", "converged",
                    "pin_force_n", "required_friction"):
            if metrics.get(key) is not None:
                grasp[key] = metrics[key]
        sheet["grasp"] = grasp
    return sheet


def _dimension(ax, p: np.ndarray, q: np.ndarray, offset: np.ndarray, text: str) -> None:
    """A dimension line from p to q [mm], drawn ``offset`` [mm] aside, with extension lines."""
    a, b = p + offset, q + offset
    for start, end in ((p, a), (q, b)):
        ax.plot(*zip(start, end, strict=True), color="0.45", lw=0.6)
    ax.annotate("", a, b, arrowprops={"arrowstyle": "<->", "color": "0.2", "lw": 0.8})
    mid = (a + b) / 2
    ax.text(*mid, text, fontsize=8, ha="center", va="center",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none"})


def drawing_figure(sheet: dict[str, Any], title: str | None = None) -> Figure:
    """A dimensioned drawing of a build sheet's gripper at rest with its object [mm]."""
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    ln, w, d3 = rows["finger_length_mm"], rows["finger_width_mm"], rows["joint_offset_mm"]
    th0 = math.radians(rows["rest_angle_deg"])
    r = rows["object_diameter_mm"] / 2
    centre = np.array(sheet["object_centre_mm"])
    fig = Figure(figsize=(6.4, 6.4), dpi=110)
    ax = fig.add_subplot()
    for side in ("right", "left"):
        ax.add_patch(Polygon(sheet["finger_outline_mm"][side], closed=True, facecolor="0.8",
                             edgecolor="0.2", lw=1.0))
    ax.add_patch(Circle(centre, r, facecolor="tab:orange", alpha=0.3, edgecolor="k"))
    for x, _ in sheet["joints_mm"]:
        ax.plot([x], [0.0], "o", color="k", ms=4)
    scale = max(ln, 2 * r + centre[1])
    gap = 0.06 * scale
    s, c = math.sin(th0), math.cos(th0)
    joint, axis, outward = np.array([d3, 0.0]), np.array([s, c]), np.array([c, -s])
    back = joint + (w / 2) * outward
    _dimension(ax, back, back + ln * axis, gap * outward, f"l = {ln:.2f}")
    tip = joint + ln * axis
    _dimension(ax, tip - (w / 2) * outward, tip + (w / 2) * outward, 0.6 * gap * axis,
               f"w = {w:.2f}")
    _dimension(ax, np.zeros(2), joint, np.array([0.0, -1.5 * gap]), f"d3 = {d3:.2f}")
    bottom = centre - np.array([0.0, r])
    _dimension(ax, np.array([0.0, 0.0]), bottom, np.array([-1.3 * gap - r, 0.0]),
               f"d1 = {rows['object_distance_mm']:.2f}")
    _dimension(ax, centre - np.array([r, 0.0]), centre + np.array([r, 0.0]),
               np.array([0.0, r + gap]), f"2r = {2 * r:.2f}")
    arc_r = 0.35 * ln
    ax.plot([d3, d3], [0.0, arc_r * 1.1], color="0.45", lw=0.6, ls="--")
    ax.add_patch(Arc((d3, 0.0), 2 * arc_r, 2 * arc_r, theta1=90 - math.degrees(th0), theta2=90,
                     color="0.2", lw=0.8))
    ax.text(d3 - 0.02 * ln, 1.1 * arc_r, f"θ0 = {rows['rest_angle_deg']:.1f}°", fontsize=8,
            ha="right", va="center")
    ax.text(0.02, 0.02, f"T_a = {rows['torque_nm']:.4g} N·m per finger\n"
            f"k_f = {rows['torsion_stiffness_nm_per_rad']:.4g} N·m/rad "
            f"({rows['torsion_stiffness_nmm_per_deg']:.4g} N·mm/deg)",
            transform=ax.transAxes, fontsize=8, va="bottom")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.12)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.grid(alpha=0.2)
    name = (sheet.get("object") or {}).get("name") or "the object"
    ax.set_title(title or f"gripper for {name}, at rest (millimetres)", fontsize=10)
    fig.tight_layout()
    return fig


def write_build_sheet(design: dict[str, float], obj: dict[str, Any], out_dir: str | Path,
                      prefix: str, metrics: dict[str, Any] | None = None) -> dict[str, Path]:
    """Write ``{prefix}_design.json``, ``{prefix}_design.csv`` and ``{prefix}_drawing.png``.

    Returns the written paths by kind (``design_json``, ``design_csv``, ``drawing``).
    """
    from .result import to_jsonable

    sheet = build_sheet(design, obj, metrics)
    folder = Path(out_dir)
    paths = {"design_json": folder / f"{prefix}_design.json",
             "design_csv": folder / f"{prefix}_design.csv",
             "drawing": folder / f"{prefix}_drawing.png"}
    paths["design_json"].write_text(json.dumps(to_jsonable(sheet), indent=1) + "\n")
    with paths["design_csv"].open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["quantity", "value", "unit", "meaning"])
        for row in sheet["rows"]:
            writer.writerow([row["quantity"], f"{row['value']:.6g}", row["unit"],
                             row["meaning"]])
        for side, corners in sheet["finger_outline_mm"].items():
            for k, (x, y) in enumerate(corners):
                writer.writerow([f"{side}_finger_corner_{k}_x_mm", f"{x:.4f}", "mm",
                                 "finger outline at rest (joint end back, joint end face, "
                                 "tip face, tip back)"])
                writer.writerow([f"{side}_finger_corner_{k}_y_mm", f"{y:.4f}", "mm", ""])
    fig = drawing_figure(sheet)
    fig.savefig(paths["drawing"])
    return paths
