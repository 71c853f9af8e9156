"""Maths that renders without a network: MathJax 3 served from the site's own _static/mathjax/.

Sphinx loads MathJax from a CDN by default, so a site opened offline (or behind a firewall) shows
raw LaTeX. This extension takes MathJax 3 (its ``es5`` build: ``tex-chtml.js`` and the files it
loads on demand: TeX extensions, CHTML fonts, the menu and accessibility parts) from the first
local copy it finds, copies it into the built site and points ``mathjax_path`` at it:

1. the ``sphinx-mathjax-offline`` package from PyPI (in adparm's ``docs`` and ``test`` extras),
2. Debian's ``node-mathjax-full`` (``/usr/share/nodejs/mathjax-full/es5``).

Without either the build fails with a warning that says what to install (with ``-W``, an error),
rather than silently depending on the network.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path
from typing import Any

from sphinx.application import Sphinx
from sphinx.util import logging

logger = logging.getLogger(__name__)

#: Where the site's copy goes (under _static) and the script the pages load.
TARGET = "mathjax"
SCRIPT = "tex-chtml.js"
#: What tex-chtml.js loads on demand (beside itself), relative to the es5 folder.
PARTS = ("tex-chtml.js", "input", "output/chtml", "ui", "a11y", "sre")
DEBIAN = Path("/usr/share/nodejs/mathjax-full/es5")


def mathjax_source() -> Path | None:
    """The es5 folder of a local MathJax 3 (the PyPI package first, then Debian's), or None."""
    spec = importlib.util.find_spec("sphinx-mathjax-offline")
    candidates = []
    if spec is not None and spec.submodule_search_locations:
        candidates += [Path(p) / "static" / "mathjax" for p in spec.submodule_search_locations]
    candidates.append(DEBIAN)
    for folder in candidates:
        if (folder / SCRIPT).is_file():
            return folder
    return None


def _configure(app: Sphinx, config: Any) -> None:
    source = mathjax_source()
    app._adparm_mathjax = source  # type: ignore[attr-defined]
    if source is None:
        logger.warning(
            "local_mathjax: no local MathJax 3 found; maths would load from a CDN. Install "
            "sphinx-mathjax-offline (pip install sphinx-mathjax-offline, in adparm's docs "
            "and test extras) or Debian's node-mathjax-full"
        )
        return
    config.mathjax_path = f"{TARGET}/{SCRIPT}"


def _copy(app: Sphinx, exception: Exception | None) -> None:
    source = getattr(app, "_adparm_mathjax", None)
    if exception is not None or source is None or app.builder.format != "html":
        return
    target = Path(app.outdir) / "_static" / TARGET
    for part in PARTS:
        origin = source / part
        if origin.is_dir():
            shutil.copytree(origin, target / part, dirs_exist_ok=True)
        elif origin.is_file():
            (target / part).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(origin, target / part)


def setup(app: Sphinx) -> dict[str, Any]:
    app.setup_extension("sphinx.ext.mathjax")
    app.connect("config-inited", _configure)
    app.connect("build-finished", _copy)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
