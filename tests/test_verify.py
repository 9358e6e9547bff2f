"""FEM verification of an optimization run (``psm-grasp verify``, ``optimize --verify-top``)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from cli.main import main
from envs.scene import DESIGN_FIELDS
from optim import OptimResult

pytest.importorskip("skfem")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    # (the reaction alone: 60 random designs lifting the foam disk too are mostly ties in the
    # slip tier, and the subject here is the verification)
    code = main(["optimize", "--method", "random", "--budget", "60", "--seed", "4", "--out",
                 str(out), "--no-progress", "--verify-top", "3", "--payload-factor", "0"])
    result = OptimResult.from_json(out / "random_seed4_result.json")
    report = json.loads((out / "verify.json").read_text())
    # the code says what the files say: no grasp, else the FEM's verdict on the optimum
    expected = (3 if not result.extra["grasp_found"] else
                0 if report["summary"]["best_confirmed"] and report["summary"][
                    "all_fem_converged"] else
                4 if not report["summary"]["best_confirmed"] else 1)
    assert code == expected
    return out


def test_a_run_keeps_its_best_distinct_designs(run_dir):
    result = OptimResult.from_json(run_dir / "random_seed4_result.json")
    top = result.top_designs
    assert 3 <= len(top) <= 10
    rewards = [t["reward"] for t in top]
    assert rewards == sorted(rewards, reverse=True)
    assert rewards[0] == result.best_reward
    assert top[0]["design"] == result.best_design


def test_verify_rescores_the_run_and_writes_its_files(run_dir):
    report = json.loads((run_dir / "verify.json").read_text())
    assert (run_dir / "verify.png").stat().st_size > 0
    result = OptimResult.from_json(run_dir / "random_seed4_result.json")
    rows = report["designs"]
    assert len(rows) == 3
    for row, kept in zip(rows, result.top_designs, strict=False):
        assert row["design"] == kept["design"]
        # the run reports the finer member's reward (its finish) of the design rounded to the
        # manufacturing resolution, which the ranking member's column repeats exactly; the
        # PSM side is the run's own model on that rounded design
        from optim.parts.resolution import round_design

        assert round_design(row["design"]) == row["design"]
        assert row["ranking_member"]["reward"] == kept["reward"]
        assert row["psm"]["reward"] == pytest.approx(kept["search_reward"], abs=0.02)
        assert row["fem"]["valid_at_rest"]
    assert sorted(r["psm_rank"] for r in rows) == [1, 2, 3]
    assert sorted(r["fem_rank"] for r in rows) == [1, 2, 3]
    best_fem = max(range(3), key=lambda i: rows[i]["fem"]["reward"])
    assert rows[best_fem]["fem_rank"] == 1
    # rows come in the run's (the ranking member's) order; "same best" is the search model's
    psm_best = [r["psm_rank"] for r in rows].index(1)
    assert report["summary"]["same_best"] == (rows[psm_best]["fem_rank"] == 1)
    assert not report["summary"]["tied"]  # random search: three different grasps
    assert -1.0 <= report["summary"]["spearman"] <= 1.0
    diff = max(abs(r["psm"]["reward"] - r["fem"]["reward"]) for r in rows)
    assert report["summary"]["max_reward_difference"] == pytest.approx(diff)
    # the reported optimum (the run's best design, first of its kept designs) against the FEM
    s = report["summary"]
    assert rows[0]["design"] == result.best_design
    assert s["reported_reward"] == result.best_reward == rows[0]["ranking_member"]["reward"]
    assert s["reward_model"] == result.extra["reward_model"]
    fem = rows[0]["fem"]["reward"]
    assert s["fem_reward_of_reported"] == fem
    assert s["reported_row"] == 0
    assert s["confirm_margin"] == pytest.approx(0.10 * abs(fem) + 1e-4, rel=1e-12)
    assert s["best_confirmed"] == (abs(result.best_reward - fem) <= 0.10 * abs(fem) + 1e-4)


def test_designs_whose_rewards_tie_get_no_rank_correlation(run_dir, tmp_path, monkeypatch,
                                                           capsys):
    """A converged optimizer's best designs often differ only in fields the grasp ignores:
    rewards within TIE_REWARD at a fidelity are a tie, reported as such, not as a Spearman."""
    import optim.verify as verify

    result = OptimResult.from_json(run_dir / "random_seed4_result.json")
    spread = np.ptp([t["reward"] for t in result.top_designs[:3]])
    monkeypatch.setattr(verify, "TIE_REWARD", 2 * spread + 1e-9)
    report = verify.verify_result(result, top=3)
    assert report["summary"]["tied"]
    assert "spearman" not in report["summary"]
    assert "ranking_member_spearman" not in report["summary"]
    copy = tmp_path / "run"  # the other tests read the run's own verify.json
    shutil.copytree(run_dir, copy)
    code = main(["verify", str(copy), "--top", "3"])
    assert code == verify.verify_exit_code(json.loads((copy / "verify.json").read_text()))
    assert "a tie, their order is not a finding" in capsys.readouterr().out


def test_verify_reranks_with_the_finer_member(run_dir):
    # the ranking member's column is that member's own evaluation of the same designs
    from envs import evaluate_designs
    from optim.charts import disk_of
    from optim.verify import RANKING_MEMBER

    report = json.loads((run_dir / "verify.json").read_text())
    result = OptimResult.from_json(run_dir / "random_seed4_result.json")
    rows = report["designs"]
    assert report["ranking_member"] == RANKING_MEMBER
    assert RANKING_MEMBER["n_rings"] > 2 and RANKING_MEMBER["n_triangles"] > 40
    designs = np.array([[r["design"][k] for k in DESIGN_FIELDS] for r in rows])
    obj = result.object
    own = evaluate_designs(designs, disk_of(obj), strain_limits=obj["strain_limit"],
                           payload_factors=obj["payload_factor"], **RANKING_MEMBER)
    np.testing.assert_allclose([r["ranking_member"]["reward"] for r in rows], own["reward"],
                               rtol=0, atol=1e-12)
    assert sorted(r["ranking_member_rank"] for r in rows) == [1, 2, 3]
    best = min(rows, key=lambda r: r["ranking_member_rank"])
    assert best["ranking_member"]["reward"] == max(r["ranking_member"]["reward"] for r in rows)
    s = report["summary"]
    assert s["ranking_member_same_best"] == (best["fem_rank"] == 1)
    assert s["fem_rank_of_ranking_member_best"] == best["fem_rank"]
    assert -1.0 <= s["ranking_member_spearman"] <= 1.0


def test_verify_warns_when_the_fem_does_not_confirm_the_best(run_dir, capsys, monkeypatch):
    import optim.verify as verify

    monkeypatch.setattr(verify, "CONFIRM_RELATIVE", 0.0)
    monkeypatch.setattr(verify, "CONFIRM_ABSOLUTE", 0.0)  # no two fidelities agree exactly
    # a script sees it: the exit code of an unconfirmed optimum
    assert main(["verify", str(run_dir), "--top", "3"]) == verify.NOT_CONFIRMED_EXIT == 4
    err = capsys.readouterr().err
    assert "the FEM does not confirm the run's reported optimum, design #1" in err
    # with the terms the models disagree on: the reported design's own, by the model that
    # reported it (the ranking member, after the finish), from the report
    report = json.loads((run_dir / "verify.json").read_text())
    s = report["summary"]
    reported = report["designs"][s["reported_row"]]
    assert reported["design"] == OptimResult.from_json(
        run_dir / "random_seed4_result.json").best_design
    assert s["reward_model"] == report["ranking_member"]
    assert (f"contact score {reported['ranking_member']['contact_score']:.3f} against the "
            f"FEM's {reported['fem']['contact_score']:.3f}") in err
    assert f"the reported {s['reported_reward']:.4f}" in err


def test_verify_command_on_the_run_folder(run_dir, capsys):
    from optim.verify import verify_exit_code

    code = main(["verify", str(run_dir), "--top", "2"])
    printed = capsys.readouterr().out
    assert code == verify_exit_code(json.loads((run_dir / "verify.json").read_text()))
    assert "FEM verification of random on paper-r070" in printed
    report = json.loads((run_dir / "verify.json").read_text())
    assert len(report["designs"]) == 2
    designs = np.array([[r["design"][k] for k in DESIGN_FIELDS] for r in report["designs"]])
    assert np.ptp(designs, axis=0).max() > 0  # distinct designs


@pytest.mark.parametrize("args, message", [
    (["--top", "0"], "--top"),
    (["--top", "11"], "--top"),
    (["--result", "missing.json"], "--result"),
])
def test_verify_refuses_bad_options(run_dir, capsys, args, message):
    assert main(["verify", str(run_dir), *args]) == 2
    assert message in capsys.readouterr().err


def test_verify_needs_a_run(tmp_path, capsys):
    assert main(["verify", str(tmp_path)]) == 2
    assert "exactly one *_result.json" in capsys.readouterr().err
    assert main(["verify", str(tmp_path / "nowhere")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_verify_without_the_fem_extra_says_what_to_install(run_dir, capsys, monkeypatch):
    import optim.run

    monkeypatch.setattr(optim.run, "fem_available", lambda: False)
    assert main(["verify", str(run_dir)]) == 2
    assert "pip install -e '.[fem]'" in capsys.readouterr().err
    assert main(["optimize", "--budget", "10", "--out", str(run_dir), "--verify-top", "2"]) == 2
    assert "--verify-top needs scikit-fem" in capsys.readouterr().err


def test_a_report_written_before_the_ranking_member_still_prints_and_draws(run_dir, tmp_path,
                                                                            capsys):
    from optim.verify import print_report, verify_figure

    report = json.loads((run_dir / "verify.json").read_text())
    report.pop("ranking_member")
    for row in report["designs"]:
        row.pop("ranking_member")
        row.pop("ranking_member_rank")
    for key in ("ranking_member_same_best", "fem_rank_of_ranking_member_best",
                "ranking_member_spearman"):
        report["summary"].pop(key, None)  # (Spearman only for three designs or more)
    print_report(report, {})
    assert "member" not in capsys.readouterr().out
    assert verify_figure(report, tmp_path / "old.png").stat().st_size > 0
