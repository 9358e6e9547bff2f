"""GripperDesign-v2 and evaluate_designs: API checkers, determinism, batching, reward order."""

from __future__ import annotations

import math
import pickle
from concurrent.futures import ThreadPoolExecutor

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode

import envs
from envs import (
    Design,
    DesignBounds,
    GripperDesignEnv,
    GripperDesignVectorEnv,
    RewardWeights,
    Scene,
    SoftDisk,
    evaluate_designs,
)
from envs.evaluate import METRIC_KEYS, _columns, _disk_table
from envs.model.contact_width import hertz_arc_coefficient
from envs.model.family import resolve_model
from envs.model.problem import REST_OK, pack_params, rest_codes, scaled_params
from envs.scene import PRESETS, Gripper
from envs.solver.status import NOT_FINITE, NOT_SOLVED
from envs.validation import InputWarning

from .contact_reference import face_extent_shares

GRIPPER, DISK = PRESETS["paper-r070"]
PAPER = np.array([GRIPPER.finger_length_m, GRIPPER.rest_angle_rad, GRIPPER.joint_offset_m,
                  GRIPPER.finger_width_m, 0.2, DISK.distance_m])
# a box in metres around the paper scenes, with valid and invalid designs (the default
# DesignBounds is relative to the object and valid at rest by construction)
WIDE_LOW = np.array([0.05, math.radians(15.0), 0.0, 0.002, 0.0, 0.0])
WIDE_HIGH = np.array([0.30, math.radians(75.0), 0.05, 0.03, 1.0, 0.06])
ACTIONS = np.array([
    [0.2, 0.0, 0.0, -0.4, -0.5, -0.5],
    [-0.3, -0.2, 0.1, 0.0, 0.1, 0.3],
    [0.5, 0.4, -0.6, 0.2, 0.8, -0.2],
])

# tests that score several designs on one object by stepping an env again without a reset (it
# warns once an episode: in a training loop it is a forgotten reset)
SAME_OBJECT_STEPS = pytest.mark.filterwarnings(
    "ignore:GripperDesignEnv.step\\(\\) after the episode ended")


def wide_designs(rng: np.random.Generator, size: int) -> np.ndarray:
    return WIDE_LOW + rng.uniform(0.0, 1.0, (size, 6)) * (WIDE_HIGH - WIDE_LOW)


def paper_designs(torques) -> np.ndarray:
    des = np.tile(PAPER, (len(torques), 1))
    des[:, 4] = torques
    return des


def _extents(design: np.ndarray, n: int = 20, element: str = "spring") -> np.ndarray:
    """Each face's interpolated contact share of the design's grasp on DISK (the definition
    in numpy, tests/contact_reference.py, on simulate's answer)."""
    scene = Design.from_array(design).to_scene(DISK)
    res = envs.simulate(scene, float(design[4]), n, element=element)
    return face_extent_shares(res.points_m, res.contact_forces_n, scene.gripper,
                              res.jaw_angles_rad, DISK)


