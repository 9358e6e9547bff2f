"""The fast path of a scenario batch (envs.solver.follow): a row solved from its leader's answer
on the leader's contact set gives the answer of an independent solve from rest, within the
solver's tolerance, and a row the fast path does not settle is solved from rest as if it had
never been tried."""

from __future__ import annotations

import numpy as np
import pytest

from envs.evaluate import DesignBounds, evaluate_designs
from envs.model.layout import I_ITERATIONS, I_STATUS
from envs.scenarios import Scenarios, evaluate_scenarios
from envs.scene import Scene
from envs.solver import follow
from envs.solver.status import OK, POLISH_FAIL

KF = 0.073  # the paper gripper's spring [N·m/rad]


@pytest.fixture(scope="module")
def disk():
    return Scene.preset("paper-r070").disk


@pytest.fixture(scope="module")
def designs(disk) -> np.ndarray:
    return DesignBounds().sample(np.random.default_rng(5), 16, disk)


@pytest.fixture(scope="module")
def grid_answers(disk, designs):
    """A 3 x 3 grid of +-2 mm placements, from rest and from each design's nominal answer."""
    grid = Scenarios.of(placement_tolerance_m=0.002)
    common = {"torsion_stiffness_nm_per_rad": KF, "friction_coefficient": 0.5}
    cold = evaluate_scenarios(designs, disk, grid, warm_start=False, **common).per_scenario
    warm = evaluate_scenarios(designs, disk, grid, warm_start=True, **common).per_scenario
    return cold, warm


