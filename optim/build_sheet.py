"""A design a builder can use: the gripper in millimetres, its spring and torque in SI units.

:func:`build_sheet` turns an optimization's best design (a dict in SI units, the columns of
:data:`envs.scene.DESIGN_FIELDS`) and its object into a table a workshop reads: the finger
outline and the placement of joints and object in millimetres in the gripper frame (origin
midway between the joints, x to the right, y up along the symmetry axis, as in the model), the
rest angle in degrees, the joint spring in N·m/rad and the actuation torque in N·m; and what the
design depends on: the friction coefficient it was designed for, the payload (where the result
has one), the placement tolerance and object ranges it was checked under with every scenario's
grasp, the fixed-centre assumption of the model, and how the fingers are assembled.

Assembly: each finger's joint end, a square end of half-width ``w / 2``, sweeps a circle of
radius ``w / 2`` about its joint as the finger turns. When the joints are closer than half a
finger width to the axis (``d_3 < w / 2``) the two circles overlap, and so do the fingers at
the joints: they can only be built **stacked**, one above the other at the joints, like the
jaws of forceps. Otherwise they can be built **side by side** in one plane.

Jaws: a finger's gripping face may carry a groove (:class:`envs.model.jaw.JawProfile`: a
cradle, a V-groove or a rounded V between). The sheet states each finger's profile (kind, depth,
bottom radius, opening angle, the groove centre's distance from the joint axis, mouth width; one
set for both fingers when they are alike) and "straight" for a flat face; the outlines carry the
cutout (its arcs as DXF bulges) and the drawing dimensions it in a detail per profile. The jaws
are read from the design by the names of :data:`envs.model.jaw.JAW_FIELDS` and
:data:`~envs.model.jaw.LEFT_JAW_FIELDS`; a design without them has straight jaws.
:func:`write_build_sheet` writes the sheet as JSON and CSV (the scenarios in a CSV of their own)
with a dimensioned drawing.
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

from envs.model.geometry import corner_radius
from envs.model.jaw import STRAIGHT, JawProfile, jaws_of_row
from envs.render import V_BULGE, V_X, V_Y, finger_outline, finger_to_drawing, outline_polygon
from envs.scene import DESIGN_FIELDS, design_row

__all__ = ["build_sheet", "write_build_sheet", "drawing_figure", "assembly_of", "write_dxf",
           "dxf_available", "DXF_LAYERS", "jaws_of_design", "jaw_rows", "JAW_ROWS",
           "ASSEMBLY_STACKED", "ASSEMBLY_SIDE_BY_SIDE", "FIXED_CENTRE_NOTE"]

MM = 1e3
OUTLINE_POINTS = 128  # points of an object's outline on the sheet and in the DXF
# layers of the DXF: each finger's outline, the joint centres, the object (for reference)
DXF_LAYERS = {"right": "FINGER_RIGHT", "left": "FINGER_LEFT", "joints": "JOINT_CENTRES",
              "object": "OBJECT_REFERENCE"}
DXF_MILLIMETRES = 4  # the DXF header's $INSUNITS code for millimetres
ASSEMBLY_STACKED = "stacked"
ASSEMBLY_SIDE_BY_SIDE = "side by side"
NOT_MODELLED = "not modelled"
FIXED_CENTRE_NOTE = (
    "The model holds the object's centre fixed while the jaws close, at (0, d1 + r) or, in a "
    "scenario with a placement error, where the object was placed (a displaced object is held "
    "where it was placed). Whether a free object stays put is judged from the friction: the "
    "grasp holds it when the friction coefficient is at least the required friction.")
DIMENSIONS_NOTE = (
    "Dimensional tolerances of the parts are not analysed by the model: the design was checked "
    "under the placement tolerance and the object ranges listed, at its nominal dimensions.")
# (key, unit, description) of the sheet's scalar rows of the gripper, in this order
ROWS: tuple[tuple[str, str, str], ...] = (
    ("finger_length_mm", "mm", "finger length l, joint axis to tip"),
    ("finger_width_mm", "mm", "finger width w (gripping face w/2 from the finger's axis)"),
    ("rest_angle_deg", "deg", "rest angle of each finger from the symmetry axis"),
    ("joint_offset_mm", "mm", "joint distance d3 from the symmetry axis"),
    ("joint_spacing_mm", "mm", "distance between the two joints, 2 d3"),
    ("joint_end_overlap_mm", "mm", "w - 2 d3: how far the fingers' joint ends overlap "
                                   "(> 0: stacked at the joints, like forceps jaws)"),
    ("object_distance_mm", "mm", "d1: joints' line to the nearest point of the object"),
    ("object_centre_y_mm", "mm", "object centre above the joints' line, d1 + r"),
    ("object_diameter_mm", "mm", "object diameter 2 r"),
    ("torque_nm", "N·m", "actuation torque on each finger"),
    ("torsion_stiffness_nm_per_rad", "N·m/rad", "torsion spring at each joint (opens the jaw)"),
    ("torsion_stiffness_nmm_per_deg", "N·mm/deg", "the same spring per degree"),
)
# (key, unit, description) of the rows of what the design depends on
CONDITION_ROWS: tuple[tuple[str, str, str], ...] = (
    ("friction_coefficient", "-", "Coulomb friction of the fingers' faces on the object the "
                                  "design was made for (the nominal one with ranges)"),
    ("strain_limit", "-", "admissible peak compression of the object"),
    ("placement_tolerance_along_mm", "mm", "placement error along the axis the design was "
                                           "checked under, +-"),
    ("placement_tolerance_across_mm", "mm", "placement error across the axis the design was "
                                            "checked under, +-"),
    ("density_kg_m3", "kg/m^3", "object density (payload)"),
    ("payload_factor", "-", "payload factor f: the load is f m g"),
    ("payload_n", "N", "payload W = f m g the grasp must carry"),
    ("grip_force_n", "N", "grip force of the grasp"),
)
# (key, unit, description) of the rows of a grooved jaw, after a prefix naming the finger(s)
JAW_ROWS: tuple[tuple[str, str, str], ...] = (
    ("kind", "-", "jaw profile: cradle (circular arc), vee (sharp V-groove) or rounded vee"),
    ("depth_mm", "mm", "groove depth h below the gripping face"),
    ("bottom_radius_mm", "mm", "radius R of the groove's bottom arc (a cradle's radius; 0: a "
                               "sharp V)"),
    ("opening_angle_deg", "deg", "full angle between the groove's flanks (0: a cradle, no "
                                 "flanks)"),
    ("position_mm", "mm", "groove centre line from the joint axis, along the finger"),
    ("mouth_width_mm", "mm", "width of the groove's mouth in the gripping face (sharp edges)"),
    ("mouth_edge_radius_mm", "mm", "the model rounds the mouth edges with this radius, as the "
                                   "finger's end corners"),
)
STRAIGHT_JAW_TEXT = "straight"
FINGERS = ("right", "left")  # the sheet's names of side 0 and 1
# a scenario row's columns: (key in the sheet, key in the result's row, scale to the sheet)
SCENARIO_COLUMNS: tuple[tuple[str, str, float], ...] = (
    ("dx_mm", "dx_m", MM), ("dy_mm", "dy_m", MM), ("reward", "reward", 1.0),
    ("holds", "holds", 1.0), ("peak_compression", "peak_compression", 1.0),
    ("required_friction", "required_friction", 1.0), ("payload_n", "payload_n", 1.0),
    ("grip_force_n", "grip_force_n", 1.0),
)
GRASP_KEYS = ("total_force_n", "peak_compression", "contact_score", "converged", "holds",
              "pin_force_n", "required_friction", "payload_n", "grip_force_n")
OBJECT_KEYS = ("name", "radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
               "density_kg_m3", "strain_limit", "friction_coefficient")


def _mm(key: str, value: Any) -> tuple[str, Any]:
    """A length in metres (a key ending in ``_m``, a number or a range) as millimetres."""
    if not key.endswith("_m") or value is None:
        return key, value
    scaled = [float(v) * MM for v in value] if isinstance(value, (list, tuple)) else (
        float(value) * MM)
    return key[:-2] + "_mm", scaled


def assembly_of(joint_offset_m: float, finger_width_m: float) -> tuple[str, str]:
    """How the fingers are built: :data:`ASSEMBLY_STACKED` when their joint ends overlap
    (``d_3 < w / 2``), else :data:`ASSEMBLY_SIDE_BY_SIDE`; and a sentence saying why.

    Parameters
    ----------
    joint_offset_m
        Joint distance ``d_3`` from the symmetry axis [m].
    finger_width_m
        Finger width ``w`` [m].
    """
    d3, w = float(joint_offset_m), float(finger_width_m)
    if d3 < w / 2:
        return ASSEMBLY_STACKED, (
            f"The joints are closer to the axis than half a finger width (d3 = {d3 * MM:.4g} mm "
            f"< w/2 = {w / 2 * MM:.4g} mm), so the fingers overlap at the joints by w - 2 d3 = "
            f"{(w - 2 * d3) * MM:.4g} mm: build them stacked, one finger above the other at "
            "the joints like the jaws of forceps, each gripping face spanning the object. A "
            "gripper that cannot stack its fingers needs a design with the joints apart "
            "(psm-grasp optimize --joints-apart).")
    return ASSEMBLY_SIDE_BY_SIDE, (
        f"The joints are at least half a finger width from the axis (d3 = {d3 * MM:.4g} mm >= "
        f"w/2 = {w / 2 * MM:.4g} mm): the fingers' joint ends never meet as they turn, and "
        "the fingers can be built side by side in one plane.")


def _sheet_outline(vertices: np.ndarray) -> np.ndarray:
    """An outline of :func:`envs.render.finger_outline` (joint end back, tip end back, tip face,
    groove, joint end face) in the sheet's order, joint end back, joint end face, groove, tip
    face, tip back: the same vertices the other way round, each arc's bulge negated and moved
    to the arc's other end."""
    count = len(vertices)
    order = [0, *range(count - 1, 0, -1)]
    # vertex order[n] now starts the segment that ended there: the old segment from the
    # vertex before it
    bulges = -vertices[[(k - 1) % count for k in order], V_BULGE]
    return np.column_stack([vertices[order][:, [V_X, V_Y]], bulges])


