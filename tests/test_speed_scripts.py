"""The throughput script (scripts/throughput.py): it refuses a baseline that is no checkout
before any work, and one measuring process reports every figure the comparison needs."""

from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "scripts" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_baseline_that_is_no_checkout_is_refused(tmp_path, capsys):
    throughput = _script("throughput")
    with pytest.raises(SystemExit) as stop:
        throughput.main(["--baseline", str(tmp_path)])
    assert stop.value.code == 2
    assert "--baseline must be a checkout" in capsys.readouterr().err


def test_one_measurement_has_every_figure():
    throughput = _script("throughput")
    strawberry = ROOT / "examples" / "objects" / "strawberry.toml"
    args = argparse.Namespace(batch=8, scenario_designs=2, placement_mm=2.0, seed=0, fan=True,
                              scenario_jaws=["straight", "any"], objects=[strawberry],
                              object_jaws=["straight", "any"])
    row = throughput.measure(args)
    assert Path(row["envs"]) == ROOT / "envs"
    for key in ("batch_default_designs_per_s", "batch_fan_designs_per_s",
                "scenarios_independent_s", "scenarios_any_warm_cpu_s",
                "object_strawberry_straight_designs_per_s", "object_strawberry_any_s",
                "object_strawberry_any_cpu_s"):
        assert row[key] > 0.0, key
    # the medians the printed ratios are taken of (a key a checkout lacks has none)
    rows = [{"x_per_s": 1.0}, {"x_per_s": 3.0}, {"x_per_s": 2.0}]
    assert throughput._median(rows, "x_per_s") == 2.0
    assert throughput._median(rows, "missing") is None


def test_the_scenario_profile_reports_both_paths(tmp_path):
    """scripts/scenario_profile.py: both ways of a scenario batch timed and compared, and the
    fast path's own figures; the answers of the two agree."""
    profile = _script("scenario_profile")
    out = tmp_path / "p.json"
    profile.main(["--designs", "3", "--repeats", "1", "--neighbours", "--batch", "12",
                  "--leaders", "4", "--out", str(out)])
    row = json.loads(out.read_text())
    sc = row["scenarios"]
    assert sc["grasps"] == 27
    assert sc["independent_cpu_s"] > 0.0 and sc["warm_cpu_s"] > 0.0
    assert sc["converged_warm"] == sc["converged_independent"]
    assert sc["max_jaw_angle_difference_rad"] < 1e-9
    assert set(sc["warm_stages_cpu_s"]) == {"from_rest", "fast_path", "finish"}
    assert row["neighbours"]["designs"] == 12


def test_lockstep_losses_from_iteration_counts():
    """scripts/lanes_probe.py: groups of K designs run to their slowest lane; a refilled lane
    loses only the batch's end."""
    probe = _script("lanes_probe")
    even = probe.lockstep([5, 5, 5, 5], sizes=(2,))
    assert even["fixed_2"] == 1.0 and even["refill_2"] == 1.0
    # groups (1, 3) and (2, 6): lane-iterations 2 (3 + 6) = 18 for 12 useful ones
    out = probe.lockstep([1, 3, 2, 6], sizes=(2,))
    assert out["fixed_2"] == 18 / 12
    # refill: lane 0 runs 1, 2 (then 6: 9), lane 1 runs 3; the last lane ends at 9
    assert out["refill_2"] == 2 * 9 / 12
    assert out["mean_iterations"] == 3.0


