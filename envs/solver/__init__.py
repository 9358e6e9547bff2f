"""How the grasp is solved: the compiled interior-point Newton solver and its Python front end.

Compiled kernels (numba), one file per job: :mod:`.banded` (linear algebra), :mod:`.contact`
(constraints), :mod:`.candidates` (contact candidate sets), :mod:`.assembly` (merit, Newton
matrix), :mod:`.ipm` (interior point), :mod:`.polish` (active-set polish), :mod:`.driver` (one
grasp, a batch). Python: :mod:`.pipeline` (the one batch entry every caller uses),
:mod:`.result` (:class:`GraspResult`), :mod:`.simulate` (``simulate``, ``simulate_ramp``),
:mod:`.baselines` (SLSQP, Nelder-Mead).
"""

from .pipeline import grasp_result
from .result import GraspResult
from .simulate import METHODS, simulate, simulate_ramp

__all__ = ["GraspResult", "METHODS", "grasp_result", "simulate", "simulate_ramp"]
