"""What the commands share."""

from __future__ import annotations

__all__ = ["cli_option"]


def cli_option(option: str, check, *args):
    """``check(*args)``, its ``ValueError`` prefixed with the command-line option's name (the
    library names its parameters, the user typed options)."""
    try:
        return check(*args)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None
