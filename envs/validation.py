"""Validation of public inputs, one function per kind of field, used at every public entry.

Every failure is a ``ValueError`` whose message names the parameter, the value given and the
allowed range, so that a user sees at once what to change.
"""

from __future__ import annotations

import math
import numbers
import os
import tempfile
from pathlib import Path

import numpy as np

from envs.model.defaults import MAX_TRIANGLES, MIN_TRIANGLES

__all__ = [
    "check_range",
    "check_integer",
    "check_n_triangles",
    "check_choice",
    "check_real",
    "check_output_file",
    "check_output_dir",
    "unit_slip",
    "read_text_file",
    "UnitSlipWarning",
]


def _real(value) -> float | None:
    """``value`` as a float when it is a real number, else None.

    Real numbers are Python and numpy integers and floats (and 0-d numeric arrays); a string is
    refused although ``float("0.2")`` would parse it, and so is a bool although ``float(True)``
    is 1: either is a caller's mistake that would otherwise run with a value nobody typed.
    """
    kind = type(value)
    if kind is float or kind is int:  # the common case first: this runs for every row
        return float(value)
    if isinstance(value, bool | np.bool_):
        return None
    if isinstance(value, numbers.Real) or (
            isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"):
        try:
            return float(value)
        except OverflowError:  # an int beyond the float range: infinite for the range check
            return math.copysign(math.inf, value)
    return None


def _kind(value) -> str:
    """The value and its type, for an error message (``'0.2' (str)``)."""
    return f"{value!r} ({type(value).__name__})"


def check_range(
    name: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Validate that ``value`` is a finite real number inside an interval.

    Parameters
    ----------
    name
        Name of the parameter, used in the error message.
    value
        The value to check: a Python or numpy integer or float (not a bool, not a string).
    low, high
        Interval bounds.
    low_open, high_open
        Whether the bounds are excluded.

    Returns
    -------
    float
        ``value`` converted to ``float``.

    Raises
    ------
    ValueError
        If ``value`` is not a real number (a string or a bool included), not finite or outside
        the interval; the message names the parameter, the value and the allowed range.
    """
    lo_b = "(" if low_open else "["
    hi_b = ")" if high_open else "]"
    allowed = f"{lo_b}{low:g}, {high:g}{hi_b}"
    v = _real(value)
    if v is None:
        raise ValueError(f"{name} must be a real number in {allowed}, got {_kind(value)}")
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite and in {allowed}, got {v!r}")
    below = v <= low if low_open else v < low
    above = v >= high if high_open else v > high
    if below or above:
        raise ValueError(f"{name} = {v!r} is outside the allowed range {allowed}")
    return v


def check_integer(name: str, value, low: int, high: int) -> int:
    """Validate that ``value`` is an integer (a Python or numpy integer, or a float with an
    integral value; not a bool, not a string) in ``[low, high]``; returns it as ``int``.

    Raises
    ------
    ValueError
        Naming the parameter, the value and the allowed range.
    """
    v = _real(value)
    if v is None:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {_kind(value)}")
    if not math.isfinite(v) or v != int(v):
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    if not low <= int(v) <= high:
        raise ValueError(f"{name} = {int(v)} is outside the allowed range [{low}, {high}]")
    return int(v)


def check_n_triangles(n_triangles) -> int:
    """Validate the number of fan triangles ``N``.

    ``N = 3`` gives 120-degree triangles, i.e. negative stiffness under the area rule; above
    :data:`~envs.model.defaults.MAX_TRIANGLES` the solver mostly fails.
    """
    try:
        return check_integer("n_triangles", n_triangles, MIN_TRIANGLES, MAX_TRIANGLES)
    except ValueError as exc:
        if "outside" in str(exc) and float(n_triangles) > MAX_TRIANGLES:
            raise ValueError(f"{exc}: beyond N = {MAX_TRIANGLES} most solves fail "
                             "(MAX_TRIANGLES, measured in envs/model/defaults.py)") from None
        raise


def check_real(name: str, value) -> float:
    """Validate that ``value`` is a real number (a Python or numpy integer or float, not a bool,
    not a string), finite or not; returns it as ``float``.

    For fields that may hold any number (a design may be impossible: the evaluator reports
    it) but must not hold something else.

    Raises
    ------
    ValueError
        Naming the parameter, the value and its type.
    """
    v = _real(value)
    if v is None:
        raise ValueError(f"{name} must be a real number, got {_kind(value)}")
    return v


def check_choice(name: str, value, allowed) -> str:
    """Validate that ``value`` is one of ``allowed``."""
    if not isinstance(value, str) or value not in allowed:
        raise ValueError(f"{name} = {value!r} is not one of {tuple(allowed)}")
    return value


def _writable_dir(name: str, folder: Path, shown) -> None:
    if not folder.exists():
        raise ValueError(f"{name} = {str(shown)!r}: the folder {str(folder)!r} does not exist "
                         "(create it first)")
    if not folder.is_dir():
        raise ValueError(f"{name} = {str(shown)!r}: {str(folder)!r} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        raise ValueError(f"{name} = {str(shown)!r}: the folder {str(folder)!r} is not writable")
    # permissions do not tell the whole story (root passes os.access; /proc, /sys and read-only
    # mounts refuse new files anyway): write a file there now, not after the work is done
    try:
        fd, probe = tempfile.mkstemp(prefix=".psm-grasp-probe-", dir=folder)
    except OSError as exc:
        raise ValueError(f"{name} = {str(shown)!r}: cannot write in the folder {str(folder)!r} "
                         f"({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(probe)


def _writable_file(name: str, path: Path, shown) -> None:
    """An existing file opened for appending (which leaves its content as is) and closed."""
    try:
        with open(path, "ab"):
            pass
    except OSError as exc:
        raise ValueError(f"{name} = {str(shown)!r} exists and cannot be written "
                         f"({exc.strerror or exc})") from None


def check_output_file(name: str, path, suffixes: tuple[str, ...]) -> Path:
    """Validate an output file before any work: its folder exists and a file can be created in
    it (tried: a temporary file is written and removed), the path is not a folder, an existing
    file can be written and the extension is one of ``suffixes`` (e.g. ``(".png",)``).

    Raises
    ------
    ValueError
        Naming the option, the user's path and what is wrong with it.
    """
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"{name} = {str(path)!r} must end in {' or '.join(suffixes)} (the "
                         f"format written), got {p.suffix or 'no extension'!r}")
    if p.is_dir():
        raise ValueError(f"{name} = {str(path)!r} is a folder, not a file")
    _writable_dir(name, p.parent if str(p.parent) else Path("."), path)
    if p.exists():
        if not os.access(p, os.W_OK):
            raise ValueError(f"{name} = {str(path)!r} exists and is not writable")
        _writable_file(name, p, path)
    return p


def check_output_dir(name: str, path) -> Path:
    """Validate an output folder before any work: it is a writable folder, or it does not exist
    yet and its parent is a writable folder (it is created then). Writable means a file could
    be created there: a temporary file is written and removed (the permission bits alone pass
    ``/proc``, ``/sys``, read-only mounts and every folder for root).

    Raises
    ------
    ValueError
        Naming the option, the user's path and what is wrong with it.
    """
    p = Path(path)
    if p.exists():
        _writable_dir(name, p, path)
    else:
        _writable_dir(name, p.parent if str(p.parent) else Path("."), path)
    return p


# the unit a value outside its plausible range was most likely typed in: (factor to SI, unit)
_SLIPS = {
    "radius_m": ((1e-3, "millimetres"), (1e-2, "centimetres")),
    "thickness_m": ((1e-3, "millimetres"), (1e-2, "centimetres")),
    "youngs_modulus_pa": ((1e6, "MPa"), (1e3, "kPa"), (1e9, "GPa")),
    "density_kg_m3": ((1e3, "g/cm^3"), (1e-3, "g/m^3")),
}


class UnitSlipWarning(UserWarning):
    """A value outside the plausible range of an object's description (most likely typed in
    another unit); the API warns, object files and the command line refuse it."""


def unit_slip(name: str, value: float) -> str | None:
    """The message for a value of an object's field outside its plausible range
    (:data:`envs.model.defaults.PLAUSIBLE_RANGES`), naming the unit it was most likely typed
    in; ``None`` for a plausible value (or a field without a range).

    Parameters
    ----------
    name
        The field (``radius_m``, ``thickness_m``, ``youngs_modulus_pa``, ``density_kg_m3``).
    value
        Its value in SI units.
    """
    from envs.model.defaults import PLAUSIBLE_RANGES

    if name not in PLAUSIBLE_RANGES or not math.isfinite(value):
        return None
    low, high = PLAUSIBLE_RANGES[name]
    if low <= value <= high:
        return None
    guess = ""
    for factor, unit in _SLIPS.get(name, ()):
        if low <= value * factor <= high:
            guess = f": was it typed in {unit}? {value:g} {unit} is {value * factor:g} in SI"
            break
    return (f"{name} = {value:g} is outside the plausible range [{low:g}, {high:g}] of a "
            f"graspable object (SI units){guess}")


def read_text_file(path, kind: str, fmt: str, encoding: str = "utf-8") -> str:
    """The text of a file the user named, or one ``ValueError`` line naming it: ``cannot read
    the {kind} file (...)`` or ``not a text ({fmt}) file``."""
    from pathlib import Path

    p = Path(path)
    try:
        return p.read_text(encoding=encoding)
    except OSError as exc:
        raise ValueError(f"{str(p)!r}: cannot read the {kind} file ({exc.strerror or exc})"
                         ) from None
    except UnicodeDecodeError:
        raise ValueError(f"{str(p)!r}: not a text ({fmt}) file") from None
