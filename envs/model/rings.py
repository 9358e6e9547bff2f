"""The disk's point mesh: the paper's fan (one ring) and the ring meshes of the model family.

Layout (docs/model.md, model family), in units of the radius r:

* ``M`` rings ``k = 1 .. M`` of ``N`` points each, point ``(k, i)`` at angle
  ``phase + 2 pi i / N`` on the circle of radius ``rho_k``; ring ``M`` is the contour
  (``rho_M = 1``), the only one that touches the fingers.
* Ring 0 holds the disk: for ``M = 1`` the pinned centre (the paper's fan); for ``M >= 2`` a
  rigid hub of ``N`` fixed points on the circle of radius :data:`HUB_RADIUS` (the FEM
  reference's boundary condition), so that the inner rings are not crowded onto one point.
* Ring radii between the hub and the contour are geometric, ``rho_k = h^((M - k) / M)``
  (``h`` the hub radius; slot ``P_SPACING`` = ``SPACING_GEOMETRIC``): with ``N`` points on
  every ring a cell's radial size then stays in proportion to its tangential size
  ``2 pi rho / N``, so triangles keep their shape from hub to rim instead of becoming needles
  near the centre. The nh-quad element uses even spacing, ``rho_k = h + (1 - h) k / M``
  (``SPACING_EVEN``): its thinnest layers are then not at the hub but where the fingers press
  (measured: geometric spacing gave it a larger error against the FEM for the same cost).
* A quad is the cell between rings ``k - 1`` and ``k`` and angles ``i, i + 1``; its corners
  counter-clockwise are ``(k - 1, i), (k, i), (k, i + 1), (k - 1, i + 1)``
  (:func:`quad_corners`), its area the sum of its two triangles'.
* Between rings ``k - 1`` and ``k`` each quad of angles ``i, i + 1`` is cut by a diagonal whose
  direction alternates with the parity of ``i`` (for even ``N`` the mesh is then mirror
  symmetric about the axis through point 0, as the scene is). Every edge carries a spring with
  the area rule (van Gelder): ``k_c = s E t sum_e A_e / |c|^2`` over the triangles sharing it;
  every triangle the area energy.

State vector ``x = (contour points, theta_R, theta_L, interior points)``: the contour and the
fingers keep the fan's slots (the contact code sees only them); interior point ``(k, i)``,
``1 <= k < M``, follows at ``2 N + 2 + 2 ((k - 1) N + i)``.

The per-layer constants (radii, rest lengths and areas) are written once per solve into the
kernel's parameter copy after its solver slots (:func:`fill_ring_table`), so that every energy
term reads them by name (``R_*`` columns) instead of recomputing trigonometry.

An object that is not a disk (slot ``P_SHAPE``, :mod:`envs.model.outline`) has the same mesh
mapped radially onto its outline: the rest position of point ``(k, i)`` is ``rho_k u_i``, with
``u_i`` the outline's contour point ``i`` (spaced evenly by arc length, in units of ``r_eq``)
in place of the unit direction, so the hub is the outline scaled by :data:`HUB_RADIUS`. Its
quads then differ around a ring: their rest areas are tabled per quad, and the contour points'
rest distances from the centroid per point (:func:`quad_rest_area_at`,
:func:`contour_rest_radius`). The springs' per-ring constants serve disks only (a spring
member refuses an outline, :func:`envs.model.problem.pack_params`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .geometry import rest_point
from .layout import (
    N_KERNEL_PARAMS,
    N_PARAMS,
    P_A0,
    P_H,
    P_KC,
    P_KR,
    P_ORIENT,
    P_OUTLINE,
    P_PHASE,
    P_RINGS,
    P_SHAPE,
    P_SPACING,
    SHAPE_DISK,
    SPACING_EVEN,
)
from .outline import outline_contour_into

__all__ = [
    "HUB_RADIUS",
    "MAX_RINGS",
    "R_RHO",
    "R_LRAD",
    "R_LCIRC",
    "R_LDIAG",
    "R_AOUT",
    "R_AIN",
    "N_RING_COLS",
    "ring_radius",
    "ring_rho",
    "quad_corners",
    "quad_xy",
    "quad_rest_area",
    "quad_rest_area_at",
    "contour_rest_radius",
    "ring_table_size",
    "fill_ring_table",
    "kernel_params",
    "kernel_copy",
    "kernel_copy_into",
    "n_state",
    "point_dof",
    "n_edge_types",
    "n_tri_types",
    "edge_ends",
    "edge_constants",
    "tri_corners",
    "tri_rest_area",
    "point_xy",
    "edge_xy",
    "tri_xy",
    "rest_xy",
    "ring_rest_state_into",
    "mesh_band_index",
    "mesh_half_bandwidth",
]

HUB_RADIUS = 0.1  # rigid hub of ring meshes [r]: the FEM reference holds the disk the same way
MAX_RINGS = 16

# ring table: one row per ring k = 0 .. M (row 0: the hub or the centre)
R_RHO = 0  # radius of ring k
R_LRAD = 1  # rest length of a radial edge (k - 1, i) - (k, i)
R_LCIRC = 2  # rest length of a circumferential edge (k, i) - (k, i + 1)
R_LDIAG = 3  # rest length of a quad diagonal between rings k - 1 and k
R_AOUT = 4  # rest area of a layer-k triangle with two corners on ring k
R_AIN = 5  # rest area of a layer-k triangle with two corners on ring k - 1 (0 for the fan)
N_RING_COLS = 6

# edge types per layer (the fan has only the first two)
EDGE_RADIAL, EDGE_CIRC, EDGE_DIAG = 0, 1, 2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def ring_radius(k, m, spacing):
    """Radius of ring ``k`` of ``m`` [r]: 0 for the fan's centre, else from the hub to the rim,
    geometric or even by ``spacing`` (``SPACING_*``)."""
    if k == m:
        return 1.0
    if m == 1:
        return 0.0
    if spacing == SPACING_EVEN:
        return HUB_RADIUS + (1.0 - HUB_RADIUS) * k / m
    return HUB_RADIUS ** ((m - k) / m)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def ring_table_size(n, m):
    """Length of the ring table, the rest directions and an outline's tables (quad areas,
    contour radii) after the kernel slots."""
    return (m + 1) * N_RING_COLS + 2 * n + m * n + n


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _row(k):
    return N_KERNEL_PARAMS + k * N_RING_COLS


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _dir_slot(m):
    return N_KERNEL_PARAMS + (m + 1) * N_RING_COLS


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _quad_slot(n, m):
    """Start of an outline's quad rest areas (layer k, angle i at ``(k - 1) n + i``)."""
    return N_KERNEL_PARAMS + (m + 1) * N_RING_COLS + 2 * n


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _radius_slot(n, m):
    """Start of an outline's contour rest radii (point i at ``i``) [r_eq]."""
    return _quad_slot(n, m) + m * n


