"""Defaults of the model, each stated once, with where it comes from.

Paper values are from Tables 1 and 2 of the source paper (*Point-spring modeling of the grasp
of a deformable object by an angular gripper*), as the model's conventions fix them
(``docs/model.md``); the others are choices of this package, with the reason.
"""

from __future__ import annotations

import math

# --- discretization ------------------------------------------------------------------------
MIN_TRIANGLES = 4  # N = 3 gives 120-degree triangles: negative stiffness under the area rule
# Largest N accepted. Measured on 60 random designs of the default design box on the r = 0.07 m
# disk (springs only, the default): the solver answers (converges or reports a confirmed fold)
# for 59/60 at N = 20, 59/60 at 100, 56/60 at 200, 54/60 at 300, but only 44/60 at 500 and 22/60
# at 700 (the rest hit the iteration limit, a failed polish or a rejected check), at 125 ms a
# design at N = 500. Beyond 500 a run would mostly score solver failures.
MAX_TRIANGLES = 500
# The ring and constant-strain members converge on finer contours: the constant-strain mesh
# with 2 rings solved paper-r070 at 0.2 N·m with N = 1000 (34 Newton iterations) and N = 2000
# (43); the model itself is defined up to MODEL_MAX_TRIANGLES.
MAX_TRIANGLES_FAMILY = 2000
# Spring ring meshes (element "spring", M >= 2) are accepted only for cells of depth over width
# (envs.model.family.spring_cell_aspect) in [1 / MAX_SPRING_CELL_ASPECT, MAX_SPRING_CELL_ASPECT].
# Why: a quad cell cut by a diagonal carries shear only through its diagonal spring, so the
# lattice's shear modulus is s E a^2 / (1 + a^2)^2 for aspect a (affine homogenisation of the
# area-rule springs): 2/3 of the equilateral value the hybrid scales assume at a = 1, a third at
# a = 2.5, falling like 1 / a^2 beyond; the area energy cannot help (shear keeps areas). Measured
# (hybrid scales, M = 2-8 rings, N = 8-500, paper-r070 and -r050, RMS closing-angle error against
# the FEM over 0.05-0.5 N·m; `python scripts/ring_accuracy.py --aspect-sweep`, 2026-11-25): with
# N >= 20 and a in [0.4, 2.5], 0.8-4.3 %, median 1.6 % (28 member-disks); outside, 2.6-10.9 %,
# median 5.1 % (48), and the error grows as the member is refined in N at fixed M, too soft
# (mean error positive): on r070 M = 4: N = 20 1.6 %, 40 5.9 %, 100 8.4 %; M = 8: N = 40 1.4 %,
# 100 8.8 %, 200 10.9 %. At a ~ 70-200 (N = 1000-2000 with 2-4 rings) the exact Newton matrix
# is indefinite at every iteration from the lightest torque on (compressed springs soften the
# nearly shear-free slivers further) and the interior point crawls to its iteration limit.
# Finer contours are the constant-strain and nh-quad members' job.
MAX_SPRING_CELL_ASPECT = 2.5
MODEL_MAX_TRIANGLES = 20000
DEFAULT_N_TRIANGLES = 20  # the paper's mesh; ~3 % of the FEM closing angle after calibration
PAPER_N_TRIANGLES = DEFAULT_N_TRIANGLES  # the paper's fan: N = 20, one ring, springs only

# --- the default model: a member of the family (docs/model.md) --------------------------------
# The cheapest member within 2 % RMS and 4 % max of the FEM closing angle over 0.05-0.5 N·m on
# disks it was not fitted to (scripts/calibrate_family.py --element nhquad, 2026-11-24; held
# out: r = 0.06 / 0.085 m, E = 50 / 300 kPa, nu = 0.30 / 0.40): nh-quad, N = 40, M = 2 with
# its shipped scale: worst held-out disk 1.49 % RMS, 2.87 % max, ~0.9 ms compiled per torque
# of a ramp (~1.2 ms from rest). Cheaper candidates miss the tolerance (nh-quad 32 x 2: 4.6 %
# max; constant-strain 20 x 3: 8.9 %; the hybrid springs 20 x 2: 21.5 %; the paper's fan at
# s = 1: 38-44 %). Per scene a cheaper member can do: envs.accuracy.choose_model(scene, 0.04)
# picks this one on paper-r100 and the hybrid springs 20 x 2 on paper-r050 and -r070 (max 3.0
# and 3.8 % there); the default must hold for objects nobody checked, hence the held-out rule:
# choose_model(list(heldout_scenes().values()), 0.04, rms_tolerance=0.02) over its default
# candidates returns this member (envs.accuracy.DEFAULT_MODEL; tests/test_rings.py::
# test_the_default_model_is_the_choice_on_disks_no_scale_was_fitted_to).
# The paper's fan is element="spring" (N then defaults to 20 and M to 1).
DEFAULT_ELEMENT = "nhquad"
DEFAULT_MODEL_N_TRIANGLES = 40
DEFAULT_MODEL_RINGS = 2
DEFAULT_TOLERANCE = 0.04  # largest relative closing-angle error the default model is chosen for
DEFAULT_PHASE_RAD = math.pi / 2  # first contour point at the top: mirror-symmetric for even N
STIFFNESS_RULES = ("van_gelder", "cst_fit")
DEFAULT_STIFFNESS_RULE = "van_gelder"  # docs/model.md: the area rule

