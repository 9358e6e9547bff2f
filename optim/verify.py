"""FEM verification of an optimization run: ``psm-grasp verify OUT_DIR --top K``.

The K best distinct designs of a run (:attr:`OptimResult.top_designs`) are scored again by
:func:`envs.evaluate.evaluate_designs` with the model the run used, with a finer point-spring
member that ranks designs like the FEM (:data:`RANKING_MEMBER`) and with the
finite-element reference (``fidelity="fem"``, same metrics and reward), and the three rankings
are written beside the run: ``verify.json`` and ``verify.png`` (reward per design and fidelity,
and the rankings).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from envs.evaluate import evaluate_designs
from envs.model.defaults import (
    DEFAULT_FRICTION_COEFFICIENT,
    FEM_DESIGN_RINGS,
    PAPER_TORSION_STIFFNESS_NM_PER_RAD,
)
from envs.model.loads import DEFAULT_LOAD_SET
from envs.scenarios import Scenarios, evaluate_scenarios, place_built
from envs.scene import DESIGN_FIELDS, design_row
from envs.validation import check_integer

from .charts import disk_of, model_of
from .finish import RANKING_MEMBER
from .result import OptimResult, grasp_found
from .verdict import NO_GRASP_EXIT

__all__ = ["DEFAULT_TOP", "RANKING_MEMBER", "CONFIRM_RELATIVE", "CONFIRM_ABSOLUTE",
           "NOT_CONFIRMED_EXIT", "NO_GRASP_EXIT", "confirm_margin", "confirmed", "find_result",
           "verify_result", "verify_run", "verify_figure", "verify_exit_code"]

DEFAULT_TOP = 3
# the FEM confirms the reported optimum when the reported reward lies within this share of the
# FEM's reward of that design, plus an absolute floor for optima near zero: beyond it the
# verification warns and ``psm-grasp verify`` exits with NOT_CONFIRMED_EXIT. The floor is small
# against the rewards it judges (a good grasp's reward is 0.01 to 0.05): at a reward of 0.01
# the verdict allows a gap of 11 %
CONFIRM_RELATIVE = 0.10
CONFIRM_ABSOLUTE = 1e-4
# exit code of `psm-grasp verify` (and `optimize --verify-top`, `demo`) when the FEM does not
# confirm the run's reported optimum (3 is NO_GRASP_EXIT, 2 a refused input, 1 a FEM grasp
# that did not converge)
NOT_CONFIRMED_EXIT = 4
MAX_TOP = 10  # what an OptimResult keeps
# designs whose rewards all lie this close at a fidelity are a tie there: their order is not a
# finding (a converged optimizer's best designs often differ only in fields the grasp ignores)
TIE_REWARD = 1e-3
REPORTED = ("reward", "contact_score", "grip_share", "peak_compression", "converged",
            "valid_at_rest", "status", "holds", "required_friction", "strain_limit", "touching")
# with scenarios, what the point-spring rows add: the governing scenario and whether the design
# holds in every scenario checked
SCENARIO_REPORTED = ("holds_all", "scenarios_holding", "n_scenarios", "governing_scenario")


def find_result(out_dir: str | Path, result: str | None = None) -> Path:
    """The result file of a run in ``out_dir``: ``result`` (a name in it) or its only
    ``*_result.json``; ``ValueError`` naming what was found otherwise."""
    folder = Path(out_dir)
    if not folder.is_dir():
        raise ValueError(f"OUT_DIR {str(folder)!r} is not a folder")
    if result is not None:
        path = folder / result
        if not path.is_file():
            raise ValueError(f"--result {result!r} is not a file in {str(folder)!r}")
        return path
    found = sorted(folder.glob("*_result.json"))
    if len(found) != 1:
        names = [p.name for p in found] or "none"
        raise ValueError(f"OUT_DIR {str(folder)!r} must hold exactly one *_result.json (found "
                         f"{names}); name one with --result")
    return found[0]


def confirm_margin(fem_reward: float) -> float:
    """The largest distance between a reported reward and the FEM's reward ``fem_reward`` of
    the same design that still confirms it: :data:`CONFIRM_RELATIVE` of ``|fem_reward|`` plus
    :data:`CONFIRM_ABSOLUTE` [reward units]."""
    return CONFIRM_RELATIVE * abs(float(fem_reward)) + CONFIRM_ABSOLUTE


def confirmed(reported_reward: float, fem_reward: float) -> bool:
    """Whether the FEM's reward of a design confirms the reward reported for it (within
    :func:`confirm_margin`); a NaN on either side does not confirm."""
    gap = abs(float(reported_reward) - float(fem_reward))
    return bool(gap <= confirm_margin(fem_reward))


def verify_exit_code(report: dict[str, Any]) -> int:
    """The exit code of a verification: :data:`NO_GRASP_EXIT` when the reported design does
    not hold (by the model that reported it, in every scenario checked, or by the FEM), else
    :data:`NOT_CONFIRMED_EXIT` when the FEM does not confirm the reported optimum, else 1 when
    a FEM grasp did not converge, else 0."""
    s = report["summary"]
    if not s.get("reported_holds", True):  # reports written before the verdict lack it
        return NO_GRASP_EXIT
    if not s.get("best_confirmed", True):  # reports written before the finish lack it
        return NOT_CONFIRMED_EXIT
    return 0 if s["all_fem_converged"] else 1


def _row(table: dict[str, Any], i: int, keys) -> dict[str, Any]:
    """Row ``i`` of a table's ``keys`` (those it has) as plain data."""
    from .result import to_jsonable

    return {k: to_jsonable(table[k][i]) for k in keys if k in table}


