"""What the commands share."""

from __future__ import annotations

__all__ = ["cli_option", "object_option", "add_load_set_option"]


def cli_option(option: str, check, *args):
    """``check(*args)``, its ``ValueError`` prefixed with the command-line option's name (the
    library names its parameters, the user typed options)."""
    try:
        return check(*args)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def add_load_set_option(p, default: str) -> None:
    """``--load-set`` of a command: how the object is picked, the payload's directions
    (:mod:`envs.model.loads`); ``default``: what applies without it, in words."""
    from envs.model.loads import LOAD_SETS

    p.add_argument("--load-set", default=None, choices=LOAD_SETS,
                   help="how the object is picked, the payload's directions the grasp must "
                   "hold it in: top-down (along the gripper's axis, towards the tips and "
                   "back), side (out of the plane, both ways) or any (every in-plane "
                   f"direction and out of the plane) (default: {default})")


def object_option(path, option: str = "--object"):
    """The object file of ``--object`` (:func:`envs.object_file.load_object`); a path that is
    no readable regular file is refused naming the option (what is in the file names the file,
    the table and the key)."""
    from envs.object_file import load_object
    from envs.validation import check_input_file

    cli_option(option, check_input_file, "the object file", path)
    return load_object(path)
