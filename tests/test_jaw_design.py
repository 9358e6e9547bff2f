"""Shaped jaws in the design space: design rows 6, 10 and 14 wide through the evaluator, the
jaw columns of DesignBounds, the optimizers, the command line, object files and
GripperJawDesign-v0. The plumbing, not the grasp physics of a groove (tests/test_jaw.py)."""

from __future__ import annotations

import itertools
import json
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest

import envs
from envs.batch_inputs import _design_table, _disk_table
from envs.batch_metrics import _columns
from envs.design_space import (
    JAW_BOUNDS,
    JAW_COLUMNS,
    JAW_KINDS,
    DesignBounds,
    fitting_depth,
    jaw_mouth_half_width,
)
from envs.evaluate import evaluate_designs
from envs.model.geometry import corner_radius
from envs.model.jaw import (
    JAW_FIELDS,
    LEFT_JAW_FIELDS,
    MAX_DEPTH_OF_WIDTH,
    STRAIGHT,
    JawProfile,
)
from envs.model.layout import G_DEPTH, G_POSITION, G_RADIUS, N_GROOVE, P_GROOVE0, P_GROOVE1
from envs.model.problem import REST_JAW, REST_OK, pack_params, rest_codes
from envs.object_file import parse_object
from envs.scenarios import Scenarios, evaluate_scenarios, place
from envs.scene import (
    ALL_DESIGN_FIELDS,
    DESIGN_FIELDS,
    Design,
    Scene,
    design_fields,
    design_mapping,
    design_row,
)
from optim.problem import DesignProblem
from optim.result import NoGraspWarning

SCENE = Scene.preset("paper-r070")
DISK = SCENE.disk
PAPER = Design.from_scene(SCENE, 0.1)
R = DISK.radius_m
CRADLE = JawProfile.cradle(1.2 * R, 0.004, 0.1)
VEE = JawProfile.vee(math.radians(90.0), 0.005, 0.12)
KF = {"torsion_stiffness_nm_per_rad": SCENE.gripper.torsion_stiffness_nm_per_rad}
# every design space: each kind, per finger or alike
SPACES = [DesignBounds(jaw=k, jaw_per_finger=p) for k in JAW_KINDS
          for p in ((False, True) if k != "straight" else (False,))]
SPACES.append(DesignBounds(jaw="vee", joints_apart=True))


def _ids(b: DesignBounds) -> str:
    return (b.jaw + ("-per-finger" if b.jaw_per_finger else "")
            + ("-joints-apart" if b.joints_apart else ""))



def _params(rows: np.ndarray) -> np.ndarray:
    """The packed solver parameters of design rows on the paper disk (the batch's one
    mapping of rows to scene columns)."""
    table = _design_table(rows)
    cols = _columns(table, _disk_table(DISK, table.shape[0]), np.full(table.shape[0], 0.073))
    return pack_params(cols, 20)


# --- design rows ----------------------------------------------------------------------------


def test_design_rows_are_6_10_or_14_wide_and_round_trip():
    both = Design(*PAPER.to_array(), jaw=CRADLE)
    each = Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE)
    assert PAPER.to_array().shape == (6,) and both.to_array().shape == (10,)
    assert each.to_array().shape == (14,)
    for d in (PAPER, both, each):
        assert Design.from_array(d.to_array()) == d
        assert design_row(design_mapping(d.to_array())).tolist() == d.to_array().tolist()
    assert list(design_mapping(each.to_array())) == list(ALL_DESIGN_FIELDS)
    assert design_fields(10) == (*DESIGN_FIELDS, *JAW_FIELDS)
    # a straight design as 10 columns: depth 0; the left jaw repeats the jaw at 14
    assert PAPER.to_array(10)[6:].tolist() == [0.0] * 4
    assert both.to_array(14)[10:].tolist() == both.to_array()[6:].tolist()
    with pytest.raises(ValueError, match="needs 14 columns"):
        each.to_array(10)
    with pytest.raises(ValueError, match=r"shape \(n,\) with n in \(6, 10, 14\)"):
        Design.from_array(np.zeros(8))
    with pytest.raises(ValueError, match="jaw must be a JawProfile"):
        Design(*PAPER.to_array(), jaw=0.1)


