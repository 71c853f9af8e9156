"""Sphinx configuration of the adparm documentation.

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html`` after ``pip install
".[test]"`` (its extra has the documentation tools); the tools alone: see "Building the docs" in
docs/design.md. The site needs no network, to build or to read: MathJax is served from the site
(``_ext/local_mathjax.py``), and ``_ext/html_checks.py`` fails the build on a broken anchor or on
anything loaded from another host.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import adparm

sys.path.insert(0, str(Path(__file__).parent / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

project = "adparm"
author = "the adparm authors"
copyright = "2026, the adparm authors"
release = version = adparm.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "local_mathjax",  # sphinx.ext.mathjax with a local MathJax 3
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
    "config_reference",
    "landing_figure",  # draws _static/critic_weights.png from a run
    "html_checks",  # broken anchors and remote assets are errors
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "examples/README.rst"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

html_theme = "furo"
html_title = f"adparm {release}"
html_static_path = ["_static"]

autosummary_generate = True
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_typehints = "none"  # the numpy-style docstrings state the types
autodoc_member_order = "bysource"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# Build without network: no intersphinx.
nitpicky = False

sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "FileNameSortKey",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "show_memory": False,
    "plot_gallery": "True",
    "capture_repr": (),  # no "<Figure ...>" lines under the figures
    # its timing pages load jQuery and DataTables from CDNs: the site stays offline
    "write_computation_times": False,
}