@njit(cache=True, error_model="numpy", _nrt=False)
def fill_ring_table(prm, n):
    """Write the ring table and the rest directions of the ``n`` angles into ``prm`` (the
    kernel copy, long enough: :func:`ring_table_size`); for an outline its contour points in
    place of the directions and its tables (see the module)."""
    m = int(prm[P_RINGS])
    delta = 2.0 * math.pi / n
    sd, cd = math.sin(delta), math.cos(delta)
    for k in range(m + 1):
        row = _row(k)
        rho = ring_radius(k, m, prm[P_SPACING])
        prm[row + R_RHO] = rho
        prm[row + R_LCIRC] = 2.0 * rho * math.sin(math.pi / n)
        if k == 0:
            prm[row + R_LRAD] = 0.0
            prm[row + R_LDIAG] = 0.0
            prm[row + R_AOUT] = 0.0
            prm[row + R_AIN] = 0.0
            continue
        rin = ring_radius(k - 1, m, prm[P_SPACING])
        prm[row + R_LRAD] = rho - rin
        # the diagonal joins (k - 1, i) to (k, i + 1) (or its mirror image)
        dx, dy = rho * cd - rin, rho * sd
        prm[row + R_LDIAG] = math.sqrt(dx * dx + dy * dy)
        prm[row + R_AOUT] = 0.5 * rho * (rho - rin) * sd
        prm[row + R_AIN] = 0.5 * rin * (rho - rin) * sd
    base = _dir_slot(m)
    if prm[P_SHAPE] == SHAPE_DISK:
        for i in range(n):
            prm[base + 2 * i], prm[base + 2 * i + 1] = rest_point(i, n, prm[P_PHASE])
        return
    outline_contour_into(prm, P_OUTLINE, prm[P_ORIENT], n, prm, base)
    _fill_outline_tables(prm, n, m)