def _holds(row: dict[str, Any]) -> bool:
    """Whether a verified row holds within the strain limit (in every scenario checked)."""
    return grasp_found(row)


def _ranks(values: np.ndarray) -> list[int]:
    """1 = best (largest); ties keep the earlier design first."""
    order = np.argsort(-values, kind="stable")
    ranks = np.empty(values.size, dtype=int)
    ranks[order] = np.arange(1, values.size + 1)
    return ranks.tolist()


def verify_result(result: OptimResult, top: int = DEFAULT_TOP,
                  fem_rings: int = FEM_DESIGN_RINGS, executor=None) -> dict[str, Any]:
    """Re-score the ``top`` best distinct designs of ``result`` with its model and the FEM.

    Returns the content of ``verify.json``: per design (in the run's order, best first) its
    fields, the PSM and FEM metrics of :data:`REPORTED` and both ranks; and a summary (the
    Spearman rank correlation for three designs or more unless they are ``tied`` (rewards within
    :data:`TIE_REWARD` at either fidelity), whether both fidelities pick the same best, the
    largest reward difference, and ``best_confirmed``: the reward the run reported for its
    optimum (``reported_reward``, by ``reward_model``: the finer member after the finish of
    :mod:`optim.finish`, else the run's own model) within :func:`confirm_margin` of the
    FEM's reward of that design (10 % of it plus 1e-4), and ``reported_row``, the index of
    that design in ``designs``).
    """
    top = check_integer("--top", top, 1, MAX_TOP)
    picks = list(result.top_designs)[:top]
    if not picks and result.best_design:
        picks = [{"design": result.best_design, "reward": result.best_reward}]
    if not picks:
        raise ValueError("the run has no evaluated design to verify")
    obj = result.object
    designs = np.array([design_row(p["design"]) for p in picks])
    common = {"strain_limits": obj["strain_limit"],
              "friction_coefficients": obj.get("friction_coefficient",
                                               DEFAULT_FRICTION_COEFFICIENT),
              "torsion_stiffness_nm_per_rad": obj.get("torsion_stiffness_nm_per_rad",
                                                      PAPER_TORSION_STIFFNESS_NM_PER_RAD),
              # (a run recorded before the payload had none)
              "payload_factors": obj.get("payload_factor", 0.0),
              # (a run recorded before the load sets checked every direction)
              "load_set": obj.get("load_set", DEFAULT_LOAD_SET)}
    disk = disk_of(obj)
    model = model_of(obj)
    reward_model = result.extra.get("reward_model", model)
    scores = _scores(designs, disk, obj, common, model, reward_model, fem_rings, executor)
    psm, fine, fem = scores["psm"], scores["ranking_member"], scores["fem"]
    psm_rank, fem_rank = _ranks(psm["reward"]), _ranks(fem["reward"])
    fine_rank = _ranks(fine["reward"])
    rows = []
    for i, p in enumerate(picks):
        rows.append({
            "design": p["design"],
            "label": p.get("label", f"#{i + 1}"),
            "psm": _row(psm, i, (*REPORTED, *SCENARIO_REPORTED)),
            "ranking_member": _row(fine, i, (*REPORTED, *SCENARIO_REPORTED)),
            "fem": _row(fem, i, REPORTED),
            **({"fem_scenario": scores["fem_scenario"][i],
                "reward_model_at_fem_scenario": float(scores["model_at_fem"][i])}
               if "fem_scenario" in scores else {}),
            "psm_rank": psm_rank[i],
            "ranking_member_rank": fine_rank[i],
            "fem_rank": fem_rank[i],
        })
    # the run's reported optimum: its best design (the first pick unless it is not among them)
    best = next((i for i, p in enumerate(picks) if p["design"] == result.best_design), 0)
    reported = float(picks[best]["reward"])  # the best design's is the run's best reward
    # with scenarios the FEM solves each design in its worst scenario: it confirms the model's
    # reward there (the robust reward itself when it is the worst scenario's)
    compared = float(scores["model_at_fem"][best]) if "model_at_fem" in scores else reported
    summary: dict[str, Any] = {
        "designs": len(rows),
        "reported_row": best,
        "reported_reward": float(reported),
        "reward_model": reward_model,
        "fem_reward_of_reported": float(fem["reward"][best]),
        "confirm_margin": confirm_margin(fem["reward"][best]),
        "best_confirmed": confirmed(compared, fem["reward"][best]),
        "same_best": psm_rank.index(1) == fem_rank.index(1),
        "fem_rank_of_psm_best": fem_rank[psm_rank.index(1)],
        "max_reward_difference": float(np.max(np.abs(psm["reward"] - fem["reward"]))),
        "all_fem_converged": bool(fem["converged"].all()),
        "ranking_member_same_best": fine_rank.index(1) == fem_rank.index(1),
        "fem_rank_of_ranking_member_best": fem_rank[fine_rank.index(1)],
    }
    # does the reported design hold: by the model that reported it (in every scenario,
    # every corner of the box) and by the FEM (in the scenario it solved)
    reporting = rows[best]["ranking_member" if dict(reward_model) == dict(RANKING_MEMBER)
                           else "psm"]
    summary["reported_holds_model"] = _holds(reporting)
    summary["reported_holds_fem"] = _holds(rows[best]["fem"])
    summary["reported_holds"] = summary["reported_holds_model"] and summary["reported_holds_fem"]
    summary["tied"] = bool(np.ptp(psm["reward"]) < TIE_REWARD
                           or np.ptp(fem["reward"]) < TIE_REWARD)
    if len(rows) >= 3 and not summary["tied"]:
        from scipy.stats import spearmanr

        for key, scores in (("spearman", psm), ("ranking_member_spearman", fine)):
            rho = spearmanr(scores["reward"], fem["reward"]).statistic
            summary[key] = None if not math.isfinite(rho) else float(rho)
    return {"run": {"method": result.method, "seed": result.seed,
                    "object": obj.get("name"), "model": model},
            "ranking_member": dict(RANKING_MEMBER),
            "fem": {"rings": fem_rings, "elements": int(6 * fem_rings**2)},
            "summary": summary, "designs": rows}


