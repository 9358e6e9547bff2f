"""What every test shares: the FEM's disk cache is the repository's ``out/cache``, not the
user's cache folder (``~/.cache/psm-grasp``), so that a test run neither reads a user's entries
nor leaves its own there; tests that need an empty cache point ``PSM_GRASP_CACHE`` at their
own ``tmp_path``."""

from __future__ import annotations

import os
from pathlib import Path

# set at import, before any test (or a subprocess it starts, which inherits it) reaches the FEM
os.environ["PSM_GRASP_CACHE"] = str(Path(__file__).resolve().parents[1] / "out" / "cache")
