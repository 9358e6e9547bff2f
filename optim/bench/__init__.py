"""A benchmark suite of gripper-design problems, for the package's methods and for yours.

- Named instances (:data:`INSTANCES`: ``OBJECT-JAW``, e.g. ``strawberry-any``), each the
  :class:`~optim.problem.DesignProblem` that ``psm-grasp optimize`` builds for that object and
  those jaws (:func:`make_problem`).
- Best-known rewards with how they were obtained (:func:`load_targets`, ``targets.json``,
  written by ``python scripts/bench_targets.py``).
- Runs scored as a user sees them: the finish's reward (the finer member re-scoring the ten best
  distinct designs) and its gap to the best known (:class:`BenchScore`); a package method with
  :func:`run_method`, your own optimizer with :class:`BenchRun`::

      from optim.bench import BenchRun

      run = BenchRun("strawberry-any", budget=1000, seed=0, algorithm="my-es",
                     log_dir="out/ioh")
      while run.remaining > 0:
          x = ask(min(20, run.remaining))   # your optimizer: rows in [-1, 1]^run.n_var
          tell(x, run.evaluate(x))          # one call per batch; rewards, to maximize
      score = run.close()
      print(score.reward, score.gap, score.reached)

- Runs logged in IOHprofiler's format, which IOHanalyzer reads (:class:`IOHLog`), and read back
  (:func:`read_ioh`).
"""

from __future__ import annotations

from .ioh_log import IOHLog, IOHRun, read_ioh
from .problems import DEFAULT_INSTANCES, INSTANCES, OBJECTS, Instance, make_problem
from .runs import BenchRun, BenchScore, run_method, score_run
from .scoring import FinishedCurve, finished_curve
from .targets import REACHED_GAP, Target, load_targets, targets_meta, targets_stale

__all__ = [
    "DEFAULT_INSTANCES",
    "INSTANCES",
    "OBJECTS",
    "REACHED_GAP",
    "BenchRun",
    "BenchScore",
    "FinishedCurve",
    "IOHLog",
    "IOHRun",
    "Instance",
    "Target",
    "finished_curve",
    "load_targets",
    "make_problem",
    "read_ioh",
    "run_method",
    "score_run",
    "targets_meta",
    "targets_stale",
]
