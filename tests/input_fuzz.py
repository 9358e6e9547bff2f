"""Bad inputs generated from the package's schemas, for every public entry, and the outcome of
each (run by ``tests/test_fuzz_inputs.py``; counted by ``scripts/fuzz_inputs.py``).

The cases are generated, not listed, so that a key or an option added later is fuzzed as soon
as it exists:

- object files: the rules of the ``[object]`` and ``[gripper]`` tables
  (:data:`envs.object_file.OBJECT_KEYS`, :data:`~envs.object_file.GRIPPER_KEYS`, every key of
  :data:`~envs.object_file.OBJECT_TABLE_KEYS`, the range-able keys of
  :data:`envs.scenarios.RANGE_FIELDS`) and the plausible ranges
  (:data:`envs.model.defaults.PLAUSIBLE_RANGES`);
- the command line: every option of :func:`cli.main.build_parser`, by its type;
- the API: the fields of the parameter dataclasses and the numeric keywords of the entry
  functions' signatures, the environments' reset options and actions;
- data read back: every field of :class:`optim.result.OptimResult` in a result file, the
  object's keys and the design's fields in it; every key of a policy's ``policy.json`` and every
  array of its ``policy.npz``.

A case is plain data (JSON-able): an ``entry``, the ``name`` a refusal must name, the
``expect`` ed outcome class and what to feed. :func:`run_case` feeds it and classifies what
happened, by class, not by message:

- ``refused``: a ``ValueError`` (``ResetNeeded`` for an env stepped after its end) or, on the
  command line, exit code 2, with one line that names the input (and no traceback);
- ``unnamed``: refused, but the line does not name the input, or is not one line;
- ``handled``: accepted with the package's warning naming the input (NaN rows of a batch);
- ``valid``: accepted; on the command line and in the drivers the work itself is replaced by
  a stand-in, so that an accepted input is seen at once and costs nothing;
- ``crash``: another exception, or a traceback; ``hang``: no answer within
  :data:`TIMEOUT_S`.

Only the public entries of the package are used to run a case (not the generator's own
imports), so that the same cases can be run against another version of the package (the
counts before and after a change: ``scripts/fuzz_inputs.py --write/--run``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import io
import json
import math
import os
import re
import shutil
import signal
import sys
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT_S = 10.0  # an input that takes longer to refuse or accept is a hang
OUTCOMES = ("refused", "unnamed", "handled", "valid", "crash", "hang")

# a valid object and gripper (a cherry tomato in the gripper of envs/object_file.py's docstring)
GOOD_OBJECT = {"radius_m": 0.012, "youngs_modulus_pa": 150e3, "poisson_ratio": 0.45,
               "thickness_m": 0.024}
GOOD_GRIPPER = {"finger_length_m": 0.05, "rest_angle_deg": 30, "joint_offset_m": 0.002,
                "finger_width_m": 0.004, "distance_m": 0.01}
# what is no number, or no plausible one, whatever the parameter
NOT_NUMBERS = ["0.5 m", True, [0.1], {"x": 1}]
NOT_FINITE = [math.nan, math.inf, -math.inf]
HUGE = [1e30, -1e30]


class Accepted(Exception):  # noqa: N818 - a signal, not an error
    """Raised by the stand-in of the work: the input was accepted."""


class _Timeout(Exception):  # noqa: N818
    pass


# --- the values ------------------------------------------------------------------------------


def _typical(low: float, high: float, plausible: tuple[float, float] | None) -> float:
    """A value well inside a key's allowed and plausible range."""
    if plausible is not None:
        low, high = max(low, plausible[0]), min(high, plausible[1])
    if low > 0 and high / low > 100:
        return math.sqrt(low * high)
    if not math.isfinite(high):
        return max(low, 0.0) + 1.0
    return 0.5 * (low + high)


def _inside(value: float, rule, plausible) -> bool:
    low, high, low_open, high_open = rule[:4]
    if not math.isfinite(value):
        return False
    if (value <= low if low_open else value < low) or (value >= high if high_open
                                                       else value > high):
        return False
    return plausible is None or plausible[0] <= value <= plausible[1]


def number_values(rule, plausible, typical: float | None = None) -> list[tuple[Any, str]]:
    """Values of a number with a rule ``(low, high, low_open, high_open, ...)`` and a plausible
    range (or None), each with its expected outcome: the ends of both ranges and beyond them,
    the unit slips of a typical value (millimetres, degrees: a factor 1000 and 57), what is no
    number, not finite or huge. ``typical``: a valid value (default: one inside both ranges)."""
    low, high = rule[0], rule[1]
    if typical is None:
        typical = _typical(low, high, plausible)
    numbers = {typical, typical * 1000.0, typical / 1000.0, typical * 180.0 / math.pi}
    for end in (low, high, *(plausible or ())):
        if math.isfinite(end):
            numbers.update({end, end - max(1.0, abs(end)), end + max(1.0, abs(end))})
    out = [(v, "valid" if _inside(v, rule, plausible) else "refused") for v in sorted(numbers)]
    return out + [(v, "refused") for v in [*NOT_NUMBERS, *NOT_FINITE, *HUGE]]


