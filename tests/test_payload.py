"""The payload: friction carries the reaction plus W = f m g over the load set (out of the plane
and every in-plane direction), against closed forms and independent linear programs with
polyhedral cones (scipy HiGHS); the object's density and the unit-slip checks."""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from envs import DesignBounds, Scene, evaluate_designs, simulate
from envs.model.defaults import GRAVITY_M_S2
from envs.model.holding import (
    H_GRIP,
    H_LIMIT,
    H_LIMIT_ANGLE,
    H_MU,
    H_PAYLOAD,
    LIMIT_IN_PLANE,
    LIMIT_OUT_OF_PLANE,
    LIMIT_REACTION,
    SPAN_TOL,
    _merge,
    lift_friction,
)
from envs.model.loads import holding_row
from envs.object_file import parse_object
from envs.scene import SoftDisk
from envs.validation import UnitSlipWarning

from .test_holding import _lp_friction, _pressure_shift

R070 = Scene.preset("paper-r070")
CENTRE = np.array([0.0, 0.1])
LENGTH = 0.05


def _tangents(normals, points, centre):
    tau = np.column_stack([-normals[:, 1], normals[:, 0]])
    arm = (points[:, 0] - centre[0]) * tau[:, 1] - (points[:, 1] - centre[1]) * tau[:, 0]
    return tau, arm


def _lp_load(normals, points, forces, pin, moment, load, out_of_plane, facets, inscribed):
    """min mu of one load as an LP: in-plane t_i and out-of-plane s_i in a polygon of
    ``facets`` sides per contact (circumscribing the circle of radius mu N_i, or inscribed in
    it), the reaction plus ``load`` (in-plane force (2,), or the out-of-plane force), the
    moment anywhere within the faces' pressure shift."""
    k = forces.size
    tau, arm = _tangents(normals, points, CENTRE)
    low, high = _pressure_shift(normals, points, forces, CENTRE, LENGTH)
    n = 2 * k + 2  # t, s, mu, the shifted moment
    a_eq = np.zeros((4, n))
    a_eq[0, :k], a_eq[1, :k], a_eq[2, :k] = tau[:, 0], tau[:, 1], arm / LENGTH
    a_eq[2, n - 1] = 1.0 / LENGTH
    a_eq[3, k : 2 * k] = 1.0
    b_eq = np.array([pin[0], pin[1], moment / LENGTH, 0.0])
    if out_of_plane:
        b_eq[3] = load
    else:
        b_eq[:2] += load
    shrink = math.cos(math.pi / facets) if inscribed else 1.0
    blocks = []
    for j in range(facets):
        a = 2 * math.pi * j / facets
        block = np.zeros((k, n))
        block[:, :k] = np.eye(k) * math.cos(a)
        block[:, k : 2 * k] = np.eye(k) * math.sin(a)
        block[:, 2 * k] = -forces * shrink
        blocks.append(block)
    a_ub = np.vstack(blocks)
    s_bounds = [(None, None)] * k if out_of_plane else [(0.0, 0.0)] * k
    cost = np.zeros(n)
    cost[2 * k] = 1.0
    res = linprog(cost, A_ub=a_ub, b_ub=np.zeros(a_ub.shape[0]), A_eq=a_eq, b_eq=b_eq,
                  bounds=[(None, None)] * k + s_bounds + [(0, None), (low, high)],
                  method="highs")
    return float(res.x[2 * k]) if res.status == 0 else math.inf


def _random_grasp(rng):
    """Contacts around a disk (some faces pressed at two points), and the reaction that
    balances their normal forces."""
    k = int(rng.integers(2, 6))
    angle = rng.uniform(0.0, 2 * math.pi, k)
    normals = -np.column_stack([np.cos(angle), np.sin(angle)]) + rng.normal(0, 0.2, (k, 2))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    points = CENTRE + LENGTH * np.column_stack([np.cos(angle), np.sin(angle)])
    forces = rng.uniform(0.1, 2.0, k)
    if rng.random() < 0.6:  # a face pressed at two points: its pressure may shift
        normals[1] = normals[0]
        points[1] = points[0] + 0.01 * np.array([-normals[0, 1], normals[0, 0]])
    pin = -(forces[:, None] * normals).sum(axis=0)
    moment = -float(np.sum(forces * ((points[:, 0] - CENTRE[0]) * normals[:, 1]
                                     - (points[:, 1] - CENTRE[1]) * normals[:, 0])))
    return normals, points, forces, pin, moment


