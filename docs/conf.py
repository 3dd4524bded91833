"""Sphinx configuration of the ocp_crawl documentation.

Build (offline; warnings are errors), from the repository's root::

    pip install -e ".[docs]"
    MPLBACKEND=Agg sphinx-build -W --keep-going -b html docs docs/_build/html

The pages are MyST Markdown; the reference pages (problem-file keys, command line, statuses,
Python API) are generated from the code at each build (``_ext/ocp_reference.py``), and the examples
gallery runs the shipped example scripts (``_ext/ocp_gallery.py``).
"""
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(1, str(DOCS.parent))

import ocp_gallery  # noqa: E402

from ocp_crawl import __version__  # noqa: E402

project = "ocp_crawl"
author = "the ocp_crawl authors"
copyright = "the ocp_crawl authors, MIT licence"
version = release = __version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx_gallery.gen_gallery",
    "ocp_docstrings",
    "ocp_reference",
    "ocp_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
# the gallery's _outputs/ and any _*.rst (a module beside the examples, not one); computation
# times are not written (that page would load scripts from the network)
exclude_patterns = ["_build", "_ext", ocp_gallery.SOURCE_DIR, f"{ocp_gallery.GALLERY_DIR}/_*",
                    "**/.*", "**sg_execution_times.rst"]

# MyST: $...$ and $$...$$ math, amsmath environments, ::: fences, definition lists; headings down to
# ### get anchors, so that [text](page.md#a-heading) links work
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# the API: a page per package (_ext/ocp_reference.py) with an autosummary table (no stub pages:
# autosummary generates nothing) and the autodoc entries; members in the order of the source; the
# numpy-style docstrings are read by napoleon's parser through _ext/ocp_docstrings.py
autosummary_generate = False
# the API entries stay out of the pages' tables of contents: each package's page starts with its own
# table of its names, and the theme renders the whole toctree again for every page (furo's sidebar),
# whose cost grows with every entry in it (about 5 s of a build with the ~190 API entries)
toc_object_entries = False
autodoc_member_order = "bysource"
autodoc_typehints = "signature"
autodoc_preserve_defaults = True

sphinx_gallery_conf = ocp_gallery.gallery_conf(DOCS)

html_theme = "furo"
html_title = f"ocp_crawl {release}"
html_static_path = []