def _scores(designs: np.ndarray, disk, obj: dict[str, Any], common: dict[str, Any],
            model: dict[str, Any], reward_model: dict[str, Any], fem_rings: int, executor
            ) -> dict[str, Any]:
    """The designs' metrics by the run's model, the ranking member and the FEM.

    Without scenarios each is one grasp a design. With scenarios (``obj["scenarios"]``) the
    point-spring rows are the robust summary over every corner of the scenario box
    (:func:`envs.scenarios.evaluate_scenarios` ``full=True``: the governing scenario's row and
    the envelopes) and the FEM solves each design in its worst scenario by the ranking member
    (``fem_scenario``, the design as built there), where ``model_at_fem`` is the reward
    model's reward to compare.
    """
    if not obj.get("scenarios"):
        return {"psm": evaluate_designs(designs, disk, **common, **model),
                "ranking_member": evaluate_designs(designs, disk, **common, **RANKING_MEMBER),
                "fem": evaluate_designs(designs, disk, **common, fidelity="fem",
                                        fem_rings=fem_rings, executor=executor)}
    scenarios = Scenarios.from_dict(obj["scenarios"])
    mu = common["friction_coefficients"]
    kw = {"torsion_stiffness_nm_per_rad": common["torsion_stiffness_nm_per_rad"],
          "friction_coefficient": mu, "strain_limits": common["strain_limits"],
          "payload_factors": common["payload_factors"], "load_set": common["load_set"],
          "robust": obj.get("robust", "worst")}
    psm = evaluate_scenarios(designs, disk, scenarios, **kw, **model, full=True)
    fine = evaluate_scenarios(designs, disk, scenarios, **kw, **RANKING_MEMBER, full=True)
    worst = fine.summary["worst_scenario"]
    cases = [fine.scenarios[w] for w in worst.tolist()]
    rows, disks, frictions, offsets, springs = place_built(
        designs, disk, mu, common["torsion_stiffness_nm_per_rad"], cases)
    fem = evaluate_designs(rows, disks, strain_limits=common["strain_limits"],
                           friction_coefficients=frictions, offsets_x_m=offsets,
                           payload_factors=common["payload_factors"],
                           load_set=common["load_set"],
                           torsion_stiffness_nm_per_rad=springs,
                           fidelity="fem", fem_rings=fem_rings, executor=executor)
    table = fine if dict(reward_model) == dict(RANKING_MEMBER) else psm
    pick = np.arange(designs.shape[0])
    return {"psm": psm.summary, "ranking_member": fine.summary, "fem": fem,
            "fem_scenario": [c.label for c in cases],
            "model_at_fem": table.per_scenario["reward"][pick, worst]}


