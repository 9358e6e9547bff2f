"""The default search: a portfolio of CMA-ES starts racing for one budget.

One CMA-ES run from the box's centre lands in whichever basin it first falls into: on shaped
jaws under scenarios the reward has cliffs (the strain limit, holding the payload) and tiers
(a grasp that slips scores below every grasp that holds), and the basins a run can fall into
differ several-fold in reward. The portfolio spends its budget so that no single basin decides:

1. **Screen**: a scrambled Sobol sample of the box, a quarter of it on straight bars when the
   jaws are shaped, and the shipped design policy's candidates. By default each design is
   judged on the nominal scenario alone (``screen="nominal"``): with ``K`` scenarios that is
   ``K`` times as many designs for the same charge (:meth:`~optim.problem.DesignProblem.screen`),
   and the nominal reward still tells a promising region from a hopeless one where the worst
   scenario's does not (most designs fail somewhere, and a failing design says little about
   its neighbours). The best of them, apart from each other, are then judged as the search
   judges all (every scenario). :data:`SCREEN_SHARE` of the budget goes to the screen.
2. **Starts**: the best screened designs that lie apart from each other (:data:`START_SPACING`
   in the normalized box), and, with shaped jaws, a start confined to straight bars (from the
   best screened straight bar): the grooved search then never ends below a straight search
   that had its share. With shaped jaws the search reads the groove's position as an offset
   from where the object meets the finger (:data:`ALIGN_REACH_R` radii either way), so that a
   sampled groove lies under the object, not elsewhere on the finger.
   With scenarios the starts first spend :data:`NOMINAL_RACE_SHARE` of the budget on the
   nominal scenario alone, each its own CMA-ES, and start the race from its best there.
3. **Race**: every live start is a CMA-ES (step :data:`SIGMA0`) asked for a population each
   round; the rounds' populations are evaluated in one batch. At :data:`HALVING_SHARES` of the
   budget the worse half of the live starts (by their best reward) stop, so the budget goes to
   the basins that lead. A start whose CMA-ES converges restarts from the next unused screened
   design.
4. **Polish**: over the last :data:`POLISH_SHARE` of the budget the leading start runs alone,
   from its best, with its own steps and the race's batch as its population; converged, it
   restarts from its best with a smaller step (:data:`POLISH_SIGMA`). The basins are found by
   then; what the seeds still differed by was how far the leader had climbed in its basin with a
   fifth of the budget.

The result records each start's best (``extra["starts"]``): the finish re-scores every start's
best, and the leader's best before the polish, with the finer member beside the run's best
distinct designs (a polish on the search model may climb where that model is optimistic), and
a verdict that nothing holds (:func:`optim.verdict.search_verdict`) needs the starts to agree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .cmaes import _import_cma, default_popsize
from .problem import DesignProblem, check_budget, check_seed
from .result import OptimResult

__all__ = ["run_portfolio", "DEFAULT_STARTS", "SCREEN_SHARE", "SIGMA0", "START_SPACING",
           "HALVING_SHARES", "POLISH_SHARE", "MAX_POLISH", "NOMINAL_RACE_SHARE",
           "MAX_NOMINAL_RACE"]

DEFAULT_STARTS = 6
# the share of the budget spent on the screen (at least MIN_SCREEN_PER_VAR points a coordinate)
SCREEN_SHARE = 0.15
MIN_SCREEN_PER_VAR = 4
# the screen's share of straight bars when the jaws are shaped (the groove's depth 0)
STRAIGHT_SHARE = 0.25
STRAIGHT_LABEL = "straight bars"
CRADLE_LABEL = "cradle"
# the screen's share of cradles that conform to the object, where the optima of shaped jaws
# lie (measured: every optimum of the default search on the strawberry, the tomatoes, the
# silicone puck and the blueberries is a groove of bottom radius 1.0-1.3 object radii, nearly
# as deep as the finger allows, centred within 0.2 radii of where the object meets the
# finger); a random draw of the box puts one design in a few hundred there, and a search whose
# starts all missed it ended at a straight bar's reward. Each of these rows keeps its other
# coordinates as drawn and maps its groove's into: the bottom radius in CRADLE_RADIUS_R object
# radii, the depth coordinate in CRADLE_DEPTH (the deeper part of what fits the finger), the
# centre within CRADLE_OFFSET of the reach about the touch foot (search coordinates)
CRADLE_SHARE = 0.25
CRADLE_RADIUS_R = (0.95, 1.4)
CRADLE_DEPTH = (0.2, 1.0)
CRADLE_OFFSET = 0.3
# CMA-ES's initial step in the normalized box [-1, 1]^n from a screened start
SIGMA0 = 0.25
# with shaped jaws the search puts the groove's centre within this many object radii of
# where the object meets the finger (envs.design_space.DesignBounds.aligned)
ALIGN_REACH_R = 1.0
# starts closer than this in every normalized coordinate to a better one are the same basin
START_SPACING = 0.3
# the nominal screen (run_portfolio's screen="nominal"): the best this many designs per start,
# apart from each other, are judged robustly
POOL_PER_START = 3
SCREENS = ("robust", "nominal")
# shares of the budget left after the screen, after which the worse half of the live starts
# stop (the straight bars' start is spared until the polish: it converges in its own smaller
# space, and a grooved run whose straight start stopped early ended below a straight run of the
# same budget: blueberries, 1,296 evaluations, 2 seeds of 5, 0.0189 against 0.0204)
HALVING_SHARES = (0.25, 0.45)
# the last share of the budget left after the screen that the leading start spends alone (the
# polish). Measured (5 seeds each, default budgets): without it the leader got a fifth of the
# budget and the runs ended short of their basin's best (tomatoes 0.163-0.192, the puck
# 0.467-0.480); with 0.4 and the halvings above the same seeds end at 0.157-0.198 and
# 0.473-0.477, the tomatoes at friction 0.5 at 0.187-0.195 against 0.161-0.192, the strawberry
# at 0.123-0.126 on 4 seeds against 0.080-0.111; 0.3 (halvings 0.3, 0.5) ended lower on the
# strawberry (0.107-0.124)
POLISH_SHARE = 0.4
# a polished start whose CMA-ES converges restarts from its best with this fraction of SIGMA0
POLISH_SIGMA = 0.25
MAX_POLISH = 0.9
# the share of the budget the starts spend on the nominal scenario alone before the race
# (Portfolio.nominal_race), with scenarios. Measured in-process, default budgets: blueberries
# (25 scenarios) 4 of 5 seeds in the cradles' basin (0.043-0.070) against 1-2 of 5 without;
# the strawberry's seed 1 0.0063 -> 0.1080, the tomatoes' seed 2 0.1876 -> 0.2000
NOMINAL_RACE_SHARE = 0.15
MAX_NOMINAL_RACE = 0.5
# rounds every live start runs between two stages of the race (a halving, the polish), also
# when the budget's shares come sooner: with 25 scenarios the default budget is 1,296 designs,
# and a first halving at a quarter of it stopped starts after 5 generations, before any of them
# found the cradles where the optimum lies (blueberries, 3 seeds of 5 ended at a straight bar's
# reward)
MIN_STAGE_ROUNDS = 6
# with a time limit, the designs a coordinate of the pilot batch whose rate sizes the phases
PILOT_PER_VAR = 2


@dataclass
class _Start:
    """One CMA-ES start of the portfolio: its strategy, the coordinates it may move (the
    others held, e.g. a straight bar's groove) and its best so far."""

    label: str
    es: Any
    free: np.ndarray  # bool mask of the coordinates the start searches
    base: np.ndarray  # the full normalized point; the held coordinates are read from it
    best_reward: float = -math.inf
    best_x: np.ndarray | None = None
    best_y: np.ndarray | None = None  # best_x in search coordinates
    best_feasible: bool = False
    evaluations: int = 0
    restarts: int = 0
    live: bool = True
    history: list[float] = field(default_factory=list)

    def full(self, xs: list[np.ndarray]) -> np.ndarray:
        """The start's asked points as full rows of the box."""
        rows = np.repeat(self.base[None, :], len(xs), axis=0)
        rows[:, self.free] = np.asarray(xs)
        return rows


def _sobol(n: int, dim: int, seed: int) -> np.ndarray:
    """``n`` scrambled Sobol points in [-1, 1]^dim (a power of two is not required: the
    first ``n`` of the sequence)."""
    from scipy.stats import qmc

    sampler = qmc.Sobol(d=dim, scramble=True, seed=np.random.default_rng(seed))
    m = max(1, math.ceil(math.log2(max(n, 2))))
    return 2.0 * sampler.random_base2(m)[:n] - 1.0


def _straight_columns(problem: DesignProblem) -> dict[int, float]:
    """The normalized coordinates that make a design of ``problem`` a straight bar (each
    groove's depth at its low end, 0) and the values they are held at; empty for straight
    jaws."""
    from envs.design_space import JAW_RELATIVE_FIELDS

    depth = JAW_RELATIVE_FIELDS[0]
    return {k: -1.0 for k, name in enumerate(problem.bounds.fields)
            if name == depth or name == "left_" + depth}


def _screen_size(problem: DesignProblem, budget: int) -> int:
    """Designs the robust screen judges: :data:`SCREEN_SHARE` of the budget, at least
    :data:`MIN_SCREEN_PER_VAR` a coordinate, at most the budget."""
    return min(budget, max(MIN_SCREEN_PER_VAR * problem.n_var, round(SCREEN_SHARE * budget)))


def _cradle_columns(problem: DesignProblem) -> dict[int, tuple[float, float]]:
    """The search coordinates of each designed groove that make it a conforming cradle
    (:data:`CRADLE_SHARE`), each with the interval its coordinate is mapped into; empty for
    straight jaws and for V-grooves (no bottom radius to design)."""
    from envs.design_space import JAW_RELATIVE_FIELDS

    depth, radius, _, position = JAW_RELATIVE_FIELDS
    names = problem.bounds.fields
    lo, hi = problem.bounds.low_array, problem.bounds.high_array
    out: dict[int, tuple[float, float]] = {}
    for prefix in ("", "left_"):
        if prefix + radius not in names:
            continue
        k = names.index(prefix + radius)
        out[k] = tuple(float(np.clip(2.0 * (r - lo[k]) / (hi[k] - lo[k]) - 1.0, -1.0, 1.0))
                       for r in CRADLE_RADIUS_R)
        out[names.index(prefix + depth)] = CRADLE_DEPTH
        out[names.index(prefix + position)] = (-CRADLE_OFFSET, CRADLE_OFFSET)
    return out


def _screen(problem: DesignProblem, n: int, seed: int) -> np.ndarray:
    """``n`` screen points in search coordinates: Sobol, with shaped jaws a
    :data:`STRAIGHT_SHARE` of them made straight bars and a :data:`CRADLE_SHARE` conforming
    cradles (:func:`_cradle_columns`)."""
    x = _sobol(n, problem.n_var, seed)
    straight = _straight_columns(problem)
    if straight:
        rows = np.arange(n) % round(1 / STRAIGHT_SHARE) == 0
        for k, v in straight.items():
            x[rows, k] = v
    cradle = _cradle_columns(problem)
    if cradle:
        # the rows halfway between the straight ones, so that any prefix of the screen holds
        # both kinds
        period = round(1 / CRADLE_SHARE)
        rows = np.arange(n) % period == period // 2
        for k, (low, high) in cradle.items():
            x[rows, k] = low + 0.5 * (x[rows, k] + 1.0) * (high - low)
    return x


def _apart(x: np.ndarray, order: np.ndarray, spacing: float, count: int,
           taken: list[np.ndarray]) -> list[int]:
    """Up to ``count`` rows of ``x`` in the given order, each farther than ``spacing`` (in the
    max norm) from the others picked and from ``taken``."""
    picked: list[int] = []
    for i in order.tolist():
        if len(picked) == count:
            break
        if all(np.max(np.abs(x[i] - t)) > spacing for t in taken) and all(
                np.max(np.abs(x[i] - x[j])) > spacing for j in picked):
            picked.append(i)
    return picked


class _Portfolio:
    """The race: the starts, the screened points left to restart from, and the rounds."""

    def __init__(self, problem: DesignProblem, seed: int, sigma0: float, popsize: int | None):
        self.problem = problem
        self.cma = _import_cma()
        self.rng = np.random.default_rng(seed)
        self.sigma0 = sigma0
        self.popsize = popsize
        self.starts: list[_Start] = []
        self.spare: list[np.ndarray] = []
        self.polishing: _Start | None = None
        self.before_polish: tuple[np.ndarray, float] | None = None

    def to_box(self, y: np.ndarray) -> np.ndarray:
        """The problem's normalized rows of search coordinates ``y``: with shaped jaws the
        groove's position is searched as an offset from where the object meets the finger
        (:meth:`envs.design_space.DesignBounds.aligned`, :data:`ALIGN_REACH_R`)."""
        return self.problem.bounds.aligned(y, ALIGN_REACH_R)

    def new_es(self, x0: np.ndarray, sigma: float, popsize: int, **options: Any) -> Any:
        """A CMA-ES in the box [-1, 1]^k from ``x0`` (k coordinates), sampled from the race's
        generator."""
        return self.cma.CMAEvolutionStrategy(np.clip(x0, -1.0, 1.0), sigma, {
            "bounds": [-1.0, 1.0], "popsize": popsize,
            "randn": lambda *shape: self.rng.standard_normal(shape),
            "seed": np.nan, "verbose": -9, "verb_log": 0, "verb_disp": 0,
            "tolflatfitness": 10, **options,
        })

    def nominal_race(self, charge: int) -> int:
        """Move every start to the best design its own CMA-ES finds on the nominal scenario
        alone for a ``charge`` of evaluations (:meth:`DesignProblem.screen`: a scenario
        count's share of an evaluation a design): the basins are found ``K`` times as cheaply
        as under every scenario, where most designs fail somewhere and a start is blind."""
        problem = self.problem
        designs = 0
        lam = {id(s): s.es.popsize for s in self.starts}
        racing = [(s, self.new_es(s.base[s.free], self.sigma0, lam[id(s)]))
                  for s in self.starts]
        best = {id(s): (-math.inf, None) for s in self.starts}
        end = problem.n_evaluations + charge
        while racing:
            asked = [(s, es, es.ask()) for s, es in racing]
            ys = np.concatenate([s.full(xs) for s, _, xs in asked])
            if problem.screen_cost(len(ys)) > min(problem.remaining,
                                                  end - problem.n_evaluations):
                break
            got = problem.screen(self.to_box(ys))["reward"]
            designs += len(ys)
            at, still = 0, []
            for s, es, xs in asked:
                k = len(xs)
                mine = got[at:at + k]
                i = int(np.argmax(mine))
                if mine[i] > best[id(s)][0]:
                    best[id(s)] = (float(mine[i]), ys[at + i].copy())
                es.tell(xs, (-mine).tolist())
                if not es.stop():
                    still.append((s, es))
                at += k
            racing = still
        for s in self.starts:
            y = best[id(s)][1]
            if y is not None:
                s.base = y
                s.es = self.new_es(y[s.free], self.sigma0, lam[id(s)])
        return designs

    def add(self, label: str, x0: np.ndarray, free: np.ndarray | None = None) -> None:
        """A new start at ``x0`` (searching the coordinates ``free``; default all)."""
        n = self.problem.n_var
        free = np.ones(n, dtype=bool) if free is None else free
        dim = int(free.sum())
        lam = default_popsize(dim) if self.popsize is None else self.popsize
        es = self.new_es(x0[free], self.sigma0, lam)
        self.starts.append(_Start(label, es, free, np.asarray(x0, dtype=np.float64).copy()))

    def restart(self, start: _Start) -> None:
        """Give a converged start a new CMA-ES from the best unused screened point (a uniform
        point when none is left), with twice the population (IPOP)."""
        local = start is self.polishing
        if local:
            x0 = start.best_y
        else:
            x0 = self.spare.pop(0) if self.spare else self.rng.uniform(-1.0, 1.0,
                                                                       self.problem.n_var)
        x0 = x0.copy()
        x0[~start.free] = start.base[~start.free]
        lam = start.es.popsize if local else 2 * start.es.popsize
        sigma = self.sigma0 * (POLISH_SIGMA if local else 1.0)
        start.es = self.new_es(x0[start.free], sigma, lam)
        start.restarts += 1

    def round(self) -> bool:
        """One round: every live start's population in one batch; False when the budget is
        spent."""
        problem = self.problem
        live = [s for s in self.starts if s.live]
        asked = [(s, s.es.ask()) for s in live]
        ys = np.concatenate([s.full(xs) for s, xs in asked])
        rows = self.to_box(ys)
        n = min(len(rows), problem.remaining)
        if n <= 0:
            return False
        out = problem.evaluate(rows[:n])
        feasible = problem.feasible(out)
        at = 0
        for s, xs in asked:
            k = len(xs)
            got = out["reward"][at:at + k]
            if len(got):
                i = int(np.argmax(got))
                if got[i] > s.best_reward:
                    s.best_reward, s.best_x = float(got[i]), rows[at + i].copy()
                    s.best_y = ys[at + i].copy()
                    s.best_feasible = bool(feasible[at + i])
                s.evaluations += len(got)
            if len(got) == k:
                s.es.tell(xs, (-got).tolist())
                if s.es.stop():
                    self.restart(s)
            at += k
            s.history.append(s.best_reward)
        return n == len(rows) and problem.remaining > 0

    def polish(self) -> _Start | None:
        """Stop every start but the leader (by its best reward), which then spends the rest of
        the budget alone; returns it."""
        ranked = sorted(self.starts, key=lambda s: -s.best_reward)
        if not ranked or ranked[0].best_x is None:
            return None
        lam = sum(s.es.popsize for s in ranked if s.live)
        for s in ranked[1:]:
            s.live = False
        lead = ranked[0]
        self.polishing = lead
        self.before_polish = (lead.best_x.copy(), lead.best_reward)
        # one CMA-ES from the leader's best with the race's batch as its population (a batch
        # of one start's population leaves the workers idle) and the leader's own steps
        es = lead.es
        stds = np.sqrt(np.clip(np.diag(es.C), 1e-12, None))
        lead.es = self.new_es(lead.best_y[lead.free], float(es.sigma), max(lam, es.popsize),
                              CMA_stds=stds)
        return lead

    def halve(self, spare_straight: bool) -> None:
        """Stop the worse half of the live starts (by their best reward; at least one stays);
        ``spare_straight``: not the straight bars' start."""
        live = sorted((s for s in self.starts if s.live), key=lambda s: -s.best_reward)
        for s in live[max(1, math.ceil(len(live) / 2)):]:
            s.live = spare_straight and s.label == STRAIGHT_LABEL


def _planned_budget(problem: DesignProblem, budget: int, seed: int) -> int:
    """The budget the phases are sized by: ``budget``, or under a time limit the evaluations
    the time left allows at the rate of a pilot batch of random designs (judged and recorded
    as the search's), whichever is less. A run given a time alone has a budget of millions: a
    screen sized by it would outlast the time in its one batch."""
    if problem.time_limit_s is None or not problem.plan_by_time:
        return budget
    pilot = _sobol(PILOT_PER_VAR * problem.n_var, problem.n_var, seed + 1)
    before, start = problem.n_evaluations, problem.elapsed_s
    problem.evaluate(pilot[:problem.remaining])
    rate = (problem.n_evaluations - before) / max(problem.elapsed_s - start, 1e-6)
    left = max(problem.time_limit_s - problem.elapsed_s, 0.0)
    return int(min(budget, problem.n_evaluations + max(1, math.floor(rate * left))))


def _screened_pool(problem: DesignProblem, race: _Portfolio, budget: int, seed: int,
                   screen: str, policy: bool, starts: int) -> tuple[np.ndarray, np.ndarray]:
    """The screen: designs in search coordinates and their robust rewards, from which the
    starts are chosen (the shipped policy's candidates first, with ``policy``).

    The nominal screen judges ``K`` times the robust screen's designs on the nominal scenario
    for the same charge (``K`` scenarios), then robustly the best :data:`POOL_PER_START` per
    start of them, apart from each other, and as many of its best straight bars."""
    n = _screen_size(problem, budget)
    nominal = screen == "nominal" and problem.scenario_count > 1
    y = _screen(problem, n * problem.scenario_count if nominal else n, seed)
    if policy:
        from .rl import policy_starts

        y = np.concatenate([problem.bounds.unaligned(policy_starts(problem), ALIGN_REACH_R),
                            y])
    if nominal:
        pool = POOL_PER_START * (starts + 1)
        y = y[:problem.scenario_count * max(problem.remaining - pool, 1)]
        judged = problem.screen(race.to_box(y))["reward"]
        order = np.argsort(-judged, kind="stable")
        keep = _apart(y, order, START_SPACING / 2, POOL_PER_START * starts, [])
        for kind in (_straight_rows(problem, y), _cradle_rows(problem, y)):
            keep += [i for i in order.tolist() if kind[i] and i not in keep][:POOL_PER_START]
        y = y[sorted(keep)]
    reward = problem.evaluate(race.to_box(y[:problem.remaining]))["reward"]
    return y[:len(reward)], reward


def _straight_rows(problem: DesignProblem, y: np.ndarray) -> np.ndarray:
    """Which rows of search coordinates are straight bars (all True for straight jaws)."""
    straight = _straight_columns(problem)
    if not straight:
        return np.ones(len(y), dtype=bool)
    return np.all([y[:, k] == v for k, v in straight.items()], axis=0)


def _cradle_rows(problem: DesignProblem, y: np.ndarray) -> np.ndarray:
    """Which rows of search coordinates are conforming cradles (:func:`_cradle_columns`: every
    designed groove's coordinates in their intervals); all False without any."""
    cradle = _cradle_columns(problem)
    if not cradle:
        return np.zeros(len(y), dtype=bool)
    return np.all([(y[:, k] >= low) & (y[:, k] <= high) for k, (low, high) in cradle.items()],
                  axis=0)


def _seat_starts(problem: DesignProblem, race: _Portfolio, y: np.ndarray, reward: np.ndarray,
                 starts: int) -> None:
    """The race's starts from the screened pool: the best straight bar (with shaped jaws,
    confined to straight bars), then the best designs apart from each other; the rest of the
    pool, best first, is left for restarts."""
    order = np.argsort(-reward, kind="stable")
    straight = _straight_columns(problem)
    taken: list[int] = []
    if straight and starts > 1 and len(reward):
        is_straight = _straight_rows(problem, y)
        best = [i for i in order.tolist() if is_straight[i]]
        if best:
            free = np.ones(problem.n_var, dtype=bool)
            free[list(straight)] = False
            race.add(STRAIGHT_LABEL, y[best[0]], free)
            taken.append(best[0])
    # the best conforming cradle, where the optima of shaped jaws lie, is a start of its own:
    # the best screened designs apart from each other may all lie elsewhere
    cradles = [i for i in order.tolist() if _cradle_rows(problem, y[i:i + 1])[0]]
    if cradles and starts > len(taken) + 1:
        race.add(CRADLE_LABEL, y[cradles[0]])
        taken.append(cradles[0])
    picked = _apart(y, order, START_SPACING, starts - len(taken), [y[i] for i in taken])
    for j, i in enumerate(picked):
        race.add(f"start {j + 1}", y[i])
    taken += picked
    race.spare = [y[i] for i in order.tolist() if i not in taken]


def run_portfolio(
    problem: DesignProblem,
    *,
    budget: int,
    seed: int = 0,
    starts: int = DEFAULT_STARTS,
    sigma0: float = SIGMA0,
    popsize: int | None = None,
    policy: bool = True,
    screen: str = "nominal",
    polish: float = POLISH_SHARE,
    nominal_race: float = NOMINAL_RACE_SHARE,
) -> OptimResult:
    """Maximize the reward with a portfolio of CMA-ES starts from a screened sample of the box.

    Parameters
    ----------
    problem
        The design problem.
    budget
        Evaluations, >= 1 (a time limit set on the problem ends the run earlier).
    seed
        Seed of the screen's scrambling and of every start's sampling.
    starts
        Starts raced, in [1, 32] (with shaped jaws one of them is the straight bars').
    sigma0
        Each start's initial step in the normalized box, in (0, 2].
    popsize
        Each start's population (default pycma's ``4 + floor(3 ln n)``), >= 2.
    policy
        Screen the shipped design policy's candidate designs too, where one designs in the
        problem's box and observes its object (:func:`optim.rl.policy_starts`; a few
        evaluations): they become starts only when they screen better than the sample.
    screen
        ``"nominal"`` (default): the screen judges its designs on the nominal scenario alone,
        ``K`` times as many for the charge of the robust screen's, then the best
        :data:`POOL_PER_START` per start of them robustly; ``"robust"``: it judges each design
        as the search does (every scenario). Without scenarios both are the same.
    polish
        The last share of the budget left after the screen that the leading start spends
        alone, in [0, :data:`MAX_POLISH`] (0: the race runs to the end).
    nominal_race
        The share of the budget, in [0, :data:`MAX_NOMINAL_RACE`], that the starts spend on
        the nominal scenario alone before the race, each moved to its best there (with
        scenarios; 0: none).

    Returns
    -------
    OptimResult
        ``extra["starts"]``: each start's label, best reward, whether its best holds within
        the strain limit (by the search model), its evaluations and restarts;
        ``extra["start_designs"]``: each start's best design and its reward, then the
        polished start's best before the polish; ``extra["polish"]``: the polished start's
        label, the run's evaluations when its polish began and its best reward then (``None``
        without a polish); ``extra["nominal_race"]``: the designs judged and the evaluations
        charged (``None`` without one).
    """
    budget, seed = check_budget(budget), check_seed(seed)
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or not (
            1 <= starts <= 32):
        raise ValueError(f"starts must be an integer in [1, 32], got {starts!r}")
    if not (isinstance(sigma0, (int, float)) and 0.0 < sigma0 <= 2.0):
        raise ValueError(f"sigma0 = {sigma0!r} is outside the allowed range (0, 2]")
    if popsize is not None and (isinstance(popsize, bool) or int(popsize) != popsize
                                or popsize < 2):
        raise ValueError(f"popsize must be None or an integer >= 2, got {popsize!r}")
    if not isinstance(policy, bool):
        raise ValueError(f"policy must be True or False, got {policy!r}")
    if screen not in SCREENS:
        raise ValueError(f"screen must be one of {SCREENS}, got {screen!r}")
    if isinstance(polish, bool) or not isinstance(polish, (int, float)) or not (
            0.0 <= polish <= MAX_POLISH):
        raise ValueError(f"polish = {polish!r} is outside the allowed range [0, {MAX_POLISH}]")
    if isinstance(nominal_race, bool) or not isinstance(nominal_race, (int, float)) or not (
            0.0 <= nominal_race <= MAX_NOMINAL_RACE):
        raise ValueError(f"nominal_race = {nominal_race!r} is outside the allowed range "
                         f"[0, {MAX_NOMINAL_RACE}]")
    problem.start(budget)
    race = _Portfolio(problem, seed, float(sigma0), popsize)
    plan = _planned_budget(problem, budget, seed)
    y, reward = _screened_pool(problem, race, plan, seed, screen, policy, starts)
    _seat_starts(problem, race, y, reward, starts)
    nominal: dict[str, int] | None = None
    if nominal_race > 0 and problem.scenario_count > 1:
        before = problem.n_evaluations
        designs = race.nominal_race(int(nominal_race * plan))
        nominal = {"designs": designs, "evaluations": problem.n_evaluations - before}
    screened = problem.n_evaluations
    polished: dict[str, Any] | None = None
    race_budget = plan - screened
    polish_at = screened + race_budget * (1.0 - polish) if polish > 0 else math.inf
    # the race's stages in order, each at its share of the budget and not before its starts
    # had MIN_STAGE_ROUNDS rounds since the last stage
    stages = [(screened + race_budget * share, "halve") for share in HALVING_SHARES
              if screened + race_budget * share < polish_at]
    stages += [(polish_at, "polish")] if polish > 0 else []
    rounds = 0
    while race.starts and race.round():
        rounds += 1
        if stages and problem.n_evaluations >= stages[0][0] and rounds >= MIN_STAGE_ROUNDS:
            rounds = 0
            if stages.pop(0)[1] == "halve":
                race.halve(spare_straight=True)
            elif race.polish() is not None:
                polished = {"label": race.polishing.label,
                            "evaluations": problem.n_evaluations,
                            "reward_before": race.before_polish[1]}
    return problem.result(
        "portfolio", seed,
        options={"starts": int(starts), "sigma0": float(sigma0), "popsize": popsize,
                 "policy": bool(policy), "screen": screen, "polish": float(polish),
                 "nominal_race": float(nominal_race)},
        extra={"screened": int(len(reward)), "screen": screen, "polish": polished,
               "nominal_race": nominal,
               "starts": [{"label": s.label, "best_reward": s.best_reward,
                           "holds": s.best_feasible, "evaluations": s.evaluations,
                           "restarts": s.restarts} for s in race.starts],
               "start_designs": [{"design": problem.design_dict(s.best_x),
                                  "reward": s.best_reward}
                                 for s in race.starts if s.best_x is not None]
               + ([{"design": problem.design_dict(race.before_polish[0]),
                    "reward": race.before_polish[1]}] if race.before_polish else [])})
