"""The object's outline: its shape, star-shaped about its centroid, without its size.

An outline here is dimensionless: it is scaled to area ``pi`` (its area-equivalent radius
``r_eq = sqrt(A / pi)`` is 1) with its centroid at the origin, in its own body frame (the first
axis along +x: an ellipse's long axis). The object's ``radius_m`` (:class:`envs.scene.SoftDisk`)
is then its ``r_eq`` in metres and its ``orientation_rad`` turns it in the gripper's frame, so a
radius range scales a shape and an orientation tolerance turns it, as scenarios do.

Shapes (docs/model.md, object outlines):

* :class:`Ellipse` (aspect ratio ``a / b >= 1``);
* :class:`RoundedRectangle` (aspect ratio of its sides, corner radius over the half short side);
* :class:`Superellipse` (``|x / a|^p + |y / b|^p = 1``, a box with rounded corners for large
  ``p``);
* :class:`MeasuredOutline`, a closed polyline (:func:`MeasuredOutline.from_points`, files:
  :mod:`envs.objects.files`), refused when self-intersecting or not star-shaped about its
  centroid;
* :class:`SplineOutline`, the model's own representation (the coefficients a scene row
  carries), which every shape turns into (:meth:`Outline.coefficients`).

A disk is not an outline: a :class:`~envs.scene.SoftDisk` (``outline`` ``None``) keeps the
disk's own code paths and answers; an outline makes a :class:`~envs.objects.SoftObject`.
Each shape's ``r(phi)`` is sampled at the model's :data:`~envs.model.layout.N_OUTLINE` knots
and interpolated by a periodic cubic B-spline (:mod:`envs.model.outline`), then scaled to
area ``pi`` and (for a measured outline) re-centred on the spline's own centroid.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..model.layout import N_OUTLINE
from ..model.outline import (
    ARC_STEPS_PER_KNOT,
    outline_area_centroid,
    outline_body_angles,
    outline_contour,
    outline_curvature,
    outline_curve,
    outline_length,
    outline_lowest,
    spline_coefficients,
)
from ..validation import check_range

__all__ = [
    "Outline",
    "Ellipse",
    "RoundedRectangle",
    "Superellipse",
    "MeasuredOutline",
    "SplineOutline",
    "SHAPES",
    "MAX_ASPECT_RATIO",
    "MIN_MEASURED_POINTS",
]

MAX_ASPECT_RATIO = 10.0  # beyond, a slice is a rod: the radial map of the disk mesh degrades
MIN_MEASURED_POINTS = 8  # a measured outline's fewest distinct points
_CENTRING_STEPS = 4  # re-centring iterations of a measured outline on the spline's centroid


class Outline:
    """A dimensionless star-shaped outline (see the module). Subclasses give
    :meth:`raw_radius`; the rest follows from it."""

    kind: ClassVar[str] = "outline"

    def raw_radius(self, phi: np.ndarray) -> np.ndarray:
        """``r(phi)`` of the shape at its own scale, about its centroid (body frame)."""
        raise NotImplementedError

    def coefficients(self) -> np.ndarray:
        """The model's K B-spline coefficients of ``r(phi) / r_eq`` (read-only, cached)."""
        return _coefficients(self)

    # --- geometry of the model's curve (units of r_eq) ------------------------------------

    def contour(self, n: int, orientation_rad: float = 0.0) -> np.ndarray:
        """``n`` points spaced evenly by arc length, the first at the top, counter-clockwise,
        turned by ``orientation_rad`` (gripper frame, about the centroid) [r_eq], (n, 2)."""
        return outline_contour(self.coefficients(), orientation_rad, n)

    def curvature_at(self, n: int, orientation_rad: float = 0.0) -> np.ndarray:
        """Curvature of the outline at the ``n`` points of :meth:`contour` [1/r_eq]."""
        c = self.coefficients()
        return np.array([outline_curvature(c, 0, float(p))
                         for p in outline_body_angles(c, orientation_rad, n)])

    @property
    def perimeter(self) -> float:
        """Perimeter [r_eq]."""
        return float(outline_length(self.coefficients(), 0))

    def lowest(self, orientation_rad: float = 0.0) -> float:
        """How far the lowest point lies below the centroid, turned by ``orientation_rad``
        [r_eq]."""
        return float(outline_lowest(self.coefficients(), 0, float(orientation_rad)))

    def radius_range(self) -> tuple[float, float]:
        """Smallest and largest distance of the outline from its centroid [r_eq]."""
        r, _, _ = outline_curve(self.coefficients(),
                                np.linspace(0.0, 2 * np.pi, 8 * N_OUTLINE, endpoint=False))
        return float(r.min()), float(r.max())

    def describe(self, radius_m: float) -> dict[str, object]:
        """The shape's own dimensions at equivalent radius ``radius_m`` [m], plain data (what
        a result JSON and a sheet show)."""
        return {"shape": self.kind}

    def scan(self, orientation_rad: float = 0.0) -> np.ndarray:
        """The outline's dense scan, turned by ``orientation_rad`` [r_eq], (P, 2): the points
        at the body angles the rest check scans
        (:func:`envs.model.problem.outline_clearance_m`), read-only."""
        return _scan(self, float(orientation_rad))

    def face_support(self, rest_angle_rad, orientation_rad: float = 0.0) -> np.ndarray:
        """How far the outline reaches towards either finger's gripping face at rest angle
        ``rest_angle_rad`` (an array) [r_eq]: the larger of its support functions along the
        faces' outward directions ``(cos, -sin)`` (right) and ``(-cos, -sin)`` (left) (1 for
        the unit circle)."""
        u = self.scan(orientation_rad)
        c, s = np.cos(rest_angle_rad), np.sin(rest_angle_rad)
        right = np.max(np.multiply.outer(c, u[:, 0]) - np.multiply.outer(s, u[:, 1]), axis=-1)
        left = np.max(np.multiply.outer(-c, u[:, 0]) - np.multiply.outer(s, u[:, 1]), axis=-1)
        return np.maximum(right, left)


