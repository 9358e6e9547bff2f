"""The soft object that is not a disk: :class:`SoftObject`, a :class:`~envs.scene.SoftDisk`
with an outline and an orientation."""

from __future__ import annotations

from dataclasses import dataclass, fields

from ..scene import SoftDisk
from ..validation import check_range
from .shapes import Outline

__all__ = ["SoftObject", "as_object"]


@dataclass(frozen=True)
class SoftObject(SoftDisk):
    """A soft object of any star-shaped outline (docs/model.md, objects that are not disks):
    every field of :class:`~envs.scene.SoftDisk`, with

    - ``radius_m`` its area-equivalent radius ``r_eq = sqrt(A / pi)`` [m], the scale of every
      relative quantity (the design box, the torque unit ``s E t r_eq^2``, the mass
      ``rho A t``);
    - ``distance_m`` the distance from the joints' line to its lowest point [m] at its
      orientation: its centroid, the fixed centre, sits at ``(x_c, d_1 + lift)``
      (:attr:`~envs.scene.SoftDisk.lift_m`).

    Build one from the shape's own dimensions with :func:`envs.objects.soft_object`.

    Parameters
    ----------
    outline
        Its shape (:mod:`envs.objects.shapes`: an :class:`~envs.objects.Ellipse`, a
        :class:`~envs.objects.RoundedRectangle`, a :class:`~envs.objects.MeasuredOutline`,
        ...), dimensionless, star-shaped about its centroid.
    orientation_rad
        ``psi`` [rad], any finite number: the angle from the +x axis (across the jaws) to the
        outline's first axis (an ellipse's long axis), counter-clockwise; 0 puts the long
        axis across the jaws.
    """

    outline: Outline | None = None
    orientation_rad: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.outline, Outline):
            raise ValueError(f"outline must be an envs.objects outline (Ellipse, "
                             f"RoundedRectangle, MeasuredOutline, ...), got "
                             f"{type(self.outline).__name__} (a disk is a SoftDisk)")
        object.__setattr__(self, "orientation_rad",
                           check_range("orientation_rad", self.orientation_rad))
        super().__post_init__()


def as_object(disk: SoftDisk, outline: Outline | None = None,
              orientation_rad: float = 0.0) -> SoftDisk:
    """``disk``'s fields with an outline and an orientation: a :class:`SoftObject`, or
    ``disk`` itself as a disk for ``outline=None``."""
    base = {f.name: getattr(disk, f.name) for f in fields(SoftDisk)}
    if outline is None:
        return disk if type(disk) is SoftDisk else SoftDisk(**base)
    return SoftObject(**base, outline=outline, orientation_rad=float(orientation_rad))
