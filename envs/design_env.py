"""GripperDesign-v2, -v3 and -v4: one step designs a gripper for a soft object; a thin
adapter over physics.

The physics and the reward live in :func:`envs.evaluate.evaluate_designs`; this module only maps
actions to designs, draws objects, builds observations and ``info``, and renders. v3 designs
shaped jaws too (:func:`make_vector_env_v3`; its single env: :func:`envs.reset_check.make_env_v3`);
v4 draws objects that are not disks (ellipses at any orientation) and observes their shape
(:func:`make_vector_env_v4`, :func:`envs.reset_check.make_env_v4`).
"""

from __future__ import annotations

import math
import operator
import textwrap
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.error import ResetNeeded
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .evaluate import (
    METRIC_KEYS,
    N_DESIGN,
    DesignBounds,
    RewardWeights,
    evaluate_designs,
)
from .model.defaults import (
    DEFAULT_ELEMENT,
    DEFAULT_PAYLOAD_FACTOR,
    GRAVITY_M_S2,
    MAX_PAYLOAD_FACTOR,
)
from .model.family import ModelSpec, resolve_model
from .model.loads import DEFAULT_LOAD_SET, load_set_code
from .objects import Ellipse, SoftObject
from .scenarios import Scenarios, nominal_leaders, place
from .scene import Design, SoftDisk, joint_spring_kwargs
from .validation import (
    PsmGraspWarning,
    check_integer,
    check_range,
    check_sequence,
    real_array,
)

__all__ = [
    "OBS_FIELDS",
    "ObjectDistribution",
    "observe",
    "payload_ratio",
    "GripperDesignEnv",
    "GripperDesignVectorEnv",
    "check_reset_arguments",
    "SHAPE_OBS_FIELDS",
    "shape_observation",
    "make_vector_env_v4",
]

# (name, transform, low, high): the observation is the transformed value mapped linearly from
# [low, high] to [-1, 1]; objects outside these ranges are rejected at reset. Only what changes
# a relative design's grasp is observed: the model is invariant under the object's size,
# stiffness and thickness (lengths in radii, torques in s E t r^2, the joint spring with them),
# so a relative design scores the same on every disk of one Poisson ratio, strain limit,
# friction coefficient, calibration scale (the Hertz contact width goes as sqrt(s)), payload
# ratio (the payload in the force unit s E t r) and placement tolerance in radii.
OBS_FIELDS: tuple[tuple[str, str, float, float], ...] = (
    ("poisson_ratio", "linear", 0.0, 0.5),
    ("strain_limit", "linear", 0.0, 0.5),
    ("friction_coefficient", "linear", 0.0, 2.0),
    ("stiffness_scale", "log10", -2.0, 1.0),
    ("payload_ratio", "log10", -8.0, 1.0),
    ("placement_tolerance_rel", "linear", 0.0, 0.5),
)
# GripperShapeDesign-v0 observes the object's shape after these: an ellipse's aspect ratio and its
# orientation as cos(2 psi) (the grasp of an ellipse repeats when it turns by pi, and mirrors
# when psi changes sign: -psi is the mirror image of psi across the gripper's axis)
SHAPE_OBS_FIELDS: tuple[tuple[str, str, float, float], ...] = (
    ("aspect_ratio", "linear", 1.0, 4.0),
    ("orientation_cos2", "linear", -1.0, 1.0),
)
# a payload ratio below the observable range is observed at its lower end: a payload that
# small changes no grasp (it is 1e-8 of the force unit)
FLOORED_FIELDS = ("payload_ratio",)
DISK_INFO_KEYS = ("radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
                  "stiffness_scale", "density_kg_m3")
# what a design must respect: the strain limit, the friction of the pads, the payload factor f
# (the payload W = f rho pi r^2 t g) and the placement tolerance in radii (+- along and across
# the gripper's axis)
NEED_KEYS = ("strain_limit", "friction_coefficient", "payload_factor",
             "placement_tolerance_rel")
OPEN_LOW_FIELDS = ("strain_limit", "friction_coefficient")
DEFAULT_NEEDS = {"payload_factor": DEFAULT_PAYLOAD_FACTOR, "placement_tolerance_rel": 0.0}
OBJECT_INFO_KEYS = DISK_INFO_KEYS + NEED_KEYS
RENDER_FPS = 4
# what a step's info holds beyond METRIC_KEYS (dtype, shape per row): evaluate_objects
ROBUST_KEYS = {"reward_nominal": (np.float64, ()), "worst_scenario": (np.int64, ())}


MAX_NUM_ENVS = 2**20  # sub-envs of a vector env at most (each step solves one grasp per sub-env)


def _pair(name: str, value, low: float, high: float, *, low_open: bool = True,
          high_open: bool = False) -> tuple[float, float]:
    pair = tuple(check_range(f"{name}[{i}]", v, low, high, low_open=low_open,
                             high_open=high_open)
                 for i, v in enumerate(check_sequence(name, value, 2)))
    if pair[0] > pair[1]:
        raise ValueError(f"{name} must be (low, high) with low <= high, got {pair}")
    return pair