@functools.lru_cache(maxsize=512)
def _coefficients(outline: Outline) -> np.ndarray:
    phi = 2.0 * np.pi * np.arange(N_OUTLINE) / N_OUTLINE
    c = spline_coefficients(outline.raw_radius(phi))
    area, _ = outline_area_centroid(c)
    c = c * math.sqrt(math.pi / area)
    c.flags.writeable = False
    return c


@functools.lru_cache(maxsize=512)
def _scan(outline: Outline, orientation_rad: float) -> np.ndarray:
    steps = N_OUTLINE * ARC_STEPS_PER_KNOT
    phi = 2.0 * np.pi * np.arange(steps) / steps
    r, _, _ = outline_curve(outline.coefficients(), phi)
    out = np.stack([r * np.cos(phi + orientation_rad), r * np.sin(phi + orientation_rad)],
                   axis=1)
    out.flags.writeable = False
    return out


def _check_aspect(name: str, value) -> float:
    return check_range(name, value, 1.0, MAX_ASPECT_RATIO)


@dataclass(frozen=True)
class Ellipse(Outline):
    """An ellipse of semi-axes ``a >= b``, the long one on the body's first axis.

    Parameters
    ----------
    aspect_ratio
        ``a / b`` [-], in [1, 10] (1: a circle, as an outline).
    """

    aspect_ratio: float
    kind: ClassVar[str] = "ellipse"

    def __post_init__(self) -> None:
        object.__setattr__(self, "aspect_ratio", _check_aspect("aspect_ratio",
                                                               self.aspect_ratio))

    @classmethod
    def of_semi_axes(cls, a_m: float, b_m: float) -> tuple[Ellipse, float]:
        """The ellipse of semi-axes ``a_m`` (along its first axis) and ``b_m`` [m] and its
        equivalent radius ``sqrt(a b)`` [m]; ``ValueError`` unless ``a_m >= b_m > 0`` (the
        long axis first: turn the object by its orientation instead)."""
        a = check_range("semi_axes_m[0]", a_m, 0.0, math.inf, low_open=True)
        b = check_range("semi_axes_m[1]", b_m, 0.0, a)
        if not b > 0.0:
            raise ValueError(f"semi_axes_m[1] = {b_m!r} must be in (0, {a!r}] (the long axis "
                             "first)")
        return cls(a / b), math.sqrt(a * b)

    def raw_radius(self, phi):
        a, b = math.sqrt(self.aspect_ratio), 1.0 / math.sqrt(self.aspect_ratio)
        return 1.0 / np.sqrt((np.cos(phi) / a) ** 2 + (np.sin(phi) / b) ** 2)

    def semi_axes_m(self, radius_m: float) -> tuple[float, float]:
        """Semi-axes ``(a, b)`` [m] at equivalent radius ``radius_m``."""
        k = self.aspect_ratio
        return radius_m * math.sqrt(k), radius_m / math.sqrt(k)

    def describe(self, radius_m):
        return {"shape": self.kind, "semi_axes_m": list(self.semi_axes_m(radius_m))}