def test_a_design_given_by_name_needs_whole_grooves():
    fields = design_mapping(Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE).to_array())
    partial = dict(fields)
    del partial["jaw_position_m"]
    with pytest.raises(ValueError, match="needs all of .* missing 'jaw_position_m'"):
        design_row(partial)
    left_only = {k: v for k, v in fields.items() if k not in JAW_FIELDS}
    with pytest.raises(ValueError, match="needs the jaw fields"):
        design_row(left_only)
    with pytest.raises(ValueError, match="missing 'torque_nm'"):
        design_row({k: v for k, v in fields.items() if k != "torque_nm"})


def test_the_scene_of_a_design_carries_its_jaws_as_the_batch_does():
    each = Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE)
    scene = each.to_scene(DISK, **KF)
    assert scene.gripper.jaws == (CRADLE, VEE)
    assert Design.from_scene(scene, each.torque_nm) == each
    # the scene matrix of Design.to_scene and of the batch's columns: one mapping
    table = each.to_array()[None, :]
    cols = _columns(table, _disk_table(DISK, 1), np.array([KF["torsion_stiffness_nm_per_rad"]]))
    np.testing.assert_allclose(cols.rows(), scene.rows(each.torque_nm), rtol=1e-15)


@pytest.mark.parametrize("width", [6, 10, 14])
def test_each_width_packs_its_grooves_into_the_solver_parameters(width):
    row = Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE).to_array(14)[:width]
    prm = _params(row[None, :])[0]
    right = CRADLE if width > 6 else STRAIGHT
    left = VEE if width == 14 else right
    for slot, jaw in ((P_GROOVE0, right), (P_GROOVE1, left)):
        groove = prm[slot : slot + N_GROOVE]
        # lengths in disk radii; the grown groove's radius is the bottom's plus the rounding
        assert groove[G_DEPTH] == pytest.approx(jaw.depth_m / R, rel=1e-14)
        assert groove[G_POSITION] == pytest.approx(jaw.position_m / R, rel=1e-14)
        if jaw.depth_m > 0:
            rho = corner_radius(PAPER.finger_width_m, R)
            assert groove[G_RADIUS] == pytest.approx((jaw.bottom_radius_m + rho) / R)
        else:
            assert not groove.any()


def test_rows_of_each_width_evaluate_and_a_bad_groove_spoils_its_row_only():
    base = PAPER.to_array()
    straight10 = np.concatenate([base, [0.0, 0.0, 0.0, 0.0]])
    cradle = Design(*base, jaw=CRADLE).to_array()
    too_deep = cradle.copy()
    too_deep[6] = 0.9 * base[3]  # deeper than 0.75 finger widths
    off_face = cradle.copy()
    off_face[9] = 0.001  # the mouth beyond the joint end
    rows = np.array([straight10, cradle, too_deep, off_face])
    out = evaluate_designs(rows, DISK, **KF)
    assert out["valid_at_rest"].tolist() == [True, True, False, False]
    assert out["converged"][:2].all()
    assert (out["penalty_invalid"][2:] < 0).all() and (out["rest_violation"][2:] >= 0).all()
    cols = _columns(rows, _disk_table(DISK, 4), np.full(4, 0.073))
    assert rest_codes(cols).tolist() == [REST_OK, REST_OK, REST_JAW, REST_JAW]
    # depth 0 is the straight bar, and a left groove equal to the right one is the same gripper
    six = evaluate_designs(base[None, :], DISK, **KF)
    fourteen = evaluate_designs(np.concatenate([cradle, cradle[6:]])[None, :], DISK, **KF)
    for key in ("reward", "jaw_angles_rad", "total_force_n", "peak_compression"):
        np.testing.assert_array_equal(out[key][0], six[key][0])
        np.testing.assert_array_equal(out[key][1], fourteen[key][0])
    # Design objects of mixed widths: a table as wide as the widest
    assert _design_table([PAPER, Design(*base, jaw=CRADLE)]).shape == (2, 10)
    with pytest.raises(ValueError, match=r"\(B, 10\) or \(B, 14\)"):
        evaluate_designs(np.zeros((1, 7)), DISK)


