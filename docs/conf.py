"""Sphinx configuration of the qsa documentation site.

Build: ``python -m sphinx -W --keep-going -b html docs docs/_build/html``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

# Import the qsa of this checkout, whatever is installed.
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))
# The examples of the docstrings run no BLAS threads of their own.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
# No figure window, ever.
os.environ.setdefault("MPLBACKEND", "Agg")

import qsa  # noqa: E402

project = "qsa"
author = "the qsa developers"
copyright = "2026, the qsa developers"
release = qsa.__version__
version = ".".join(release.split(".")[:2])

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_nb",
    "sphinx_copybutton",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = [
    "_build",
    "Thumbs.db",
    ".DS_Store",
    "**.ipynb_checkpoints",
    "gallery/*.ipynb",  # the gallery's downloadable notebooks are not pages
]

# -- API reference -------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc's parameter lists say the types
numpydoc_show_class_members = False  # the class template lists the members
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# -- Notebooks and MyST --------------------------------------------------------------
# notebooks/ is the single source of the notebooks (stored without outputs). The build
# copies them into docs/notebooks/ (not tracked) and executes them there, caching the
# outputs in the build directory: a notebook runs again only when its source changes
# (after a change to qsa itself, delete _build/ to rerun them), and a failing cell
# (an assert of a headline number) fails the build.
DOCS = Path(__file__).resolve().parent
BUILD = DOCS / "_build"


def _sync_notebooks(src=ROOT / "notebooks", dst=DOCS / "notebooks"):
    dst.mkdir(exist_ok=True)
    names = {p.name for p in src.glob("*.ipynb")}
    for stale in dst.glob("*.ipynb"):
        if stale.name not in names:
            stale.unlink()
    for name in sorted(names):
        data = (src / name).read_bytes()
        if not (dst / name).exists() or (dst / name).read_bytes() != data:
            (dst / name).write_bytes(data)


_sync_notebooks()
# The kernels import the qsa of this checkout, and write their files into the build.
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
(BUILD / "notebook-files").mkdir(parents=True, exist_ok=True)
os.environ["QSA_NOTEBOOK_OUT"] = str(BUILD / "notebook-files")
nb_execution_mode = "cache"
nb_execution_cache_path = str(BUILD / ".jupyter_cache")
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_timeout = 900  # seconds per cell
nb_merge_streams = True
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# No network: no intersphinx inventories.
intersphinx_mapping: dict = {}

# -- Examples gallery ----------------------------------------------------------------
# The scripts of examples/ run as ``python examples/exNN_<topic>.py`` would; their
# figures are saved by the scraper of docs/_ext/qsa_gallery.py.
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "gallery",
    "filename_pattern": r"ex\d\d_",
    "image_scrapers": ("qsa_gallery.qsa_figure_scraper",),
    "reset_modules": (),
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "min_reported_time": 1,
    "show_signature": False,
}

# -- HTML ----------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"qsa {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path: list[str] = []