# --- gripper and material (docs/model.md, paper Tables 1 and 2) -----------------------------
PAPER_TORSION_STIFFNESS_NM_PER_RAD = 0.073  # k_f of the paper gripper
DEFAULT_YOUNGS_MODULUS_PA = 100e3
DEFAULT_POISSON_RATIO = 0.45
DEFAULT_THICKNESS_M = 0.01
DEFAULT_STIFFNESS_SCALE = 1.0
DEFAULT_CONTOUR_STIFFNESS_RATIO = 1.0  # the plain stiffness rule
# The joint spring of a design relative to its object: k_f over the object's torque unit
# s E t r^2 [1/rad]. The design space is relative to the object (lengths in radii, the torque in
# s E t r^2), and the model is invariant under that scaling only if the joint spring scales
# like the torque: an absolute 0.073 N·m/rad is ~100 times the largest torque of the design box
# on a 4 mm, 8 kPa tissue sample, whose designs then never reach it. Default: the paper
# gripper's spring on its r = 0.07 m disk (E = 100 kPa, t = 0.01 m, s = 1: torque unit
# 4.9 N·m), so every answer on that disk stays as it was.
PAPER_R070_TORQUE_UNIT_NM = DEFAULT_STIFFNESS_SCALE * DEFAULT_YOUNGS_MODULUS_PA \
    * DEFAULT_THICKNESS_M * 0.07**2
PAPER_TORSION_STIFFNESS_REL = PAPER_TORSION_STIFFNESS_NM_PER_RAD / PAPER_R070_TORQUE_UNIT_NM
# c_A of the area energy: 0 keeps the paper's springs-only fan the default until the
# calibrated members of the model family (interior rings) ship
DEFAULT_AREA_STIFFNESS_SCALE = 0.0

# --- contact geometry ----------------------------------------------------------------------
# Finger end corners are rounded with this radius (fraction of the disk radius, at most a
# twentieth of the finger width): it makes point-on-corner contact differentiable; its effect
# on the geometry is below 1e-3 r.
CORNER_ROUNDING = 1e-3

# --- design objective ----------------------------------------------------------------------
# admissible compressive strain of the grasped object: a limit on the peak compression (the
# largest shortening of a radius by the fingers, over r; envs.evaluate_designs), the
# optimizers' and the batch evaluator's default; the environment draws its own per object.
# Soft tissue and produce bruise at strains of 0.1-0.2 (0.15 on the peak log strain); the
# compression, which converges with the mesh where the point-load strain does not, is 0.66 of
# the log strain at the median of 300 random designs on the paper disks (FEM: 0.066 against
# 0.100), so 0.10 on it is that limit
DEFAULT_STRAIN_LIMIT = 0.10

# Coulomb friction coefficient between the fingers and the object: a design whose grasp needs
# more does not hold the object once its centre is free (envs.model.holding). Default 0.5, a
# rubber or silicone finger pad on skin, fruit or soft tissue: dry material pairs mostly lie
# at 0.3-0.6, gripping surfaces on skin were measured at 0.36-0.63 (medical tapes) and 0.7-1.2
# (sandpapers) (Table 1 of PMC4808115), the friction of human skin on most materials at about
# 0.2-1 (Derler and Gerhardt, Tribology Letters 45, 2012). Wet tissue on polished steel jaws
# slips at much less (0.1-0.3): give such an object its own coefficient.
DEFAULT_FRICTION_COEFFICIENT = 0.5
MAX_FRICTION_COEFFICIENT = 10.0  # beyond any Coulomb contact (a hook, not friction)