# --- object files ----------------------------------------------------------------------------


def toml_value(value: Any) -> str:
    """A TOML value (numbers, strings, booleans, arrays, inline tables; nan and inf)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(value)


def toml_text(tables: dict[str, dict[str, Any]]) -> str:
    return "".join(f"[{name}]\n" + "".join(f"{k} = {toml_value(v)}\n" for k, v in t.items())
                   for name, t in tables.items())


def _alternatives(key: str, table: dict[str, Any]) -> dict[str, Any]:
    """The table without the keys that give the same quantity in another unit
    (``rest_angle_deg`` for ``rest_angle_rad``): a key fuzzed alone."""
    stem = key.rsplit("_", 1)[0]
    return {k: v for k, v in table.items()
            if k == key or k.rsplit("_", 1)[0] != stem or k.count("_") != key.count("_")}


def _file_case(label: str, tables: dict, name: str, expect: str) -> dict[str, Any]:
    return {"entry": "object file", "label": label, "name": name, "expect": expect,
            "text": toml_text(tables)}


def object_file_cases() -> list[dict[str, Any]]:
    """Every key of both tables with the values of its rule, ranges for the range-able keys,
    wrong types for every other key, unknown and missing keys."""
    from envs.model.defaults import PLAUSIBLE_RANGES
    from envs.object_file import GRIPPER_KEYS, OBJECT_KEYS, OBJECT_TABLE_KEYS, TOLERANCE_KEY
    from envs.scenarios import RANGE_FIELDS

    cases = []
    numeric = {"object": {**OBJECT_KEYS, TOLERANCE_KEY: (0.0, math.inf, False, False, False)},
               "gripper": GRIPPER_KEYS}
    for table, rules in numeric.items():
        for key, rule in rules.items():
            plausible = PLAUSIBLE_RANGES.get(key)
            good = {**GOOD_OBJECT, **GOOD_GRIPPER}.get(key)
            for value, expect in number_values(rule, plausible, good):
                tables = {"object": dict(GOOD_OBJECT)}
                if table == "gripper":
                    tables["gripper"] = _alternatives(key, {**GOOD_GRIPPER, key: value})
                else:
                    tables["object"][key] = value
                if table == "gripper" and key == "torque_nm" and expect == "valid":
                    # plausible on this object: at most MAX_TORQUE_UNITS of its torque unit
                    expect = _torque_expect(value, tables)
                if key == TOLERANCE_KEY and expect == "valid" and isinstance(
                        value, int | float) and value > GOOD_OBJECT["radius_m"]:
                    expect = "refused"  # a placement error beyond the object's radius
                cases.append(_file_case(f"[{table}] {key} = {value!r}", tables, key, expect))
            if key in RANGE_FIELDS and table == "object":
                cases += _range_cases(key, rule, plausible)
        required = [k for k, r in rules.items() if r[-1]]
        base = {"object": dict(GOOD_OBJECT), "gripper": dict(GOOD_GRIPPER)}
        for key in required:
            tables = {t: {k: v for k, v in base[t].items() if k != key} for t in base}
            cases.append(_file_case(f"[{table}] without {key}", tables, key, "refused"))
        tables = {t: dict(v) for t, v in base.items()}
        tables[table][f"{next(iter(rules))}x"] = 1.0
        cases.append(_file_case(f"[{table}] unknown key", tables, f"{next(iter(rules))}x",
                                "refused"))
    # the keys that are not numbers (a name, the jaws, keys added later): wrong types
    for key in OBJECT_TABLE_KEYS:
        if key in numeric["object"]:
            continue
        for value in ({"a": 1}, [[1, 2]], 12, "", "round", 1.5):
            if isinstance(value, str) and value == "round" and key == "name":
                continue  # (a name may be any word)
            cases.append(_file_case(f"[object] {key} = {value!r}",
                                    {"object": {**GOOD_OBJECT, key: value}}, key, "refused"))
    cases.append(_file_case("a good file", {"object": GOOD_OBJECT, "gripper": GOOD_GRIPPER},
                            "", "valid"))
    return cases


def _torque_expect(torque: float, tables: dict) -> str:
    from envs.model.defaults import MAX_TORQUE_UNITS, PAPER_TORSION_STIFFNESS_REL

    o = tables["object"]
    unit = o.get("stiffness_scale", 1.0) * o["youngs_modulus_pa"] * o["thickness_m"] * (
        o["radius_m"] ** 2)
    kf = PAPER_TORSION_STIFFNESS_REL * unit
    return "valid" if torque <= MAX_TORQUE_UNITS * unit + kf * math.pi / 2 else "refused"


def _range_cases(key: str, rule, plausible) -> list[dict[str, Any]]:
    typical = _typical(rule[0], rule[1], plausible)
    lo, hi = sorted((typical * 0.9, typical * 1.1))
    far = (plausible[1] * 1000.0 if plausible else math.inf)
    values = [([lo, hi], "valid"), ([hi, lo], "refused"), ([typical], "refused"),
              ([lo, typical, hi], "refused"), (["a", "b"], "refused"), ([True, False], "refused"),
              ([lo, math.nan], "refused"), ([lo, far], "refused"), ([far, far * 2], "refused"),
              ([-far * 2, -far], "refused")]
    return [_file_case(f"[object] {key} = {v!r}", {"object": {**GOOD_OBJECT, key: v}}, key, e)
            for v, e in values]


def file_cases() -> list[dict[str, Any]]:
    """Files that are not object files: what is not a regular file must be refused before it
    is opened (a FIFO without a writer would block for ever), and so must the rest."""
    kinds = ("fifo", "folder", "missing", "device", "empty", "binary", "huge", "bom")
    return [{"entry": "object file", "label": f"a {kind} file", "name": "{path}",
             "expect": "valid" if kind == "bom" else "refused", "file": kind} for kind in kinds]


# --- the command line ------------------------------------------------------------------------

CLI_BASE = {  # a valid command line of each command, paths in the case's folder
    "simulate": [],
    "demo": ["--out", "{tmp}/demo"],
    "optimize": ["--out", "{tmp}/optimize", "--no-progress"],
    "verify": ["{run}"],
    "train-policy": ["--out", "{tmp}/train", "--no-progress"],
    "design": ["--object", "{object}", "--out", "{tmp}/design", "--no-progress"],
}
# options that name files or folders, by their destination: outputs (refused when empty, when
# an existing regular file stands for a folder, when they are no regular file) and inputs
OUTPUT_DESTS = ("out", "plot")
PATH_METAVARS = ("FILE", "DIR", "PNG")


def _is_path(action) -> bool:
    return action.dest in OUTPUT_DESTS or any(m in str(action.metavar or "")
                                             for m in PATH_METAVARS)


def cli_values(action) -> list[str]:
    """Bad command-line values of an option, by its type."""
    if action.choices is not None:
        return ["no-such-choice", ""]
    if action.type in (int, float):
        return ["nan", "inf", "-inf", "1e30", "-1e30", "-1", "abc", "", "2.5e400"]
    if action.type is not None:  # a parsing function (M[,M])
        return ["nan", "inf", "-1", "1e30", "abc", ""]
    if _is_path(action):
        return ["", "{fifo}", "/dev/null", "{tmp}/no/such/place", "{file}"
                if action.dest in OUTPUT_DESTS else "{tmp}"]
    return ["", " "]


def cli_cases() -> list[dict[str, Any]]:
    """Every option of every command with the bad values of its type (argparse's option list:
    an option added later is fuzzed as soon as it exists)."""
    import argparse

    from cli.main import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    cases = []
    for command, parser in sub.choices.items():
        base = CLI_BASE.get(command, [])
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction) or action.nargs == 0:
                continue
            flag = action.option_strings[0] if action.option_strings else None
            name = flag or action.metavar or action.dest
            for value in cli_values(action):
                if flag is None:  # the positional: in place of the base one
                    argv = [command, value, *base[1:]]
                else:
                    argv = [command, *_without(base, flag), flag, value]
                cases.append({"entry": f"cli {command}", "label": " ".join(argv[1:]) or command,
                              "name": name, "expect": "refused", "argv": argv})
        cases.append({"entry": f"cli {command}", "label": f"{command} (valid)", "name": "",
                      "expect": "valid", "argv": [command, *base]})
    return cases


def _without(argv: list[str], flag: str) -> list[str]:
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
            continue
        if a == flag:
            skip = True
            continue
        out.append(a)
    return out


def cli_object_cases() -> list[dict[str, Any]]:
    """The refused object files once more through ``psm-grasp simulate --object``."""
    return [{**c, "entry": "cli simulate --object", "argv": ["simulate", "--object", "{case}"]}
            for c in object_file_cases() + file_cases() if c["expect"] == "refused"]


# --- the API ---------------------------------------------------------------------------------


def _numeric_type(annotation: Any) -> bool:
    text = str(annotation)
    return bool(re.fullmatch(r"(float|int)( \| None)?", text))


def _tuple_type(annotation: Any) -> bool:
    return str(annotation).startswith("tuple[float")


DATACLASSES = {  # a valid instance's keyword arguments; the fields are the schema
    "SoftDisk": {"radius_m": 0.012, "distance_m": 0.0},
    "Gripper": {"finger_length_m": 0.05, "rest_angle_rad": 0.5, "joint_offset_m": 0.002,
                "finger_width_m": 0.004, "torsion_stiffness_nm_per_rad": 0.01},
    "DesignBounds": {},
    "RewardWeights": {},
    "ObjectDistribution": {},
}


def _dataclass(name: str):
    import envs
    from envs.design_env import ObjectDistribution

    return {"ObjectDistribution": ObjectDistribution}.get(name) or getattr(envs, name)


def dataclass_cases() -> list[dict[str, Any]]:
    """Every numeric field of the parameter dataclasses: no number, not finite, huge, beyond
    the plausible range; every element of a tuple field likewise; strings and booleans of the
    wrong kind."""
    from envs.model.defaults import PLAUSIBLE_RANGES

    cases = []
    for cls_name, base in DATACLASSES.items():
        cls = _dataclass(cls_name)
        instance = cls(**base)
        for f in dataclasses.fields(cls):
            current = getattr(instance, f.name)
            values: list[tuple[Any, str]] = []
            if _numeric_type(f.type):
                values = [(v, "refused") for v in [*NOT_NUMBERS, *NOT_FINITE, *HUGE]]
                if f.default is not None:
                    values.append((None, "refused"))
                plausible = PLAUSIBLE_RANGES.get(f.name)
                if plausible is not None:
                    values.append((plausible[1] * 1000.0, "refused"))
                kwargs_of = [({f.name: v}, e) for v, e in values]
            elif _tuple_type(f.type) and current is not None:
                kwargs_of = [({f.name: [v, *list(current)[1:]]}, "refused")
                             for v in [*NOT_NUMBERS, *NOT_FINITE, *HUGE]]
                kwargs_of += [({f.name: "0.1"}, "refused"), ({f.name: 0.1}, "refused")]
            elif str(f.type) == "bool":
                kwargs_of = [({f.name: v}, "refused") for v in ("yes", 1, None)]
            elif str(f.type) == "str":
                kwargs_of = [({f.name: v}, "refused") for v in ("round", 1, None)]
            else:
                continue
            for kwargs, expect in kwargs_of:
                cases.append({"entry": "api dataclass", "target": cls_name, "name": f.name,
                              "label": f"{cls_name}({f.name}={next(iter(kwargs.values()))!r})",
                              "expect": expect, "kwargs": {**base, **kwargs}})
        cases.append({"entry": "api dataclass", "target": cls_name, "name": "",
                      "label": f"{cls_name}() (valid)", "expect": "valid", "kwargs": base})
    cases += [{"entry": "api dataclass", "target": "DesignBounds", "name": "rest_angle_rad",
               "label": "DesignBounds(high=...60 deg typed for radians)", "expect": "refused",
               "kwargs": {"high": [8.0, 60.0, 0.6, 0.4, 0.3, 1.2]}},
              {"entry": "api dataclass", "target": "DesignBounds", "name": "finger_width_r",
               "label": "DesignBounds(low=... negative width)", "expect": "refused",
               "kwargs": {"low": [1.5, 0.17, 0.0, -0.05, 0.0, 0.005]}}]
    return cases


FUNCTIONS = {  # entry -> the valid call's keyword arguments (the signature is the schema)
    "simulate": {"torque_nm": 0.2},
    "evaluate_designs": {},
    "DesignProblem": {},
    "run_optimize": {"method": "cmaes", "budget": 20},
    "GripperDesignEnv": {},
    "GripperDesignVectorEnv": {"num_envs": 2},
}
# keyword arguments that are not numbers (whatever their default)
NOT_NUMERIC = {"executor", "weights", "leaders", "disks", "designs", "calibrated", "element",
               "method", "stiffness_rule", "fidelity", "scene", "obj", "out", "dask", "bounds",
               "distribution", "render_mode", "prefix", "robust", "jaw", "jaw_per_finger",
               "progress", "verbose", "finish", "joints_apart", "name", "disk", "kwargs",
               "options", "autoreset_mode"}


def _function(name: str) -> Callable:
    import envs
    import optim
    from optim.run import run_optimize

    return {"run_optimize": run_optimize, "DesignProblem": optim.DesignProblem}.get(
        name) or getattr(envs, name)


def function_cases() -> list[dict[str, Any]]:
    """Every numeric keyword of the entry functions (their signatures): no number, not
    finite, huge (``None`` is a default there, not a bad value)."""
    cases = []
    for fn_name, base in FUNCTIONS.items():
        fn = _function(fn_name)
        params = inspect.signature(fn.__init__ if inspect.isclass(fn) else fn).parameters
        for p in params.values():
            if (p.name in NOT_NUMERIC or p.name == "self" or p.kind in (p.VAR_KEYWORD,
                                                                       p.VAR_POSITIONAL)):
                continue
            default_numeric = isinstance(p.default, int | float) and not isinstance(
                p.default, bool)
            if not (default_numeric or _numeric_type(p.annotation) or p.default is None
                    or p.name in base):
                continue
            for v in [*NOT_NUMBERS, *NOT_FINITE, *HUGE]:
                cases.append({"entry": "api function", "target": fn_name, "name": p.name,
                              "label": f"{fn_name}({p.name}={v!r})", "expect": "refused",
                              "kwargs": {**base, p.name: v}})
        cases.append({"entry": "api function", "target": fn_name, "name": "",
                      "label": f"{fn_name}() (valid)", "expect": "valid", "kwargs": base})
    return cases


def batch_cases() -> list[dict[str, Any]]:
    """``evaluate_designs`` on rows of the wrong kind (refused) and on rows holding NaN or inf
    (handled: the row flagged, the others answered)."""
    from envs.scene import DESIGN_FIELDS

    cases = []
    for col, field in enumerate(DESIGN_FIELDS):
        for v in (math.nan, math.inf):
            cases.append({"entry": "api evaluate_designs", "name": field, "expect": "handled",
                          "label": f"a row with {field} = {v!r}", "bad": [col, v]})
    for kind in ("str", "bool", "object-none", "complex", "ragged", "width7", "1d"):
        cases.append({"entry": "api evaluate_designs", "name": "designs", "expect": "refused",
                      "label": f"designs of {kind}", "kind": kind})
    return cases


def env_cases() -> list[dict[str, Any]]:
    """The environments: every reset option with what it cannot be, actions of the wrong
    kind, a step after the episode's end."""
    from envs.design_env import RESET_OPTIONS

    cases = []
    for env in ("single", "vector"):
        for key in RESET_OPTIONS:
            for v in [*NOT_NUMBERS, *NOT_FINITE, *HUGE, -1.0]:
                cases.append({"entry": f"api env {env}", "name": key, "expect": "refused",
                              "label": f"{env} reset({key}={v!r})", "options": {key: v}})
        for kind in ("str", "bool", "nan", "shape"):
            cases.append({"entry": f"api env {env}", "name": "action", "expect": "refused",
                          "label": f"{env} step(action of {kind})", "action": kind})
    cases.append({"entry": "api env single", "name": "reset()", "expect": "handled",
                  "label": "step after terminated=True", "action": "again"})
    return cases


