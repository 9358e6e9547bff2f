"""sb3_vec_env: SB3's VecEnv contract, training with PPO / SAC / A2C, wrappers, seeding, errors."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

from stable_baselines3 import A2C, PPO, SAC  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.vec_env import VecEnv, VecMonitor, VecNormalize  # noqa: E402

import envs  # noqa: E402
from envs import (  # noqa: E402
    DesignBounds,
    GripperDesignEnv,
    RewardWeights,
    SoftDisk,
)
from envs.design_env import evaluate_objects  # noqa: E402
from envs.sb3_env import SB3_INSTALL_HINT, sb3_vec_env  # noqa: E402

N_ENVS = 6
SEED = 11
OBJECT_KEYS = ("radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
               "stiffness_scale", "density_kg_m3", "strain_limit", "friction_coefficient",
               "payload_factor", "placement_tolerance_rel")
NEED_KEYS = ("strain_limit", "friction_coefficient", "payload_factor", "placement_tolerance_rel")
N_OBS = 6


def actions_for(n: int, seed: int = 0) -> np.ndarray:
    """Random actions, with one row outside [-1, 1] (the env clips it)."""
    a = np.random.default_rng(seed).uniform(-1.0, 1.0, size=(n, 6)).astype(np.float32)
    a[0, 4] = 1.5
    return a


def single_env_objects(seed: int, n: int, resets: int = 1) -> list[list[dict]]:
    """Object infos of ``resets`` successive resets of single envs seeded ``seed + i``."""
    rows = []
    for i in range(n):
        env = GripperDesignEnv()
        infos = [env.reset(seed=seed + i)[1]]
        infos += [env.reset()[1] for _ in range(resets - 1)]
        rows.append(infos)
    return rows


def disk_of(info: dict) -> SoftDisk:
    return SoftDisk(info["radius_m"], 0.0, info["youngs_modulus_pa"], info["poisson_ratio"],
                    info["thickness_m"], info["stiffness_scale"],
                    density_kg_m3=info["density_kg_m3"])


def reference(actions: np.ndarray, objects: list[dict], **kwargs) -> dict[str, np.ndarray]:
    """The env's evaluation (the worst of each object's placements) on the same designs and
    objects, without the adapter."""
    disks = [disk_of(o) for o in objects]
    designs = DesignBounds().scale(np.clip(actions.astype(np.float64), -1.0, 1.0), disks)
    needs = np.array([[o[k] for k in NEED_KEYS] for o in objects])
    return evaluate_objects(designs, disks, needs, **kwargs)


@pytest.fixture()
def vec():
    env = sb3_vec_env(N_ENVS, seed=SEED)
    yield env
    env.close()


# --- the VecEnv contract -----------------------------------------------------------------------


def test_reset_observations_and_reset_infos_match_single_envs(vec):
    assert isinstance(vec, VecEnv) and vec.num_envs == N_ENVS
    assert type(vec).__name__ == "GripperDesignSB3VecEnv"
    obs = vec.reset()
    assert obs.shape == (N_ENVS, N_OBS) and obs.dtype == np.float32
    assert vec.observation_space.shape == (N_OBS,) and vec.action_space.shape == (6,)
    for i, (info,) in enumerate(single_env_objects(SEED, N_ENVS)):
        expected, _ = GripperDesignEnv().reset(seed=SEED + i)
        np.testing.assert_array_equal(obs[i], expected)
        assert vec.reset_infos[i] == info
    assert vec._seeds == [None] * N_ENVS  # seeds are used once, as in DummyVecEnv


def test_step_matches_evaluate_designs_and_follows_sb3_conventions(vec):
    obs0 = vec.reset()
    objects = single_env_objects(SEED, N_ENVS, resets=2)
    actions = actions_for(N_ENVS)
    obs1, rewards, dones, infos = vec.step(actions)
    ref = reference(actions, [o[0] for o in objects])

    assert rewards.shape == (N_ENVS,) and rewards.dtype == np.float32
    np.testing.assert_array_equal(rewards, ref["reward"].astype(np.float32))
    assert np.unique(rewards).size > 1  # different objects and designs: not a constant
    assert dones.dtype == np.bool_ and dones.all()
    assert len(infos) == N_ENVS
    env = GripperDesignEnv()
    env.reset(seed=SEED)
    *_, single_info = env.step(actions[0])
    single_keys = set(single_info)
    for i, info in enumerate(infos):
        assert set(info) == single_keys | {"terminal_observation", "TimeLimit.truncated"}
        assert info["TimeLimit.truncated"] is False
        np.testing.assert_array_equal(info["terminal_observation"], obs0[i])
        assert info["reward"] == ref["reward"][i] and type(info["reward"]) is float
        assert info["converged"] == ref["converged"][i] and type(info["converged"]) is bool
        assert type(info["iterations"]) is int
        np.testing.assert_array_equal(info["jaw_angles_rad"], ref["jaw_angles_rad"][i])
        np.testing.assert_array_equal(info["design"], DesignBounds().scale(
            np.clip(actions[i].astype(np.float64), -1, 1), disk_of(objects[i][0])))
        assert info["clipped"] is (i == 0)
        for key in OBJECT_KEYS:
            assert info[key] == objects[i][0][key]
    # the single env's info on sub-env 0 is the same, value for value
    for key, value in single_info.items():
        np.testing.assert_array_equal(infos[0][key], value, err_msg=key)
    # every sub-env reset itself: the next observation is its next object
    for i in range(N_ENVS):
        assert vec.reset_infos[i] == objects[i][1]
        assert not np.array_equal(obs1[i], obs0[i])


def test_terminal_observation_chains_over_steps(vec):
    obs = vec.reset()
    for k in range(3):
        next_obs, _, dones, infos = vec.step(actions_for(N_ENVS, seed=k))
        assert dones.all()
        for i in range(N_ENVS):
            np.testing.assert_array_equal(infos[i]["terminal_observation"], obs[i])
        obs = next_obs


def test_env_kwargs_reach_the_evaluation():
    weights = RewardWeights(contact=2.0)
    env = sb3_vec_env(3, seed=0, n_triangles=12, weights=weights,
                      torsion_stiffness_nm_per_rad=0.1, element="spring")
    env.reset()
    actions = actions_for(3)
    _, rewards, _, infos = env.step(actions)
    ref = reference(actions, [o[0] for o in single_env_objects(0, 3)], n_triangles=12,
                    weights=weights, torsion_stiffness_nm_per_rad=0.1, element="spring")
    assert [info["n_triangles"] for info in infos] == [12, 12, 12]
    np.testing.assert_array_equal(rewards, ref["reward"].astype(np.float32))
    assert env.get_attr("weights") == [weights] * 3


def test_set_options_apply_to_the_next_reset_only(vec):
    disk = SoftDisk(0.05, 0.0, 200e3)
    vec.set_options({"disk": disk, "strain_limit": 0.2, "friction_coefficient": 0.7,
                     "payload_factor": 1.0, "placement_tolerance_rel": 0.1})
    obs = vec.reset()
    assert np.all(obs == obs[0])  # every sub-env got the same object
    assert all(info["radius_m"] == 0.05 and info["strain_limit"] == 0.2
               for info in vec.reset_infos)
    assert vec._options == [{}] * N_ENVS
    assert np.unique(vec.reset()[:, 1]).size == N_ENVS  # random objects again

    # per-env options: only sub-env 2 gets the fixed disk
    options = [{} for _ in range(N_ENVS)]
    options[2] = {"disk": disk}
    vec.set_options(options)
    vec.reset()
    fixed = [info["youngs_modulus_pa"] == 200e3 for info in vec.reset_infos]
    assert fixed == [i == 2 for i in range(N_ENVS)]


def test_attributes_methods_and_wrapping(vec):
    assert vec.get_attr("n_triangles") == [40] * N_ENVS  # the default model's
    assert vec.get_attr("n_triangles", indices=[1, 4]) == [40, 40]
    assert vec.has_attr("distribution") and not vec.has_attr("no_such_attribute")
    vec.set_attr("n_triangles", 16)
    vec.reset()
    _, _, _, infos = vec.step(actions_for(N_ENVS))
    assert {info["n_triangles"] for info in infos} == {16}
    with pytest.raises(ValueError, match="all 6 sub-envs"):
        vec.set_attr("n_triangles", 12, indices=[0])
    with pytest.raises(IndexError, match=r"outside \[0, 6\)"):
        vec.get_attr("n_triangles", indices=[6])
    assert vec.env_method("__str__") == [str(vec.vector_env)] * N_ENVS
    with pytest.raises(ValueError, match="all 6 sub-envs"):
        vec.env_method("__str__", indices=2)
    assert vec.env_is_wrapped(VecMonitor) == [False] * N_ENVS
    assert vec.env_is_wrapped(VecMonitor, indices=[0, 3]) == [False, False]
    with pytest.raises(RuntimeError, match="step_async"):
        vec.step_wait()


def test_render_tiles_one_frame_per_env():
    env = sb3_vec_env(2, seed=0, render_mode="rgb_array")
    assert env.render_mode == "rgb_array"
    # as with DummyVecEnv, a step resets the sub-envs, so frames show the current objects
    # (and no design yet): give the two sub-envs visibly different disks
    env.set_options([{"disk": SoftDisk(0.05, 0.0)}, {"disk": SoftDisk(0.10, 0.0)}])
    env.reset()
    frames = env.get_images()
    assert len(frames) == 2 and frames[0].dtype == np.uint8 and frames[0].ndim == 3
    assert not np.array_equal(frames[0], frames[1])
    (frame,) = env.env_method("render", indices=[1])
    np.testing.assert_array_equal(frame, frames[1])
    tiled = env.render()
    h, w, _ = frames[0].shape
    assert tiled.shape == (2 * h, w, 3)  # SB3 tiles 2 images in a 2 x 1 grid
    np.testing.assert_array_equal(tiled[:h], frames[0])
    plain = sb3_vec_env(2, seed=0)
    plain.reset()
    with pytest.warns(UserWarning, match="rgb_array"):
        assert plain.get_images() == [None, None]


def test_class_pickles_by_name():
    env = sb3_vec_env(1)
    assert pickle.loads(pickle.dumps(type(env))) is type(env)
    assert type(env) is envs.sb3_env.GripperDesignSB3VecEnv


# --- seeding -------------------------------------------------------------------------------------


def rollout(env, steps: int = 3) -> tuple[np.ndarray, np.ndarray]:
    obs = [env.reset()]
    rewards = []
    for k in range(steps):
        o, r, _, _ = env.step(actions_for(env.num_envs, seed=k))
        obs.append(o)
        rewards.append(r)
    return np.array(obs), np.array(rewards)


def test_same_seed_same_run_other_seed_other_run():
    a_obs, a_rew = rollout(sb3_vec_env(4, seed=3))
    b_obs, b_rew = rollout(sb3_vec_env(4, seed=3))
    np.testing.assert_array_equal(a_obs, b_obs)
    np.testing.assert_array_equal(a_rew, b_rew)
    c_obs, _ = rollout(sb3_vec_env(4, seed=4))
    assert not np.array_equal(a_obs, c_obs)
    # sub-env i of seed 3 is sub-env i - 1 of seed 4: both are a single env seeded 3 + i
    np.testing.assert_array_equal(a_obs[:, 1:], c_obs[:, :-1])
    d_obs, _ = rollout(sb3_vec_env(4))
    assert not np.array_equal(a_obs, d_obs)


def test_seed_method_reseeds_the_next_reset():
    env = sb3_vec_env(3, seed=0)
    first = env.reset()
    assert env.seed(0) == [0, 1, 2]
    np.testing.assert_array_equal(env.reset(), first)
    assert not np.array_equal(env.reset(), first)  # the seeds were used once


def test_action_space_is_seeded():
    a = sb3_vec_env(2, seed=9).action_space.sample()
    b = sb3_vec_env(2, seed=9).action_space.sample()
    np.testing.assert_array_equal(a, b)


def test_ppo_trains_exactly_as_on_make_vec_env():
    """Same seed: the batched env feeds PPO the same data as SB3's DummyVecEnv of single envs."""
    kwargs = {"n_steps": 8, "batch_size": 16, "n_epochs": 1, "gamma": 0.0, "seed": 2,
              "device": "cpu", "policy_kwargs": {"net_arch": [16]}}
    batched = PPO("MlpPolicy", sb3_vec_env(4), **kwargs).learn(64)
    dummy = PPO("MlpPolicy", make_vec_env(envs.ENV_ID, n_envs=4), **kwargs).learn(64)
    np.testing.assert_array_equal(batched.rollout_buffer.rewards, dummy.rollout_buffer.rewards)
    np.testing.assert_array_equal(batched.rollout_buffer.observations,
                                  dummy.rollout_buffer.observations)
    for p, q in zip(batched.policy.parameters(), dummy.policy.parameters(), strict=True):
        np.testing.assert_array_equal(p.detach().numpy(), q.detach().numpy())


