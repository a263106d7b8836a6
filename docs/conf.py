"""Sphinx configuration of the casflutter documentation (``make docs``).

The gallery examples in ``docs/examples`` are executed during the build.  ``make docs`` sets
``CASFLUTTER_DOCS_QUICK=1`` so that the examples run at a small size (the whole build
stays within a few minutes on two cores); without it they run at full size.  The seed-wing
pipeline example always runs the default configuration (about 70 s; its text says why).

The site reads the same offline as online: MathJax is bundled (``sphinx-mathjax-offline``)
instead of loaded from a CDN, and when the build has finished ``_site_check.py`` fails it
(a warning under ``-W``) on any page that loads a file from another host, on a page with math
but no bundled MathJax, on a leaked return value in a gallery output and on raw reST markup in
a gallery card.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import sphinx_gallery.gen_rst as _sg_gen_rst
from sphinx.util import logging as sphinx_logging

import casflutter

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS))            # _gallery_order, _site_check

from _site_check import check_site  # noqa: E402

os.environ.setdefault("MPLBACKEND", "Agg")

project = "casflutter"
author = "the casflutter developers"
copyright = "2026, the casflutter developers"
version = release = casflutter.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",         # MathJax 3 copied into _static: math without a CDN
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

templates_path = ["_templates"]
exclude_patterns = ["_build", "_gallery_order.py", "_site_check.py", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.md5", "auto_examples/*.json"]
# `text` in single backticks: a link when it names a Python object, otherwise emphasis (the
# numpydoc convention for parameter names), never a code chip; literals take ``double``
# backticks and math :math:`...`
default_role = "autolink"
nitpicky = False

# -- API reference ------------------------------------------------------------------------
# autosummary's one-line summaries end at the first ". "; the docstrings cite "eq. 5",
# "Sec. III", "Fig. 9", "et al.", "e.g.": do not end a summary there.
import sphinx.ext.autosummary as _autosummary  # noqa: E402

_autosummary.periods_re = re.compile(
    r"(?<!\beq)(?<!\bEq)(?<!\bSec)(?<!\bFig)(?<!\bal)(?<!e\.g)(?<!i\.e)(?<!\bvs)\.(?:\s+)")

autosummary_generate = True
autosummary_imported_members = True
autosummary_ignore_module_all = False
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"            # numpydoc's Parameters sections carry the types
autoclass_content = "class"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True

# -- gallery ------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "within_subsection_order": "_gallery_order.PipelineOrder",
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "reset_modules": ("matplotlib",),
    "abort_on_example_error": False,
    "only_warn_on_example_error": False,
    # an example shows what it prints and its figures, never the repr of a block's last
    # expression (``Text(0.5, 0, 'V')`` after ``ax.set_xlabel(...)``)
    "capture_repr": (),
    # the computation-times page loads jQuery and DataTables from CDNs
    "write_computation_times": False,
}

# The gallery cards show an example's title and first paragraph as plain text.
# sphinx-gallery strips reST markup from them only after white space, so "(``casflutter
# run``)" kept its backticks: strip what it leaves.
_sg_sanitize_rst = _sg_gen_rst._sanitize_rst
_LEFTOVER_ROLE = re.compile(r":(?:[\w-]+:)+`~?([^`<]*?)\s*(?:<[^`>]*>)?`")


def _card_text(text: str) -> str:
    """``sphinx_gallery``'s sanitiser, then roles and backticks anywhere removed."""
    text = _LEFTOVER_ROLE.sub(r"\1", _sg_sanitize_rst(text))
    return text.replace("`", "")


_sg_gen_rst._sanitize_rst = _card_text

# -- HTML ---------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"casflutter {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path: list[str] = []


# -- checks of the built site -------------------------------------------------------------
def _check_built_site(app, exc):
    """Warn (an error under ``-W``) on every problem :func:`_site_check.check_site` finds."""
    if exc is not None or app.builder.format != "html":
        return
    log = sphinx_logging.getLogger("casflutter.docs")
    for problem in check_site(app.outdir):
        log.warning(problem)


def setup(app):
    # after sphinx-mathjax-offline has copied MathJax into _static (its handler: priority 500)
    app.connect("build-finished", _check_built_site, priority=900)
