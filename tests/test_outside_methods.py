"""The methods of other libraries (Nevergrad, Optuna, pycma's restarts) on the package's
problem: the registry, the drivers' contract (exact budget, whole batches, seeds) and the CLI.

Budgets are small; the scene is the paper's r = 0.07 m disk with straight jaws (thousands of
designs a second).
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from optim import METHODS, DesignProblem, OptimResult, optimize
from optim.optimize import FAMILY_METHODS, check_options, get_optimizer, option_names

SCENE = "paper-r070"
STRAIN_LIMIT = 0.15


def make_problem() -> DesignProblem:
    return DesignProblem.from_scene(SCENE, STRAIN_LIMIT)


# --- the registry -----------------------------------------------------------------------------


def test_the_registry_lists_the_prefixed_methods_its_modules_run():
    from optim import cma_restarts, ng_methods, optuna_methods

    listed = {"ng": ng_methods.LISTED, "optuna": optuna_methods.LISTED,
              "cma": cma_restarts.STRATEGIES}
    assert set(FAMILY_METHODS) == {f"{p}:{n}" for p, names in listed.items() for n in names}
    assert set(FAMILY_METHODS) < set(METHODS)
    for method in FAMILY_METHODS:
        assert callable(get_optimizer(method))
    # any optimizer of Nevergrad's registry, not only the listed ones
    assert callable(get_optimizer("ng:PSO"))


@pytest.mark.parametrize(("method", "match"), [
    ("ng:TwoPointDE", r"unknown Nevergrad optimizer 'TwoPointDE' \(close: .*TwoPointsDE"),
    ("optuna:cma", r"unknown Optuna sampler 'cma'; allowed: tpe, random, qmc"),
    ("cma:lpop", r"unknown pycma restart strategy 'lpop'; allowed: ipop, bipop"),
    ("foo:bar", r"unknown method 'foo:bar'; allowed: portfolio, cmaes, .*ng:NAME"),
])
def test_an_unknown_name_says_what_is_allowed(method, match):
    with pytest.raises(ValueError, match=match):
        get_optimizer(method)


def test_options_of_the_prefixed_methods():
    assert option_names("ng:NGOpt") == ("batch_size",)
    assert option_names("optuna:tpe") == ("batch_size",)
    assert option_names("cma:bipop") == ("tolfun", "tolx", "tolstagnation")
    with pytest.raises(ValueError, match=r"unknown option 'popsize' for method 'ng:NGOpt'; "
                                         r"allowed: batch_size$"):
        check_options("ng:NGOpt", {"popsize": 4})
    with pytest.raises(ValueError, match=r"batch_size must be an integer in \[1, 10000\]"):
        optimize("optuna:random", make_problem(), budget=5, batch_size=0)


# --- the drivers' contract --------------------------------------------------------------------


@pytest.mark.parametrize("method", ["ng:TwoPointsDE", "optuna:tpe", "optuna:qmc"])
def test_exact_budget_in_whole_batches_and_seeds_repeat(method):
    problem = make_problem()
    a = optimize(method, problem, budget=45, seed=3)
    assert a.method == method and a.n_evaluations == 45
    assert a.history_evaluations == (20, 40, 45)  # batches of 20, the last asked short
    assert np.all(np.diff(a.history_best_reward) >= 0)
    b = optimize(method, problem, budget=45, seed=3)
    assert a.best_design == b.best_design and a.history_best_reward == b.history_best_reward
    c = optimize(method, problem, budget=45, seed=4)
    assert c.best_design != a.best_design


@pytest.mark.parametrize(("method", "budget"), [("ng:TwoPointsDE", 200), ("optuna:tpe", 120)])
def test_outside_methods_maximize_the_reward(method, budget):
    """A search moves its samples towards higher rewards: its last designs grasp (a positive
    reward; a design that fails scores about -1) and score above its first ones. A sign slip in
    the loss would send them to the failures (random search's last 40 here: median -1.01)."""
    problem = make_problem()
    optimize(method, problem, budget=budget, seed=0)
    reward = problem.archive()["reward"]
    assert np.median(reward[-40:]) > max(np.median(reward[:20]), 0.0)


def test_cma_restarts_use_the_budget_and_leave_numpy_alone():
    np.random.seed(123)  # noqa: NPY002 (the global state pycma's BIPOP draws from)
    state = np.random.get_state()[1].copy()  # noqa: NPY002
    problem = make_problem()
    # a loose tolerance ends runs early: BIPOP restarts within this budget
    bipop = optimize("cma:bipop", problem, budget=300, seed=0, tolfun=0.01)
    assert np.array_equal(np.random.get_state()[1], state)  # noqa: NPY002 (the caller's, back)
    assert bipop.n_evaluations == 300 and bipop.extra["runs"] >= 2
    again = optimize("cma:bipop", problem, budget=300, seed=0, tolfun=0.01)
    assert again.history_best_reward == bipop.history_best_reward
    # IPOP before its first restart samples as the package's own CMA-ES (same settings)
    ipop = optimize("cma:ipop", problem, budget=40, seed=5)
    own = optimize("cmaes", problem, budget=40, seed=5)
    assert ipop.history_best_reward == own.history_best_reward


class _Captured(Exception):
    """Raised by a stand-in for ``cma.fmin2`` once it has the options it was given."""


@pytest.mark.parametrize("tolstagnation", [None, 7])
def test_cma_restarts_pass_tolstagnation_to_pycma(monkeypatch, tolstagnation):
    import cma
    given: dict = {}

    def fmin2(objective, x0, sigma0, options, **kwargs):
        given.update(options)
        raise _Captured

    monkeypatch.setattr(cma, "fmin2", fmin2)
    with pytest.raises(_Captured):
        optimize("cma:ipop", make_problem(), budget=40, seed=0, tolstagnation=tolstagnation)
    # None leaves pycma's own default (its options carry no key); an integer is passed as is
    assert given.get("tolstagnation") == tolstagnation
    assert given["tolfun"] == 1e-4 and given["tolx"] == 1e-3


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "10", "abc"])
def test_cma_restarts_refuse_a_bad_tolstagnation(bad):
    with pytest.raises(ValueError, match=r"tolstagnation must be None or an integer >= 1"):
        optimize("cma:bipop", make_problem(), budget=40, seed=0, tolstagnation=bad)


