"""The example problem files shipped inside the package, and writing them out (``ocp-crawl init``).

The package data folder ``ocp_crawl/data/problems/`` is the one source of the example problems
(``paper_gait.toml``, ``ocp_max_speed.toml``, ...).  :func:`write_problems` copies them into
``DIR/problems/``, so that the README's commands (``ocp-crawl simulate problems/paper_gait.toml``)
work from any install; the repository's top-level ``problems/`` folder is exactly what
``ocp-crawl init`` writes at the repository root (a test checks that the two never differ).
"""
from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from ocp_crawl.io.files import atomic_write

#: the shipped example problems (package data)
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "data" / "problems"
#: the folder of DIR into which :func:`write_problems` writes them
INIT_SUBDIR = "problems"


def shipped_problems() -> dict[str, Path]:
    """The shipped example problem files.

    Returns
    -------
    dict of str to Path
        File name (``"paper_gait.toml"``, ...) to its path inside the installed package, sorted by
        name.  Every file of the folder is listed (problem files and any data files they name).
    """
    return {p.name: p for p in sorted(SHIPPED_DIR.iterdir()) if p.is_file() and not p.name.startswith(".")}


def shipped_problem(name: str) -> Path:
    """Path of one shipped example problem, e.g. ``shipped_problem("paper_gait")``.

    Parameters
    ----------
    name : str
        The file name, with or without ``.toml``.

    Returns
    -------
    Path
        The file inside the installed package (read it with :func:`~ocp_crawl.problem.load_problem`).

    Raises
    ------
    KeyError
        If no shipped problem has that name (the message lists the names).
    """
    files = shipped_problems()
    key = name if name in files else f"{name}.toml"
    if key not in files:
        raise KeyError(f"no shipped problem {name!r}; shipped: {', '.join(sorted(files))}")
    return files[key]


def init_plan(directory: str | os.PathLike = ".", *, force: bool = False) -> list[tuple[Path, Path]]:
    """Check that the shipped problems can be written into ``directory/problems/``, writing nothing.

    Parameters
    ----------
    directory : str or path-like
        Where to create (or fill) the ``problems/`` folder; default the current directory.
    force : bool
        Allow overwriting files that already exist there.

    Returns
    -------
    list of (Path, Path)
        (shipped file, target) pairs, in name order.

    Raises
    ------
    FileExistsError
        A target exists and ``force`` is false (``filename`` is the first such file).
    OSError
        ``directory/problems`` cannot be created or written (not a directory, no permission, ...).
        The folder is created if needed; no file is written.
    """
    out = Path(directory) / INIT_SUBDIR
    for folder in (Path(directory), out):
        if os.path.lexists(folder) and not folder.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(folder))
    plan = [(src, out / name) for name, src in shipped_problems().items()]
    if not force:
        for _, target in plan:
            if os.path.lexists(target):
                raise FileExistsError(errno.EEXIST, "exists", str(target))
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryFile(dir=out):  # writable: refused now rather than after the first file
        pass
    return plan


def write_problems(directory: str | os.PathLike = ".", *, force: bool = False) -> list[Path]:
    """Write the shipped example problems into ``directory/problems/`` (what ``ocp-crawl init`` does).

    Every check (:func:`init_plan`) comes before the first file is written; each file is written
    atomically (:func:`~ocp_crawl.io.files.atomic_write`), byte for byte as shipped.

    Parameters
    ----------
    directory : str or path-like
        Where to create (or fill) the ``problems/`` folder; default the current directory.
    force : bool
        Overwrite files that already exist (without it a FileExistsError is raised and nothing is written).

    Returns
    -------
    list of Path
        The files written, in name order.
    """
    written = []
    for src, target in init_plan(directory, force=force):
        data = src.read_bytes()
        written.append(atomic_write(target, lambda fh, data=data: fh.write(data)))
    return written