def _lift(normals, points, forces, pin, moment, weight):
    """:func:`lift_friction` (the out-of-plane load alone) of a contact list."""
    tau, arm = _tangents(normals, points, CENTRE)
    gens = np.column_stack([forces[:, None] * tau, forces * arm / LENGTH])
    low, high = _pressure_shift(normals, points, forces, CENTRE, LENGTH)
    m = _merge(gens, forces.size)
    return lift_friction(gens, m, pin[0], pin[1], (moment - 0.5 * (low + high)) / LENGTH,
                         0.5 * (high - low) / LENGTH, weight, SPAN_TOL * forces.sum())


def _symmetric(theta, forces=(1.0, 2.0, 1.5, 1.5), spread=0.01):
    """Two faces at finger angle theta, each pressed at two points ``spread`` apart (3 N on
    each face by default)."""
    n_r, n_l = np.array([-math.cos(theta), math.sin(theta)]), np.array([math.cos(theta),
                                                                        math.sin(theta)])
    axis_r, axis_l = np.array([math.sin(theta), math.cos(theta)]), np.array([-math.sin(theta),
                                                                             math.cos(theta)])
    foot_r, foot_l = CENTRE - LENGTH * n_r, CENTRE - LENGTH * n_l
    normals = np.array([n_r, n_r, n_l, n_l])
    points = np.array([foot_r, foot_r + spread * axis_r, foot_l, foot_l - spread * axis_l])
    forces = np.array(forces, dtype=float)
    return normals, points, forces, -(forces[:, None] * normals).sum(axis=0)


def test_hanging_from_a_symmetric_grasp_needs_the_root_of_the_sum_of_squares():
    """Out of the plane, every contact saturates in the plane (tan theta) and the weight
    shares the rest of each cone: mu = sqrt(tan^2 theta + (W / sum N)^2)."""
    for theta in (0.2, 0.5, 0.8):
        normals, points, forces, pin = _symmetric(theta)
        for weight in (0.1, 1.0, 4.0):
            expect = math.hypot(math.tan(theta), weight / forces.sum())
            got = _lift(normals, points, forces, pin, 0.0, weight)
            assert got == pytest.approx(expect, rel=1e-9)


def test_no_payload_reproduces_the_reaction_alone():
    rng = np.random.default_rng(4)
    for _ in range(40):
        normals, points, forces, pin, moment = _random_grasp(rng)
        row = holding_row(normals, points, forces, CENTRE, LENGTH, pin, moment, 0.0)
        ref = _lp_friction(normals, points, forces, CENTRE, LENGTH, pin, moment)
        assert row[H_PAYLOAD] == 0.0 and row[H_GRIP] == pytest.approx(forces.sum())
        if ref < 1e6:
            assert row[H_MU] == pytest.approx(ref, rel=1e-6, abs=1e-9)
            assert row[H_LIMIT] == LIMIT_REACTION and math.isnan(row[H_LIMIT_ANGLE])
        else:
            assert row[H_MU] > 1e6


def test_the_out_of_plane_need_lies_between_inscribed_and_circumscribed_polygons():
    """The exact circular cones against LPs with 64-sided polygons around and inside them
    (the two bracket the circle within 0.12 %), on random grasps."""
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(40):
        normals, points, forces, pin, moment = _random_grasp(rng)
        weight = float(rng.choice([0.05, 0.5, 2.0, 6.0]))
        got = _lift(normals, points, forces, pin, moment, weight)
        low = _lp_load(normals, points, forces, pin, moment, weight, True, 64, False)
        high = _lp_load(normals, points, forces, pin, moment, weight, True, 64, True)
        if math.isinf(low):
            assert math.isinf(got)
            continue
        assert low * (1 - 1e-7) <= got <= high * (1 + 1e-7)
        # the bounds the exact answer must respect
        assert got >= weight / forces.sum() * (1 - 1e-12)
        checked += 1
    assert checked >= 20


def test_a_sixteen_sided_cone_is_within_two_percent():
    """What a 16-facet polyhedral cone would give (the LP, inscribed and circumscribed):
    within 2 % of the exact cones."""
    normals, points, forces, pin = _symmetric(0.5)
    exact = _lift(normals, points, forces, pin, 0.0, 2.0)
    for inscribed in (False, True):
        poly = _lp_load(normals, points, forces, pin, 0.0, 2.0, True, 16, inscribed)
        assert abs(poly / exact - 1.0) < 0.02