def verify_figure(report: dict[str, Any], path: str | Path) -> Path:
    """PSM against FEM reward per design, and the two rankings, as a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = report["designs"]
    labels = [r.get("label", f"#{i + 1}") for i, r in enumerate(rows)]
    psm = [r["psm"]["reward"] for r in rows]
    fem = [r["fem"]["reward"] for r in rows]
    member = report.get("ranking_member")
    fine = [r["ranking_member"]["reward"] for r in rows] if member else None
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(9.5, 4.0))
    x = np.arange(len(rows))
    width = 0.27 if member else 0.4
    ax.bar(x - width, psm, width, label=f"PSM ({report['run']['model']['element']}, "
           f"N = {report['run']['model']['n_triangles']}, M = {report['run']['model']['n_rings']})",
           color="tab:blue")
    if member:
        ax.bar(x, fine, width, label=f"PSM ranking member ({member['element']}, N = "
               f"{member['n_triangles']}, M = {member['n_rings']})", color="tab:green")
    ax.bar(x + width, fem, width, label=f"FEM ({report['fem']['elements']} P2 triangles)",
           color="tab:orange")
    ax.set_xticks(x, labels, fontsize=7 if max(len(t) for t in labels) > 4 else None)
    ax.set_xlabel("design")
    ax.set_ylabel("reward")
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.legend(fontsize=8)
    s = report["summary"]
    rho = s.get("spearman")
    ax.set_title(f"{report['run']['method']} on {report['run']['object']}: max |PSM - FEM| "
                 f"{s['max_reward_difference']:.3f}", fontsize=9)
    n = len(rows)
    columns = (["psm_rank", "ranking_member_rank", "fem_rank"] if member
               else ["psm_rank", "fem_rank"])
    for i, r in enumerate(rows):
        ax2.plot(range(len(columns)), [r[c] for c in columns], "o-", color=f"C{i % 10}")
        ax2.annotate(labels[i], (0, r["psm_rank"]), xytext=(-22, -3),
                     textcoords="offset points", fontsize=8)
    ax2.set_xticks(range(len(columns)),
                   ["PSM rank", "ranking member", "FEM rank"] if member
                   else ["PSM rank", "FEM rank"])
    ax2.set_xlim(-0.4, len(columns) - 0.7)
    ax2.set_ylim(n + 0.5, 0.5)
    ax2.set_yticks(range(1, n + 1))
    ax2.set_ylabel("rank (1 = best)")
    ax2.set_title(f"a tie: rewards within {TIE_REWARD:g}" if s.get("tied") else
                  ("same best design" if s["same_best"] else
                   f"the PSM's best is the FEM's #{s['fem_rank_of_psm_best']}")
                  + (f"; Spearman {rho:.2f}" if rho is not None else ""), fontsize=9)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


OBJECT_FIELDS = ("radius_m", "youngs_modulus_pa", "poisson_ratio", "thickness_m",
                 "stiffness_scale", "strain_limit")


def _check_verifiable(result: OptimResult, path: Path) -> None:
    """What :func:`verify_result` reads of a result file is there: the object's fields and
    each kept design's six fields (and its jaw fields, all four of each finger) and reward;
    ``ValueError`` naming the file and the first missing field otherwise (a hand-edited or
    truncated result)."""
    where = f"{str(path)!r}: not a result written by psm-grasp optimize"
    missing = [k for k in OBJECT_FIELDS if k not in result.object]
    if missing:
        raise ValueError(f"{where} (its object has no {missing[0]!r})")
    for i, pick in enumerate(result.top_designs or [{"design": result.best_design,
                                                     "reward": result.best_reward}]):
        design = pick.get("design") if isinstance(pick, dict) else None
        absent = ([k for k in DESIGN_FIELDS if k not in design] if isinstance(design, dict)
                  else ["design"])
        if absent or "reward" not in pick:
            raise ValueError(f"{where} (top_designs[{i}] has no "
                             f"{(absent or ['reward'])[0]!r})")
        try:
            design_row(design)
        except ValueError as exc:
            raise ValueError(f"{where} (top_designs[{i}]: {exc})") from None


def verify_run(out_dir: str | Path, top: int = DEFAULT_TOP, *, result: str | None = None,
               fem_rings: int = FEM_DESIGN_RINGS, executor=None) -> tuple[dict, dict]:
    """Verify the run in ``out_dir``; write ``verify.json`` and ``verify.png`` there.

    Returns the report and the written paths.
    """
    path = find_result(out_dir, result)
    run = OptimResult.from_json(path)
    _check_verifiable(run, path)
    report = verify_result(run, top, fem_rings, executor)
    report["run"]["result_file"] = path.name
    folder = Path(out_dir)
    paths = {"verify": folder / "verify.json", "chart": folder / "verify.png"}
    paths["verify"].write_text(json.dumps(report, indent=1) + "\n")
    verify_figure(report, paths["chart"])
    return report, paths


def print_report(report: dict[str, Any], paths: dict[str, Path]) -> None:
    """A short table of the verification."""
    print(f"FEM verification of {report['run']['method']} on {report['run']['object']} "
          f"({report['fem']['elements']} quadratic triangles):")
    member = report.get("ranking_member")  # absent from reports written before it
    if member:
        print(f"  (ranking member: {member['element']} N = {member['n_triangles']}, M = "
              f"{member['n_rings']})")
    print("  design   PSM reward" + ("  member reward" if member else "") + "  FEM reward  "
          "PSM rank" + ("  member rank" if member else "") + "  FEM rank  FEM contact  "
          "FEM compression")
    for i, r in enumerate(report["designs"]):
        label = r.get("label", f"#{i + 1}")
        if not label.startswith("#"):
            print(f"  #{i + 1}: {label}")
        print(f"  #{i + 1:<6d} {r['psm']['reward']:10.4f}"
              + (f"  {r['ranking_member']['reward']:13.4f}" if member else "")
              + f"  {r['fem']['reward']:10.4f}  {r['psm_rank']:8d}"
              + (f"  {r['ranking_member_rank']:11d}" if member else "")
              + f"  {r['fem_rank']:8d}  {r['fem']['contact_score']:11.3f}  "
              f"{r['fem']['peak_compression']:14.3f}")
    s = report["summary"]
    print(f"  same best design: {s['same_best']}"
          + (f" (ranking member: {s['ranking_member_same_best']})" if member else "")
          + f"; max |PSM - FEM| reward {s['max_reward_difference']:.4f}"
          + (f"; Spearman {s['spearman']:.3f}" if s.get("spearman") is not None else "")
          + (f" (ranking member {s['ranking_member_spearman']:.3f})"
             if s.get("ranking_member_spearman") is not None else "")
          + (f"; the designs' rewards lie within {TIE_REWARD:g} of each other at a fidelity: "
             "a tie, their order is not a finding" if s.get("tied") else ""))
    if "reported_reward" in s:  # reports written before the finish lack it
        m = s["reward_model"]
        print(f"  reported optimum (#{_reported_row(report) + 1}): {s['reported_reward']:.4f} "
              f"(by {m.get('element')} N = {m.get('n_triangles')}, M = {m.get('n_rings')}), "
              f"FEM {s['fem_reward_of_reported']:.4f}: "
              + ("confirmed" if s["best_confirmed"] else "NOT confirmed")
              + f" (within {CONFIRM_RELATIVE:.0%} of the FEM's + {CONFIRM_ABSOLUTE:g})")
    if "reported_holds" in s:  # reports written before the verdict lack it
        print(f"  reported design holds: {'yes' if s['reported_holds_model'] else 'NO'} by "
              f"the reporting model" + (" in every scenario checked" if report["designs"][
                  _reported_row(report)].get("fem_scenario") else "")
              + f", {'yes' if s['reported_holds_fem'] else 'NO'} by the FEM")
    for name, p in paths.items():
        print(f"  {name:12s}: {p}")
    if not s.get("reported_holds", True):
        print("psm-grasp: warning: the reported design does not hold its object "
              + ("" if s["reported_holds_model"] else "in every scenario by the model that "
                 "reported it" + ("" if s["reported_holds_fem"] else " nor ")) +
              ("" if s["reported_holds_fem"] else "by the FEM") + ": do not build it",
              file=sys.stderr)
    if not s["best_confirmed"]:
        _warn_not_confirmed(report)


def _reported_row(report: dict[str, Any]) -> int:
    """Index in ``report["designs"]`` of the run's reported optimum (the first design in
    reports written before the summary named it: the run's best comes first)."""
    return int(report["summary"].get("reported_row", 0))