# --- training ------------------------------------------------------------------------------------


def test_ppo_learns_on_it():
    model = PPO("MlpPolicy", sb3_vec_env(8), n_steps=16, batch_size=32, n_epochs=2, gamma=0.0,
                seed=0, device="cpu", policy_kwargs={"net_arch": [32]}).learn(256)
    assert model.num_timesteps == 256
    rewards = model.rollout_buffer.rewards
    # (a placement within the tolerance may put the disk onto a finger: invalid, >= -4.5)
    assert rewards.shape == (16, 8) and np.all((rewards >= -4.5) & (rewards <= 0.5))
    assert np.unique(rewards).size > 10
    action, _ = model.predict(np.zeros(N_OBS, dtype=np.float32), deterministic=True)
    assert action.shape == (6,) and np.all(np.abs(action) <= 1.0)


def test_sac_learns_on_it_and_stores_terminal_observations():
    model = SAC("MlpPolicy", sb3_vec_env(8), learning_starts=32, batch_size=32, gamma=0.0,
                buffer_size=1000, seed=0, device="cpu", policy_kwargs={"net_arch": [32]})
    model.learn(200)
    assert model.num_timesteps == 200
    buf = model.replay_buffer
    assert buf.pos == 25  # 200 transitions in rows of 8
    # every episode is one step on one object: the stored next observation must be the
    # terminal one (the same object), not the freshly reset object's
    np.testing.assert_array_equal(buf.next_observations[:25], buf.observations[:25])
    assert np.all(buf.dones[:25] == 1.0) and np.all(buf.timeouts[:25] == 0.0)
    assert np.all((buf.rewards[:25] >= -4.5) & (buf.rewards[:25] <= 0.5))


