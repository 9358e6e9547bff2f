"""Named layouts of the arrays shared by the Python side and the compiled solver.

The compiled kernels take plain float64 vectors; every slot has a name here, and nothing reads
them by bare index.

Parameter vector of a scaled problem (lengths in units of the radius r, forces in units of
``s E t r``, torques in units of ``s E t r^2``), written by :func:`envs.model.problem.pack_params`:

========  ==================================================================================
P_KR      radial spring stiffness per ``s E t``
P_KC      contour spring stiffness per ``s E t`` (times the contour stiffness ratio)
P_H       contour rest length ``2 sin(pi / N)``
P_C0X/Y   disk centre relative to the right joint
P_C1X/Y   disk centre relative to the left joint
P_HW      half finger width
P_LMAX    finger length
P_TAU     actuation torque
P_KAPPA   joint torsion stiffness
P_TH0     rest angle of the fingers [rad]
P_THMIN   closed-jaw angle (joint stop) [rad]
P_PHASE   angle of the first contour point [rad]
P_RHO     rounding radius of the finger corners
P_KA      area stiffness ``c_A K / (s E)`` of the area energy (0: springs only, the paper's fan)
P_A0      rest area of a fan triangle ``sin(2 pi / N) / 2``
P_RINGS   rings M of the disk's point mesh (1: the paper's fan; :mod:`envs.model.rings`)
P_MU      element energy: 0 for springs and the area energy, else the shear modulus ``mu / E``
          of the constant-strain neo-Hookean triangle that replaces them
P_LAM     its Lame modulus ``lambda / E`` (plane strain; 0 for the nh-quad element, whose
          volumetric part acts per quad)
P_QUAD    volumetric stiffness ``lambda / E`` of the area energy per quad of a ring mesh (the
          nh-quad element; 0: none)
P_SPACING ring spacing of a ring mesh: 0 geometric from the hub, 1 even (:mod:`envs.model.rings`)
P_GROOVE0 the right finger's jaw groove, ``N_GROOVE`` slots ``G_*`` (:mod:`envs.model.jaw`)
P_GROOVE1 the left finger's
P_SHAPE   the object's shape: ``SHAPE_DISK`` (0, the disk's own code paths) or ``SHAPE_OUTLINE``
P_ORIENT  an outline's orientation ``psi`` [rad] (:mod:`envs.model.outline`)
P_OUTLINE an outline's ``N_OUTLINE`` B-spline coefficients of ``r(phi) / r_eq``
========  ==================================================================================

The kernels keep a longer private copy: the solver's slots P_GAUGE (stiffness of the rotation
gauge spring), P_POLICY (contact policy of the attempt) and the gauge's state in the fast
attempt (envs.solver.gauge): P_GREF (its anchor), P_GMAX (its starting stiffness) and P_GPROX
(its mode, one of the ``GAUGE_*`` values); then, from N_KERNEL_PARAMS on, the ring table of
the mesh (:func:`envs.model.rings.fill_ring_table`).
"""

from __future__ import annotations

import numpy as np

# parameter vector
P_KR, P_KC, P_H, P_C0X, P_C0Y, P_C1X, P_C1Y, P_HW, P_LMAX = range(9)
P_TAU, P_KAPPA, P_TH0, P_THMIN, P_PHASE, P_RHO, P_KA, P_A0, P_RINGS = range(9, 18)
P_MU, P_LAM, P_QUAD, P_SPACING = 18, 19, 20, 21
# the groove of each finger's jaw, N_GROOVE slots a finger (envs.model.jaw.pack_groove, G_*)
G_POSITION, G_DEPTH, G_CENTRE, G_RADIUS, G_COS, G_SIN, G_MOUTH = range(7)
N_GROOVE = 7
P_GROOVE0 = 22  # right finger's groove (P_GROOVE0 + G_*)
P_GROOVE1 = P_GROOVE0 + N_GROOVE  # left finger's
# the object's outline (envs.model.outline): a disk has SHAPE_DISK and zeros after it
N_OUTLINE = 128  # B-spline coefficients of r(phi) / r_eq over 2 pi
SHAPE_DISK, SHAPE_OUTLINE = 0.0, 1.0
P_SHAPE = P_GROOVE1 + N_GROOVE
P_ORIENT = P_SHAPE + 1
P_OUTLINE = P_SHAPE + 2
N_PARAMS = P_OUTLINE + N_OUTLINE
P_GAUGE = N_PARAMS  # solver copy only: gauge spring stiffness
P_POLICY = N_PARAMS + 1  # solver copy only: contact policy of this attempt
P_GREF = N_PARAMS + 2  # solver copy only: the gauge spring's anchor (point 0's tangential
# displacement)
P_GMAX = N_PARAMS + 3  # solver copy only: the gauge stiffness at the start of the attempt
P_GPROX = N_PARAMS + 4  # solver copy only: the gauge's mode (GAUGE_* below)
N_KERNEL_PARAMS = N_PARAMS + 5  # the ring table follows