@dataclass(frozen=True)
class RoundedRectangle(Outline):
    """A rectangle of sides ``L >= W`` with corners rounded by ``c``, ``L`` along the first
    axis (a pill, a soft package).

    Parameters
    ----------
    aspect_ratio
        ``L / W`` [-], in [1, 10].
    corner_ratio
        ``c / (W / 2)`` [-], in [0, 1]: 0 a sharp box (its corners smoothed over one knot
        interval of the model's spline), 1 a stadium.
    """

    aspect_ratio: float
    corner_ratio: float
    kind: ClassVar[str] = "rounded_rectangle"

    def __post_init__(self) -> None:
        object.__setattr__(self, "aspect_ratio", _check_aspect("aspect_ratio",
                                                               self.aspect_ratio))
        object.__setattr__(self, "corner_ratio", check_range("corner_ratio",
                                                             self.corner_ratio, 0.0, 1.0))

    @classmethod
    def of_sides(cls, length_m: float, width_m: float, corner_radius_m: float
                 ) -> tuple[RoundedRectangle, float]:
        """The rounded rectangle of sides ``length_m >= width_m`` and corner radius [m], and
        its equivalent radius [m]."""
        length = check_range("sides_m[0]", length_m, 0.0, math.inf, low_open=True)
        width = check_range("sides_m[1]", width_m, 0.0, length)
        if not width > 0.0:
            raise ValueError(f"sides_m[1] = {width_m!r} must be in (0, {length!r}] (the long "
                             "side first)")
        c = check_range("corner_radius_m", corner_radius_m, 0.0, width / 2)
        shape = cls(length / width, c / (width / 2))
        area = length * width - (4.0 - math.pi) * c * c
        return shape, math.sqrt(area / math.pi)

    def _half_sides(self) -> tuple[float, float, float]:
        return self.aspect_ratio, 1.0, self.corner_ratio  # A, B, c for B = 1

    def raw_radius(self, phi):
        big, small, c = self._half_sides()
        u, v = np.abs(np.cos(phi)), np.abs(np.sin(phi))
        with np.errstate(divide="ignore", invalid="ignore"):
            tx = np.where(u > 0, big / u, np.inf)  # the side x = A
            ty = np.where(v > 0, small / v, np.inf)  # the side y = B
            flat = np.minimum(tx, ty)
            on_x = (tx <= ty) & (tx * v <= small - c + 1e-15)
            on_y = (ty < tx) & (ty * u <= big - c + 1e-15)
            px, py = big - c, small - c
            up = u * px + v * py
            corner = up + np.sqrt(np.maximum(up * up - (px * px + py * py) + c * c, 0.0))
        return np.where(on_x | on_y, flat, corner)

    def sides_m(self, radius_m: float) -> tuple[float, float, float]:
        """Sides ``(L, W)`` and corner radius [m] at equivalent radius ``radius_m``."""
        big, small, c = self._half_sides()
        area = 4 * big * small - (4.0 - math.pi) * c * c
        k = radius_m * math.sqrt(math.pi / area)
        return 2 * big * k, 2 * small * k, c * k

    def describe(self, radius_m):
        length, width, c = self.sides_m(radius_m)
        return {"shape": self.kind, "sides_m": [length, width], "corner_radius_m": c}


