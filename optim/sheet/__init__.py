"""The build sheet: a design a builder can use, the gripper in millimetres, its spring and
torque in SI units, and the parts a workshop makes (:mod:`optim.parts`).

:func:`build_sheet` turns an optimization's best design (a dict in SI units, the columns of
:data:`envs.scene.DESIGN_FIELDS`) and its object into a table a workshop reads: the finger
outline and the placement of joints and object in millimetres in the gripper frame (origin
midway between the joints, x to the right, y up along the symmetry axis, as in the model), the
rest angle in degrees, the joint spring in N·m/rad and the actuation torque in N·m; and what the
design depends on: the friction coefficient it was designed for, the payload (where the result
has one), the placement tolerance and object ranges it was checked under with every scenario's
grasp, the fixed-centre assumption of the model, and how the fingers are assembled.

Assembly: each finger's joint end, a square end of half-width ``w / 2``, sweeps a circle of
radius ``w / 2`` about its joint as the finger turns. When the joints are closer than half a
finger width to the axis (``d_3 < w / 2``) the two circles overlap, and so do the fingers at
the joints: they can only be built **stacked**, one above the other at the joints, like the
jaws of forceps. Otherwise they can be built **side by side** in one plane.

Jaws: a finger's gripping face may carry a groove (:class:`envs.model.jaw.JawProfile`: a
cradle, a V-groove or a rounded V between). The sheet states each finger's profile (kind, depth,
bottom radius, opening angle, the groove centre's distance from the joint axis, mouth width; one
set for both fingers when they are alike) and "straight" for a flat face; the outlines carry the
cutout (its arcs as DXF bulges) and the drawing dimensions it in a detail per profile. The jaws
are read from the design by the names of :data:`envs.model.jaw.JAW_FIELDS` and
:data:`~envs.model.jaw.LEFT_JAW_FIELDS`; a design without them has straight jaws.
:func:`write_build_sheet` writes the sheet as JSON and CSV (the scenarios in a CSV of their own)
with a dimensioned drawing.
"""


from .common import ASSEMBLY_COMMON_PIVOT, DXF_LAYERS
from .drawing import drawing_figure
from .files import dxf_available, write_build_sheet, write_dxf
from .jaws import JAW_ROWS, jaw_rows, jaws_of_design
from .tables import (
    ASSEMBLY_SIDE_BY_SIDE,
    ASSEMBLY_STACKED,
    FIXED_CENTRE_NOTE,
    assembly_of,
    build_sheet,
)

__all__ = ["build_sheet", "write_build_sheet", "drawing_figure", "assembly_of", "write_dxf",
           "dxf_available", "DXF_LAYERS", "jaws_of_design", "jaw_rows", "JAW_ROWS",
           "ASSEMBLY_STACKED", "ASSEMBLY_SIDE_BY_SIDE", "ASSEMBLY_COMMON_PIVOT",
           "FIXED_CENTRE_NOTE"]
