"""The build sheet as data: the gripper's rows, what it depends on, the scenarios (see
:mod:`optim.sheet`)."""

from __future__ import annotations

import math
from typing import Any

from envs.render import V_BULGE, V_X, V_Y
from envs.scene import DESIGN_FIELDS

from .common import (
    ASSEMBLY_COMMON_PIVOT,
    ASSEMBLY_SIDE_BY_SIDE,
    ASSEMBLY_STACKED,
    FINGERS,
    MM,
    NOT_MODELLED,
    OUTLINE_POINTS,
)
from .jaws import _finger_outline_mm, _jaws, jaws_of_design

FIXED_CENTRE_NOTE = (
    "The model holds the object's centre fixed while the jaws close, at (0, d1 + r) or, in a "
    "scenario with a placement error, where the object was placed (a displaced object is held "
    "where it was placed). Whether a free object stays put is judged from the friction: the "
    "grasp holds it when the friction coefficient is at least the required friction.")
DIMENSIONS_NOTE = (
    "Manufacturing tolerances: none were checked; the design was checked at its stated (rounded) "
    "dimensions under the placement tolerance and the object ranges listed.")
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
    ("payload_n", "N", "payload W = f m g the grasp must carry: the largest any scenario "
                       "puts on the gripper"),
    ("grip_force_n", "N", "grip force of the grasp (the governing scenario's)"),
)
# the envelopes over the scenarios the sheet states, each under its own name
ENVELOPE_ROWS = ("max_payload_n", "max_required_friction", "max_peak_compression",
                 "min_contact_score", "min_friction_margin", "min_strain_margin",
                 "scenarios_holding", "n_scenarios")
# (key, unit, description) of the rows of a grooved jaw, after a prefix naming the finger(s)
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


def assembly_of(joint_offset_m: float, finger_width_m: float,
                boss_radius_m: float | None = None) -> tuple[str, str]:
    """How the fingers are built: :data:`ASSEMBLY_COMMON_PIVOT` when the joints coincide
    (``d_3 = 0``: both fingers on one pin), :data:`ASSEMBLY_STACKED` when their joint ends
    overlap (``d_3`` less than the boss radius, ``w / 2`` by default), else
    :data:`ASSEMBLY_SIDE_BY_SIDE`; and a sentence saying why.

    Parameters
    ----------
    joint_offset_m
        Joint distance ``d_3`` from the symmetry axis [m].
    finger_width_m
        Finger width ``w`` [m].
    boss_radius_m
        The boss's radius about each pivot [m] (default ``w / 2``,
        :func:`optim.parts.joint.boss_radius`).
    """
    d3, w = float(joint_offset_m), float(finger_width_m)
    radius = w / 2 if boss_radius_m is None else float(boss_radius_m)
    stacked = ("build them stacked, one finger above the other at the joints like the jaws of "
               "forceps (a half-lap keeps their gripping faces in one plane), each gripping face "
               "spanning the object. A gripper that cannot stack its fingers needs a design "
               "with the joints apart (psm-grasp optimize --joints-apart).")
    if d3 == 0.0:
        return ASSEMBLY_COMMON_PIVOT, (
            f"The joints coincide on the axis (d3 = 0 at the resolution): both fingers turn on "
            f"one pin, a common pivot, and overlap at the joints by their width w = "
            f"{w * MM:.4g} mm: " + stacked)
    if d3 < radius:
        return ASSEMBLY_STACKED, (
            f"The joints are closer to the axis than the boss about each pin (d3 = "
            f"{d3 * MM:.4g} mm < {radius * MM:.4g} mm, half a finger width w/2 by default), so "
            f"the fingers overlap at the joints by w - 2 d3 = {(w - 2 * d3) * MM:.4g} mm: "
            + stacked)
    return ASSEMBLY_SIDE_BY_SIDE, (
        f"The joints are at least a boss radius from the axis (d3 = {d3 * MM:.4g} mm >= "
        f"{radius * MM:.4g} mm, w/2 by default): the fingers' joint ends never meet as they "
        "turn, and the fingers can be built side by side in one plane.")


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
                  if k not in ("label", "dx_m", "dy_m", "design")}
        entry["object"] = dict(_mm(k, v) for k, v in varied.items())
        if scenario.get("design"):
            entry["built"] = built_changes(scenario["design"])
        table.append(entry)
    return table


def built_changes(design: dict[str, float]) -> dict[str, float]:
    """A scenario's changes of the design as built (:mod:`envs.tolerances`) in the sheet's
    units: lengths in mm (``finger_length_mm`` ...), the rest angle in degrees, the torque's
    and the spring's relative changes in percent."""
    out = {}
    for key, value in design.items():
        if key.endswith("_rel"):
            out[key[:-4] + "_percent"] = float(value) * 100.0
        elif key.endswith("_rad"):
            out[key[:-4] + "_deg"] = math.degrees(float(value))
        else:
            out.update([_mm(key, value)])
    return out


