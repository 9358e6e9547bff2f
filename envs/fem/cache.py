"""Disk cache of :func:`~envs.fem.fem_grasp` results, keyed by a hash of all inputs.

Entries are JSON files under ``$PSM_GRASP_CACHE/fem`` (default ``out/cache/fem`` relative to
the working directory); :data:`FEM_VERSION` is part of every key.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from .result import FemResult

#: Version tag of the discretisation and solver; part of the cache key.
# fem-3: contact fractions, stop torques, stretch strain; fem-4: holding; fem-5: the contact
# fractions interpolated between rim nodes (envs.model.contact_width)
FEM_VERSION = "fem-5"


def _cache_dir() -> Path:
    return Path(os.environ.get("PSM_GRASP_CACHE", os.path.join("out", "cache"))) / "fem"


def _cache_key(inputs: dict) -> str:
    text = json.dumps(inputs, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def _load_cache(path: Path, inputs: dict) -> list[FemResult] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if data.get("inputs") != inputs:
        return None
    try:
        return [FemResult.from_json(r) for r in data["results"]]
    except (KeyError, TypeError, ValueError):
        return None


def _store_cache(path: Path, inputs: dict, results: list[FemResult]) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".tmp{os.getpid()}")
        tmp.write_text(json.dumps({"inputs": inputs, "results": [r.to_json() for r in results]}))
        os.replace(tmp, path)
    except OSError:
        pass  # the cache is an optimisation only