@dataclass(frozen=True)
class Superellipse(Outline):
    """``|x / a|^p + |y / b|^p = 1``, ``a >= b`` along the first axis.

    Parameters
    ----------
    aspect_ratio
        ``a / b`` [-], in [1, 10].
    exponent
        ``p`` [-], in [1, 20]: 2 an ellipse, larger a box with rounded corners, 1 a rhombus.
    """

    aspect_ratio: float
    exponent: float
    kind: ClassVar[str] = "superellipse"

    def __post_init__(self) -> None:
        object.__setattr__(self, "aspect_ratio", _check_aspect("aspect_ratio",
                                                               self.aspect_ratio))
        object.__setattr__(self, "exponent", check_range("exponent", self.exponent, 1.0,
                                                         20.0))

    def raw_radius(self, phi):
        a, b, p = self.aspect_ratio, 1.0, self.exponent
        return (np.abs(np.cos(phi) / a) ** p + np.abs(np.sin(phi) / b) ** p) ** (-1.0 / p)

    def semi_axes_m(self, radius_m: float) -> tuple[float, float]:
        """Semi-axes ``(a, b)`` [m] at equivalent radius ``radius_m``."""
        p, k = self.exponent, self.aspect_ratio
        area = 4 * k * math.gamma(1 + 1 / p) ** 2 / math.gamma(1 + 2 / p)  # for b = 1
        b = radius_m * math.sqrt(math.pi / area)
        return k * b, b

    def describe(self, radius_m):
        return {"shape": self.kind, "semi_axes_m": list(self.semi_axes_m(radius_m)),
                "exponent": self.exponent}


@dataclass(frozen=True)
class SplineOutline(Outline):
    """An outline given by the model's own B-spline coefficients of ``r(phi) / r_eq`` (a
    scene row's, :mod:`envs.model.outline`), as they are.

    Parameters
    ----------
    coefficient_values
        :data:`~envs.model.layout.N_OUTLINE` positive-spline coefficients (area ``pi`` and the
        centroid at the origin to the spline's accuracy: they are not scaled again).
    name
        What the outline was (``"ellipse"``, a file's name), for reports.
    """

    coefficient_values: tuple[float, ...]
    name: str = field(default="outline", compare=False)
    kind: ClassVar[str] = "spline"

    def __post_init__(self) -> None:
        values = tuple(float(v) for v in np.asarray(self.coefficient_values,
                                                    dtype=np.float64).ravel())
        if len(values) != N_OUTLINE or not all(math.isfinite(v) and v > 0 for v in values):
            raise ValueError(f"coefficient_values must be {N_OUTLINE} positive finite numbers")
        object.__setattr__(self, "coefficient_values", values)

    def coefficients(self) -> np.ndarray:
        c = np.array(self.coefficient_values)
        c.flags.writeable = False
        return c

    def raw_radius(self, phi):
        r, _, _ = outline_curve(self.coefficients(), phi)
        return r

    def describe(self, radius_m):
        return {"shape": self.name}


@dataclass(frozen=True)
class MeasuredOutline(Outline):
    """A closed outline measured as points (a scan, a CAD slice), about its centroid.

    Build it with :meth:`from_points` (it validates, centres and scales); the points held are
    in units of ``r_eq``, counter-clockwise, their centroid at the origin.

    Parameters
    ----------
    points
        The polygon's vertices ``((x, y), ...)`` [r_eq].
    name
        Where it came from (a file's name), for reports.
    """

    points: tuple[tuple[float, float], ...]
    name: str = field(default="measured", compare=False)
    kind: ClassVar[str] = "measured"

    @classmethod
    def from_points(cls, points_m, name: str = "measured") -> tuple[MeasuredOutline, float]:
        """Validate a closed polyline [m] and return it as an outline with its equivalent
        radius [m].

        Raises
        ------
        ValueError
            Fewer than :data:`MIN_MEASURED_POINTS` distinct points, a non-finite coordinate,
            a self-intersecting polyline, or one that is not star-shaped about its centroid
            (a ray from the centroid crossing it more than once), naming which.
        """
        pts = _polyline(points_m, name)
        try:
            from shapely.geometry import Polygon
        except ImportError:  # pragma: no cover - shapely is a dependency
            raise ValueError("reading a measured outline needs shapely (pip install shapely)"
                             ) from None
        poly = Polygon(pts)
        if not poly.is_valid:
            from shapely.validation import explain_validity

            raise ValueError(f"outline {name!r} is self-intersecting or degenerate "
                             f"({explain_validity(poly)}): give a simple closed polyline")
        if poly.exterior.is_ccw is False:
            pts = pts[::-1]
        centroid = np.array([poly.centroid.x, poly.centroid.y])
        _check_star(pts, centroid, name)
        scale = math.sqrt(poly.area / math.pi)
        rel = (pts - centroid) / scale
        shape = centred_measured(cls(tuple(map(tuple, rel.tolist())), name))
        # the spline's own area (its smoothing of the polyline's corners) sets r_eq
        area, _ = outline_area_centroid(spline_coefficients(shape.raw_radius(
            2.0 * np.pi * np.arange(N_OUTLINE) / N_OUTLINE)))
        return shape, scale * math.sqrt(area / math.pi)

    def raw_radius(self, phi):
        pts = np.asarray(self.points)
        return _ray_polygon(pts, phi)

    def describe(self, radius_m):
        pts = np.asarray(self.points) * radius_m
        return {"shape": self.kind, "name": self.name,
                "size_m": [float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1]))]}


