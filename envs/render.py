"""Drawings of a grasp shared by the design environment, the CLI and the scripts.

:func:`draw_grasp` draws on a matplotlib ``Axes``: the fingers at rest (dashed) and at the grasp
angles, each with the groove of its jaw profile (:func:`finger_polygon`), the rest and the
deformed disk, the springs coloured by strain (with a labelled colour bar) and the contact
points, with a legend for each mark.
:func:`grasp_figure` makes a stand-alone figure (saved as PNG when given a path) and
:func:`grasp_rgb_array` renders one off-screen with the Agg canvas, so no pyplot state or GUI
backend is involved.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from .model.jaw import STRAIGHT, JawProfile, jaws_of_row
from .scene import N_DESIGN, Gripper, Scene, SoftDisk
from .validation import check_range

__all__ = [
    "draw_grasp",
    "draw_design",
    "grasp_figure",
    "grasp_rgb_array",
    "figure_rgb_array",
    "finger_polygon",
    "finger_outline",
    "finger_to_drawing",
    "groove_vertices",
    "outline_polygon",
    "object_patch",
    "OUTLINE_COLUMNS",
    "spring_segments",
    "unit_scale",
    "LENGTH_UNITS",
]

# Strain colours: blue compressed, white unstrained, red stretched, always with a labelled
# colour bar; the contact markers use colours that map has none of (green and yellow with a
# black edge), so that no red dot reads as a high strain.
STRAIN_CMAP = "coolwarm"
STRAIN_LABEL = "spring strain [-] (blue: compressed, red: stretched)"
REST_STYLE = {"fill": False, "linestyle": "--", "linewidth": 0.8, "edgecolor": "0.55"}
CONTACT_STYLE = ({"color": "limegreen", "label": "contact, right"},
                 {"color": "gold", "label": "contact, left"})
# the columns of an outline's vertices (finger_outline: x, y in the drawing's frame;
# groove_vertices: s, m in the finger's): two coordinates, then the bulge tan(theta / 4) of the
# segment to the next vertex, as a DXF polyline has it (0 a straight line)
OUTLINE_COLUMNS = ("x", "y", "bulge")
V_X, V_Y, V_BULGE = range(len(OUTLINE_COLUMNS))
# the length units a drawing may use, and metres in each
LENGTH_UNITS = {"m": 1.0, "mm": 1e3}


def unit_scale(length_unit: str) -> float:
    """Drawn units per metre of ``length_unit`` (:data:`LENGTH_UNITS`).

    Raises
    ------
    ValueError
        For a unit not in :data:`LENGTH_UNITS`.
    """
    if length_unit not in LENGTH_UNITS:
        raise ValueError(f"length_unit must be one of {sorted(LENGTH_UNITS)}, got "
                         f"{length_unit!r}")
    return LENGTH_UNITS[length_unit]


def groove_vertices(jaw: JawProfile, width: float) -> np.ndarray:
    """The cutout of a jaw's groove in finger coordinates [m], mouth edges drawn sharp.

    Parameters
    ----------
    jaw
        The finger's jaw profile (:class:`envs.model.jaw.JawProfile`).
    width
        Finger width ``w`` [m]: the gripping face lies at ``m = w/2``.

    Returns
    -------
    numpy.ndarray
        Shape (K, 3), columns :data:`OUTLINE_COLUMNS` (``s`` along the finger from the joint,
        ``m`` along the face's inward normal, and the bulge of the segment to the next vertex,
        see :func:`outline_polygon`): the groove's vertices from its tip-side mouth edge to
        its joint-side one (K = 0 for a straight jaw, 2 for a cradle, 3 for a V, 4 for a
        rounded V whose flanks carry the bottom arc). The last vertex's bulge is 0.
    """
    if jaw.depth_m == 0.0:
        return np.zeros((0, len(OUTLINE_COLUMNS)))
    hw, a, depth, radius = width / 2, jaw.position_m, jaw.depth_m, jaw.bottom_radius_m
    half = jaw.opening_angle_rad / 2
    mouth = jaw.mouth_half_width_m
    if radius == 0.0:
        # a sharp V: two flanks meeting at the bottom
        return np.array([[a + mouth, hw, 0.0], [a, hw - depth, 0.0], [a - mouth, hw, 0.0]])
    centre = depth - radius  # the bottom arc's centre, as a depth below the face
    # the arc turns from the tip side through the bottom (deeper, smaller m) to the joint
    # side: clockwise in (s, m), a negative bulge
    if jaw.kind == "cradle":
        # the arc reaches the face before its flanks begin: it spans the whole mouth
        swing = math.acos(min(max(-centre / radius, -1.0), 1.0))
        return np.array([[a + mouth, hw, -math.tan(swing / 2)], [a - mouth, hw, 0.0]])
    # flanks from the mouth to the arc's tangent points, half the opening angle off the depth
    swing = math.pi / 2 - half
    tan_u, tan_v = radius * math.cos(half), centre + radius * math.sin(half)
    return np.array([[a + mouth, hw, 0.0], [a + tan_u, hw - tan_v, -math.tan(swing / 2)],
                     [a - tan_u, hw - tan_v, 0.0], [a - mouth, hw, 0.0]])


def finger_outline(length: float, angle: float, offset: float, width: float, side: int,
                   jaw: JawProfile = STRAIGHT) -> np.ndarray:
    """The exact outline of one finger [m]: its vertices and the bulges of the arcs between.

    Side 0 right, 1 left (conventions of scene.finger_frame). The vertices run joint end back,
    tip end back, tip end face, the groove's (:func:`groove_vertices`, from the tip side), joint
    end face; rows of :data:`OUTLINE_COLUMNS` (``x``, ``y`` and the bulge of the segment to the
    next vertex, counterclockwise positive in the drawing's frame, as a DXF polyline has it).
    """
    hw = width / 2
    local = np.concatenate([
        np.array([[0.0, -hw, 0.0], [length, -hw, 0.0], [length, hw, 0.0]]),
        groove_vertices(jaw, width),
        np.array([[0.0, hw, 0.0]]),
    ])
    # the left finger's frame is mirrored: its arcs turn the other way in the drawing
    handed = 1.0 if side == 0 else -1.0
    return np.column_stack([finger_to_drawing(local[:, [V_X, V_Y]], angle, offset, side),
                            handed * local[:, V_BULGE]])


def finger_to_drawing(points: np.ndarray, angle: float, offset: float, side: int
                      ) -> np.ndarray:
    """Points in a finger's coordinates (``s`` along it from its joint, ``m`` along its face's
    inward normal; shape (K, 2)) in the drawing's frame [m], side 0 right, 1 left, the finger at
    ``angle`` from the +y axis with its joint ``offset`` from the symmetry axis."""
    if side not in (0, 1):
        raise ValueError(f"side must be 0 (right) or 1 (left), got {side!r}")
    s, c = math.sin(angle), math.cos(angle)
    joint = np.array([offset, 0.0]) if side == 0 else np.array([-offset, 0.0])
    axis = np.array([s, c]) if side == 0 else np.array([-s, c])
    normal = np.array([-c, s]) if side == 0 else np.array([c, s])
    local = np.asarray(points, dtype=float).reshape(-1, 2)
    return joint + local[:, [V_X]] * axis + local[:, [V_Y]] * normal


def outline_polygon(vertices: np.ndarray, arc_step_rad: float = math.radians(5.0)
                    ) -> np.ndarray:
    """A closed outline of vertices and bulges as a polygon, its arcs sampled.

    Parameters
    ----------
    vertices
        Shape (K, 3): ``x``, ``y`` and the bulge ``tan(theta / 4)`` of the segment to the next
        vertex (the last one's closes the outline): 0 a straight line, else an arc of
        included angle ``theta``, counterclockwise when positive.
    arc_step_rad
        Largest angle between two samples of an arc [rad], in (0, pi].

    Returns
    -------
    numpy.ndarray
        Shape (M, 2): the vertices with the arcs' inner points between them, each arc's
        midpoint among them.
    """
    check_range("arc_step_rad", arc_step_rad, 0.0, math.pi, low_open=True)
    verts = np.asarray(vertices, dtype=float)
    if verts.ndim != 2 or verts.shape[1] != len(OUTLINE_COLUMNS):
        raise ValueError(f"vertices must have shape (K, {len(OUTLINE_COLUMNS)}) (x, y, bulge), "
                         f"got {verts.shape}")
    out = []
    for k, vertex in enumerate(verts):
        start, bulge = vertex[[V_X, V_Y]], float(vertex[V_BULGE])
        out.append(start)
        if bulge == 0.0:
            continue
        end = verts[(k + 1) % len(verts)][[V_X, V_Y]]
        theta = 4.0 * math.atan(bulge)
        chord = end - start
        length = float(np.hypot(*chord))
        # the centre lies on the chord's left (counterclockwise arcs) at this signed distance
        left = np.array([-chord[V_Y], chord[V_X]]) / length
        centre = (start + end) / 2 + left * (length / 2) * (1.0 - bulge * bulge) / (2.0 * bulge)
        radius = float(np.hypot(*(start - centre)))
        begin = math.atan2(start[V_Y] - centre[V_Y], start[V_X] - centre[V_X])
        # an even count: the arc's midpoint (a groove's bottom) is a sample
        n = 2 * max(1, math.ceil(abs(theta) / (2 * arc_step_rad)))
        for t in np.linspace(0.0, 1.0, n + 1)[1:-1]:
            out.append(centre + radius * np.array([math.cos(begin + t * theta),
                                                   math.sin(begin + t * theta)]))
    return np.array(out)


def finger_polygon(length: float, angle: float, offset: float, width: float, side: int,
                   jaw: JawProfile = STRAIGHT) -> np.ndarray:
    """Outline of one finger bar [m] as a polygon, side 0 right, 1 left (conventions of
    scene.finger_frame): joint end back, tip end back, tip end face, the groove of ``jaw``
    (arcs sampled, mouth edges sharp; none for a straight jaw), joint end face."""
    return outline_polygon(finger_outline(length, angle, offset, width, side, jaw))


def spring_segments(points_m: np.ndarray, center_m: np.ndarray, radius_m: float):
    """Radial and contour spring segments and their strains ``(L - L0) / L0``.

    Parameters
    ----------
    points_m
        Contour points [m], shape (N, 2).
    center_m
        Disk centre [m].
    radius_m
        Rest radius [m] (radial rest length); the contour rest length is ``2 r sin(pi/N)``.

    Returns
    -------
    segments : numpy.ndarray
        Shape (2N, 2, 2): N radial then N contour springs.
    strains : numpy.ndarray
        Shape (2N,).
    """
    pts = np.asarray(points_m, dtype=float)
    n = pts.shape[0]
    nxt = np.roll(pts, -1, axis=0)
    centre = np.broadcast_to(np.asarray(center_m, dtype=float), pts.shape)
    radial = np.stack([centre, pts], axis=1)
    contour = np.stack([pts, nxt], axis=1)
    h = 2 * radius_m * math.sin(math.pi / n)
    strains = np.concatenate([
        np.linalg.norm(pts - centre, axis=1) / radius_m - 1.0,
        np.linalg.norm(nxt - pts, axis=1) / h - 1.0,
    ])
    return np.concatenate([radial, contour]), strains


def mesh_segments(points_m: np.ndarray, interior_m: np.ndarray, center_m: np.ndarray,
                  radius_m: float, n_rings: int, phase_rad: float = math.pi / 2,
                  element: str = "spring", rest_unit: np.ndarray | None = None):
    """Edges of a ring mesh (:mod:`envs.model.rings`) and their strains ``(L - L0) / L0``.

    Parameters
    ----------
    points_m, interior_m
        Contour points (N, 2) and interior points ((M - 1) N, 2), ring by ring from the hub
        out [m] (``GraspResult.points_m``, ``.interior_points_m``).
    center_m, radius_m
        Disk centre and radius [m].
    n_rings
        Rings M (>= 2; the fan is :func:`spring_segments`).
    element
        The member's element (its ring spacing: even for ``"nhquad"``).
    phase_rad
        Angle of the first point of every ring [rad].
    rest_unit
        An outline's contour points at rest in units of ``radius_m`` about the centre (N, 2)
        (:meth:`envs.objects.Outline.contour`): the mesh's rings scaled onto it; ``None``: the
        disk's unit circle.

    Returns
    -------
    segments : numpy.ndarray
        Shape (3 N M, 2, 2) minus the hub's own edges: every spring of the mesh.
    strains : numpy.ndarray
    """
    from .model.layout import SPACING_EVEN, SPACING_GEOMETRIC
    from .model.rings import edge_ends, n_edge_types, ring_radius

    spacing = SPACING_EVEN if element == "nhquad" else SPACING_GEOMETRIC
    pts = np.asarray(points_m, dtype=float)
    inner = np.asarray(interior_m, dtype=float).reshape(-1, 2)
    n, m = pts.shape[0], int(n_rings)
    centre = np.asarray(center_m, dtype=float)
    ang = phase_rad + 2 * math.pi * np.arange(n) / n
    unit = (np.stack([np.cos(ang), np.sin(ang)], axis=1) if rest_unit is None
            else np.asarray(rest_unit, dtype=float))

    def point(k, i, rest):
        if rest or k == 0:
            return centre + radius_m * ring_radius(k, m, spacing) * unit[i]
        return pts[i] if k == m else inner[(k - 1) * n + i]

    segs, strains = [], []
    for t in range(n_edge_types(m)):
        for i in range(n):
            ka, ia, kb, ib = edge_ends(t, i, n, m)
            a, b = point(ka, ia, False), point(kb, ib, False)
            rest = np.linalg.norm(point(kb, ib, True) - point(ka, ia, True))
            segs.append((a, b))
            strains.append(np.linalg.norm(b - a) / rest - 1.0)
    return np.array(segs), np.array(strains)


def object_patch(disk: SoftDisk, scale: float = 1.0, centre_m=None, **style):
    """The object at rest as a matplotlib patch, ``scale`` drawn units a metre: a circle for
    a disk, its outline at its orientation otherwise (centred at ``centre_m``, default its
    own centre)."""
    centre = np.asarray(disk.center_m if centre_m is None else centre_m, dtype=float)
    if disk.outline is None:
        return Circle(scale * centre, scale * disk.radius_m, **style)
    pts = centre + disk.radius_m * disk.outline.contour(256, disk.orientation_rad)
    return Polygon(scale * pts, closed=True, **style)


def _reach(disk: SoftDisk | None, radius_m: float) -> float:
    """The farthest the object reaches from its centre [m] (framing a drawing)."""
    if disk is None or disk.outline is None:
        return radius_m
    return disk.radius_m * disk.outline.radius_range()[1]


def _frame(ax, fingers: list[np.ndarray], center: np.ndarray, radius: float,
           length_unit: str = "m") -> None:
    """Limits around the fingers and the disk, equal axes, labelled in ``length_unit``."""
    pts = np.concatenate([*fingers, center + radius * np.array([[-1, -1], [1, 1]])])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.08 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(min(lo[1], 0.0) - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{length_unit}]")
    ax.set_ylabel(f"y [{length_unit}]")


def draw_design(ax, design, radius_m: float, *, title: str | None = None,
                length_unit: str = "m", disk: SoftDisk | None = None) -> None:
    """Draw a design at rest from raw numbers, without validating it (for invalid designs).

    Parameters
    ----------
    ax
        Matplotlib axes.
    design
        Six numbers in :data:`envs.evaluate.DESIGN_FIELDS` order (SI units), optionally
        followed by the jaw columns (:data:`envs.model.jaw.JAW_FIELDS`, 10 or 14 wide); a jaw
        out of range is drawn straight.
    radius_m
        Disk radius [m].
    title
        Axes title.
    length_unit
        Units of the drawing's axes, ``"m"`` (default) or ``"mm"``.
    disk
        The object, where it is not a disk of ``radius_m`` (an outline is drawn at its
        orientation, its lowest point ``d_1`` above the joints' line); its own
        ``distance_m`` is not read.
    """
    k = unit_scale(length_unit)
    row = np.asarray(design, dtype=float)
    ln, th0, d3, w, _, d1 = (float(v) for v in row[:N_DESIGN])
    try:
        right, left = jaws_of_row(row)
        jaws = (right, right if left is None else left)
    except ValueError:
        jaws = (STRAIGHT, STRAIGHT)
    center = k * np.array([0.0, d1 + radius_m])
    fingers = [k * finger_polygon(ln, th0, d3, w, side, jaws[side]) for side in (0, 1)]
    for poly in fingers:
        ax.add_patch(Polygon(poly, closed=True, facecolor="0.75", edgecolor="0.3", alpha=0.8))
    if disk is None or disk.outline is None:
        ax.add_patch(Circle(center, k * radius_m, facecolor="tab:orange", alpha=0.3,
                            edgecolor="k"))
    else:
        center = k * np.array([disk.offset_x_m, d1 + disk.lift_m])
        ax.add_patch(object_patch(disk, k, center / k, facecolor="tab:orange", alpha=0.3,
                                  edgecolor="k"))
    _frame(ax, fingers, center, k * _reach(disk, radius_m), length_unit)
    if title:
        ax.set_title(title, fontsize=9)


def draw_grasp(
    ax,
    scene: Scene,
    result: Any | None = None,
    *,
    strain_limit: float | None = None,
    show_rest: bool = True,
    show_springs: bool = True,
    cmap: str = STRAIN_CMAP,
    title: str | None = None,
    legend: bool = True,
    length_unit: str = "m",
):
    """Draw a grasp: fingers, rest and deformed disk, springs coloured by strain, contacts.

    Parameters
    ----------
    ax
        Matplotlib axes.
    scene
        Gripper and disk.
    result
        Anything with ``points_m`` (N, 2) [m], ``jaw_angles_rad`` (2,) and ``contact_mask``
        (2, N), e.g. a :class:`~envs.solver.GraspResult`; ``None`` draws the scene at rest.
    strain_limit
        Strain mapped to the ends of the colour scale [-]; default: the largest |strain|.
    show_rest
        Also draw the fingers and the disk at rest (dashed).
    show_springs
        Draw the radial and contour springs coloured by strain.
    cmap
        Diverging colour map for the strain (blue: compressed, red: stretched).
    title
        Axes title.
    legend
        Add a legend naming the contact points of each finger, the rest outlines, the deformed
        disk, the pinned centre and the joints.
    length_unit
        Units of the drawing's axes, ``"m"`` (default) or ``"mm"`` (the strains are ratios
        and do not change).

    Returns
    -------
    matplotlib.collections.LineCollection or None
        The spring collection (for a colour bar), ``None`` without a result.
    """
    g: Gripper = scene.gripper
    d: SoftDisk = scene.disk
    k = unit_scale(length_unit)  # every position is drawn k times its value in metres
    center = k * np.asarray(d.center_m, dtype=float)
    rest_fingers = [k * finger_polygon(g.finger_length_m, g.rest_angle_rad, g.joint_offset_m,
                                        g.finger_width_m, side, g.jaws[side])
                    for side in (0, 1)]
    angles = (g.rest_angle_rad, g.rest_angle_rad) if result is None else result.jaw_angles_rad
    fingers = [k * finger_polygon(g.finger_length_m, float(angles[side]), g.joint_offset_m,
                                   g.finger_width_m, side, g.jaws[side]) for side in (0, 1)]
    if show_rest and result is not None:
        for poly in rest_fingers:
            ax.add_patch(Polygon(poly, closed=True, **REST_STYLE))
        ax.add_patch(object_patch(d, k, **REST_STYLE, label="rest (dashed)"))
    for poly in fingers:
        ax.add_patch(Polygon(poly, closed=True, facecolor="0.75", edgecolor="0.3", alpha=0.9,
                             zorder=3))
    joints = k * np.array([[g.joint_offset_m, 0.0], [-g.joint_offset_m, 0.0]])
    ax.plot(joints[:, 0], joints[:, 1], "o", color="k", markersize=4, zorder=4,
            label="joints")
    ax.plot(*center, "+", color="k", markersize=8, zorder=4, label="centre (pinned)")
    if d.offset_x_m != 0.0:
        # a displaced object is held where it was placed: show how far off the axis that is
        ax.axvline(0.0, color="0.55", linestyle=":", linewidth=0.8, zorder=0,
                   label=f"gripper axis (object held {d.offset_x_m * 1e3:+.3g} mm off it)")
    lines = None
    if result is None:
        ax.add_patch(object_patch(d, k, facecolor="tab:orange", alpha=0.3, edgecolor="k"))
    else:
        pts_m = np.asarray(result.points_m, dtype=float)
        pts = k * pts_m
        ax.add_patch(Polygon(pts, closed=True, facecolor="tab:orange", alpha=0.15,
                             edgecolor="0.2", linewidth=2.4, zorder=1, label="deformed disk"))
        if show_springs:
            rings = int(getattr(result, "n_rings", 1))
            if rings > 1:
                # a ring mesh: every edge (for the constant-strain element, the triangles'
                # edge strains), the hub's ring drawn at rest
                segs, strains = mesh_segments(
                    pts_m, result.interior_points_m, d.center_m, d.radius_m, rings,
                    element=getattr(result, "element", "spring"),
                    rest_unit=None if d.outline is None else d.outline.contour(
                        len(pts_m), d.orientation_rad))
                widths = np.full(len(segs), 0.8)
            else:
                segs, strains = spring_segments(pts_m, d.center_m, d.radius_m)
                widths = np.r_[np.full(len(pts), 1.0), np.full(len(pts), 1.8)]
            lim = strain_limit if strain_limit else max(float(np.max(np.abs(strains))), 1e-6)
            lines = LineCollection(k * segs, cmap=cmap, norm=Normalize(-lim, lim),
                                   linewidths=widths, zorder=2)
            lines.set_array(strains)
            ax.add_collection(lines)
        mask = np.asarray(result.contact_mask, dtype=bool)
        for side, style in enumerate(CONTACT_STYLE):
            hit = pts[mask[side]]
            ax.plot(hit[:, 0], hit[:, 1], "o", markersize=6, markeredgecolor="k",
                    markeredgewidth=0.8, zorder=5, linestyle="none",
                    **{"markerfacecolor": style["color"], "label": style["label"]})
    _frame(ax, rest_fingers + fingers, center, k * _reach(d, d.radius_m), length_unit)
    if legend:
        # below the axes: inside, it would hide the grasp it explains
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=3, fontsize=7,
                  frameon=False, handlelength=1.5, columnspacing=1.0)
    if title:
        ax.set_title(title, fontsize=9)
    return lines


def _summary(result: Any) -> str:
    nc = np.asarray(result.contact_mask).sum(axis=1)
    status = "converged" if getattr(result, "converged", True) else "NOT converged"
    return (f"T = {result.torque_nm:.3g} N·m, contacts {int(nc[0])}/{int(nc[1])}\n"
            f"peak strain {result.peak_strain:.3g} ({status})")


def grasp_figure(
    scene: Scene,
    result: Any | None = None,
    path: str | Path | None = None,
    *,
    strain_limit: float | None = None,
    title: str | None = None,
    figsize: tuple[float, float] = (5.0, 5.0),
    dpi: int = 100,
    length_unit: str = "m",
) -> Figure:
    """A stand-alone figure of a grasp with a strain colour bar, saved as PNG if ``path``.

    Parameters
    ----------
    scene
        Gripper and disk.
    result
        A :class:`~envs.solver.GraspResult` (or a look-alike, see :func:`draw_grasp`); ``None``
        draws the scene at rest.
    path
        Where to write the PNG (parent folders are created).
    strain_limit, title
        See :func:`draw_grasp`; the default title summarizes the result.
    figsize, dpi
        Figure size [in] and resolution.
    length_unit
        Units of the axes, ``"m"`` (default) or ``"mm"``.
    """
    fig = Figure(figsize=figsize, dpi=dpi)
    ax = fig.add_subplot()
    if title is None and result is not None and hasattr(result, "torque_nm"):
        title = _summary(result)
    lines = draw_grasp(ax, scene, result, strain_limit=strain_limit, title=title,
                       length_unit=length_unit)
    if lines is not None:
        fig.colorbar(lines, ax=ax, shrink=0.7, label=STRAIN_LABEL)
    fig.tight_layout()
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, format="png")
    return fig


def figure_rgb_array(fig: Figure) -> np.ndarray:
    """Render a figure off-screen with the Agg canvas; uint8 array (H, W, 3)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def grasp_rgb_array(scene: Scene, result: Any | None = None, **kwargs) -> np.ndarray:
    """:func:`grasp_figure` rendered off-screen; uint8 array (H, W, 3)."""
    return figure_rgb_array(grasp_figure(scene, result, **kwargs))
