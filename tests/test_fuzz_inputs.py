"""Generated bad inputs at every public entry (tests/input_fuzz.py): each ends in a named
refusal (a ``ValueError``, or exit code 2 with one line naming it), a documented handling, or
is valid; none crashes, prints a traceback or hangs.

The inputs are generated from the schemas (the object file's rule tables, the command line's
options, the dataclasses' fields, the signatures, the result's fields, the policy's keys), so
a key or an option added later is fuzzed here without a change to this file. A failure lists
each input whose outcome class is not the expected one, with the message.
"""

from __future__ import annotations

import collections
import re

import pytest

from tests import input_fuzz as fuzz

CASES = fuzz.all_cases()
BY_ENTRY: dict[str, list[dict]] = collections.defaultdict(list)
for _case in CASES:
    BY_ENTRY[_case["entry"]].append(_case)


@pytest.fixture(scope="module")
def fixtures(tmp_path_factory):
    return fuzz.Fixtures(tmp_path_factory.mktemp("fuzz"))


def _mismatches(cases, fixtures) -> list[str]:
    with fuzz.stand_ins():
        outcomes = [fuzz.run_case(case, fixtures) for case in cases]
    return [f"{c['label']}: expected {c['expect']}, got {outcome} ({detail.strip()[-200:]})"
            for c, (outcome, detail) in zip(cases, outcomes, strict=True)
            if outcome != c["expect"]]


@pytest.mark.parametrize("entry", sorted(BY_ENTRY))
def test_every_generated_input_ends_in_its_outcome_class(entry, fixtures):
    bad = _mismatches(BY_ENTRY[entry], fixtures)
    assert not bad, f"{len(bad)} of {len(BY_ENTRY[entry])} inputs:\n" + "\n".join(bad[:40])


def test_the_cases_cover_every_key_and_option():
    """The generator reads the schemas: every key of both tables, every option of every
    command and every field of the result and the dataclasses has cases."""
    import argparse

    from cli.main import build_parser
    from envs.object_file import GRIPPER_KEYS, OBJECT_TABLE_KEYS
    from optim.result import OptimResult

    named = collections.defaultdict(set)
    for case in CASES:
        named[case["entry"]].add(case["name"])
    assert set(OBJECT_TABLE_KEYS) | set(GRIPPER_KEYS) <= named["object file"]
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    for command, parser in sub.choices.items():
        for action in parser._actions:
            if action.option_strings and action.nargs != 0 and action.dest != "help":
                assert action.option_strings[0] in named[f"cli {command}"], action.dest
    import dataclasses

    assert {f.name for f in dataclasses.fields(OptimResult)} <= named["result file"]


def test_the_object_table_lists_the_keys_the_parser_allows():
    """OBJECT_TABLE_KEYS (what the fuzzing reads) is what parse_object accepts: the keys its
    unknown-key message lists."""
    from envs.object_file import OBJECT_TABLE_KEYS, parse_object

    with pytest.raises(ValueError, match="unknown key") as info:
        parse_object({"object": {**fuzz.GOOD_OBJECT, "zz_unknown": 1}}, "x.toml")
    allowed = re.search(r"allowed: (.*)$", str(info.value)).group(1).split(", ")
    assert allowed == list(OBJECT_TABLE_KEYS)


def test_the_fuzzing_finds_an_input_accepted_without_a_word(monkeypatch, fixtures):
    """Not a test that cannot fail: without the plausible ranges, millimetres typed for metres
    pass, and the generated cases say so."""
    import envs.object_file

    monkeypatch.setattr(envs.object_file, "check_plausible", lambda name, value: float(value))
    cases = [c for c in BY_ENTRY["object file"] if c["name"] == "finger_length_m"]
    bad = _mismatches(cases, fixtures)
    assert any("finger_length_m = 50.0: expected refused, got valid" in b for b in bad), bad


def test_a_fifo_ends_in_a_refusal_not_a_hang(fixtures):
    case = next(c for c in BY_ENTRY["object file"] if c.get("file") == "fifo")
    assert fuzz.run_case(case, fixtures)[0] == "refused"


@pytest.mark.slow
def test_random_numbers_in_every_key_of_an_object_file(fixtures):
    """A wider sweep: 20 log-uniform numbers of either sign from 1e-12 to 1e12 per numeric key
    of both tables, each refused exactly when it lies outside the key's allowed or plausible
    range (the torque: its ceiling on the object)."""
    import numpy as np

    from envs.model.defaults import PLAUSIBLE_RANGES
    from envs.object_file import GRIPPER_KEYS, OBJECT_KEYS

    rng = np.random.default_rng(47)
    cases = []
    for table, rules in (("object", OBJECT_KEYS), ("gripper", GRIPPER_KEYS)):
        for key, rule in rules.items():
            for _ in range(20):
                v = float(rng.choice([-1, 1]) * 10.0 ** rng.uniform(-12, 12))
                expect = "valid" if fuzz._inside(v, rule, PLAUSIBLE_RANGES.get(key)) else "refused"
                tables = {"object": dict(fuzz.GOOD_OBJECT)}
                if table == "gripper":
                    tables["gripper"] = fuzz._alternatives(key, {**fuzz.GOOD_GRIPPER, key: v})
                    if key == "torque_nm" and expect == "valid":
                        expect = fuzz._torque_expect(v, tables)
                else:
                    tables["object"][key] = v
                cases.append(fuzz._file_case(f"[{table}] {key} = {v!r}", tables, key, expect))
    bad = _mismatches(cases, fixtures)
    assert not bad, "\n".join(bad[:40])
