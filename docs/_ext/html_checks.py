"""Checks of the built site, as warnings (errors with ``-W``), and one fix for a viewcode bug.

After an HTML build, every page of the output is scanned (like ``linkcheck``, but offline and for
the site's own links only):

- every link to an anchor of the site (``href="page.html#id"`` or ``href="#id"``) must reach an
  element with that id on that page;
- every script, stylesheet and image the pages load must be a file of the site: nothing from a
  CDN or any other host, so that the site, its maths included, works without a network.

The fix: viewcode's "[docs]" links from a module's source page back to the documentation use one
module name per source module (the first one it met), so when the objects of one module are
documented under two names (``adparm.ExpressionBasis`` and ``adparm.bases.parse_term``, both
from adparm/bases.py) the links of one group pointed at ids that do not exist
(``#adparm.parse_term``). Each such object now also carries the id viewcode links to.
"""

from __future__ import annotations

from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlsplit

from docutils import nodes
from sphinx import addnodes
from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)


class _Page(HTMLParser):
    """The ids of a page, its links (href) and the assets it loads (script src, stylesheet
    href, img src)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.links: list[str] = []
        self.assets: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = {key: value or "" for key, value in attrs}
        for key in ("id", "name") if tag == "a" else ("id",):
            if values.get(key):
                self.ids.add(values[key])
        if tag == "a" and "href" in values:
            self.links.append(values["href"])
        elif tag == "link" and "stylesheet" in values.get("rel", "").split():
            self.assets.append(values.get("href", ""))
        elif tag in ("script", "img") and values.get("src"):
            self.assets.append(values["src"])


def scan(root: Path) -> list[str]:
    """The problems of the HTML site in ``root``: broken anchors, remote or missing assets."""
    root = root.resolve()
    pages: dict[Path, _Page] = {}
    for path in sorted(root.rglob("*.html")):
        page = _Page()
        page.feed(path.read_text(encoding="utf-8", errors="replace"))
        pages[path.resolve()] = page
    problems = []
    for path, page in pages.items():
        name = path.relative_to(root)
        for href in page.links:
            parts = urlsplit(href)
            if parts.scheme or parts.netloc or not parts.fragment:
                continue
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            if target.suffix != ".html":
                continue
            if target not in pages:
                problems.append(f"{name}: link to a missing page: {href}")
            elif unquote(parts.fragment) not in pages[target].ids:
                problems.append(f"{name}: link to a missing anchor: {href}")
        for src in page.assets:
            parts = urlsplit(src)
            if parts.scheme in ("data",):
                continue
            if parts.scheme or parts.netloc:
                problems.append(f"{name}: loads {src} from the network (serve it from _static)")
            elif parts.path and not (path.parent / unquote(parts.path)).resolve().exists():
                problems.append(f"{name}: loads a missing file: {src}")
    return problems


def _check(app: Sphinx, exception: Exception | None) -> None:
    if exception is not None or app.builder.format != "html":
        return
    for problem in scan(Path(app.outdir)):
        logger.warning("html_checks: %s", problem)


def _viewcode_anchors(app: Sphinx, doctree: nodes.document) -> None:
    """After viewcode's own doctree-read: an object documented under another module name than
    the one viewcode's links of its source module use also gets the id those links point at."""
    from sphinx.ext.viewcode import _get_full_modname

    modules = getattr(app.env, "_viewcode_modules", {})
    for signode in doctree.findall(addnodes.desc_signature):
        module, fullname = signode.get("module"), signode.get("fullname")
        if not module or not fullname:
            continue
        source = app.events.emit_firstresult("viewcode-follow-imported", module, fullname)
        entry = modules.get(source or _get_full_modname(module, fullname))
        if not entry:
            continue
        _, _, used, refname = entry
        current = getattr(app.env, "current_document", None)
        docname = current.docname if current is not None else app.env.docname
        if refname != module and used.get(fullname) == docname:
            anchor = f"{refname}.{fullname}"
            if anchor not in signode["ids"]:
                signode["ids"].append(anchor)


def setup(app: Sphinx) -> dict[str, Any]:
    app.connect("doctree-read", _viewcode_anchors, priority=900)
    app.connect("build-finished", _check, priority=900)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
