"""A designer's first hour: options checked before work, honest output, safe executors.

Each test reproduces one report of the issue and fails on the behaviour it describes.
"""

from __future__ import annotations

import importlib.util
import json
import multiprocessing
import re
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

import envs
from cli.main import main
from envs.evaluate import DesignBounds, evaluate_designs
from envs.scene import PRESETS, Scene
from envs.solver.status import PUBLIC_STATUS

ROOT = Path(__file__).resolve().parents[1]
GRIPPER, DISK = PRESETS["paper-r070"]


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# --- options and output paths are checked before any work ----------------------------------


def test_simulate_checks_the_plot_path_first(tmp_path, capsys):
    missing = tmp_path / "no_such_dir" / "grasp.png"
    assert main(["simulate", "--plot", str(missing)]) == 2
    err = capsys.readouterr().err
    assert "--plot" in err and str(missing) in err and "does not exist" in err
    assert not missing.parent.exists()  # no folder created behind the user's back
    txt = tmp_path / "grasp.txt"
    assert main(["simulate", "--plot", str(txt)]) == 2
    assert "must end in .png" in capsys.readouterr().err and not txt.exists()
    png = tmp_path / "grasp.png"
    assert main(["simulate", "--plot", str(png)]) == 0
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_simulate_reports_solve_and_kernel_load_apart(capsys):
    assert main(["simulate", "--triangles", "12"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"solve time\s+: [\d.]+ ms, \d+ iterations", out)
    assert re.search(r"kernel load\s+: \d+ ms \(first call in this process", out)
    assert main(["simulate", "--triangles", "12", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["kernel_load_s"] >= 0.0 and data["solve_time_s"] > 0.0


@pytest.mark.parametrize("argv,match", [
    (["--triangles", "0", "--element", "spring"],
     r"--triangles/--rings/--element: n_triangles = 0 is outside the allowed range \[4, 500\]"),
    (["--triangles", "600", "--element", "spring"], r"beyond N = 500 most solves fail"),
    (["--triangles", "2001"], r"n_triangles = 2001 is outside the allowed range \[4, 2000\]"),
    (["--rings", "1", "--element", "nhquad"], r"n_rings = 1 is outside the allowed range"),
    (["--budget", "0"], r"--budget: budget must be an integer in \[1, 10,000,000\] .*got 0"),
    (["--budget", "1000000000000"], r"--budget: budget = 1,000,000,000,000 is outside the "
                                    r"allowed range \[1, 10,000,000\]"),
    (["--strain-limit", "1.5"], r"--strain-limit: strain_limit = 1.5 is outside"),
])
def test_optimize_checks_options_before_any_evaluation(argv, match, tmp_path, capsys,
                                                       monkeypatch):
    import optim.run

    def no_run(*args, **kwargs):
        raise AssertionError("the optimizer ran before the options were checked")

    monkeypatch.setattr(optim.run, "run_optimize", no_run)
    assert main(["optimize", "--out", str(tmp_path), *argv]) == 2
    assert re.search(match, capsys.readouterr().err)


def test_optimize_checks_the_output_folder_first(tmp_path, capsys, monkeypatch):
    import optim.run

    monkeypatch.setattr(optim.run, "run_optimize", lambda *a, **k: pytest.fail("ran"))
    a_file = tmp_path / "results.txt"
    a_file.write_text("not a folder")
    assert main(["optimize", "--out", str(a_file / "x")]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and str(a_file / "x") in err and "is not a folder" in err


def test_a_run_without_a_grasp_warns_and_fails(tmp_path, capsys, monkeypatch):
    import optim.run
    from optim.problem import DesignProblem

    def no_torque(problem: DesignProblem, *, budget: int, seed: int, **options):
        # zero torque: the fingers stay at rest, clear of the disk
        problem.start(budget)
        problem.evaluate(np.array([[0.0, 0.0, 0.0, 0.0, -1.0, 0.0]] * budget))
        return problem.result("stub", seed)

    monkeypatch.setattr(optim.run, "get_optimizer", lambda method: no_torque)
    code = main(["optimize", "--budget", "2", "--out", str(tmp_path), "--no-progress"])
    # one start cannot say that nothing holds: no verdict about the object (not exit 3)
    assert code == optim.run.UNDECIDED_EXIT != 0
    err = capsys.readouterr().err
    assert "no design that holds was found in 2 evaluations" in err and "does not touch" in err
    assert "one start" in err
    data = json.loads((tmp_path / "portfolio_seed0_result.json").read_text())
    assert data["extra"]["grasp_found"] is False


def test_a_run_with_a_grasp_is_flagged_found(tmp_path):
    from optim.run import run_optimize

    result, _ = run_optimize("random", scene="forceps-a", budget=40, seed=0, out=tmp_path,
                             progress=False, verbose=False)
    assert result.extra["grasp_found"] is True
    assert result.best_metrics["valid_at_rest"] and all(result.best_metrics["touching"])


# --- no internal status in public results ---------------------------------------------------


def test_only_public_statuses_reach_results():
    rng = np.random.default_rng(9)
    low = np.array([0.05, 0.26, 0.0, 0.002, 0.0, 0.0])
    high = np.array([0.30, 1.31, 0.05, 0.03, 1.0, 0.06])
    designs = low + rng.uniform(0, 1, (300, 6)) * (high - low)
    for n in (8, 60):
        status = evaluate_designs(designs, DISK, n_triangles=n, element="spring")["status"]
        assert set(np.unique(status).tolist()) <= set(PUBLIC_STATUS), n


# --- executors --------------------------------------------------------------------------------


def test_a_forking_process_pool_works_after_the_kernels_ran_here():
    # the batch rows run on Python threads (envs.parallel), not on numba's OpenMP pool, which a
    # child forked after it started could not use (it would crash the pool)
    designs = DesignBounds().sample(np.random.default_rng(0), 8, DISK)
    here = evaluate_designs(designs, DISK)  # the kernels and the row threads ran here
    pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork"))
    try:
        there = evaluate_designs(designs, DISK, executor=pool, chunk_size=3)
    finally:
        pool.shutdown()
    for key in ("reward", "jaw_angles_rad", "status"):
        np.testing.assert_array_equal(there[key], here[key])


def test_tasks_carry_enough_designs_to_pay():
    from optim.executors import SerialExecutor
    from optim.problem import MIN_CHUNK_SIZE, DesignProblem

    class TwoWorkers(SerialExecutor):
        n_workers = 2

    problem = DesignProblem(DISK, executor=TwoWorkers())
    assert problem._chunk_size_for(9) == MIN_CHUNK_SIZE >= 64  # a CMA-ES population: 1 task
    assert problem._chunk_size_for(1000) == 500  # one task per worker


# --- honest figures ---------------------------------------------------------------------------


def test_grasp_drawing_has_a_legend_and_a_labelled_strain_scale():
    from envs.render import grasp_figure

    scene = Scene(GRIPPER, DISK)
    fig = grasp_figure(scene, envs.simulate(scene, 0.2, 20, element="spring"))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    for needed in ("contact, right", "contact, left", "rest (dashed)", "centre (pinned)"):
        assert needed in labels
    assert "compressed" in fig.axes[1].get_ylabel() and "stretched" in fig.axes[1].get_ylabel()
    # no contact marker is drawn in a colour of the strain map's red end
    faces = [line.get_markerfacecolor() for line in fig.axes[0].get_lines()
             if line.get_label().startswith("contact")]
    assert faces and all(face not in ("tab:red", "red") for face in faces)


def test_best_so_far_bands_never_go_down():
    compare = _script("compare_optimizers")
    from optim.result import OptimResult

    def run(evals, best):
        return OptimResult("ppo", 0, 100, {}, best[-1], {}, evals, best, evals, 100, 1.0)

    # a weak run whose first probe comes late would pull a median over started runs down
    runs = [run((10, 100), (0.22, 0.23)), run((10, 100), (0.21, 0.22)),
            run((60, 100), (0.10, 0.11))]
    b = compare.band(runs, np.linspace(1, 100, 100), "evaluations")
    med = b["median"][np.isfinite(b["median"])]
    assert med.size > 10 and np.all(np.diff(med) >= 0)


def test_convergence_chart_curves_are_monotone():
    from optim.charts import convergence_figure
    from optim.result import OptimResult

    res = OptimResult("cmaes", 0, 30, {}, 0.2, {}, (10, 20, 30), (0.1, 0.15, 0.2),
                      (0.1, 0.2, 0.3), 30, 0.3)
    fig: Figure = convergence_figure([res])
    ys = fig.axes[0].get_lines()[0].get_ydata()
    assert np.all(np.diff(ys) >= 0)


def test_the_forceps_objects_are_observable():
    # the forceps' TPU (calibration scale 0.033) is observable: the observation is scale-free
    from envs.design_env import observe

    for name in PRESETS:
        obs = observe(Scene.preset(name).disk, 0.1, 0.5)
        assert np.all(np.abs(obs) <= 1.0)


def test_compile_notice_only_when_the_kernels_are_not_cached(tmp_path, monkeypatch, capsys):
    """A warm cache prints nothing; a cold one (no cache index files) names the wait."""
    import envs.solver.warmup as warmup

    envs.simulate(envs.Scene.preset("paper-r070"), 0.2, 20,
        element="spring")  # the kernels are cached now
    assert warmup.kernels_cached()
    assert not warmup.announce_compile()
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(warmup, "_cache_dir", lambda module, name: tmp_path)  # empty
    # a process announces (and splits the compile) once: as if it had not yet
    monkeypatch.setattr(warmup, "_announced", False)
    compiled = []
    monkeypatch.setattr(warmup, "precompile", lambda: compiled.append(True) or True)
    assert not warmup.kernels_cached()
    assert warmup.announce_compile()
    assert "compiling the solver's kernels" in capsys.readouterr().err
    assert compiled == [True]  # and it starts the two-process compile


def test_the_fidelity_script_accepts_its_default_members():
    # a member without a shipped scale (8 rings have none) is valid: evaluated, a member takes
    # the shipped scale where there is one
    import argparse

    fidelity = _script("fidelity")
    ap = argparse.ArgumentParser()
    defaults = [f"{a}x{b}" for a, b in fidelity.MEMBERS]
    assert fidelity.parse_members(ap, defaults) == list(fidelity.MEMBERS)
    with pytest.raises(SystemExit):
        fidelity.parse_members(ap, ["96x0"])