def test_the_fem_gets_each_row_s_gripper_with_its_jaws(monkeypatch):
    import envs.fem.designs

    seen = []

    def capture(scenes, *args, **kwargs):
        seen.extend(scenes)
        raise RuntimeError("captured")

    monkeypatch.setattr(envs.fem.designs, "fem_design_grasps", capture)
    rows = np.array([Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE).to_array(),
                     Design(*PAPER.to_array(), jaw=VEE).to_array(14)])
    with pytest.raises(RuntimeError, match="captured"):
        evaluate_designs(rows, DISK, fidelity="fem", **KF)
    assert [s.gripper.jaws for s in seen] == [(CRADLE, VEE), (VEE, VEE)]


def test_scenarios_keep_one_physical_groove():
    rows = np.array([Design(*PAPER.to_array(), jaw=CRADLE, left_jaw=VEE).to_array()])
    scenarios = Scenarios.of({"radius_m": (0.06, 0.08)}, 0.002)
    cases = scenarios.scenarios()
    placed, disks, _, _ = place(np.repeat(rows, len(cases), axis=0), DISK, 0.5, cases)
    assert placed.shape == (len(cases), 14)
    assert (placed[:, 6:] == rows[0, 6:]).all()  # absolute jaws in every scenario
    table = evaluate_scenarios(rows, DISK, scenarios, friction_coefficient=0.5, **KF)
    assert table.per_scenario["reward"].shape == (1, len(cases))


# --- the design box ---------------------------------------------------------------------------


def test_the_groove_s_depth_for_a_mouth_inverts_the_mouth_of_a_depth():
    rng = np.random.default_rng(4)
    radius = rng.uniform(0.0, 3.0, 400)
    opening = np.where(rng.random(400) < 0.2, 0.0, rng.uniform(0.05, 2.9, 400))
    radius[opening == 0.0] += 0.1  # a cradle has a radius
    depth = rng.uniform(0.0, 1.0, 400) * np.where(opening == 0.0, radius, 2.0)
    mouth = jaw_mouth_half_width(depth, radius, opening)
    np.testing.assert_allclose(fitting_depth(mouth, radius, opening), depth, rtol=1e-9,
                               atol=1e-12)
    # each against JawProfile's own mouth (the rest check's rule)
    for i in range(0, 400, 37):
        jaw = JawProfile(depth[i], radius[i], opening[i], 10.0)
        assert mouth[i] == pytest.approx(jaw.mouth_half_width_m, rel=1e-13, abs=1e-15)
    # a cradle's mouth never exceeds its radius: any depth up to it fits a wider mouth
    assert fitting_depth(2.0, 1.0, 0.0) == math.inf
    assert fitting_depth(0.0, 1.0, 0.5) == 0.0