@dataclass(frozen=True)
class ObjectDistribution:
    """Distribution of the object drawn at reset: a disk and what a design must respect.

    The default covers real use: produce and tissue from 1 mm to 0.2 m, from 10 kPa to 10 MPa,
    from a foam's 20 kg/m^3 to 1200 kg/m^3, lifted with a payload factor up to 2 (the weight
    plus a lift at 1 g) and placed within up to a quarter of the radius.
    Radius, modulus, thickness and density are drawn log-uniformly, the rest uniformly.

    Parameters
    ----------
    radius_range_m
        Disk radius [m].
    youngs_modulus_range_pa
        Young's modulus [Pa].
    poisson_ratio_range
        Poisson's ratio [-], inside [0, 0.5) (the observable range).
    thickness_range_m
        Thickness [m].
    strain_limit_range
        Admissible peak compression (see :func:`envs.evaluate_designs`) [-], inside (0, 0.5]
        (the observable range).
    friction_range
        Coulomb friction coefficient of the fingers on the object [-], inside (0, 2].
    stiffness_scale
        Calibration scale ``s`` of every object [-].
    density_range_kg_m3
        Density [kg/m^3] (the payload's mass ``rho pi r^2 t``).
    payload_factor_range
        Payload factor ``f`` [-], inside [0, 100]: the grasp carries ``W = f rho pi r^2 t g``.
    placement_tolerance_range_rel
        Placement tolerance over the radius [-], inside [0, 0.5] (the observable range): the
        object's centre may lie anywhere within ``+-`` it along and across the gripper's axis.
    aspect_ratio_range
        An ellipse's aspect ratio ``a / b`` [-], inside [1, 4] (the observable range of
        ``GripperShapeDesign-v0``): with either range below not a single point, every object is an
        ellipse (:class:`envs.objects.Ellipse`) of the drawn radius as its area-equivalent
        radius. Default ``(1, 1)`` with ``orientation_range_rad`` ``(0, 0)``: disks, drawn as
        before (the same random stream).
    orientation_range_rad
        An ellipse's orientation ``psi`` [rad] (its long axis from +x, across the jaws),
        inside [-pi, pi].

    The largest payload ratio of the ranges (:func:`payload_ratio`) must be observable (at
    most 10).
    """

    radius_range_m: tuple[float, float] = (1e-3, 0.2)
    youngs_modulus_range_pa: tuple[float, float] = (10e3, 10e6)
    poisson_ratio_range: tuple[float, float] = (0.25, 0.49)
    thickness_range_m: tuple[float, float] = (1e-3, 0.1)
    strain_limit_range: tuple[float, float] = (0.03, 0.17)
    friction_range: tuple[float, float] = (0.2, 1.0)
    stiffness_scale: float = 1.0
    density_range_kg_m3: tuple[float, float] = (20.0, 1200.0)
    payload_factor_range: tuple[float, float] = (0.0, DEFAULT_PAYLOAD_FACTOR)
    placement_tolerance_range_rel: tuple[float, float] = (0.0, 0.25)
    aspect_ratio_range: tuple[float, float] = (1.0, 1.0)
    orientation_range_rad: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        for name, low, high, low_open, high_open in (
                ("radius_range_m", 0.0, math.inf, True, False),
                ("youngs_modulus_range_pa", 0.0, math.inf, True, False),
                ("poisson_ratio_range", 0.0, 0.5, False, True),
                ("thickness_range_m", 0.0, math.inf, True, False),
                ("strain_limit_range", 0.0, 0.5, True, False),
                ("friction_range", 0.0, 2.0, True, False),
                ("density_range_kg_m3", 0.0, math.inf, True, False),
                ("payload_factor_range", 0.0, MAX_PAYLOAD_FACTOR, False, False),
                ("placement_tolerance_range_rel", 0.0, 0.5, False, False),
                ("aspect_ratio_range", 1.0, 4.0, False, False),
                ("orientation_range_rad", -math.pi, math.pi, False, False)):
            object.__setattr__(self, name, _pair(name, getattr(self, name), low, high,
                                                 low_open=low_open, high_open=high_open))
        scale = check_range("stiffness_scale", self.stiffness_scale, 10.0**-2, 10.0)
        object.__setattr__(self, "stiffness_scale", scale)
        # a SoftDisk validates the material fields (both ends of every range)
        for end in (0, 1):
            SoftDisk(self.radius_range_m[end], 0.0, self.youngs_modulus_range_pa[end],
                     self.poisson_ratio_range[end], self.thickness_range_m[end], scale,
                     density_kg_m3=self.density_range_kg_m3[end])
        # the heaviest, largest, softest object's payload ratio (it grows with f rho r / E)
        heaviest = SoftDisk(self.radius_range_m[1], 0.0, self.youngs_modulus_range_pa[0],
                            self.poisson_ratio_range[0], self.thickness_range_m[0], scale,
                            density_kg_m3=self.density_range_kg_m3[1])
        largest = payload_ratio(heaviest, self.payload_factor_range[1])
        limit = 10.0 ** _OBS_RANGE["payload_ratio"][1]
        if largest > limit:
            raise ValueError(f"the ranges reach a payload ratio f rho g pi r / (s E) = "
                             f"{largest:.3g}, beyond the observable {limit:g}: narrow "
                             "payload_factor_range, density_range_kg_m3, radius_range_m or "
                             "youngs_modulus_range_pa")
        object.__setattr__(self, "_template", SoftDisk(
            self.radius_range_m[0], 0.0, self.youngs_modulus_range_pa[0],
            self.poisson_ratio_range[0], self.thickness_range_m[0], scale,
            density_kg_m3=self.density_range_kg_m3[0]))

    @property
    def has_shapes(self) -> bool:
        """Whether the objects drawn are ellipses (an aspect ratio or orientation range)."""
        return (self.aspect_ratio_range != (1.0, 1.0)
                or self.orientation_range_rad[0] != self.orientation_range_rad[1]
                or self.orientation_range_rad[0] != 0.0)

    def sample(self, rng: np.random.Generator
               ) -> tuple[SoftDisk, float, float, float, float]:
        """Draw an object and what a design must respect (:data:`NEED_KEYS`): the disk, its
        strain limit, friction coefficient, payload factor and placement tolerance over the
        radius; nine uniform numbers of ``rng`` in one call (radius, modulus, Poisson ratio,
        thickness, strain limit, friction, density, payload factor, tolerance, in this order),
        eleven with shapes (:attr:`has_shapes`: then the aspect ratio and the orientation).

        The disk's ``distance_m`` is 0: the design's ``distance_m`` replaces it.
        """
        # one call, not nine: a vector env draws hundreds of objects per step and each call of
        # a Generator costs about a microsecond
        u = rng.random(11 if self.has_shapes else 9).tolist()

        def log_uniform(pair, x):
            return math.exp(math.log(pair[0]) + x * (math.log(pair[1]) - math.log(pair[0])))

        def uniform(pair, x):
            return pair[0] + x * (pair[1] - pair[0])

        # every field lies in a range validated at construction: a copy of the validated
        # template with the drawn fields, not a SoftDisk validated again (a vector env draws
        # one object per reset, hundreds per step)
        disk = object.__new__(SoftDisk)
        disk.__dict__.update(self._template.__dict__)  # copy.copy without its reduce protocol
        for name, value in (("radius_m", log_uniform(self.radius_range_m, u[0])),
                            ("youngs_modulus_pa", log_uniform(self.youngs_modulus_range_pa,
                                                              u[1])),
                            ("poisson_ratio", uniform(self.poisson_ratio_range, u[2])),
                            ("thickness_m", log_uniform(self.thickness_range_m, u[3])),
                            ("density_kg_m3", log_uniform(self.density_range_kg_m3, u[6]))):
            object.__setattr__(disk, name, value)
        if self.has_shapes:
            # the same copy as a SoftObject, its drawn ellipse and orientation in it
            shaped = object.__new__(SoftObject)
            shaped.__dict__.update(disk.__dict__)
            object.__setattr__(shaped, "outline", Ellipse(uniform(self.aspect_ratio_range,
                                                                  u[9])))
            object.__setattr__(shaped, "orientation_rad", uniform(self.orientation_range_rad,
                                                                  u[10]))
            disk = shaped
        return (disk, uniform(self.strain_limit_range, u[4]),
                uniform(self.friction_range, u[5]), uniform(self.payload_factor_range, u[7]),
                uniform(self.placement_tolerance_range_rel, u[8]))


_OBS_RANGE = {name: (low, high) for name, _, low, high in OBS_FIELDS}
_SHAPE_OBS_RANGE = {name: (low, high) for name, _, low, high in SHAPE_OBS_FIELDS}


def payload_ratio(disk: SoftDisk, payload_factor: float) -> float:
    """The payload ``W = f rho pi r^2 t g`` in the object's force unit ``s E t r``: ``f rho g
    pi r / (s E)`` [-], what the payload changes in a relative design's grasp."""
    return float(_payload_ratios(np.array([[disk.radius_m, disk.youngs_modulus_pa,
                                            disk.stiffness_scale, disk.density_kg_m3]]),
                                 np.array([payload_factor], dtype=float))[0])


def _payload_ratios(fields: np.ndarray, factors: np.ndarray) -> np.ndarray:
    """:func:`payload_ratio` of rows (radius, modulus, scale, density) and factors (B,), as
    array operations: ``SoftDisk.payload_n(f)`` over ``SoftDisk.torque_unit_nm / r`` row by
    row (tested), without a Python call per object (a vector env observes hundreds a step)."""
    radius, modulus, scale, density = fields.T
    return factors * density * GRAVITY_M_S2 * math.pi * radius / (scale * modulus)


def observe(disk: SoftDisk, strain_limit: float, friction_coefficient: float,
            payload_factor: float = DEFAULT_PAYLOAD_FACTOR,
            placement_tolerance_rel: float = 0.0) -> np.ndarray:
    """Normalized observation of an object, float32 (6,) in [-1, 1] (see :data:`OBS_FIELDS`).

    Parameters
    ----------
    disk
        The object (its ``density_kg_m3`` with ``payload_factor`` gives the payload ratio).
    strain_limit, friction_coefficient
        What the design must respect [-].
    payload_factor
        ``f`` of the payload ``W = f rho pi r^2 t g`` [-] (default 2).
    placement_tolerance_rel
        Placement tolerance over the radius [-] (default 0: placed exactly).

    Raises
    ------
    ValueError
        If a value lies outside the observable range (the message names it).
    """
    return observe_rows([disk], np.array([[strain_limit, friction_coefficient, payload_factor,
                                           placement_tolerance_rel]], dtype=float))[0]


