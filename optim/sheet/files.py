"""The build sheet's files: JSON, CSV, the drawing, the assembly DXF (see :mod:`optim.sheet`)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np

from .common import DXF_LAYERS, DXF_MILLIMETRES, FINGERS
from .drawing import _finger_vertices, drawing_figure
from .jaws import jaw_rows
from .tables import SCENARIO_COLUMNS, build_sheet


def _csv_value(value: Any, digits: str) -> str:
    """A CSV cell: text as it is, a flag as True/False, a number to ``digits``."""
    if isinstance(value, (str, bool, np.bool_)):
        return str(value)
    return "" if value is None else format(float(value), digits)


def _write_design_csv(path: Path, sheet: dict[str, Any], scenarios_file: str) -> None:
    """The sheet as one table: quantity, value, unit, meaning (a design that does not hold:
    its banner first)."""
    verdict = sheet.get("verdict") or {}
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["quantity", "value", "unit", "meaning"])
        if verdict.get("banner"):
            writer.writerow(["WARNING", verdict["banner"], "", "the design does not hold its "
                             "object in every scenario checked: do not build it as one that "
                             "holds"])
        if (sheet.get("grasp") or {}).get("scenario"):
            writer.writerow(["governing_scenario", sheet["grasp"]["scenario"], "",
                             "the scenario with the lowest reward, whose own grasp the sheet "
                             "states"])
        for row in (*sheet["rows"], *jaw_rows(sheet), *sheet["conditions"],
                    *sheet.get("part_rows", ())):
            writer.writerow([row["quantity"], _csv_value(row["value"], ".6g"), row["unit"],
                             row["meaning"]])
        writer.writerow(["assembly", sheet["assembly"], "", sheet["assembly_note"]])
        writer.writerow(["fixed_centre", "yes", "", sheet["fixed_centre"]])
        for key, (low, high) in sheet["tolerances"]["object_ranges"].items():
            unit = "mm" if key.endswith("_mm") else ""
            writer.writerow([f"range_{key}", f"{low:.6g} to {high:.6g}", unit,
                             "object range the design was checked under"])
        for key, value in (sheet.get("envelopes") or {}).items():
            writer.writerow([f"envelope_{key}", _csv_value(value, ".6g"), "",
                             "over every scenario checked"])
        tolerances = (sheet.get("checked") or {}).get("tolerances")
        writer.writerow(["manufacturing_tolerances",
                         "none" if not tolerances else ", ".join(
                             f"{k} {v:g}" for k, v in tolerances.items()), "",
                         sheet["tolerances"]["dimensions"]])
        if sheet.get("checked"):
            writer.writerow(["load_set", sheet["checked"]["load_set"], "",
                             "the directions the payload was checked in"])
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
    """The scenario table: a row per scenario, the varied object quantities and the design's
    changes as built (``built_...``) in columns."""
    varied = sorted({k for row in sheet["scenarios"] for k in row["object"]})
    built = sorted({k for row in sheet["scenarios"] for k in row.get("built", {})})
    measures = [key for key, _, _ in SCENARIO_COLUMNS
                if any(key in row for row in sheet["scenarios"])]
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["label", *measures, *varied, *(f"built_{k}" for k in built)])
        for row in sheet["scenarios"]:
            writer.writerow([row["label"], *(_csv_value(row.get(k), ".6g") for k in measures),
                             *(_csv_value(row["object"].get(k), ".6g") for k in varied),
                             *(_csv_value(row.get("built", {}).get(k, 0.0), ".6g")
                               for k in built)])


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
    if sheet.get("object_outline_mm"):  # an object that is not a disk, at its orientation
        space.add_lwpolyline(sheet["object_outline_mm"], format="xy", close=True,
                             dxfattribs={"layer": DXF_LAYERS["object"]})
    else:
        space.add_circle(sheet["object_centre_mm"], rows["object_diameter_mm"] / 2,
                         dxfattribs={"layer": DXF_LAYERS["object"]})
    doc.saveas(Path(path))
    return Path(path)


def write_build_sheet(design: dict[str, float], obj: dict[str, Any], out_dir: str | Path,
                      prefix: str, metrics: dict[str, Any] | None = None,
                      scenario_rows: list[dict[str, Any]] | None = None, *,
                      parts=None, extra: dict[str, Any] | None = None) -> dict[str, Path]:
    """Write ``{prefix}_design.json``, ``{prefix}_design.csv`` and ``{prefix}_drawing.png``,
    with scenarios ``{prefix}_scenarios.csv``, with ezdxf the assembly's outlines
    ``{prefix}_fingers.dxf`` (:func:`write_dxf`) and a part per finger
    ``{prefix}_finger_right.dxf``, ``..._left.dxf`` (:func:`optim.parts.dxf.write_part_dxf`),
    and with trimesh and manifold3d a 3-D part per finger ``{prefix}_finger_right.stl``,
    ``..._left.stl`` (:func:`optim.parts.mesh.write_stl`, millimetres). ``parts`` and
    ``extra`` as in :func:`build_sheet`.

    Returns the written paths by kind (``design_json``, ``design_csv``, ``drawing``,
    ``scenarios_csv``, ``dxf``, ``dxf_right``, ``dxf_left``, ``stl_right``, ``stl_left``).
    """
    from optim.result import to_jsonable

    sheet = build_sheet(design, obj, metrics, scenario_rows, parts=parts, extra=extra)
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
    paths.update(_write_parts(design, obj, metrics, scenario_rows, parts, sheet, folder, prefix))
    return paths


def _part_notes(sheet: dict[str, Any], side: str) -> list[str]:
    """The text of a finger's part drawing."""
    v = sheet["parts"]["values"]
    name = (sheet.get("object") or {}).get("name") or "the object"
    same = sheet["parts"]["fingers"][side].get("same_as")
    notes = [f"{side.upper()} FINGER for {name}, millimetres, own frame (x from the pivot to "
             "the tip, gripping face up)" + (f": the same part as the {same} one, turned over"
                                             if same else ""),
             f"plate {v['plate_thickness_mm']:.4g}, pivot hole {v['pin_diameter_mm']:.4g} "
             f"({v['pivot']}), pad from {v['pad_from_mm']:.4g} to the tip (friction >= "
             f"{_csv_value(v['pad_friction_min'], '.3g')})"]
    if v["half_lap_mm"]:
        notes.append(f"half-lap: the underside removed to half the plate from the joint end to "
                     f"{v['half_lap_mm']:.4g} (the dashed line)")
    banner = (sheet.get("verdict") or {}).get("banner")
    return [f"WARNING: {banner}", *notes] if banner else notes


def _write_parts(design, obj, metrics, scenario_rows, parts, sheet, folder: Path,
                 prefix: str) -> dict[str, Path]:
    """A DXF (with ezdxf) and an STL (with trimesh and manifold3d) per finger."""
    from optim.parts.dxf import write_part_dxf
    from optim.parts.mesh import mesh_available, write_stl

    from .jaws import jaws_of_design
    from .parts import parts_section
    from .tables import _part_options

    _, fingers = parts_section(design, obj, dict(metrics or {}), scenario_rows,
                               _part_options(parts), jaws_of_design(design))
    paths = {}
    for part in fingers:
        if dxf_available():
            paths[f"dxf_{part.side}"] = write_part_dxf(
                part, folder / f"{prefix}_finger_{part.side}.dxf", _part_notes(sheet, part.side),
                sheet["parts"]["values"]["pad_from_mm"] / 1e3)
        if mesh_available():
            paths[f"stl_{part.side}"] = write_stl(part, folder / f"{prefix}_finger_{part.side}.stl")
    return paths

