"""Sphinx configuration of the casflutter documentation (``make docs``).

The gallery examples in ``docs/examples`` are executed during the build.  ``make docs`` sets
``CASFLUTTER_DOCS_QUICK=1`` so that the examples run at a small size (the whole build
stays within a few minutes on two cores); without it they run at full size.  The seed-wing
pipeline example always runs the default configuration (about 70 s; its text says why).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import casflutter

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS))            # _gallery_order

os.environ.setdefault("MPLBACKEND", "Agg")

project = "casflutter"
author = "the casflutter developers"
copyright = "2026, the casflutter developers"
version = release = casflutter.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

templates_path = ["_templates"]
exclude_patterns = ["_build", "_gallery_order.py", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.md5", "auto_examples/*.json"]
default_role = "code"
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
}

# -- HTML ---------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"casflutter {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path: list[str] = []