def _finger_outline_mm(length: float, angle: float, offset: float, width: float,
                       side: int, jaw: JawProfile = STRAIGHT) -> np.ndarray:
    """A finger at rest [mm]: joint end (back, face), the groove's vertices from the joint side,
    tip end (face, back), and the bulge of each segment to the next vertex; side 0 right, 1
    left (the drawings' own finger, :func:`envs.render.finger_outline`)."""
    outline = _sheet_outline(finger_outline(length, angle, offset, width, side, jaw))
    outline[:, [V_X, V_Y]] *= MM
    return outline


def jaws_of_design(design: dict[str, Any]) -> tuple[JawProfile, JawProfile]:
    """The right and the left finger's jaw profiles of a design dict: by the names of
    :data:`envs.model.jaw.JAW_FIELDS` (both fingers) and :data:`~envs.model.jaw.LEFT_JAW_FIELDS`
    (the left finger's, where it differs); none of them: straight jaws.

    Raises
    ------
    ValueError
        For a design with some of a finger's jaw fields but not all, or a groove out of range.
    """
    right, left = jaws_of_row(design_row(design))
    return right, right if left is None else left


def _jaw_entry(jaw: JawProfile, rounding_m: float, corner_mm: list[float]) -> dict[str, Any]:
    """A finger's jaw profile in the sheet's units: ``{"kind": "straight"}`` or the groove's
    dimensions (:data:`JAW_ROWS`) and the groove centre on the face at rest [mm]."""
    if jaw.depth_m == 0.0:
        return {"kind": STRAIGHT_JAW_TEXT}
    return {"kind": jaw.kind, "depth_mm": jaw.depth_m * MM,
            "bottom_radius_mm": jaw.bottom_radius_m * MM,
            "opening_angle_deg": math.degrees(jaw.opening_angle_rad),
            "position_mm": jaw.position_m * MM, "mouth_width_mm": 2 * jaw.mouth_half_width_m * MM,
            "mouth_edge_radius_mm": rounding_m * MM, "centre_on_face_mm": corner_mm}


def _jaws(jaws: tuple[JawProfile, JawProfile], length: float, angle: float, offset: float,
          width: float, radius: float) -> dict[str, Any]:
    """The sheet's ``jaws``: each finger's profile (:func:`_jaw_entry`) and whether they are
    alike; ``ValueError`` for a groove that does not fit its finger."""
    rounding = corner_radius(width, radius)
    entries = {}
    for side, (name, jaw) in enumerate(zip(FINGERS, jaws, strict=True)):
        try:
            jaw.check_fits(length, width, rounding)
        except ValueError as exc:
            raise ValueError(f"the {name} finger's jaw: {exc}") from exc
        # the groove centre on the face at rest: s = a, m = w/2 in the finger's frame
        (centre,) = MM * finger_to_drawing([[jaw.position_m, width / 2]], angle, offset, side)
        entries[name] = _jaw_entry(jaw, rounding, [round(float(v), 4) for v in centre])
    return {**entries, "same": jaws[0] == jaws[1]}


