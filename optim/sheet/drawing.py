"""The build sheet's dimensioned drawing (see :mod:`optim.sheet`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Arc, Circle, Polygon

from envs.render import V_X, V_Y, finger_outline, finger_to_drawing, outline_polygon

from .common import ASSEMBLY_SIDE_BY_SIDE, FINGERS, MM, NOT_MODELLED
from .jaws import STRAIGHT_JAW_TEXT, _jaw_groups, _jaw_of_entry


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
    if sheet["assembly"] == ASSEMBLY_SIDE_BY_SIDE:
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
    checked = sheet.get("checked") or {}
    load = f", load set {checked['load_set']}" if checked.get("load_set") else ""
    payload_line = (f"payload: {NOT_MODELLED} (the grasp was judged without the object's weight)"
                    if isinstance(payload, str) else
                    f"payload W = {payload:.4g} N, the largest any scenario puts on the gripper "
                    f"(density {number('density_kg_m3', '.4g')} kg/m^3, factor "
                    f"{number('payload_factor', '.3g')}{load}); grip force "
                    f"{number('grip_force_n', '.4g')} N")
    along, across = tol["placement_along_mm"], tol["placement_across_mm"]
    placement = (f"placement tolerance: +-{along:.3g} mm along the axis, +-{across:.3g} mm "
                 "across" if along or across else
                 "placement tolerance: none (the object at its nominal place only)")
    return [
        *_verdict_lines(sheet),
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
        *_part_lines(sheet),
    ]


def _verdict_lines(sheet: dict[str, Any]) -> list[str]:
    """The verdict and the governing scenario, for the notes."""
    lines = []
    verdict = sheet.get("verdict") or {}
    if verdict.get("banner"):
        lines.append(f"WARNING: {verdict['banner']}: do not build it as a gripper that holds.")
    grasp = sheet.get("grasp") or {}
    env = sheet.get("envelopes") or {}
    if grasp.get("scenario"):
        total = verdict.get("scenarios", 0)
        lines.append(
            f"governing scenario (the lowest reward; its own grasp is stated): "
            f"{grasp['scenario']}; over all {total} scenarios: holds in "
            f"{total - verdict.get('failing', 0)}, largest friction needed "
            f"{_text(env.get('max_required_friction'), '.3g')}, largest compression "
            f"{_text(env.get('max_peak_compression'), '.3g')}")
    return lines


def _part_lines(sheet: dict[str, Any]) -> list[str]:
    """The parts (pivot, plate, half-lap, pad, spring, stops), for the notes."""
    parts = sheet.get("parts")
    if not parts:
        return []
    v = {k: "-" if value is None else value for k, value in parts["values"].items()}
    lap = (f"; half-lap {v['half_lap_mm']:.4g} mm from the joint end: {parts['stacking']}"
           if v["half_lap_mm"] else "")
    return [
        f"pivot: {v['pivot']}, pin {v['pin_diameter_mm']:.4g} mm in a boss of radius "
        f"{v['boss_radius_mm']:.4g} mm ({parts['pin_rule']}); plate "
        f"{v['plate_thickness_mm']:.4g} mm{lap}",
        f"pad: {parts['pad']}; friction needed at least {_text(v['pad_friction_min'], '.3g')}",
        f"spring: free angle {v['spring_free_angle_deg']:.4g}° (relaxed at rest), preload "
        f"{v['spring_preload_nmm']:.3g} N·mm, {_text(v['spring_moment_at_grasp_nmm'], '.3g')} "
        f"N·mm at the governing grasp; stops: rest {v['rest_stop_deg']:.4g}°, closing "
        f"{v['closing_stop_deg']:.4g}° (the faces' tips meet at {v['faces_meet_deg']:.3g}°, "
        f"the smallest grasp angle {_text(v['smallest_grasp_angle_deg'], '.3g')}°)",
    ]


def _scenario_cells(sheet: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """The scenario table as text cells: header, rows."""
    header = ["scenario", "dx [mm]", "dy [mm]", "reward", "holds", "peak compr.",
              "req. friction"]
    has_payload = any("payload_n" in row for row in sheet["scenarios"])
    if has_payload:
        header += ["payload [N]", "grip [N]"]
    cells = []
    for row in sheet["scenarios"]:
        label = short_label(row["label"])
        line = [label, f"{row.get('dx_mm', 0.0):+.3g}", f"{row.get('dy_mm', 0.0):+.3g}",
                f"{row.get('reward', math.nan):.4f}", "yes" if row.get("holds") else "no",
                f"{row.get('peak_compression', math.nan):.3f}",
                _text(row.get("required_friction"), ".3g")]
        if has_payload:
            line += [_text(row.get("payload_n"), ".3g"), _text(row.get("grip_force_n"), ".3g")]
        cells.append(line)
    return header, cells


# the drawing's short names of the scenario dimensions (the CSV keeps the result's labels)
SHORT_NAMES = {"radius_m": "r", "youngs_modulus_pa": "E", "poisson_ratio": "nu",
               "thickness_m": "t", "density_kg_m3": "rho", "friction_coefficient": "mu",
               "dx_m": "dx", "dy_m": "dy", "finger_length_m": "l", "finger_width_m": "w",
               "joint_offset_m": "d3", "rest_angle_rad": "θ0", "closing_moment": "M"}


def short_label(label: str) -> str:
    """A scenario's label with short names (``dx_m+ finger_length_m-`` -> ``dx+ l-``)."""
    return " ".join(SHORT_NAMES.get(part[:-1], part[:-1]) + part[-1]
                    if part[-1:] in "+-" and part[:-1] in SHORT_NAMES else part
                    for part in label.split())


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


