"""The documentation: a short README whose links resolve, no page or module citing a file
outside the repository, no diary."""

from __future__ import annotations

import math
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
# words of a development diary: work periods, numbered issues, attempts
DIARY = re.compile(r"\b(session \d+|sessions? \d+-\d+|issue \d+|\(issue|work period)",
                   re.IGNORECASE)


def _tracked(*patterns: str) -> list[Path]:
    out = subprocess.run(["git", "ls-files", *patterns], cwd=ROOT, capture_output=True,
                         text=True, check=False)
    if out.returncode != 0:  # not a git checkout: every file below the root
        return [p for pat in patterns for p in ROOT.glob(f"**/{pat}")]
    return [ROOT / line for line in out.stdout.splitlines() if line]


def test_the_readme_is_a_short_front_door():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= 250
    assert any("make demo" in line for line in lines) and any("make test" in line
                                                              for line in lines)


@pytest.mark.parametrize("page", ["README.md", "CHANGELOG.md"])
def test_every_relative_link_of_the_front_pages_resolves(page):
    text = (ROOT / page).read_text()
    for target in LINK.findall(text):
        if "://" in target or target.startswith("mailto:"):
            continue
        assert (ROOT / target).exists(), f"{page}: {target} does not exist"


def test_nothing_cites_a_file_outside_the_repository_or_narrates_development():
    files = _tracked("*.py", "*.md", "*.toml", "*.yml", "Makefile")
    assert len(files) > 50
    for path in files:
        # the changelog says what changed between versions, on purpose; this file names what
        # it looks for
        if "CHANGELOG" in path.name or path.name == "test_docs.py" or not path.is_file():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        assert "shared/" not in text and "CONVENTIONS.md" not in text, path
        match = DIARY.search(text)
        assert match is None, f"{path}: {match.group(0)!r}"


# --- the command-line page states what the code enforces -------------------------------------

INTERVAL = re.compile(r"^([(\[])([-\d.e]+|-inf), ([-\d.e]+|inf)([)\]])")
BOUND = re.compile(r"^(>=|>) ([-\d.e]+)")


def _table_rows(page: str, heading: str, header: str = "|") -> dict[str, list[str]]:
    """The rows of the first table after the line ``heading`` of a page whose header line
    starts with ``header``, by first cell."""
    lines = (ROOT / page).read_text().splitlines()
    rows: dict[str, list[str]] = {}
    table: list[str] = []
    for line in [*lines[lines.index(heading) + 1:], ""]:
        if line.startswith("|"):
            table.append(line)
            continue
        if table and table[0].startswith(header):
            for row in table[1:]:
                cells = [c.strip() for c in row.strip("|").split("|")]
                if not set(cells[0]) <= set("-"):
                    rows[cells[0]] = cells
            return rows
        table = []
    raise AssertionError(f"{page}: no table starting {header!r} after {heading!r}")


def _stated(allowed: str) -> tuple[float, float, bool, bool]:
    """(low, high, low_open, high_open) of an 'allowed' cell: (a, b], > a, >= a, any."""
    if allowed.startswith("any"):
        return -math.inf, math.inf, False, False
    if m := INTERVAL.match(allowed):
        return float(m[2]), float(m[3]), m[1] == "(", m[4] == ")"
    m = BOUND.match(allowed)
    assert m, allowed
    return float(m[2]), math.inf, m[1] == ">", False


def _probes(low: float, high: float, low_open: bool, high_open: bool):
    """(value, accepted) at and just beyond each finite end of a stated range."""
    for end, is_open, outward in ((low, low_open, -1.0), (high, high_open, 1.0)):
        if math.isfinite(end):
            step = 1e-9 * max(1.0, abs(end))
            yield end, not is_open
            yield end + outward * step, False
            yield end - outward * step, True


@pytest.mark.parametrize("table, heading", [("object", "`[object]`:"),
                                            ("gripper", "`[gripper]` (one gripper and the "
                                             "object's placement, for `simulate`; `optimize` "
                                             "designs its own):")])
def test_the_object_file_ranges_of_cli_md_are_the_loader_s(table, heading):
    from envs.object_file import GRIPPER_KEYS, OBJECT_KEYS, parse_object

    keys = OBJECT_KEYS if table == "object" else GRIPPER_KEYS
    rows = _table_rows("docs/cli.md", heading)
    stated = {}
    for first, cells in rows.items():
        for key in re.findall(r"`(\w+)`", first):
            stated[key] = cells[3].split(" deg")[0] if key.endswith("_deg") else cells[3]
    stated.pop("rest_angle_rad", None)  # its row states degrees (radians: the same range)
    assert set(stated) - {"name"} == set(keys) - {"rest_angle_rad"}
    base = {"object": {"radius_m": 0.01, "youngs_modulus_pa": 1e5, "poisson_ratio": 0.4,
                       "thickness_m": 0.01},
            "gripper": {"finger_length_m": 0.05, "rest_angle_deg": 30.0, "joint_offset_m": 0.0,
                        "finger_width_m": 0.004, "distance_m": 0.001}}
    for key, allowed in stated.items():
        if key == "name":
            continue
        for value, accepted in _probes(*_stated(allowed)):
            data = {t: dict(v) for t, v in base.items()}
            data[table][key] = value
            try:
                parse_object(data, "probe")
                ok = True
            except ValueError:
                ok = False
            assert ok == accepted, (key, allowed, value)


def test_the_option_ranges_of_cli_md_are_the_checks():
    from optim.problem import check_friction, check_strain_limit

    rows = _table_rows("docs/cli.md", "## optimize", "| option | meaning |")
    for option, check in (("`--strain-limit EPS`", check_strain_limit),
                          ("`--friction MU`", check_friction)):
        allowed = re.search(r"in ([(\[][^ ]+, [^ ]+[)\]])", rows[option][1])[1]
        for value, accepted in _probes(*_stated(allowed)):
            try:
                check(value)
                ok = True
            except ValueError:
                ok = False
            assert ok == accepted, (option, allowed, value)


def test_cli_md_lists_every_exit_code_the_commands_return():
    from cli.main import BROKEN_PIPE_EXIT, ERROR_EXIT
    from optim.run import NO_GRASP_EXIT, UNDECIDED_EXIT
    from optim.verify import NO_GRASP_EXIT as DOES_NOT_HOLD
    from optim.verify import NOT_CONFIRMED_EXIT

    rows = _table_rows("docs/cli.md", "## Exit codes")
    assert DOES_NOT_HOLD == NO_GRASP_EXIT  # one code, one meaning: the design does not hold
    assert {int(code) for code in rows if code.isdigit()} == {
        0, 1, ERROR_EXIT, NO_GRASP_EXIT, NOT_CONFIRMED_EXIT, UNDECIDED_EXIT, BROKEN_PIPE_EXIT}
    assert "10 %" in rows[str(NOT_CONFIRMED_EXIT)][1] and "`1e-4`" in rows["4"][1]


# --- the API pages: docstrings in Markdown, which mkdocstrings renders ------------------------

RST_TABLE_RULE = re.compile(r"^\s*=+( +=+)+\s*$", re.MULTILINE)


def test_no_docstring_on_an_api_page_has_a_restructuredtext_table():
    import importlib
    import inspect

    targets = set()
    for page in (ROOT / "docs" / "api").glob("*.md"):
        targets |= set(re.findall(r"^::: ([\w.]+)", page.read_text(), re.MULTILINE))
    assert "envs.evaluate" in targets
    for target in sorted(targets):
        if target.split(".")[0] not in ("envs", "optim", "cli"):
            target = f"envs.{target}"  # mkdocs.yml's paths hold envs/ as well
        module_name, obj = target, None
        while True:
            try:
                module = importlib.import_module(module_name)
                break
            except ImportError:
                module_name, _, attr = module_name.rpartition(".")
                obj = attr if obj is None else f"{attr}.{obj}"
        root = module
        for part in (obj.split(".") if obj else []):
            root = getattr(root, part)
        members = [root] + [m for _, m in inspect.getmembers(root)
                            if (inspect.isclass(m) or inspect.isfunction(m))
                            and getattr(m, "__module__", "").split(".")[0] in ("envs", "optim")]
        for member in members:
            doc = inspect.getdoc(member) or ""
            assert not RST_TABLE_RULE.search(doc), (target, getattr(member, "__name__", member))


# --- how to read a reward (docs/own-object.md) --------------------------------------------------


def test_the_reading_of_a_reward_in_own_object_md_is_the_evaluator_s():
    import numpy as np

    from envs import DesignBounds, evaluate_designs
    from envs.object_file import load_object

    page = (ROOT / "docs" / "own-object.md").read_text()
    assert "reward = min(c, 0.5) - 0.25 eps / eps_max" in page
    assert "-0.25 - 0.75 x / (1 + x)" in page
    obj = load_object(ROOT / "examples" / "objects" / "cherry_tomato.toml")
    designs = DesignBounds().sample(np.random.default_rng(0), 64, obj.disk)
    out = evaluate_designs(designs, obj.disk, strain_limits=obj.strain_limit,
                           friction_coefficients=obj.friction_coefficient,
                           element="spring", n_triangles=20)
    holds = out["holds"] & out["converged"] & out["valid_at_rest"]
    assert 5 <= holds.sum() < 64  # both kinds among random designs
    c, q = out["contact_score"][holds], out["peak_compression"][holds] / obj.strain_limit
    within = q <= 1.0
    assert within.any() and (~within).any()  # both kinds of hold among random designs
    expected = np.where(within, np.minimum(c, 0.5) - 0.25 * q,
                        -0.25 - 0.75 * (q - 1.0) / q)  # x / (1 + x) with x = q - 1
    np.testing.assert_allclose(out["reward"][holds], expected, rtol=0, atol=1e-12)
    # the page's bands: a hold scores at least -1, anything else below -1
    assert np.all(out["reward"][holds] >= -1.0) and np.all(out["reward"][~holds] < -1.0)


# --- the pages run as written: README, cli.md, limitations.md, own-object.md ------------------

RUN_PAGES = ("README.md", "docs/cli.md", "docs/limitations.md", "docs/own-object.md")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.MULTILINE | re.DOTALL)
# what a page's command or snippet asks for, made small enough to run in a test
SMALL = ((re.compile(r"--budget \d+"), "--budget 12"), (re.compile(r"budget=\d+"), "budget=12"),
         (re.compile(r"--refine \d+"), "--refine 3"), (re.compile(r"--top \d+"), "--top 1"),
         (re.compile(r"--verify-top \d+"), "--verify-top 1"),
         (re.compile(r"--steps \d+"), "--steps 256"))


def _blocks(page: str, language: str) -> list[str]:
    return [body for lang, body in FENCE.findall((ROOT / page).read_text()) if lang == language]


def _commands(page: str) -> list[str]:
    """The ``psm-grasp`` command lines of a page's bash blocks (comments dropped)."""
    lines = [line.split("#")[0].strip() for block in _blocks(page, "bash")
             for line in block.splitlines()]
    return [line for line in lines if line.startswith("psm-grasp ")]


def test_every_option_of_every_command_is_in_cli_md():
    from cli.main import build_parser

    text = (ROOT / "docs" / "cli.md").read_text()
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    for name, command in sub.choices.items():
        options = [o for a in command._actions for o in a.option_strings
                   if o.startswith("--") and o != "--help"]
        missing = [o for o in options if f"`{o}" not in text]
        assert not missing, (name, missing)
    rows = _table_rows("docs/cli.md", "## optimize", "| option | meaning |")
    (optimize,) = [c for n, c in sub.choices.items() if n == "optimize"]
    for action in optimize._actions:
        for option in action.option_strings:
            if option.startswith("--") and option not in ("--help", "--object", "--scene"):
                assert any(option in first for first in rows), option


@pytest.mark.parametrize("page", RUN_PAGES)
def test_the_pages_files_and_commands_are_what_the_package_reads(page):
    """Every TOML block of a page loads, and every command line of it parses (a typo in an
    option fails here, in the fast suite; the slow test below runs them)."""
    import shlex

    from cli.main import build_parser
    from envs.object_file import parse_object

    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    for body in _blocks(page, "toml"):
        data = tomllib.loads(body)
        if "object" in data:
            parse_object(data, page)
    for line in _commands(page):
        build_parser().parse_args(shlex.split(line)[1:])


@pytest.mark.slow
@pytest.mark.parametrize("page", RUN_PAGES)
def test_the_pages_run_as_written(page, tmp_path, monkeypatch, capsys):
    """Every command of a page (budgets made small) and every Python snippet run, in order, in a
    folder of their own; placeholders (``my_object.toml``) are an example object."""
    import shlex
    import shutil

    from cli.main import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    shutil.copy(ROOT / "examples" / "objects" / "cherry_tomato.toml", "my_object.toml")
    for line in _commands(page):
        for pattern, small in SMALL:
            line = pattern.sub(small, line)
        args = shlex.split(line)[1:]
        if args[0] == "train-policy":
            pytest.importorskip("stable_baselines3")
            if "--steps" not in args:  # (the default trains for 200,000 designs)
                args += ["--steps", "256"]
        if "--policy" in args and not Path(args[args.index("--policy") + 1]).exists():
            continue  # (a policy the page trained with more steps than a test takes)
        code = main(args)
        # a short run need not find a grasp (3, 5), nor its optimum be confirmed (4)
        assert code in (0, 3, 4, 5), (page, line, code, capsys.readouterr().err[-2000:])
    for body in _blocks(page, "python"):
        if "stable_baselines3" in body:
            pytest.importorskip("stable_baselines3")
        for pattern, small in SMALL:
            body = pattern.sub(small, body)
        exec(compile(body, page, "exec"), {"__name__": "__doc_snippet__"})
