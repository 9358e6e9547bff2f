"""numba's on-disk kernel cache, in a folder named by a digest of the package's source.

numba checks a cached kernel against the modification time of its own source file only. Most
of the solver's kernels inline or call functions of other files (the driver links the interior
point, the assembly, the model's energy terms, ...) and read constants of plain modules (the
named slots of :mod:`envs.model.layout`, the status codes), so after an edit of one of those a
cache shared across edits would go on running the old code with no sign of it. So the package's
kernels are cached in a folder of their own for each version of the source
(:func:`kernel_cache_dir`): an edit starts an empty folder (the next solve compiles, as after an
install), and a process still running the old code writes only to the old folder.

The folder is chosen while the package's modules create their kernels (:func:`kernel_cache`,
around the imports in ``envs/__init__.py``) through numba's public ``config.CACHE_DIR``, put
back afterwards: other numba code in the process keeps its own cache.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

import numba

__all__ = ["source_digest", "kernel_cache_dir", "kernel_cache", "KEEP_OLD"]

PACKAGE_ROOT = Path(__file__).resolve().parent
PREFIX = "numba-"
KEEP_OLD = 2  # older source versions' folders kept (a process may still run that code)


def source_digest(root: Path = PACKAGE_ROOT) -> str:
    """Digest of the path and text of every ``*.py`` file under ``root`` (~2 ms): kernels read
    constants of files that do not mention numba."""
    digest = hashlib.blake2b(digest_size=8)
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(folder, os.W_OK)


def kernel_cache_dir(digest: str, root: Path = PACKAGE_ROOT) -> Path:
    """Where the kernels of this source version are cached: inside ``NUMBA_CACHE_DIR`` when the
    user set it, else beside the sources (``__pycache__``), else (a read-only install) in the
    user's cache folder."""
    name = f"{PREFIX}{digest}"
    user_dir = os.environ.get("NUMBA_CACHE_DIR")
    if user_dir:
        return Path(user_dir) / f"psm-grasp-{name}"
    if _writable(root / "__pycache__"):
        return root / "__pycache__" / name
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "psm-grasp" / name


def _prune(folder: Path) -> None:
    """Delete all but the :data:`KEEP_OLD` newest other versions' folders beside ``folder``."""
    prefix = folder.name[: folder.name.index(PREFIX) + len(PREFIX)]
    others = [p for p in folder.parent.glob(f"{prefix}*") if p.is_dir() and p != folder]
    others.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    for old in others[KEEP_OLD:]:
        shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def kernel_cache(root: Path = PACKAGE_ROOT) -> Iterator[Path | None]:
    """Within it, numba kernels created with ``cache=True`` are cached in
    :func:`kernel_cache_dir` of the current source; yields that folder (``None`` if no folder
    can be written: numba's own choice then)."""
    folder = kernel_cache_dir(source_digest(root), root)
    if not _writable(folder):
        yield None
        return
    with contextlib.suppress(OSError):
        _prune(folder)
    previous = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(folder)
    try:
        yield folder
    finally:
        numba.config.CACHE_DIR = previous