def assert_outputs_equal(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def assert_all_finite(out: dict) -> None:
    for key, v in out.items():
        assert np.all(np.isfinite(np.asarray(v, dtype=float))), key


# --- evaluate_designs --------------------------------------------------------------------------


def test_outputs_have_documented_keys_shapes_and_paper_values():
    out = evaluate_designs(paper_designs([0.1, 0.2]), DISK, element="spring")
    assert list(out) == list(METRIC_KEYS)
    for key, (dtype, shape) in METRIC_KEYS.items():
        assert out[key].shape == (2, *shape), key
        assert out[key].dtype == dtype, key
    assert out["converged"].all() and out["valid_at_rest"].all()
    np.testing.assert_array_equal(out["n_contacts"], [[3, 3], [3, 3]])
    # each face's share: the contact's extent interpolated between its points (three pressed
    # points a face: two segments and parts of the next), at most the Hertz width of the face
    # force (no corner touches here: face = total force)
    k = hertz_arc_coefficient(DISK.radius_m, DISK.thickness_m, DISK.youngs_modulus_pa,
                              DISK.poisson_ratio, DISK.radius_m)
    width = k * np.sqrt(out["total_force_n"])
    extents = np.array([_extents(row) for row in paper_designs([0.1, 0.2])])
    assert np.all((extents > 2 / 20) & (extents < 4 / 20))
    np.testing.assert_allclose(out["contact_score"],
                               out["grip_share"] * np.minimum(extents, width).sum(axis=1),
                               rtol=1e-9)
    total = (out["reward_contact"] + out["reward_deform"] + out["penalty_slip"]
             + out["penalty_miss"] + out["penalty_gap"] + out["penalty_invalid"]
             + out["penalty_fail"])
    np.testing.assert_array_equal(out["reward"], total)
    # the paper's gripper at 35-36 deg needs friction tan(theta) ~ 0.72 to hold the disk
    # without its pin: more than the default 0.5, so it scores in the tier of grasps that slip;
    # lifting the foam disk too (its weight and a lift at 1 g, in every direction) needs more
    alone = evaluate_designs(paper_designs([0.1, 0.2]), DISK, element="spring",
                             payload_factors=0)
    np.testing.assert_allclose(alone["required_friction"],
                               np.tan(alone["jaw_angles_rad"][:, 0]), rtol=1e-9)
    assert np.all(out["required_friction"] > alone["required_friction"])
    np.testing.assert_allclose(out["payload_n"], DISK.payload_n(2.0), rtol=1e-12)
    w = RewardWeights()
    assert not out["holds"].any() and np.all(out["reward_contact"] == 0.0)
    assert np.all((out["reward"] > -w.deform * w.deform_cap - w.slip)
                  & (out["reward"] < -w.deform * w.deform_cap))


@pytest.mark.parametrize("model", [{}, {"n_triangles": 20, "element": "spring"}])
def test_matches_simulate_on_the_paper_scene(model):
    """The batch and simulate solve the same member: the default model (nh-quad, its shipped
    calibration) and the paper's fan."""
    res = envs.simulate(Scene(GRIPPER, DISK), 0.2, **model)
    out = evaluate_designs(paper_designs([0.2]), DISK, **model)
    assert out["n_triangles"][0] == res.n_triangles
    np.testing.assert_allclose(out["jaw_angles_rad"][0], res.jaw_angles_rad, rtol=1e-12)
    np.testing.assert_allclose(out["peak_strain"][0], res.peak_strain, rtol=1e-10)
    np.testing.assert_allclose(out["total_force_n"][0], res.total_force_n, rtol=1e-9)
    np.testing.assert_array_equal(out["n_contacts"][0], res.n_contacts)


def test_batch_design_to_scene_is_the_scene_path():
    # validity and packing of design rows are those of Design.to_scene + Scene, row by row
    rng = np.random.default_rng(7)
    designs = wide_designs(rng, 400)
    cols = _columns(designs, _disk_table(DISK, 400), np.full(400, 0.073))
    valid = rest_codes(cols) == REST_OK
    prm = pack_params(cols, 20)
    assert 0.2 < valid.mean() < 0.95
    for i, row in enumerate(designs):
        design = Design.from_array(row)
        try:
            scene = design.to_scene(DISK, 0.073)
        except ValueError:
            assert not valid[i]
            continue
        assert valid[i]
        assert Design.from_scene(scene, design.torque_nm) == design
        np.testing.assert_array_equal(prm[i], scaled_params(scene, design.torque_nm, 20))


def test_batched_and_single_evaluation_agree_exactly():
    designs = paper_designs([0.0, 0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 0.3])
    designs[7, 1] = math.radians(20.0)  # invalid row in the batch
    designs[6, 5] = 0.02
    batch = evaluate_designs(designs, DISK)
    assert not batch["valid_at_rest"][7]
    for i in range(len(designs)):
        single = evaluate_designs(designs[i : i + 1], DISK)
        for key in batch:
            np.testing.assert_array_equal(batch[key][i], single[key][0], err_msg=key)


def test_executor_chunks_and_per_row_n_agree_with_in_process():
    designs = paper_designs([0.05, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8])
    n_tri = np.array([12, 20, 12, 20, 16, 20, 12])
    ref = evaluate_designs(designs, DISK, n_triangles=n_tri, element="spring")
    with ThreadPoolExecutor(2) as pool:
        chunked = evaluate_designs(designs, DISK, n_triangles=n_tri, executor=pool, chunk_size=3,
            element="spring")
    assert_outputs_equal(ref, chunked)
    for n in (12, 16, 20):
        rows = n_tri == n
        alone = evaluate_designs(designs[rows], DISK, n_triangles=n, element="spring")
        for key in ref:
            np.testing.assert_array_equal(ref[key][rows], alone[key], err_msg=key)


def test_design_objects_and_per_row_disks():
    designs = [Design.from_array(row) for row in paper_designs([0.1, 0.2])]
    np.testing.assert_array_equal(designs[1].to_array(), PAPER)
    disks = [DISK, SoftDisk(0.05, 0.0)]
    out = evaluate_designs(designs, disks)
    ref = evaluate_designs(paper_designs([0.2]), SoftDisk(0.05, 0.123))
    np.testing.assert_array_equal(out["peak_strain"][1], ref["peak_strain"][0])


def test_contact_score_barely_depends_on_n():
    out = evaluate_designs(paper_designs([0.2, 0.2]), DISK, n_triangles=np.array([20, 40]),
                           element="spring")
    assert out["converged"].all()
    assert abs(out["contact_score"][0] - out["contact_score"][1]) <= 0.1


def test_reward_prefers_a_grasp_over_a_miss():
    out = evaluate_designs(paper_designs([1e-4, 0.1]), DISK)
    assert out["converged"].all()
    np.testing.assert_array_equal(out["n_contacts"][0], [0, 0])  # too weak to reach the disk
    assert np.all(out["n_contacts"][1] > 0)
    w = RewardWeights()
    assert out["penalty_miss"][0] == -(w.deform * w.deform_cap + w.slip) - 2 * w.miss
    assert out["penalty_gap"][0] < 0.0 and out["penalty_gap"][1] == 0.0
    assert out["reward"][1] > out["reward"][0]


def test_reward_prefers_a_gentle_grasp_at_equal_contacts():
    torques = np.linspace(0.05, 0.8, 16)
    # (friction 1: the paper's gripper needs 0.7-0.8 to hold, more than the default; the
    # reaction alone: the ranking by compression is the subject, not the payload)
    out = evaluate_designs(paper_designs(torques), DISK, friction_coefficients=1.0,
                           payload_factors=0)
    assert out["holds"].all()
    assert out["converged"].all()
    groups: dict[tuple[int, int], list[int]] = {}
    for i, nc in enumerate(map(tuple, out["n_contacts"].tolist())):
        groups.setdefault(nc, []).append(i)
    pairs = 0
    for rows in groups.values():
        rows = sorted(rows, key=lambda i: out["peak_log_strain"][i])
        for gentle, crushing in zip(rows, rows[1:], strict=False):
            if out["peak_log_strain"][crushing] > out["peak_log_strain"][gentle]:
                assert out["reward"][gentle] > out["reward"][crushing]
                pairs += 1
    assert pairs >= 2


def test_invalid_design_gets_the_penalty_and_finite_values():
    bad = PAPER.copy()
    bad[1], bad[5] = math.radians(15.0), 0.0  # fingers overlap the disk at rest
    with pytest.raises(ValueError):
        Scene(Gripper(*bad[:4], 0.073), SoftDisk(DISK.radius_m, bad[5]))
    nan_row = PAPER.copy()
    nan_row[0] = np.nan
    with pytest.warns(InputWarning, match=r"row 1: finger_length_m = nan"):
        out = evaluate_designs(np.stack([bad, nan_row]), DISK)
    assert not out["valid_at_rest"].any() and not out["converged"].any()
    w = RewardWeights()
    # graded: an overlap scores between -invalid and -(invalid + violation); NaN the worst
    assert -w.invalid - w.violation < out["reward"][0] < -w.invalid
    assert out["reward"][1] == -w.invalid - w.violation
    np.testing.assert_array_equal(out["reward"], out["penalty_invalid"])
    np.testing.assert_array_equal(out["status"], [NOT_SOLVED, NOT_FINITE])
    assert_all_finite(out)


def test_malformed_inputs_raise():
    with pytest.raises(ValueError):
        evaluate_designs(PAPER, DISK)  # 1-D
    with pytest.raises(ValueError):
        evaluate_designs(paper_designs([0.1]), [DISK, DISK])
    with pytest.raises(ValueError):
        evaluate_designs(paper_designs([0.1]), DISK, n_triangles=3, element="spring")
    with pytest.raises(ValueError):
        evaluate_designs(paper_designs([0.1]), DISK, strain_limits=0.0)
    # a column of per-row values is checked as one array; a bad row is still named
    limits = np.full(4, 0.1)
    designs = paper_designs([0.1] * 4)
    np.testing.assert_array_equal(
        evaluate_designs(designs, DISK, strain_limits=limits)["strain_limit"], limits)
    for bad in (0.0, 1.5, np.nan, np.inf):
        limits[2] = bad
        with pytest.raises(ValueError, match=r"strain_limits\[2\]"):
            evaluate_designs(designs, DISK, strain_limits=limits)
    with pytest.raises(ValueError, match=r"torsion_stiffness_nm_per_rad\[1\]"):
        evaluate_designs(designs, DISK, torsion_stiffness_nm_per_rad=[0.07, -1.0, 0.07, 0.07])


def test_bounds_scale_round_trip():
    bounds = DesignBounds()
    a = np.random.default_rng(0).uniform(-1, 1, (5, 6))
    a[:, 1] = np.abs(a[:, 1])  # rest angles over 35 deg: no placement raised to 0
    np.testing.assert_allclose(bounds.unscale(bounds.scale(a, DISK), DISK), a, atol=1e-12)
    disks = [DISK, SoftDisk(0.002, 0.0, 29e6, stiffness_scale=0.033)] * 2 + [DISK]
    np.testing.assert_allclose(bounds.unscale(bounds.scale(a, disks), disks), a, atol=1e-12)
    for name in PRESETS:  # every preset's own gripper lies in the box, the forceps included
        scene = Scene.preset(name)
        design = Design.from_scene(scene, 0.01 * scene.disk.torque_unit_nm).to_array()
        assert np.all(np.abs(bounds.unscale(design, scene.disk)) <= 1.0), name
    with pytest.raises(ValueError, match="finger_length_r"):
        DesignBounds(low=(9.0, 0.2, 0.0, 0.002, 0.0, 0.0))


def test_relative_box_scales_with_the_object():
    # the same actions on a 70 mm foam disk and a 2 mm TPU bead: the same grasp in radii, with
    # every default (the joint spring too is relative to the object) but the payload, whose
    # group f rho g r / (s E) differs between the two (off here; see the test below)
    bounds = DesignBounds()
    small = SoftDisk(0.002, 0.0, 29e6, stiffness_scale=0.033)
    a = np.random.default_rng(1).uniform(-1, 1, (40, 6))
    big = evaluate_designs(bounds.scale(a, DISK), DISK, payload_factors=0)
    tiny = evaluate_designs(bounds.scale(a, small), small, payload_factors=0)
    assert big["valid_at_rest"].all() and tiny["valid_at_rest"].all()
    np.testing.assert_array_equal(big["converged"], tiny["converged"])
    np.testing.assert_allclose(big["jaw_angles_rad"], tiny["jaw_angles_rad"], atol=1e-7)
    np.testing.assert_allclose(big["reward"], tiny["reward"], atol=1e-6)
    # an absolute spring is still possible by name: on the bead the paper's 0.073 N·m/rad is
    # twice the bead's torque unit, and one design in 40 closes on it (30 with the default)
    stiff = evaluate_designs(bounds.scale(a, small), small, torsion_stiffness_nm_per_rad=0.073)
    assert stiff["touching"].all(axis=1).sum() <= 2 < 20 <= tiny["touching"].all(axis=1).sum()
    with pytest.raises(ValueError, match="not both"):
        evaluate_designs(bounds.scale(a, small), small, torsion_stiffness_rel=0.01,
                         torsion_stiffness_nm_per_rad=0.073)


@SAME_OBJECT_STEPS
def test_every_default_scores_relative_designs_alike_on_objects_far_apart():
    """The paper's r = 0.07 m disk and one 20x smaller and 50x softer (and 2.5x lighter, so that
    the payload's group rho g r / E is the same): 64 relative designs score the same through
    evaluate_designs, DesignProblem, the single and the vector env, each with its defaults (an
    absolute default spring made them differ by up to 1.3 in reward)."""
    from envs.design_env import GripperDesignEnv, GripperDesignVectorEnv
    from optim.problem import DesignProblem

    paper = Scene.preset("paper-r070").disk
    # the payload scales with rho g r / E: 20x smaller and 50x softer keeps it at 50 * 20 / 50
    small = SoftDisk(0.0035, 0.0, youngs_modulus_pa=2e3, poisson_ratio=0.45, thickness_m=0.01,
                     density_kg_m3=paper.density_kg_m3 * 20.0 / 50.0)
    a = np.random.default_rng(7).uniform(-1, 1, (64, 6))
    rewards = []
    for disk in (paper, small):
        bounds = DesignBounds()
        out = evaluate_designs(bounds.scale(a, disk), disk)
        by_batch = out["reward"]
        assert out["touching"].all(axis=1).mean() > 0.5  # grasps, not 64 misses scoring alike
        problem = DesignProblem(disk)
        by_problem = problem.evaluate_physical(problem.to_physical(a))["reward"]
        env = GripperDesignEnv()
        # evaluate_designs' defaults: payload factor 2, placed exactly
        fixed = {"disk": disk, "strain_limit": 0.1, "friction_coefficient": 0.5,
                 "payload_factor": 2.0, "placement_tolerance_rel": 0.0}
        env.reset(seed=0, options=fixed)
        by_env = np.array([env.step(row)[1] for row in a[:4]])
        vec = GripperDesignVectorEnv(4)
        vec.reset(seed=0, options=fixed)
        by_vec = vec.step(a[:4])[1]
        # (float64 actions: a float32 cast moves a design near a bifurcation onto another branch)
        for other in (by_problem, by_env, by_vec):
            np.testing.assert_array_equal(other, by_batch[: other.size])
        rewards.append(by_batch)
    np.testing.assert_allclose(rewards[0], rewards[1], atol=1e-6)


def test_default_box_is_valid_for_every_preset():
    rng = np.random.default_rng(2)
    for name in PRESETS:
        disk = Scene.preset(name).disk
        cols = _columns(DesignBounds().sample(rng, 500, disk), _disk_table(disk, 500),
                        np.full(500, 1e-3))
        assert np.all(rest_codes(cols) == REST_OK), name


def test_graded_penalties_point_towards_a_grasp():
    # deeper overlap scores lower; a finger farther from the disk scores lower
    overlap = paper_designs([0.2, 0.2, 0.2])
    overlap[:, 5] = [0.0, -0.01, -0.03]
    overlap[:, 1] = math.radians(30.0)
    out = evaluate_designs(overlap, DISK)
    assert not out["valid_at_rest"].any()
    v = out["rest_violation"]
    assert 0 < v[0] < v[1] < v[2] < 1
    assert out["reward"][0] > out["reward"][1] > out["reward"][2]
    weak = paper_designs([1e-4, 3e-4, 1e-3])  # too weak to reach the disk: miss by less
    out = evaluate_designs(weak, DISK)
    assert out["converged"].all() and not out["touching"].any()
    gaps = out["finger_gap_m"][:, 0]
    assert gaps[0] > gaps[1] > gaps[2] > 0
    assert out["reward"][0] < out["reward"][1] < out["reward"][2]


def test_every_invalid_design_scores_below_every_valid_one():
    rng = np.random.default_rng(4)
    out = evaluate_designs(wide_designs(rng, 400), DISK)
    valid = out["valid_at_rest"]
    assert 0 < valid.sum() < 400
    assert out["reward"][~valid].max() < out["reward"][valid].min()
    failed = valid & ~out["converged"]
    assert np.all(out["reward"][failed] == -RewardWeights().fail)
    assert np.all(out["reward"][out["converged"]] > -RewardWeights().fail)
    with pytest.raises(ValueError, match="invalid = 1.0 must be at least"):
        RewardWeights(invalid=1.0)


# --- the environment ---------------------------------------------------------------------------


def test_gymnasium_check_env():
    check_env(GripperDesignEnv(), skip_render_check=True)
    check_env(gym.make("GripperDesign-v2", render_mode="rgb_array").unwrapped)


def test_gymnasium_check_env_as_registered():
    # as a user makes it: with the wrappers of make (no TimeLimit: one step terminates)
    env = gym.make("GripperDesign-v2")
    assert env.spec.max_episode_steps is None
    with pytest.warns(UserWarning, match="different from the unwrapped"):
        check_env(env, skip_render_check=True)
    env.reset(seed=0)
    *_, terminated, truncated, _ = env.step(env.action_space.sample())
    assert terminated is True and truncated is False


def test_sb3_check_env():
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    sb3_checker.check_env(GripperDesignEnv(), warn=True)


def test_same_seed_gives_identical_rollouts():
    def rollout(seed: int):
        env = GripperDesignEnv()
        env.action_space.seed(seed)
        steps = []
        for k in range(4):
            obs, _ = env.reset(seed=seed if k == 0 else None)
            steps.append((obs, *env.step(env.action_space.sample())))
        return steps

    a, b = rollout(3), rollout(3)
    for sa, sb in zip(a, b, strict=True):
        np.testing.assert_array_equal(sa[0], sb[0])
        assert sa[2] == sb[2]
        for key in sa[5]:
            np.testing.assert_array_equal(sa[5][key], sb[5][key], err_msg=key)
    assert not np.array_equal(rollout(4)[0][0], a[0][0])


@SAME_OBJECT_STEPS
def test_env_pickles():
    env = GripperDesignEnv(render_mode="rgb_array")
    env.reset(seed=5)
    env.step(ACTIONS[0])
    clone = pickle.loads(pickle.dumps(env))
    r1 = env.step(ACTIONS[1])
    r2 = clone.step(ACTIONS[1])
    assert r1[1] == r2[1]
    np.testing.assert_array_equal(r1[0], r2[0])
    np.testing.assert_array_equal(env.reset()[0], clone.reset()[0])


@pytest.mark.parametrize(
    "action",
    [np.full(6, np.nan), np.array([0, 0, 0, 0, np.inf, 0.0]), np.zeros(5), np.zeros((1, 6)),
     "abc"],
)
def test_bad_actions_raise(action):
    env = GripperDesignEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError):
        env.step(action)


