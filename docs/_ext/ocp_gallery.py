"""The examples gallery: sphinx-gallery runs the scripts of ``ocp_crawl/data/examples/``.

Each ``NN_*.py`` script runs in the build's process as ``__main__`` (with ``__file__`` set, as in
``python examples/NN_x.py``), with ``OCP_CRAWL_EXAMPLES_QUICK=1`` (the examples' quick budget; set
the variable empty beforehand for the full runs) and one argument, its output directory
``$OCP_CRAWL_EXAMPLES_OUT/<script stem>`` (default: ``_outputs/<script stem>`` in the generated
gallery), emptied first.  The figures an example writes there (PNG) are shown on its page.

The scripts stay where the package ships them: the build reads them through a directory of links,
``docs/_gallery_src/`` (git-ignored), which also holds the gallery's header, since sphinx-gallery
wants one beside the scripts.  An example's page gets its docstring's first line as its title, and
the docstring reads as text (``|S|`` is no reST substitution).
"""
from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

from ocp_docstrings import plain_text

#: the directory under which the examples write their outputs, one sub-directory per example
OUT_ENV = "OCP_CRAWL_EXAMPLES_OUT"
#: the examples' quick budget (``examples/_common.py``)
QUICK_ENV = "OCP_CRAWL_EXAMPLES_QUICK"
#: the generated gallery, relative to the documentation's source directory
GALLERY_DIR = "gallery"
#: the directory of links to the scripts, relative to the documentation's source directory
SOURCE_DIR = "_gallery_src"

HEADER = """\
Examples
========

The scripts shipped in ``ocp_crawl/data/examples/`` (in a checkout also under ``examples/``;
``ocp-crawl init`` writes them into ``./examples/``).  Each runs as
``python examples/NN_name.py [OUT_DIR]`` and writes its figures and tables into ``OUT_DIR``.
The pages below were made by running every script while the documentation was built, with the
quick budget of the examples' test (``OCP_CRAWL_EXAMPLES_QUICK=1``): the calibration stops after a
few evaluations there, and says so.
"""

_reported: dict[str, set[Path]] = {}


def examples_dir() -> Path:
    """Where the package ships the example scripts."""
    import ocp_crawl
    return Path(ocp_crawl.__file__).resolve().parent / "data" / "examples"


def stage(docs: Path) -> Path:
    """Fill ``docs/_gallery_src/`` with links to the example scripts and data, and the header."""
    src = docs / SOURCE_DIR
    src.mkdir(exist_ok=True)
    wanted = {p.name: p for p in sorted(examples_dir().iterdir())
              if p.suffix in (".py", ".csv") and p.is_file()}
    for p in src.iterdir():
        if p.name not in wanted and p.name != "GALLERY_HEADER.rst":
            p.unlink()
    for name, target in wanted.items():
        link = src / name
        if link.is_symlink() and link.resolve() == target:
            continue
        if link.exists() or link.is_symlink():
            link.unlink()
        link.symlink_to(target)
    header = src / "GALLERY_HEADER.rst"
    if not header.is_file() or header.read_text(encoding="utf-8") != HEADER:
        header.write_text(HEADER, encoding="utf-8")
    return src


def output_root(docs: Path) -> Path:
    return Path(os.environ.get(OUT_ENV) or docs / GALLERY_DIR / "_outputs").resolve()


def example_output_dir(src_file: str | Path) -> Path:
    """The output directory of the example ``src_file`` (a link in ``docs/_gallery_src/``)."""
    docs = Path(src_file).absolute().parent.parent
    return output_root(docs) / Path(src_file).stem


def example_argv(gallery_conf, script_vars) -> list[str]:
    """sphinx-gallery's ``reset_argv``: the example's arguments, its emptied output directory.

    Also gives the example its ``__file__`` (sphinx-gallery leaves it unset), the link's path: its
    target, as resolved by the script, is the shipped file beside its data.
    """
    src_file = script_vars["src_file"]
    example_globals = script_vars.get("example_globals")
    if example_globals is not None:
        example_globals["__file__"] = str(src_file)
    out = example_output_dir(src_file)
    if out.exists():
        shutil.rmtree(out)
    _reported[str(src_file)] = set()
    return [str(out)]


def scrape_outputs(block, block_vars, gallery_conf) -> str:
    """sphinx-gallery image scraper: the PNG files the example wrote into its output directory
    (since the last block), copied into the gallery's images."""
    from sphinx_gallery.scrapers import figure_rst
    src_file = str(block_vars["src_file"])
    out = example_output_dir(src_file)
    reported = _reported.setdefault(src_file, set())
    new = sorted(p for p in out.rglob("*.png") if p not in reported) if out.is_dir() else []
    images = []
    for png, image in zip(new, block_vars["image_path_iterator"]):
        shutil.copyfile(png, image)
        reported.add(png)
        images.append(image)
    return figure_rst(images, gallery_conf["src_dir"]) if images else ""


def gallery_conf(docs: Path) -> dict:
    """The ``sphinx_gallery_conf`` of the documentation in ``docs``."""
    os.environ.setdefault(QUICK_ENV, "1")
    return {
        "examples_dirs": str(stage(docs)),
        "gallery_dirs": GALLERY_DIR,
        "filename_pattern": r"/\d\d_[^/]*\.py$",       # run every numbered script
        "ignore_pattern": r"^_",                        # _common.py is a module, not an example
        "within_subsection_order": "FileNameSortKey",
        "reset_argv": "ocp_gallery.example_argv",
        "image_scrapers": ("matplotlib", "ocp_gallery.scrape_outputs"),
        "download_all_examples": False,
        "remove_config_comments": True,
        "plot_gallery": "True",
        "write_computation_times": False,            # its page loads scripts from the network
        # with an output directory asked for, every example runs, even if unchanged since a build
        "run_stale_examples": bool(os.environ.get(OUT_ENV)),
    }


_LABEL = re.compile(r"^\.\. _sphx_glr_[^\n]*:\n\n", re.MULTILINE)
_UNDERLINED = re.compile(r"[=\-~^\"'`#*+]{3,}")
_CODE = ".. GENERATED FROM PYTHON SOURCE LINES"


def example_page(source: str) -> str:
    """An example's page (reST from sphinx-gallery) with the docstring's first line as the page's
    title, and the docstring's text read as text (:func:`ocp_docstrings.plain_text`: ``|S|``)."""
    label = _LABEL.search(source)
    if label is None:
        return source
    end = source.find(_CODE, label.end())
    end = len(source) if end < 0 else end
    intro = [plain_text(line) for line in source[label.end():end].split("\n")]
    if intro and intro[0].strip() and not intro[0].startswith(".. ") and (
            len(intro) < 2 or not _UNDERLINED.fullmatch(intro[1].strip())):
        intro[1:1] = ["=" * len(intro[0]), ""]
    return source[:label.end()] + "\n".join(intro) + source[end:]


def _source_read(app, docname: str, source: list[str]) -> None:
    if docname.startswith(GALLERY_DIR + "/") and not docname.endswith("index"):
        source[0] = example_page(source[0])


def setup(app):
    app.connect("source-read", _source_read)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
