"""What the commands share."""

from __future__ import annotations

__all__ = ["cli_option", "object_option"]


def cli_option(option: str, check, *args):
    """``check(*args)``, its ``ValueError`` prefixed with the command-line option's name (the
    library names its parameters, the user typed options)."""
    try:
        return check(*args)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def object_option(path, option: str = "--object"):
    """The object file of ``--object`` (:func:`envs.object_file.load_object`); a path that is
    no readable regular file is refused naming the option (what is in the file names the file,
    the table and the key)."""
    from envs.object_file import load_object
    from envs.validation import check_input_file

    cli_option(option, check_input_file, "the object file", path)
    return load_object(path)