@SAME_OBJECT_STEPS
def test_clipping_is_reported():
    env = GripperDesignEnv()
    env.reset(seed=0)
    *_, info = env.step(np.zeros(6))
    assert info["clipped"] is False
    *_, info = env.step(np.array([1.5, 0, 0, 0, -3.0, 0]))
    assert info["clipped"] is True
    assert info["design"][0] == env.bounds.high[0] * info["radius_m"]
    assert info["design"][4] == env.bounds.low[4] == 0.0


def test_reset_options_fix_the_object_and_invalid_actions_are_penalized():
    env = GripperDesignEnv()
    obs, info = env.reset(seed=0, options={"disk": DISK, "strain_limit": 0.1,
                                           "friction_coefficient": 0.9, "payload_factor": 2.0,
                                           "placement_tolerance_rel": 0.0})
    assert info["radius_m"] == DISK.radius_m and info["strain_limit"] == 0.1
    assert info["friction_coefficient"] == 0.9
    action = env.bounds.unscale(PAPER, DISK)
    _, reward, terminated, truncated, info = env.step(action)
    assert terminated and not truncated and info["converged"] and info["holds"]
    ref = evaluate_designs(env.bounds.scale(np.clip(action, -1, 1), DISK)[None], DISK,
                           strain_limits=0.1, friction_coefficients=0.9)
    assert reward == ref["reward"][0]
    # a box reaching negative clearances (overlap) gets the graded invalid penalty
    low = list(DesignBounds().low)
    low[5] = -0.5
    env = GripperDesignEnv(bounds=DesignBounds(low=tuple(low)))
    env.reset(seed=0, options={"disk": DISK})
    action = -np.ones(6)
    action[1] = 1.0  # 60 deg: the disk would sit below the joints; raised to 0, it overlaps
    _, reward, *_, info = env.step(action)
    w = RewardWeights()
    assert -(w.invalid + w.violation) < reward < -w.invalid and not info["valid_at_rest"]
    with pytest.raises(ValueError, match="poisson_ratio = -0.2 is outside the observable"):
        env.reset(options={"disk": SoftDisk(0.2, 0.0, poisson_ratio=-0.2)})
    with pytest.raises(ValueError, match="friction_coefficient = 3.0 is outside"):
        env.reset(options={"friction_coefficient": 3.0})
    with pytest.raises(ValueError):
        env.reset(options={"colour": "red"})