@pytest.mark.parametrize("bounds", SPACES, ids=_ids)
def test_scale_and_unscale_are_inverse_and_relative_designs_scale_free(bounds):
    rng = np.random.default_rng(7)
    x = rng.uniform(-1.0, 1.0, (300, bounds.n_var))
    x[:20] = np.sign(x[:20])  # box corners too
    si = bounds.scale(x, DISK)
    assert si.shape == (300, bounds.design_width)
    placed = si[:, DESIGN_FIELDS.index("distance_m")] > 0  # (else the placement was raised)
    assert placed.sum() > 250
    np.testing.assert_allclose(bounds.unscale(si, DISK)[placed], x[placed], atol=1e-9)
    np.testing.assert_allclose(bounds.scale(x[0], DISK), si[0], rtol=1e-14)
    forceps = Scene.preset("forceps-a").disk
    small = bounds.scale(x, forceps)
    lengths = [k for k, f in enumerate(bounds.design_fields) if f.endswith("_m")]
    np.testing.assert_allclose(small[:, lengths] / forceps.radius_m, si[:, lengths] / R,
                               rtol=1e-9)
    assert bounds.fields[:6] == envs.scene.RELATIVE_FIELDS
    assert len(bounds.fields) == bounds.n_var == 6 + len(bounds.jaw_fields)
    assert bounds.sample(rng, 5, DISK).shape == (5, bounds.design_width)


def test_the_jaw_columns_of_each_kind():
    assert DesignBounds().n_var == 6 and DesignBounds().design_width == 6
    assert DesignBounds(jaw="cradle").jaw_fields == ("jaw_depth_w", "jaw_radius_r",
                                                     "jaw_position")
    assert DesignBounds(jaw="vee", jaw_per_finger=True).n_var == 12
    assert DesignBounds(jaw="any", jaw_per_finger=True).design_fields[-4:] == LEFT_JAW_FIELDS
    rng = np.random.default_rng(1)
    for kind in ("cradle", "vee"):
        si = DesignBounds(jaw=kind).sample(rng, 200, DISK)
        jaws = [JawProfile(*row[6:]) for row in si]
        fixed = [j.opening_angle_rad if kind == "cradle" else j.bottom_radius_m for j in jaws]
        assert fixed == [0.0] * 200
        assert {j.kind for j in jaws} <= {kind, "straight"}
    # action -1 of the depth: the straight bar is in every box
    b = DesignBounds(jaw="any")
    x = np.zeros(b.n_var)
    x[b.fields.index("jaw_depth_w")] = -1.0
    assert b.scale(x, DISK)[6] == 0.0


@pytest.mark.parametrize("bounds", SPACES[1:], ids=_ids)
@pytest.mark.parametrize("preset", ["paper-r070", "forceps-a"])
def test_every_corner_of_the_box_is_valid_at_rest(bounds, preset):
    disk = Scene.preset(preset).disk
    corners = np.array(list(itertools.product((-1.0, 1.0), repeat=bounds.n_var)))
    si = bounds.scale(corners, disk)
    cols = _columns(si, _disk_table(disk, si.shape[0]), np.full(si.shape[0], 1e-3))
    assert (rest_codes(cols) == REST_OK).all()
    # and the box reaches the limits: the deepest groove of a short finger fills it
    w, ln = si[:, 3], si[:, 0]
    mouth = jaw_mouth_half_width(si[:, 6], si[:, 7], si[:, 8])
    room = 0.5 * ln - corner_radius(w, disk.radius_m) - mouth
    deepest = si[:, 6] >= MAX_DEPTH_OF_WIDTH * w * (1 - 1e-12)
    assert np.any(room < 1e-6 * ln) and np.any(deepest)


def test_other_jaws_for_a_box_keep_its_jaw_bounds_for_the_same_kind_only():
    narrow = DesignBounds(jaw="cradle", jaw_low=(0.1, 1.0, 0.2), jaw_high=(0.5, 1.5, 0.8))
    per_finger = narrow.with_jaw(jaw_per_finger=True)
    assert (per_finger.jaw_low, per_finger.jaw_high) == (narrow.jaw_low, narrow.jaw_high)
    assert per_finger.n_var == 12
    vee = narrow.with_jaw("vee")
    assert (vee.jaw_low, vee.jaw_high) == tuple(
        tuple(JAW_BOUNDS["vee"][c][i] for c in JAW_COLUMNS["vee"]) for i in (0, 1))
    assert DesignProblem(DISK, bounds=narrow, jaw="cradle").bounds == narrow
    assert DesignProblem(DISK, bounds=narrow, jaw="any").bounds == DesignBounds(jaw="any")