# --- data read back: results and policies ----------------------------------------------------


def result_cases() -> list[dict[str, Any]]:
    """A run's result file with every field of :class:`~optim.result.OptimResult`, every
    number of its object and every field of its designs replaced by what it cannot be."""
    from envs.model.defaults import PLAUSIBLE_RANGES
    from envs.object_file import OBJECT_KEYS
    from envs.scene import DESIGN_FIELDS
    from optim.result import OptimResult

    by_type = {"str": [1, None, []], "int": ["zero", 1.5, -1, True, None, 1e30],
               "float": ["high", True, None, [], math.nan],
               "dict": ["x", [], 1, None], "tuple": ["x", 1, {}]}
    cases = []
    for f in dataclasses.fields(OptimResult):
        kind = str(f.type).split("[")[0]
        for v in by_type.get(kind, []):
            cases.append(_result_case([f.name], v, f.name))
    for key in [k for k in good_result()["object"] if k in OBJECT_KEYS]:
        # (the refused values only: a valid one changes the object under the designs, whose
        # torque may then be implausible on it)
        for v, expect in number_values(OBJECT_KEYS[key], PLAUSIBLE_RANGES.get(key)):
            if expect == "refused":
                cases.append(_result_case(["object", key], v, key))
    for where in (["best_design"], ["top_designs", 0, "design"]):
        for key in DESIGN_FIELDS:
            for v in ["x", None, math.nan, 1e30, True, -1e30]:
                cases.append(_result_case([*where, key], v, key))
            cases.append(_result_case([*where, key], "<delete>", key))
    for key, v in (("jaw", "round"), ("jaw_per_finger", "yes"), ("grasp_found", "yes")):
        cases.append(_result_case(["extra", key], v, key))
    cases.append(_result_case([], None, "", "valid"))
    return cases


