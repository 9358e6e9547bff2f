"""MkDocs hook: show the docstrings' Sphinx roles as cross-references.

The package's numpy-style docstrings name objects with Sphinx roles (``:func:`envs.simulate```,
``:class:`~envs.evaluate.DesignBounds```). mkdocstrings renders the role's name as plain text in
front of the code span; this hook turns each role into an optional mkdocs-autorefs reference:
a link where the object has an API page, the code span alone where it has none. A leading
``~`` shows the last component only, as in Sphinx. A paragraph ending in reStructuredText's
``::`` (a literal block follows, which Markdown already shows as code) ends in one colon.
"""

from __future__ import annotations

import re

_ROLE = re.compile(
    r":(?:py:)?(?:func|class|meth|mod|data|attr|exc|obj|const):<code>(~?)([\w.]+)(\(\))?</code>"
)


def _reference(match: re.Match) -> str:
    tilde, target, call = match.group(1), match.group(2), match.group(3) or ""
    shown = target.rsplit(".", 1)[-1] if tilde else target
    identifier = target.lstrip(".")
    return f'<autoref identifier="{identifier}" optional><code>{shown}{call}</code></autoref>'


def on_page_content(html: str, **kwargs) -> str:
    return _ROLE.sub(_reference, html).replace("::</p>", ":</p>")
