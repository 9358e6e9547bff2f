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


def test_helper_process_runs():
    done = subprocess.run(warmup._helper_command(), env=warmup._helper_env(),
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]


def test_warm_cache_compiles_nothing():
    assert warmup.precompile() is False
    assert warmup.announce_compile() is False