def _result_case(path: list, value: Any, name: str, expect: str = "refused") -> dict[str, Any]:
    label = ".".join(map(str, path)) + f" = {value!r}" if path else "a good result"
    return {"entry": "result file", "name": name, "expect": expect, "label": label,
            "path": path, "value": value}


def policy_cases() -> list[dict[str, Any]]:
    """The shipped policy's folder with every key of ``policy.json`` and every array of
    ``policy.npz`` replaced by what it cannot be."""
    from optim.rl import SHIPPED_POLICY

    meta = json.loads((Path(SHIPPED_POLICY) / "policy.json").read_text())
    cases = []
    for key, current in meta.items():
        bad = [v for v in ("x", 12345, None, [], {}) if type(v) is not type(current)]
        for v in bad:
            cases.append({"entry": "policy folder", "name": key, "expect": "refused",
                          "label": f"policy.json {key} = {v!r}", "meta": {key: v}})
    for key, v in (("activation", "sigmoidish"), ("squash", "x"), ("n_layers", 0),
                   ("n_layers", 10**9), ("format", 99)):
        cases.append({"entry": "policy folder", "name": key, "expect": "refused",
                      "label": f"policy.json {key} = {v!r}", "meta": {key: v}})
    with np.load(Path(SHIPPED_POLICY) / "policy.npz") as data:
        names = list(data.files)
    for array in names:
        for damage in ("widen", "nan", "inf", "row", "delete"):
            cases.append({"entry": "policy folder", "name": array, "expect": "refused",
                          "label": f"policy.npz {array}: {damage}", "array": [array, damage]})
    cases.append({"entry": "policy folder", "name": "", "expect": "valid",
                  "label": "the shipped policy"})
    return cases