# The finite-element fidelity of evaluate_designs: rings of the disk mesh (element size r / 12,
# 864 quadratic triangles, ~3,500 unknowns; the mesh of the accuracy references, within ~0.5 %
# of the mesh-converged closing angle on the paper disks), and the largest accepted
FEM_DESIGN_RINGS = 12
FEM_MAX_RINGS = 40

# --- payload -------------------------------------------------------------------------------
# A grasp must carry its object: the payload W = f m g, m = rho pi r^2 t, that friction at the
# contacts carries beside the fixed centre's reaction, out of the plane and in every in-plane
# direction (envs.model.holding). f = 2: the weight plus a lift accelerating at 1 g; 0 turns
# the payload off (holding then judges the reaction alone).
GRAVITY_M_S2 = 9.81
DEFAULT_PAYLOAD_FACTOR = 2.0
MAX_PAYLOAD_FACTOR = 100.0  # a lift at 99 g: beyond any gripper
# Densities [kg/m^3]. The paper's disks are soft foam (E = 100 kPa): flexible polyurethane
# foams have relative densities of about 0.02-0.05 of their ~1200 kg/m^3 solid, 25-60 kg/m^3
# (Gibson and Ashby, Cellular Solids, 2nd ed., 1997, ch. 1); 50 is taken. Soft tissue is about
# 1060 (liver 1060, muscle 1090, fat 900-950: ICRU Report 44, 1989), fruit 950-1050 (a tomato
# sinks slowly: ~1000), silicone rubber ~1100, TPU 1100-1250 (~1200, the forceps' beads). An
# object file without a density is taken as water-like, 1000: the conservative choice for the
# soft objects a gripper designer brings (a foam must say so).
FOAM_DENSITY_KG_M3 = 50.0
TPU_DENSITY_KG_M3 = 1200.0
OBJECT_DENSITY_KG_M3 = 1000.0
# one default for the API and object files: water-like (produce, tissue, silicone lie within 10 %);
# the paper's presets are foam and say so (envs.scene.PRESETS)
DEFAULT_DENSITY_KG_M3 = OBJECT_DENSITY_KG_M3

# Plausible ranges [SI]: a value outside is most likely typed in another unit (a radius of 15
# "m" meant in millimetres gives 62 m fingers) or not meant at all (a stiffness scale of 1e30).
# Every entry refuses such a value with the unit it was most likely typed in
# (envs.validation.check_plausible). An object's description: soft objects span ~100 Pa
# (hydrogels, brain) to tens of MPa (TPU, rubber), 1e10 Pa is a glass; the calibration scale s
# of the point-spring model is ~0.8-1 for the default model, 0.033 for the forceps' TPU beads
# and never beyond a factor 1000 either way. A gripper (two rigid fingers and joint springs)
# for such objects: the design box reaches fingers of 8 radii for the 1 m radius at the top of
# the objects' range, and microgrippers of a few micrometres at its bottom; a joint spring
# beyond 1e4 N·m/rad is a rigid joint. A gripper value outside is refused the same way
# (millimetres typed for metres: finger_length_m = 200).
PLAUSIBLE_RANGES: dict[str, tuple[float, float]] = {
    "radius_m": (1e-5, 1.0),
    "thickness_m": (1e-6, 1.0),
    "youngs_modulus_pa": (50.0, 1e10),
    "density_kg_m3": (5.0, 25e3),
    "stiffness_scale": (1e-3, 1e3),
    "finger_length_m": (1e-6, 10.0),
    "joint_offset_m": (0.0, 10.0),
    "finger_width_m": (1e-8, 2.0),
    "distance_m": (-10.0, 10.0),
    "offset_x_m": (-10.0, 10.0),
    "placement_tolerance_m": (0.0, 1.0),
    "torsion_stiffness_nm_per_rad": (0.0, 1e4),
}
# The squeeze of a plausible actuation torque: at most this many of the object's torque unit
# s E t r^2 beyond what the joint springs take when the fingers close fully (k_f pi / 2). At 10
# units the r = 0.07 m paper disk is compressed by 75 % (envs.simulate(Scene.preset(
# "paper-r070"), 50.0): peak compression 0.750, peak strain 2.3); a larger torque is a unit slip
# (N·mm typed for N·m) or not meant, and far beyond the model's range.
MAX_TORQUE_UNITS = 10.0
# A relative joint spring at most, in the object's torque unit per radian: it would take the
# largest plausible squeeze (MAX_TORQUE_UNITS) in a tenth of a radian (the paper's is 0.0149)
MAX_SPRING_REL = 100.0
