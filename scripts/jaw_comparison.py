"""What shaped jaws buy: the best robust reward with shaped jaws against straight jaws at an
equal budget, each optimum confirmed by the FEM.

For each object (a scene preset or an object file, with its scenarios and payload), each of
``--methods`` (default CMA-ES) designs the gripper ``--seeds`` times with ``--budget``
evaluations in the straight design space and in the shaped one (``--jaw``, default ``any``:
the rounded V-groove family whose limits are the cradle and the V-groove). The best run of
each is the optimum as ``psm-grasp optimize`` reports it (re-scored by the finer member,
:mod:`optim.finish`) and the FEM re-scores it (:func:`optim.verify.verify_result`, in its
worst scenario where the object has scenarios): confirmed when within 10 % of the FEM's reward
(plus 1e-4).

Prints a table and writes ``out/jaw_comparison.json`` and ``out/jaw_comparison.png`` (the
reported and the FEM's reward per object, straight against shaped).

Usage::

    python scripts/jaw_comparison.py [--budget 1000] [--seeds 2] [--jaw any]
        [--methods cmaes nsga2]
        [--objects paper-r070 examples/objects/strawberry.toml ...] [--out out]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from envs.model.jaw import JAW_FIELDS  # noqa: E402
from envs.object_file import load_object  # noqa: E402
from envs.scene import PRESETS  # noqa: E402
from optim import NoGraspWarning  # noqa: E402
from optim.result import to_jsonable  # noqa: E402
from optim.run import run_optimize  # noqa: E402
from optim.verify import verify_result  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OBJECTS = ("paper-r070", "examples/objects/strawberry.toml",
                   "examples/objects/tomatoes_10_15mm.toml", "examples/objects/liver_sample.toml",
                   "examples/objects/silicone_puck.toml", "examples/objects/water_disk.toml")


def _target(name: str) -> dict:
    """run_optimize's object arguments of a preset name or an object file."""
    if name in PRESETS:
        return {"scene": name}
    path = Path(name) if Path(name).is_absolute() else ROOT / name
    return {"obj": load_object(path)}


def best_run(name: str, jaw: str, budget: int, seeds: int, out: Path,
             methods: tuple[str, ...] = ("cmaes",)):
    """The best of ``seeds`` runs of each method (finished, as ``optimize`` reports it)."""
    best = None
    for method in methods:
        for seed in range(seeds):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", NoGraspWarning)
                result, _ = run_optimize(method, **_target(name), budget=budget, seed=seed,
                                         out=out, jaw=jaw, progress=False, verbose=False,
                                         prefix=f"{Path(name).stem}_{jaw}_{method}_{seed}")
            if best is None or result.best_reward > best.best_reward:
                best = result
    return best


def row_of(name: str, jaw: str, budget: int, seeds: int, out: Path,
           methods: tuple[str, ...] = ("cmaes",)) -> dict:
    """One object and one design space: the reported optimum and the FEM's verdict."""
    t0 = time.perf_counter()
    result = best_run(name, jaw, budget, seeds, out, methods)
    report = verify_result(result, top=1)
    summary = report["summary"]
    design = result.best_design
    return {
        "object": result.object.get("name", name), "jaw": jaw, "method": result.method,
        "reported_reward": summary["reported_reward"],
        "fem_reward": summary["fem_reward_of_reported"],
        "confirmed": bool(summary["best_confirmed"]),
        "grasp_found": bool(result.extra.get("grasp_found")),
        "contact_score": result.best_metrics.get("contact_score"),
        "peak_compression": result.best_metrics.get("peak_compression"),
        "required_friction": result.best_metrics.get("required_friction"),
        "jaw_profile": {k: design[k] for k in JAW_FIELDS if k in design},
        "design": design, "wall_time_s": time.perf_counter() - t0,
    }


def chart(rows: list[dict], path: Path, title: str) -> None:
    """Reported and FEM reward per object, straight against shaped."""
    names = list(dict.fromkeys(r["object"] for r in rows))
    jaws = list(dict.fromkeys(r["jaw"] for r in rows))
    fig = Figure(figsize=(max(6.0, 1.6 * len(names)), 4.2), dpi=110)
    ax = fig.subplots()
    width = 0.8 / len(jaws)
    for k, jaw in enumerate(jaws):
        xs = np.arange(len(names)) + (k - (len(jaws) - 1) / 2) * width
        got = {r["object"]: r for r in rows if r["jaw"] == jaw}
        rep = [got[n]["reported_reward"] if n in got else np.nan for n in names]
        fem = [got[n]["fem_reward"] if n in got else np.nan for n in names]
        ax.bar(xs, rep, width * 0.9, label=f"{jaw}: reported", alpha=0.75,
               color=f"C{k}")
        ax.plot(xs, fem, "k_", markersize=14, markeredgewidth=2,
                label="FEM" if k == 0 else None)
    ax.set_xticks(np.arange(len(names)), names, rotation=20, fontsize=8)
    ax.axhline(0.0, color="k", linewidth=0.8)
    ax.set_ylabel("robust reward (worst scenario)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="y")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=int, default=1000, help="evaluations per run")
    ap.add_argument("--seeds", type=int, default=2, help="seeds per method and design space")
    ap.add_argument("--methods", nargs="+", default=["cmaes"],
                    choices=("cmaes", "ga", "nsga2", "random"),
                    help="the methods whose best run is the optimum (default cmaes)")
    ap.add_argument("--jaw", default="any", choices=("cradle", "vee", "any"),
                    help="the shaped design space compared with the straight one")
    ap.add_argument("--objects", nargs="+", default=list(DEFAULT_OBJECTS))
    ap.add_argument("--out", default="out")
    args = ap.parse_args(argv)
    if args.budget < 1 or args.seeds < 1:
        ap.error("--budget and --seeds must be >= 1")
    out = Path(args.out)
    rows = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as scratch:
        for name in args.objects:
            for jaw in ("straight", args.jaw):
                row = row_of(name, jaw, args.budget, args.seeds, Path(scratch),
                             tuple(args.methods))
                rows.append(row)
                print(f"{row['object']:>22s} {jaw:>8s} ({row['method']}): reported "
                      f"{row['reported_reward']:+.4f}"
                      f"  FEM {row['fem_reward']:+.4f}  "
                      f"{'confirmed' if row['confirmed'] else 'NOT confirmed'}  contact "
                      f"{row['contact_score']:.3f}  compression {row['peak_compression']:.4f}"
                      f"  ({row['wall_time_s']:.0f} s)", flush=True)
    gains = {}
    for name in dict.fromkeys(r["object"] for r in rows):
        pair = {r["jaw"]: r for r in rows if r["object"] == name}
        if "straight" in pair and args.jaw in pair:
            gains[name] = pair[args.jaw]["fem_reward"] - pair["straight"]["fem_reward"]
    print("\nFEM reward gained by shaped jaws: "
          + ", ".join(f"{k} {v:+.4f}" for k, v in gains.items()))
    title = (f"best of {', '.join(args.methods)}: {args.budget} evaluations x {args.seeds} "
             f"seeds per design space; "
             f"straight vs {args.jaw} jaws; bars: reported, marks: FEM")
    chart(rows, out / "jaw_comparison.png", title)
    payload = {"config": vars(args), "rows": rows, "fem_gain": gains,
               "total_time_s": time.perf_counter() - t0}
    out.mkdir(parents=True, exist_ok=True)
    (out / "jaw_comparison.json").write_text(json.dumps(to_jsonable(payload), indent=1) + "\n")
    print(f"wrote {out / 'jaw_comparison.json'} and {out / 'jaw_comparison.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