def all_cases() -> list[dict[str, Any]]:
    """Every generated case."""
    return (object_file_cases() + file_cases() + cli_cases() + cli_object_cases()
            + dataclass_cases() + function_cases() + batch_cases() + env_cases()
            + result_cases() + policy_cases())


# --- running a case --------------------------------------------------------------------------


@contextlib.contextmanager
def deadline(seconds: float = TIMEOUT_S) -> Iterator[None]:
    """Raise :class:`_Timeout` in the main thread after ``seconds`` (a blocked ``open`` of a
    FIFO is interrupted too)."""
    def fire(signum, frame):
        raise _Timeout

    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def stand_ins() -> Iterator[None]:
    """The work of every command and driver replaced by :class:`Accepted` (raised where the
    checks are over): a grasp's solve, a run's executor, the FEM verification, the training,
    the demo; and no compile notice."""
    import envs.solver.warmup
    import optim.executors
    import optim.rl
    import optim.run
    import optim.verify

    def accept(*args, **kwargs):
        raise Accepted

    simulate_module = sys.modules["envs.solver.simulate"]
    targets = [(simulate_module, "_solve_newton"), (optim.executors, "make_executor"),
               (optim.run, "run_demo"), (optim.verify, "verify_result"),
               (optim.rl, "train_policy")]
    saved = [(obj, name, getattr(obj, name)) for obj, name in targets]
    warm = envs.solver.warmup.announce_compile
    try:
        for obj, name in targets:
            setattr(obj, name, accept)
        envs.solver.warmup.announce_compile = lambda *a, **k: False
        yield
    finally:
        for obj, name, value in saved:
            setattr(obj, name, value)
        envs.solver.warmup.announce_compile = warm