def test_followers_give_the_independent_answers(grid_answers):
    cold, warm = grid_answers
    np.testing.assert_array_equal(warm["converged"], cold["converged"])
    np.testing.assert_array_equal(warm["status"], cold["status"])
    solved = cold["converged"]
    assert solved[:, 1:].sum() >= 60  # enough followers that the comparison means something
    # the nominal scenario leads: its answer is the independent one, bit for bit
    np.testing.assert_array_equal(warm["jaw_angles_rad"][:, 0], cold["jaw_angles_rad"][:, 0])
    # the followers: the same equilibrium to the solver's tolerance (the check's force
    # balance is 1e-8 of the force scale; finger angles of ~0.2 rad agree far closer)
    np.testing.assert_allclose(warm["jaw_angles_rad"][solved], cold["jaw_angles_rad"][solved],
                               rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(warm["total_force_n"][solved], cold["total_force_n"][solved],
                               rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(warm["peak_compression"][solved],
                               cold["peak_compression"][solved], rtol=0.0, atol=1e-10)
    np.testing.assert_array_equal(warm["n_contacts"][solved], cold["n_contacts"][solved])


def test_followers_take_fewer_newton_steps(grid_answers):
    """The fast path is taken: most followers settle in a few polish steps, fewer than a
    solve from rest (a follower that falls back counts both)."""
    cold, warm = grid_answers
    solved = cold["converged"][:, 1:]
    steps_warm = warm["iterations"][:, 1:][solved]
    steps_cold = cold["iterations"][:, 1:][solved]
    assert np.median(steps_warm) < 0.7 * np.median(steps_cold)
    assert steps_warm.sum() < steps_cold.sum()
    # Newton's multipliers: from a start 2 mm off, quadratic convergence takes 3 to 4 steps
    # (the augmented Lagrangian's own update, linear at ~1e-2 a step, took a median of 6 here)
    assert np.median(steps_warm) <= 4


def test_a_follower_the_fast_path_misses_is_solved_from_rest(disk, designs, monkeypatch):
    """Where the fast path reports a failure, the row is solved from rest: bit for bit the
    answer without a leader (the fallback is the plain solve, not a second guess)."""
    rows = np.repeat(designs[:6], 2, axis=0)
    rows[1::2, 4] *= 1.05  # each odd row: its even neighbour's design, 5 % more torque
    leaders = np.where(np.arange(12) % 2 == 1, np.arange(12) - 1, -1)
    alone = evaluate_designs(rows, disk, torsion_stiffness_nm_per_rad=KF)

    real = follow.follow_batch

    def failing(*args):
        real(*args)
        args[-1][:, I_STATUS] = POLISH_FAIL  # every fast-path answer refused

    monkeypatch.setattr(follow, "follow_batch", failing)
    led = evaluate_designs(rows, disk, torsion_stiffness_nm_per_rad=KF, leaders=leaders)
    for key in ("status", "jaw_angles_rad", "reward", "total_force_n"):
        np.testing.assert_array_equal(led[key][::2], alone[key][::2])
        np.testing.assert_array_equal(led[key][1::2], alone[key][1::2])
    # the refused fast path's steps are counted on top of the plain solve's (a leader that
    # did not settle, or settled on a turned grasp, leads no fast path)
    more = led["iterations"][1::2] - alone["iterations"][1::2]
    assert np.all(more >= 0) and np.sum(more > 0) >= 3


def test_bad_leaders_are_named(disk, designs):
    with pytest.raises(ValueError, match="leaders must be integers of shape"):
        evaluate_designs(designs[:3], disk, leaders=[-1, 0])
    with pytest.raises(ValueError, match="leaders must be -1 or the index"):
        evaluate_designs(designs[:3], disk, leaders=[-1, 0, 3])
    with pytest.raises(ValueError, match="row 2 is not"):
        evaluate_designs(designs[:3], disk, leaders=[-1, 0, 1])  # a leader with a leader
    with pytest.raises(ValueError, match="leaders must be integers"):
        evaluate_designs(designs[:3], disk, leaders=[-1.0, 0.5, 0.0])
    with pytest.raises(ValueError, match="warm_start must be True or False"):
        evaluate_scenarios(designs[:2], disk, Scenarios(placement_along_m=0.001),
                           torsion_stiffness_nm_per_rad=KF, friction_coefficient=0.5,
                           warm_start="yes")


def test_grooved_jaws_are_solved_from_rest_in_every_scenario(disk):
    """The fast path places contacts on straight faces only: designs with a groove lead no
    scenario, so their scenario answers are those of independent solves, bit for bit."""
    designs = DesignBounds(jaw="any").sample(np.random.default_rng(2), 4, disk)
    grid = Scenarios.of(placement_tolerance_m=0.002)
    common = {"torsion_stiffness_nm_per_rad": KF, "friction_coefficient": 0.5}
    cold = evaluate_scenarios(designs, disk, grid, warm_start=False, **common).per_scenario
    warm = evaluate_scenarios(designs, disk, grid, warm_start=True, **common).per_scenario
    for key in ("reward", "contact_score", "peak_compression", "required_friction"):
        np.testing.assert_array_equal(np.asarray(warm[key]), np.asarray(cold[key]))


def test_a_corner_contact_leads_no_fast_path(disk, monkeypatch):
    """A nominal grasp pressed by a bar corner is not followed (the corner slides over the
    contour's edges when the object moves): its followers report no Newton step and a failure,
    the others are followed, and every scenario answer is the independent one."""
    designs = DesignBounds().sample(np.random.default_rng(0), 40, disk)
    grid = Scenarios.of(placement_tolerance_m=0.002)
    common = {"torsion_stiffness_nm_per_rad": KF, "friction_coefficient": 0.5}
    seen = []
    real = follow.follow_batch

    def spy(*args):
        corner_led = np.any(args[5] > 0.0, axis=(1, 2, 3))  # the leaders' corner forces
        real(*args)
        seen.append((corner_led, args[-1].copy()))

    monkeypatch.setattr(follow, "follow_batch", spy)
    warm = evaluate_scenarios(designs, disk, grid, warm_start=True, **common).per_scenario
    monkeypatch.setattr(follow, "follow_batch", real)
    cold = evaluate_scenarios(designs, disk, grid, warm_start=False, **common).per_scenario
    corner_led = np.concatenate([c for c, _ in seen])
    infos = np.concatenate([i for _, i in seen])
    assert corner_led.sum() >= 8 and (~corner_led).sum() >= 100
    np.testing.assert_array_equal(infos[corner_led, I_ITERATIONS], 0.0)
    assert np.all(infos[corner_led, I_STATUS] != OK)
    assert np.mean(infos[~corner_led, I_STATUS] == OK) > 0.85
    np.testing.assert_array_equal(warm["converged"], cold["converged"])
    solved = cold["converged"]
    np.testing.assert_allclose(warm["jaw_angles_rad"][solved], cold["jaw_angles_rad"][solved],
                               rtol=0.0, atol=1e-9)