def test_the_in_plane_closed_form_is_the_worst_direction_of_a_sweep():
    """Over every in-plane direction, the closed form (facets of the contacts' zonotope and
    the shift's axis) against the largest LP optimum of 180 directions: never below it, above
    by no more than the sweep's resolution; and the reported direction is the LP's worst."""
    rng = np.random.default_rng(6)
    checked = 0
    for _ in range(25):
        normals, points, forces, pin, moment = _random_grasp(rng)
        weight = float(rng.choice([0.1, 1.0, 3.0]))
        row = holding_row(normals, points, forces, CENTRE, LENGTH, pin, moment, weight)
        phis = np.linspace(0.0, 2 * math.pi, 180, endpoint=False)
        # the load friction carries is the reaction plus -pull: a pull at phi
        sweep = np.array([_lp_load(normals, points, forces, pin, moment,
                                   -weight * np.array([math.cos(p), math.sin(p)]), False, 4,
                                   False) for p in phis])
        worst = float(np.max(sweep))
        if math.isinf(worst):
            assert math.isinf(row[H_MU]) or row[H_LIMIT] == LIMIT_OUT_OF_PLANE
            continue
        if row[H_LIMIT] != LIMIT_IN_PLANE:
            continue
        assert worst * (1 - 1e-7) <= row[H_MU] <= worst * (1 + 2e-3)
        at = phis[int(np.argmax(sweep))]
        gap = abs((row[H_LIMIT_ANGLE] - at + math.pi) % (2 * math.pi) - math.pi)
        assert gap <= 2 * math.pi / 180 + 1e-9 or sweep[int(np.argmax(sweep))] <= (
            _lp_load(normals, points, forces, pin, moment,
                     -weight * np.array([math.cos(row[H_LIMIT_ANGLE]),
                                         math.sin(row[H_LIMIT_ANGLE])]), False, 4, False)
            * (1 + 1e-6))
        checked += 1
    assert checked >= 10


def test_a_symmetric_grasp_is_limited_by_a_pull_out_of_the_jaws():
    """Two faces at theta (a hair of pressure shift each): pulled along +y, out of the jaws,
    the friction along the finger axes carries the reaction and W: (2 N sin theta + W) /
    (2 N cos theta) at least; the worst direction needs at least that and more than hanging."""
    theta = 0.4
    normals, points, forces, pin = _symmetric(theta, (1.0, 1.0, 1.0, 1.0), spread=0.04)
    weight = 0.5
    row = holding_row(normals, points, forces, CENTRE, LENGTH, pin, 0.0, weight)
    along_axis = (forces.sum() * math.sin(theta) + weight) / (forces.sum() * math.cos(theta))
    assert row[H_LIMIT] == LIMIT_IN_PLANE
    assert row[H_MU] >= along_axis * (1 - 1e-12)
    assert row[H_MU] > math.hypot(math.tan(theta), weight / forces.sum())


def test_the_payload_of_an_object_and_what_holds_it():
    disk = R070.disk
    assert disk.density_kg_m3 == 50.0  # the paper's foam
    mass = 50.0 * math.pi * disk.radius_m**2 * disk.thickness_m
    assert disk.payload_n(2.0) == pytest.approx(2 * mass * GRAVITY_M_S2, rel=1e-12)
    designs = DesignBounds().sample(np.random.default_rng(8), 200, disk)
    heavy = SoftDisk(disk.radius_m, disk.distance_m, density_kg_m3=1000.0)
    out = {f: evaluate_designs(designs, heavy, payload_factors=f, friction_coefficients=1.0)
           for f in (0.0, 1.0, 2.0)}
    assert np.all(out[2.0]["payload_n"] == pytest.approx(heavy.payload_n(2.0)))
    grasp = out[0.0]["converged"] & out[0.0]["touching"].all(axis=1)
    # more payload never needs less friction (the reaction alone is in every load set);
    # holding implies that friction can lift it. Along a ray of loads the need is the largest
    # of ratios of affine functions of the load (the loaded normal forces are linear in it), so
    # a larger circle of pulls reaches at least the smaller one's worst, up to the Hertz
    # patches' pressure shift, which grows as F^1.5 (measured: at most 7e-4 of the need)
    assert np.all(out[1.0]["required_friction"][grasp]
                  >= out[0.0]["required_friction"][grasp] * (1 - 1e-9))
    assert np.all(out[2.0]["required_friction"][grasp]
                  >= out[1.0]["required_friction"][grasp] * (1 - 2e-3))
    holds = out[2.0]["holds"]
    assert holds.sum() < out[0.0]["holds"].sum()
    assert np.all(out[2.0]["friction_coefficient"][holds] * out[2.0]["grip_force_n"][holds]
                  >= out[2.0]["payload_n"][holds])
    np.testing.assert_allclose(out[2.0]["grip_force_n"][grasp],
                               out[2.0]["total_force_n"][grasp].sum(axis=1), rtol=1e-9)
    # a slip scores below every hold: the tiers keep their order
    r = out[2.0]["reward"]
    slips = grasp & ~holds
    assert holds.any() and slips.any() and r[holds].min() > r[slips].max()


