"""MkDocs hook: show the docstrings' Sphinx roles as cross-references.

The package's numpy-style docstrings name objects with Sphinx roles (``:func:`envs.simulate```,
``:class:`~envs.evaluate.DesignBounds```, ``:attr:`title <envs.scene.SoftDisk.radius_m>```).
mkdocstrings renders the role's name as plain text in front of the code span; this hook turns
each role into an optional mkdocs-autorefs reference: a link where the object has an API page,
the code span alone where it has none. A leading ``~`` shows the last component only, as in
Sphinx; an explicit title is shown as given. A paragraph ending in reStructuredText's ``::`` (a
literal block follows, which Markdown already shows as code) ends in one colon. A role left raw
on a page (one the patterns miss, e.g. a role whose target was broken across two lines) is a
warning, so ``mkdocs build --strict`` fails on it.
"""

from __future__ import annotations

import re

from mkdocs.plugins import get_plugin_logger

_ROLES = r":(?:py:)?(?:func|class|meth|mod|data|attr|exc|obj|const):"
_ROLE = re.compile(_ROLES + r"<code>(~?)([\w.]+)(\(\))?</code>")
# a role with an explicit title: :attr:`title <target>` (the target escaped in the HTML)
_TITLED = re.compile(_ROLES + r"<code>([^<]*?)\s*&lt;(~?)([\w.]+)&gt;</code>")
_RAW = re.compile(_ROLES)
log = get_plugin_logger(__name__)


def _reference(match: re.Match) -> str:
    tilde, target, call = match.group(1), match.group(2), match.group(3) or ""
    shown = target.rsplit(".", 1)[-1] if tilde else target
    identifier = target.lstrip(".")
    return f'<autoref identifier="{identifier}" optional><code>{shown}{call}</code></autoref>'


def _titled(match: re.Match) -> str:
    title, target = match.group(1), match.group(3)
    return f'<autoref identifier="{target.lstrip(".")}" optional><code>{title}</code></autoref>'


def on_page_content(html: str, page, **kwargs) -> str:
    html = _TITLED.sub(_titled, _ROLE.sub(_reference, html)).replace("::</p>", ":</p>")
    for raw in _RAW.finditer(html):
        context = re.sub(r"<[^>]+>", "", html[raw.start():raw.start() + 120]).split("\n")[0]
        log.warning(f"{page.file.src_uri}: a Sphinx role left raw: {context!r} (a role "
                    "broken across lines in a docstring?)")
    return html