def observe_rows(disks: list[SoftDisk], needs: np.ndarray) -> np.ndarray:
    """Normalized observations of B objects, float32 (B, 6) in [-1, 1]: :func:`observe` row by
    row, as array operations (a vector env observes hundreds of new objects per step).

    Parameters
    ----------
    disks
        The B disks.
    needs
        Their strain limits, friction coefficients, payload factors and placement tolerances
        over the radius, (B, 4) (:data:`NEED_KEYS`); or only the first two, (B, 2), with the
        defaults for the others (payload factor 2, no tolerance).

    Raises
    ------
    ValueError
        If a value lies outside the observable range (the message names it, and the row when
        B > 1).
    """
    return _observe_table(_object_table(disks), _full_needs(needs))


def _full_needs(needs) -> np.ndarray:
    """Needs (B, 2) or (B, 4) as (B, 4), the missing columns at :data:`DEFAULT_NEEDS`."""
    needs = np.asarray(needs, dtype=float)
    needs = needs.reshape(1, -1) if needs.ndim == 1 else needs
    if needs.ndim != 2 or needs.shape[1] not in (2, len(NEED_KEYS)):
        raise ValueError(f"needs must have shape (B, 2) or (B, {len(NEED_KEYS)}) (columns "
                         f"{', '.join(NEED_KEYS)}), got {needs.shape}")
    if needs.shape[1] == 2:
        extra = np.array([DEFAULT_NEEDS[k] for k in NEED_KEYS[2:]])
        needs = np.hstack([needs, np.broadcast_to(extra, (needs.shape[0], extra.size))])
    return needs


_DISK_FIELDS = operator.attrgetter(*DISK_INFO_KEYS)  # one C call per object


def _object_table(disks: list[SoftDisk]) -> np.ndarray:
    """The disks' fields, float (B, 6), columns as :data:`DISK_INFO_KEYS`."""
    return np.array([_DISK_FIELDS(d) for d in disks],
                    dtype=float).reshape(len(disks), len(DISK_INFO_KEYS))


def shape_observation(disks: list[SoftDisk]) -> np.ndarray:
    """The shape part of ``GripperShapeDesign-v0``'s observation, float32 (B, 2) in [-1, 1]
    (:data:`SHAPE_OBS_FIELDS`): an ellipse's aspect ratio and ``cos(2 psi)`` (a disk: aspect
    1, ``cos 0``); ``ValueError`` for an outline that is not an ellipse or an aspect ratio
    outside [1, 4]."""
    obs = np.empty((len(disks), len(SHAPE_OBS_FIELDS)), dtype=np.float32)
    for i, d in enumerate(disks):
        if d.outline is not None and not isinstance(d.outline, Ellipse):
            raise ValueError(f"GripperShapeDesign-v0 observes ellipses and disks, got a "
                             f"{d.shape} (row {i})")
        aspect = 1.0 if d.outline is None else d.outline.aspect_ratio
        low, high = _SHAPE_OBS_RANGE["aspect_ratio"]
        if not low <= aspect <= high:
            raise ValueError(f"aspect_ratio = {aspect!r} (row {i}) is outside the observable "
                             f"range [{low:g}, {high:g}]")
        obs[i] = (2.0 * (aspect - low) / (high - low) - 1.0,
                  math.cos(2.0 * (0.0 if d.outline is None else d.orientation_rad)))
    return obs


def _observe_table(table: np.ndarray, needs: np.ndarray) -> np.ndarray:
    """:func:`observe_rows` of a disk table (:func:`_object_table`) and the needs (B, 4)."""
    values = {key: table[:, k] for k, key in enumerate(DISK_INFO_KEYS)}
    values.update({key: needs[:, k] for k, key in enumerate(NEED_KEYS)})
    factors = values["payload_factor"]
    bad = np.flatnonzero(~((factors >= 0.0) & (factors <= MAX_PAYLOAD_FACTOR)))
    if bad.size:  # (the payload ratio would name the factor's mistake less clearly)
        raise ValueError(f"payload_factor = {float(factors[bad[0]])!r}"
                         f"{f' (row {int(bad[0])})' if table.shape[0] > 1 else ''} is outside "
                         f"the allowed range [0, {MAX_PAYLOAD_FACTOR:g}]")
    columns = [DISK_INFO_KEYS.index(k) for k in ("radius_m", "youngs_modulus_pa",
                                                  "stiffness_scale", "density_kg_m3")]
    values["payload_ratio"] = _payload_ratios(table[:, columns], factors)
    n_rows = table.shape[0]
    obs = np.empty((n_rows, len(OBS_FIELDS)), dtype=np.float32)
    for i, (name, transform, low, high) in enumerate(OBS_FIELDS):
        v = values[name]
        if name in FLOORED_FIELDS:
            v = np.where(v >= 0.0, np.maximum(v, 10.0**low), v)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.log10(v) if transform == "log10" else v
        # a strain limit or friction of 0 is no object: the lower end is open for them
        open_low = name in OPEN_LOW_FIELDS
        bad = np.flatnonzero(~(((low < t) if open_low else (low <= t)) & (t <= high)))
        if bad.size:
            row = int(bad[0])
            lo, hi = ((10**low, 10**high) if transform == "log10" else (low, high))
            shown = f"{'(' if open_low else '['}{lo:g}, {hi:g}]"
            where = f" (row {row})" if n_rows > 1 else ""
            raise ValueError(f"{name} = {float(v[row])!r}{where} is outside the observable "
                             f"range {shown}")
        obs[:, i] = 2.0 * (t - low) / (high - low) - 1.0
    return np.clip(obs, -1.0, 1.0)


def _object_info(disk: SoftDisk, needs: np.ndarray) -> dict[str, float]:
    # the disk's fields named in DISK_INFO_KEYS, then the needs (as _object_table)
    return {**dict(zip(DISK_INFO_KEYS, _DISK_FIELDS(disk), strict=True)),
            **{key: float(v) for key, v in zip(NEED_KEYS, needs, strict=True)}}