def test_a_finger_too_short_for_its_groove_is_invalid_not_an_error():
    # a cradle at least 0.5 w deep and 2.5 r wide: 0.98 r of mouth each side of its centre
    bounds = DesignBounds(jaw="cradle", jaw_low=(0.5, 2.5, 0.0), jaw_high=(0.75, 3.0, 1.0))
    x = -np.ones((2, bounds.n_var))
    x[1, 0] = 1.0  # the longest finger, 8 r
    x[:, 3] = 1.0  # the widest, 0.4 r
    out = evaluate_designs(bounds.scale(x, DISK), DISK, **KF)
    assert out["valid_at_rest"].tolist() == [False, True]


@pytest.mark.parametrize("kwargs, match", [
    ({"jaw": "round"}, "jaw must be one of"),
    ({"jaw_per_finger": True}, "jaw_per_finger needs a jaw other than 'straight'"),
    ({"jaw": "cradle", "jaw_per_finger": 1}, "jaw_per_finger must be True or False"),
    ({"jaw": "vee", "jaw_low": (0.0, 0.5)}, r"jaw_low needs 3 values for jaw 'vee'"),
    ({"jaw": "vee", "jaw_high": (0.8, 2.0, 1.0)}, r"jaw_high\[jaw_depth_w\]"),
    ({"jaw": "cradle", "jaw_low": (0.0, 0.0, 0.0)}, "low jaw_radius_r must be > 0"),
    ({"jaw": "any", "jaw_low": (0.0, 0.0, 0.0, 0.0)}, "jaw_radius_r or jaw_opening_rad"),
    ({"jaw": "cradle", "jaw_low": (0.2, 1.0, 0.0), "jaw_high": (0.2, 2.0, 1.0)},
     "must be smaller than"),
])
def test_bad_jaw_bounds_are_refused_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DesignBounds(**kwargs)


def test_actions_of_the_wrong_width_are_refused():
    with pytest.raises(ValueError, match=r"action must have shape \(B, 9\)"):
        DesignBounds(jaw="cradle").scale(np.zeros(6), DISK)
    with pytest.raises(ValueError, match=r"designs must have shape \(B, 14\)"):
        DesignBounds(jaw="vee", jaw_per_finger=True).unscale(np.zeros((1, 10)), DISK)


# --- optimizers, command line, object files ---------------------------------------------------


def test_the_design_problem_searches_the_wider_box():
    problem = DesignProblem(DISK, jaw="vee", jaw_per_finger=True, **KF)
    assert problem.n_var == 12
    problem.start(24)
    x = np.random.default_rng(2).uniform(-1, 1, (24, 12))
    out = problem.evaluate(x)
    assert out["reward"].shape == (24,)
    best = problem.top_designs(3)[0]["design"]
    assert set(best) == set(ALL_DESIGN_FIELDS)
    assert design_row(best).tolist() == problem.to_physical(problem.best_x).tolist()
    with pytest.raises(ValueError, match=r"x must have shape \(B, 12\)"):
        problem.evaluate(np.zeros((1, 6)))


@pytest.mark.parametrize("method", ["cmaes", "ga", "nsga2", "random"])
def test_every_method_searches_the_jaws(method):
    from optim.optimize import optimize

    problem = DesignProblem(DISK, jaw="any", **KF)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NoGraspWarning)
        result = optimize(method, problem, budget=30, seed=3)
    assert result.n_evaluations == 30
    assert list(result.best_design) == list(design_fields(10))
    assert result.extra["jaw"] == "any"
    assert problem.archive()["x"].shape == (30, 10)
    for pick in [*result.top_designs, *result.pareto_front]:
        assert design_row(pick["design"]).shape == (10,)


