"""Runs logged in IOHprofiler's format, which IOHanalyzer reads, and read back.

A run's evaluations (the search model's reward of every design, in evaluation order) are
replayed through an ``ioh`` problem with IOHprofiler's ``Analyzer`` logger attached, after the
run: the problem knows nothing of logging (IOHexperimenter's split), every method is logged the
same way, and a batch evaluated in one call is logged as its rows one by one. The logger writes,
under ``root/folder``, one ``IOHprofiler_f{ID}_{NAME}.json`` per instance (its runs, their
attributes) and ``data_f{ID}_{NAME}/IOHprofiler_f{ID}_DIM{n}.dat`` (a block per run: a header
line, then ``evaluations raw_y wall_time_s`` at each improvement and at the run's end). The
problem is maximized; ``raw_y`` is the reward, ``wall_time_s`` the search's wall time when that
evaluation's batch was done. Each run carries the attributes ``seed`` and, after the finish,
``finished_reward`` (the finer member's reward of the reported design).

Function ids: ``ioh`` gives a wrapped problem the first free id of its class, so the suite's
instances are wrapped in the suite's order, all at once, the first time one is logged: an
instance has the same id in every process (with the same ``ioh`` version).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .problems import INSTANCES

__all__ = ["IOH_PREFIX", "RUN_ATTRIBUTES", "IOHLog", "read_ioh", "IOHRun"]

IOH_PREFIX = "psm_"  # an instance's function name in the logs: psm_strawberry-any
WALL_TIME = "wall_time_s"
RUN_ATTRIBUTES = ("seed", "finished_reward")
NOT_SCORED = -1e300

_registered: dict[str, tuple[Any, int]] = {}  # name -> (its ioh problem, its dimension)
_pending: list[float] = []  # the rewards the wrapped problems return, in order


def _import_ioh():
    try:
        import ioh
    except ImportError as exc:
        raise ImportError("IOHprofiler logs need ioh: pip install 'psm-grasp[bench]'") from exc
    return ioh


def _replayed(x: np.ndarray) -> float:
    """The wrapped problems' function: the next recorded reward (the design is the logger's)."""
    return _pending.pop(0)


def _problem(name: str, n_var: int):
    """The ``ioh`` problem of an instance (wrapped once per process, the suite's in order)."""
    ioh = _import_ioh()
    if not _registered:
        for key, inst in INSTANCES.items():
            _registered[key] = (None, inst.n_var)
    if name not in _registered:
        _registered[name] = (None, n_var)
    for key, (problem, dim) in list(_registered.items()):
        if problem is None:
            _registered[key] = (ioh.wrap_problem(
                _replayed, name=f"{IOH_PREFIX}{key}", problem_class=ioh.ProblemClass.REAL,
                dimension=dim, instance=1, optimization_type=ioh.OptimizationType.MAX,
                lb=-1.0, ub=1.0), dim)
    problem, dim = _registered[name]
    if dim != n_var:
        raise ValueError(f"instance {name!r} was logged with {dim} variables, not {n_var}")
    return problem


def _finite(reward: float) -> float:
    """A reward as the logs hold it: ``ioh`` writes a NaN or an infinity as ``nan`` or ``inf``,
    which JSON readers refuse; below every finite reward instead (a design the evaluator could
    not score)."""
    return float(reward) if math.isfinite(reward) else NOT_SCORED


class IOHLog:
    """An IOHprofiler ``Analyzer`` logger for one algorithm's runs, on any instances.

    Use it as a context manager (the files are complete once it is closed)::

        with IOHLog("out/ioh", "ng:NGOpt") as log:
            log.add("strawberry-any", archive["x"], archive["reward"],
                    result.history_evaluations, result.history_wall_time_s, seed=0)

    Parameters
    ----------
    root
        The folder of the logs.
    algorithm
        The algorithm's name (the method).
    folder
        The logger's folder under ``root`` (default: the algorithm's name, ``:`` as ``-``;
        ``ioh`` appends ``-1``, ``-2``, ... rather than write into an existing one).
    info
        The algorithm's description in the logs.
    """

    def __init__(self, root: str | Path, algorithm: str, *, folder: str | None = None,
                 info: str = "") -> None:
        ioh = _import_ioh()
        self.wall_time_s = 0.0  # watched by the logger: the replayed batch's wall time
        self._logger = ioh.logger.Analyzer(
            root=str(root), folder_name=folder or algorithm.replace(":", "-"),
            algorithm_name=algorithm, algorithm_info=info or algorithm)
        self._logger.watch(self, WALL_TIME)
        for key in RUN_ATTRIBUTES:
            self._logger.add_run_attribute(key, 0.0)

    @property
    def path(self) -> Path:
        """The folder written."""
        return Path(self._logger.output_directory)

    def add(self, name: str, archive_x: np.ndarray, archive_reward: np.ndarray,
            batch_ends: Sequence[int], batch_seconds: Sequence[float], *, seed: int,
            finished_reward: float, archive_evaluations: Sequence[int] | None = None) -> None:
        """Log one run.

        Parameters
        ----------
        name
            The instance (a name of :data:`~optim.bench.problems.INSTANCES`, or another).
        archive_x, archive_reward
            Every evaluated design (n, n_var) in [-1, 1] and its reward (n,), in evaluation
            order (:meth:`~optim.problem.DesignProblem.archive`).
        batch_ends, batch_seconds
            The evaluation count and the wall time [s] at the end of each batch
            (``history_evaluations``, ``history_wall_time_s`` of the result).
        seed
            The run's seed (a run attribute).
        finished_reward
            The reward of the design the run reports, by the finer member of its finish (a run
            attribute).
        archive_evaluations
            The evaluation count of each archived design, increasing (the archive's
            ``evaluations``; default 1, 2, ...). Counts no design has (the budget a screen on
            the nominal scenario charged, :meth:`~optim.problem.DesignProblem.screen`) are
            logged as evaluations that score :data:`NOT_SCORED`: the log's evaluations are the
            run's budget.

        Raises
        ------
        ValueError
            When the arrays disagree in length, or the batches do not end at the last
            evaluation.
        """
        x = np.asarray(archive_x, dtype=np.float64)
        reward = np.asarray(archive_reward, dtype=np.float64)
        ends = np.asarray(batch_ends, dtype=np.int64)
        evals = (np.arange(1, x.shape[0] + 1) if archive_evaluations is None
                 else np.asarray(archive_evaluations, dtype=np.int64))
        total = int(ends[-1]) if len(ends) else 0
        if x.ndim != 2 or reward.shape != (x.shape[0],) or evals.shape != reward.shape or (
                len(ends) != len(batch_seconds)) or (evals.size and (
                    evals[0] < 1 or np.any(np.diff(evals) <= 0) or evals[-1] > total)):
            raise ValueError(f"a run's archive ({x.shape}, {reward.shape}, evaluations "
                             f"{evals.shape}) and batches ({len(ends)} ending at {total}) "
                             "disagree")
        problem = _problem(name, x.shape[1])
        self._logger.set_run_attributes({"seed": float(seed),
                                         "finished_reward": _finite(finished_reward)})
        row_of = dict(zip(evals.tolist(), range(evals.size), strict=True))
        # the batch each evaluation ended in, for its wall time
        batch = np.searchsorted(ends, np.arange(1, total + 1), side="left")
        seconds = np.asarray(batch_seconds, dtype=np.float64)
        unscored = np.zeros(x.shape[1])
        problem.attach_logger(self._logger)
        try:
            for e in range(1, total + 1):
                self.wall_time_s = float(seconds[batch[e - 1]])
                i = row_of.get(e)
                _pending.append(NOT_SCORED if i is None else _finite(reward[i]))
                problem(unscored if i is None else x[i])
            problem.reset()
        finally:
            _pending.clear()
            problem.detach_logger()

    def close(self) -> None:
        """Write the files out."""
        self._logger.close()

    def __enter__(self) -> IOHLog:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


@dataclass(frozen=True)
class IOHRun:
    """One run read back from IOHprofiler logs.

    Parameters
    ----------
    function_name, function_id, algorithm, dimension, maximization
        From the run's ``.json`` file.
    evaluations, raw_y
        The logged rows: evaluation counts and rewards (at each improvement and at the end).
    columns
        Every column of the ``.dat`` block, by its header name.
    evals, best_y
        The ``.json``'s record of the run: its evaluations and its best reward.
    attributes
        The run's attributes (:data:`RUN_ATTRIBUTES`: ``seed``, ``finished_reward``).
    """

    function_name: str
    function_id: int
    algorithm: str
    dimension: int
    maximization: bool
    evaluations: np.ndarray
    raw_y: np.ndarray
    columns: dict[str, np.ndarray]
    evals: int
    best_y: float
    attributes: dict[str, Any]

    def best_so_far(self) -> np.ndarray:
        """The best reward so far at each logged row."""
        return (np.maximum if self.maximization else np.minimum).accumulate(self.raw_y)


def _dat_blocks(path: Path) -> list[dict[str, np.ndarray]]:
    """The run blocks of a ``.dat`` file: each a header line of column names, then rows."""
    blocks: list[tuple[list[str], list[list[float]]]] = []
    for line in path.read_text().splitlines():
        parts = line.split()
        if not parts:
            continue
        try:
            row = [float(p) for p in parts]
        except ValueError:  # a header: a new run
            blocks.append((parts, []))
            continue
        if not blocks:
            raise ValueError(f"{path}: data before the first header line")
        blocks[-1][1].append(row)
    return [{h: np.array([r[k] for r in rows]) for k, h in enumerate(header)}
            for header, rows in blocks]


# ioh writes non-finite numbers as C++ prints them (nan, inf, -inf), which JSON does not allow
_NON_FINITE = re.compile(r"(?<![\w.\"])(-?)(nan|inf)(?![\w\"])")


def _json_constant(match: re.Match) -> str:
    sign, word = match.groups()
    return "NaN" if word == "nan" else f"{sign}Infinity"


def read_ioh(folder: str | Path) -> list[IOHRun]:
    """Every run of the IOHprofiler logs under ``folder`` (its ``IOHprofiler_*.json`` files and
    the ``.dat`` files they name), in the files' order.

    Raises
    ------
    ValueError
        When a ``.dat`` file holds another number of runs than its ``.json`` lists.
    """
    runs: list[IOHRun] = []
    for meta_path in sorted(Path(folder).rglob("IOHprofiler_*.json")):
        meta = json.loads(_NON_FINITE.sub(_json_constant, meta_path.read_text()))
        for scenario in meta["scenarios"]:
            blocks = _dat_blocks(meta_path.parent / scenario["path"])
            if len(blocks) != len(scenario["runs"]):
                raise ValueError(f"{meta_path}: {len(scenario['runs'])} runs listed, "
                                 f"{len(blocks)} in {scenario['path']}")
            for block, run in zip(blocks, scenario["runs"], strict=True):
                runs.append(IOHRun(
                    function_name=meta["function_name"], function_id=int(meta["function_id"]),
                    algorithm=meta["algorithm"]["name"], dimension=int(scenario["dimension"]),
                    maximization=bool(meta["maximization"]),
                    evaluations=block["evaluations"].astype(np.int64), raw_y=block["raw_y"],
                    columns=block, evals=int(run["evals"]), best_y=float(run["best"]["y"]),
                    attributes={k: run[k] for k in meta.get("run_attributes", ())
                                if k in run}))
    return runs