def _check_actions(actions, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Validate actions; return them clipped to [-1, 1] (float64) and a per-row clipped flag."""
    a = real_array("action", actions, f"numbers of shape {shape}")
    if a.shape != shape:
        raise ValueError(f"action must have shape {shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"action must be finite (no NaN or inf), got {a.tolist()}")
    clipped = np.any((a < -1.0) | (a > 1.0), axis=-1)
    return np.clip(a, -1.0, 1.0), np.asarray(clipped)


RESET_OPTIONS = ("disk", "strain_limit", "friction_coefficient", "payload_factor",
                 "placement_tolerance_rel")


def _options_dict(options: Any) -> dict[str, Any]:
    """A copy of the ``options`` of a reset: ``None`` or a mapping, by option name."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ValueError(f"options must be None or a dict of reset options (allowed keys: "
                         f"{', '.join(RESET_OPTIONS)}), got {type(options).__name__} "
                         f"{options!r:.60}")
    return dict(options)


def _parse_options(options: dict[str, Any] | None) -> dict[str, Any]:
    """The reset options, every one validated (numbers as floats) before a reset changes
    anything: a refused reset leaves the env, its random stream included, as it was."""
    options = _options_dict(options)
    unknown = set(options) - set(RESET_OPTIONS)
    if unknown:
        raise ValueError(f"unknown reset options {sorted(unknown)}; allowed: "
                         f"{', '.join(RESET_OPTIONS)}")
    if "disk" in options and not isinstance(options["disk"], SoftDisk):
        raise ValueError(f"options['disk'] must be a SoftDisk, got {type(options['disk'])}")
    if "strain_limit" in options:
        options["strain_limit"] = check_range("strain_limit", options["strain_limit"], 0.0, 0.5,
                                              low_open=True)
    if "friction_coefficient" in options:
        options["friction_coefficient"] = check_range(
            "friction_coefficient", options["friction_coefficient"], 0.0, 2.0, low_open=True)
    if "payload_factor" in options:
        options["payload_factor"] = check_range("payload_factor", options["payload_factor"],
                                                0.0, MAX_PAYLOAD_FACTOR)
    if "placement_tolerance_rel" in options:
        low, high = _OBS_RANGE["placement_tolerance_rel"]
        options["placement_tolerance_rel"] = check_range(
            "placement_tolerance_rel", options["placement_tolerance_rel"], low, high)
    if "disk" in options:  # observable (valid needs stand in for ones drawn later)
        _observe_table(_object_table([options["disk"]]),
                       np.array([[0.1, 0.5, options.get("payload_factor", 0.0), 0.0]]))
    return options


def check_reset_arguments(seed: int | None, options: dict[str, Any] | None) -> dict[str, Any]:
    """Validate the arguments of :meth:`GripperDesignEnv.reset` without touching any state;
    return the parsed options.

    Also called by :class:`envs.reset_check.ResetCheck` around the env ``gym.make`` builds, before
    Gymnasium's passive checker: that wrapper marks its first reset as checked before calling
    the env, so a refused first reset would leave it without the reset's data and its first
    step check would fail with a ``TypeError`` from then on.

    Raises
    ------
    ValueError
        For a seed that is not None or an integer >= 0, an unknown option, a ``disk`` that is
        not an observable :class:`~envs.scene.SoftDisk`, a ``strain_limit`` outside (0, 0.5],
        a ``friction_coefficient`` outside (0, 2], a ``payload_factor`` outside [0, 100], a
        ``placement_tolerance_rel`` outside [0, 0.5].
    """
    if seed is not None and (isinstance(seed, bool | np.bool_)
                             or not isinstance(seed, int | np.integer) or seed < 0):
        raise ValueError(f"seed must be None or an integer >= 0, got {seed!r}")
    return _parse_options(options)


def _draw(rng: np.random.Generator, distribution: ObjectDistribution,
          options: dict[str, Any]) -> tuple[SoftDisk, np.ndarray]:
    # always draw, so the random stream does not depend on the options (validated by
    # _parse_options; the distribution's own draws lie in its validated range)
    disk, *drawn = distribution.sample(rng)
    return options.get("disk", disk), np.array([options.get(key, value) for key, value
                                                in zip(NEED_KEYS, drawn, strict=True)])


def _draw_object(rng: np.random.Generator, distribution: ObjectDistribution,
                 options: dict[str, Any], shapes: bool = False
                 ) -> tuple[SoftDisk, np.ndarray, np.ndarray]:
    disk, needs = _draw(rng, distribution, options)
    obs = observe(disk, *needs)
    if shapes:
        obs = np.concatenate([obs, shape_observation([disk])[0]])
    return disk, needs, obs


def evaluate_objects(designs: np.ndarray, disks: list[SoftDisk], needs: np.ndarray,
                     **kwargs: Any) -> dict[str, np.ndarray]:
    """The env's answer to B designs, each for its own object: the worst grasp over the
    object's placements, all of them solved in one batch.

    Each object with a placement tolerance ``tau`` (its ``placement_tolerance_rel`` times its
    radius) is placed at the 9 points of the ``+-tau`` box along and across the gripper's axis
    (:meth:`envs.scenarios.Scenarios.of`, :func:`envs.scenarios.place`); one without tolerance
    at its nominal place only. Every row of every object goes through one
    :func:`~envs.evaluate.evaluate_designs` call.

    Parameters
    ----------
    designs
        (B, 6) SI designs, placed against the nominal object.
    disks
        The B objects.
    needs
        (B, 4): strain limit, friction coefficient, payload factor, placement tolerance over
        the radius (:data:`NEED_KEYS`).
    **kwargs
        Passed to :func:`~envs.evaluate.evaluate_designs`: the reward weights, the joint
        spring, the model member (not the per-row objects, friction, payload or offsets).

    Returns
    -------
    dict
        Every key of :data:`~envs.evaluate.METRIC_KEYS` (first axis B) of each object's worst
        placement (the lowest reward; the first such on ties), whose reward is the robust
        (worst) reward; ``reward_nominal`` (the nominal placement's reward) and
        ``worst_scenario`` (the index of the worst placement in
        :meth:`~envs.scenarios.Scenarios.scenarios`'s order).
    """
    limit, friction, factor, tolerance = np.asarray(needs, dtype=float).T  # NEED_KEYS order
    # each design repeats over its object's placements (place() moves each row to its own)
    rows, placed, frictions, offsets = [], [], [], []
    for i, disk in enumerate(disks):
        cases = Scenarios.of(placement_tolerance_m=float(tolerance[i]) * disk.radius_m
                             ).scenarios()
        r, d, f, o = place(np.repeat(designs[i][None, :], len(cases), axis=0), disk,
                           float(friction[i]), cases)
        rows.append(r)
        placed.extend(d)
        frictions.append(f)
        offsets.append(o + disk.offset_x_m)  # (a disk placed off the axis stays there)
    sizes = np.array([r.shape[0] for r in rows])
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    out = evaluate_designs(
        np.concatenate(rows), placed, strain_limits=np.repeat(limit, sizes),
        friction_coefficients=np.concatenate(frictions),
        payload_factors=np.repeat(factor, sizes), offsets_x_m=np.concatenate(offsets),
        # each design's other placements start from its nominal answer, the first of its rows
        leaders=nominal_leaders(sizes), **kwargs)
    worst = np.minimum.reduceat(out["reward"], starts)
    index = np.arange(out["reward"].size)
    is_worst = out["reward"] == np.repeat(worst, sizes)
    pick = np.minimum.reduceat(np.where(is_worst, index, index.size), starts)
    picked = {key: v[pick] for key, v in out.items()}
    picked["reward_nominal"] = out["reward"][starts]
    picked["worst_scenario"] = (pick - starts).astype(np.int64)
    return picked


def _check_settings(bounds, distribution, weights, n_triangles, n_rings, element, calibrated):
    """The env settings, validated at construction (not at the first step); defaults for None.
    The last is the model member (:class:`envs.model.family.ModelSpec`)."""
    checked = []
    for name, value, kind in (("bounds", bounds, DesignBounds),
                              ("distribution", distribution, ObjectDistribution),
                              ("weights", weights, RewardWeights)):
        if value is not None and not isinstance(value, kind):
            raise ValueError(f"{name} must be None or a {kind.__name__}, got "
                             f"{type(value).__name__}")
        checked.append(kind() if value is None else value)
    return (*checked, resolve_model(n_triangles, n_rings,
                                    DEFAULT_ELEMENT if element is None else element, calibrated))


def _spaces(bounds: DesignBounds, shapes: bool = False) -> tuple[spaces.Box, spaces.Box]:
    """The action space (one coordinate per column of the bounds: 6, plus the jaw columns)
    and the observation space."""
    action = spaces.Box(-1.0, 1.0, shape=(bounds.n_var,), dtype=np.float32)
    obs = spaces.Box(-1.0, 1.0, shape=(_n_obs(shapes),), dtype=np.float32)
    return action, obs


def _n_obs(shapes: bool) -> int:
    """Length of an observation: :data:`OBS_FIELDS`, and with shapes (v4)
    :data:`SHAPE_OBS_FIELDS`."""
    return len(OBS_FIELDS) + (len(SHAPE_OBS_FIELDS) if shapes else 0)


#: The default objects of ``GripperShapeDesign-v0``: v2's, each an ellipse of aspect ratio 1 to 3
#: at any orientation (0 to pi/2 covers them all: the grasp of psi + pi is that of psi, and
#: that of -psi its mirror image)
SHAPE_DISTRIBUTION = dict(aspect_ratio_range=(1.0, 3.0), orientation_range_rad=(0.0,
                                                                                  math.pi / 2))


def _shape_settings(distribution, observe_shapes) -> tuple[ObjectDistribution | None, bool]:
    """``observe_shapes`` validated, and the distribution (v4's default with shapes)."""
    if not isinstance(observe_shapes, bool):
        raise ValueError(f"observe_shapes must be True or False, got {observe_shapes!r}")
    if observe_shapes and distribution is None:
        distribution = ObjectDistribution(**SHAPE_DISTRIBUTION)
    return distribution, observe_shapes


def _info_value(v: np.ndarray):
    """Per-row info entry: Python scalar for scalars, small array otherwise."""
    if v.ndim == 0:
        return v.item()
    return v.copy()


def _render_frame(design: np.ndarray | None, disk: SoftDisk, strain_limit: float,
                  model: ModelSpec, spring: dict[str, float], cache: dict) -> np.ndarray:
    """Off-screen frame (uint8 H x W x 3) of a design on a disk; re-solves with simulate()."""
    from matplotlib.figure import Figure

    from .render import draw_design, figure_rgb_array, grasp_figure
    from .solver import simulate

    if design is None:
        fig = Figure(figsize=(5.0, 5.0), dpi=80)
        # the centre of the default box, at the object's scale
        draw_design(fig.add_subplot(), DesignBounds().scale(np.zeros(N_DESIGN), disk),
                    disk.radius_m, title="no design yet: call step()", disk=disk)
        return figure_rgb_array(fig)
    chosen = Design.from_array(design)
    try:
        # the one Design -> Scene mapping, the one evaluate_designs scored
        scene = chosen.to_scene(disk, **spring)
    except ValueError as exc:
        fig = Figure(figsize=(5.0, 5.0), dpi=80)
        draw_design(fig.add_subplot(), design, disk.radius_m,
                    title="invalid design:\n" + textwrap.fill(str(exc).split(":")[0], 60),
                    disk=disk)
        return figure_rgb_array(fig)
    key = (tuple(design.tolist()), disk, model, tuple(spring.items()))
    if cache.get("key") != key:
        cache.clear()
        cache["key"], cache["result"] = key, simulate(scene, chosen.torque_nm,
                                                      **model.kwargs())
    fig = grasp_figure(scene, cache["result"], strain_limit=strain_limit, dpi=80)
    return figure_rgb_array(fig)


class GripperDesignEnv(gym.Env):
    """
    ## Description

    Design an angular two-finger gripper for a soft disk. Each episode presents one object (a
    soft 2-D disk with a radius, a stiffness, a density, a strain limit, a friction coefficient
    of the finger pads on it, a payload to lift and a placement tolerance); the agent answers
    with one
    design (finger length, rest angle, joint offset, finger width, actuation torque and where the
    object sits), the grasp is solved with the point-spring model of the disk (quasi-static,
    frictionless contact, a member of the model family) and the episode ends. It is a
    contextual bandit: one step is one grasp. The physics is
    :func:`envs.evaluate.evaluate_designs`; this class is only the Gymnasium adapter (the same
    function evaluates populations for optimizers).

    Frame: x to the right, y up, the gripper's symmetry axis is the y axis, the finger joints are
    at ``(+-d_3, 0)``, the disk centre at ``(x_c, d_1 + r)``: ``x_c = 0`` unless a disk given at
    reset is placed off the axis (``SoftDisk.offset_x_m``; held where it was placed).

    ## Action Space

    The action is a `ndarray` with shape `(6,)`, float32 in `[-1, 1]`, mapped linearly to the
    box of `bounds` (a :class:`~envs.evaluate.DesignBounds`), which is relative to the object
    drawn at reset: lengths in disk radii `r`, the torque in the disk's torque unit
    `s E t r^2`, and the placement given as the rest clearance between the disk and the
    gripping faces (so every action of the default box is a design valid at rest, for a 2 mm
    bead as for a 100 mm disk). Values outside `[-1, 1]` are clipped (reported in
    `info["clipped"]`); NaN, inf or a wrong shape raise `ValueError`. `info["design"]` holds
    the physical design (SI units).

    | Num | Action                                    | Unit | Min (-1)        | Max (+1)        |
    |-----|-------------------------------------------|------|-----------------|-----------------|
    | 0   | finger length `l / r`                     | -    | 1.5             | 8               |
    | 1   | rest angle `theta_a0`                     | rad  | 0.1745 (10 deg) | 1.0472 (60 deg) |
    | 2   | joint offset `d_3 / r`                    | -    | 0.0             | 0.6             |
    | 3   | finger width `w / r`                      | -    | 0.05            | 0.4             |
    | 4   | actuation torque `T_a / (s E t r^2)`      | -    | 0.0             | 0.3             |
    | 5   | rest clearance of disk and faces, `/ r`   | -    | 0.005           | 1.2             |

    The placement `d_1` follows from the clearance `g`:
    `d_1 = max(0, (r (1 + g) + w/2 - d_3 cos theta_a0) / sin theta_a0 - r)`
    (:func:`envs.scene.design_from_relative`).

    ## Observation Space

    The observation is a float32 `ndarray` with shape `(6,)` describing the object, each value
    mapped linearly from the range below to `[-1, 1]` (a reset with an object outside these
    ranges raises `ValueError`; a payload ratio below 1e-8 is observed as 1e-8). The radius,
    the modulus, the thickness and the density are not observed: the model is invariant under
    them (lengths in radii, torques and the joint spring in `s E t r^2`, forces in `s E t r`),
    so an action scores the same on every disk of one Poisson ratio, strain limit, friction
    coefficient, calibration scale, payload ratio and relative placement tolerance (tested);
    `info` holds them.

    | Num | Observation                                   | Transform | Min    | Max   |
    |-----|-----------------------------------------------|-----------|--------|-------|
    | 0   | Poisson's ratio `nu` [-]                      | linear    | 0.0    | 0.5   |
    | 1   | strain limit `eps_max` [-]                    | linear    | 0.0    | 0.5   |
    | 2   | friction coefficient `mu` [-]                 | linear    | 0.0    | 2.0   |
    | 3   | calibration scale `s` [-]                     | log10     | 0.01   | 10    |
    | 4   | payload ratio `W / (s E t r) = f rho g pi r / (s E)` | log10 | 1e-8 | 10  |
    | 5   | placement tolerance over the radius `tau / r` | linear    | 0.0    | 0.5   |

    The payload is `W = f rho pi r^2 t g` (payload factor `f`, density `rho`): the grasp must
    carry it by friction (:func:`~envs.evaluate.evaluate_designs` ``payload_factors``).

    ## Rewards

    The robust reward over the object's placements: with a placement tolerance `tau > 0` the
    object's centre is placed at the 9 points of the `+-tau` box along and across the
    gripper's axis (its centre, edge midpoints and corners, :class:`envs.scenarios.Scenarios`)
    and the reward is the worst of the 9 grasps (one batch, :func:`evaluate_objects`); `info`
    holds that grasp's metrics, `reward_nominal` (the centred placement's reward) and
    `worst_scenario`. Each grasp's reward is that of :func:`~envs.evaluate.evaluate_designs`
    with the weights `w` of :class:`~envs.evaluate.RewardWeights`, in tiers (defaults in
    brackets):

    - a grasp that **holds** the object (both fingers touching, the friction it needs to hold
      a free object within `mu`): *w_contact min(c, c_max) - w_deform min(eps / eps_max,
      q_max)*, in `[-1, 0.5]`, with `c` the contact score, the fraction of the contour in
      contact (each face's share the smaller of its pressed points over `N` and the Hertz
      width of its force) times the grip share, the part of the actuation torque that grips
      the object (`w_contact = 1`, `c_max = 0.5`), and `eps` the peak compression, the
      largest shortening of a radius by the fingers over r (`w_deform = 0.25`, `q_max = 4`);
    - a grasp that would **slip** (it needs friction `mu_req > mu`): *-1 - w_slip x / (1 + x)*,
      `x = mu_req / mu - 1`, in `[-1.5, -1)` (`w_slip = 0.5`);
    - a **miss** (a finger does not touch): *-1.5 - w_miss m - w_gap g / (1 + g)*, `m` the
      fingers missing, `g` the largest gap of such a finger to the disk in radii, in
      `(-3, -2]` (`w_miss = 0.5`, `w_gap = 0.5`): closer fingers score higher;
    - the solver failed: *-w_fail* (`-3`);
    - invalid at rest (the fingers overlap the disk, ...; nothing is solved):
      *-w_invalid - w_violation v / (1 + v)*, `v` how far it is from valid, in `[-4.5, -3.5]`.

    Every outcome of a tier scores below every outcome of the tiers above, and the reward is
    finite. Each signed term is in `info` (`reward_contact`, `reward_deform`, `penalty_slip`,
    `penalty_miss`, `penalty_gap`, `penalty_invalid`, `penalty_fail`), with `required_friction`,
    `pin_force_n`, `holds`, `finger_gap_m` and `rest_violation`.

    ## Starting State

    At reset an object is drawn from `distribution` (an :class:`ObjectDistribution`; default,
    covering real use: radius 1 mm to 0.2 m, Young's modulus 10 kPa to 10 MPa, thickness
    1 mm to 0.1 m and density 20 to 1200 kg/m^3 log-uniform, `nu` 0.25 to 0.49, strain limit
    (admissible compression) 0.03 to 0.17, friction coefficient 0.2 to 1.0, payload factor 0
    to 2 and placement tolerance 0 to 0.25 radii uniform, `s = 1`).
    `reset(options={"disk": SoftDisk(...), "strain_limit": 0.1, "friction_coefficient": 0.5,
    "payload_factor": 2.0, "placement_tolerance_rel": 0.1})` fixes any of them (the disk's
    `distance_m` is ignored: `d_1` is part of the action; its `density_kg_m3` is used).

    ## Episode End

    The episode terminates after its single step (`terminated=True`, `truncated=False`): it is
    a contextual bandit, one object and one design per episode. It is registered without a
    `TimeLimit` (`max_episode_steps=None`), so `check_env(gym.make("GripperDesign-v2"))`
    passes. Stepping again without a reset evaluates another design on the same object, with a
    warning once an episode (:class:`~envs.validation.PsmGraspWarning`, as Gymnasium's own
    environments warn): in a training loop it is a forgotten reset.

    Vectorized, every step should evaluate a design: `gym.make_vec("GripperDesign-v2", n)`
    (the batched :class:`GripperDesignVectorEnv`) resets ended sub-envs in the same step by
    default. Gymnasium's `"sync"` and `"async"` modes reset on the *next* step unless told
    otherwise, which would spend every other step on a reset: pass
    `vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP}`.

    ## Arguments

    - `render_mode`: `None`, `"rgb_array"` (off-screen Agg frame) or `"human"` (matplotlib
      window). The frame shows the jaws at rest and closed, the rest and deformed disk, the
      contacts and the springs coloured by strain; it re-solves the last design with
      :func:`envs.solver.simulate` (same kernel).
    - `bounds`: :class:`~envs.evaluate.DesignBounds` of the action mapping (relative units).
    - `distribution`: :class:`ObjectDistribution` of the objects drawn at reset.
    - `weights`: :class:`~envs.evaluate.RewardWeights`.
    - `n_triangles`, `n_rings`, `element`, `calibrated`: the member of the model family that
      solves each grasp, as in :func:`envs.simulate` (default: the default model, nh-quad with
      `N = 40` contour points, 2 rings and its shipped calibration, chosen to be within 2 %
      RMS and 4 % max of the FEM closing angle; `element="spring"` is the paper's fan with
      `N = 20`, cheaper and far off the FEM at `s = 1`; docs/accuracy.md). `self.model` holds
      the resolved member.
    - `torsion_stiffness_rel`: joint torsion spring `k_f` in the object's torque unit
      `s E t r^2` per radian (default: the paper gripper's 0.073 N·m/rad on its r = 0.07 m
      disk, 0.0149 per radian: the spring scales with each object like the torque, so an
      action means the same grasp for every object); `torsion_stiffness_nm_per_rad`: an
      absolute spring [N·m/rad] instead. `self.joint_spring` holds the one given.
    - `load_set`: how the gripper picks, the payload's directions a grasp must hold the
      object in (`"top-down"`, `"side"` or `"any"`, :mod:`envs.model.loads`; default
      `"any"`, every direction): a setting of the env, not observed.

    `info` holds every metric of :func:`~envs.evaluate.evaluate_designs` (`converged`,
    `valid_at_rest`, `jaw_angles_rad`, `n_contacts`, `peak_strain`, ...), the reward terms,
    `clipped`, the physical `design` (6 values in SI units, :data:`envs.scene.DESIGN_FIELDS`
    order; 10 or 14 with shaped jaws, :data:`envs.scene.ALL_DESIGN_FIELDS`) and the object.

    ## Version History

    * ``GripperShapeDesign-v0`` (an id of its own beside v2): objects that are not disks.
      Every object is an ellipse
      (:class:`envs.objects.Ellipse`, the drawn radius its area-equivalent radius ``r_eq``) of
      aspect ratio 1 to 3 at an orientation of 0 to 90 degrees (:data:`SHAPE_DISTRIBUTION`;
      ``ObjectDistribution.aspect_ratio_range`` and ``orientation_range_rad``), placed with
      its lowest point ``d_1`` above the joints' line and the faces clearing it by the
      action's clearance; the observation gains its aspect ratio (linear, 1 to 4) and
      ``cos(2 psi)`` (shape 8). Actions, rewards and the placements are v2's
      (``gym.make("GripperShapeDesign-v0")``, ``observe_shapes=True``).
    * v3: shaped jaws. The action gains the jaw columns of the design space
      (:class:`~envs.evaluate.DesignBounds` ``jaw``, ``jaw_per_finger``): a groove cut into the
      gripping faces, chosen at make, `gym.make("GripperJawDesign-v0", jaw="cradle")` (default
      `"any"`: depth, bottom radius, opening angle and position, shape 10; `"cradle"` and
      `"vee"` 9; `jaw_per_finger=True` doubles the jaw columns). The observation, the
      objects and the reward are v2's; `bounds` may be given too (its jaw is replaced).

    * v2: the payload and the placement tolerance: the object's density, a payload factor
      and a placement tolerance over the radius are drawn at reset (and reset options); the
      observation gains the payload ratio `f rho g pi r / (s E)` and the tolerance `tau / r`
      (shape 6); the reward is the worst over the 9 placements of the tolerance box. The
      reward tiers gain "crushes" (a hold beyond the strain limit). v1 is no longer
      registered (its observation space differs).
    * v1: the object's friction coefficient, and holding: a grasp that would let a free object
      slip scores below every grasp that holds; the reward in tiers (a miss below every grasp);
      the observation is what changes a relative design's grasp (Poisson ratio, strain limit,
      friction, calibration scale), not the radius, modulus and thickness; the default object
      distribution covers real use; the joint spring relative to the object.
    * v0: Initial version. Later in v0: actions relative to the object (lengths in radii,
      torque in `s E t r^2`, placement as a rest clearance) instead of metres; graded
      penalties for missing and invalid designs; no `TimeLimit` in the registration.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": RENDER_FPS}

    def __init__(
        self,
        render_mode: str | None = None,
        *,
        bounds: DesignBounds | None = None,
        distribution: ObjectDistribution | None = None,
        weights: RewardWeights | None = None,
        n_triangles: int | None = None,
        torsion_stiffness_rel: float | None = None,
        torsion_stiffness_nm_per_rad: float | None = None,
        n_rings: int | None = None,
        element: str | None = None,
        calibrated: bool | None = None,
        observe_shapes: bool = False,
        load_set: str = DEFAULT_LOAD_SET,
    ) -> None:
        load_set_code(load_set)  # (a bad setting at construction, not at the first step)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of "
                             f"{self.metadata['render_modes']}")
        self.render_mode = render_mode
        distribution, self.observe_shapes = _shape_settings(distribution, observe_shapes)
        self.bounds, self.distribution, self.weights, self.model = _check_settings(
            bounds, distribution, weights, n_triangles, n_rings, element, calibrated)
        self.joint_spring = joint_spring_kwargs(torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
        self.load_set = load_set
        self.action_space, self.observation_space = _spaces(self.bounds, self.observe_shapes)
        self._disk: SoftDisk | None = None
        self._terminated = 0  # steps since the episode ended (it ends with its first)
        self._needs = np.zeros(len(NEED_KEYS))  # NEED_KEYS order
        self._obs = np.zeros(_n_obs(self.observe_shapes), dtype=np.float32)
        self._last_design: np.ndarray | None = None
        self._render_cache: dict = {}
        self._figure = None

    @property
    def n_triangles(self) -> int:
        """Contour points ``N`` of the model member (setting it keeps the member's rings and
        element and validates the new member)."""
        return self.model.n_triangles

    @n_triangles.setter
    def n_triangles(self, value) -> None:
        self.model = resolve_model(value, self.model.n_rings, self.model.element)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        opts = check_reset_arguments(seed, options)  # before anything changes
        super().reset(seed=None if seed is None else int(seed))
        self._disk, self._needs, self._obs = _draw_object(
            self.np_random, self.distribution, opts, self.observe_shapes)
        self._last_design = None
        self._terminated = 0
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), _object_info(self._disk, self._needs)

    def step(self, action):
        if self._disk is None:
            raise ResetNeeded("call reset() before step()")
        if self._terminated == 1:  # said once an episode, as Gymnasium's own envs do
            warnings.warn("GripperDesignEnv.step() after the episode ended (terminated=True): "
                          "it evaluates another design on the same object; call reset() for "
                          "the next episode", PsmGraspWarning, stacklevel=2)
        act, clipped = _check_actions(action, (self.bounds.n_var,))
        design = self.bounds.scale(act, self._disk)
        out = evaluate_objects(design[None, :], [self._disk], self._needs[None, :],
                               weights=self.weights, **self.joint_spring,
                               load_set=self.load_set, **self.model.kwargs())
        info = {key: _info_value(v[0]) for key, v in out.items()}
        info["clipped"] = bool(clipped)
        info["design"] = design
        info.update(_object_info(self._disk, self._needs))
        self._last_design = design
        self._terminated += 1
        if self.render_mode == "human":
            self.render()
        return self._obs.copy(), float(out["reward"][0]), True, False, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; set it at construction")
            return None
        if self._disk is None:
            raise ResetNeeded("call reset() before render()")
        frame = _render_frame(self._last_design, self._disk, float(self._needs[0]),
                              self.model, self.joint_spring,
                              self._render_cache)
        if self.render_mode == "rgb_array":
            return frame
        self._show(frame)
        return None

    def _show(self, frame: np.ndarray) -> None:
        import matplotlib.pyplot as plt

        if self._figure is None or not plt.fignum_exists(self._figure.number):
            self._figure = plt.figure("GripperDesign-v2")
            self._image = self._figure.add_subplot().imshow(frame)
            self._figure.axes[0].set_axis_off()
        else:
            self._image.set_data(frame)
        plt.pause(1.0 / self.metadata["render_fps"])

    def close(self) -> None:
        if self._figure is not None:
            import matplotlib.pyplot as plt

            plt.close(self._figure)
            self._figure = None

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_figure"] = None  # GUI objects do not pickle; a new window opens on render
        state.pop("_image", None)
        state["_render_cache"] = {}
        return state


class GripperDesignVectorEnv(VectorEnv):
    """``num_envs`` copies of :class:`GripperDesignEnv` stepped with ONE batched evaluation.

    All designs of a step go through a single :func:`~envs.evaluate.evaluate_designs` call (the
    compiled solver runs the rows in parallel threads), so this is much cheaper than
    ``SyncVectorEnv`` or ``AsyncVectorEnv`` over single envs, and gives the same results: sub-env
    ``i`` reset with ``seed + i`` draws the same objects as a single env reset with that seed.

    Autoreset (``autoreset_mode``, see https://farama.org/Vector-Autoreset-Mode):

    - ``SAME_STEP`` (default: no wasted steps): every step evaluates the designs and returns
      the observation of the next object; the evaluated object's observation and info are in
      ``info["final_obs"]`` and ``info["final_info"]``.
    - ``NEXT_STEP`` (Gymnasium's own vector envs' default): every episode is one step, so
      steps alternate: a step evaluating the designs (reward, ``terminated=True``) is followed
      by a step that resets the sub-envs and ignores their actions (reward 0,
      ``terminated=False``).
    - ``DISABLED``: the caller resets with ``reset(options={"reset_mask": mask})``.

    ``truncated`` mirrors a ``TimeLimit`` wrapper: True on the evaluation step when
    ``max_episode_steps`` is 1 (the registration sets none: the episode terminates by itself).

    Parameters
    ----------
    num_envs
        Number of sub-environments.
    render_mode
        ``None`` or ``"rgb_array"`` (``render()`` returns one frame per sub-env).
    bounds, distribution, weights, n_triangles, torsion_stiffness_rel,
    torsion_stiffness_nm_per_rad, n_rings, element, calibrated
        As for :class:`GripperDesignEnv`.
    max_episode_steps
        ``None`` (the registered value) or an integer >= 1; see ``truncated`` above.
    autoreset_mode
        An :class:`gymnasium.vector.AutoresetMode` (or its value).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": RENDER_FPS,
                "autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(
        self,
        num_envs: int = 1,
        *,
        render_mode: str | None = None,
        bounds: DesignBounds | None = None,
        distribution: ObjectDistribution | None = None,
        weights: RewardWeights | None = None,
        n_triangles: int | None = None,
        torsion_stiffness_rel: float | None = None,
        torsion_stiffness_nm_per_rad: float | None = None,
        n_rings: int | None = None,
        element: str | None = None,
        calibrated: bool | None = None,
        max_episode_steps: int | None = None,
        autoreset_mode: AutoresetMode | str = AutoresetMode.SAME_STEP,
        observe_shapes: bool = False,
        load_set: str = DEFAULT_LOAD_SET,
    ) -> None:
        load_set_code(load_set)
        num_envs = check_integer("num_envs", num_envs, 1, MAX_NUM_ENVS)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r} is not one of "
                             f"{self.metadata['render_modes']}")
        if max_episode_steps is not None:
            max_episode_steps = check_integer("max_episode_steps", max_episode_steps, 1,
                                              2**62)
        self.num_envs = int(num_envs)
        self.render_mode = render_mode
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        distribution, self.observe_shapes = _shape_settings(distribution, observe_shapes)
        self.bounds, self.distribution, self.weights, self.model = _check_settings(
            bounds, distribution, weights, n_triangles, n_rings, element, calibrated)
        self.joint_spring = joint_spring_kwargs(torsion_stiffness_rel, torsion_stiffness_nm_per_rad)
        self.load_set = load_set
        self.max_episode_steps = max_episode_steps
        self.single_action_space, self.single_observation_space = _spaces(
            self.bounds, self.observe_shapes)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        n = self.num_envs
        self._rngs: list[np.random.Generator | None] = [None] * n
        self._disks: list[SoftDisk | None] = [None] * n
        self._needs = np.zeros((n, len(NEED_KEYS)))  # NEED_KEYS order
        self._objects = np.zeros((n, len(OBJECT_INFO_KEYS)))
        self._obs = np.zeros((n, _n_obs(self.observe_shapes)), dtype=np.float32)
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._last_designs: list[np.ndarray | None] = [None] * n
        self._render_caches: list[dict] = [{} for _ in range(n)]

    @property
    def n_triangles(self) -> int:
        """Contour points ``N`` of the model member (setting it keeps the member's rings and
        element and validates the new member)."""
        return self.model.n_triangles

    @n_triangles.setter
    def n_triangles(self, value) -> None:
        self.model = resolve_model(value, self.model.n_rings, self.model.element)

    # --- helpers -------------------------------------------------------------------------------

    def _reset_rows(self, rows: np.ndarray, seeds: list[int | None], options: dict) -> None:
        idx = rows.tolist()
        disks, needs = [], np.empty((len(idx), len(NEED_KEYS)))
        for k, i in enumerate(idx):
            if seeds[i] is not None or self._rngs[i] is None:
                self._rngs[i], _ = seeding.np_random(seeds[i])
            # every sub-env draws from its own stream, as GripperDesignEnv.reset does
            disk, needs[k] = _draw(self._rngs[i], self.distribution, options)
            disks.append(disk)
        # the object infos' table (columns in OBJECT_INFO_KEYS order) and the observations,
        # which validate a fixed object from the options before any sub-env changes
        table = _object_table(disks)
        obs = _observe_table(table, needs)
        if self.observe_shapes:
            obs = np.hstack([obs, shape_observation(disks)])
        for k, i in enumerate(idx):
            self._disks[i] = disks[k]
            self._last_designs[i] = None
        self._needs[rows] = needs
        self._objects[rows, : len(DISK_INFO_KEYS)] = table
        self._objects[rows, len(DISK_INFO_KEYS):] = needs
        self._obs[rows] = obs
        self._autoreset[rows] = False

    def _object_infos(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        info: dict[str, np.ndarray] = {}
        for col, key in enumerate(OBJECT_INFO_KEYS):
            arr = np.zeros(self.num_envs)
            arr[rows] = self._objects[rows, col]
            info[key] = arr
            info[f"_{key}"] = self._mask(rows)
        return info

    def _mask(self, rows: np.ndarray) -> np.ndarray:
        mask = np.zeros(self.num_envs, dtype=np.bool_)
        mask[rows] = True
        return mask

    def _evaluate(self, rows: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, dict]:
        act, clipped = _check_actions(actions[rows], (rows.size, self.bounds.n_var))
        designs = self.bounds.scale(act, [self._disks[i] for i in rows.tolist()])
        out = evaluate_objects(designs, [self._disks[i] for i in rows.tolist()],
                               self._needs[rows], weights=self.weights, **self.joint_spring,
                               load_set=self.load_set, **self.model.kwargs())
        info: dict[str, np.ndarray] = {}
        mask = self._mask(rows)
        for key, (dtype, shape) in {**METRIC_KEYS, **ROBUST_KEYS}.items():
            arr = np.zeros((self.num_envs, *shape), dtype=dtype)
            arr[rows] = out[key]
            info[key], info[f"_{key}"] = arr, mask.copy()
        for key, values, dtype in (("clipped", clipped, np.bool_), ("design", designs, float)):
            arr = np.zeros((self.num_envs, *values.shape[1:]), dtype=dtype)
            arr[rows] = values
            info[key], info[f"_{key}"] = arr, mask.copy()
        for k, i in enumerate(rows.tolist()):
            self._last_designs[i] = designs[k]
        return out["reward"], info

    # --- API -----------------------------------------------------------------------------------

    def reset(self, *, seed: int | list[int | None] | None = None,
              options: dict[str, Any] | None = None):
        n = self.num_envs
        if seed is None:
            seeds: list[int | None] = [None] * n
        elif isinstance(seed, int | np.integer):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"seed list must have length num_envs={n}, got {len(seeds)}")
        options = _options_dict(options)
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(n, dtype=np.bool_)
        mask = np.asarray(mask)
        if mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
            raise ValueError(f"options['reset_mask'] must be a bool array of shape ({n},) with "
                             "at least one True value")
        rows = np.flatnonzero(mask)
        self._reset_rows(rows, seeds, _parse_options(options))
        return self._obs.copy(), self._object_infos(rows)

    def step(self, actions):
        n = self.num_envs
        if any(d is None for d in self._disks):
            raise ResetNeeded("call reset() before step()")
        actions = np.asarray(actions)
        if actions.shape != (n, self.bounds.n_var):
            raise ValueError(f"actions must have shape ({n}, {self.bounds.n_var}), got "
                             f"{actions.shape}")
        rewards = np.zeros(n)
        terminated = np.zeros(n, dtype=np.bool_)
        truncated = np.zeros(n, dtype=np.bool_)
        if self.autoreset_mode == AutoresetMode.NEXT_STEP:
            resets = self._autoreset.copy()
        else:
            if self.autoreset_mode == AutoresetMode.DISABLED and self._autoreset.any():
                raise RuntimeError("sub-envs "
                                   f"{np.flatnonzero(self._autoreset).tolist()} ended: reset "
                                   "them with reset(options={'reset_mask': mask})")
            resets = np.zeros(n, dtype=np.bool_)
        rows = np.flatnonzero(~resets)
        info: dict[str, Any] = {}
        if rows.size:
            rewards[rows], info = self._evaluate(rows, actions)
            terminated[rows] = True
            truncated[rows] = self.max_episode_steps is not None and self.max_episode_steps <= 1
            info.update(self._object_infos(rows))
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and resets.any():
            self._reset_rows(np.flatnonzero(resets), [None] * n, {})
            # object keys cover both the evaluated rows and the freshly reset ones
            info.update(self._object_infos(np.arange(n)))
        elif self.autoreset_mode == AutoresetMode.SAME_STEP and rows.size:
            final_obs = np.full(n, None, dtype=object)
            for i in rows.tolist():
                final_obs[i] = self._obs[i].copy()
            info = {"final_obs": final_obs, "_final_obs": self._mask(rows),
                    "final_info": info, "_final_info": self._mask(rows)}
            self._reset_rows(rows, [None] * n, {})
            info.update(self._object_infos(rows))
        self._autoreset = terminated | truncated
        return self._obs.copy(), rewards, terminated, truncated, info

    def render(self):
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; set it at construction")
            return None
        if any(d is None for d in self._disks):
            raise ResetNeeded("call reset() before render()")
        return tuple(
            _render_frame(self._last_designs[i], self._disks[i], float(self._needs[i, 0]),
                          self.model, self.joint_spring,
                          self._render_caches[i])
            for i in range(self.num_envs)
        )