TABLE_ROWS = 24  # scenario rows the drawing shows at most (the CSV has them all)


def _shown_scenarios(sheet: dict[str, Any]) -> tuple[list[int], int]:
    """The scenario rows the drawing's table shows: all up to :data:`TABLE_ROWS`, else the
    nominal and the lowest rewards; and how many there are."""
    rows = sheet.get("scenarios") or []
    if len(rows) <= TABLE_ROWS:
        return list(range(len(rows))), len(rows)
    order = sorted(range(1, len(rows)), key=lambda i: rows[i].get("reward", math.inf))
    return [0, *sorted(order[:TABLE_ROWS - 1])], len(rows)


def _draw_table(ax, sheet: dict[str, Any]) -> None:
    """The scenario table in an axes of its own."""
    ax.axis("off")
    header, cells = _scenario_cells(sheet)
    shown, total = _shown_scenarios(sheet)
    first = 0.3 if any(len(c[0]) > 12 for c in cells) else 0.16  # the labels' column
    table = ax.table(cellText=[cells[i] for i in shown], colLabels=header,
                     colWidths=[first] + [(1.0 - first) / (len(header) - 1)] * (len(header) - 1),
                     loc="upper center", bbox=[0.0, 0.0, 1.0, 1.0])
    table.auto_set_font_size(False)
    table.set_fontsize(6.5)
    which = ("" if len(shown) == total else
             f";\nthe nominal and the {len(shown) - 1} lowest rewards of {total}: every row in "
             "the scenarios CSV")
    ax.set_title("scenarios: the design under every object, placement and build it was checked "
                 f"for\n(dx across, dy along the axis; M: the closing moment, torque up and "
                 f"spring down{which})", fontsize=7)