def test_ngopt_metamodel_runs_under_this_numpy(monkeypatch):
    """NGOpt picks Nevergrad's metamodel at this budget; Nevergrad 1.0.12 converts its
    one-element predictions with float(array), which numpy >= 2.4 refuses (and the process
    hung at exit): the driver mends it for the run and puts Nevergrad's module back."""
    from nevergrad.optimization import metamodel

    import optim.ng_methods as ng_methods

    calls = []
    mend = ng_methods._one_element_float
    monkeypatch.setattr(ng_methods, "_one_element_float", lambda v: calls.append(v) or mend(v))
    result = optimize("ng:NGOpt", make_problem(), budget=60, seed=0)
    assert result.n_evaluations == 60 and result.extra["selected"] == "MetaModel"
    assert calls and all(np.size(v) == 1 for v in calls)  # the metamodel's predictions
    assert "float" not in vars(metamodel)


def test_optuna_stays_quiet_and_keeps_its_verbosity(caplog):
    import optuna

    optuna.logging.set_verbosity(optuna.logging.INFO)
    optuna.logging.enable_propagation()
    try:
        with caplog.at_level(logging.INFO, logger="optuna"):
            optimize("optuna:random", make_problem(), budget=30, seed=0)
        assert not [r for r in caplog.records if r.name.startswith("optuna")]
        assert optuna.logging.get_verbosity() == optuna.logging.INFO
    finally:
        optuna.logging.disable_propagation()
        optuna.logging.set_verbosity(optuna.logging.INFO)


# --- the command line -------------------------------------------------------------------------


@pytest.mark.parametrize(("method", "stem"), [("ng:TwoPointsDE", "ng-TwoPointsDE"),
                                              ("optuna:tpe", "optuna-tpe")])
def test_cli_runs_the_outside_methods_with_the_finish_and_verdict(method, stem, tmp_path):
    from cli.main import main
    from optim.finish import RANKING_MEMBER
    from optim.verdict import verdict_exit_code

    code = main(["optimize", "--method", method, "--budget", "25", "--seed", "2", "--out",
                 str(tmp_path), "--no-progress"])
    result = OptimResult.from_json(tmp_path / f"{stem}_seed2_result.json")
    assert result.method == method and result.n_evaluations == 25
    assert (tmp_path / f"{stem}_seed2_convergence.png").stat().st_size > 0
    # reported by the finer member, as every method's optimum; exit code from the verdict of
    # its one start
    assert result.extra["reward_model"] == RANKING_MEMBER
    assert result.best_reward == result.top_designs[0]["reward"]
    assert result.extra["verdict"]["starts"] == 1
    assert code == verdict_exit_code(result.extra["verdict"])


def test_api_outside_methods_get_the_packages_finish_and_verdict(tmp_path):
    from optim.run import run_optimize

    kwargs = {"scene": SCENE, "budget": 30, "seed": 1, "progress": False, "verbose": False}
    own, _ = run_optimize("cmaes", out=tmp_path / "own", **kwargs)
    theirs, files = run_optimize("optuna:tpe", out=tmp_path / "optuna", **kwargs)
    assert files and all(path.name.startswith("optuna-tpe_seed1") for path in files.values())
    finished = {"reward_model", "search_model", "search_reward", "finish", "verdict",
                "grasp_found", "search_grasp_found"}
    assert finished <= set(own.extra) and finished <= set(theirs.extra)
    assert theirs.extra["reward_model"] == own.extra["reward_model"]
    assert theirs.extra["verdict"]["verdict"] in ("holds", "undecided")


def test_cli_refuses_an_unknown_outside_method(capsys):
    from cli.main import main

    assert main(["optimize", "--method", "ng:Nope"]) == 2
    assert "--method: unknown Nevergrad optimizer 'Nope'" in capsys.readouterr().err