def test_the_jaws_of_a_chart_title():
    from optim.charts import jaw_label

    assert jaw_label(design_mapping(PAPER.to_array())) == ""
    both = jaw_label(design_mapping(Design(*PAPER.to_array(), jaw=CRADLE).to_array(14)))
    assert both == "\njaws: cradle h = 4 mm, R = 84 mm, 0°, at 100 mm"
    each = jaw_label(design_mapping(Design(*PAPER.to_array(), jaw=CRADLE,
                                           left_jaw=VEE).to_array()))
    assert each.splitlines()[1:] == ["right jaw: cradle h = 4 mm, R = 84 mm, 0°, at 100 mm",
                                     "left jaw: vee h = 5 mm, R = 0 mm, 90°, at 120 mm"]


def test_optimize_with_a_cradle_writes_the_jaws_by_name(tmp_path):
    from cli.main import main

    code = main(["optimize", "--scene", "paper-r070", "--jaw", "cradle", "--budget", "40",
                 "--no-progress", "--out", str(tmp_path)])
    assert code in (0, 3)
    result = json.loads((tmp_path / "portfolio_seed0_result.json").read_text())
    assert result["extra"]["jaw"] == "cradle" and result["extra"]["jaw_per_finger"] is False
    for design in [result["best_design"], *(p["design"] for p in result["top_designs"])]:
        assert list(design) == list(design_fields(10))
        jaw = JawProfile(*(design[k] for k in JAW_FIELDS))
        assert jaw.opening_angle_rad == 0.0 and jaw.kind in ("cradle", "straight")
    assert (tmp_path / "portfolio_seed0_best_grasp.png").stat().st_size > 0