def _message_outcome(text: str, name: str) -> str:
    lines = [line for line in text.strip().splitlines() if line.strip()]
    named = not name or name in text
    return "refused" if len(lines) == 1 and named and "Traceback" not in text else "unnamed"


def _warned(caught: list, name: str) -> bool:
    return any(issubclass(w.category, UserWarning) and name in str(w.message) for w in caught)


def call(fn: Callable[[], Any], name: str) -> tuple[str, str]:
    """Run ``fn`` and classify what happened (see the module's docstring)."""
    from gymnasium.error import ResetNeeded

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with deadline():
                fn()
        except Accepted:
            return "valid", "accepted"
        except (ValueError, ResetNeeded) as exc:
            return _message_outcome(str(exc), name), str(exc)
        except _Timeout:
            return "hang", f"no answer within {TIMEOUT_S:g} s"
        except Exception as exc:  # noqa: BLE001 - that is the finding
            return "crash", f"{type(exc).__name__}: {exc}"
    if _warned(caught, name) and name:
        return "handled", str(next(w.message for w in caught if name in str(w.message)))
    return "valid", "accepted"


def run_cli(argv: list[str], name: str) -> tuple[str, str]:
    """``psm-grasp ARGV`` in this process (stand-ins for the work), classified."""
    from cli.main import main

    out, err = io.StringIO(), io.StringIO()
    code: Any = None
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), deadline():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                code = main(argv)
    except SystemExit as exc:
        code = exc.code
    except Accepted:
        code = "accepted"
    except _Timeout:
        return "hang", f"no answer within {TIMEOUT_S:g} s"
    except Exception as exc:  # noqa: BLE001 - an escaped exception is a traceback
        return "crash", f"{type(exc).__name__}: {exc}"
    text = err.getvalue()
    if "Traceback" in text:
        return "crash", text
    if code == "accepted" or code == 0:
        warned = [line for line in text.splitlines() if "warning" in line and name
                  and name in line]
        return ("handled" if warned else "valid"), text.strip() or "accepted"
    if code == 2:
        errors = [line for line in text.splitlines() if "error" in line or "usage" in line]
        return _message_outcome("\n".join(errors) or text, name), text.strip()
    return "crash", f"exit code {code!r}: {text.strip()}"


