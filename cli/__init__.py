"""The ``psm-grasp`` command line, on top of both packages: ``envs`` (the model, its solver and
environment) and ``optim`` (the optimizers); neither imports it.

- :mod:`cli.main`: the parser, :func:`~cli.main.main` (the console script) and its error
  handling: a ``ValueError`` becomes one line ``psm-grasp: error: ...`` on stderr (exit 2), a
  reader that stops reading (``psm-grasp simulate --json | head -1``) a quiet exit.
- :mod:`cli.simulate`: ``psm-grasp simulate``.
- :mod:`cli.optimize`: ``psm-grasp optimize``, ``verify`` and ``demo``.
- :mod:`cli.options`: what the commands share (an option's name in front of its error).
"""