# ring spacing of a ring mesh (slot P_SPACING)
SPACING_GEOMETRIC = 0.0
SPACING_EVEN = 1.0

# modes of the gauge spring (slot P_GPROX)
GAUGE_AT_REST = 0.0  # holds point 0 at rest; tested for holding up a saddle (fast attempt)
GAUGE_PROXIMAL = 1.0  # re-anchored at each iterate, its stiffness adapted to the step length
GAUGE_HELD = -1.0  # holds point 0 at rest, no saddle test (the plain attempts)

# scene row: one scene and its torque, SI units (the fields of envs.model.problem.SceneColumns);
# S_OFFSET_X: the disk centre's x, across the gripper's axis (0: on the axis)
(S_LENGTH, S_REST_ANGLE, S_JOINT_OFFSET, S_WIDTH, S_TORSION, S_RADIUS, S_DISTANCE, S_YOUNG,
 S_POISSON, S_THICKNESS, S_SCALE, S_CONTOUR_RATIO, S_AREA_SCALE, S_TORQUE) = range(14)
S_OFFSET_X = 14
# the object's shape (SHAPE_*), an outline's orientation psi [rad] (counter-clockwise from +x,
# across the jaws, to its first axis) and its N_OUTLINE B-spline coefficients of r(phi) / r_eq
# (envs.model.outline); S_RADIUS is then r_eq = sqrt(A / pi) and S_DISTANCE the distance from
# the joints' line to the outline's lowest point. A disk: SHAPE_DISK and zeros.
N_SCENE_SCALARS = S_OFFSET_X + 1  # the scalar columns of a scene row come first
S_SHAPE = N_SCENE_SCALARS
S_ORIENT = S_SHAPE + 1
S_OUTLINE = S_SHAPE + 2
# the jaw profile of each finger (envs.model.jaw.JawProfile), SI: J_* slots from S_JAW0 (right
# finger) and S_JAW1 (left finger); depth 0 is the straight bar
J_DEPTH, J_BOTTOM_RADIUS, J_OPENING, J_POSITION = range(4)
N_JAW = 4
S_JAW0 = S_OUTLINE + N_OUTLINE
S_JAW1 = S_JAW0 + N_JAW
N_SCENE = S_JAW1 + N_JAW

# solver options
O_TOL, O_MAXIT, O_MAXROUND, O_MU0, O_POLISH, O_GAUGE, O_POLISH_STEPS = range(7)
N_OPTIONS = 7

# info vector written by the compiled solve of one grasp
I_STATUS = 0  # status code (envs.solver.status)
I_ITERATIONS = 1  # Newton iterations of all rounds, polishes and policies
I_ROUNDS = 2  # outer rounds over the contact candidate sets
I_STABLE = 3  # 1.0: strict local minimum (the constrained Newton matrix positive definite)
I_STATIONARITY = 4  # stationarity residual / force scale
I_CONTACT_GAP = 5  # largest |gap| of a loaded constraint
I_MIN_GAP = 6  # smallest gap of a considered constraint
I_INVERTED = 7  # fan triangles turned over
N_INFO = 8

# constraint kinds
KIND_FACE, KIND_CORNER, KIND_STOP = 0, 1, 2
# the rounded convex corners of a finger (corner-against-edge constraints): the gripping face's
# tip and root ends, the back's tip and root ends, and the two mouth edges of a jaw groove (on
# the tip side, s = a + u_E, and the root side, s = a - u_E; inactive for a straight jaw)
C_FACE_TIP, C_FACE_ROOT, C_BACK_TIP, C_BACK_ROOT, C_MOUTH_TIP, C_MOUTH_ROOT = range(6)
N_CORNERS = 6
N_BAR_CORNERS = 4  # the corners every finger has (the bar's ends); the mouth's follow


def default_options() -> np.ndarray:
    """Solver options, indexed by the ``O_*`` names.

    Stationarity tolerance (relative to the force scale), interior-point iteration limit,
    outer-round limit, initial barrier factor, polish on/off, gauge stiffness factor and the
    Newton steps one polish may take.
    """
    opts = np.zeros(N_OPTIONS)
    opts[O_TOL] = 1e-12
    opts[O_MAXIT] = 300.0
    opts[O_MAXROUND] = 12.0
    opts[O_MU0] = 1e-2
    opts[O_POLISH] = 1.0
    opts[O_GAUGE] = 1.0
    opts[O_POLISH_STEPS] = 40.0
    return opts