def test_a2c_learns_on_it():
    model = A2C("MlpPolicy", sb3_vec_env(8), n_steps=5, gamma=0.0, seed=0, device="cpu",
                policy_kwargs={"net_arch": [32]}).learn(200)
    assert model.num_timesteps == 200
    assert np.all(model.rollout_buffer.episode_starts == 1.0)  # every step starts an episode


def test_vec_monitor_and_vec_normalize():
    env = VecNormalize(VecMonitor(sb3_vec_env(8, seed=1)), gamma=0.0)
    obs = env.reset()
    raw_before = env.get_original_obs()
    _, norm_rewards, dones, infos = env.step(actions_for(8))
    raw_rewards = env.get_original_reward()
    assert dones.all()
    for i, info in enumerate(infos):
        assert info["episode"]["l"] == 1
        assert info["episode"]["r"] == pytest.approx(raw_rewards[i], abs=1e-6)
        # VecNormalize normalizes the terminal observation like the observation it was
        np.testing.assert_allclose(info["terminal_observation"],
                                   env.normalize_obs(raw_before[i]), rtol=1e-6, atol=1e-6)
    assert not np.allclose(obs, raw_before)  # observations are really normalized
    assert not np.allclose(norm_rewards, raw_rewards)
    model = PPO("MlpPolicy", env, n_steps=16, batch_size=32, n_epochs=1, gamma=0.0, seed=0,
                device="cpu", policy_kwargs={"net_arch": [16]}).learn(128)
    assert model.num_timesteps == 128
    assert len(model.ep_info_buffer) == 100  # VecMonitor's episodes reach SB3's logger
    assert all(ep["l"] == 1 for ep in model.ep_info_buffer)