def test_vector_observations_are_the_single_objects_observations():
    """The vector env observes its new objects in one array pass (observe_rows): each row is
    what observe() gives that object, and a row outside the observable range is named."""
    from envs.design_env import observe, observe_rows

    vec = GripperDesignVectorEnv(5)
    obs, info = vec.reset(seed=3)
    for i in range(5):
        disk = vec._disks[i]
        assert np.array_equal(obs[i], observe(disk, *vec._needs[i]))
        assert info["youngs_modulus_pa"][i] == disk.youngs_modulus_pa
    # and the same objects as five single envs seeded alike draw
    for i in range(5):
        single_obs, _ = GripperDesignEnv().reset(seed=3 + i)
        assert np.array_equal(obs[i], single_obs)
    # a fixed object outside the observable range leaves the vector env as it was
    fresh = GripperDesignVectorEnv(3)
    with pytest.raises(ValueError, match="poisson_ratio"):
        fresh.reset(seed=0, options={"disk": SoftDisk(0.2, 0.0, poisson_ratio=-0.1)})
    with pytest.raises(gym.error.ResetNeeded):
        fresh.step(np.zeros((3, 6)))
    obs_before = vec._obs.copy()
    with pytest.raises(ValueError, match="strain_limit"):
        vec.reset(options={"strain_limit": 0.6})
    assert np.array_equal(vec._obs, obs_before) and vec._disks[0] is not None
    disks = [DISK, SoftDisk(0.2, 0.0, stiffness_scale=20.0), DISK]
    with pytest.raises(ValueError, match=r"stiffness_scale = 20.0 \(row 1\) is outside"):
        observe_rows(disks, np.full((3, 2), 0.1))
    with pytest.raises(ValueError, match=r"strain_limit = 0.0 \(row 2\)"):
        observe_rows([DISK] * 3, np.array([[0.1, 0.5], [0.2, 0.5], [0.0, 0.5]]))
    with pytest.raises(ValueError, match=r"friction_coefficient = 0.0 \(row 0\)"):
        observe_rows([DISK] * 3, np.array([[0.1, 0.0], [0.2, 0.5], [0.1, 0.5]]))


