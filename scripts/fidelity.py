"""How far the point-spring model's ranking of designs can be trusted: PSM against FEM rewards.

For each paper disk, ``--designs`` random designs of :class:`envs.evaluate.DesignBounds` are
scored by :func:`envs.evaluate.evaluate_designs` at ``fidelity="psm"`` (the default model, the
paper's springs-only fan and finer nh-quad members beside it, each with its shipped scale
where its ring count has one, and their cost a design) and at ``fidelity="fem"`` (the
finite-element reference, cached on disk per design). Over the designs valid at rest that
converged at both fidelities (invalid designs get the same penalty at both and would only
inflate the agreement) it reports:

- the Spearman rank correlation of the PSM and FEM reward (target >= 0.95), and of each reward
  term that varies (the contact score, the peak compression) and of the strains beside them;
- whether the PSM's best design is the FEM's best, and the FEM reward it gives away (regret);
- the reward error (mean and largest |PSM - FEM|);
- the default model's reward Spearman at other strain limits (``--strain-limits``): how the
  agreement depends on the weight of deformation against contact.

``--jaw cradle|vee|any`` draws the random designs with grooved jaws (writes
``out/fidelity_{jaw}.json`` and ``.png``). Writes ``out/fidelity.json`` and
``out/fidelity.png`` (PSM against FEM reward per design, one
panel per disk). The FEM costs ~0.3-1 s per design; ``--workers`` runs it in processes.

Usage::

    python scripts/fidelity.py [--designs 100] [--seed 0] [--workers 2] [--quick]
                               [--members 80x2 96x6 120x6 160x8]
                               [--strain-limits 0.05 0.15 0.2]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.stats import bootstrap, spearmanr

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.evaluate import DesignBounds, evaluate_designs  # noqa: E402
from envs.model.family import resolve_model  # noqa: E402
from envs.scene import Scene  # noqa: E402

SCENES = ("paper-r050", "paper-r070", "paper-r100")
MODELS = {"default": {}, "paper fan": {"element": "spring"}}
# finer nh-quad members (N x rings; the shipped calibration where there is one, M <= 6): how
# the ranking follows refinement, and its cost
MEMBERS = ((80, 2), (96, 6), (120, 6), (160, 8))
TERMS = ("reward", "contact_score", "peak_compression", "peak_log_strain", "peak_strain")


def rank_agreement(psm: dict, fem: dict, rows: np.ndarray) -> dict:
    """Spearman correlations, best-design agreement and reward error over ``rows``."""
    out: dict = {"designs": int(rows.size)}
    if rows.size < 3:
        return out
    for key in TERMS:
        a, b = psm[key][rows], fem[key][rows]
        out[f"spearman_{key}"] = (float(spearmanr(a, b).statistic)
                                  if np.ptp(a) > 0 and np.ptp(b) > 0 else None)
    p, f = psm["reward"][rows], fem["reward"][rows]
    best_psm, best_fem = int(np.argmax(p)), int(np.argmax(f))
    out["same_best"] = bool(best_psm == best_fem)
    out["fem_rank_of_psm_best"] = int(np.sum(f > f[best_psm])) + 1
    out["fem_regret"] = float(f[best_fem] - f[best_psm])
    err = np.abs(p - f)
    out["reward_error_mean"] = float(err.mean())
    out["reward_error_max"] = float(err.max())
    out["spearman_reward_ci95"] = spearman_interval(p, f)
    # a design held by one fidelity and not by the other: the reward's largest steps (a tier),
    # so the designs a rank correlation turns on
    out["tier_flips"] = int(np.sum(psm["holds"][rows] != fem["holds"][rows]))
    return out


def spearman_interval(psm: np.ndarray, fem: np.ndarray, draws: int = 2000,
                      seed: int = 0) -> list[float] | None:
    """The 95 % percentile bootstrap interval of the reward Spearman over designs resampled
    in pairs: how far the figure of one sample of random designs can be trusted."""
    if np.ptp(psm) == 0 or np.ptp(fem) == 0:
        return None
    res = bootstrap((psm, fem), lambda a, b: spearmanr(a, b).statistic, paired=True,
                    vectorized=False, n_resamples=draws, method="percentile",
                    random_state=np.random.default_rng(seed))
    return [float(res.confidence_interval.low), float(res.confidence_interval.high)]


def parse_members(ap: argparse.ArgumentParser, values: list[str]) -> list[tuple[int, int]]:
    """``NxM`` strings as (N, M) nh-quad members, each checked by the model family before any
    FEM runs (a bad one exits with the parser's message)."""
    members = []
    for text in values:
        parts = text.lower().split("x")
        if len(parts) != 2 or not all(p.isdigit() for p in parts):
            ap.error(f"--members takes NxM values (e.g. 96x6), got {text!r}")
        n_pts, rings = int(parts[0]), int(parts[1])
        try:
            # as evaluated below: the shipped scale where the ring count has one (M <= 6)
            resolve_model(n_pts, rings, "nhquad", None)
        except ValueError as exc:
            ap.error(f"--members {text}: {exc}")
        members.append((n_pts, rings))
    return members


def model_table(members) -> dict[str, dict]:
    """The models scored against the FEM: the default, the paper's fan and ``members``."""
    table = dict(MODELS)
    for n_pts, rings in members:
        table[f"nh-quad {n_pts}x{rings}"] = {"n_triangles": n_pts, "n_rings": rings}
    return table


def limit_sensitivity(designs: np.ndarray, scene: Scene, executor, limits) -> dict:
    """Spearman of the default model's reward against the FEM's at other strain limits (the
    weight of deformation against contact; the FEM is read from its cache)."""
    out = {}
    for lim in limits:
        fem = evaluate_designs(designs, scene.disk, fidelity="fem", executor=executor,
                               strain_limits=lim)
        psm = evaluate_designs(designs, scene.disk, strain_limits=lim)
        rows = np.flatnonzero(fem["valid_at_rest"] & fem["converged"] & psm["converged"])
        out[str(lim)] = float(spearmanr(psm["reward"][rows], fem["reward"][rows]).statistic)
    return out


def run_scene(name: str, n: int, seed: int, executor, models: dict,
              limits: tuple[float, ...] = (), jaw: str = "straight") -> dict:
    scene = Scene.preset(name)
    designs = DesignBounds(jaw=jaw).sample(np.random.default_rng(seed), n, scene.disk)
    t0 = time.perf_counter()
    fem = evaluate_designs(designs, scene.disk, fidelity="fem", executor=executor)
    fem_s = time.perf_counter() - t0
    entry: dict = {"scene": name, "designs": n, "fem_wall_s": fem_s,
                   "fem_converged": int(fem["converged"].sum()),
                   "valid_at_rest": int(fem["valid_at_rest"].sum()), "models": {}}
    for label, kw in models.items():
        t0 = time.perf_counter()
        psm = evaluate_designs(designs, scene.disk, **kw)
        psm_s = time.perf_counter() - t0
        rows = np.flatnonzero(fem["valid_at_rest"] & fem["converged"] & psm["converged"])
        entry["models"][label] = {
            "psm_wall_s": psm_s,
            "psm_ms_per_design": 1e3 * psm_s / n,
            "psm_converged": int((psm["converged"] & psm["valid_at_rest"]).sum()),
            **rank_agreement(psm, fem, rows),
            "rows": rows.tolist(),
            "psm_reward": psm["reward"].tolist(),
        }
    entry["fem_reward"] = fem["reward"].tolist()
    entry["fem_status"] = fem["status"].tolist()
    entry["spearman_by_strain_limit"] = limit_sensitivity(designs, scene, executor, limits)
    return entry


def chart(results: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(4.4 * len(results), 4.4),
                             squeeze=False)
    for ax, entry in zip(axes[0], results, strict=True):
        fem = np.asarray(entry["fem_reward"])
        lo, hi = np.inf, -np.inf
        for (label, m), style in zip(entry["models"].items(), (("o", "C0"), ("x", "C3")),
                                     strict=False):
            rows = np.asarray(m["rows"], dtype=int)
            if rows.size == 0:
                continue
            psm = np.asarray(m["psm_reward"])[rows]
            rho = m.get("spearman_reward")
            ax.scatter(fem[rows], psm, marker=style[0], color=style[1], s=18,
                       label=f"{label}: Spearman {rho:.3f}" if rho is not None else label)
            lo, hi = min(lo, fem[rows].min(), psm.min()), max(hi, fem[rows].max(), psm.max())
        if np.isfinite(lo):
            ax.plot([lo, hi], [lo, hi], color="0.6", lw=0.8, label="PSM = FEM")
        ax.set_xlabel("FEM reward")
        ax.set_ylabel("PSM reward")
        ax.set_title(f"{entry['scene']}: {entry['models']['default']['designs']} valid designs")
        ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=None,
                    help="FEM in this many spawned processes (default: in process)")
    ap.add_argument("--quick", action="store_true", help="12 designs of paper-r070 only")
    ap.add_argument("--members", nargs="*", default=[f"{a}x{b}" for a, b in MEMBERS],
                    help="finer nh-quad members NxM scored beside the default (none: skip)")
    ap.add_argument("--strain-limits", nargs="*", type=float, default=[0.05, 0.15, 0.2],
                    help="also rank the default model at these strain limits (default 0.10)")
    ap.add_argument("--jaw", default="straight", choices=("straight", "cradle", "vee", "any"),
                    help="random designs of this jaw design space (default straight)")
    ap.add_argument("--out", default="out")
    args = ap.parse_args(argv)
    scenes = ("paper-r070",) if args.quick else SCENES
    n = 12 if args.quick else args.designs
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    models = model_table(parse_members(ap, args.members))  # checked before any pool starts
    executor = None
    if args.workers:
        from optim.executors import ProcessExecutor

        executor = ProcessExecutor(args.workers)
    results = []
    try:
        for name in scenes:
            entry = run_scene(name, n, args.seed, executor, models, tuple(args.strain_limits),
                              args.jaw)
            results.append(entry)
            print(f"{name}: {entry['valid_at_rest']} of {n} valid, FEM "
                  f"{entry['fem_converged']} converged in {entry['fem_wall_s']:.0f} s")
            if entry["spearman_by_strain_limit"]:
                print("  default model at other strain limits: Spearman reward " + ", ".join(
                    f"{lim} {rho:.3f}" for lim, rho in entry["spearman_by_strain_limit"].items()))
            for label, m in entry["models"].items():
                terms = ", ".join(
                    f"{k} {m[f'spearman_{k}']:.3f}" for k in TERMS[1:]
                    if m.get(f"spearman_{k}") is not None)
                ci = m.get("spearman_reward_ci95") or (float("nan"),) * 2
                print(f"  {label:14s}: Spearman reward "
                      f"{m.get('spearman_reward', float('nan')):.3f}"
                      f" [95 % {ci[0]:.3f}-{ci[1]:.3f}], tier flips {m.get('tier_flips')}"
                      f" ({terms}); same best {m.get('same_best')}, FEM rank of the PSM's best "
                      f"{m.get('fem_rank_of_psm_best')}, regret {m.get('fem_regret', 0):.4f}; "
                      f"|error| mean {m.get('reward_error_mean', 0):.4f} max "
                      f"{m.get('reward_error_max', 0):.4f}; {m['psm_ms_per_design']:.1f} ms a "
                      "design")
    finally:
        if executor is not None:
            executor.close()
    stem = "fidelity" if args.jaw == "straight" else f"fidelity_{args.jaw}"
    (out / f"{stem}.json").write_text(json.dumps(
        {"designs": n, "seed": args.seed, "jaw": args.jaw, "scenes": results}, indent=1) + "\n")
    chart(results, out / f"{stem}.png")
    print(f"wrote {out / f'{stem}.json'} and {out / f'{stem}.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
