"""Charts of optimizer results: convergence, best grasp, Pareto front.

Figures are built with :class:`matplotlib.figure.Figure` (Agg, no pyplot state), like
:mod:`envs.render`, and saved as PNG.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from envs.evaluate import N_DESIGN
from envs.model.defaults import (
    DEFAULT_CONTOUR_STIFFNESS_RATIO,
    DEFAULT_DENSITY_KG_M3,
    PAPER_N_TRIANGLES,
    PAPER_TORSION_STIFFNESS_NM_PER_RAD,
)
from envs.model.jaw import jaws_of_row
from envs.objects import as_object, outline_fields
from envs.render import draw_design, draw_grasp, grasp_figure
from envs.scene import Design, Scene, SoftDisk, design_row

from .build_sheet import assembly_of
from .result import OptimResult, front_point

__all__ = ["scene_of", "convergence_figure", "best_grasp_figure", "pareto_figure",
           "scenario_figure"]

SCENARIO_LABELS_MAX = 30  # scenarios whose labels a scenario chart writes under its bars
METHOD_COLOURS = {"portfolio": "black", "cmaes": "tab:blue", "ga": "tab:green",
                  "nsga2": "tab:olive", "random": "tab:gray", "policy": "tab:purple",
                  "ng:TwoPointsDE": "tab:orange", "ng:NGOpt": "tab:red",
                  "optuna:tpe": "tab:brown", "optuna:random": "silver", "optuna:qmc": "tab:pink",
                  "cma:ipop": "tab:cyan", "cma:bipop": "navy"}


def _save(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, format="png")
    return fig


def disk_of(obj: dict[str, Any], distance_m: float = 0.0) -> SoftDisk:
    """The disk of a result's object (its placement ``distance_m``; a design replaces it)."""
    return as_object(SoftDisk(obj["radius_m"], distance_m, obj["youngs_modulus_pa"],
                              obj["poisson_ratio"], obj["thickness_m"], obj["stiffness_scale"],
                              obj.get("contour_stiffness_ratio",
                                      DEFAULT_CONTOUR_STIFFNESS_RATIO),
                              density_kg_m3=obj.get("density_kg_m3", DEFAULT_DENSITY_KG_M3)),
                     **outline_fields(obj))


def scene_of(design: dict[str, float], obj: dict[str, Any]) -> Scene:
    """The :class:`~envs.scene.Scene` of a design (dict in SI units) on a result's object.

    Raises
    ------
    ValueError
        If the design is invalid at rest (the fingers overlap the disk, ...).
    """
    disk = disk_of(obj, design["distance_m"])
    torsion = obj.get("torsion_stiffness_nm_per_rad", PAPER_TORSION_STIFFNESS_NM_PER_RAD)
    # the one Design -> Scene mapping, the one evaluate_designs scored
    return Design.from_array(design_row(design)).to_scene(disk, torsion)


def jaw_label(design: dict[str, float]) -> str:
    """The jaws of a design (dict in SI units) for a chart's title, in millimetres: ``""``
    for straight bars, else a line per distinct groove (``"\\njaws: cradle h = ..."``)."""
    row = design_row(design)
    if row.size == N_DESIGN:
        return ""
    try:
        right, left = jaws_of_row(row)
    except ValueError:  # (an impossible groove: the chart shows the bare design)
        return "\njaws: out of range"
    named = ([("jaws", right)] if left is None or left == right
             else [("right jaw", right), ("left jaw", left)])
    lines = []
    for name, jaw in named:
        text = f"{name}: {jaw.kind}"
        if jaw.depth_m > 0.0:
            text += (f" h = {jaw.depth_m * 1e3:.3g} mm, R = {jaw.bottom_radius_m * 1e3:.3g} mm, "
                     f"{math.degrees(jaw.opening_angle_rad):.0f}°, at "
                     f"{jaw.position_m * 1e3:.3g} mm")
        lines.append(text)
    return "".join("\n" + line for line in lines)


def model_of(obj: dict[str, Any]) -> dict[str, Any]:
    """The model member an optimization result was scored with, as keyword arguments of
    :func:`envs.simulate` (results written before the model family: the paper's fan)."""
    return {"n_triangles": int(obj.get("n_triangles", PAPER_N_TRIANGLES)),
            "n_rings": int(obj.get("n_rings", 1)), "element": obj.get("element", "spring"),
            "calibrated": bool(obj.get("calibrated", False))}


def _draw_design_grasp(ax, design: dict[str, float], obj: dict[str, Any], title: str,
                       legend: bool = True) -> None:
    """Solve and draw a design's grasp; fall back to the bare design if it is invalid."""
    from envs.solver import simulate

    try:
        scene = scene_of(design, obj)
    except ValueError:
        draw_design(ax, design_row(design), obj["radius_m"], title=title + " (invalid)",
                    length_unit="mm", disk=disk_of(obj))
        return
    res = simulate(scene, design["torque_nm"], **model_of(obj))
    draw_grasp(ax, scene, res, strain_limit=obj.get("strain_limit"), title=title, legend=legend,
               length_unit="mm")