def test_render_rgb_array_and_grasp_figure(tmp_path):
    from envs.render import grasp_figure

    env = GripperDesignEnv(render_mode="rgb_array")
    env.reset(seed=0, options={"disk": DISK})
    before = env.render()
    env.step(env.bounds.unscale(PAPER, DISK))
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.shape == before.shape and not np.array_equal(frame, before)
    res = envs.simulate(Scene(GRIPPER, DISK), 0.2, 20, element="spring")
    grasp_figure(Scene(GRIPPER, DISK), res, tmp_path / "grasp.png")
    assert (tmp_path / "grasp.png").read_bytes()[:4] == b"\x89PNG"


# --- vector environments -----------------------------------------------------------------------


def _run_vec(env, n_steps: int = 3):
    obs, _ = env.reset(seed=11)
    trace = [obs]
    for _ in range(n_steps):
        obs, rew, term, trunc, info = env.step(ACTIONS)
        trace.append((obs, rew, term, trunc, info))
    env.close()
    return trace


def _assert_same_trace(a, b, info_keys=("peak_strain", "_peak_strain", "radius_m")):
    np.testing.assert_array_equal(a[0], b[0])
    for sa, sb in zip(a[1:], b[1:], strict=True):
        for x, y in zip(sa[:4], sb[:4], strict=True):
            np.testing.assert_array_equal(x, y)
        for key in info_keys:
            if key in sa[4] or key in sb[4]:
                np.testing.assert_array_equal(sa[4][key], sb[4][key], err_msg=key)


SAME_STEP = {"autoreset_mode": AutoresetMode.SAME_STEP}


@pytest.mark.parametrize("mode,kwargs", [
    ("vector_entry_point", {}),  # the batched env: same-step autoreset by default
    ("sync", {"vector_kwargs": SAME_STEP}),
    ("async", {"vector_kwargs": SAME_STEP}),
])
def test_make_vec_evaluates_a_design_on_every_step(mode, kwargs):
    env = gym.make_vec("GripperDesign-v2", num_envs=3, vectorization_mode=mode, **kwargs)
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    env.reset(seed=11)
    for _ in range(3):
        _, rewards, terminated, truncated, info = env.step(ACTIONS)
        # every sub-env scored a design in every step: no reset step with reward 0
        assert terminated.all() and not truncated.any()
        assert info["_final_info"].all()
        np.testing.assert_array_equal(rewards, info["final_info"]["reward"])
        assert np.all(rewards != 0.0)
    env.close()


def test_make_vec_modes_agree():
    traces = {
        mode: _run_vec(gym.make_vec("GripperDesign-v2", num_envs=3, vectorization_mode=mode,
                                    **kwargs))
        for mode, kwargs in (("sync", {"vector_kwargs": SAME_STEP}),
                             ("async", {"vector_kwargs": SAME_STEP}),
                             ("vector_entry_point", {}))
    }
    vec = gym.make_vec("GripperDesign-v2", num_envs=3)
    assert isinstance(vec.unwrapped, GripperDesignVectorEnv)
    for mode in ("sync", "async"):
        _assert_same_trace(traces[mode], traces["vector_entry_point"],
                           info_keys=("radius_m", "_radius_m", "_final_obs"))


def test_next_step_autoreset_is_still_available():
    env = GripperDesignVectorEnv(3, autoreset_mode=AutoresetMode.NEXT_STEP)
    steps = _run_vec(env)[1:]
    assert steps[0][2].all() and not steps[0][3].any()
    assert not steps[1][2].any() and np.all(steps[1][1] == 0.0)  # the reset step


def test_same_step_autoreset_agrees_with_sync():
    same = AutoresetMode.SAME_STEP
    sync = _run_vec(gym.make_vec("GripperDesign-v2", num_envs=3, vectorization_mode="sync",
                                 vector_kwargs={"autoreset_mode": same}))
    ours = _run_vec(GripperDesignVectorEnv(3, autoreset_mode=same))
    _assert_same_trace(sync, ours, info_keys=("radius_m", "_radius_m", "_final_obs"))
    for sa, sb in zip(sync[1:], ours[1:], strict=True):
        assert sb[2].all()
        np.testing.assert_array_equal(np.stack(sa[4]["final_obs"]),
                                      np.stack(sb[4]["final_obs"]))
        np.testing.assert_array_equal(sa[4]["final_info"]["reward"],
                                      sb[4]["final_info"]["reward"])


def test_vector_env_rejects_bad_actions():
    env = GripperDesignVectorEnv(2)
    env.reset(seed=0)
    with pytest.raises(ValueError):
        env.step(np.zeros((3, 6)))
    bad = np.zeros((2, 6))
    bad[1, 2] = np.nan
    with pytest.raises(ValueError):
        env.step(bad)


def test_rendered_grasp_is_the_scored_grasp_with_calibration_fields():
    from envs.design_env import _render_frame

    disk = SoftDisk(0.07, 0.0, stiffness_scale=1.7, contour_stiffness_ratio=2.5)
    design = np.array([0.2, 0.8, 0.025, 0.01, 0.3, 0.013])
    model = resolve_model()  # the default member, calibrated: the scored one
    out = evaluate_designs(design[None, :], disk)
    assert out["converged"][0]
    cache: dict = {}
    frame = _render_frame(design, disk, 0.15, model, {}, cache)  # the default spring
    assert frame.ndim == 3 and frame.shape[2] == 3
    assert cache["result"].converged
    np.testing.assert_allclose(cache["result"].jaw_angles_rad, out["jaw_angles_rad"][0],
                               rtol=0, atol=1e-12)


