"""All compiled solver and model kernels in one namespace ``K``, for the derivative tests."""

from types import SimpleNamespace

from envs.model import energy, geometry, layout, metrics
from envs.solver import (
    assembly,
    banded,
    candidates,
    contact,
    driver,
    gauge,
    ipm,
    polish,
    start,
    status,
)

K = SimpleNamespace()
for _module in (layout, geometry, energy, metrics, status, banded, contact, candidates, assembly,
                gauge, start, ipm, polish, driver):
    for _name, _value in vars(_module).items():
        if not _name.startswith("__"):
            setattr(K, _name, _value)
