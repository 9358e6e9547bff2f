"""One DXF per finger, in its own frame (:mod:`optim.parts.profile`), for a laser cutter or a
CNC shop: the outline (the groove's arcs and the boss as true arcs), the pivot hole, the
half-lap's edge, the pad along the gripping face, the part's text and its dimensions, each on a
layer of its own (:data:`PART_LAYERS`), millimetres.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from envs.render import V_BULGE, V_X, V_Y

from .profile import FingerPart

__all__ = ["write_part_dxf", "PART_LAYERS"]

MM = 1e3
DXF_MILLIMETRES = 4  # the header's $INSUNITS code for millimetres
# layer -> colour (AutoCAD colour index)
PART_LAYERS = {"OUTLINE": 7, "PIVOT_HOLE": 1, "HALF_LAP": 3, "PAD": 5, "TEXT": 7,
               "DIMENSIONS": 2}


def _text(space, text: str, at: tuple[float, float], height: float) -> None:
    space.add_text(text, height=height, dxfattribs={"layer": "TEXT"}).set_placement(at)


def write_part_dxf(part: FingerPart, path: str | Path, notes: list[str],
                   pad_from_m: float | None = None) -> Path:
    """Write a finger's part as a DXF [mm].

    Parameters
    ----------
    part
        The part.
    path
        The file.
    notes
        Lines of text written below the part (its name, material, plate, pin, tolerances).
    pad_from_m
        Where the pad along the gripping face starts, from the pivot [m] (default: the boss's
        or the half-lap's end, whichever is farther).

    Raises
    ------
    ValueError
        Without ezdxf (the extra ``dxf``).
    """
    import importlib.util

    if importlib.util.find_spec("ezdxf") is None:
        raise ValueError("the DXF needs ezdxf: pip install -e '.[dxf]'")
    import ezdxf

    doc = ezdxf.new("R2010", setup=True)
    doc.header["$INSUNITS"] = DXF_MILLIMETRES
    doc.header["$MEASUREMENT"] = 1
    for name, colour in PART_LAYERS.items():
        doc.layers.add(name, color=colour)
    space = doc.modelspace()
    outline = part.outline()
    points = [(x * MM, y * MM, b) for x, y, b in outline[:, [V_X, V_Y, V_BULGE]].tolist()]
    space.add_lwpolyline(points, format="xyb", close=True, dxfattribs={"layer": "OUTLINE"})
    space.add_circle((0.0, 0.0), part.pin_diameter_m / 2 * MM,
                     dxfattribs={"layer": "PIVOT_HOLE"})
    length, hw = part.length_m * MM, part.width_m / 2 * MM
    if part.lap_length_m > 0.0:
        lap = part.lap_length_m * MM
        space.add_line((lap, -hw), (lap, hw), dxfattribs={"layer": "HALF_LAP",
                                                          "linetype": "DASHED"})
    start = max(part.boss_radius_m, part.lap_length_m) if pad_from_m is None else pad_from_m
    space.add_line((start * MM, hw), (length, hw), dxfattribs={"layer": "PAD"})
    size = max(part.width_m * MM, 0.05 * length)
    height = 0.18 * size
    _dimensions(space, part, size)
    for k, line in enumerate(notes):
        _text(space, line, (-part.boss_radius_m * MM, -hw - 2.6 * size - 1.6 * height * k),
              height)
    doc.saveas(Path(path))
    return Path(path)


def _dimensions(space, part: FingerPart, size: float) -> None:
    """Length (pivot to tip), width, the half-lap's length, the hole's diameter [mm]."""
    length, hw = part.length_m * MM, part.width_m / 2 * MM
    # the drawing's own units (ezdxf's styles scale by 100 for metres in centimetres), a
    # decimal point, two decimals: 0.01 mm
    style = {"dimtxt": 0.18 * size, "dimasz": 0.15 * size, "dimexe": 0.05 * size,
             "dimexo": 0.05 * size, "dimlfac": 1.0, "dimdsep": ord("."), "dimdec": 2}
    attribs: dict[str, Any] = {"layer": "DIMENSIONS"}
    space.add_linear_dim(base=(0.0, -hw - 1.2 * size), p1=(0.0, 0.0), p2=(length, 0.0),
                         override=style, dxfattribs=attribs).render()
    space.add_linear_dim(base=(length + 0.8 * size, 0.0), p1=(length, -hw), p2=(length, hw),
                         angle=90, override=style, dxfattribs=attribs).render()
    if part.lap_length_m > 0.0:
        space.add_linear_dim(base=(0.0, hw + 0.8 * size), p1=(0.0, 0.0),
                             p2=(part.lap_length_m * MM, hw), override=style,
                             dxfattribs=attribs).render()
    space.add_diameter_dim(center=(0.0, 0.0), radius=part.pin_diameter_m / 2 * MM, angle=45.0,
                           override=style, dxfattribs=attribs).render()