# --- arguments -----------------------------------------------------------------------------------


@pytest.mark.parametrize("num_envs", [0, -2, 1.5, 2.0, True, "4", None])
def test_bad_num_envs(num_envs):
    with pytest.raises(ValueError, match=r"num_envs must be an integer >= 1"):
        sb3_vec_env(num_envs)


@pytest.mark.parametrize("seed", [-1, 2**32, 1.5, True, "0"])
def test_bad_seed(seed):
    with pytest.raises(ValueError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
        sb3_vec_env(2, seed=seed)


def test_bad_env_kwargs():
    with pytest.raises(ValueError, match="autoreset_mode"):
        sb3_vec_env(2, autoreset_mode="NextStep")
    with pytest.raises(ValueError, match="render_mode"):
        sb3_vec_env(2, render_mode="human")
    with pytest.raises(ValueError, match="torsion_stiffness_nm_per_rad"):
        sb3_vec_env(2, torsion_stiffness_nm_per_rad=-1.0)
    env = sb3_vec_env(2, seed=0)
    env.reset()
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((3, 6), dtype=np.float32))
    with pytest.raises(ValueError, match="unknown reset options"):
        env.set_options({"radius": 0.1})
        env.reset()


def test_missing_sb3_gives_the_install_hint(monkeypatch):
    from envs import sb3_env

    monkeypatch.setitem(sys.modules, "stable_baselines3.common.vec_env.base_vec_env", None)
    sb3_env._sb3_class.cache_clear()
    try:
        with pytest.raises(ImportError, match=r"pip install 'psm-grasp\[rl\]'"):
            sb3_vec_env(2)
    finally:
        sb3_env._sb3_class.cache_clear()
    assert "psm-grasp[rl]" in SB3_INSTALL_HINT


def test_importing_the_module_does_not_import_sb3():
    code = ("import sys, envs.sb3_env; "
            "assert 'stable_baselines3' not in sys.modules, 'eager import'; print('ok')")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=False, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
