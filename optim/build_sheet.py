"""The build sheet (kept for its import path): see :mod:`optim.sheet`."""

from .sheet import *  # noqa: F403
from .sheet import __all__  # noqa: F401
