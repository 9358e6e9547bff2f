"""The build sheet's parts: pivot, plate, stacking, pad, spring and stops, each finger's part
(:mod:`optim.parts`), as a section and as table rows; and what the design was checked for."""

from __future__ import annotations

import math
from typing import Any

from envs.model.jaw import JawProfile

from .common import FINGERS, MM

__all__ = ["parts_section", "part_rows", "checked_section", "PART_ROWS", "DEFAULT_LOAD_SET"]

# what the payload's load set is when a result does not say (the holding model's: every
# in-plane direction and out of the plane)
DEFAULT_LOAD_SET = "any: out of the plane and every in-plane direction"
# (key, unit, description) of the parts' rows
PART_ROWS: tuple[tuple[str, str, str], ...] = (
    ("pivot", "-", "side by side (each finger on its pin, one plane), stacked (each on its "
                   "pin, joint ends overlapping) or common pivot (both on one pin)"),
    ("pin_diameter_mm", "mm", "pivot pin (the hole in each finger's boss)"),
    ("boss_radius_mm", "mm", "the boss about the pivot: the finger's end, a half disk or a disk "
                             "of this radius"),
    ("plate_thickness_mm", "mm", "each finger's plate (out of the plane): at least the object's "
                                 "slice, which its faces must cover"),
    ("half_lap_mm", "mm", "stacked fingers: from the joint end to this far along the finger each "
                          "plate is half as thick (right finger upper half, left lower)"),
    ("pad_from_mm", "mm", "the pad: the gripping face from here to the tip"),
    ("pad_friction_min", "-", "the pad's friction coefficient on the object must be at least "
                              "the largest any scenario needs (the design assumed the "
                              "friction coefficient stated below)"),
    ("spring_free_angle_deg", "deg", "the joint spring's free angle: the rest angle (relaxed at "
                                     "rest, as the model's k_f (theta_a0 - theta))"),
    ("spring_preload_nmm", "N·mm", "the spring's moment at rest"),
    ("spring_moment_at_grasp_nmm", "N·mm", "the spring's opening moment at the governing "
                                           "scenario's grasp"),
    ("rest_stop_deg", "deg", "the rest stop: each finger rests against it at the rest angle"),
    ("closing_stop_deg", "deg", "the closing stop: each finger never closes past it (below "
                                "every grasp angle of every scenario)"),
    ("faces_meet_deg", "deg", "the angle at which the gripping faces' tips meet on the axis"),
    ("smallest_grasp_angle_deg", "deg", "the smallest finger angle of a grasp over the "
                                        "scenarios"),
)


