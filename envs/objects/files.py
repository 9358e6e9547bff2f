"""Measured outlines from files: a CSV of points or a DXF polyline.

* **CSV** (``.csv``, ``.txt``): one point a line, ``x, y`` (commas, semicolons, tabs or
  spaces); lines starting with ``#`` and a header line of words are skipped. The polyline is
  closed (a repeated first point is dropped).
* **DXF** (``.dxf``, needs the ``dxf`` extra: ``pip install psm-grasp[dxf]``): the closed
  ``LWPOLYLINE`` or ``POLYLINE`` of largest area in the model space; arcs (bulges) are
  flattened to within 1/2000 of the polyline's size.

The points are in ``unit`` (``"m"`` or ``"mm"``). The outline must be a simple closed curve,
star-shaped about its centroid (:meth:`envs.objects.MeasuredOutline.from_points` says which
test fails, and where).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..validation import read_text_file
from .shapes import MeasuredOutline

__all__ = ["OUTLINE_UNITS", "OUTLINE_SUFFIXES", "read_outline_points", "read_outline"]

#: Units the points of an outline file may be in, and their size in metres.
OUTLINE_UNITS = {"m": 1.0, "mm": 1e-3}
OUTLINE_SUFFIXES = (".csv", ".txt", ".dxf")
_SEPARATORS = re.compile(r"[,;\s]+")


def read_outline_points(path, unit: str) -> np.ndarray:
    """The points of an outline file [m], (n, 2) (see the module for the formats).

    Raises
    ------
    ValueError
        An unknown unit or suffix, a file that cannot be read, a line that is not two numbers,
        a DXF without a closed polyline: one message naming the file.
    """
    if unit not in OUTLINE_UNITS:
        raise ValueError(f"outline unit must be one of {sorted(OUTLINE_UNITS)}, got {unit!r}")
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in OUTLINE_SUFFIXES:
        raise ValueError(f"{str(p)!r}: an outline file must be one of {OUTLINE_SUFFIXES} "
                         f"(points as CSV, or a DXF polyline), got {suffix or 'no suffix'!r}")
    points = _dxf_points(p) if suffix == ".dxf" else _csv_points(p)
    return points * OUTLINE_UNITS[unit]


def read_outline(path, unit: str, name: str | None = None) -> tuple[MeasuredOutline, float]:
    """The outline of a file and its equivalent radius [m]
    (:meth:`~envs.objects.MeasuredOutline.from_points`)."""
    p = Path(path)
    try:
        return MeasuredOutline.from_points(read_outline_points(p, unit), name or p.stem)
    except ValueError as exc:
        raise ValueError(f"{str(p)!r}: {exc}") from None


def _csv_points(p: Path) -> np.ndarray:
    text = read_text_file(p, "outline", "CSV", encoding="utf-8-sig")
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f for f in _SEPARATORS.split(line) if f]
        try:
            values = [float(f) for f in fields]
        except ValueError:
            if not rows and not any(ch.isdigit() for ch in line):
                continue  # a header of words
            raise ValueError(f"{str(p)!r}: line {number} is not two numbers x, y: "
                             f"{line!r}") from None
        if len(values) != 2:
            raise ValueError(f"{str(p)!r}: line {number} has {len(values)} numbers, "
                             f"expected x, y: {line!r}")
        rows.append(values)
    if not rows:
        raise ValueError(f"{str(p)!r}: no points (x, y lines) in the outline file")
    return np.array(rows, dtype=np.float64)


def _dxf_points(p: Path) -> np.ndarray:
    try:
        import ezdxf
        from ezdxf import path as dxf_path
    except ImportError:
        raise ValueError("reading a DXF outline needs ezdxf: pip install psm-grasp[dxf]"
                         ) from None
    try:
        doc = ezdxf.readfile(str(p))
    except (OSError, ezdxf.DXFError) as exc:
        raise ValueError(f"{str(p)!r}: cannot read the DXF file ({exc})") from None
    best, best_area = None, 0.0
    for entity in doc.modelspace().query("LWPOLYLINE POLYLINE"):
        if not entity.is_closed:
            continue
        outline = dxf_path.make_path(entity)
        size = max(np.ptp([v.x for v in outline.control_vertices()] or [0.0]),
                   np.ptp([v.y for v in outline.control_vertices()] or [0.0]), 1e-300)
        pts = np.array([(v.x, v.y) for v in outline.flattening(size / 2000.0)])
        if len(pts) < 3:
            continue
        area = 0.5 * abs(float(np.sum(pts[:, 0] * np.roll(pts[:, 1], -1)
                                      - np.roll(pts[:, 0], -1) * pts[:, 1])))
        if area > best_area:
            best, best_area = pts, area
    if best is None:
        raise ValueError(f"{str(p)!r}: no closed LWPOLYLINE or POLYLINE in the DXF's model "
                         "space")
    return best
