"""``python -m cli``: the ``psm-grasp`` command."""

from .main import main

raise SystemExit(main())