def _jaw_groups(sheet: dict[str, Any]) -> list[tuple[str | None, dict[str, Any]]]:
    """The sheet's distinct jaw profiles: ``[(None, entry)]`` for fingers alike, else each
    finger's ``(side, entry)``; a sheet written before jaw profiles has straight jaws."""
    jaws = sheet.get("jaws") or {"right": {"kind": STRAIGHT_JAW_TEXT}, "same": True}
    return [(None, jaws["right"])] if jaws["same"] else [(side, jaws[side]) for side in FINGERS]


def jaw_rows(sheet: dict[str, Any]) -> list[dict[str, Any]]:
    """The sheet's jaw profiles as table rows (quantity, value, unit, meaning): one ``jaw``
    row "straight" for flat faces, else :data:`JAW_ROWS` prefixed ``jaw_`` (both fingers
    alike) or ``right_jaw_`` and ``left_jaw_``."""
    rows = []
    for side, entry in _jaw_groups(sheet):
        prefix = "jaw" if side is None else f"{side}_jaw"
        whose = "both fingers" if side is None else f"{side} finger"
        if entry["kind"] == STRAIGHT_JAW_TEXT:
            rows.append({"quantity": prefix, "value": STRAIGHT_JAW_TEXT, "unit": "-",
                         "meaning": f"{whose}: a flat gripping face, no groove"})
            continue
        rows += [{"quantity": f"{prefix}_{key}", "value": entry[key], "unit": unit,
                  "meaning": f"{whose}: {text}"} for key, unit, text in JAW_ROWS]
    return rows


def _scenario_table(rows: list[dict[str, Any]] | None) -> list[dict[str, Any]]:
    """A result's scenario rows (:meth:`optim.problem.DesignProblem.scenario_rows`) as the
    sheet's table: label, the placement error in mm, the grasp's measures and the varied
    object quantities (lengths in mm)."""
    table = []
    for row in rows or []:
        scenario = row.get("scenario", {})
        entry: dict[str, Any] = {"label": scenario.get("label", "")}
        for key, source, scale in SCENARIO_COLUMNS:
            value = scenario.get(source, row.get(source))
            if value is None:
                continue
            entry[key] = bool(value) if key == "holds" else (
                value if isinstance(value, str) else float(value) * scale)
        varied = {k: v for k, v in scenario.items()
                  if k not in ("label", "dx_m", "dy_m")}
        entry["object"] = dict(_mm(k, v) for k, v in varied.items())
        table.append(entry)
    return table


def _conditions(obj: dict[str, Any], metrics: dict[str, Any]) -> dict[str, Any]:
    """What the design depends on: friction, strain limit, placement tolerance, payload."""
    scenarios = obj.get("scenarios") or {}
    payload = metrics.get("payload_n")

    def given(value: Any) -> Any:
        return NOT_MODELLED if value is None else value

    return {
        "friction_coefficient": obj.get("friction_coefficient"),
        "strain_limit": obj.get("strain_limit"),
        "placement_tolerance_along_mm": float(scenarios.get("placement_along_m") or 0.0) * MM,
        "placement_tolerance_across_mm": float(scenarios.get("placement_across_m") or 0.0) * MM,
        "density_kg_m3": given(obj.get("density_kg_m3")),
        "payload_factor": given(obj.get("payload_factor")),
        "payload_n": given(payload),
        "grip_force_n": given(metrics.get("grip_force_n")),
    }


