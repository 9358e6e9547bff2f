"""Finite-element reference for the soft-disk grasp (scikit-fem, quadratic triangles).

This package solves the same quasi-static grasp as the point-spring model (see
``docs/model.md``) with a continuum model, so that the point-spring results can be
checked against a mesh-converged reference:

* the disk is meshed with quadratic triangles: isoparametric P2 geometry (``MeshTri2``, the
  midside nodes of the rim are on the circle) and P2 displacements
  (``ElementVector(ElementTriP2())``);
* the material is a compressible neo-Hookean solid,
  ``W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2`` per unit reference volume, with the Lame
  parameters of the *physical* ``E`` and ``nu`` of the disk. The point-spring calibration factor
  ``stiffness_scale`` is deliberately ignored: the FEM is the physical reference;
* plane strain (default, out-of-plane stretch 1) or plane stress (out-of-plane stretch
  ``lambda_3`` solved at every quadrature point from ``S_33 = 0``, i.e. the exact plane-stress
  reduction of the same 3-D energy; it linearises to the usual plane-stress elasticity);
* the energy per unit reference area is multiplied by the (reference) thickness ``t``;
* the centre of the disk is held by a small rigid hub: every P2 node within ``hub_radius_m``
  (default ``0.1 r``) of the centre is fixed; the mesh has a ring of nodes (with curved P2
  edges) exactly on the hub's edge, so the hub is the same circle on every mesh. The peak strain
  is measured outside the hub (and outside a layer of one hub radius around it, where the hub
  causes a local concentration, reported separately);
* each finger is a rigid bar on a torsion spring, torque controlled: the unknowns are the
  displacement field and the two finger angles, the finger potential is
  ``T_a theta + k_f (theta - theta_a0)^2 / 2``;
* frictionless contact between every rim node of the P2 mesh (vertices and midside nodes) and the
  gripping face of each finger, by a node-to-face penalty ``eps/2 min(g, 0)^2`` weighted by the
  node's share of the rim (Simpson weights ``L/6, 2L/3, L/6`` of each quadratic rim edge) and by
  ``t``, i.e. a pressure penalty (default ``eps = 100 E / h``); optional augmented-Lagrangian
  updates reduce the penetration;
* the tip corner of each gripping face (``J + l e + (w/2) n``) is a second contact feature: a
  corner-to-rim penalty on its signed distance to the deformed rim polygon (rim nodes in order),
  with stiffness ``eps t`` times the mean rim segment length. It matters when the disk sits
  beyond the finger tips (e.g. the forceps scenes); the force it carries is reported separately.
  The end face of the bar is not modelled (a node beyond the tip is free);
* the closed-jaw stop of ``closed_angle_rad`` is a stiff one-sided torsion penalty
  (``1e4 k_f``), reached only when the disk is out of reach.

The coupled displacement/angle system is solved by Newton's method with exact tangents: the
elastic tangent is assembled from the scikit-fem basis (vectorised element kernels on the
``Basis`` gradients, quadrature weights and dof maps, checked against ``skfem.asm`` in the
tests), contact derivatives with respect to the displacements and the angles are added exactly
(the corner Hessian by complex-step differentiation of the analytic gradient, exact to
round-off), the linear systems are solved with SuperLU (minimum-degree ordering on ``A^T + A``,
symmetric mode, ordering reused between Newton steps), steps are globalised by a bracketing
strong-Wolfe line search on the total potential with an anti-tunnelling penetration cap, and a
failed load step is bisected. Each load step starts from the secant extrapolation of the two
previous converged states when that is admissible.

Public API
----------
:func:`fem_grasp`, :class:`FemResult`, :func:`fem_plate_compression`,
:func:`hertz_line_compression`,
:data:`FEM_VERSION`, :func:`default_mesh_size_m`.

Layout
------
One file per job: :mod:`.mesh` (structured disk meshes, the hub ring, the graded quarter disk),
:mod:`.material` (neo-Hookean energy, stress and tangent), :mod:`.body` (the P2 body and its
assembly), :mod:`.contact` (rim nodes, jaw faces, plate, tip corners), :mod:`.system` (the
total potential of the coupled unknowns), :mod:`.newton` (Newton, line search, load ramp),
:mod:`.result` (:class:`FemResult`), :mod:`.cache` (the disk cache), :mod:`.grasp`
(:func:`fem_grasp`) and :mod:`.hertz` (the plate-compression check against Hertz).
"""

from __future__ import annotations

from .body import _Body as _Body
from .cache import FEM_VERSION, fem_cache_dir
from .grasp import fem_grasp
from .hertz import fem_plate_compression, hertz_line_compression
from .material import _lame as _lame
from .material import _neo_hookean as _neo_hookean
from .mesh import _arc_facets as _arc_facets
from .mesh import _fan_mesh as _fan_mesh
from .mesh import _quadratic_mesh as _quadratic_mesh
from .mesh import default_mesh_size_m
from .result import FemResult

__all__ = [
    "FemResult",
    "fem_grasp",
    "fem_plate_compression",
    "hertz_line_compression",
    "default_mesh_size_m",
    "FEM_VERSION",
    "fem_cache_dir",
]