@njit(cache=True, error_model="numpy", _nrt=False)
def _fill_outline_tables(prm, n, m):
    """An outline's quad rest areas and contour rest radii (from the rest positions)."""
    quads = _quad_slot(n, m)
    for k in range(1, m + 1):
        for i in range(n):
            ka, ia, kb, ib, kc, ic, kd, id_ = quad_corners(k, i, n)
            xa, ya = rest_xy(prm, n, m, ka, ia)
            xb, yb = rest_xy(prm, n, m, kb, ib)
            xc, yc = rest_xy(prm, n, m, kc, ic)
            xd, yd = rest_xy(prm, n, m, kd, id_)
            prm[quads + (k - 1) * n + i] = 0.5 * ((xa * yb - xb * ya) + (xb * yc - xc * yb)
                                                   + (xc * yd - xd * yc) + (xd * ya - xa * yd))
    radii = _radius_slot(n, m)
    base = _dir_slot(m)
    for i in range(n):
        prm[radii + i] = math.hypot(prm[base + 2 * i], prm[base + 2 * i + 1])


@njit(cache=True, error_model="numpy", _nrt=False)
def kernel_copy_into(params, n, out):
    """The kernels' copy of a packed row into ``out`` (zeroed solver slots, ring table)."""
    out[:] = 0.0
    for j in range(N_PARAMS):
        out[j] = params[j]
    fill_ring_table(out, n)


@njit(cache=True, error_model="numpy")
def kernel_copy(params, n):
    """:func:`kernel_copy_into` into a new array."""
    out = np.empty(N_KERNEL_PARAMS + ring_table_size(n, int(params[P_RINGS])))
    kernel_copy_into(params, n, out)
    return out