def test_simulate_reports_the_payload_and_the_grip():
    heavy = R070.with_changes(density_kg_m3=1000.0) if hasattr(R070, "with_changes") else None
    scene = heavy if heavy is not None else R070
    res = simulate(scene, 0.2)
    assert res.payload_n == pytest.approx(scene.disk.payload_n(2.0))
    assert res.grip_force_n == pytest.approx(sum(res.total_force_n), rel=1e-9)
    assert res.friction_limit == LIMIT_IN_PLANE
    assert res.required_friction > math.tan(res.jaw_angles_rad[0])
    assert res.to_dict()["friction_limit"] == "in plane"


@pytest.mark.parametrize(("key", "value", "unit"), [
    ("radius_m", 15, "millimetres"), ("thickness_m", 5, "millimetres"),
    ("youngs_modulus_pa", 0.005, "MPa"), ("density_kg_m3", 1.06, "g/cm^3")])
def test_a_value_in_another_unit_is_refused_naming_the_unit_by_a_file_and_the_api(key, value, unit):
    table = {"radius_m": 0.01, "youngs_modulus_pa": 5e3, "poisson_ratio": 0.45,
             "thickness_m": 0.005, key: value}
    with pytest.raises(ValueError, match=f"{key}.*{re.escape(unit)}"):
        parse_object({"object": table}, "liver.toml")
    with pytest.raises(ValueError, match=f"^{key} = {value} is outside the plausible range.*"
                                         f"{re.escape(unit)}"):
        SoftDisk(**{"radius_m": 0.01, "distance_m": 0.0, "youngs_modulus_pa": 5e3,
                    "thickness_m": 0.005, key: value})


def test_plausible_objects_pass_silently_and_carry_their_density():
    spec = parse_object({"object": {"radius_m": 0.01, "youngs_modulus_pa": 5e3,
                                    "poisson_ratio": 0.45, "thickness_m": 0.005,
                                    "density_kg_m3": 1060, "payload_factor": 0}}, "x.toml")
    assert spec.disk.density_kg_m3 == 1060 and spec.payload_factor == 0
    plain = parse_object({"object": {"radius_m": 0.01, "youngs_modulus_pa": 5e3,
                                     "poisson_ratio": 0.45, "thickness_m": 0.005}}, "y.toml")
    assert plain.disk.density_kg_m3 == 1000.0  # water-like unless the file says otherwise
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnitSlipWarning)
        for name in ("paper-r050", "paper-r100", "forceps-a"):
            Scene.preset(name)


def test_a_cradle_carries_the_water_like_disk_by_its_normal_forces():
    """The paper's r = 0.07 m disk as dense as water (examples/objects/water_disk.toml: 3.02 N
    with the lift, friction 0.5, strain limit 0.10): the optimum of ``psm-grasp optimize
    --jaw any --budget 800`` (a cradle of 68.8 mm, 20.1 mm deep) holds and lifts it within the
    strain limit, its grip times the friction above the payload. Its run's normals wrap the
    disk and carry the in-plane loads: it needs a quarter of the friction the same gripper
    needs with straight jaws, and what it needs is set out of the plane, where only friction
    carries the weight (``W / sum N`` with the reaction's small need beside it)."""
    from envs.model.holding import LIMIT_OUT_OF_PLANE
    from envs.object_file import load_object

    obj = load_object(Path(__file__).resolve().parents[1] / "examples/objects/water_disk.toml")
    cradle = np.array([0.29015, 1.02507, 0.041456, 0.026958, 1.20842, 0.028904,
                       0.020079, 0.068823, 1.20201, 0.088859])
    rows = np.stack([cradle, np.r_[cradle[:6], 0.0, 0.0, 0.0, 0.0]])
    out = evaluate_designs(rows, obj.disk, strain_limits=obj.strain_limit,
                           friction_coefficients=obj.friction_coefficient,
                           torsion_stiffness_nm_per_rad=0.073)
    assert out["payload_n"][0] == pytest.approx(3.02, rel=1e-3)
    assert out["holds"][0] and out["required_friction"][0] < obj.friction_coefficient
    assert out["peak_compression"][0] < obj.strain_limit
    assert obj.friction_coefficient * out["grip_force_n"][0] > out["payload_n"][0]
    assert out["contact_score"][0] > 0.3
    assert out["required_friction"][0] < 0.3 * out["required_friction"][1]
    assert out["friction_limit"][0] == LIMIT_OUT_OF_PLANE
    share = out["payload_n"][0] / out["grip_force_n"][0]
    assert share <= out["required_friction"][0] <= 1.25 * share
