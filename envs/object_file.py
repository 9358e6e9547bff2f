"""Objects from files: a TOML ``[object]`` table (and, for one grasp, a ``[gripper]`` table).

A designer's own object is four numbers and, optionally, what the design must respect::

    [object]
    name = "cherry tomato"        # optional (default: the file's name)
    radius_m = 0.012
    youngs_modulus_pa = 150e3
    poisson_ratio = 0.45
    thickness_m = 0.024
    stiffness_scale = 1.0         # optional: calibration scale s of the point-spring model
    strain_limit = 0.08           # optional: admissible peak compression (default 0.10)
    friction_coefficient = 0.5    # optional: Coulomb coefficient of the finger pads on it
    placement_tolerance_m = 0.0015  # optional: +- placement error, both ways, or
                                    # [along, across] the gripper's axis
    density_kg_m3 = 1000          # optional: its density (default 1000, water-like)
    payload_factor = 2            # optional: payload W = f m g to lift (default 2; 0: none)
    load_set = "top-down"         # optional: how it is picked, the payload's directions:
                                  # "top-down", "side" or "any" (default: the command's, any)
    jaw = "cradle"                # optional: the jaws to design, "straight" (default),
                                  # "cradle", "vee" or "any" (envs.design_space.DesignBounds)
    jaw_per_finger = false        # optional: each finger its own groove (default false)

An object that is not a disk names its shape and its own dimensions instead of ``radius_m``
(:mod:`envs.objects`; its area-equivalent radius is then the object's scale)::

    shape = "ellipse"             # "disk" (default), "ellipse", "rounded_rectangle",
                                  # "superellipse" or "measured"
    semi_axes_m = [0.020, 0.010]  # ellipse, superellipse: along and across its first axis
                                  # (each may be a range [low, high])
    exponent = 4                  # superellipse: |x/a|^p + |y/b|^p = 1
    sides_m = [0.030, 0.015]      # rounded_rectangle: its sides, the long one first
    corner_radius_m = 0.004       # rounded_rectangle: at most half the short side
    outline_file = "part.csv"     # measured: points (CSV) or a closed DXF polyline, next
    outline_unit = "mm"           # to the object file; their unit, "m" or "mm"
    orientation_deg = 90          # optional: its first axis from +x (across the jaws), ccw
    orientation_tolerance_deg = 15  # optional: +- turn about its centroid as placed

A range instead of a number, e.g. ``radius_m = [0.010, 0.015]``, asks for one design that
serves every object in it (radius, modulus, Poisson ratio, thickness, density, friction): the
design is made for the ranges' centre and judged over the scenarios of :mod:`envs.scenarios`.

    [gripper]                     # optional, for one grasp (psm-grasp simulate)
    finger_length_m = 0.05
    rest_angle_deg = 30           # or rest_angle_rad
    joint_offset_m = 0.002
    finger_width_m = 0.004
    distance_m = 0.01             # d_1: the joints' line to the nearest point of the object
    torque_nm = 0.02              # optional (default: the command's --torque)
    torsion_stiffness_nm_per_rad = 0.001  # optional (default: relative to the object)

    [gripper.tolerances]          # optional: manufacturing tolerances the design must survive
    length_mm = 0.1               # finger length, width and joint offset, +-
    angle_deg = 0.5               # rest angle, +-
    spring_percent = 10           # joint spring, +-
    torque_percent = 5            # actuation torque, +-

The tolerances (:mod:`envs.tolerances`) are scenario dimensions of the design beside the
object's ranges (the ``[gripper]`` table may hold them alone, without a gripper).

Every key is checked before any work: an unknown key, a missing key or a bad value is one
``ValueError`` naming the file, the table, the key and the allowed range. A radius, thickness,
modulus or density outside the plausible range of a graspable object
(:data:`envs.model.defaults.PLAUSIBLE_RANGES`) is refused with the unit it was most likely
typed in (``radius_m = 15``: millimetres).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from .design_space import JAW_KINDS
from .model.defaults import (
    DEFAULT_STIFFNESS_SCALE,
    MAX_FRICTION_COEFFICIENT,
    MAX_PAYLOAD_FACTOR,
    OBJECT_DENSITY_KG_M3,
)
from .model.loads import LOAD_SETS
from .objects import SHAPE_NAMES, as_object, outline_info, outline_of
from .objects.files import OUTLINE_UNITS, read_outline
from .scenarios import OUTLINE_RANGE_FIELDS, RANGE_FIELDS, Scenarios
from .scene import Gripper, Scene, SoftDisk, check_torque, joint_spring_nm_per_rad
from .tolerances import Tolerances, parse_tolerances
from .validation import check_plausible, check_range, read_text_file

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["ObjectSpec", "GripperSpec", "load_object", "OBJECT_KEYS", "GRIPPER_KEYS",
           "OBJECT_TABLE_KEYS", "check_value"]

# key -> (low, high, low_open, high_open, required) of the [object] table
OBJECT_KEYS: dict[str, tuple[float, float, bool, bool, bool]] = {
    "radius_m": (0.0, math.inf, True, False, True),
    "youngs_modulus_pa": (0.0, math.inf, True, False, True),
    "poisson_ratio": (-1.0, 0.5, True, True, True),
    "thickness_m": (0.0, math.inf, True, False, True),
    "stiffness_scale": (0.0, math.inf, True, False, False),
    "strain_limit": (0.0, 1.0, True, False, False),
    "friction_coefficient": (0.0, MAX_FRICTION_COEFFICIENT, True, False, False),
    "density_kg_m3": (0.0, math.inf, True, False, False),
    "payload_factor": (0.0, MAX_PAYLOAD_FACTOR, False, False, False),
}
# key -> (low, high, low_open, high_open, required) of the [gripper] table
GRIPPER_KEYS: dict[str, tuple[float, float, bool, bool, bool]] = {
    "finger_length_m": (0.0, math.inf, True, False, True),
    "rest_angle_deg": (0.0, 90.0, True, True, False),
    "rest_angle_rad": (0.0, math.pi / 2, True, True, False),
    "joint_offset_m": (0.0, math.inf, False, False, True),
    "finger_width_m": (0.0, math.inf, True, False, True),
    "distance_m": (-math.inf, math.inf, False, False, True),
    "torque_nm": (0.0, math.inf, False, False, False),
    "torsion_stiffness_nm_per_rad": (0.0, math.inf, True, False, False),
}
TABLES = ("object", "gripper")
# the placement tolerance: one number (both ways) or [along, across] the gripper's axis [m]
TOLERANCE_KEY = "placement_tolerance_m"
TOLERANCE_RULE = (0.0, math.inf, False, False, False)
# the jaws a design problem designs (envs.design_space.DesignBounds): a word and a flag
JAW_KEY, JAW_PER_FINGER_KEY = "jaw", "jaw_per_finger"
# an object that is not a disk (envs.objects): its shape, dimensions and orientation
SHAPE_KEYS = ("shape", "semi_axes_m", "exponent", "sides_m", "corner_radius_m",
              "outline_file", "outline_unit", "orientation_deg", "orientation_tolerance_deg")
_LENGTH_RULE = (0.0, math.inf, True, False, False)
_SHAPE_NEEDS = {"ellipse": ("semi_axes_m",), "superellipse": ("semi_axes_m", "exponent"),
                "rounded_rectangle": ("sides_m", "corner_radius_m"),
                "measured": ("outline_file", "outline_unit")}
# how the object is picked: the payload's directions (envs.model.loads.LOAD_SETS)
LOAD_SET_KEY = "load_set"
# the [gripper] table's manufacturing tolerances (envs.tolerances.TOLERANCE_KEYS)
TOLERANCES_KEY = "tolerances"
# every key of the [object] table, in the order the unknown-key message lists them
OBJECT_TABLE_KEYS = ("name", TOLERANCE_KEY, *OBJECT_KEYS, JAW_KEY, JAW_PER_FINGER_KEY,
                     LOAD_SET_KEY, *SHAPE_KEYS)


@dataclass(frozen=True)
class GripperSpec:
    """A ``[gripper]`` table: one gripper and the object's placement, SI units.

    ``torsion_stiffness_nm_per_rad`` ``None``: the joint spring relative to the object
    (:func:`envs.scene.joint_spring`); ``torque_nm`` ``None``: the caller's torque.
    """

    finger_length_m: float
    rest_angle_rad: float
    joint_offset_m: float
    finger_width_m: float
    distance_m: float
    torque_nm: float | None = None
    torsion_stiffness_nm_per_rad: float | None = None


@dataclass(frozen=True)
class ObjectSpec:
    """An object read from a file.

    Parameters
    ----------
    name
        The object's name (the file's stem unless the table names it).
    disk
        The disk (its ``distance_m`` is 0, or the ``[gripper]`` table's placement).
    strain_limit
        Admissible peak compression [-], or ``None`` (the caller's default).
    friction_coefficient
        Coulomb friction coefficient between the fingers and the object [-], or ``None``.
    payload_factor
        ``f`` of the payload ``W = f m g`` to lift [-], or ``None`` (the caller's default).
    gripper
        The ``[gripper]`` table, or ``None``.
    path
        The file read.
    scenarios
        The object's ranges and placement tolerance (:class:`envs.scenarios.Scenarios`), or
        ``None`` when the file gives neither; ``disk`` and ``friction_coefficient`` are then
        the ranges' centre.
    payload_factor
        ``f`` of the payload to lift, or ``None``.
    load_set
        How the object is picked, the payload's directions
        (:data:`envs.model.loads.LOAD_SETS`), or ``None`` (the caller's default).
    jaw, jaw_per_finger
        The jaws to design (one of :data:`envs.design_space.JAW_KINDS`) and whether each
        finger has its own groove, or ``None`` (the caller's default: straight bars).
    tolerances
        The ``[gripper.tolerances]`` table (:class:`envs.tolerances.Tolerances`), or ``None``;
        ``scenarios`` then carries them too.
    """

    name: str
    disk: SoftDisk
    strain_limit: float | None = None
    friction_coefficient: float | None = None
    gripper: GripperSpec | None = None
    path: Path | None = None
    scenarios: Scenarios | None = None
    payload_factor: float | None = None
    jaw: str | None = None
    jaw_per_finger: bool | None = None
    load_set: str | None = None
    tolerances: Tolerances | None = None

    def scene(self) -> Scene:
        """The scene of the ``[gripper]`` table and this object.

        Raises
        ------
        ValueError
            Without a ``[gripper]`` table, or for a gripper that overlaps the object at rest.
        """
        if self.gripper is None:
            raise ValueError(f"{self._where()}: no [gripper] table to build a scene from")
        g = self.gripper
        disk = replace(self.disk, distance_m=g.distance_m)
        try:  # the table's keys, named with the file (finger_length_m > finger_width_m)
            kf = joint_spring_nm_per_rad(disk, None, g.torsion_stiffness_nm_per_rad)
            gripper = Gripper(g.finger_length_m, g.rest_angle_rad, g.joint_offset_m,
                              g.finger_width_m, kf)
            return Scene(gripper, disk)
        except ValueError as exc:
            raise ValueError(f"{self._where()}: [gripper]: {exc}") from None

    def info(self) -> dict[str, Any]:
        """The object's fields as plain data (what a result JSON records)."""
        d = self.disk
        return {"name": self.name, "radius_m": d.radius_m, **outline_info(d),
                "youngs_modulus_pa": d.youngs_modulus_pa, "poisson_ratio": d.poisson_ratio,
                "thickness_m": d.thickness_m, "stiffness_scale": d.stiffness_scale,
                "density_kg_m3": d.density_kg_m3,
                "strain_limit": self.strain_limit,
                "friction_coefficient": self.friction_coefficient,
                "payload_factor": self.payload_factor,
                **({} if self.load_set is None else {LOAD_SET_KEY: self.load_set}),
                "file": None if self.path is None else str(self.path),
                **({} if self.scenarios is None else {"scenarios": self.scenarios.as_dict()}),
                **{k: v for k, v in ((JAW_KEY, self.jaw),
                                     (JAW_PER_FINGER_KEY, self.jaw_per_finger))
                   if v is not None}}

    def _where(self) -> str:
        return str(self.path) if self.path is not None else self.name


def check_value(key: str, value: Any, rule: tuple[float, float, bool, bool, bool]) -> float:
    """One number of an object's description (a key of :data:`OBJECT_KEYS` or
    :data:`GRIPPER_KEYS` with its rule), wherever it is read (an object file, a run's result):
    a number (not a bool or a string: ``True`` is not 1 m), in the key's allowed range and in
    its plausible range (:func:`envs.validation.check_plausible`); ``ValueError`` naming
    ``key`` otherwise."""
    low, high, low_open, high_open, _ = rule
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{key} must be a number, got {value!r}")
    check_range(key, value, low, high, low_open=low_open, high_open=high_open)
    return check_plausible(key, value)


def _number(where: str, key: str, value: Any, rule: tuple[float, float, bool, bool, bool]
            ) -> float:
    try:
        return check_value(key, value, rule)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None


def _table(where: str, data: dict[str, Any], rules: dict, extra: tuple[str, ...] = (),
           after: tuple[str, ...] = ()) -> dict[str, float]:
    """The numbers of a table by key, checked (``extra`` and ``after``: its other keys,
    read elsewhere, named before and after the numbers' keys where a key is unknown)."""
    unknown = sorted(set(data) - set(rules) - set(extra) - set(after))
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r}; allowed: "
                         f"{', '.join([*extra, *rules, *after])}")
    missing = [k for k, rule in rules.items() if rule[-1] and k not in data]
    if missing:
        raise ValueError(f"{where}: missing key {missing[0]!r} (required: "
                         f"{', '.join(k for k, r in rules.items() if r[-1])})")
    return {k: _number(where, k, v, rules[k]) for k, v in data.items() if k in rules}


def _gripper(where: str, data: Any) -> tuple[GripperSpec | None, Tolerances | None]:
    """The ``[gripper]`` table: a gripper (``None`` when the table holds only tolerances) and
    its ``tolerances`` sub-table (``None`` without one)."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: must be a table")
    data = dict(data)
    tolerances = (parse_tolerances(data.pop(TOLERANCES_KEY), f"{where}: {TOLERANCES_KEY}")
                  if TOLERANCES_KEY in data else None)
    if not data and tolerances is not None:
        return None, tolerances
    values = _table(where, data, GRIPPER_KEYS, after=(TOLERANCES_KEY,))
    if ("rest_angle_deg" in values) == ("rest_angle_rad" in values):
        raise ValueError(f"{where}: give the rest angle once, as rest_angle_deg or "
                         "rest_angle_rad")
    angle = values.pop("rest_angle_rad", None)
    if angle is None:
        angle = math.radians(values.pop("rest_angle_deg"))
    return GripperSpec(rest_angle_rad=angle, **values), tolerances


def parse_object(data: dict[str, Any], where: str, default_name: str = "object",
                 path: Path | None = None) -> ObjectSpec:
    """An :class:`ObjectSpec` of parsed TOML data (see :func:`load_object`)."""
    unknown = sorted(set(data) - set(TABLES))
    if unknown:
        raise ValueError(f"{where}: unknown table or key {unknown[0]!r}; allowed: [object], "
                         "[gripper]")
    if "object" not in data:
        raise ValueError(f"{where}: missing the [object] table")
    table = data["object"]
    if not isinstance(table, dict):
        raise ValueError(f"{where}: object must be a table ([object])")
    name = table.get("name", default_name)
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"{where}: [object] name must be a non-empty string, got {name!r}")
    table = dict(table)
    folder = Path(".") if path is None else path.parent
    outline, table, axis_ranges, turn = _shape(f"{where}: [object]", table, folder)
    tolerance = _tolerance(f"{where}: [object]", table.pop(TOLERANCE_KEY, None))
    jaw, per_finger = _jaws(f"{where}: [object]", table.pop(JAW_KEY, None),
                            table.pop(JAW_PER_FINGER_KEY, None))
    load_set = table.pop(LOAD_SET_KEY, None)
    if load_set is not None and (not isinstance(load_set, str) or load_set not in LOAD_SETS):
        raise ValueError(f"{where}: [object] {LOAD_SET_KEY} must be one of "
                         f"{', '.join(repr(k) for k in LOAD_SETS)}, got {load_set!r}")
    table, ranges = _ranges(f"{where}: [object]", table)
    values = _table(f"{where}: [object]", table, OBJECT_KEYS, extra=("name", TOLERANCE_KEY),
                    after=(JAW_KEY, JAW_PER_FINGER_KEY, LOAD_SET_KEY, *SHAPE_KEYS))
    ranges.update(axis_ranges)
    gripper, tolerances = (_gripper(f"{where}: [gripper]", data["gripper"])
                           if "gripper" in data else (None, None))
    scenarios = None
    if ranges or tolerance is not None or tolerances is not None or turn is not None:
        try:
            scenarios = Scenarios.of(ranges, tolerance, tolerances, turn)
            scenarios.check_placement(values["radius_m"])  # (the ranges' centre)
        except ValueError as exc:
            raise ValueError(f"{where}: [object]: {exc}") from None
    disk = as_object(SoftDisk(values["radius_m"], 0.0, values["youngs_modulus_pa"],
                              values["poisson_ratio"], values["thickness_m"],
                              values.get("stiffness_scale", DEFAULT_STIFFNESS_SCALE),
                              density_kg_m3=values.get("density_kg_m3", OBJECT_DENSITY_KG_M3)),
                     **outline)
    if gripper is not None and gripper.torque_nm is not None:
        try:  # a torque far beyond what squeezes this object (N·mm typed for N·m)
            check_torque("torque_nm", data["gripper"]["torque_nm"], disk.torque_unit_nm,
                         joint_spring_nm_per_rad(disk, None,
                                                 gripper.torsion_stiffness_nm_per_rad))
        except ValueError as exc:
            raise ValueError(f"{where}: [gripper]: {exc}") from None
    return ObjectSpec(name.strip(), disk, values.get("strain_limit"),
                      values.get("friction_coefficient"), gripper, path, scenarios,
                      values.get("payload_factor"), jaw, per_finger, load_set, tolerances)


def _jaws(where: str, jaw: Any, per_finger: Any) -> tuple[str | None, bool | None]:
    """``jaw`` (one of :data:`~envs.design_space.JAW_KINDS`) and ``jaw_per_finger`` (true or
    false, with a groove only), each ``None`` when the file does not set it."""
    if jaw is not None and (not isinstance(jaw, str) or jaw not in JAW_KINDS):
        raise ValueError(f"{where}: {JAW_KEY} must be one of "
                         f"{', '.join(repr(k) for k in JAW_KINDS)}, got {jaw!r}")
    if per_finger is not None:
        if not isinstance(per_finger, bool):
            raise ValueError(f"{where}: {JAW_PER_FINGER_KEY} must be true or false, got "
                             f"{per_finger!r}")
        if per_finger and jaw in (None, "straight"):
            raise ValueError(f"{where}: {JAW_PER_FINGER_KEY} = true needs {JAW_KEY} = "
                             + ", ".join(repr(k) for k in JAW_KINDS[1:])
                             + f" (a groove to cut into each finger), got {JAW_KEY} = {jaw!r}")
    return jaw, per_finger


def _ranges(where: str, table: dict[str, Any]) -> tuple[dict[str, Any], dict[str, tuple]]:
    """The table with each range ``[low, high]`` replaced by its centre, and the ranges (each
    end checked like the key's single value)."""
    table = dict(table)
    ranges: dict[str, tuple[float, float]] = {}
    for key, value in list(table.items()):
        if not isinstance(value, list):
            continue
        if key not in RANGE_FIELDS or key not in OBJECT_KEYS:
            allowed = ", ".join(k for k in RANGE_FIELDS if k in OBJECT_KEYS)
            raise ValueError(f"{where}: {key} must be a number, got {value!r} (ranges are "
                             f"allowed for {allowed})")
        if len(value) != 2:
            raise ValueError(f"{where}: {key} as a range must be [low, high], got {value!r}")
        ends = []
        for end, v in zip(("low", "high"), value, strict=True):
            try:  # each end like the key's single value, the range quoted as written
                ends.append(check_value(key, v, OBJECT_KEYS[key]))
            except ValueError as exc:
                raise ValueError(f"{where}: {key} = {_written(value)}: its {end} end: {exc}"
                                 ) from None
        low, high = ends
        if not low <= high:
            raise ValueError(f"{where}: {key} = {value!r}: low must not exceed high")
        ranges[key] = (low, high)
        table[key] = 0.5 * (low + high)
    return table, ranges


def _shape(where: str, table: dict[str, Any], folder: Path
           ) -> tuple[dict[str, Any], dict[str, Any], dict[str, tuple[float, float]],
                      float | None]:
    """The shape keys of an ``[object]`` table (:data:`SHAPE_KEYS`): the object's ``outline``
    and ``orientation_rad`` (empty for a disk), the table without them (with ``radius_m`` the
    outline's equivalent radius), the semi-axis ranges (:mod:`envs.scenarios`) and the
    orientation tolerance [deg] (``None``: not given)."""
    table = dict(table)
    given = {k: table.pop(k) for k in SHAPE_KEYS if k in table}
    shape = given.pop("shape", "measured" if "outline_file" in given else "disk")
    if not isinstance(shape, str) or shape not in SHAPE_NAMES:
        raise ValueError(f"{where}: shape must be one of "
                         f"{', '.join(repr(k) for k in SHAPE_NAMES)}, got {shape!r}")
    psi = given.pop("orientation_deg", None)
    turn = given.pop("orientation_tolerance_deg", None)
    if shape == "disk":
        extra = [k for k in (*given, *(("orientation_deg",) if psi is not None else ()),
                             *(("orientation_tolerance_deg",) if turn is not None else ()))]
        if extra:
            raise ValueError(f"{where}: {extra[0]} applies to an object with a shape, not a "
                             "disk: set shape = \"ellipse\", \"rounded_rectangle\", "
                             "\"superellipse\" or \"measured\"")
        return {}, table, {}, None
    if "radius_m" in table:
        raise ValueError(f"{where}: radius_m does not apply to shape = {shape!r}: its own "
                         f"dimensions ({', '.join(_SHAPE_NEEDS[shape])}) set its size")
    wrong = [k for k in given if k not in _SHAPE_NEEDS[shape]]
    if wrong:
        raise ValueError(f"{where}: {wrong[0]} does not apply to shape = {shape!r} (it takes "
                         f"{', '.join(_SHAPE_NEEDS[shape])})")
    missing = [k for k in _SHAPE_NEEDS[shape] if k not in given]
    if missing:
        raise ValueError(f"{where}: shape = {shape!r} needs {missing[0]}")
    ranges: dict[str, tuple[float, float]] = {}
    try:
        if shape == "measured":
            outline, r_eq = _measured(where, given, folder)
        else:
            dims = {}
            for key in ("semi_axes_m", "sides_m"):
                if key in given:
                    dims[key], found = _pair_of_lengths(where, key, given[key])
                    if key == "semi_axes_m":
                        ranges.update({name: pair for name, pair in zip(
                            OUTLINE_RANGE_FIELDS, found, strict=True) if pair is not None})
            if "corner_radius_m" in given:
                dims["corner_radius_m"] = _number(where, "corner_radius_m",
                                                  given["corner_radius_m"], (0.0, math.inf,
                                                                             False, False,
                                                                             False))
            if "exponent" in given:
                dims["exponent"] = _number(where, "exponent", given["exponent"],
                                           (1.0, 20.0, False, False, False))
            outline, r_eq = outline_of(shape, **dims)
    except ValueError as exc:
        raise ValueError(f"{where}: {exc}") from None
    angle = 0.0 if psi is None else _number(where, "orientation_deg", psi,
                                            (-360.0, 360.0, False, False, False))
    if turn is not None:
        turn = _number(where, "orientation_tolerance_deg", turn, (0.0, 90.0, False, False,
                                                                   False))
    table["radius_m"] = r_eq
    return ({"outline": outline, "orientation_rad": math.radians(angle)}, table, ranges,
            turn)


def _pair_of_lengths(where: str, key: str, value: Any
                     ) -> tuple[tuple[float, float], tuple[tuple[float, float] | None, ...]]:
    """A pair of lengths [m] whose entries may each be a range [low, high]: the pair at the
    ranges' centres, and each entry's range (``None`` for a number)."""
    if not isinstance(value, list) or len(value) != 2:
        raise ValueError(f"{key} must be a pair [first, second] of lengths [m], got {value!r}")
    centre, ranges = [], []
    for i, v in enumerate(value):
        if isinstance(v, list):
            if len(v) != 2:
                raise ValueError(f"{key}[{i}] as a range must be [low, high], got {v!r}")
            low, high = (_number(where, f"{key}[{i}][{j}]", x, _LENGTH_RULE)
                         for j, x in enumerate(v))
            if not low <= high:
                raise ValueError(f"{key}[{i}] = {v!r}: low must not exceed high")
            centre.append(0.5 * (low + high))
            ranges.append((low, high))
        else:
            centre.append(_number(where, f"{key}[{i}]", v, _LENGTH_RULE))
            ranges.append(None)
    if key != "semi_axes_m" and any(r is not None for r in ranges):
        raise ValueError(f"{key} must be two numbers (ranges are allowed for semi_axes_m)")
    return (centre[0], centre[1]), tuple(ranges)


def _measured(where: str, given: dict[str, Any], folder: Path):
    """A measured outline of ``outline_file`` (next to the object file) in ``outline_unit``."""
    name, unit = given["outline_file"], given["outline_unit"]
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"outline_file must be a file name, got {name!r}")
    if not isinstance(unit, str) or unit not in OUTLINE_UNITS:
        raise ValueError(f"outline_unit must be one of {', '.join(map(repr, OUTLINE_UNITS))}, "
                         f"got {unit!r}")
    path = Path(name)
    return read_outline(path if path.is_absolute() else folder / path, unit)


def _written(value: list) -> str:
    """A TOML array as the file writes it (``[10, 15]``)."""
    return "[" + ", ".join(repr(v) if not isinstance(v, bool) else str(v).lower()
                           for v in value) + "]"


def _tolerance(where: str, value: Any) -> float | tuple[float, float] | None:
    """``placement_tolerance_m``: one number or [along, across], each >= 0 [m]."""
    if value is None:
        return None
    if isinstance(value, list):
        if len(value) != 2:
            raise ValueError(f"{where}: {TOLERANCE_KEY} must be a number or [along, across], "
                             f"got {value!r}")
        return tuple(_number(where, f"{TOLERANCE_KEY}[{i}]", v, TOLERANCE_RULE)
                     for i, v in enumerate(value))
    return _number(where, TOLERANCE_KEY, value, TOLERANCE_RULE)


def load_object(path: str | Path) -> ObjectSpec:
    """Read an object file (TOML with an ``[object]`` and an optional ``[gripper]`` table).

    Parameters
    ----------
    path
        The file: see this module's docstring for its keys and units.

    Raises
    ------
    ValueError
        A file that cannot be read or parsed, an unknown table or key, a missing key or a bad
        value: one line naming the file, the table and the key.
    """
    p = Path(path)
    # "utf-8-sig": a byte-order mark, which some editors write first, is not TOML
    text = read_text_file(p, "object", "TOML", encoding="utf-8-sig")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{p}: not valid TOML: {exc}") from None
    return parse_object(data, str(p), p.stem, p)