@pytest.mark.parametrize("value,match", [
    (np.nan, r"n_triangles must be an integer in \[4, 500\], got nan"),
    (20.7, r"n_triangles must be an integer in \[4, 500\], got 20.7"),
    (0, r"n_triangles = 0 is outside the allowed range \[4, 500\]"),
    ([20, "a"], r"n_triangles\[1\] must be an integer"),
])
def test_evaluate_names_a_bad_mesh_size(value, match):
    designs = np.array([[0.2, 0.785, 0.025, 0.01, 0.2, 0.013]] * 2)
    with pytest.raises(ValueError, match=match):
        evaluate_designs(designs, DISK, n_triangles=value, element="spring")


def test_a_nan_row_is_reported_and_the_others_answered():
    good = [0.2, 0.785, 0.025, 0.01, 0.2, 0.013]
    designs = np.array([good, [np.nan, *good[1:]], good])
    # named: which row, which field (status NOT_FINITE), the others answered
    with pytest.warns(InputWarning, match=r"1 of 3 design rows .* \(row 1: finger_length_m = "
                                          r"nan; rows 1\)"):
        out = evaluate_designs(designs, DISK, friction_coefficients=1.0)
    np.testing.assert_array_equal(out["valid_at_rest"], [True, False, True])
    np.testing.assert_array_equal(out["converged"], [True, False, True])
    w = RewardWeights()
    assert out["status"][1] == NOT_FINITE and out["reward"][1] == -(w.invalid + w.violation)
    for kind in (np.array([["0.2"] * 6]), np.ones((1, 6), dtype=bool)):  # numpy's numbers
        with pytest.raises(ValueError, match=r"^designs must be an array of numbers"):
            evaluate_designs(kind, DISK)
    # the good rows are answered as if alone: a grasp with both fingers
    assert out["reward"][0] == out["reward"][2] > -1.0
    assert out["touching"][[0, 2]].all()
    assert all(np.isfinite(v).all() for v in out.values() if v.dtype.kind == "f")


@pytest.mark.parametrize("value,match", [
    (20.7, r"n_triangles must be an integer in \[4, .*got 20.7"),
    (100000, r"n_triangles = 100000 is outside the allowed range \[4, 500\]: beyond N = 500"),
    (np.nan, r"n_triangles must be an integer"),
])
def test_envs_check_the_mesh_size_at_construction(value, match):
    # at construction, not at the first step; 20.7 is not N = 20
    with pytest.raises(ValueError, match=match):
        GripperDesignEnv(n_triangles=value, element="spring")
    with pytest.raises(ValueError, match=match):
        GripperDesignVectorEnv(2, n_triangles=value, element="spring")
    with pytest.raises(ValueError, match="weights must be None or a RewardWeights"):
        GripperDesignEnv(weights={"contact": 1.0})


def test_fingers_that_merely_touch_score_no_contact():
    """A torque tuned so that the torsion springs stop the fingers just at the object (contact
    forces ~1e-7 N; CMA-ES found this design when contact was counted by force > 0 alone): the
    grip share is ~0 and so is the contact score; a squeeze keeps most of its torque."""
    touch = np.array([[0.4563, math.radians(28.01), 0.0031, 0.0076, 0.0185, 0.2323]])
    out = evaluate_designs(touch, DISK)
    assert out["converged"][0] and out["touching"][0].all()
    assert out["n_contacts"][0].sum() > 0 and out["total_force_n"][0].max() < 1e-3
    assert out["grip_share"][0] < 1e-3 and out["contact_score"][0] < 1e-4
    squeeze = evaluate_designs(paper_designs([0.2]), DISK)
    theta = squeeze["jaw_angles_rad"][0]
    spring = 0.073 * (GRIPPER.rest_angle_rad - theta)  # no stop: the rest grips
    assert squeeze["grip_share"][0] == pytest.approx(np.min(1 - spring / 0.2), rel=1e-12)
    assert 0.5 < squeeze["grip_share"][0] < 1.0
    k = hertz_arc_coefficient(DISK.radius_m, DISK.thickness_m, DISK.youngs_modulus_pa,
                              DISK.poisson_ratio, DISK.radius_m)
    shares = np.minimum(_extents(paper_designs([0.2])[0], 40, "nhquad"),
                        k * np.sqrt(squeeze["total_force_n"][0]))
    assert squeeze["contact_score"][0] == pytest.approx(
        squeeze["grip_share"][0] * shares.sum(), rel=1e-9)


def test_object_draws_follow_the_stated_distribution():
    """Radius, modulus, thickness and density log-uniform, Poisson ratio, strain limit,
    friction, payload factor and placement tolerance uniform (KS tests at 4000 draws),
    independent, every draw inside its range; a degenerate range gives its value."""
    from scipy import stats

    from envs.design_env import ObjectDistribution

    dist = ObjectDistribution()
    rng = np.random.default_rng(5)
    draws = [dist.sample(rng) for _ in range(4000)]
    disks = [d[0] for d in draws]
    columns = {
        "radius_range_m": (np.array([d.radius_m for d in disks]), True),
        "youngs_modulus_range_pa": (np.array([d.youngs_modulus_pa for d in disks]), True),
        "thickness_range_m": (np.array([d.thickness_m for d in disks]), True),
        "density_range_kg_m3": (np.array([d.density_kg_m3 for d in disks]), True),
        "poisson_ratio_range": (np.array([d.poisson_ratio for d in disks]), False),
        "strain_limit_range": (np.array([d[1] for d in draws]), False),
        "friction_range": (np.array([d[2] for d in draws]), False),
        "payload_factor_range": (np.array([d[3] for d in draws]), False),
        "placement_tolerance_range_rel": (np.array([d[4] for d in draws]), False),
    }
    unit = []
    for name, (values, log) in columns.items():
        low, high = getattr(dist, name)
        assert np.all((values >= low) & (values <= high)), name
        u = ((np.log(values) - math.log(low)) / (math.log(high) - math.log(low)) if log
             else (values - low) / (high - low))
        assert stats.kstest(u, "uniform").pvalue > 1e-3, name
        unit.append(u)
    # nine independent draws, not one number reused (|r| ~ 0.016 for independent ones)
    corr = np.corrcoef(np.array(unit))
    assert np.max(np.abs(corr - np.eye(len(columns)))) < 0.08
    disk = draws[0][0]
    assert disk.distance_m == 0.0 and disk.stiffness_scale == 1.0
    fixed = ObjectDistribution(radius_range_m=(0.07, 0.07), youngs_modulus_range_pa=(5e4, 5e4),
                               strain_limit_range=(0.1, 0.1), friction_range=(0.4, 0.4))
    disk, limit, mu, _, _ = fixed.sample(rng)
    assert disk.youngs_modulus_pa == pytest.approx(5e4, rel=1e-12) and limit == 0.1
    assert mu == 0.4 and disk.radius_m == pytest.approx(0.07, rel=1e-12)