def build_sheet(design: dict[str, float], obj: dict[str, Any],
                metrics: dict[str, Any] | None = None,
                scenario_rows: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """The design as a builder needs it, every length in millimetres.

    Parameters
    ----------
    design
        A design in SI units (keys of :data:`envs.scene.DESIGN_FIELDS` and, for grooved jaws,
        of :data:`envs.model.jaw.JAW_FIELDS`, :data:`~envs.model.jaw.LEFT_JAW_FIELDS`).
    obj
        The object (``radius_m``, ``torsion_stiffness_nm_per_rad`` and, where known, ``name``,
        the material fields, ``strain_limit``, ``friction_coefficient``, ``scenarios``,
        ``density_kg_m3``, ``payload_factor``), as in :attr:`optim.result.OptimResult.object`.
    metrics
        The design's grasp metrics (jaw angles, forces, ``payload_n``, ``grip_force_n`` ...),
        copied in where present.
    scenario_rows
        The design under every scenario (``extra["scenario_rows"]`` of a result), or ``None``.

    Returns
    -------
    dict
        ``rows`` (the gripper's quantities of :data:`ROWS`), ``conditions`` (what the design
        depends on, :data:`CONDITION_ROWS`; the payload ``"not modelled"`` where the result has
        none), ``assembly`` (``"stacked"`` or ``"side by side"``) and ``assembly_note``,
        ``fixed_centre``, ``tolerances`` (the placement tolerance, the object's ranges in mm
        and what is not analysed), ``scenarios`` (a row per scenario), ``finger_outline_mm``
        (the corners of the right and left finger at rest), ``joints_mm``,
        ``object_centre_mm``, ``object``, ``jaws`` (each finger's jaw profile: ``kind``
        "straight", or the groove's dimensions of :data:`JAW_ROWS` and its centre on the face;
        ``same`` when both fingers are alike), with a groove ``finger_outline_bulge`` (the
        bulge ``tan(theta / 4)`` of each outline segment to the next vertex, 0 a line, as a DXF
        polyline has it) and, with metrics, ``grasp`` (closing angles in degrees, forces in N,
        peak compression, required friction).

    Raises
    ------
    ValueError
        If the design lacks a field (or some of a finger's jaw fields), the object its radius
        or joint spring, or a groove does not fit its finger.
    """
    missing = [k for k in DESIGN_FIELDS if k not in design]
    if missing:
        raise ValueError(f"design is missing {missing}")
    if "torsion_stiffness_nm_per_rad" not in obj or "radius_m" not in obj:
        raise ValueError("obj needs radius_m and torsion_stiffness_nm_per_rad")
    ln, th0, d3, w, torque, d1 = (float(design[k]) for k in DESIGN_FIELDS)
    r, kf = float(obj["radius_m"]), float(obj["torsion_stiffness_nm_per_rad"])
    outline = _object_outline(obj, d1)  # an object that is not a disk, or None
    lift = r if outline is None else outline["lift_m"]
    metrics = dict(metrics or {})
    values = {
        "finger_length_mm": ln * MM, "finger_width_mm": w * MM,
        "rest_angle_deg": math.degrees(th0), "joint_offset_mm": d3 * MM,
        "joint_spacing_mm": 2 * d3 * MM, "joint_end_overlap_mm": (w - 2 * d3) * MM,
        "object_distance_mm": d1 * MM, "object_centre_y_mm": (d1 + lift) * MM,
        "object_diameter_mm": 2 * r * MM, "torque_nm": torque,
        "torsion_stiffness_nm_per_rad": kf,
        "torsion_stiffness_nmm_per_deg": kf * MM * math.pi / 180.0,
    }
    jaws = jaws_of_design(design)
    outlines = {name: _finger_outline_mm(ln, th0, d3, w, side, jaws[side])
                for side, name in enumerate(FINGERS)}
    conditions = _conditions(obj, metrics)
    assembly, note = assembly_of(d3, w)
    ranges = (obj.get("scenarios") or {}).get("ranges") or {}
    sheet: dict[str, Any] = {
        "object": dict(_mm(k, obj.get(k)) for k in OBJECT_KEYS),
        "rows": [{"quantity": key, "value": values[key], "unit": unit, "meaning": text}
                 for key, unit, text in ROWS],
        "conditions": [{"quantity": key, "value": conditions[key], "unit": unit,
                        "meaning": text} for key, unit, text in CONDITION_ROWS],
        "assembly": assembly,
        "assembly_note": note,
        "fixed_centre": FIXED_CENTRE_NOTE,
        "tolerances": {
            "placement_along_mm": conditions["placement_tolerance_along_mm"],
            "placement_across_mm": conditions["placement_tolerance_across_mm"],
            "object_ranges": dict(_mm(k, v) for k, v in ranges.items()),
            "dimensions": DIMENSIONS_NOTE,
        },
        "scenarios": _scenario_table(scenario_rows),
        "frame": "origin midway between the joints, x to the right, y up the symmetry axis "
                 "towards the object; fingers at rest; millimetres",
        "joints_mm": [[d3 * MM, 0.0], [-d3 * MM, 0.0]],
        "object_centre_mm": [0.0, (d1 + lift) * MM],
        "finger_outline_mm": {name: [[round(float(v), 4) for v in vertex[[V_X, V_Y]]]
                                     for vertex in outline]
                              for name, outline in outlines.items()},
        "jaws": _jaws(jaws, ln, th0, d3, w, r),
    }
    if outline is not None:
        # the object's outline at its orientation, as placed (its area-equivalent radius r)
        sheet["object_outline_mm"] = outline["points_mm"]
        sheet["object_shape"] = outline["shape"]
        turn = (obj.get("scenarios") or {}).get("orientation_tolerance_rad")
        if turn:
            sheet["tolerances"]["orientation_deg"] = math.degrees(float(turn))
    if any(jaw.depth_m > 0.0 for jaw in jaws):
        # (+ 0.0: a straight segment's bulge is 0, never -0)
        sheet["finger_outline_bulge"] = {name: [float(b) + 0.0 for b in outline[:, V_BULGE]]
                                         for name, outline in outlines.items()}
    if metrics:
        grasp: dict[str, Any] = {}
        if metrics.get("jaw_angles_rad") is not None:
            grasp["closed_angles_deg"] = [math.degrees(float(a))
                                          for a in metrics["jaw_angles_rad"]]
        for key in GRASP_KEYS:
            if metrics.get(key) is not None:
                grasp[key] = metrics[key]
        sheet["grasp"] = grasp
    return sheet


def _object_outline(obj: dict[str, Any], distance_m: float) -> dict[str, Any] | None:
    """An object's outline as the sheet states it (``None`` for a disk): its shape and
    dimensions, its centre's height above its lowest point [m] and its points at rest in the
    drawing's frame [mm], as placed ``distance_m`` above the joints' line."""
    if obj.get("outline_coefficients") is None:
        return None
    from envs.objects import as_object, outline_fields
    from envs.scene import SoftDisk

    disk = as_object(SoftDisk(float(obj["radius_m"]), distance_m), **outline_fields(obj))
    shape = {k: v for k, v in obj.items()
             if k in ("shape", "semi_axes_m", "sides_m", "corner_radius_m", "exponent",
                      "size_m")}
    shape["orientation_deg"] = math.degrees(float(obj.get("orientation_rad", 0.0)))
    points = disk.contour_m(OUTLINE_POINTS) * MM
    return {"shape": shape, "lift_m": disk.lift_m,
            "points_mm": [[round(float(x), 4), round(float(y), 4)] for x, y in points]}


def _dimension(ax, p: np.ndarray, q: np.ndarray, offset: np.ndarray, text: str,
               at: float = 0.5) -> None:
    """A dimension line from p to q [mm], drawn ``offset`` [mm] aside, with extension lines,
    its text ``at`` that fraction of the way from p to q."""
    a, b = p + offset, q + offset
    for start, end in ((p, a), (q, b)):
        ax.plot(*zip(start, end, strict=True), color="0.45", lw=0.6)
    ax.annotate("", a, b, arrowprops={"arrowstyle": "<->", "color": "0.2", "lw": 0.8})
    mid = a + at * (b - a)
    ax.text(*mid, text, fontsize=8, ha="center", va="center",
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none"})


def _finger_vertices(sheet: dict[str, Any], side: str) -> np.ndarray:
    """A finger's outline in the sheet [mm] with its bulges (zero for straight jaws)."""
    corners = np.asarray(sheet["finger_outline_mm"][side], dtype=float)
    bulges = (sheet.get("finger_outline_bulge") or {}).get(side)
    return np.column_stack([corners, np.zeros(len(corners)) if bulges is None else bulges])


def _finger_shapes(sheet: dict[str, Any]) -> dict[str, np.ndarray]:
    """Each finger's outline as a polygon [mm], the groove's arcs sampled."""
    return {side: outline_polygon(_finger_vertices(sheet, side)) for side in FINGERS}


def _draw_fingers(ax, sheet: dict[str, Any], w: float, legend: bool = True) -> None:
    """The two fingers at rest [mm]; stacked ones with the left finger behind the right one
    (hatched, its hidden edges dashed) and the circles their joint ends sweep."""
    outline = _finger_shapes(sheet)
    if sheet["assembly"] != ASSEMBLY_STACKED:
        for side in FINGERS:
            ax.add_patch(Polygon(outline[side], closed=True, facecolor="0.8", edgecolor="0.2",
                                 lw=1.0))
        return
    ax.add_patch(Polygon(outline["left"], closed=True, facecolor="0.93", edgecolor="0.2",
                         hatch="////", lw=1.0, zorder=1, label="left finger (behind)"))
    ax.add_patch(Polygon(outline["right"], closed=True, facecolor="0.8", edgecolor="0.2",
                         lw=1.0, zorder=2, label="right finger (in front)"))
    ax.add_patch(Polygon(outline["left"], closed=True, fill=False, edgecolor="0.2",
                         linestyle=(0, (3, 2)), lw=0.8, zorder=3))
    for x, y in sheet["joints_mm"]:
        ax.add_patch(Circle((x, y), w / 2, fill=False, edgecolor="tab:red", lw=0.8,
                            linestyle=":", zorder=3))
    if legend:
        ax.legend(loc="upper right", fontsize=7, framealpha=0.9)


def _jaw_lines(sheet: dict[str, Any]) -> list[str]:
    """The jaw profiles, a line per distinct one, for the drawing's notes."""
    lines = []
    for side, entry in _jaw_groups(sheet):
        whose = "jaws, both fingers" if side is None else f"jaw, {side} finger"
        if entry["kind"] == STRAIGHT_JAW_TEXT:
            lines.append(f"{whose}: straight (a flat gripping face, no groove)")
            continue
        # a cradle has no flanks, a V no bottom arc: each is stated where it has one
        shape = ([f"bottom radius R = {entry['bottom_radius_mm']:.3f} mm"]
                 if entry["bottom_radius_mm"] > 0.0 else []) + (
            [f"opening angle {entry['opening_angle_deg']:.1f}°"]
            if entry["opening_angle_deg"] > 0.0 else [])
        lines.append(
            f"{whose}: {entry['kind']} groove, depth h = {entry['depth_mm']:.3f} mm, "
            + ", ".join(shape) + f", centre a = {entry['position_mm']:.3f} mm from the joint "
            f"axis, mouth {entry['mouth_width_mm']:.3f} mm wide (its edges rounded "
            f"{entry['mouth_edge_radius_mm']:.3g} mm in the model)")
    return lines


def _condition_lines(sheet: dict[str, Any]) -> list[str]:
    """What the design depends on, a line each, for the drawing's notes."""
    cond = {row["quantity"]: row["value"] for row in sheet["conditions"]}
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}

    def number(key: str, fmt: str) -> str:
        value = cond.get(key)
        return value if isinstance(value, str) or value is None else format(value, fmt)

    tol = sheet["tolerances"]
    ranges = "; ".join(f"{k} {v[0]:.4g} to {v[1]:.4g}" for k, v in tol["object_ranges"].items())
    payload = cond["payload_n"]
    payload_line = (f"payload: {NOT_MODELLED} (the grasp was judged without the object's weight)"
                    if isinstance(payload, str) else
                    f"payload W = {payload:.4g} N (density {number('density_kg_m3', '.4g')} "
                    f"kg/m^3, factor {number('payload_factor', '.3g')}); grip force "
                    f"{number('grip_force_n', '.4g')} N")
    along, across = tol["placement_along_mm"], tol["placement_across_mm"]
    placement = (f"placement tolerance: +-{along:.3g} mm along the axis, +-{across:.3g} mm "
                 "across" if along or across else
                 "placement tolerance: none (the object at its nominal place only)")
    return [
        f"actuation torque T_a = {rows['torque_nm']:.4g} N·m on each finger; joint spring k_f = "
        f"{rows['torsion_stiffness_nm_per_rad']:.4g} N·m/rad "
        f"({rows['torsion_stiffness_nmm_per_deg']:.4g} N·mm/deg), opening",
        *_jaw_lines(sheet),
        f"assembly: {sheet['assembly'].upper()}. {sheet['assembly_note']}",
        f"friction coefficient mu = {number('friction_coefficient', '.3g')} (fingers on the "
        f"object); strain limit {number('strain_limit', '.3g')}",
        payload_line,
        placement + (f"; object ranges: {ranges}" if ranges else ""),
        *_shape_lines(sheet),
        f"fixed centre (+ in the drawing): {sheet['fixed_centre']}",
        tol["dimensions"],
    ]


def _shape_lines(sheet: dict[str, Any]) -> list[str]:
    """The object's outline (not a disk), a line for the drawing's notes (none for a disk)."""
    shape = sheet.get("object_shape")
    if not shape:
        return []
    dims = ", ".join(f"{k.replace('_m', '')} {_lengths_mm(v)}" for k, v in shape.items()
                     if k.endswith("_m"))
    turn = sheet["tolerances"].get("orientation_deg")
    return [f"object: {shape.get('shape', 'outline')}" + (f" ({dims} mm)" if dims else "")
            + f", orientation {shape['orientation_deg']:.1f}° (first axis from x, ccw), drawn "
            "as placed" + (f"; orientation tolerance +-{turn:.3g}°" if turn else "")
            + "; r is its area-equivalent radius sqrt(A / pi)"]


def _lengths_mm(value: Any) -> str:
    """A length or a list of lengths [m] in mm, for a note."""
    if isinstance(value, list | tuple):
        return " x ".join(f"{float(v) * MM:.3g}" for v in value)
    return f"{float(value) * MM:.3g}"


def _scenario_cells(sheet: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The scenario table as text cells: header, rows."""
    header = ["scenario", "dx [mm]", "dy [mm]", "reward", "holds", "peak compr.",
              "req. friction"]
    has_payload = any("payload_n" in row for row in sheet["scenarios"])
    if has_payload:
        header += ["payload [N]", "grip [N]"]
    cells = []
    for row in sheet["scenarios"]:
        # the result's labels name quantities in SI ("dx_m+"); the sheet's table is in mm
        label = " ".join(part.replace("_m", "", 1) if part[:-1].endswith("_m") else part
                         for part in row["label"].split())
        line = [label, f"{row.get('dx_mm', 0.0):+.3g}", f"{row.get('dy_mm', 0.0):+.3g}",
                f"{row.get('reward', math.nan):.4f}", "yes" if row.get("holds") else "no",
                f"{row.get('peak_compression', math.nan):.3f}",
                _text(row.get("required_friction"), ".3g")]
        if has_payload:
            line += [_text(row.get("payload_n"), ".3g"), _text(row.get("grip_force_n"), ".3g")]
        cells.append(line)
    return header, cells


def _text(value: Any, fmt: str) -> str:
    """A number formatted, or the text a result holds instead (``"inf"``, "not modelled")."""
    if value is None:
        return "-"
    return value if isinstance(value, str) else format(float(value), fmt)


def _note_text(sheet: dict[str, Any], width: int) -> str:
    """The drawing's notes, wrapped to ``width`` characters."""
    import textwrap

    return "\n".join(textwrap.fill(line, width) for line in _condition_lines(sheet))


def _draw_joint_detail(ax, sheet: dict[str, Any], w: float) -> None:
    """Detail of the joints of stacked fingers, magnified: the overlap, the hidden edges and
    the circles of radius w/2 the joint ends sweep."""
    _draw_fingers(ax, sheet, w, legend=False)
    for x, y in sheet["joints_mm"]:
        ax.plot([x], [y], "o", color="k", ms=3, zorder=4)
    ax.set_xlim(-1.6 * w, 1.6 * w)
    ax.set_ylim(-0.9 * w, 2.0 * w)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=6)
    ax.set_title(f"detail at the joints [mm]\noverlap w - 2 d3 = "
                 f"{w - 2 * sheet['joints_mm'][0][0]:.3g} mm\n(dotted: joint ends' sweep)",
                 fontsize=7)


def _draw_table(ax, sheet: dict[str, Any]) -> None:
    """The scenario table in an axes of its own."""
    ax.axis("off")
    header, cells = _scenario_cells(sheet)
    table = ax.table(cellText=cells, colLabels=header, loc="upper center",
                     bbox=[0.0, 0.0, 1.0, 1.0])
    table.auto_set_font_size(False)
    table.set_fontsize(6.5)
    ax.set_title("scenarios: the design under every object and placement it was checked for "
                 "(dx across, dy along the axis)", fontsize=8)


def _jaw_profiles(sheet: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """The grooved jaw profiles to detail: (whose, entry), once for fingers alike."""
    return [("both fingers'" if side is None else f"{side} finger's", entry)
            for side, entry in _jaw_groups(sheet) if entry["kind"] != STRAIGHT_JAW_TEXT]


def _jaw_of_entry(entry: dict[str, Any]) -> JawProfile:
    """A sheet's jaw entry [mm, deg] as the profile in SI units."""
    return JawProfile(entry["depth_mm"] / MM, entry["bottom_radius_mm"] / MM,
                      math.radians(entry["opening_angle_deg"]), entry["position_mm"] / MM)


def _dimension_grooves(ax, sheet: dict[str, Any], offset: float) -> None:
    """In the drawing [mm]: each grooved finger's groove centre line across the finger and its
    distance ``a`` from the joint, dimensioned along the finger's back ``offset`` outside it."""
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    w, d3 = rows["finger_width_mm"], rows["joint_offset_mm"]
    th0 = math.radians(rows["rest_angle_deg"])
    for name, entry in _jaw_groups(sheet):
        if entry["kind"] == STRAIGHT_JAW_TEXT:
            continue
        side = FINGERS.index(name or "right")  # fingers alike: dimensioned on the right one
        a = entry["position_mm"]
        joint_back, back, face = finger_to_drawing(
            [[0.0, -w / 2], [a, -w / 2], [a, w / 2]], th0, d3, side)
        outward = (back - face) / w
        ax.plot(*zip(face, back + 0.4 * offset * outward, strict=True), color="0.3", lw=0.6,
                ls="-.")
        # its text near the groove, clear of the dimensions about the joints
        _dimension(ax, joint_back, back, offset * outward, f"a = {a:.2f}", at=0.75)


def _draw_jaw_detail(ax, entry: dict[str, Any], length: float, width: float, whose: str
                     ) -> None:
    """A jaw profile magnified in the finger's own frame [mm] (the joint to the left, the
    gripping face up): the groove with its mouth width, depth, bottom radius and opening angle
    dimensioned, its centre line ``a`` from the joint axis."""
    jaw = _jaw_of_entry(entry)
    outline = finger_outline(length / MM, math.pi / 2, 0.0, width / MM, 0, jaw)
    outline[:, [V_X, V_Y]] *= MM
    ax.add_patch(Polygon(outline_polygon(outline), closed=True, facecolor="0.8",
                         edgecolor="0.2", lw=1.0))
    a, h, hw = entry["position_mm"], entry["depth_mm"], width / 2
    radius, mouth = entry["bottom_radius_mm"], entry["mouth_width_mm"] / 2
    half = math.radians(entry["opening_angle_deg"]) / 2
    span = max(2.6 * mouth, 1.3 * width)  # the detail's half-width
    # room above the face for the dimensions, enough for their text on a thin finger
    headroom = max(0.75 * width, 0.25 * span)
    top = hw + headroom  # the detail's upper edge
    ax.plot([a, a], [-hw - 0.1 * width, hw + 0.8 * headroom], color="0.3", lw=0.6, ls="-.")
    _dimension(ax, np.array([a - mouth, hw]), np.array([a + mouth, hw]),
               np.array([0.0, 0.5 * headroom]), f"mouth {2 * mouth:.2f}")
    _dimension(ax, np.array([a, hw]), np.array([a, hw - h]), np.array([1.5 * mouth, 0.0]),
               f"h = {h:.2f}")
    centre = np.array([a, hw - (h - radius)])  # the bottom arc's centre
    if radius > 0.0:
        # a radius dimension along a radius, off the centre line, from the centre or, where
        # that lies above the detail (a shallow cradle), from the detail's top
        lean = -0.5 * min(math.pi / 2 - half, math.acos(min(max((radius - h) / radius, -1.0),
                                                               1.0)))
        ray = np.array([math.sin(lean), -math.cos(lean)])
        wall = centre + radius * ray
        high = hw + 0.8 * headroom  # above the mouth's dimension
        start = centre if centre[1] <= high else centre + ray * (centre[1] - high) / -ray[1]
        ax.annotate(f"R {radius:.2f}", wall, start, fontsize=7, ha="right", va="center",
                    arrowprops={"arrowstyle": "->", "color": "0.2", "lw": 0.8})
    lowest = hw - h
    if half > 0.0:
        # the flanks, extended to where they meet, and the angle between them
        apex = np.array([a, hw - (h - radius + radius / math.sin(half))])
        lowest = apex[1]
        for sign in (-1.0, 1.0):
            ax.plot([a + sign * mouth, apex[0]], [hw, apex[1]], color="0.45", lw=0.6, ls=":")
        swing = 0.6 * (hw - apex[1])
        ax.add_patch(Arc(apex, 2 * swing, 2 * swing, theta1=90 - math.degrees(half),
                         theta2=90 + math.degrees(half), color="0.2", lw=0.8))
        # right of the centre line: the radius' text stands left of it
        ax.text(a + 0.1 * mouth, apex[1] + 1.08 * swing, f"{entry['opening_angle_deg']:.1f}°",
                fontsize=7, ha="left", va="bottom",
                bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none"})
    ax.set_xlim(max(a - span, -0.05 * length), min(a + span, 1.05 * length))
    ax.set_ylim(min(-hw, lowest) - 0.15 * width, top)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=6)
    ax.set_title(f"{whose} jaw: {entry['kind']} [mm]\n(finger's frame, joint axis at 0; "
                 f"groove centre a = {a:.2f})", fontsize=7)


def drawing_figure(sheet: dict[str, Any], title: str | None = None) -> Figure:
    """A dimensioned drawing of a build sheet's gripper at rest with its object [mm], a detail of
    each grooved jaw profile, the notes a workshop needs (jaws, assembly, friction, payload,
    tolerances, the fixed centre) and the scenario table below it."""
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    ln, w, d3 = rows["finger_length_mm"], rows["finger_width_mm"], rows["joint_offset_mm"]
    th0 = math.radians(rows["rest_angle_deg"])
    r = rows["object_diameter_mm"] / 2
    centre = np.array(sheet["object_centre_mm"])
    stacked = sheet["assembly"] == ASSEMBLY_STACKED
    notes = _note_text(sheet, 80 if stacked else 115)
    profiles = _jaw_profiles(sheet)
    # rows of the figure: the drawing, the jaw details (grooved jaws only), the notes, the
    # scenario table (with scenarios only)
    heights = {"drawing": 6.4, "jaws": 2.3 if profiles else 0.0,
               "notes": max(2.2 if stacked else 0.0, 0.12 * (notes.count("\n") + 1) + 0.1),
               "table": 0.17 * (len(sheet["scenarios"]) + 1) + 0.3 if sheet.get("scenarios")
               else 0.0}
    heights = {key: value for key, value in heights.items() if value > 0.0}
    fig = Figure(figsize=(7.2, sum(heights.values())), dpi=110)
    grid = dict(zip(heights, fig.add_gridspec(len(heights), 1,
                                              height_ratios=list(heights.values())),
                    strict=False))
    ax = fig.add_subplot(grid["drawing"])
    _draw_fingers(ax, sheet, w)
    if sheet.get("object_outline_mm"):
        ax.add_patch(Polygon(np.asarray(sheet["object_outline_mm"]), closed=True,
                             facecolor="tab:orange", alpha=0.3, edgecolor="k"))
    else:
        ax.add_patch(Circle(centre, r, facecolor="tab:orange", alpha=0.3, edgecolor="k"))
    ax.plot([centre[0]], [centre[1]], "+", color="k", ms=8)
    for x, _ in sheet["joints_mm"]:
        ax.plot([x], [0.0], "o", color="k", ms=4, zorder=4)
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
    bottom = (centre - np.array([0.0, r]) if not sheet.get("object_outline_mm")
              else np.array([centre[0], rows["object_distance_mm"]]))
    _dimension(ax, np.array([0.0, 0.0]), bottom, np.array([-1.3 * gap - r, 0.0]),
               f"d1 = {rows['object_distance_mm']:.2f}")
    _dimension(ax, centre - np.array([r, 0.0]), centre + np.array([r, 0.0]),
               np.array([0.0, r + gap]), f"2r = {2 * r:.2f}" if not sheet.get(
                   "object_outline_mm") else f"2r_eq = {2 * r:.2f}")
    _dimension_grooves(ax, sheet, 2.2 * gap)
    arc_r = 0.35 * ln
    ax.plot([d3, d3], [0.0, arc_r * 1.1], color="0.45", lw=0.6, ls="--")
    ax.add_patch(Arc((d3, 0.0), 2 * arc_r, 2 * arc_r, theta1=90 - math.degrees(th0), theta2=90,
                     color="0.2", lw=0.8))
    ax.text(d3 - 0.02 * ln, 1.1 * arc_r, f"θ0 = {rows['rest_angle_deg']:.1f}°", fontsize=8,
            ha="right", va="center")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.12)
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.grid(alpha=0.2)
    name = (sheet.get("object") or {}).get("name") or "the object"
    ax.set_title(title or f"gripper for {name}, at rest (millimetres), fingers "
                 f"{sheet['assembly']}", fontsize=10)
    if profiles:
        cells = grid["jaws"].subgridspec(1, len(profiles))
        for cell, (whose, entry) in zip(cells, profiles, strict=False):
            _draw_jaw_detail(fig.add_subplot(cell), entry, ln, w, whose)
    if stacked:
        cells = grid["notes"].subgridspec(1, 2, width_ratios=[2.6, 1.0])
        note_ax = fig.add_subplot(cells[0])
        _draw_joint_detail(fig.add_subplot(cells[1]), sheet, w)
    else:
        note_ax = fig.add_subplot(grid["notes"])
    note_ax.axis("off")
    note_ax.text(0.0, 1.0, notes, fontsize=7, va="top", ha="left", transform=note_ax.transAxes)
    if "table" in grid:
        _draw_table(fig.add_subplot(grid["table"]), sheet)
    fig.tight_layout()
    return fig


def _csv_value(value: Any, digits: str) -> str:
    """A CSV cell: text as it is, a flag as True/False, a number to ``digits``."""
    if isinstance(value, (str, bool, np.bool_)):
        return str(value)
    return "" if value is None else format(float(value), digits)


def _write_design_csv(path: Path, sheet: dict[str, Any], scenarios_file: str) -> None:
    """The sheet as one table: quantity, value, unit, meaning."""
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["quantity", "value", "unit", "meaning"])
        for row in (*sheet["rows"], *jaw_rows(sheet), *sheet["conditions"]):
            writer.writerow([row["quantity"], _csv_value(row["value"], ".6g"), row["unit"],
                             row["meaning"]])
        writer.writerow(["assembly", sheet["assembly"], "", sheet["assembly_note"]])
        writer.writerow(["fixed_centre", "yes", "", sheet["fixed_centre"]])
        for key, (low, high) in sheet["tolerances"]["object_ranges"].items():
            unit = "mm" if key.endswith("_mm") else ""
            writer.writerow([f"range_{key}", f"{low:.6g} to {high:.6g}", unit,
                             "object range the design was checked under"])
        writer.writerow(["dimensional_tolerances", NOT_MODELLED, "",
                         sheet["tolerances"]["dimensions"]])
        writer.writerow(["scenarios", len(sheet["scenarios"]), "",
                         f"one row each in {scenarios_file}" if sheet["scenarios"]
                         else "none: the object at its nominal place only"])
        grooved = "finger_outline_bulge" in sheet
        order = ("joint end back, joint end face, the groove's vertices from the joint side, "
                 "tip face, tip back" if grooved else
                 "joint end back, joint end face, tip face, tip back")
        for side in FINGERS:
            for k, (x, y, bulge) in enumerate(_finger_vertices(sheet, side)):
                writer.writerow([f"{side}_finger_corner_{k}_x_mm", f"{x:.4f}", "mm",
                                 f"finger outline at rest ({order})"])
                writer.writerow([f"{side}_finger_corner_{k}_y_mm", f"{y:.4f}", "mm", ""])
                if grooved:
                    writer.writerow([f"{side}_finger_corner_{k}_bulge", f"{bulge:.6g}", "-",
                                     "to the next corner: 0 a line, else an arc of included "
                                     "angle 4 atan(bulge), counterclockwise if > 0 (DXF)"])