def parts_section(design: dict[str, Any], obj: dict[str, Any], metrics: dict[str, Any],
                  scenario_rows: list[dict[str, Any]] | None, options,
                  jaws: tuple[JawProfile, JawProfile]) -> tuple[dict[str, Any], tuple]:
    """The parts of a design (:mod:`optim.parts`) as the sheet's section, and the two finger
    parts (:class:`~optim.parts.profile.FingerPart`)."""
    from optim.parts.joint import pivot_of
    from optim.parts.spring import smallest_grasp_angle, stops_of

    resolution = None if options is None else options.resolution
    pin = None if options is None else options.pin_diameter_m
    smallest = smallest_grasp_angle(metrics, scenario_rows)
    thickness = float(obj.get("thickness_m") or design["finger_width_m"])
    pivot, parts = pivot_of(design, jaws, thickness, resolution, pin, smallest)
    stops = stops_of(design, float(obj["torsion_stiffness_nm_per_rad"]), smallest,
                     pivot.assembly != "side by side",
                     None if resolution is None else resolution.angle_rad)
    governing = (metrics.get("jaw_angles_rad") or [math.nan])
    need = metrics.get("max_required_friction", metrics.get("required_friction"))
    pad_from = max(pivot.boss_radius_m, pivot.lap_length_m)
    values = {
        "pivot": pivot.assembly, "pin_diameter_mm": pivot.pin_diameter_m * MM,
        "boss_radius_mm": pivot.boss_radius_m * MM,
        "plate_thickness_mm": pivot.plate_thickness_m * MM,
        "half_lap_mm": pivot.lap_length_m * MM, "pad_from_mm": pad_from * MM,
        "pad_friction_min": need if isinstance(need, str) or need is None else float(need),
        "spring_free_angle_deg": math.degrees(stops.free_angle_rad),
        "spring_preload_nmm": stops.preload_nm * MM,
        "spring_moment_at_grasp_nmm": stops.moment_nm(min(map(float, governing))) * MM,
        "rest_stop_deg": math.degrees(stops.rest_rad),
        "closing_stop_deg": math.degrees(stops.closing_rad),
        "faces_meet_deg": math.degrees(stops.faces_meet_rad),
        "smallest_grasp_angle_deg": math.degrees(stops.smallest_grasp_rad),
    }
    # no grasp to judge by (a sheet without metrics): said as null, not as NaN; an angle of
    # 1e-17 degrees is 0
    values = {k: None if isinstance(v, float) and math.isnan(v) else
              round(v, 9) + 0.0 if isinstance(v, float) else v for k, v in values.items()}
    same = jaws[0] == jaws[1]
    section = {
        "values": values, "pin_rule": pivot.pin_rule, "stacking": pivot.stacking,
        "pin_x_mm": [x * MM for x in pivot.pin_x_m],
        "fingers": {side: {"volume_mm3": part.volume_m3 * MM**3,
                           "plate_thickness_mm": part.plate_thickness_m * MM,
                           "half_lap_mm": part.lap_length_m * MM,
                           "frame": "own: x along the finger from the pivot's centre to the tip, "
                                    "the gripping face up (y = w/2), millimetres",
                           "same_as": "right" if side == "left" and same else None}
                    for side, part in zip(FINGERS, parts, strict=True)},
        "pad": f"a pad or coating on the gripping face from {pad_from * MM:.4g} mm to the tip, "
               "friction coefficient on the object at least the design's; a bonded layer "
               "replaces the outer part of the finger's width (the face stays at w/2) and "
               "should stay thin (the model takes the face as rigid)",
    }
    return section, parts


def part_rows(section: dict[str, Any]) -> list[dict[str, Any]]:
    """The parts as table rows (quantity, value, unit, meaning), :data:`PART_ROWS`."""
    return [{"quantity": key, "value": section["values"][key], "unit": unit, "meaning": text}
            for key, unit, text in PART_ROWS]


def checked_section(obj: dict[str, Any], scenario_rows: list[dict[str, Any]] | None,
                    extra: dict[str, Any] | None) -> dict[str, Any]:
    """What the design was checked for: the scenario set and its size, the placement, the
    object's ranges, the manufacturing tolerances (user units), the resolution, the payload's
    load set."""
    from envs.tolerances import Tolerances

    extra = extra or {}
    scenarios = obj.get("scenarios") or {}
    tolerances = Tolerances.from_dict(scenarios.get("tolerances"))
    rows = scenario_rows or []
    kind = extra.get("scenario_set") or ("full" if rows else "nominal")
    return {
        "scenario_set": ("the nominal scenario only" if not rows else
                         f"every corner of the box, its face centres and its centre "
                         f"({len(rows)} scenarios)" if kind == "full" else
                         f"a covering set of the box's corners, its face centres and its "
                         f"centre ({len(rows)} scenarios)"),
        "scenarios": len(rows) or 1,
        "placement_along_mm": float(scenarios.get("placement_along_m") or 0.0) * MM,
        "placement_across_mm": float(scenarios.get("placement_across_m") or 0.0) * MM,
        "object_ranges": sorted(scenarios.get("ranges") or {}),
        "tolerances": None if tolerances.is_zero else tolerances.as_user_units(),
        "resolution": extra.get("resolution"),
        "load_set": obj.get("load_set") or DEFAULT_LOAD_SET,
        "payload_factor": obj.get("payload_factor"),
    }
