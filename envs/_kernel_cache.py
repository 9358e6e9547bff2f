"""numba's on-disk kernel cache, kept in step with the whole of the package's compiled source.

numba checks a cached kernel against the modification time of its own source file only. Most
of the solver's kernels inline or call functions of other files (the driver links the interior
point, the assembly, the model's energy terms, ...), so after an edit of one of those a warm
cache would go on running the old code with no sign of it. Before any kernel loads,
:func:`refresh_cache` compares a digest of every source file that uses numba with the one
stored beside the cache and, when they differ, deletes the cached kernels (the next solve
compiles them again, as after an install).

Only the cache next to the sources is handled: a read-only install keeps numba's cache in its
user-wide folder, where an upgrade changes every file's time anyway.
"""

from __future__ import annotations

import hashlib
from itertools import chain
from pathlib import Path

__all__ = ["source_digest", "refresh_cache"]

PACKAGE_ROOT = Path(__file__).resolve().parent
STAMP_NAME = "numba-source.stamp"


def source_digest(root: Path = PACKAGE_ROOT) -> str:
    """Digest of the path and text of every ``*.py`` file under ``root`` that uses numba."""
    digest = hashlib.blake2b(digest_size=16)
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"numba" in text:
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(text)
    return digest.hexdigest()


def refresh_cache(root: Path = PACKAGE_ROOT) -> bool:
    """Delete numba's cached kernels under ``root`` if its compiled source changed since they
    were written (or nothing records it); returns whether it deleted.

    A folder it cannot write (a read-only install) is left alone.
    """
    stamp = root / "__pycache__" / STAMP_NAME
    digest = source_digest(root)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    try:
        for cached in chain(root.rglob("*.nbi"), root.rglob("*.nbc")):
            cached.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(digest)
    except OSError:
        return False
    return True


# at the package's import, before any kernel loads (envs/__init__.py imports this first)
refresh_cache()
