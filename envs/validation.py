"""Validation of public inputs, one function per kind of field, used at every public entry.

Every failure is a ``ValueError`` whose message names the parameter, the value given and the
allowed range, so that a user sees at once what to change.
"""

from __future__ import annotations

import math
import numbers
import os
import re
import stat
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
    "real_array",
    "check_sequence",
    "check_output_file",
    "check_output_dir",
    "check_plausible",
    "check_regular_file",
    "check_input_file",
    "unit_slip",
    "slip_hint",
    "read_text_file",
    "PsmGraspWarning",
    "UnitSlipWarning",
    "InputWarning",
    "MAX_INPUT_BYTES",
]

# the largest file a user may hand in (an object file, a run's result, a policy): far above
# any the package writes (a result of a 10^7-evaluation run is a few MB), far below a mistake
# such as a disk image that would be read into memory for minutes
MAX_INPUT_BYTES = 64 * 2**20


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


def _shown(value, v: float) -> str:
    """A real number as the caller wrote it (``15``, not ``15.0``; a numpy number as its
    Python value), for an error message; ``v`` is its float."""
    if type(value) is int or type(value) is float:
        return repr(value)
    item = getattr(value, "item", None)
    if callable(item):
        try:
            return repr(item())
        except (TypeError, ValueError):
            pass
    return repr(v)


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
        def inside(x: float) -> bool:
            return (x > low if low_open else x >= low) and (x < high if high_open else x <= high)

        raise ValueError(f"{name} = {_shown(value, v)} is outside the allowed range {allowed}"
                         + slip_hint(name, v, inside))
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


def check_regular_file(name: str, path) -> Path:
    """``path`` as a :class:`~pathlib.Path` if it is a regular file (links followed), else
    one ``ValueError`` naming the path, ``name`` (what it should be: ``"the object file"``)
    and what it is instead. Checked before any ``open``: opening a FIFO without a writer, or
    a terminal, blocks until someone writes."""
    text = os.fspath(path) if isinstance(path, str | os.PathLike) else path
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"{name} must be the path of a file, got {path!r}")
    try:
        mode = os.stat(text).st_mode
    except OSError as exc:
        raise ValueError(f"{text!r}: cannot read {name} ({exc.strerror or exc})") from None
    if not stat.S_ISREG(mode):
        kind = ("a folder" if stat.S_ISDIR(mode) else "a FIFO (named pipe)"
                if stat.S_ISFIFO(mode) else "a device" if stat.S_ISCHR(mode)
                or stat.S_ISBLK(mode) else "a socket" if stat.S_ISSOCK(mode) else "special")
        raise ValueError(f"{text!r}: cannot read {name} (it is {kind}, not a regular file"
                         + ("" if kind == "a folder" else ": reading it could block") + ")")
    return Path(text)


def check_input_file(name: str, path, max_bytes: int = MAX_INPUT_BYTES) -> Path:
    """A file the user hands in: a regular file (:func:`check_regular_file`) of at most
    ``max_bytes``; one ``ValueError`` line naming the path and ``name`` (``"the object
    file"``) otherwise."""
    p = check_regular_file(name, path)
    size = p.stat().st_size
    if size > max_bytes:
        raise ValueError(f"{str(p)!r}: cannot read {name} (it is {size / 2**20:.0f} MiB, more "
                         f"than the {max_bytes / 2**20:.0f} MiB any such file holds)")
    return p


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


_DTYPE_WORDS = {"U": "str", "S": "bytes", "b": "bool", "c": "complex", "M": "datetime",
                "m": "timedelta", "V": "records"}


