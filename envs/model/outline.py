"""The object's outline as the compiled model reads it: a star-shaped closed curve about its
centroid, ``r(phi)``, in units of the area-equivalent radius ``r_eq = sqrt(A / pi)``.

Conventions (docs/model.md, object outlines): ``phi`` is the polar angle in the object's own
(body) frame, measured from its first axis (an ellipse's long axis); the object turned by its
orientation ``psi`` (counter-clockwise from +x, the direction across the jaws) puts the body
direction ``phi`` at the gripper-frame angle ``phi + psi``. The outline has area ``pi`` and
its centroid at the origin in these units, so that the disk's formulas that take ``r`` (the
torque unit ``s E t r^2``, the mass ``rho pi r^2 t``, the design box in radii) take ``r_eq``.

Representation: ``r(phi)`` is a periodic uniform cubic B-spline in ``phi`` over
:data:`~envs.model.layout.N_OUTLINE` knots ``phi_k = 2 pi k / K``; the scene row and the packed
parameters carry its K coefficients ``c_k`` (:func:`spline_coefficients` turns K samples
``r(phi_k)`` into them: the spline interpolates the samples). Why a spline: every layer that
needs the outline (the rest mesh, the FEM's mapped mesh, the contact measure's curvature, the
drawings) evaluates the same smooth curve, with its first and second derivatives, from K
numbers of fixed count, whatever the shape (an ellipse, a rounded rectangle, a measured
polyline); a disk is not an outline here (its rows keep the disk's own code paths).

Contour points (:func:`outline_contour_into`): ``N`` points spaced evenly by arc length, the
first at the outline's top (the gripper-frame direction ``+y`` from the centroid), counter-
clockwise, as the disk's are spaced evenly in angle from its top. The point-spring model's
rings are the contour scaled about the centroid (a radially mapped disk mesh), and so is the
FEM's mesh.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .layout import N_OUTLINE, SHAPE_DISK

__all__ = [
    "ARC_STEPS_PER_KNOT",
    "spline_coefficients",
    "outline_radius",
    "outline_point",
    "outline_speed",
    "outline_curvature",
    "outline_length",
    "outline_lowest",
    "outline_support",
    "outline_body_angles_into",
    "outline_body_angles",
    "outline_contour_into",
    "outline_contour",
    "outline_curve",
    "outline_area_centroid",
    "contour_curvatures_into",
    "outline_contact_geometry",
]

#: Sub-steps of the arc-length quadrature per knot interval (Simpson's rule on each): the
#: contour's spacing is even to ~1e-6 of a spacing (measured 5e-7 on a 2.5:1 ellipse).
ARC_STEPS_PER_KNOT = 4


def spline_coefficients(samples) -> np.ndarray:
    """The K periodic cubic B-spline coefficients that interpolate ``samples`` (``r(phi_k)``
    at ``phi_k = 2 pi k / K``), float64[K].

    The uniform cubic B-spline takes the value ``(c_{k-1} + 4 c_k + c_{k+1}) / 6`` at knot
    ``k``: a circulant system, solved exactly by its discrete Fourier transform.
    """
    s = np.asarray(samples, dtype=np.float64)
    k = s.size
    symbol = (4.0 + 2.0 * np.cos(2.0 * np.pi * np.arange(k) / k)) / 6.0
    return np.real(np.fft.ifft(np.fft.fft(s) / symbol))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def outline_radius(coef, base, phi):
    """``(r, dr/dphi, d2r/dphi2)`` of the outline at body angle ``phi`` [rad] (any real
    angle), from the K coefficients ``coef[base:base + K]``."""
    k = N_OUTLINE
    h = 2.0 * math.pi / k
    x = phi / h
    x -= k * math.floor(x / k)
    i = int(math.floor(x))
    t = x - i
    if i >= k:  # x rounded up to k
        i -= k
    c0 = coef[base + (i - 1) % k]
    c1 = coef[base + i]
    c2 = coef[base + (i + 1) % k]
    c3 = coef[base + (i + 2) % k]
    u = 1.0 - t
    t2 = t * t
    value = (u * u * u * c0 + (3.0 * t2 * t - 6.0 * t2 + 4.0) * c1
             + (-3.0 * t2 * t + 3.0 * t2 + 3.0 * t + 1.0) * c2 + t2 * t * c3) / 6.0
    slope = (-u * u * c0 + (3.0 * t2 - 4.0 * t) * c1 + (-3.0 * t2 + 2.0 * t + 1.0) * c2
             + t2 * c3) / (2.0 * h)
    bend = (u * c0 + (3.0 * t - 2.0) * c1 + (1.0 - 3.0 * t) * c2 + t * c3) / (h * h)
    return value, slope, bend


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def outline_point(coef, base, phi, psi):
    """Gripper-frame position ``(x, y)`` of the outline's point at body angle ``phi``, the
    object turned by ``psi`` [rad] (relative to the centroid, units of ``r_eq``)."""
    r, _, _ = outline_radius(coef, base, phi)
    return r * math.cos(phi + psi), r * math.sin(phi + psi)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def outline_speed(coef, base, phi):
    """``ds/dphi = sqrt(r^2 + r'^2)``: arc length per radian of body angle."""
    r, dr, _ = outline_radius(coef, base, phi)
    return math.sqrt(r * r + dr * dr)


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def outline_curvature(coef, base, phi):
    """Curvature of the outline at body angle ``phi`` [1/r_eq], positive where it is convex:
    ``(r^2 + 2 r'^2 - r r'') / (r^2 + r'^2)^(3/2)`` (``1`` on the unit circle)."""
    r, dr, ddr = outline_radius(coef, base, phi)
    q = r * r + dr * dr
    return (r * r + 2.0 * dr * dr - r * ddr) / (q * math.sqrt(q))


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def _simpson(coef, base, a, step):
    """Arc length between body angles ``a`` and ``a + step`` (Simpson's rule)."""
    return step / 6.0 * (outline_speed(coef, base, a) + 4.0 * outline_speed(
        coef, base, a + 0.5 * step) + outline_speed(coef, base, a + step))


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_length(coef, base):
    """Perimeter of the outline [r_eq]."""
    steps = N_OUTLINE * ARC_STEPS_PER_KNOT
    step = 2.0 * math.pi / steps
    total = 0.0
    for j in range(steps):
        total += _simpson(coef, base, j * step, step)
    return total


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_support(coef, base, psi, dx, dy):
    """Largest ``(dx, dy) . p`` over the outline's points ``p`` (gripper frame, the object
    turned by ``psi``) [r_eq]: its support function in the unit direction ``(dx, dy)``, on a
    dense scan refined by a parabola through the best scan point and its neighbours."""
    steps = N_OUTLINE * ARC_STEPS_PER_KNOT
    step = 2.0 * math.pi / steps
    best = -math.inf
    at = 0
    for j in range(steps):
        x, y = outline_point(coef, base, j * step, psi)
        v = dx * x + dy * y
        if v > best:
            best = v
            at = j
    xa, ya = outline_point(coef, base, (at - 1) * step, psi)
    xb, yb = outline_point(coef, base, (at + 1) * step, psi)
    va, vb = dx * xa + dy * ya, dx * xb + dy * yb
    curve = va - 2.0 * best + vb
    if curve < 0.0:
        shift = 0.5 * (va - vb) / curve
        if -1.0 < shift < 1.0:
            x, y = outline_point(coef, base, (at + shift) * step, psi)
            v = dx * x + dy * y
            if v > best:
                best = v
    return best


@njit(cache=True, error_model="numpy", inline="always", _nrt=False)
def outline_lowest(coef, base, psi):
    """How far the outline's lowest point lies below its centroid [r_eq] (the object turned by
    ``psi``): the centroid sits this far above the nearest point to the joints' line, ``1`` for
    the unit circle."""
    return outline_support(coef, base, psi, 0.0, -1.0)


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_body_angles_into(coef, base, psi, n, out, out_base):
    """Body angles [rad] of ``n`` points spaced evenly by arc length along the outline into
    ``out[out_base:out_base + n]``, counter-clockwise, the first at the top: on the ray from
    the centroid along ``+y``, body angle ``pi / 2 - psi``.

    Arc length is integrated by Simpson's rule on :data:`ARC_STEPS_PER_KNOT` sub-steps of
    each knot interval and each point placed at its length by linear interpolation of the
    body angle within its sub-step, refined by one Newton step on the arc length.
    """
    steps = N_OUTLINE * ARC_STEPS_PER_KNOT
    step = 2.0 * math.pi / steps
    start = 0.5 * math.pi - psi
    total = 0.0
    for j in range(steps):
        total += _simpson(coef, base, start + j * step, step)
    spacing = total / n
    out[out_base] = start
    i = 1
    walked = 0.0
    for j in range(steps):
        a = start + j * step
        piece = _simpson(coef, base, a, step)
        while i < n and i * spacing <= walked + piece:
            target = i * spacing - walked
            phi = a + step * target / piece
            # one Newton step: arc length from a to phi against the target
            phi += (target - _simpson(coef, base, a, phi - a)) / outline_speed(coef, base, phi)
            out[out_base + i] = phi
            i += 1
        walked += piece
    while i < n:
        out[out_base + i] = start + 2.0 * math.pi * (1.0 - (n - i) * spacing / total)
        i += 1


@njit(cache=True, error_model="numpy", _nrt=False)
def outline_contour_into(coef, base, psi, n, out, out_base):
    """Write the ``n`` contour points at the body angles of :func:`outline_body_angles_into`
    into ``out[out_base:out_base + 2 n]`` as ``(x_0, y_0, x_1, ...)`` (gripper frame, units of
    ``r_eq``, relative to the centroid): spaced evenly by arc length, counter-clockwise, the
    first at the top."""
    # the angles in the second half of the slots, each read before its slot is written (point
    # i's slots 2 i, 2 i + 1 hold only angles of points before it)
    outline_body_angles_into(coef, base, psi, n, out, out_base + n)
    for i in range(n):
        phi = out[out_base + n + i]
        x, y = outline_point(coef, base, phi, psi)
        out[out_base + 2 * i], out[out_base + 2 * i + 1] = x, y


@njit(cache=True, error_model="numpy", _nrt=False)
def contour_curvatures_into(coef, base, psi, n, out):
    """The rest curvatures [1/r_eq] of the ``n`` contour points of
    :func:`outline_contour_into` into ``out[:n]`` (their body angles first, each read before
    it is overwritten)."""
    outline_body_angles_into(coef, base, psi, n, out, 0)
    for i in range(n):
        out[i] = outline_curvature(coef, base, out[i])


def outline_contact_geometry(shape, orientation_rad, outline, radius_m, n: int
                             ) -> tuple[np.ndarray, np.ndarray]:
    """The perimeter [m] (0 for a disk) and the contour points' rest curvatures [1/m]
    (zeros for a disk) of scenes' objects, (B,) and (B, n): what the contact measure of an
    outline reads (:func:`envs.scoring.psm_metrics_rows`). ``shape``, ``orientation_rad``,
    ``outline`` and ``radius_m`` are the scene columns (``None`` for disks only)."""
    b = np.shape(radius_m)[0]
    perimeter = np.zeros(b)
    curvature = np.zeros((b, int(n)))
    if shape is None:
        return perimeter, curvature
    for i in np.flatnonzero(np.asarray(shape) != SHAPE_DISK):
        coef = np.ascontiguousarray(outline[i], dtype=np.float64)
        r = float(radius_m[i])
        perimeter[i] = outline_length(coef, 0) * r
        contour_curvatures_into(coef, 0, float(orientation_rad[i]), int(n), curvature[i])
        curvature[i] /= r
    return perimeter, curvature


def outline_contour(coef, psi: float, n: int) -> np.ndarray:
    """The ``n`` contour points of :func:`outline_contour_into` as an (n, 2) array [r_eq]."""
    out = np.empty(2 * int(n))
    outline_contour_into(np.ascontiguousarray(coef, dtype=np.float64), 0, float(psi), int(n),
                         out, 0)
    return out.reshape(-1, 2)


def outline_body_angles(coef, psi: float, n: int) -> np.ndarray:
    """The body angles [rad] of the ``n`` contour points of :func:`outline_contour`."""
    out = np.empty(int(n))
    outline_body_angles_into(np.ascontiguousarray(coef, dtype=np.float64), 0, float(psi),
                             int(n), out, 0)
    return out


def outline_curve(coef, phi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(r, r', r'')`` of the outline at body angles ``phi`` (an array) [r_eq, per rad]."""
    c = np.ascontiguousarray(coef, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    out = np.array([outline_radius(c, 0, float(p)) for p in phi.ravel()]).reshape(
        *phi.shape, 3)
    return out[..., 0], out[..., 1], out[..., 2]


def outline_area_centroid(coef, steps: int = 4 * N_OUTLINE) -> tuple[float, np.ndarray]:
    """Area and centroid of the spline outline (units of its own coefficients), by the
    trapezoid rule on ``steps`` angles, spectrally accurate for a periodic smooth integrand:
    ``A = 1/2 int r^2``, ``C = 1/(3 A) int r^3 (cos, sin)``."""
    phi = 2.0 * np.pi * np.arange(steps) / steps
    r, _, _ = outline_curve(coef, phi)
    w = 2.0 * np.pi / steps
    area = 0.5 * float(np.sum(r * r)) * w
    cx = float(np.sum(r**3 * np.cos(phi))) * w / (3.0 * area)
    cy = float(np.sum(r**3 * np.sin(phi))) * w / (3.0 * area)
    return area, np.array([cx, cy])
