"""A new user's audit: nine bad inputs, each refused with a ``ValueError`` naming the parameter
and what it allows (on the command line: one line ``psm-grasp: error: ...``, no traceback).

Each test reproduces one report and fails on the behaviour it describes.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import time
from fractions import Fraction
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import envs
from cli.main import BROKEN_PIPE_EXIT, main
from envs import Design, DesignBounds, GripperDesignVectorEnv, Scene, SoftDisk, simulate
from envs.design_env import ObjectDistribution
from envs.evaluate import RewardWeights, evaluate_designs
from envs.model.family import resolve_model
from envs.scene import PRESETS
from envs.validation import check_integer, check_output_dir, check_output_file, check_range
from optim import DesignProblem, optimize

ROOT = Path(__file__).resolve().parents[1]
SCENE = Scene.preset("paper-r070")
GRIPPER, DISK = PRESETS["paper-r070"]
NOT_NUMBERS = ["0.2", b"0.2", True, False, np.bool_(True), None, [0.2], np.array([0.2]),
               1 + 0j]
NUMPY_NUMBERS = [np.float64(0.2), np.float32(0.25), np.int64(3), np.int8(2), np.array(0.5),
                 Fraction(1, 4)]
# a path below which no file can be created, whoever runs the tests (root included)
UNWRITABLE = Path("/proc/psm-grasp-audit")
needs_proc = pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")


def _one_error_line(err: str, *needles: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("psm-grasp: error: "), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], (needle, err)


# --- 1, 2, 3: the validation layer refuses strings and bools everywhere ------------------------


@pytest.mark.parametrize("value", NOT_NUMBERS, ids=repr)
def test_check_range_and_check_integer_refuse_what_is_not_a_number(value):
    with pytest.raises(ValueError, match=r"^x must be a real number in \[0, 1\], got "):
        check_range("x", value, 0.0, 1.0)
    with pytest.raises(ValueError, match=r"^n must be an integer in \[0, 9\], got "):
        check_integer("n", value, 0, 9)


@pytest.mark.parametrize("value", NUMPY_NUMBERS, ids=repr)
def test_numpy_numbers_are_still_numbers(value):
    assert check_range("x", value, 0.0, 5.0) == float(value)
    if float(value).is_integer():
        assert check_integer("n", value, 0, 9) == int(value)


def test_simulate_refuses_a_string_torque():
    with pytest.raises(ValueError, match=r"torque_nm must be a real number in \[0, inf\], got "
                                         r"'0\.2' \(str\)"):
        simulate(SCENE, "0.2")


def test_simulate_refuses_a_bool_torque():
    with pytest.raises(ValueError, match=r"torque_nm must be a real number .*got True \(bool\)"):
        simulate(SCENE, True)


@pytest.mark.parametrize("value", ["40", True, "4.0e1"], ids=repr)
@pytest.mark.parametrize("entry", [
    "simulate", "evaluate_designs", "env", "gym.make", "vector env", "problem", "resolve_model",
])
def test_every_public_entry_refuses_n_triangles_that_is_not_an_integer(entry, value):
    calls = {
        "simulate": lambda: simulate(SCENE, 0.2, value),
        "evaluate_designs": lambda: evaluate_designs(np.zeros((1, 6)), DISK, n_triangles=value),
        "env": lambda: envs.GripperDesignEnv(n_triangles=value),
        "gym.make": lambda: gym.make("GripperDesign-v1", n_triangles=value),
        "vector env": lambda: GripperDesignVectorEnv(2, n_triangles=value),
        "problem": lambda: DesignProblem(DISK, n_triangles=value),
        "resolve_model": lambda: resolve_model(value, element="spring"),
    }
    with pytest.raises(ValueError, match=r"n_triangles must be an integer in \[4, \d+\], got "):
        calls[entry]()


def test_the_fan_range_check_survives_a_string():
    # check_n_triangles reads the value again to explain a too large N: not for a string
    with pytest.raises(ValueError, match=r"n_triangles must be an integer in \[4, 500\], got "
                                         r"'600' \(str\)"):
        resolve_model("600", element="spring")


# --- 4: the parameter dataclasses ---------------------------------------------------------------


def _instances():
    design = Design.from_scene(SCENE, 0.2)
    return [GRIPPER, DISK, design]


@pytest.mark.parametrize("value", ["0.01", True], ids=repr)
@pytest.mark.parametrize("instance", _instances(), ids=lambda d: type(d).__name__)
def test_every_numeric_field_of_the_dataclasses_refuses_strings_and_bools(instance, value):
    for f in dataclasses.fields(instance):
        with pytest.raises(ValueError, match=rf"^{f.name} must be a real number"):
            dataclasses.replace(instance, **{f.name: value})


def test_soft_disk_refuses_a_string_radius_and_keeps_numpy_numbers():
    with pytest.raises(ValueError, match=r"radius_m must be a real number in \(0, inf\], got "
                                         r"'0\.01' \(str\)"):
        SoftDisk(radius_m="0.01", distance_m=0.0)
    disk = SoftDisk(radius_m=np.float32(0.07), distance_m=np.int64(0))
    assert type(disk.radius_m) is float and type(disk.distance_m) is float
    design = Design(*(np.float64(v) for v in Design.from_scene(SCENE, 0.2).to_array()))
    assert all(type(getattr(design, f.name)) is float for f in dataclasses.fields(design))


def test_a_design_may_be_impossible_but_not_a_string():
    assert np.isnan(Design(0.2, 0.7, 0.0, 0.01, float("nan"), 0.0).torque_nm)
    with pytest.raises(ValueError, match="distance_m must be a real number, got '0' \\(str\\)"):
        Design(0.2, 0.7, 0.0, 0.01, 0.1, "0")


def test_the_other_parameter_dataclasses_refuse_strings():
    low = list(DesignBounds().low)
    low[4] = "0"
    with pytest.raises(ValueError, match=r"DesignBounds\.low\[torque_rel\] must be a real"):
        DesignBounds(low=tuple(low))
    with pytest.raises(ValueError, match=r"RewardWeights\.miss must be a real number"):
        RewardWeights(miss="0.5")
    with pytest.raises(ValueError, match=r"poisson_ratio_range\[i\] must be a real number"):
        ObjectDistribution(poisson_ratio_range=("0.3", 0.45))
    with pytest.raises(ValueError, match=r"radius_range_m\[i\] must be a real number"):
        ObjectDistribution(radius_range_m=(0.05, True))


# --- 5: an optimizer option it does not take ----------------------------------------------------


def test_optimize_refuses_an_unknown_option_naming_the_allowed_ones():
    problem = DesignProblem.from_scene("paper-r070")
    with pytest.raises(ValueError, match=r"unknown option 'foo' for method 'cmaes'; allowed: "
                                         r"popsize, sigma0, x0, restarts$"):
        optimize("cmaes", problem, budget=5, foo=1)
    with pytest.raises(ValueError, match=r"unknown options 'bar', 'foo' for method 'random'; "
                                         r"allowed: batch_size$"):
        optimize("random", problem, budget=5, foo=1, bar=2)
    assert problem.n_evaluations == 0  # refused before any evaluation
    with pytest.raises(ValueError, match=r"for method 'nsga2'; allowed: pop_size$"):
        optimize("nsga2", problem, budget=5, popsize=8)


def test_the_policy_method_takes_a_policy_only():
    from optim.optimize import option_names

    assert option_names("policy") == ("policy",)
    with pytest.raises(ValueError, match=r"unknown option 'verbose' for method 'policy'"):
        optimize("policy", DesignProblem.from_scene("paper-r070"), budget=10, verbose=1)


def test_run_optimize_refuses_an_unknown_option_before_any_work(tmp_path):
    from optim.run import run_optimize

    with pytest.raises(ValueError, match=r"unknown option 'foo' for method 'ga'; allowed: "
                                         r"pop_size"):
        run_optimize("ga", budget=5, out=tmp_path / "run", progress=False, foo=1)
    assert not (tmp_path / "run").exists()


# --- 6: an output path nothing can be written to ------------------------------------------------


@needs_proc
def test_output_paths_are_written_to_before_any_work():
    with pytest.raises(ValueError, match=r"--out = '/proc/psm-grasp-audit': cannot write in "
                                         r"the folder '/proc'"):
        check_output_dir("--out", UNWRITABLE)
    with pytest.raises(ValueError, match=r"--plot = '/proc/psm-grasp-audit/x\.png': "):
        check_output_file("--plot", UNWRITABLE / "x.png", (".png",))
    with pytest.raises(ValueError, match=r"cannot write in the folder '/proc'"):
        check_output_file("--plot", "/proc/psm-grasp-audit.png", (".png",))


def test_a_writable_folder_keeps_no_trace_of_the_probe(tmp_path):
    assert check_output_dir("--out", tmp_path / "new") == tmp_path / "new"
    png = tmp_path / "a.png"
    png.write_bytes(b"kept")
    assert check_output_file("--plot", png, (".png",)) == png
    assert png.read_bytes() == b"kept"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]


@needs_proc
@pytest.mark.parametrize("argv", [
    ["optimize", "--budget", "10", "--out", str(UNWRITABLE)],
    ["demo", "--out", str(UNWRITABLE)],
    ["simulate", "--plot", "/proc/psm-grasp-audit.png"],
], ids=["optimize", "demo", "simulate"])
def test_commands_refuse_an_unwritable_output_before_any_work(argv, capsys, monkeypatch):
    import envs.solver
    import optim.run

    def ran(*args, **kwargs):
        raise AssertionError("the work ran before the output path was checked")

    for module, name in ((optim.run, "run_optimize"), (optim.run, "run_demo"),
                         (envs.solver, "simulate")):
        monkeypatch.setattr(module, name, ran)
    assert main(argv) == 2
    _one_error_line(capsys.readouterr().err, argv[-2], "cannot write in the folder '/proc'")


# --- 7: a Dask scheduler that is not there ------------------------------------------------------


def test_an_unreachable_dask_scheduler_is_one_line_within_seconds(tmp_path, capsys,
                                                                  monkeypatch):
    pytest.importorskip("distributed")
    import optim.executors

    monkeypatch.setattr(optim.executors, "DASK_CONNECT_TIMEOUT_S", 1.0)
    t0 = time.perf_counter()
    code = main(["optimize", "--budget", "10", "--no-progress", "--out", str(tmp_path),
                 "--dask", "tcp://127.0.0.1:1"])
    assert time.perf_counter() - t0 < 10.0
    assert code == 2
    _one_error_line(capsys.readouterr().err, "dask = 'tcp://127.0.0.1:1'",
                    "no Dask scheduler answered there within 1 s")
    assert list(tmp_path.iterdir()) == []


# --- 8: an env whose first reset was refused ----------------------------------------------------


@pytest.mark.parametrize("bad", [
    {"options": {"strain_limit": 2.0}},
    {"options": {"strain_limit": "0.1"}},
    {"options": {"colour": "red"}},
    {"options": {"disk": SoftDisk(0.05, 0.0, poisson_ratio=-0.2)}},  # outside the observable
    {"seed": -1},
], ids=["limit", "string-limit", "unknown", "disk", "seed"])
def test_a_made_env_works_after_a_refused_first_reset(bad):
    env = gym.make("GripperDesign-v1", element="spring")
    with pytest.raises(ValueError):
        env.reset(**bad)
    obs, _ = env.reset(seed=3)
    _, reward, terminated, truncated, info = env.step(np.zeros(6, dtype=np.float32))
    assert terminated and not truncated and np.isfinite(reward) and info["converged"]
    fresh = gym.make("GripperDesign-v1", element="spring")
    np.testing.assert_array_equal(obs, fresh.reset(seed=3)[0])
    env.close()
    fresh.close()


def test_a_refused_reset_leaves_the_random_stream_as_it_was():
    env, twin = envs.GripperDesignEnv(), envs.GripperDesignEnv()
    env.reset(seed=5)
    twin.reset(seed=5)
    with pytest.raises(ValueError, match=r"strain_limit = 2\.0 is outside"):
        env.reset(seed=9, options={"strain_limit": 2.0})
    np.testing.assert_array_equal(env.reset()[0], twin.reset()[0])
    vec, vec_twin = GripperDesignVectorEnv(3), GripperDesignVectorEnv(3)
    vec.reset(seed=5)
    vec_twin.reset(seed=5)
    with pytest.raises(ValueError, match=r"strain_limit = 0\.0 is outside"):
        vec.reset(options={"strain_limit": 0.0})
    np.testing.assert_array_equal(vec.reset()[0], vec_twin.reset()[0])


def test_the_made_env_keeps_one_checker_inside_the_reset_check():
    env = gym.make("GripperDesign-v1")
    stack = "OrderEnforcing<ResetCheck<PassiveEnvChecker<GripperDesignEnv<GripperDesign-v1>>>>"
    assert str(env) == f"<{stack}>"
    again = gym.make(env.spec)  # the spec builds the same stack, not a second checker outside
    assert str(again) == str(env) and again.unwrapped is not env.unwrapped
    vec = gym.make_vec("GripperDesign-v1", num_envs=2, vectorization_mode="vector_entry_point")
    assert isinstance(vec, GripperDesignVectorEnv)


# --- 9: a reader that stops reading -------------------------------------------------------------


def test_a_closed_pipe_ends_the_command_quietly():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(
        [sys.executable, "-m", "cli", "simulate", "--json", "--element", "spring",
         "--triangles", "12"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=ROOT)
    proc.stdout.close()  # the reader is gone before the first line is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=600) == BROKEN_PIPE_EXIT
    assert "Traceback" not in err and "BrokenPipeError" not in err and "Exception" not in err