def _write_scenarios_csv(path: Path, sheet: dict[str, Any]) -> None:
    """The scenario table: a row per scenario, the varied object quantities in columns."""
    varied = sorted({k for row in sheet["scenarios"] for k in row["object"]})
    measures = [key for key, _, _ in SCENARIO_COLUMNS
                if any(key in row for row in sheet["scenarios"])]
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["label", *measures, *varied])
        for row in sheet["scenarios"]:
            writer.writerow([row["label"], *(_csv_value(row.get(k), ".6g") for k in measures),
                             *(_csv_value(row["object"].get(k), ".6g") for k in varied)])


def dxf_available() -> bool:
    """Whether the DXF can be written (the optional extra ``dxf``: ezdxf)."""
    import importlib.util

    return importlib.util.find_spec("ezdxf") is not None


def write_dxf(sheet: dict[str, Any], path: str | Path) -> Path:
    """The fingers' outlines at rest as a DXF in millimetres, the format a laser cutter or a CNC
    shop takes: a closed polyline per finger on its own layer (:data:`DXF_LAYERS`), a groove's
    bottom arc as an arc of the polyline (a bulge; flanks and faces as lines), the joint
    centres as points with a cross, and the object's outline for reference, in the sheet's
    frame (origin midway between the joints, y up the symmetry axis).

    Raises
    ------
    ValueError
        Without ezdxf (the extra ``dxf``), with the install hint.
    """
    if not dxf_available():
        raise ValueError("the DXF needs ezdxf: pip install -e '.[dxf]'")
    import ezdxf

    doc = ezdxf.new("R2010", setup=True)
    doc.header["$INSUNITS"] = DXF_MILLIMETRES
    doc.header["$MEASUREMENT"] = 1  # metric
    space = doc.modelspace()
    for key, name in DXF_LAYERS.items():
        doc.layers.add(name, color={"right": 1, "left": 5, "joints": 7, "object": 8}[key])
    for side in FINGERS:
        # a groove's arcs are true arcs of the polyline (bulges), as a cutter follows them
        space.add_lwpolyline(_finger_vertices(sheet, side).tolist(), format="xyb", close=True,
                             dxfattribs={"layer": DXF_LAYERS[side]})
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    mark = 0.25 * rows["finger_width_mm"]
    for x, y in sheet["joints_mm"]:
        attribs = {"layer": DXF_LAYERS["joints"]}
        space.add_point((x, y), dxfattribs=attribs)
        space.add_line((x - mark, y), (x + mark, y), dxfattribs=attribs)
        space.add_line((x, y - mark), (x, y + mark), dxfattribs=attribs)
    if sheet.get("object_outline_mm"):
        space.add_lwpolyline(sheet["object_outline_mm"], format="xy", close=True,
                             dxfattribs={"layer": DXF_LAYERS["object"]})
    else:
        space.add_circle(sheet["object_centre_mm"], rows["object_diameter_mm"] / 2,
                         dxfattribs={"layer": DXF_LAYERS["object"]})
    doc.saveas(Path(path))
    return Path(path)


