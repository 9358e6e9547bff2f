"""The cold-start compile split (envs/solver/warmup.py): its units' argument types are those
the solver compiles them with, and its helper process runs."""

from __future__ import annotations

import inspect
import subprocess

import numpy as np
import pytest

from envs import DesignBounds, SoftDisk, evaluate_designs
from envs.solver import warmup

UNITS = warmup._HELPER_UNITS + warmup._MAIN_UNITS


@pytest.fixture(scope="module", autouse=True)
def solved():
    """A batch of the default model and of the fan has run (compiled or loaded the solver)."""
    disk = SoftDisk(0.07, 0.0)
    designs = DesignBounds().sample(np.random.default_rng(1), 4, disk)
    evaluate_designs(designs, disk)
    evaluate_designs(designs, disk, element="spring", n_triangles=20)


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


def test_kernel_cache_follows_every_compiled_source_file(tmp_path):
    # numba checks a cached kernel against its own file only: the package deletes the cache
    # when any file that uses numba changes (a kernel inlines its callees from other files)
    from envs._kernel_cache import refresh_cache

    (tmp_path / "kernels.py").write_text("from numba import njit\n")
    (tmp_path / "plain.py").write_text("X = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()

    def write_cache():
        for name in ("kernels.f-1.py312.nbi", "kernels.f-1.py312.1.nbc"):
            (cache / name).write_bytes(b"x")

    write_cache()
    assert refresh_cache(tmp_path)  # nothing recorded which source wrote it: deleted
    assert not list(cache.glob("*.nb?"))
    write_cache()
    assert not refresh_cache(tmp_path)  # same source: kept
    (tmp_path / "plain.py").write_text("X = 2\n")
    assert not refresh_cache(tmp_path)  # a file without kernels changed: kept
    assert len(list(cache.glob("*.nb?"))) == 2
    (tmp_path / "kernels.py").write_text("from numba import njit  # edited\n")
    assert refresh_cache(tmp_path)
    assert not list(cache.glob("*.nb?"))
