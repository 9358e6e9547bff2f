"""MkDocs hook: the 404 page's links relative to the site's root folder.

MkDocs writes an error page's links from the root of ``site_url``, or from ``/`` without one
(https://github.com/mkdocs/mkdocs/issues/1598): such a page is broken when the site is opened
from disk or served under a sub-path (``https://host/psm-grasp/``), and the package has no fixed
address to put in ``site_url``. ``404.html`` lies in the root folder, so links relative to it
(``./assets/...``) work from disk and as the 404 page of any server folder the site is copied to.
"""

from __future__ import annotations


def on_template_context(context, template_name: str, config, **kwargs):
    if template_name == "404.html":
        context["base_url"] = "."
    return context
