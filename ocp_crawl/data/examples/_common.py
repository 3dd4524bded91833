"""What the example scripts share: where they write, and saving a figure.

Each example takes one optional argument, the output directory (created if needed); without it the
example writes into a fresh temporary directory and prints its path.  Figures are drawn on
``matplotlib.figure.Figure`` objects (no pyplot), so the examples run headless.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from ocp_crawl.viz.gait import save_figure


#: set (to anything) by the examples' test (tests/test_examples.py) and the documentation's build
#: (docs/_ext/ocp_gallery.py, which gives each example its output directory): an example whose
#: full run takes minutes runs the same steps with a smaller iteration budget, so that the gallery
#: is checked in seconds; unset, they run in full
QUICK_ENV = "OCP_CRAWL_EXAMPLES_QUICK"


def quick() -> bool:
    """Whether the examples run with the small budget of their test (:data:`QUICK_ENV` set)."""
    return bool(os.environ.get(QUICK_ENV))


def output_dir(argv: list[str] | None = None) -> Path:
    """The directory given as the first argument, or a fresh temporary one."""
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else Path(tempfile.mkdtemp(prefix="ocp_crawl_example_"))
    out.mkdir(parents=True, exist_ok=True)
    return out


def save(fig, path: Path) -> Path:
    """Write ``fig`` to ``path`` (atomically) and say so."""
    save_figure(fig, path)
    print(f"wrote {path}")
    return path
