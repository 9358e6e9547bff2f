"""Meshes of the disk: structured fans, the grasp mesh with its hub ring, the graded quarter.

Straight-sided :class:`skfem.MeshTri` meshes are built here and turned into isoparametric P2
meshes (:class:`skfem.MeshTri2`) whose rim (and hub-edge) midside nodes lie on their circles.
Also the default element size of the grasp mesh and the validation of a mesh size.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from skfem import MeshTri, MeshTri2

from envs.validation import check_range

_DEFAULT_RINGS = 12  # rings of the default disk mesh: 6 * 12**2 = 864 elements


def _check_mesh_size(mesh_size_m: float, radius_m: float) -> float:
    return check_range("mesh_size_m", mesh_size_m, 0.0, radius_m, low_open=True, high_open=True)


def default_mesh_size_m(radius_m: float) -> float:
    """Default element size of the grasp mesh, ``r / 12`` (864 quadratic triangles) [m]."""
    return radius_m / _DEFAULT_RINGS


def _fan_mesh(
    radius_m: float,
    rings: int,
    sectors: int,
    start_angle_rad: float,
    span_rad: float,
    ring_radii_m: np.ndarray | None = None,
) -> MeshTri:
    """Structured disk (or disk sector) mesh of straight triangles.

    The domain is cut into ``sectors`` equal circular sectors; each one carries the regular
    triangulation of a triangle with ``rings`` lattice rows, mapped so that row ``k`` lies on the
    circle of radius ``k r / rings`` (or ``ring_radii_m[k - 1]``) with uniformly spaced nodes.
    With six sectors starting at ``pi/2`` the full disk is mirror symmetric about the y axis (and
    nearly equilateral). Centred at the origin.
    """
    periodic = math.isclose(span_rad, 2 * math.pi)
    points = [np.zeros((2, 1))]
    first = [0]
    count = 1
    for k in range(1, rings + 1):
        n = sectors * k if periodic else sectors * k + 1
        ang = start_angle_rad + np.arange(n) * span_rad / (sectors * k)
        rad = radius_m * k / rings if ring_radii_m is None else float(ring_radii_m[k - 1])
        points.append(np.vstack((rad * np.cos(ang), rad * np.sin(ang))))
        first.append(count)
        count += n

    def index(k: int, s: int, i: np.ndarray) -> np.ndarray:
        if k == 0:
            return np.zeros_like(i)
        g = s * k + i
        if periodic:
            g = g % (sectors * k)
        return first[k] + g

    tris = []
    for s in range(sectors):
        for k in range(1, rings + 1):
            i = np.arange(k)
            tris.append(np.vstack((index(k - 1, s, i), index(k, s, i), index(k, s, i + 1))))
            j = np.arange(k - 1)
            tris.append(np.vstack((index(k - 1, s, j), index(k, s, j + 1), index(k - 1, s, j + 1))))
    p = np.hstack(points)
    p[np.abs(p) < 1e-15 * radius_m] = 0.0
    return MeshTri(p, np.hstack(tris).astype(np.int64))


def _quadratic_mesh(
    mesh: MeshTri,
    radius_m: float,
    arc_facets: np.ndarray,
    centre: np.ndarray | None = None,
    extra_circles: Sequence[tuple[float, np.ndarray]] = (),
) -> MeshTri2:
    """Quadratic (isoparametric) copy of ``mesh`` with the rim midside nodes on the circle.

    ``centre`` is the centre of the circle (default: origin); ``extra_circles`` lists further
    ``(radius, facets)`` whose midside nodes are moved onto concentric circles (the hub edge).
    """
    c = np.zeros((2, 1)) if centre is None else np.asarray(centre, dtype=float).reshape(2, 1)
    m2 = MeshTri2.from_mesh(mesh)
    loc = m2.doflocs.copy()
    for rad, facets in [(radius_m, arc_facets), *extra_circles]:
        dofs = m2.dofs.get_facet_dofs(facets).flatten()
        rel = loc[:, dofs] - c
        loc[:, dofs] = c + rel * (rad / np.linalg.norm(rel, axis=0))
    return replace(m2, doflocs=loc)


def _arc_facets(mesh: MeshTri, radius_m: float, boundary: bool = True) -> np.ndarray:
    """Facets lying on the circle of radius ``radius_m`` about the origin (both end nodes on it).

    Only boundary facets are searched unless ``boundary`` is false.
    """
    cand = mesh.boundary_facets() if boundary else np.arange(mesh.facets.shape[1])
    ends = mesh.p[:, mesh.facets[:, cand]]  # (2, 2, nf)
    rad = np.linalg.norm(ends, axis=0)
    on = np.all(np.abs(rad - radius_m) < 1e-9 * radius_m, axis=0)
    return cand[on]


def _grasp_mesh(radius_m: float, rings: int, hub_radius_m: float) -> tuple[MeshTri, int]:
    """Ring radii of the grasp mesh: one ring lies exactly on the hub's edge.

    ``k_h = max(1, round(rings * hub / r))`` rings evenly fill the hub and the remaining
    ``rings - k_h`` evenly fill the annulus ``hub < rho < r``, so that the rigid hub is the same
    circle on every mesh (a hub made of "the nodes that happen to lie inside" would change its
    size with the mesh, and the hub's compliance with it). Returns the straight-sided mesh
    (centred at the origin) and ``k_h``.
    """
    k_h = int(min(rings - 1, max(1, round(rings * hub_radius_m / radius_m))))
    inner = hub_radius_m * np.arange(1, k_h + 1) / k_h
    outer = hub_radius_m + (radius_m - hub_radius_m) * np.arange(1, rings - k_h + 1) / (rings - k_h)
    radii = np.concatenate((inner, outer))
    return _fan_mesh(radius_m, rings, 6, math.pi / 2, 2 * math.pi, radii), k_h


def _project_rim(mesh: MeshTri, radius_m: float, quarter: bool) -> MeshTri:
    """Move the boundary nodes of the rim (not of the symmetry lines) onto the circle."""
    p = mesh.p.copy()
    nodes = mesh.boundary_nodes()
    if quarter:
        tol = 1e-12 * radius_m
        nodes = nodes[(p[0, nodes] > tol) & (p[1, nodes] > tol)]
    p[:, nodes] *= radius_m / np.linalg.norm(p[:, nodes], axis=0)
    return replace(mesh, doflocs=p)


def _graded_quarter_mesh(radius_m: float, contact_size_m: float) -> tuple[MeshTri, int]:
    """Quarter disk (x, y >= 0, centred at the origin) refined towards the top point (0, r).

    Starts from the structured quarter mesh with ``max(8, r / contact_size)`` rings (capped) and
    bisects, level by level, the elements close to ``(0, r)`` until the element size there is at
    most ``contact_size_m``; rim nodes are projected back on the circle after every level.
    Returns the mesh and the number of refinement levels.
    """
    rings = int(min(16, max(8, math.ceil(radius_m / contact_size_m))))
    mesh = _fan_mesh(radius_m, rings, 2, 0.0, math.pi / 2)
    top = np.array([[0.0], [radius_m]])
    size = radius_m / rings
    levels = 0
    while size > contact_size_m * (1 + 1e-9) and levels < 30:
        centroids = mesh.p[:, mesh.t].mean(axis=1)
        dist = np.linalg.norm(centroids - top, axis=0)
        marked = np.nonzero(dist < 4.0 * size)[0]
        mesh = _project_rim(mesh.refined(marked), radius_m, quarter=True)
        size /= 2
        levels += 1
    return mesh, levels


# --- an outline's mesh: the disk mesh mapped radially onto it ------------------------------

_ARC_TABLE_POINTS = 4096  # arc-length table of the map: body angles at s = j / 4096


class OutlineMap:
    """The map of the unit disk onto an object's outline (:mod:`envs.model.outline`) that
    meshes it: the disk's point at radius ``rho`` and angle ``theta`` (counter-clockwise from
    the top) goes to ``rho r(phi) (cos(phi + psi), sin(phi + psi))``, with ``phi`` the body
    angle at the arc-length fraction ``(theta - pi / 2) / (2 pi)`` of the outline from its top.

    Rays go to rays, so the disk mesh's rings become the outline scaled about its centroid
    (the point-spring model's rings, :mod:`envs.model.rings`) and its rim nodes, spaced evenly
    in angle on the disk, lie on the outline spaced evenly by arc length. ``fraction`` inverts
    the radial part (where a point lies between the centroid and the outline, 0 to 1).
    """

    def __init__(self, coefficients: np.ndarray, orientation_rad: float, radius_m: float):
        from envs.model.outline import outline_body_angles, outline_length

        self.coef = np.ascontiguousarray(coefficients, dtype=np.float64)
        self.psi = float(orientation_rad)
        self.radius_m = float(radius_m)
        phi = outline_body_angles(self.coef, self.psi, _ARC_TABLE_POINTS)
        self._phi = np.append(phi, phi[0] + 2 * math.pi)  # unwrapped, s = 0 .. 1
        self.perimeter_m = float(outline_length(self.coef, 0)) * self.radius_m

    def body_angle(self, theta: np.ndarray) -> np.ndarray:
        """Body angle of the outline point the disk's rim angle ``theta`` maps to [rad]."""
        s = np.mod((np.asarray(theta) - math.pi / 2) / (2 * math.pi), 1.0)
        return np.interp(s * _ARC_TABLE_POINTS, np.arange(_ARC_TABLE_POINTS + 1), self._phi)

    def radius(self, phi: np.ndarray) -> np.ndarray:
        """``r(phi)`` [m]."""
        from envs.model.outline import outline_curve

        return outline_curve(self.coef, phi)[0] * self.radius_m

    def curvature_per_m(self, phi: np.ndarray) -> np.ndarray:
        """The outline's curvature at body angles ``phi`` [1/m]."""
        from envs.model.outline import outline_curvature

        return np.array([outline_curvature(self.coef, 0, float(p))
                         for p in np.ravel(phi)]).reshape(np.shape(phi)) / self.radius_m

    def apply(self, locs: np.ndarray, disk_radius_m: float) -> np.ndarray:
        """Map points ``locs`` (2, k) of the disk of radius ``disk_radius_m`` centred at the
        origin onto the outline (centred at the origin) [m]."""
        rho = np.hypot(locs[0], locs[1]) / disk_radius_m
        phi = self.body_angle(np.arctan2(locs[1], locs[0]))
        dist = rho * self.radius(phi)
        return np.vstack((dist * np.cos(phi + self.psi), dist * np.sin(phi + self.psi)))

    def fraction(self, points: np.ndarray, centre: np.ndarray) -> np.ndarray:
        """Where points (2, ...) lie between the centroid (0) and the outline (1) on their
        ray."""
        rel = points - centre.reshape((2,) + (1,) * (points.ndim - 1))
        phi = np.arctan2(rel[1], rel[0]) - self.psi
        return np.hypot(rel[0], rel[1]) / self.radius(phi)

    def arc_fraction(self, points: np.ndarray, centre: np.ndarray) -> np.ndarray:
        """Arc-length coordinate along the outline from its top, as a fraction of the
        perimeter in [0, 1), of points (k, 2) on it (or on their rays)."""
        rel = points - centre
        phi = np.arctan2(rel[:, 1], rel[:, 0]) - self.psi
        phi = self._phi[0] + np.mod(phi - self._phi[0], 2 * math.pi)
        return np.interp(phi, self._phi, np.arange(_ARC_TABLE_POINTS + 1)) / _ARC_TABLE_POINTS


def _p2_lengths(ends_a: np.ndarray, mids: np.ndarray, ends_b: np.ndarray) -> np.ndarray:
    """Lengths of quadratic edges through ``a``, the midside node ``m`` and ``b`` ((2, k)
    each): 3-point Gauss on ``|x'(xi)|``, ``x(xi) = a (1 - xi)(1 - 2 xi) + 4 m xi (1 - xi) +
    b xi (2 xi - 1)``."""
    total = np.zeros(ends_a.shape[1])
    for xi, w in ((0.5 - math.sqrt(0.15), 5 / 18), (0.5, 8 / 18), (0.5 + math.sqrt(0.15), 5 / 18)):
        d = ends_a * (4 * xi - 3) + mids * (4 - 8 * xi) + ends_b * (4 * xi - 1)
        total += w * np.hypot(d[0], d[1])
    return total