def _jaw_profiles(sheet: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """The grooved jaw profiles to detail: (whose, entry), once for fingers alike."""
    return [("both fingers'" if side is None else f"{side} finger's", entry)
            for side, entry in _jaw_groups(sheet) if entry["kind"] != STRAIGHT_JAW_TEXT]



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


def drawing_figure(sheet: dict[str, Any], title: str | None = None) -> Figure:
    """A dimensioned drawing of a build sheet's gripper at rest with its object [mm], a detail of
    each grooved jaw profile, the notes a workshop needs (jaws, assembly, friction, payload,
    tolerances, the fixed centre) and the scenario table below it."""
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    ln, w, d3 = rows["finger_length_mm"], rows["finger_width_mm"], rows["joint_offset_mm"]
    th0 = math.radians(rows["rest_angle_deg"])
    r = rows["object_diameter_mm"] / 2
    centre = np.array(sheet["object_centre_mm"])
    stacked = sheet["assembly"] != ASSEMBLY_SIDE_BY_SIDE
    notes = _note_text(sheet, 80 if stacked else 115)
    profiles = _jaw_profiles(sheet)
    # rows of the figure: the drawing, the jaw details (grooved jaws only), the notes, the
    # scenario table (with scenarios only)
    heights = {"drawing": 6.4, "jaws": 2.3 if profiles else 0.0,
               "notes": max(2.2 if stacked else 0.0, 0.12 * (notes.count("\n") + 1) + 0.1),
               "table": 0.17 * (len(_shown_scenarios(sheet)[0]) + 1) + 0.3
               if sheet.get("scenarios") else 0.0}
    heights = {key: value for key, value in heights.items() if value > 0.0}
    fig = Figure(figsize=(7.2, sum(heights.values())), dpi=110)
    grid = dict(zip(heights, fig.add_gridspec(len(heights), 1,
                                              height_ratios=list(heights.values())),
                    strict=False))
    ax = fig.add_subplot(grid["drawing"])
    _draw_fingers(ax, sheet, w)
    _draw_pivots_and_stops(ax, sheet)
    _draw_object(ax, sheet)
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
    outline = bool(sheet.get("object_outline_mm"))
    # d1 to the object's lowest point (a disk's: below its centre); 2r_eq for an outline
    bottom = (np.array([centre[0], rows["object_distance_mm"]]) if outline
              else centre - np.array([0.0, r]))
    _dimension(ax, np.array([0.0, 0.0]), bottom, np.array([-1.3 * gap - r, 0.0]),
               f"d1 = {rows['object_distance_mm']:.2f}")
    _dimension(ax, centre - np.array([r, 0.0]), centre + np.array([r, 0.0]),
               np.array([0.0, r + gap]), f"{'2r_eq' if outline else '2r'} = {2 * r:.2f}")
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
    banner = (sheet.get("verdict") or {}).get("banner")
    if banner:
        fig.suptitle(banner, color="white", backgroundcolor="tab:red", fontsize=10,
                     fontweight="bold")
    fig.tight_layout()
    return fig


def _draw_object(ax, sheet: dict[str, Any]) -> None:
    """The object at its nominal place [mm] (a disk, or an outline at its orientation), its
    fixed centre marked."""
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    centre = np.array(sheet["object_centre_mm"])
    if sheet.get("object_outline_mm"):
        ax.add_patch(Polygon(np.asarray(sheet["object_outline_mm"]), closed=True,
                             facecolor="tab:orange", alpha=0.3, edgecolor="k"))
    else:
        ax.add_patch(Circle(centre, rows["object_diameter_mm"] / 2, facecolor="tab:orange",
                            alpha=0.3, edgecolor="k"))
    ax.plot([centre[0]], [centre[1]], "+", color="k", ms=8)


def _draw_pivots_and_stops(ax, sheet: dict[str, Any]) -> None:
    """The pivot pins and their bosses, and each finger at its closing stop (dotted) [mm]."""
    from envs.render import finger_outline

    parts = sheet.get("parts")
    if not parts:
        return
    v = parts["values"]
    for x in parts["pin_x_mm"]:
        ax.add_patch(Circle((x, 0.0), v["pin_diameter_mm"] / 2, fill=False, edgecolor="k",
                            lw=0.8, zorder=5))
        ax.add_patch(Circle((x, 0.0), v["boss_radius_mm"], fill=False, edgecolor="0.3",
                            lw=0.6, ls="--", zorder=5))
    rows = {row["quantity"]: row["value"] for row in sheet["rows"]}
    closing = math.radians(v["closing_stop_deg"])
    for side in (0, 1):
        outline = finger_outline(rows["finger_length_mm"], closing, rows["joint_offset_mm"],
                                 rows["finger_width_mm"], side)
        ring = np.vstack([outline[:, :2], outline[:1, :2]])
        ax.plot(ring[:, 0], ring[:, 1], color="tab:blue", lw=0.6, ls=":",
                label="closing stop" if side == 0 else None)