def _polyline(points_m, name: str) -> np.ndarray:
    """The distinct vertices of a closed polyline (a repeated first point dropped), (n, 2)."""
    try:
        pts = np.array(points_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"outline {name!r}: points must be numbers (x, y)") from None
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"outline {name!r}: points must have shape (n, 2), got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError(f"outline {name!r}: a coordinate is not a finite number")
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0.0, axis=1)
    pts = pts[keep]
    if len(pts) > 1 and np.all(pts[0] == pts[-1]):
        pts = pts[:-1]
    if len(pts) < MIN_MEASURED_POINTS:
        raise ValueError(f"outline {name!r} has {len(pts)} distinct points; at least "
                         f"{MIN_MEASURED_POINTS} are needed")
    return pts


def _check_star(pts: np.ndarray, centroid: np.ndarray, name: str) -> None:
    """``ValueError`` unless every ray from ``centroid`` crosses the counter-clockwise
    polygon ``pts`` once: the vertices' polar angles about it rise at every step, by less than
    pi, once round."""
    rel = pts - centroid
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    step = np.mod(np.diff(np.append(ang, ang[0])), 2 * np.pi)
    dist = np.hypot(rel[:, 0], rel[:, 1])
    if (np.any(dist <= 1e-12 * dist.max()) or np.any(step <= 0.0) or np.any(step >= np.pi)
            or not math.isclose(float(step.sum()), 2 * np.pi, rel_tol=1e-9)):
        bad = int(np.argmax((step <= 0.0) | (step >= np.pi))) if np.any(
            (step <= 0.0) | (step >= np.pi)) else 0
        raise ValueError(
            f"outline {name!r} is not star-shaped about its centroid ({centroid[0]:.6g}, "
            f"{centroid[1]:.6g}): a ray from it crosses the outline more than once (near "
            f"point {bad}, ({pts[bad, 0]:.6g}, {pts[bad, 1]:.6g})); the model needs r(phi) "
            "> 0 with one crossing per ray")


def _ray_polygon(pts: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Distance from the origin to a star-shaped polygon along each ray ``phi``."""
    a = pts
    b = np.roll(pts, -1, axis=0)
    d = np.stack([np.cos(phi), np.sin(phi)], axis=-1)  # (K, 2)
    e = b - a  # (E, 2)
    # solve t d = a + s e for t (ray), s in [0, 1] (edge)
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]  # (K, E)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (a[None, :, 0] * e[None, :, 1] - a[None, :, 1] * e[None, :, 0]) / den
        s = (a[None, :, 0] * d[:, None, 1] - a[None, :, 1] * d[:, None, 0]) / den
    hit = (s >= -1e-12) & (s <= 1 + 1e-12) & (t > 0) & np.isfinite(t)
    return np.where(hit, t, np.inf).min(axis=1)


def centred_measured(outline: MeasuredOutline) -> MeasuredOutline:
    """``outline`` moved so that its model spline's centroid is at the origin (the polygon's
    and the spline's centroids differ by the spline's smoothing, ~1e-4 r_eq)."""
    shape = outline
    for _ in range(_CENTRING_STEPS):
        _, centroid = outline_area_centroid(spline_coefficients(shape.raw_radius(
            2.0 * np.pi * np.arange(N_OUTLINE) / N_OUTLINE)))
        if float(np.hypot(*centroid)) < 1e-12:
            break
        pts = np.asarray(shape.points) - centroid
        shape = MeasuredOutline(tuple(map(tuple, pts.tolist())), shape.name)
    return shape


SHAPES = {cls.kind: cls for cls in (Ellipse, RoundedRectangle, Superellipse, MeasuredOutline)}