def _reported_metrics(report: dict[str, Any], row: dict[str, Any]) -> dict[str, Any]:
    """The metrics of ``row`` by the model that reported the run's optimum: the ranking
    member's column when it is that model (the finish), else the run's own model's."""
    member, model = report.get("ranking_member"), report["summary"].get("reward_model")
    same = member and model and all(model.get(k) == member.get(k)
                                    for k in ("element", "n_triangles", "n_rings"))
    return row["ranking_member"] if same else row["psm"]


def _warn_not_confirmed(report: dict[str, Any]) -> None:
    """One warning on stderr quoting the reported design's own terms, so that a designer sees
    which one the models disagree on (the demo's light-touch optimum: the contact, a facet of
    the point model's contour flat on a face)."""
    s = report["summary"]
    k = _reported_row(report)
    row = report["designs"][k]
    model, fem = _reported_metrics(report, row), row["fem"]
    print(f"psm-grasp: warning: the FEM does not confirm the run's reported optimum, design "
          f"#{k + 1} (reward {s.get('fem_reward_of_reported', fem['reward']):.4f} against the "
          f"reported {s.get('reported_reward', model['reward']):.4f}, more than "
          f"{CONFIRM_RELATIVE:.0%} + {CONFIRM_ABSOLUTE:g} apart; contact score "
          f"{model['contact_score']:.3f} against the FEM's {fem['contact_score']:.3f}, peak "
          f"compression {model['peak_compression']:.4f} against "
          f"{fem['peak_compression']:.4f}): check it before building it", file=sys.stderr)