class Fixtures:
    """The files the cases need, in one folder: a good object file, a run folder with a good
    result, a copy of the shipped policy, a FIFO, a regular file."""

    def __init__(self, folder: Path) -> None:
        self.tmp = Path(folder)
        self.tmp.mkdir(parents=True, exist_ok=True)
        self.object = self.tmp / "good.toml"
        self.object.write_text(toml_text({"object": GOOD_OBJECT, "gripper": GOOD_GRIPPER}))
        self.fifo = self.tmp / "fifo"
        if not self.fifo.exists():
            os.mkfifo(self.fifo)
        self.file = self.tmp / "a_file.txt"
        self.file.write_text("x\n")
        self.run = self.tmp / "run"
        self.run.mkdir(exist_ok=True)
        self.result = good_result()
        (self.run / "portfolio_seed0_result.json").write_text(json.dumps(self.result))
        self.n = 0
        import envs

        # the kernels loaded (or compiled) now, not inside a case's deadline
        envs.evaluate_designs(np.array([[0.2, 0.785, 0.025, 0.01, 0.2, 0.013]]),
                              envs.Scene.preset("paper-r070").disk)

    def fresh(self) -> Path:
        self.n += 1
        folder = self.tmp / f"case{self.n}"
        folder.mkdir()
        return folder

    def fill(self, argv: list[str], case_path: str | None = None) -> list[str]:
        return [a.replace("{tmp}", str(self.tmp)).replace("{run}", str(self.run))
                .replace("{object}", str(self.object)).replace("{fifo}", str(self.fifo))
                .replace("{file}", str(self.file)).replace("{case}", case_path or "")
                for a in argv]


def good_result() -> dict[str, Any]:
    """A result as ``psm-grasp optimize`` writes it (the paper's gripper on a foam disk)."""
    design = {"finger_length_m": 0.2, "rest_angle_rad": math.radians(45.0),
              "joint_offset_m": 0.025, "finger_width_m": 0.01, "torque_nm": 0.2,
              "distance_m": 0.013}
    obj = {"name": "puck", "radius_m": 0.07, "youngs_modulus_pa": 100e3, "poisson_ratio": 0.45,
           "thickness_m": 0.01, "stiffness_scale": 1.0, "strain_limit": 0.1,
           "friction_coefficient": 0.5, "density_kg_m3": 50.0, "payload_factor": 2.0,
           "torsion_stiffness_nm_per_rad": 0.073}
    return {"method": "cmaes", "seed": 0, "budget": 10, "best_design": design,
            "best_reward": 0.0466, "best_metrics": {}, "history_evaluations": [10],
            "history_best_reward": [0.0466], "history_wall_time_s": [1.0], "n_evaluations": 10,
            "wall_time_s": 1.0, "object": obj, "pareto_front": [],
            "options": {}, "top_designs": [{"design": dict(design), "reward": 0.0466}],
            "executor": "in-process", "extra": {"grasp_found": True}, "version": 1}


def _write_special(kind: str, folder: Path, fx: Fixtures) -> str:
    path = folder / "obj.toml"
    if kind == "fifo":
        return str(fx.fifo)
    if kind == "folder":
        return str(folder)
    if kind == "missing":
        return str(folder / "missing.toml")
    if kind == "device":
        return "/dev/zero"
    if kind == "empty":
        path.write_text("")
    elif kind == "binary":
        path.write_bytes(b"\xff\xfe\x00\x01" * 10)
    elif kind == "huge":
        with open(path, "wb") as f:
            f.truncate(65 * 2**20)  # sparse: 65 MiB that cost nothing
    elif kind == "bom":
        path.write_bytes(b"\xef\xbb\xbf" + toml_text({"object": GOOD_OBJECT}).encode())
    return str(path)


def _set_path(data: Any, path: list, value: Any) -> None:
    for key in path[:-1]:
        data = data[key]
    if value == "<delete>":
        del data[path[-1]]
    else:
        data[path[-1]] = value


def _damage_array(folder: Path, array: str, damage: str) -> None:
    path = folder / "policy.npz"
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    a = arrays[array]
    if damage == "widen":  # one input more (a matrix) or one output more (a bias)
        arrays[array] = (np.concatenate([a, a[:, :1]], axis=1) if a.ndim == 2
                         else np.concatenate([a, a[:1]]))
    elif damage == "nan":
        arrays[array] = np.full_like(a, np.nan)
    elif damage == "inf":
        arrays[array] = np.where(np.arange(a.size).reshape(a.shape) == 0, np.inf, a)
    elif damage == "row":
        arrays[array] = a[:-1]
    elif damage == "delete":
        del arrays[array]
    np.savez(path, **arrays)


