"""Sphinx configuration of the yade-qdem documentation (``make doc``).

The pages are Markdown (MyST); the API reference and the settings table are
generated at build time from the package itself (``_ext/qdemdoc.py``), so
they cannot go stale.  ``qdem`` is imported for real: ``make doc`` puts the
built package (``build/python``) and YADE's Python modules on ``sys.path``."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "_ext"))

project = "yade-qdem"
author = "yade-qdem authors"
copyright = "2026, yade-qdem authors"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "qdemdoc"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# doc/dev/ is the developers' notebook (measurement history), kept in the
# repository but not part of the user site.
exclude_patterns = ["_build", "dev", "Thumbs.db", ".DS_Store"]

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 4

autodoc_member_order = "bysource"
autodoc_typehints = "none"
autodoc_default_options = {"members": True, "undoc-members": True}
napoleon_google_docstring = False
napoleon_numpy_docstring = True

html_theme = "furo"
html_title = "yade-qdem"
html_static_path = []
