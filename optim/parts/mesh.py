"""One 3-D part per finger: its plan extruded to the plate's thickness, the half-lap cut
(manifold3d, a maintained solid-modelling kernel), written as an STL (trimesh) in millimetres.

The mesh is built from the same sampled plan as :attr:`~optim.parts.profile.FingerPart.volume_m3`,
so a mesh library reading it back finds it watertight with that volume (to rounding).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .profile import FingerPart

__all__ = ["mesh_available", "finger_mesh", "write_stl", "MESH_HINT"]

MESH_HINT = "the 3-D parts need trimesh and manifold3d: pip install -e '.[parts]'"
MM = 1e3


def mesh_available() -> bool:
    """Whether the 3-D parts can be written (the optional extra ``parts``)."""
    import importlib.util

    return all(importlib.util.find_spec(m) is not None
               for m in ("trimesh", "manifold3d"))


def _rings(polygon) -> list[np.ndarray]:
    """A shapely polygon's rings [mm], each without its closing point."""
    return [np.asarray(ring.coords)[:-1] * MM
            for ring in (polygon.exterior, *polygon.interiors)]


def finger_mesh(part: FingerPart):
    """The part as a closed triangle mesh in its own frame [mm]: ``z`` from 0 to the plate's
    thickness, the half-lap's underside (``z < t/2`` for ``x <= lap``) removed; a
    :class:`trimesh.Trimesh`.

    Raises
    ------
    ValueError
        Without trimesh or manifold3d (:data:`MESH_HINT`).
    """
    if not mesh_available():
        raise ValueError(MESH_HINT)
    import manifold3d
    import trimesh

    thickness = part.plate_thickness_m * MM
    section = manifold3d.CrossSection(_rings(part.polygon()), manifold3d.FillRule.EvenOdd)
    solid = section.extrude(thickness)
    if part.lap_length_m > 0.0:
        x0, y0, _, y1 = (v * MM for v in part.polygon().bounds)
        margin = thickness
        cut = manifold3d.Manifold.cube(
            [part.lap_length_m * MM - x0 + margin, y1 - y0 + 2 * margin, thickness / 2 + margin]
        ).translate([x0 - margin, y0 - margin, -margin])
        solid = solid - cut
    mesh = solid.to_mesh()
    return trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3],
                           np.asarray(mesh.tri_verts), process=True)


def write_stl(part: FingerPart, path: str | Path) -> Path:
    """Write the part's mesh (:func:`finger_mesh`) as a binary STL [mm]."""
    path = Path(path)
    finger_mesh(part).export(path, file_type="stl")
    return path