def convergence_figure(results: Sequence[OptimResult], path: str | Path | None = None, *,
                       reference: float | None = None, reference_label: str = "paper gripper",
                       title: str | None = None) -> Figure:
    """Best reward so far against evaluations, one step line per result.

    Parameters
    ----------
    results
        Results to draw (colour by method).
    path
        Where to write the PNG.
    reference
        A reward drawn as a horizontal dashed line (e.g. the paper's gripper).
    reference_label, title
        Labels.
    """
    fig = Figure(figsize=(6.4, 4.2), dpi=110)
    ax = fig.add_subplot()
    for r in results:
        if not r.history_evaluations:
            continue
        label = f"{r.method} (seed {r.seed}): {r.best_reward:.4f}"
        ax.step(r.history_evaluations, r.history_best_reward, where="post",
                color=METHOD_COLOURS.get(r.method), label=label)
    if reference is not None:
        ax.axhline(reference, color="k", linestyle="--", linewidth=1,
                   label=f"{reference_label}: {reference:.4f}")
    ax.set_xlabel("evaluations")
    ax.set_ylabel("best reward so far")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(title or "convergence", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def best_grasp_figure(result: OptimResult, path: str | Path | None = None) -> Figure:
    """The best design of a result, re-solved with :func:`envs.solver.simulate` and drawn in
    millimetres (every length in its title too), the centre held where the object sits."""
    from envs.solver import simulate

    from .design_verdict import verdict_of

    obj = result.object
    d, m = result.best_design, result.best_metrics
    name = obj.get("name") or "the object"
    size = "r" if obj.get("outline_coefficients") is None else f"{obj.get('shape')}, r_eq"
    governing = m.get("governing_scenario")
    # with scenarios the numbers are the governing scenario's, the drawing the nominal grasp
    where = (f"governing scenario {governing}: " if governing is not None else "")
    banner = verdict_of(m, result.extra.get("scenario_rows")).banner
    title = ((f"{banner}\n" if banner else "")
             + f"{name}, {size} = {obj['radius_m'] * 1e3:.3g} mm: {result.method} (seed "
             f"{result.seed}) best, reward {result.best_reward:.4f}\n"
             + (f"drawn: the nominal scenario; {where}" if governing is not None else "")
             + f"contact {m.get('contact_score', math.nan):.2f}, "
             f"compression {m.get('peak_compression', math.nan):.3f}; fingers "
             f"{assembly_of(d['joint_offset_m'], d['finger_width_m'])[0]}\n"
             f"l = {d['finger_length_m'] * 1e3:.3g} mm, "
             f"θ0 = {math.degrees(d['rest_angle_rad']):.1f}°, "
             f"d3 = {d['joint_offset_m'] * 1e3:.3g} mm, w = {d['finger_width_m'] * 1e3:.3g} mm\n"
             f"d1 = {d['distance_m'] * 1e3:.3g} mm, T = {d['torque_nm']:.3g} N·m"
             + jaw_label(d))
    try:
        scene = scene_of(result.best_design, obj)
    except ValueError:
        fig = Figure(figsize=(5.5, 5.5), dpi=100)
        row = design_row(result.best_design)
        draw_design(fig.add_subplot(), row, obj["radius_m"], title=title + " (invalid)",
                    length_unit="mm", disk=disk_of(obj))
        return _save(fig, path)
    # the member that reported the metrics in the title (the finer one after the finish)
    member = result.extra.get("reward_model") or model_of(obj)
    res = simulate(scene, result.best_design["torque_nm"], **member)
    fig = grasp_figure(scene, res, strain_limit=obj.get("strain_limit"), title=title,
                       figsize=(6.0, 6.0), length_unit="mm")
    if banner:
        fig.suptitle(banner, color="white", backgroundcolor="tab:red", fontsize=9,
                     fontweight="bold")
    return _save(fig, path)


def _front_picks(front: Sequence[dict[str, Any]], n: int) -> list[int]:
    if not front:
        return []
    idx = np.unique(np.linspace(0, len(front) - 1, min(n, len(front))).round().astype(int))
    return idx.tolist()


def pareto_figure(result: OptimResult, path: str | Path | None = None, *,
                  archive: dict[str, np.ndarray] | None = None,
                  others: Sequence[OptimResult] = (), n_drawn: int = 3) -> Figure:
    """NSGA-II front (contact score up, peak compression down) with a few of its designs drawn.

    Parameters
    ----------
    result
        A result with a ``pareto_front``.
    path
        Where to write the PNG.
    archive
        Every evaluated point (:meth:`~optim.problem.DesignProblem.archive`), drawn in grey.
    others
        Single-objective results whose best designs are marked on the chart.
    n_drawn
        Front designs drawn beside the chart (spread along the front).
    """
    front = list(result.pareto_front)
    picks = _front_picks(front, n_drawn)
    fig = Figure(figsize=(4.2 + 3.0 * max(1, len(picks)), 4.4), dpi=100)
    grid = fig.add_gridspec(1, 1 + max(1, len(picks)), width_ratios=[1.5] + [1] * max(
        1, len(picks)))
    ax = fig.add_subplot(grid[0, 0])
    if archive is not None and len(archive["reward"]):
        ok = archive["feasible"]
        ax.scatter(archive["peak_compression"][ok], archive["contact_score"][ok], s=4,
                   color="0.75",
                   label="feasible evaluated")
    if front:
        contact, strain = (list(v) for v in zip(*map(front_point, front), strict=True))
        ax.step(strain, contact, where="post", color="tab:red", linewidth=1)
        ax.plot(strain, contact, "o", color="tab:red", markersize=4, label="NSGA-II front")
        for k, i in enumerate(picks):
            ax.annotate(chr(ord("A") + k), (strain[i], contact[i]), textcoords="offset points",
                        xytext=(5, -10), fontsize=9, color="tab:red")
    for r in others:
        m = r.best_metrics
        if "peak_compression" in m:
            ax.plot(m["peak_compression"], m["contact_score"], "*", markersize=11,
                    color=METHOD_COLOURS.get(r.method, "k"),
                    label=f"best {r.method} (s{r.seed}): {r.best_reward:.3f}")
    limit = result.object.get("strain_limit")
    if limit:
        ax.axvline(limit, color="k", linestyle=":", linewidth=1, label="strain limit")
    ax.set_xlabel("peak compression [-] (down)")
    ax.set_ylabel("contact score [-] (up)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title(f"Pareto front, {result.method} seed {result.seed}", fontsize=10)
    for k, i in enumerate(picks):
        sub = fig.add_subplot(grid[0, 1 + k])
        p = front[i]
        worst = "worst " if "min_contact_score" in p else ""
        _draw_design_grasp(sub, p["design"], result.object,
                           f"{chr(ord('A') + k)}: {worst}contact {contact[i]:.2f}, "
                           f"{worst}compression {strain[i]:.3f}", legend=k == 0)
    fig.tight_layout()
    return _save(fig, path)


def scenario_figure(result: OptimResult, path: str | Path | None = None) -> Figure:
    """The reported design under each scenario of its run: the reward per scenario (the
    nominal first), marked where the grasp does not hold or exceeds the strain limit, and the
    peak compression against the strain limit.

    Raises
    ------
    ValueError
        If the result has no scenario rows (a run without scenarios).
    """
    rows = result.extra.get("scenario_rows")
    if not rows:
        raise ValueError("the result has no scenario rows (a run without scenarios)")
    from .sheet.drawing import short_label

    many = len(rows) > SCENARIO_LABELS_MAX
    # many scenarios: their indices (the scenarios CSV names them), not their labels
    labels = [str(i) if many else short_label(r["scenario"]["label"]).replace(" ", "\n")
              for i, r in enumerate(rows)]
    reward = np.array([r["reward"] for r in rows])
    compression = np.array([r["peak_compression"] for r in rows])
    limit = float(rows[0]["strain_limit"])
    ok = np.array([bool(r["holds"]) and r["peak_compression"] <= r["strain_limit"]
                   for r in rows])
    fig = Figure(figsize=(min(max(6.0, 0.55 * len(rows) + 2.0), 14.0), 5.2),
                 layout="constrained")
    ax, ax2 = fig.subplots(2, 1, sharex=True)
    x = np.arange(len(rows))
    ax.bar(x, reward, color=np.where(ok, "tab:blue", "tab:red"))
    ax.axhline(float(reward.min()), color="k", lw=0.8, ls="--",
               label=f"worst {reward.min():.4f}")
    ax.set_ylabel("reward")
    ax.legend(fontsize=8, loc="lower right")
    name = result.object.get("name") or "object"
    ax.set_title(f"{result.method} design for {name} under {len(rows)} scenarios "
                 "\n(red: does not hold within the strain limit; a displaced object is "
                 "held where it was placed)", fontsize=8)
    ax2.bar(x, compression, color="tab:orange")
    ax2.axhline(limit, color="tab:red", lw=1.0, label=f"strain limit {limit:g}")
    ax2.set_ylabel("peak compression")
    ax2.legend(fontsize=8)
    step = max(1, len(rows) // 36)
    ax2.set_xticks(x[::step], labels[::step], fontsize=6)
    if many:
        ax2.set_xlabel("scenario (its row in the scenarios CSV; 0 the nominal)", fontsize=8)
    return _save(fig, path)
