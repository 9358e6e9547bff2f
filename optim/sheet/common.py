"""What the build sheet's modules share: units, names of the fingers and of the assemblies."""

from __future__ import annotations

__all__ = ["MM", "FINGERS", "DXF_LAYERS", "DXF_MILLIMETRES", "ASSEMBLY_STACKED",
           "ASSEMBLY_SIDE_BY_SIDE", "ASSEMBLY_COMMON_PIVOT", "NOT_MODELLED", "OUTLINE_POINTS"]

MM = 1e3
OUTLINE_POINTS = 128  # points of an object's outline (not a disk) on the sheet and in the DXF
# layers of the DXF: each finger's outline, the joint centres, the object (for reference)
DXF_LAYERS = {"right": "FINGER_RIGHT", "left": "FINGER_LEFT", "joints": "JOINT_CENTRES",
              "object": "OBJECT_REFERENCE"}
DXF_MILLIMETRES = 4  # the DXF header's $INSUNITS code for millimetres
ASSEMBLY_STACKED = "stacked"
ASSEMBLY_SIDE_BY_SIDE = "side by side"
NOT_MODELLED = "not modelled"
ASSEMBLY_COMMON_PIVOT = "common pivot"
FINGERS = ("right", "left")  # the sheet's names of side 0 and 1
