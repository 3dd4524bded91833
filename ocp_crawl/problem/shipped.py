"""The example problem files and scripts shipped inside the package, and writing them out
(``ocp-crawl init``).

The package data folders ``ocp_crawl/data/problems/`` (``paper_gait.toml``, ``ocp_max_speed.toml``,
...) and ``ocp_crawl/data/examples/`` (the examples gallery) are the one source of these files.
:func:`write_problems` copies them into ``DIR/problems/`` and ``DIR/examples/``, so that the
documentation's commands (``ocp-crawl simulate problems/paper_gait.toml``,
``python examples/01_simulate_one_gait.py``) work from any install; the repository's top-level
``problems/`` and ``examples/`` folders are exactly what ``ocp-crawl init`` writes at the repository
root (a test checks that they never differ).
"""
from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path

from ocp_crawl.io.files import atomic_write, write_set

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
#: the folders written by ``ocp-crawl init``: name in DIR -> the package data folder it copies
SHIPPED_FOLDERS = {"problems": DATA_DIR / "problems", "examples": DATA_DIR / "examples"}
#: the shipped example problems (package data)
SHIPPED_DIR = SHIPPED_FOLDERS["problems"]


def shipped_files(folder: str = "problems") -> dict[str, Path]:
    """The files of one shipped folder.

    Parameters
    ----------
    folder : {"problems", "examples"}
        The example problem files, or the examples gallery (Python scripts).

    Returns
    -------
    dict of str to Path
        File name (``"paper_gait.toml"``, ...) to its path inside the installed package, sorted by
        name (hidden files and folders such as ``__pycache__`` left out).
    """
    if folder not in SHIPPED_FOLDERS:
        raise KeyError(f"no shipped folder {folder!r}; shipped: {', '.join(SHIPPED_FOLDERS)}")
    return {p.name: p for p in sorted(SHIPPED_FOLDERS[folder].iterdir())
            if p.is_file() and not p.name.startswith(".") and not p.name.endswith(".pyc")}


def shipped_problems() -> dict[str, Path]:
    """The shipped example problem files: file name -> path inside the installed package (see
    :func:`shipped_files`)."""
    return shipped_files("problems")


def shipped_problem(name: str) -> Path:
    """Path of one shipped example problem, e.g. ``shipped_problem("paper_gait")``.

    Parameters
    ----------
    name : str
        The file name, with or without ``.toml``.

    Returns
    -------
    Path
        The file inside the installed package (read it with
        :func:`~ocp_crawl.problem.load_problem`).

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


def init_plan(directory: str | os.PathLike = ".", *,
              force: bool = False) -> list[tuple[Path, Path]]:
    """Check that the shipped files can be written into ``directory/problems/`` and
    ``directory/examples/``.

    Parameters
    ----------
    directory : str or path-like
        Where to create (or fill) the ``problems/`` and ``examples/`` folders; default the current
        directory.
    force : bool
        Allow overwriting files that already exist there.

    Returns
    -------
    list of (Path, Path)
        (shipped file, target) pairs: the problems, then the examples, each in name order.

    Raises
    ------
    FileExistsError
        A target exists and ``force`` is false (``filename`` is the first such file).
    NotADirectoryError, IsADirectoryError, OSError
        ``directory`` or one of its two folders is not a directory, a target is a directory, or a
        folder cannot be created or written.
        The folders are created if needed; no file is written.
    """
    root = Path(directory)
    plan = [(src,
             root / folder
             / name) for folder in SHIPPED_FOLDERS for name, src in shipped_files(folder).items()]
    for path in (root, *(root / folder for folder in SHIPPED_FOLDERS)):
        if os.path.lexists(path) and not path.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(path))
    for _, target in plan:
        if target.is_dir():  # not even --force overwrites a directory with a file
            raise IsADirectoryError(errno.EISDIR, "is a directory where a shipped file goes",
                                    str(target))
        if not force and os.path.lexists(target):
            raise FileExistsError(errno.EEXIST, "exists", str(target))
    for folder in SHIPPED_FOLDERS:
        (root / folder).mkdir(parents=True, exist_ok=True)
        # writable: refused now rather than after the first file
        with tempfile.TemporaryFile(dir=root / folder):
            pass
    return plan


def write_problems(directory: str | os.PathLike = ".", *, force: bool = False) -> list[Path]:
    """Write the shipped problems and examples into ``directory`` (what ``ocp-crawl init`` does).

    Every check (:func:`init_plan`) comes before the first file is written; the files are written
    all or nothing (:func:`~ocp_crawl.io.files.write_set`: into a staging directory, then renamed
    into place), byte for byte as shipped.

    Parameters
    ----------
    directory : str or path-like
        Where to create (or fill) the ``problems/`` and ``examples/`` folders; default the current
        directory.
    force : bool
        Overwrite files that already exist (without it a FileExistsError is raised and nothing is
        written).

    Returns
    -------
    list of Path
        The files written: ``directory/problems/...`` then ``directory/examples/...``, each in name
        order.
    """
    root = Path(directory)
    plan = init_plan(directory, force=force)

    def write(staging: Path) -> list[Path]:
        written = []
        for src, target in plan:
            data = src.read_bytes()
            path = staging / target.relative_to(root)
            path.parent.mkdir(exist_ok=True)
            # atomic_write calls the writer before it returns: data is this iteration's
            written.append(atomic_write(path, lambda fh: fh.write(data)))
        return written
    return write_set(root, write, overwrite=force)
