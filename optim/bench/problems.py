"""The suite's named problem instances: an object (its ranges and placement tolerance) and the
jaws designed, each built as the :class:`~optim.problem.DesignProblem` every method solves.

An instance is named ``OBJECT-JAW``: ``strawberry-any`` is the strawberry with any shaped jaws
(a rounded V, from a straight bar to a cradle, alike on both fingers), ``strawberry-straight``
the same object with straight bars. The objects are written here, not read from
``examples/objects``: a benchmark instance must not move when an example is edited. Five are the
examples' (the silicone puck, the cherry tomato, the foam disk, the strawberry, the tomatoes of
10-15 mm); two are drawn with ranges and a tolerance for the suite (blueberries; tomatoes of
10-15 mm on pads of friction 0.5).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from envs.object_file import ObjectSpec, parse_object

from ..problem import DesignProblem

__all__ = ["OBJECTS", "JAWS", "INSTANCES", "DEFAULT_INSTANCES", "Instance", "make_problem",
           "check_instance"]

JAWS = ("any", "straight")

# the [object] tables of the suite's objects (the keys of an object file, envs.object_file)
OBJECTS: dict[str, dict[str, Any]] = {
    # examples/objects/silicone_puck.toml: a moulded rubber part, 10 mm across
    "puck": {"name": "silicone puck", "radius_m": 0.005, "youngs_modulus_pa": 1.2e6,
             "poisson_ratio": 0.49, "thickness_m": 0.004, "strain_limit": 0.15,
             "friction_coefficient": 0.9},
    # examples/objects/cherry_tomato.toml
    "cherry-tomato": {"name": "cherry tomato", "radius_m": 0.012, "youngs_modulus_pa": 150e3,
                      "poisson_ratio": 0.45, "density_kg_m3": 1000, "thickness_m": 0.024,
                      "strain_limit": 0.10, "friction_coefficient": 0.5},
    # examples/objects/foam_disk.toml (its [gripper] left out)
    "foam": {"name": "foam disk", "radius_m": 0.06, "youngs_modulus_pa": 30e3,
             "poisson_ratio": 0.3, "density_kg_m3": 50, "thickness_m": 0.01,
             "strain_limit": 0.15, "friction_coefficient": 0.6},
    # examples/objects/strawberry.toml: placed within +-1.5 mm both ways (9 scenarios)
    "strawberry": {"name": "strawberry", "radius_m": 0.015, "youngs_modulus_pa": 2e5,
                   "poisson_ratio": 0.45, "thickness_m": 0.03, "density_kg_m3": 1000,
                   "strain_limit": 0.06, "friction_coefficient": 0.6,
                   "placement_tolerance_m": 0.0015},
    # examples/objects/tomatoes_10_15mm.toml: radius and modulus ranges (9 scenarios)
    "tomatoes": {"name": "tomatoes 10-15 mm", "radius_m": [0.010, 0.015],
                 "youngs_modulus_pa": [1e5, 3e5], "poisson_ratio": 0.45, "thickness_m": 0.02,
                 "density_kg_m3": 1000, "strain_limit": 0.10, "friction_coefficient": 0.8},
    # drawn for the suite: the tomatoes on pads of friction 0.5, 24 mm thick
    "tomatoes-mu05": {"name": "tomatoes 10-15 mm, friction 0.5", "radius_m": [0.010, 0.015],
                      "youngs_modulus_pa": [1e5, 3e5], "poisson_ratio": 0.45,
                      "thickness_m": 0.024, "density_kg_m3": 1000, "strain_limit": 0.10,
                      "friction_coefficient": 0.5},
    # drawn for the suite: blueberries of radius 6-9 mm and 0.2-0.6 MPa placed within
    # +-1 mm (25 scenarios); a slice as thick as the middle berry is wide, as dense as water, a
    # tenth of the radius the squeeze they bear, on grippy pads
    "blueberries": {"name": "blueberries 6-9 mm", "radius_m": [0.006, 0.009],
                    "youngs_modulus_pa": [2e5, 6e5], "poisson_ratio": 0.45,
                    "thickness_m": 0.015, "density_kg_m3": 1000, "strain_limit": 0.10,
                    "friction_coefficient": 0.6, "placement_tolerance_m": 0.001},
}


@dataclass(frozen=True)
class Instance:
    """One named problem of the suite.

    Parameters
    ----------
    name
        ``OBJECT-JAW``.
    object_key
        The object's key in :data:`OBJECTS`.
    jaw
        The jaws designed: ``"any"`` or ``"straight"``.
    """

    name: str
    object_key: str
    jaw: str

    def spec(self) -> ObjectSpec:
        """The object, as an object file gives it."""
        return parse_object({"object": OBJECTS[self.object_key]}, f"instance {self.name}")

    @property
    def n_var(self) -> int:
        """Columns of a design of this instance (6, plus the jaw's)."""
        from envs.design_space import DesignBounds

        return DesignBounds(jaw=self.jaw).n_var

    def n_scenarios(self) -> int:
        """The scenarios each design is judged under (1: the one exact object)."""
        sc = self.spec().scenarios
        return 1 if sc is None or sc.is_trivial else len(sc.scenarios())


INSTANCES: dict[str, Instance] = {
    f"{key}-{jaw}": Instance(f"{key}-{jaw}", key, jaw) for key in OBJECTS for jaw in JAWS}
# what scripts/compare_optimizers.py and scripts/bench_targets.py run unless told
DEFAULT_INSTANCES: tuple[str, ...] = tuple(INSTANCES)


def check_instance(name: Any) -> Instance:
    """The instance of a name.

    Raises
    ------
    ValueError
        For an unknown name (the message lists the allowed ones).
    """
    if not isinstance(name, str) or name not in INSTANCES:
        raise ValueError(f"unknown benchmark instance {name!r}; allowed: "
                         f"{', '.join(INSTANCES)}")
    return INSTANCES[name]


def make_problem(name: str, **kwargs: Any) -> DesignProblem:
    """The design problem of an instance, as ``psm-grasp optimize --object FILE --jaw JAW``
    builds it: the object's ranges and tolerance, its strain limit, friction and payload
    (the default payload factor 2), the default model.

    Parameters
    ----------
    name
        An instance of :data:`INSTANCES`.
    **kwargs
        Further :class:`~optim.problem.DesignProblem` arguments (``executor``, ``progress``,
        a model member): not the object's nor the jaws'.

    Raises
    ------
    ValueError
        For an unknown instance, or an argument that would change the instance.
    """
    from ..run import problem_kwargs

    inst = check_instance(name)
    spec = inst.spec()
    disk, settings = problem_kwargs(None, spec, None, None, None, None, jaw=inst.jaw)
    fixed = sorted(set(kwargs) & {*settings, "disk", "name", "bounds", "scenarios"})
    if fixed:
        raise ValueError(f"{', '.join(fixed)}: fixed by instance {name!r} (a benchmark "
                         "instance is the same problem for every run)")
    return DesignProblem(disk, name=name, **settings, **kwargs)
