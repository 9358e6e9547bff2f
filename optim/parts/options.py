"""The options of the parts a build sheet describes (:mod:`optim.parts`)."""

from __future__ import annotations

from dataclasses import dataclass

from envs.validation import check_range

from .resolution import DEFAULT_RESOLUTION, Resolution

__all__ = ["PartOptions", "MAX_PIN_DIAMETER_M"]

MAX_PIN_DIAMETER_M = 1.0  # a pin of a metre and more: a unit typed wrong


@dataclass(frozen=True)
class PartOptions:
    """What the parts are made to.

    Parameters
    ----------
    resolution
        The manufacturing resolution (:class:`~optim.parts.resolution.Resolution`) the
        reported design is rounded to; ``None``: the design as found, unrounded.
    pin_diameter_m
        The joint pin's diameter [m], in (0, 1]; ``None``: the default rule of
        :func:`optim.parts.joint.default_pin_diameter` (half the finger width, rounded down to
        the resolution).
    """

    resolution: Resolution | None = DEFAULT_RESOLUTION
    pin_diameter_m: float | None = None

    def __post_init__(self) -> None:
        if self.resolution is not None and not isinstance(self.resolution, Resolution):
            raise ValueError(f"resolution must be None or an optim.parts.resolution."
                             f"Resolution, got {type(self.resolution).__name__}")
        if self.pin_diameter_m is not None:
            object.__setattr__(self, "pin_diameter_m", check_range(
                "pin_diameter_m", self.pin_diameter_m, 0.0, MAX_PIN_DIAMETER_M, low_open=True))