@pytest.mark.slow
def test_the_lanes_probe_answers_as_the_package(tmp_path):
    """scripts/lanes_probe.py: the lane-major factor and assembly give the package's answers
    (the probe refuses to report otherwise) and every figure of the ceiling is there."""
    probe = _script("lanes_probe")
    out = tmp_path / "lanes.json"
    probe.main(["--batch", "16", "--out", str(out)])
    row = json.loads(out.read_text())
    for lanes in probe.LANE_COUNTS:
        part = row[f"lanes_{lanes}"]
        for name in ("factor", "assembly"):
            assert part[name]["max_rel_diff"] <= probe.RTOL
            assert part[name]["lanes_us"] > 0.0 and part[name]["sequential_us"] > 0.0
        ceiling = row[f"ceiling_{lanes}"]
        # the optimistic ceiling is above the parts-only one, lockstep groups below refill
        assert ceiling["all_free"] >= ceiling["parts_free"] >= ceiling["parts_fixed"]


def test_the_scenario_profile_breaks_an_object_batch_down(tmp_path):
    """scripts/scenario_profile.py --objects: an object file's own scenario batch split into
    its stages and its grasps from rest by contact, for each jaw; the shares add up."""
    profile = _script("scenario_profile")
    out = tmp_path / "w.json"
    obj = ROOT / "examples" / "objects" / "strawberry.toml"
    profile.main(["--objects", str(obj), "--designs", "2", "--repeats", "1", "--out", str(out)])
    per_jaw = json.loads(out.read_text())["where"][str(obj)]
    assert set(per_jaw) == {"straight", "any"}
    for row in per_jaw.values():
        assert row["scenarios"] == 9 and row["cpu_s"] > 0.0
        assert row["from_rest_over_warm"] > 0.0
        assert set(row["stages_cpu_s"]) == {"from_rest", "fast_path", "finish", "python"}
        rest = row["from_rest"]
        shares = [rest[k]["share_of_time"] for k in ("faces", "mouth_edge", "bar_corner")
                  if k in rest]
        assert abs(sum(shares) - 1.0) < 1e-9
        assert sum(rest[k]["rows"] for k in ("faces", "mouth_edge", "bar_corner")
                   if k in rest) == rest["rows"]
    # grooved designs lead no scenario; straight ones do
    assert per_jaw["any"]["followers_tried"] == 0 and per_jaw["straight"]["followers_tried"] > 0
    assert per_jaw["straight"]["cpu_over_straight"] == 1.0


def test_the_default_search_script_reads_runs_as_a_user_does(tmp_path, capsys):
    default_search = _script("default_search")
    puck = ROOT / "examples" / "objects" / "silicone_puck.toml"
    default_search.main([str(puck), "--seeds", "1", "--out", str(tmp_path), "--",
                         "--method", "random", "--budget", "16"])
    runs = json.loads((tmp_path / "default_search.json").read_text())["runs"]
    assert [(r["jaw"], r["seed"], r["method"], r["evaluations"]) for r in runs] == [
        ("any", 0, "random", 16), ("straight", 0, "random", 16)]
    assert all(r["wall_s"] >= r["search_s"] > 0 and r["cpu_s"] > 0 for r in runs)
    # the best known is the best run of either jaw: the shaped jaws' run is within reach
    # when it is not more than the gap below the straight bars' one
    reward = {r["jaw"]: r["reward"] for r in runs}
    reach = int(reward["any"] >= max(reward.values()) - default_search.GAP)
    assert f"within 0.01 of the best known: {reach} of 1 runs" in capsys.readouterr().out


def test_the_default_search_summary_flags_shaped_jaws_below_straight_bars():
    default_search = _script("default_search")
    rows = [{"object": "o", "jaw": jaw, "seed": seed, "reward": reward, "holds": True,
             "wall_s": 1.0, "cpu_s": 2.0}
            for jaw, seed, reward in (("any", 0, 0.30), ("straight", 0, 0.10),
                                      ("any", 1, 0.05), ("straight", 1, 0.10))]
    best = default_search.best_known(rows, {"o-any": 0.305})
    assert best == {"o": 0.305}
    text = "\n".join(default_search.summary(rows, best, 0.01))
    assert "| o | any | 0.3050 | 0.1750 (0.0500 - 0.3000) | 1 of 2 |" in text
    assert "--jaw any >= --jaw straight on 1 of 2 (object, seed) pairs: below on o seed 1" in text
    assert "within 0.01 of the best known: 1 of 2 runs (50 %)" in text