def _api_call(case: dict[str, Any], fx: Fixtures) -> Callable[[], Any]:
    import envs

    kwargs = dict(case.get("kwargs", {}))
    target = case.get("target")
    disk = envs.Scene.preset("paper-r070").disk
    if case["entry"] == "api dataclass":
        return lambda: _dataclass(target)(**kwargs)
    if target == "simulate":
        return lambda: envs.simulate(envs.Scene.preset("paper-r070"), **kwargs)
    if target == "evaluate_designs":  # (two rows: a list of one value is the wrong shape)
        rows = np.array([[0.2, 0.785, 0.025, 0.01, 0.2, 0.013]] * 2)
        return lambda: envs.evaluate_designs(rows, disk, **kwargs)
    if target == "DesignProblem":
        return lambda: _function(target)(disk, **kwargs)
    if target == "run_optimize":
        return lambda: _function(target)(out=str(fx.fresh()), progress=False, verbose=False,
                                         **kwargs)
    if target == "GripperDesignEnv":
        return lambda: envs.GripperDesignEnv(**kwargs)
    if target == "GripperDesignVectorEnv":
        return lambda: envs.GripperDesignVectorEnv(**kwargs)
    raise KeyError(target)


def _batch_call(case: dict[str, Any]) -> Callable[[], Any]:
    import envs

    disk = envs.Scene.preset("paper-r070").disk
    good = [0.2, 0.785, 0.025, 0.01, 0.2, 0.013]
    if "bad" in case:
        col, v = case["bad"]
        rows = np.array([good, good])
        rows[0, col] = v

        def flagged():
            out = envs.evaluate_designs(rows, disk)
            if out["valid_at_rest"][0] or not out["converged"][1]:
                raise RuntimeError("the bad row was solved, or the good one was not")
        return flagged
    designs = {"str": [[str(v) for v in good]], "bool": [[True] * 6],
               "object-none": np.array([[*good[:5], None]], dtype=object),
               "complex": [[complex(v) for v in good]], "ragged": [good, good[:3]],
               "width7": [good + [0.0]], "1d": good}[case["kind"]]
    return lambda: envs.evaluate_designs(designs, disk)


def _env_call(case: dict[str, Any]) -> Callable[[], Any]:
    import envs

    vector = case["entry"].endswith("vector")
    env = envs.GripperDesignVectorEnv(2) if vector else envs.GripperDesignEnv()
    shape = (2, 6) if vector else (6,)
    if "options" in case:
        return lambda: env.reset(seed=0, options=case["options"])
    action = {"str": np.full(shape, "0.1"), "bool": np.ones(shape, dtype=bool),
              "nan": np.full(shape, np.nan), "shape": np.zeros(7),
              "again": np.zeros(shape)}[case["action"]]

    def step():
        env.reset(seed=0)
        if case["action"] == "again":
            env.step(action)
        env.step(action)
    return step


def run_case(case: dict[str, Any], fx: Fixtures) -> tuple[str, str]:
    """Feed one case to its entry; its outcome class and the message or what happened."""
    entry = case["entry"]
    if entry.startswith("cli"):
        path = None
        if entry == "cli simulate --object":
            path = (_write_special(case["file"], fx.fresh(), fx) if "file" in case
                    else _write_case_file(case, fx))
        name = case["name"].replace("{path}", path or "")
        return run_cli(fx.fill(case["argv"], path), name)
    if entry == "object file":
        from envs.object_file import load_object

        path = (_write_special(case["file"], fx.fresh(), fx) if "file" in case
                else _write_case_file(case, fx))
        return call(lambda: load_object(path), case["name"].replace("{path}", path))
    if entry in ("api dataclass", "api function"):
        return call(_api_call(case, fx), case["name"])
    if entry == "api evaluate_designs":
        return call(_batch_call(case), case["name"])
    if entry.startswith("api env"):
        return call(_env_call(case), case["name"])
    if entry == "result file":
        folder = fx.fresh()
        data = json.loads(json.dumps(fx.result))
        if case["path"]:
            _set_path(data, case["path"], case["value"])
        (folder / "portfolio_seed0_result.json").write_text(json.dumps(data))
        return run_cli(["verify", str(folder)], case["name"])
    if entry == "policy folder":
        from optim.rl import SHIPPED_POLICY, load_policy

        folder = fx.fresh() / "policy"
        shutil.copytree(SHIPPED_POLICY, folder)
        if "meta" in case:
            meta = json.loads((folder / "policy.json").read_text())
            meta.update(case["meta"])
            (folder / "policy.json").write_text(json.dumps(meta))
        if "array" in case:
            _damage_array(folder, *case["array"])
        return call(lambda: load_policy(folder), case["name"])
    raise KeyError(entry)


def _write_case_file(case: dict[str, Any], fx: Fixtures) -> str:
    path = fx.fresh() / "obj.toml"
    path.write_text(case["text"])
    return str(path)


def run_all(cases: list[dict[str, Any]], folder: Path,
            progress: Callable[[int], None] | None = None) -> list[tuple[str, str]]:
    """The outcome of every case (stand-ins for the work)."""
    fx = Fixtures(folder)
    out = []
    with stand_ins():
        for i, case in enumerate(cases):
            out.append(run_case(case, fx))
            if progress is not None:
                progress(i)
    return out