def _conditions(obj: dict[str, Any], metrics: dict[str, Any],
                scenario_rows: list[dict[str, Any]] | None = None) -> dict[str, Any]:
    """What the design depends on: friction, strain limit, placement tolerance, payload (the
    largest any scenario puts on the gripper)."""
    scenarios = obj.get("scenarios") or {}
    payloads = [float(r["payload_n"]) for r in scenario_rows or []
                if r.get("payload_n") is not None]
    payload = metrics.get("max_payload_n", max(payloads) if payloads
                          else metrics.get("payload_n"))

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


def _tolerance_text(checked: dict[str, Any]) -> str:
    """The manufacturing tolerances the design was checked under, in words."""
    tol = checked.get("tolerances")
    if not tol:
        return DIMENSIONS_NOTE
    return (f"Manufacturing tolerances checked as scenarios: lengths (finger length, width, "
            f"joint offset) +-{tol['length_mm']:g} mm, rest angle +-{tol['angle_deg']:g} deg, "
            f"spring +-{tol['spring_percent']:g} % and torque +-{tol['torque_percent']:g} % "
            "(the weakest and the strongest closing moment), both fingers alike; "
            f"{checked['scenario_set']}.")


def _grasp(metrics: dict[str, Any]) -> dict[str, Any]:
    """The governing scenario's grasp: closing angles in degrees and :data:`GRASP_KEYS`."""
    grasp: dict[str, Any] = {}
    if metrics.get("governing_scenario") is not None:
        grasp["scenario"] = metrics["governing_scenario"]
    if metrics.get("jaw_angles_rad") is not None:
        grasp["closed_angles_deg"] = [math.degrees(float(a)) for a in metrics["jaw_angles_rad"]]
    for key in GRASP_KEYS:
        if metrics.get(key) is not None:
            grasp[key] = metrics[key]
    return grasp


def build_sheet(design: dict[str, float], obj: dict[str, Any],
                metrics: dict[str, Any] | None = None,
                scenario_rows: list[dict[str, Any]] | None = None, *,
                parts=None, extra: dict[str, Any] | None = None) -> dict[str, Any]:
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
    parts
        The parts' options (:class:`optim.parts.options.PartOptions`; default the defaults).
    extra
        The result's ``extra`` (which scenario set was checked, the resolution).

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
        peak compression, required friction: the governing scenario's own row, named under
        ``scenario``); ``envelopes`` over the scenarios under their own names (the largest
        payload, friction needed and compression, the smallest contact score and margins);
        ``verdict`` (:func:`optim.design_verdict.verdict_of`: whether it holds in every
        scenario, and its ``banner`` when it does not); ``checked`` (the scenario set,
        placement, ranges, tolerances, resolution and load set); ``parts`` and ``part_rows``
        (pivot, plate, half-lap, pad, spring and stops; each finger's part, :mod:`optim.parts`).

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
    lift = r if outline is None else outline["lift_m"]  # its centre above its lowest point
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
    conditions = _conditions(obj, metrics, scenario_rows)
    jaw_entries = _jaws(jaws, ln, th0, d3, w, r)  # (a groove that does not fit: named first)
    from optim.design_verdict import verdict_of

    from .parts import checked_section, part_rows, parts_section

    section, _ = parts_section(design, obj, metrics, scenario_rows, _part_options(parts), jaws)
    assembly, note = assembly_of(d3, w, section["values"]["boss_radius_mm"] / MM)
    checked = checked_section(obj, scenario_rows, extra)
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
            "dimensions": _tolerance_text(checked),
        },
        "verdict": verdict_of(metrics, scenario_rows).as_dict(),
        "checked": checked,
        "parts": section,
        "part_rows": part_rows(section),
        "scenarios": _scenario_table(scenario_rows),
        "frame": "origin midway between the joints, x to the right, y up the symmetry axis "
                 "towards the object; fingers at rest; millimetres",
        "joints_mm": [[d3 * MM, 0.0], [-d3 * MM, 0.0]],
        "object_centre_mm": [0.0, (d1 + lift) * MM],
        "finger_outline_mm": {name: [[round(float(v), 4) for v in vertex[[V_X, V_Y]]]
                                     for vertex in outline]
                              for name, outline in outlines.items()},
        "jaws": jaw_entries,
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
        sheet["grasp"] = _grasp(metrics)
    envelopes = {k: metrics[k] for k in ENVELOPE_ROWS if k in metrics}
    if envelopes:
        sheet["envelopes"] = envelopes
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


def _part_options(parts):
    """The parts' options, the defaults for ``None``."""
    from optim.parts.options import PartOptions

    return PartOptions() if parts is None else parts