def test_the_default_search_reads_the_suites_targets_by_object_name():
    from optim.bench import load_targets, targets_stale

    default_search = _script("default_search")
    if targets_stale():
        pytest.skip("the model changed since the targets were computed")
    objects = ROOT / "examples" / "objects"
    found = default_search.suite_targets([objects / "strawberry.toml",
                                          objects / "tomatoes_friction_05.toml",
                                          objects / "liver_sample.toml"])
    targets = load_targets()
    # the example files and the suite's objects share their names; the liver is no instance
    assert found == {"strawberry": targets["strawberry-any"].reward,
                     "tomatoes_friction_05": targets["tomatoes-mu05-any"].reward}


def test_the_optimum_cost_script_times_a_runs_designs_under_each_load_set(tmp_path, capsys):
    """Each row (random designs, the run's kept designs) has a positive time as searched,
    under each load set and without a payload; the run's designs are read from its result."""
    from envs.model.loads import LOAD_SETS
    from optim import optimize
    from optim.run import object_problem

    optimum_cost = _script("optimum_cost")
    path = ROOT / "examples" / "objects" / "silicone_puck.toml"
    problem = object_problem(path, "any")
    assert problem.bounds.n_var > 6 and problem.name == "silicone puck"
    result = optimize("random", problem, budget=12, seed=0)
    saved = tmp_path / "run" / "random_seed0_result.json"
    saved.parent.mkdir()
    saved.write_text(json.dumps({"top_designs": list(result.top_designs)[:3]}))
    optimum_cost.main(["--object", str(path), "--result", str(saved), "--random", "4",
                       "--repeats", "1"])
    lines = capsys.readouterr().out.splitlines()
    header = [c.strip() for c in lines[1].strip("|").split("|")]
    assert header == ["designs", "as searched", *(f"load set {s}" for s in LOAD_SETS),
                      "no payload"]
    rows = {r.strip("|").split("|")[0].strip(): [float(v) for v in r.strip("|").split("|")[1:]]
            for r in lines[3:]}
    assert set(rows) == {"4 random designs", "run/random_seed0_result.json"}
    assert all(v > 0.0 for row in rows.values() for v in row)


def test_the_optimum_neighbours_stay_within_half_the_resolution():
    """The neighbours of a design move each length by at most half the length step, each
    angle by half the angle step, the torque by half a unit of its third figure, and keep a
    zero groove (a straight bar) at zero."""
    import numpy as np

    from envs.scene import design_mapping, design_row
    from optim.parts.resolution import DEFAULT_RESOLUTION

    optimum_neighbours = _script("optimum_neighbours")
    design = {"finger_length_m": 0.09, "rest_angle_rad": 0.3, "joint_offset_m": 0.002,
              "finger_width_m": 0.005, "torque_nm": 0.1, "distance_m": 0.03,
              "jaw_depth_m": 0.0, "jaw_bottom_radius_m": 0.02, "jaw_opening_angle_rad": 1.0,
              "jaw_position_m": 0.04}
    rows = optimum_neighbours.neighbours(design, 50, np.random.default_rng(1))
    base = design_row(design)
    assert rows.shape == (50, base.size)
    moved = [design_mapping(r) for r in rows]
    for name, value in design.items():
        got = np.array([m[name] for m in moved])
        if name.endswith("_nm"):
            limit = optimum_neighbours.TORQUE_RELATIVE_STEP * value
        elif name.endswith("_rad"):
            limit = 0.5 * DEFAULT_RESOLUTION.angle_rad
        else:
            limit = 0.0 if value == 0.0 else 0.5 * DEFAULT_RESOLUTION.length_m
        assert np.all(np.abs(got - value) <= limit + 1e-15), name
        if limit:
            assert np.ptp(got) > 0.5 * limit, name  # they do move