def jaw_bounds(jaw: str = "any", jaw_per_finger: bool = False,
               bounds: DesignBounds | None = None) -> DesignBounds:
    """The design space of ``GripperJawDesign-v0``: ``bounds`` (default the default box) with
    the jaws ``jaw`` (one of :data:`envs.design_space.JAW_KINDS`, default ``"any"``) and
    ``jaw_per_finger`` (:meth:`~envs.evaluate.DesignBounds.with_jaw`)."""
    if bounds is not None and not isinstance(bounds, DesignBounds):
        raise ValueError(f"bounds must be None or a DesignBounds, got {type(bounds).__name__}")
    base = DesignBounds() if bounds is None else bounds
    return base.with_jaw(jaw, jaw_per_finger)


def make_vector_env_v4(num_envs: int = 1, **kwargs: Any) -> GripperDesignVectorEnv:
    """The vector entry point of ``GripperShapeDesign-v0``: a :class:`GripperDesignVectorEnv`
    that draws ellipses at any orientation (:data:`SHAPE_DISTRIBUTION` unless a
    ``distribution`` is given) and observes their shape (``observe_shapes=True``)."""
    return GripperDesignVectorEnv(num_envs, observe_shapes=True, **kwargs)


def make_vector_env_v3(num_envs: int = 1, *, jaw: str = "any", jaw_per_finger: bool = False,
                       bounds: DesignBounds | None = None, **kwargs: Any
                       ) -> GripperDesignVectorEnv:
    """The vector entry point of ``GripperJawDesign-v0``: a :class:`GripperDesignVectorEnv`
    whose actions carry the jaw columns (:func:`jaw_bounds`); ``kwargs`` as for the class."""
    return GripperDesignVectorEnv(num_envs, bounds=jaw_bounds(jaw, jaw_per_finger, bounds),
                                  **kwargs)