def kernel_params(params: np.ndarray, n: int) -> np.ndarray:
    """The kernels' copy of one parameter row: the solver slots zeroed and the ring table
    filled (what :func:`envs.model.energy.mesh_energy` reads), a new float64 array."""
    return kernel_copy(np.ascontiguousarray(params, dtype=np.float64), int(n))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def n_state(n, m):
    """Length of the state vector of an ``n``-point, ``m``-ring mesh."""
    return 2 * n * m + 2


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def point_dof(n, m, k, i):
    """Index in the state of the x coordinate of point ``(k, i)``; -1 for a fixed point (ring
    0)."""
    if k == m:
        return 2 * i
    if k == 0:
        return -1
    return 2 * n + 2 + 2 * ((k - 1) * n + i)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def point_xy(x, n, m, prm, k, i):
    """Position of point ``(k, i)`` in state ``x`` (ring 0: the fixed centre or hub point)."""
    d = point_dof(n, m, k, i)
    if d >= 0:
        return x[d], x[d + 1]
    if m == 1:
        return 0.0, 0.0
    rho = prm[_row(0) + R_RHO]
    base = _dir_slot(m)
    return rho * prm[base + 2 * i], rho * prm[base + 2 * i + 1]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def n_edge_types(m):
    """Edge families ``t``: per layer ``k`` radial, circumferential and diagonal
    (``t = 3 (k - 1) + EDGE_*``); the fan has the radial and the contour springs only."""
    return 2 if m == 1 else 3 * m


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def n_tri_types(m):
    """Triangle families: two per layer (one for the fan)."""
    return 1 if m == 1 else 2 * m


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _next(i, n):
    return i + 1 if i + 1 < n else 0


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def edge_ends(t, i, n, m):
    """Ends ``(ka, ia, kb, ib)`` of edge ``i`` of family ``t`` (a fixed end, if any, first)."""
    k = t // 3 + 1
    kind = t % 3
    i1 = _next(i, n)
    if kind == EDGE_RADIAL:
        return k - 1, i, k, i
    if kind == EDGE_CIRC:
        return k, i, k, i1
    if i % 2 == 0:
        return k - 1, i, k, i1
    return k - 1, i1, k, i


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _left_right_areas(prm, k, i, n):
    """Rest areas of the two triangles sharing radial edge ``(k - 1, i) - (k, i)``: the one in
    quad ``i`` and the one in quad ``i - 1``."""
    row = _row(k)
    a_out, a_in = prm[row + R_AOUT], prm[row + R_AIN]
    im = i - 1 if i > 0 else n - 1
    left = a_out if i % 2 == 0 else a_in
    right = a_in if im % 2 == 0 else a_out
    return left + right


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def edge_constants(prm, t, i, n, m):
    """Stiffness (per ``s E t``) and rest length of edge ``i`` of family ``t``: the area rule
    over the triangles sharing it. The fan's and the contour's springs are the packed
    ``P_KR``, ``P_KC`` (the contour ratio and the fan's stiffness rule included)."""
    k = t // 3 + 1
    kind = t % 3
    row = _row(k)
    if kind == EDGE_CIRC:
        if k == m:
            return prm[P_KC], prm[P_H]
        # shared by the outer triangle of layer k and the inner one of layer k + 1
        rest = prm[row + R_LCIRC]
        return (prm[row + R_AOUT] + prm[_row(k + 1) + R_AIN]) / (rest * rest), rest
    if m == 1:
        return prm[P_KR], 1.0
    if kind == EDGE_RADIAL:
        rest = prm[row + R_LRAD]
        return _left_right_areas(prm, k, i, n) / (rest * rest), rest
    rest = prm[row + R_LDIAG]
    return (prm[row + R_AOUT] + prm[row + R_AIN]) / (rest * rest), rest


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def tri_corners(t, i, n, m):
    """Corners ``(ka, ia, kb, ib, kc, ic)`` of triangle ``i`` of family ``t``, counter-clockwise
    (the fan's: centre, ``q_i``, ``q_i+1``)."""
    i1 = _next(i, n)
    if m == 1:
        return 0, i, 1, i, 1, i1
    k = t // 2 + 1
    second = t % 2
    if i % 2 == 0:
        # diagonal (k - 1, i) - (k, i + 1)
        if second == 0:
            return k - 1, i, k, i, k, i1
        return k - 1, i, k, i1, k - 1, i1
    # diagonal (k - 1, i + 1) - (k, i)
    if second == 0:
        return k - 1, i, k, i, k - 1, i1
    return k, i, k, i1, k - 1, i1


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def tri_rest_area(prm, t, i, m):
    """Rest area of triangle ``i`` of family ``t`` (the fan's ``P_A0``)."""
    if m == 1:
        return prm[P_A0]
    k = t // 2 + 1
    row = _row(k)
    outer = (t % 2 == 0) == (i % 2 == 0)
    return prm[row + R_AOUT] if outer else prm[row + R_AIN]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def edge_xy(x, n, m, prm, t, i):
    """Both ends ``(xa, ya, xb, yb)`` of edge ``i`` of family ``t`` in state ``x``."""
    ka, ia, kb, ib = edge_ends(t, i, n, m)
    xa, ya = point_xy(x, n, m, prm, ka, ia)
    xb, yb = point_xy(x, n, m, prm, kb, ib)
    return xa, ya, xb, yb


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def tri_xy(x, n, m, prm, t, i):
    """The three corners ``(xa, ya, xb, yb, xc, yc)`` of triangle ``i`` of family ``t``."""
    ka, ia, kb, ib, kc, ic = tri_corners(t, i, n, m)
    xa, ya = point_xy(x, n, m, prm, ka, ia)
    xb, yb = point_xy(x, n, m, prm, kb, ib)
    xc, yc = point_xy(x, n, m, prm, kc, ic)
    return xa, ya, xb, yb, xc, yc


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def quad_corners(k, i, n):
    """Corners of quad ``i`` of layer ``k`` (between rings ``k - 1`` and ``k``),
    counter-clockwise: ``(k - 1, i), (k, i), (k, i + 1), (k - 1, i + 1)`` as
    ``(ka, ia, kb, ib, kc, ic, kd, id)``."""
    i1 = _next(i, n)
    return k - 1, i, k, i, k, i1, k - 1, i1


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def quad_xy(x, n, m, prm, k, i):
    """The four corners ``(xa, ya, .., xd, yd)`` of quad ``i`` of layer ``k`` in state ``x``."""
    ka, ia, kb, ib, kc, ic, kd, id_ = quad_corners(k, i, n)
    xa, ya = point_xy(x, n, m, prm, ka, ia)
    xb, yb = point_xy(x, n, m, prm, kb, ib)
    xc, yc = point_xy(x, n, m, prm, kc, ic)
    xd, yd = point_xy(x, n, m, prm, kd, id_)
    return xa, ya, xb, yb, xc, yc, xd, yd


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def quad_rest_area(prm, k):
    """Rest area of a quad of layer ``k``: its two triangles'."""
    row = _row(k)
    return prm[row + R_AOUT] + prm[row + R_AIN]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def quad_rest_area_at(prm, n, m, k, i):
    """Rest area of quad ``i`` of layer ``k``: :func:`quad_rest_area` on a disk, an outline's
    own quad's (its quads differ around a ring)."""
    if prm[P_SHAPE] == SHAPE_DISK:
        return quad_rest_area(prm, k)
    return prm[_quad_slot(n, m) + (k - 1) * n + i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def contour_rest_radius(prm, n, m, i):
    """Rest distance of contour point ``i`` from the centre [r]: 1 on a disk, the outline's
    ``r(phi_i)`` [r_eq]."""
    if prm[P_SHAPE] == SHAPE_DISK:
        return 1.0
    return prm[_radius_slot(n, m) + i]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def ring_rho(prm, k):
    """Rest radius of ring ``k`` from the ring table [r]."""
    return prm[_row(k) + R_RHO]


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def rest_xy(prm, n, m, k, i):
    """Rest position of point ``(k, i)`` (kernel copy with the ring table)."""
    rho = prm[_row(k) + R_RHO]
    base = _dir_slot(m)
    return rho * prm[base + 2 * i], rho * prm[base + 2 * i + 1]


@njit(cache=True, error_model="numpy", _nrt=False)
def ring_rest_state_into(prm, n, x):
    """Rest positions of the interior points into ``x`` (the contour and angles are set by
    the caller)."""
    m = int(prm[P_RINGS])
    base = _dir_slot(m)
    for k in range(1, m):
        rho = prm[_row(k) + R_RHO]
        for i in range(n):
            d = point_dof(n, m, k, i)
            x[d] = rho * prm[base + 2 * i]
            x[d + 1] = rho * prm[base + 2 * i + 1]


@njit(cache=True, error_model="numpy")
def mesh_band_index(n, m):
    """Band position of every point's x row, by point: contour point ``i`` at index ``i``,
    interior point ``(k, i)`` at ``N + (k - 1) N + i``.

    The angles are interleaved (0, N-1, 1, N-2, ...) so that the cyclic neighbours are at most
    two places apart, and each angle's ``M`` points (contour first) are consecutive: half
    bandwidth ``2 (3 M - 1) + 1`` (5 for the fan).
    """
    idx = np.empty(n * m, dtype=np.int64)
    half = (n - 1) // 2
    for i in range(n):
        pos = 2 * i if i <= half else 2 * (n - 1 - i) + 1
        for k in range(1, m + 1):
            p = i if k == m else n + (k - 1) * n + i
            idx[p] = 2 * (pos * m + (m - k))
    return idx


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def mesh_half_bandwidth(m):
    """Half bandwidth of the Newton matrix's point block in :func:`mesh_band_index` order:
    neighbouring angles are at most two places apart, each angle's M points consecutive."""
    return 2 * (3 * m - 1) + 1