def write_build_sheet(design: dict[str, float], obj: dict[str, Any], out_dir: str | Path,
                      prefix: str, metrics: dict[str, Any] | None = None,
                      scenario_rows: list[dict[str, Any]] | None = None) -> dict[str, Path]:
    """Write ``{prefix}_design.json``, ``{prefix}_design.csv`` and ``{prefix}_drawing.png``,
    with scenarios ``{prefix}_scenarios.csv``, and with ezdxf the outlines
    ``{prefix}_fingers.dxf`` (:func:`write_dxf`).

    Returns the written paths by kind (``design_json``, ``design_csv``, ``drawing``,
    ``scenarios_csv``, ``dxf``).
    """
    from .result import to_jsonable

    sheet = build_sheet(design, obj, metrics, scenario_rows)
    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"design_json": folder / f"{prefix}_design.json",
             "design_csv": folder / f"{prefix}_design.csv",
             "drawing": folder / f"{prefix}_drawing.png"}
    if sheet["scenarios"]:
        paths["scenarios_csv"] = folder / f"{prefix}_scenarios.csv"
        _write_scenarios_csv(paths["scenarios_csv"], sheet)
    paths["design_json"].write_text(json.dumps(to_jsonable(sheet), indent=1) + "\n")
    _write_design_csv(paths["design_csv"], sheet, f"{prefix}_scenarios.csv")
    fig = drawing_figure(sheet)
    fig.savefig(paths["drawing"])
    if dxf_available():
        paths["dxf"] = write_dxf(sheet, folder / f"{prefix}_fingers.dxf")
    return paths
