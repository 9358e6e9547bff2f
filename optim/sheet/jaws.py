"""The jaw profiles of a build sheet: each finger's groove in millimetres, its rows and
outline (see :mod:`optim.sheet`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from envs.model.geometry import corner_radius
from envs.model.jaw import STRAIGHT, JawProfile, jaws_of_row
from envs.render import V_BULGE, V_X, V_Y, finger_outline, finger_to_drawing
from envs.scene import design_row

from .common import FINGERS, MM

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



def _jaw_of_entry(entry: dict[str, Any]) -> JawProfile:
    """A sheet's jaw entry [mm, deg] as the profile in SI units."""
    return JawProfile(entry["depth_mm"] / MM, entry["bottom_radius_mm"] / MM,
                      math.radians(entry["opening_angle_deg"]), entry["position_mm"] / MM)