def test_the_policy_refuses_shaped_jaws_before_any_work(tmp_path, capsys):
    from cli.main import main

    obj = tmp_path / "bead.toml"
    obj.write_text('[object]\nradius_m = 0.01\nyoungs_modulus_pa = 1e5\npoisson_ratio = 0.4\n'
                   'thickness_m = 0.01\njaw = "vee"\n')
    assert main(["design", "--object", str(obj), "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "design straight or any jaws alike on both fingers, not jaw 'vee' (the object " \
        "file's)" in err
    assert f"optimize --object {obj} --jaw vee" in err
    assert main(["optimize", "--method", "policy", "--jaw", "cradle", "--out",
                 str(tmp_path / "b")]) == 2
    assert "--jaw: the design policies design jaws any or straight alike on both fingers, " \
        "not jaw 'cradle'" in capsys.readouterr().err
    assert main(["optimize", "--jaw-per-finger", "--out", str(tmp_path / "c")]) == 2
    assert "jaw_per_finger needs a jaw other than 'straight'" in capsys.readouterr().err
    assert not any((tmp_path / d).exists() for d in "abc")


def test_verify_checks_the_jaws_of_the_run(tmp_path):
    from cli.optimize import _check_same_jaws

    _check_same_jaws("cradle", None, {"jaw": "cradle", "jaw_per_finger": False}, "r.json")
    _check_same_jaws("straight", None, {}, "r.json")  # a run before shaped jaws: straight
    with pytest.raises(ValueError, match="designed jaw 'cradle', not jaw 'vee'"):
        _check_same_jaws("vee", None, {"jaw": "cradle"}, "r.json")
    with pytest.raises(ValueError, match="not jaw 'cradle' per finger"):
        _check_same_jaws(None, True, {"jaw": "cradle"}, "r.json")


OBJECT = {"radius_m": 0.01, "youngs_modulus_pa": 1e5, "poisson_ratio": 0.4,
          "thickness_m": 0.01}


def test_object_files_name_the_jaws_to_design():
    from optim.run import jaw_settings

    spec = parse_object({"object": {**OBJECT, "jaw": "vee", "jaw_per_finger": True}}, "f")
    assert (spec.jaw, spec.jaw_per_finger) == ("vee", True)
    assert spec.info()["jaw"] == "vee"
    assert jaw_settings(spec) == {"jaw": "vee", "jaw_per_finger": True}
    # the command line wins; straight bars drop the file's per-finger flag
    assert jaw_settings(spec, "cradle") == {"jaw": "cradle", "jaw_per_finger": True}
    assert jaw_settings(spec, "straight") == {"jaw": "straight", "jaw_per_finger": False}
    plain = parse_object({"object": OBJECT}, "f")
    assert plain.jaw is None and "jaw" not in plain.info()
    assert jaw_settings(plain) == {"jaw": "straight", "jaw_per_finger": False}


@pytest.mark.parametrize("extra, match", [
    ({"jaw": "round"}, r"f: \[object\]: jaw must be one of 'straight', 'cradle', 'vee', 'any', "
                       r"got 'round'"),
    ({"jaw": 1}, "jaw must be one of"),
    ({"jaw": "vee", "jaw_per_finger": "yes"}, "jaw_per_finger must be true or false"),
    ({"jaw_per_finger": True}, "jaw_per_finger = true needs jaw = 'cradle', 'vee', 'any'"),
    ({"jaw": "straight", "jaw_per_finger": True}, "got jaw = 'straight'"),
    ({"jaws": "vee"}, "unknown key 'jaws'; allowed: .*jaw, jaw_per_finger"),
])
def test_bad_jaw_keys_of_an_object_file_are_named(extra, match):
    with pytest.raises(ValueError, match=match):
        parse_object({"object": {**OBJECT, **extra}}, "f")


# --- the environment --------------------------------------------------------------------------


@pytest.mark.parametrize("kwargs, width", [({}, 10), ({"jaw": "cradle"}, 9),
                                           ({"jaw": "vee", "jaw_per_finger": True}, 12)])
def test_the_jaw_env_has_the_jaw_actions(kwargs, width):
    env = gym.make(envs.JAW_ENV_ID, **kwargs)
    assert env.action_space.shape == (width,) and env.observation_space.shape == (6,)
    env.reset(seed=0)
    action = np.zeros(width)
    action[6] = 1.0  # the deepest groove that fits
    _, reward, terminated, _, info = env.step(action)
    assert terminated and math.isfinite(reward) and info["valid_at_rest"]
    assert info["design"].shape == (14 if kwargs.get("jaw_per_finger") else 10,)
    assert info["design"][6] > 0.0
    vec = gym.make_vec(envs.JAW_ENV_ID, num_envs=3, vectorization_mode="vector_entry_point",
                       **kwargs)
    assert vec.single_action_space.shape == (width,)
    vec.reset(seed=1)
    _, rewards, *_ = vec.step(np.zeros((3, width)))
    assert np.isfinite(rewards).all()
    with pytest.raises(ValueError, match=rf"shape \(3, {width}\)"):
        vec.step(np.zeros((3, 6)))


def test_gripper_design_v2_keeps_six_actions():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the jaw env is not a later version of v2: no warning
        env = gym.make(envs.ENV_ID)
    assert env.action_space.shape == (6,)
    assert {k: len(v) for k, v in JAW_COLUMNS.items()} == {"straight": 0, "cradle": 3,
                                                           "vee": 3, "any": 4}


def test_design_with_the_jaw_policy_writes_a_groove(tmp_path):
    """``psm-grasp design --jaw any``: the shipped jaw policy's design, with its groove by name
    in the result and the run's jaws recorded."""
    from cli.main import main

    obj = tmp_path / "bead.toml"
    obj.write_text('[object]\nradius_m = 0.01\nyoungs_modulus_pa = 1e5\npoisson_ratio = 0.4\n'
                   'thickness_m = 0.01\ndensity_kg_m3 = 100\n')
    code = main(["design", "--object", str(obj), "--jaw", "any", "--no-progress", "--out",
                 str(tmp_path / "out")])
    assert code in (0, 3)
    result = json.loads((tmp_path / "out" / "design_result.json").read_text())
    assert result["extra"]["jaw"] == "any"
    assert list(result["best_design"]) == list(design_fields(10))
