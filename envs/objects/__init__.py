"""The object as one concept: its outline (a disk, an ellipse, a rounded box, a measured
outline), its size, material, mass, placement and orientation.

The object of every layer is an :class:`envs.scene.SoftDisk`: a disk, or a
:class:`SoftObject` (a ``SoftDisk`` with an ``outline``, :mod:`envs.objects.shapes`, whose
``radius_m`` is its area-equivalent radius ``r_eq`` and whose ``orientation_rad`` turns it
between the jaws; docs/model.md, objects that are not disks). :func:`soft_object` builds one
from the shape's own dimensions::

    from envs.objects import soft_object

    grape = soft_object("ellipse", semi_axes_m=(0.02, 0.01), orientation_deg=90,
                        youngs_modulus_pa=2e5, thickness_m=0.02, density_kg_m3=1000)

:mod:`envs.objects.files` reads measured outlines (CSV points, DXF polylines).
"""

from __future__ import annotations

import math

from ..validation import check_range
from .shapes import (
    MAX_ASPECT_RATIO,
    SHAPES,
    Ellipse,
    MeasuredOutline,
    Outline,
    RoundedRectangle,
    SplineOutline,
    Superellipse,
)
from .soft_object import SoftObject, as_object

__all__ = [
    "SoftObject",
    "as_object",
    "Outline",
    "Ellipse",
    "RoundedRectangle",
    "Superellipse",
    "MeasuredOutline",
    "SplineOutline",
    "SHAPES",
    "SHAPE_NAMES",
    "MAX_ASPECT_RATIO",
    "soft_object",
    "outline_of",
    "with_semi_axes",
    "OUTLINE_INFO_KEYS",
    "outline_info",
    "outline_fields",
]

#: The shapes an object may have (``"disk"`` is the disk itself, no outline).
SHAPE_NAMES = ("disk", "ellipse", "rounded_rectangle", "superellipse", "measured")


def outline_of(shape: str, *, radius_m: float | None = None, semi_axes_m=None, sides_m=None,
               corner_radius_m: float | None = None, exponent: float | None = None,
               points_m=None, name: str | None = None) -> tuple[Outline | None, float]:
    """The outline of a shape given by its own dimensions [m], and its equivalent radius
    ``r_eq`` [m].

    Parameters
    ----------
    shape
        One of :data:`SHAPE_NAMES`: ``"disk"`` (``radius_m``; the outline ``None``),
        ``"ellipse"`` (``semi_axes_m = (a, b)``, ``a >= b``), ``"rounded_rectangle"``
        (``sides_m = (L, W)``, ``L >= W``, and ``corner_radius_m`` in ``[0, W / 2]``),
        ``"superellipse"`` (``semi_axes_m`` and ``exponent`` in [1, 20]) or ``"measured"``
        (``points_m``: a closed polyline, :meth:`MeasuredOutline.from_points`).
    """
    given = {"radius_m": radius_m, "semi_axes_m": semi_axes_m, "sides_m": sides_m,
             "corner_radius_m": corner_radius_m, "exponent": exponent, "points_m": points_m}
    needs = {"disk": ("radius_m",), "ellipse": ("semi_axes_m",),
             "rounded_rectangle": ("sides_m", "corner_radius_m"),
             "superellipse": ("semi_axes_m", "exponent"), "measured": ("points_m",)}
    if shape not in needs:
        raise ValueError(f"shape must be one of {SHAPE_NAMES}, got {shape!r}")
    missing = [k for k in needs[shape] if given[k] is None]
    extra = [k for k, v in given.items() if v is not None and k not in needs[shape]]
    if missing or extra:
        raise ValueError(f"shape {shape!r} takes {', '.join(needs[shape])}"
                         + (f"; missing {missing[0]}" if missing else "")
                         + (f"; {extra[0]} does not apply" if extra else ""))
    if shape == "disk":
        return None, check_range("radius_m", radius_m, 0.0, math.inf, low_open=True)
    if shape in ("ellipse", "superellipse"):
        pair = _pair("semi_axes_m", semi_axes_m)
        outline, r_eq = Ellipse.of_semi_axes(*pair)
        if shape == "ellipse":
            return outline, r_eq
        sup = Superellipse(outline.aspect_ratio, exponent)
        p = sup.exponent
        area = 4 * pair[0] * pair[1] * math.gamma(1 + 1 / p) ** 2 / math.gamma(1 + 2 / p)
        return sup, math.sqrt(area / math.pi)
    if shape == "rounded_rectangle":
        return RoundedRectangle.of_sides(*_pair("sides_m", sides_m), corner_radius_m)
    return MeasuredOutline.from_points(points_m, name or "measured")


