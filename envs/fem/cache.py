"""Disk cache of :func:`~envs.fem.fem_grasp` results, keyed by a hash of all inputs.

Entries are JSON files in :func:`fem_cache_dir`: ``$PSM_GRASP_CACHE/fem`` when that variable is
set, else the user's cache folder, ``$XDG_CACHE_HOME/psm-grasp/fem`` (default
``~/.cache/psm-grasp/fem``), never the working directory; :data:`FEM_VERSION` is part of every
key.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from .result import FemResult

#: Version tag of the discretisation and solver; part of the cache key.
# fem-3: contact fractions, stop torques, stretch strain; fem-4: holding; fem-5: the disk's
# lateral offset in the key (every disk field but the point-spring calibration scales); fem-6:
# the payload, the grip force and what limits the friction; fem-7: the pressure shift within the
# faces' Hertz patches; fem-8: the contact fractions interpolated between rim nodes
# (envs.model.contact_width); fem-9: a grooved jaw's runs of loaded rim nodes are pressure
# patches in the holding (envs.model.holding); fem-11 (fem-10 was a measured, reverted variant of
# the mouth edges' radius whose entries may still be in caches): a grooved jaw's contact shares
# by envs.model.contact_width.run_share (force-weighted curvature, the cap at most half a spacing
# below the extent at each edge); fem-12: the free object's grasp under load (envs.fem.loaded)
# and the load set
FEM_VERSION = "fem-12"


def fem_cache_dir() -> Path:
    """The folder of the FEM's cache entries: ``$PSM_GRASP_CACHE/fem`` when that variable is
    set (and not empty), else ``$XDG_CACHE_HOME/psm-grasp/fem`` when that is an absolute path
    (the XDG rule), else ``~/.cache/psm-grasp/fem``."""
    override = os.environ.get("PSM_GRASP_CACHE")
    if override:
        return Path(override).expanduser() / "fem"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "psm-grasp" / "fem"


_cache_dir = fem_cache_dir  # the name the grasp's solver imports


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
