"""The cold-start compile split (envs/solver/warmup.py): its units' argument types are those
the solver compiles them with, and its helper process runs."""

from __future__ import annotations

import inspect
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from envs import DesignBounds, SoftDisk, evaluate_designs
from envs.scenarios import Scenarios, evaluate_scenarios
from envs.solver import warmup

UNITS = warmup._HELPER_UNITS + warmup._MAIN_UNITS + warmup._FINAL_UNITS


@pytest.fixture(scope="module", autouse=True)
def solved():
    """A batch of the default model, of the fan and of placements has run (compiled or
    loaded the solver)."""
    disk = SoftDisk(0.07, 0.0)
    designs = DesignBounds().sample(np.random.default_rng(1), 4, disk)
    evaluate_designs(designs, disk)
    evaluate_designs(designs, disk, element="spring", n_triangles=20)
    # and a scenario batch, whose placements follow their nominal answers (the follow entry)
    evaluate_scenarios(designs, disk, Scenarios.of(placement_tolerance_m=0.002),
                       torsion_stiffness_nm_per_rad=0.073, friction_coefficient=0.5)


@pytest.mark.parametrize(("module", "name", "spec"), UNITS, ids=[u[1] for u in UNITS])
def test_unit_types_are_the_solvers(module, name, spec):
    dispatcher = warmup.unit_dispatcher(module, name)
    sig = warmup.unit_signature(spec)
    assert len(sig) == len(inspect.signature(dispatcher.py_func).parameters)
    misses = sum(dispatcher.stats.cache_misses.values())
    dispatcher.compile(sig)
    # the solver's own specialization (in memory or in the cache): nothing compiled anew
    assert sum(dispatcher.stats.cache_misses.values()) == misses
    assert warmup.kernels_cached()
    # and the only one on disk: a unit precompiled with other types would sit in numba's
    # index beside the one the solver compiled (the check above passes for both)
    cached = {key[0] for key in dispatcher._cache._cache_file._load_index()}
    assert cached == {sig}


def test_warm_started_solves_add_no_specialization():
    # a warm start's arrays come in any memory order (N = 200 starts from the transposed
    # prolongation of a coarse answer): the pipeline hands the kernels C order, so the
    # entries keep one specialization each
    from envs.scene import Scene
    from envs.solver import simulate, simulate_ramp

    scene = Scene.preset("paper-r070")
    simulate(scene, 0.05, 200, element="spring")  # (the fan may fold: only its start counts)
    simulate_ramp(scene, [0.1, 0.2], 20, element="spring")
    for module, name in warmup._ENTRIES:
        dispatcher = warmup.unit_dispatcher(module, name)
        assert len({key[0] for key in dispatcher._cache._cache_file._load_index()}) == 1


def test_helper_process_runs():
    done = subprocess.run(warmup._helper_command(), env=warmup._helper_env(),
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]


def test_warm_cache_compiles_nothing():
    assert warmup.precompile() is False
    assert warmup.announce_compile() is False


def _double(x):
    return 2.0 * x


def test_kernel_cache_folder_follows_every_source_file(tmp_path, monkeypatch):
    # numba checks a cached kernel against its own file only; the package's kernels live in a
    # folder named by a digest of all its source, so any edit (a callee, a constant of a plain
    # module) starts a new folder, and the process's numba setting is put back afterwards
    import numba

    from envs import _kernel_cache as kc

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    (tmp_path / "kernels.py").write_text("from numba import njit\n")
    (tmp_path / "layout.py").write_text("SLOT = 1\n")
    first = kc.source_digest(tmp_path)
    (tmp_path / "layout.py").write_text("SLOT = 3\n")  # no kernel in it, read by kernels
    second = kc.source_digest(tmp_path)
    assert first != second
    before = numba.config.CACHE_DIR
    with kc.kernel_cache(tmp_path) as folder:
        assert folder == tmp_path / "__pycache__" / f"numba-{second}"
        assert numba.config.CACHE_DIR == str(folder)
        kernel = numba.njit(cache=True)(_double)
    assert numba.config.CACHE_DIR == before
    assert Path(kernel.stats.cache_path).is_relative_to(folder)
    assert kernel(2.0) == 4.0
    # older versions' folders: the newest KEEP_OLD are kept (a process may still run them)
    for k in range(kc.KEEP_OLD + 2):
        old = tmp_path / "__pycache__" / f"numba-old{k}"
        old.mkdir()
        os.utime(old, (1e9 + k, 1e9 + k))
    with kc.kernel_cache(tmp_path):
        pass
    left = sorted(p.name for p in (tmp_path / "__pycache__").glob("numba-*"))
    assert left == sorted([f"numba-{second}", "numba-old2", "numba-old3"])
    # a user's own NUMBA_CACHE_DIR holds the package's folder
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert kc.kernel_cache_dir("abc", tmp_path) == tmp_path / "mine" / "psm-grasp-numba-abc"


def test_the_package_kernels_are_cached_by_source_version():
    from envs import _kernel_cache as kc
    from envs.solver import driver

    folder = kc.kernel_cache_dir(kc.source_digest())
    assert Path(driver.solve_rows.stats.cache_path).is_relative_to(folder)


def test_a_failed_compile_split_warns_and_stops_its_helper(monkeypatch):
    # best effort: the first solve compiles what is missing, so a failure only warns, and the
    # helper process is stopped rather than waited for
    import sys
    import time

    monkeypatch.setattr(warmup, "kernels_cached", lambda: False)
    monkeypatch.setattr(warmup, "_helper_command",
                        lambda: [sys.executable, "-c", "import time; time.sleep(60)"])

    def broken(units):
        raise TypeError("a unit's signature does not match")

    monkeypatch.setattr(warmup, "_compile_units", broken)
    t0 = time.perf_counter()
    with pytest.warns(RuntimeWarning, match="compile split failed"):
        assert warmup.precompile() is True
    assert time.perf_counter() - t0 < 30.0


def test_a_pool_worker_announces_without_splitting(monkeypatch, capsys):
    import multiprocessing

    monkeypatch.setattr(warmup, "kernels_cached", lambda: False)
    monkeypatch.setattr(warmup, "_announced", False)
    split = []
    monkeypatch.setattr(warmup, "precompile", lambda: split.append(True) or True)
    monkeypatch.setattr(multiprocessing, "parent_process", lambda: object())
    assert warmup.announce_compile()
    assert "in this worker process" in capsys.readouterr().err
    assert split == []


def test_a_batch_of_one_adds_no_specialization():
    # a column of the solution's metrics table is a strided view (numba's layout "A"), but
    # contiguous for a batch of one ("C"): the metrics kernel gets C-order copies, so a single
    # design after a batch (the environment's step) compiles it no second time
    from envs.scoring import psm_metrics_rows

    disk = SoftDisk(0.07, 0.0)
    designs = DesignBounds().sample(np.random.default_rng(2), 3, disk)
    evaluate_designs(designs[:1], disk)
    evaluate_designs(designs, disk)
    assert len(psm_metrics_rows.signatures) == 1