def _pair(name: str, value) -> tuple[float, float]:
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name} must be a pair of lengths [m], got {value!r}")
    return float(value[0]), float(value[1])


def soft_object(shape: str = "disk", *, distance_m: float = 0.0,
                orientation_deg: float | None = None, orientation_rad: float | None = None,
                radius_m: float | None = None, semi_axes_m=None, sides_m=None,
                corner_radius_m: float | None = None, exponent: float | None = None,
                points_m=None, name: str | None = None, **material):
    """A soft object of a shape given by its own dimensions (see :func:`outline_of`).

    Parameters
    ----------
    shape, radius_m, semi_axes_m, sides_m, corner_radius_m, exponent, points_m, name
        The shape and its dimensions [m] (:func:`outline_of`).
    distance_m
        ``d_1``: the joints' line to the object's lowest point [m].
    orientation_deg, orientation_rad
        The orientation ``psi`` (one of them; default 0: the first axis across the jaws).
    **material
        The other fields of :class:`envs.scene.SoftDisk` (``youngs_modulus_pa``,
        ``poisson_ratio``, ``thickness_m``, ``density_kg_m3``, ``offset_x_m``, ...).

    Returns
    -------
    SoftDisk
        A :class:`SoftObject`, or for ``shape="disk"`` the :class:`~envs.scene.SoftDisk`.
    """
    if orientation_deg is not None and orientation_rad is not None:
        raise ValueError("give the orientation once: orientation_deg or orientation_rad")
    psi = (math.radians(check_range("orientation_deg", orientation_deg))
           if orientation_deg is not None else 0.0 if orientation_rad is None
           else check_range("orientation_rad", orientation_rad))
    outline, r_eq = outline_of(shape, radius_m=radius_m, semi_axes_m=semi_axes_m,
                               sides_m=sides_m, corner_radius_m=corner_radius_m,
                               exponent=exponent, points_m=points_m, name=name)
    from ..scene import SoftDisk

    disk = SoftDisk(r_eq, distance_m, **material)
    return disk if outline is None else as_object(disk, outline, psi)


def with_semi_axes(disk, a_m: float | None = None, b_m: float | None = None):
    """``disk`` (an :class:`envs.scene.SoftDisk` with an :class:`Ellipse` or
    :class:`Superellipse` outline) with its semi-axes along (``a_m``) and across (``b_m``) its
    first axis set [m] (``None``: kept), its equivalent radius following: what a scenario's
    semi-axis ranges vary (:mod:`envs.scenarios`)."""
    from dataclasses import replace

    shape = disk.outline
    if not isinstance(shape, Ellipse | Superellipse):
        raise ValueError(f"semi-axis ranges need an ellipse or a superellipse, the object is "
                         f"a {disk.shape}")
    a0, b0 = shape.semi_axes_m(disk.radius_m)
    a = a0 if a_m is None else float(a_m)
    b = b0 if b_m is None else float(b_m)
    if isinstance(shape, Ellipse):
        new, r_eq = Ellipse.of_semi_axes(a, b)
    else:
        new, r_eq = outline_of("superellipse", semi_axes_m=(a, b), exponent=shape.exponent)
    return replace(disk, radius_m=r_eq, outline=new)


#: The keys of an object's plain data (a result JSON's ``object``) that carry its outline.
OUTLINE_INFO_KEYS = ("shape", "orientation_rad", "outline_coefficients")


def outline_info(disk) -> dict:
    """An object's outline as plain data: nothing for a disk; else its shape and own
    dimensions (:meth:`Outline.describe`), ``orientation_rad`` and the model's
    ``outline_coefficients`` (what :func:`outline_fields` rebuilds it from, exactly)."""
    if disk.outline is None:
        return {}
    return {**disk.outline.describe(disk.radius_m), "orientation_rad": disk.orientation_rad,
            "outline_coefficients": disk.outline.coefficients().tolist()}


def outline_fields(obj) -> dict:
    """The :func:`as_object` keyword arguments of an object's plain data
    (:func:`outline_info`): ``{}`` for a disk, else its ``outline`` (the model's spline,
    :class:`SplineOutline`, named by its shape) and ``orientation_rad``."""
    coefficients = obj.get("outline_coefficients")
    if coefficients is None:
        return {}
    return {"outline": SplineOutline(tuple(coefficients), name=str(obj.get("shape", "outline"))),
            "orientation_rad": float(obj.get("orientation_rad", 0.0))}