def real_array(name: str, value, what: str = "numbers") -> np.ndarray:
    """``value`` as a float64 array if it holds real numbers only; one ``ValueError`` naming
    ``name`` otherwise. numpy would turn the strings ``"0.1"`` into numbers and ``True`` into
    1: an array of strings, bytes, bools or complex numbers, or an object array holding one, is
    refused (``what``: the array's meaning in the message). A ragged sequence is refused too."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of {what}: {exc}") from None
    if raw.dtype.kind == "O":
        for index, v in np.ndenumerate(raw):
            if _real(v) is None:
                raise ValueError(f"{name}[{', '.join(map(str, index))}] must be a real number, "
                                 f"got {_kind(v)}")
    elif raw.dtype.kind not in "fiu":
        raise ValueError(f"{name} must be an array of {what}, got an array of "
                         f"{_DTYPE_WORDS.get(raw.dtype.kind, str(raw.dtype))}")
    try:
        return raw.astype(np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be an array of {what}: {exc}") from None


def check_sequence(name: str, value, length: int | None = None) -> tuple:
    """``value`` as a tuple if it is a sequence of values (a tuple, a list, a 1-D array; not
    a string, a mapping or a number), of ``length`` items if given; ``ValueError`` naming
    ``name`` otherwise."""
    if isinstance(value, str | bytes | dict) or not hasattr(value, "__iter__") or (
            isinstance(value, np.ndarray) and value.ndim != 1):
        raise ValueError(f"{name} must be a sequence of numbers"
                         + (f" ({length})" if length is not None else "")
                         + f", got {_kind(value)}")
    items = tuple(value)
    if length is not None and len(items) != length:
        raise ValueError(f"{name} needs {length} values, got {len(items)}")
    return items


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


def _not_empty(name: str, path) -> None:
    """An output path that names nothing (``--out ''``) is refused: ``Path('')`` is the
    current folder, which nobody typed."""
    text = os.fspath(path) if isinstance(path, str | os.PathLike) else path
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"{name} must be a path, got {path!r}")


def _writable_file(name: str, path: Path, shown) -> None:
    """An existing file opened for appending (which leaves its content as is) and closed."""
    if not path.is_file():  # a FIFO or a device: opening it could block, writing never end
        raise ValueError(f"{name} = {str(shown)!r} exists and is not a regular file")
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
    _not_empty(name, path)
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
    _not_empty(name, path)
    p = Path(path)
    if p.exists():
        _writable_dir(name, p, path)
    else:
        _writable_dir(name, p.parent if str(p.parent) else Path("."), path)
    return p


# the units a value outside its range was most likely typed in, by the unit its name ends in
# (longest first): (factor to SI, unit) tried in order
_UNIT_SLIPS: tuple[tuple[str, tuple[tuple[float, str], ...]], ...] = (
    ("_nm_per_rad", ((1e-3, "N·mm/rad"), (180.0 / math.pi, "N·m/deg"))),
    ("_kg_m3", ((1e3, "g/cm^3"), (1e-3, "g/m^3"))),
    ("_pa", ((1e6, "MPa"), (1e3, "kPa"), (1e9, "GPa"))),
    ("_nm", ((1e-3, "N·mm"),)),
    ("_rad", ((math.pi / 180.0, "degrees"),)),
    ("_m", ((1e-3, "millimetres"), (1e-2, "centimetres"), (1e-6, "micrometres"))),
)
_SUFFIX_UNITS = {"_m": "m", "_pa": "Pa", "_kg_m3": "kg/m^3", "_rad": "rad", "_nm": "N·m",
                 "_nm_per_rad": "N·m/rad"}
# what a plausible range is the range of, by field (the rest: of a gripper)
_OBJECT_FIELDS = ("radius_m", "thickness_m", "youngs_modulus_pa", "density_kg_m3",
                  "stiffness_scale", "placement_tolerance_m")


def _base_key(name: str) -> str:
    """The field a parameter's name refers to: ``radius_m[1]`` -> ``radius_m``,
    ``DesignBounds.high[rest_angle_rad]`` -> ``rest_angle_rad``, ``--torque`` -> ``torque``,
    ``[gripper] finger_length_m`` -> ``finger_length_m``."""
    inner = re.findall(r"\[([A-Za-z_]\w*)\]", name)
    if inner and inner[-1] not in ("object", "gripper"):
        return inner[-1]
    bare = re.sub(r"\[[^\]]*\]", "", name).strip().split()[-1:] or [""]
    return bare[0].rsplit(".", 1)[-1].lstrip("-").replace("-", "_")


def slip_hint(name: str, value: float, inside) -> str:
    """The unit ``value`` of the parameter ``name`` was most likely typed in: ``": was it
    typed in millimetres? 15 millimetres is 0.015 m"``, the first of the units of its name's
    unit suffix (``_m``, ``_rad``, ``_pa``, ``_kg_m3``, ``_nm``, ``_nm_per_rad``) that brings it
    ``inside`` (a predicate on SI values); ``""`` when none does."""
    key = _base_key(name)
    for suffix, units in _UNIT_SLIPS:
        if key.endswith(suffix):
            for factor, unit in units:
                if inside(value * factor):
                    return (f": was it typed in {unit}? {value:g} {unit} is "
                            f"{value * factor:.4g} {_SUFFIX_UNITS[suffix]}")
            return ""
    return ""


class PsmGraspWarning(UserWarning):
    """Base of the package's own warnings (the command line shows them as one line
    ``psm-grasp: warning: ...``, each once)."""


class UnitSlipWarning(PsmGraspWarning):
    """A value outside the plausible range of an object's description (most likely typed in
    another unit). Kept for callers that filter it: every entry now refuses such a value
    (:func:`check_plausible`)."""


class InputWarning(PsmGraspWarning):
    """Part of an input was handled rather than refused: rows of a batch that hold a value
    that is not a finite number are flagged and left unsolved, the other rows answered."""


def unit_slip(name: str, value: float, shown: str | None = None) -> str | None:
    """The message for a value outside its plausible range
    (:data:`envs.model.defaults.PLAUSIBLE_RANGES`: an object's radius, thickness, modulus,
    density and stiffness scale, a gripper's lengths and joint spring), naming the unit it was
    most likely typed in; ``None`` for a plausible value (or a field without a range).

    Parameters
    ----------
    name
        The parameter as the user knows it (``radius_m``, ``radius_m[1]`` for a range's end,
        ``[gripper] finger_length_m``): its field is the last name in it.
    value
        Its value in SI units.
    shown
        The value as the user wrote it (default ``repr(value)``).
    """
    from envs.model.defaults import PLAUSIBLE_RANGES

    key = _base_key(name)
    if key not in PLAUSIBLE_RANGES or not math.isfinite(value):
        return None
    low, high = PLAUSIBLE_RANGES[key]
    if low <= value <= high:
        return None
    what = "a graspable object" if key in _OBJECT_FIELDS else "a gripper"
    return (f"{name} = {shown or repr(value)} is outside the plausible range "
            f"[{low:g}, {high:g}] of {what} (SI units)"
            + slip_hint(name, value, lambda x: low <= x <= high))


def check_plausible(name: str, value) -> float:
    """Validate a real number that has a plausible range
    (:data:`envs.model.defaults.PLAUSIBLE_RANGES`, by the field ``name`` ends in); returns it
    as ``float``.

    Raises
    ------
    ValueError
        One line naming the parameter, the value, the plausible range and the unit it was most
        likely typed in (``radius_m = 15``: millimetres).
    """
    v = check_real(name, value)
    slip = unit_slip(name, v, _shown(value, v))
    if slip is not None:
        raise ValueError(slip)
    return v


def read_text_file(path, kind: str, fmt: str, encoding: str = "utf-8") -> str:
    """The text of a file the user named, or one ``ValueError`` line naming it: ``cannot read
    the {kind} file (...)``, ``not a text ({fmt}) file``, or not a regular file of at most
    :data:`MAX_INPUT_BYTES` (a FIFO or a device, checked before it is opened: reading one
    could block forever)."""
    p = check_input_file(f"the {kind} file", path)
    try:
        return p.read_text(encoding=encoding)
    except OSError as exc:
        raise ValueError(f"{str(p)!r}: cannot read the {kind} file ({exc.strerror or exc})"
                         ) from None
    except UnicodeDecodeError:
        raise ValueError(f"{str(p)!r}: not a text ({fmt}) file") from None