@SAME_OBJECT_STEPS
def test_a_placement_tolerance_scores_the_worst_of_the_nine_placements():
    """With a tolerance the env's reward is the worst of the 9 placements of the +-tau box,
    as envs.scenarios.evaluate_scenarios scores the same designs (one physical spring, the
    nominal object's); never above the centred placement's reward, and below it for some
    design; without a tolerance it is the one grasp of evaluate_designs."""
    from envs.design_env import GripperDesignEnv
    from envs.model.defaults import PAPER_TORSION_STIFFNESS_REL
    from envs.scenarios import Scenarios, evaluate_scenarios

    disk = Scene.preset("paper-r070").disk
    a = np.random.default_rng(4).uniform(-1, 1, (6, 6))
    env = GripperDesignEnv()
    options = {"disk": disk, "strain_limit": 0.1, "friction_coefficient": 0.5,
               "payload_factor": 2.0, "placement_tolerance_rel": 0.1}
    env.reset(seed=0, options=options)
    steps = [env.step(row) for row in a]
    rewards = np.array([s[1] for s in steps])
    nominal = np.array([s[4]["reward_nominal"] for s in steps])
    table = evaluate_scenarios(
        env.bounds.scale(a, disk), disk, Scenarios.of(placement_tolerance_m=0.1 * disk.radius_m),
        torsion_stiffness_nm_per_rad=PAPER_TORSION_STIFFNESS_REL * disk.torque_unit_nm,
        friction_coefficient=0.5, strain_limits=0.1, payload_factors=2.0)
    assert len(table.scenarios) == 9
    np.testing.assert_allclose(rewards, table.summary["reward"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(nominal, table.summary["reward_nominal"], rtol=1e-9, atol=1e-12)
    assert np.all(rewards <= nominal) and np.any(rewards < nominal - 1e-3)
    env.reset(seed=0, options={**options, "placement_tolerance_rel": 0.0})
    exact = np.array([env.step(row)[1] for row in a])
    np.testing.assert_array_equal(exact, nominal)


@SAME_OBJECT_STEPS
def test_payload_and_tolerance_are_observed_as_ratios():
    """The payload ratio f rho g pi r / (s E) and the tolerance over the radius are observed:
    a 20x smaller, 50x softer disk 2.5x lighter, with the same relative tolerance, looks the
    same and scores the same relative designs alike; a heavier payload is observed higher;
    no payload is observed at the range's floor; bad options and distributions are named."""
    from envs.design_env import GripperDesignEnv, ObjectDistribution, observe, payload_ratio

    paper = Scene.preset("paper-r070").disk
    small = SoftDisk(0.0035, 0.0, youngs_modulus_pa=2e3, poisson_ratio=0.45, thickness_m=0.01,
                     density_kg_m3=paper.density_kg_m3 * 20.0 / 50.0)
    # the payload W = f m g in the force unit s E t r (the torque unit over r)
    assert payload_ratio(paper, 2.0) == pytest.approx(
        paper.payload_n(2.0) / (paper.torque_unit_nm / paper.radius_m), rel=1e-12)
    a = np.random.default_rng(9).uniform(-1, 1, (4, 6))
    seen, scored = [], []
    for disk in (paper, small):
        env = GripperDesignEnv()
        obs, _ = env.reset(seed=0, options={"disk": disk, "strain_limit": 0.1,
                                            "friction_coefficient": 0.5,
                                            "payload_factor": 2.0,
                                            "placement_tolerance_rel": 0.15})
        seen.append(obs)
        scored.append([env.step(row)[1] for row in a])
    np.testing.assert_allclose(seen[0], seen[1], atol=1e-6)
    np.testing.assert_allclose(scored[0], scored[1], atol=1e-6)
    light, heavy, none = (observe(paper, 0.1, 0.5, f, 0.1) for f in (0.5, 2.0, 0.0))
    assert light[4] < heavy[4] and none[4] == -1.0
    assert observe(paper, 0.1, 0.5, 2.0, 0.5)[5] == 1.0
    env = GripperDesignEnv()
    with pytest.raises(ValueError, match="payload_factor"):
        env.reset(options={"payload_factor": -1.0})
    with pytest.raises(ValueError, match="placement_tolerance_rel"):
        env.reset(options={"placement_tolerance_rel": 0.6})
    with pytest.raises(ValueError, match="payload ratio"):
        ObjectDistribution(payload_factor_range=(0.0, 100.0))
