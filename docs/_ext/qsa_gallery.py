"""The examples gallery's image scraper.

qsa's figures are Agg ``Figure`` objects made outside pyplot (``plotting.new_figure``),
which the gallery's matplotlib scraper cannot see. After each block of an example this
scraper saves every ``Figure`` of the example's namespace that it has not saved yet.
"""

from __future__ import annotations

import weakref

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

_saved: weakref.WeakSet = weakref.WeakSet()


def qsa_figure_scraper(block, block_vars, gallery_conf, **kwargs):
    """Save the example's new figures; return their reST."""
    images = block_vars["image_path_iterator"]
    paths = []
    for value in list(block_vars["example_globals"].values()):
        if isinstance(value, Figure) and value not in _saved:
            _saved.add(value)
            path = next(images)
            value.savefig(path, dpi=110)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
