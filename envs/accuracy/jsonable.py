"""JSON-safe copies of reports, numpy values and tuples for the study scripts (:func:`jsonable`)."""

from __future__ import annotations

import math

import numpy as np


def jsonable(obj):
    """Recursively convert numpy values, tuples and dataclass reports to JSON-safe objects.

    Non-finite floats become ``None`` (strict JSON has no NaN).
    """
    if hasattr(obj, "to_dict"):
        return jsonable(obj.to_dict())
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer | int):
        return int(obj)
    if isinstance(obj, np.floating | float):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj
