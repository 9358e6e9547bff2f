"""The documentation: a short README whose links resolve, no page or module citing a file
outside the repository, no diary."""

from __future__ import annotations

import re
import subprocess
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
