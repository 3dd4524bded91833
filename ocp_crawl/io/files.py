"""Atomic file output: a reader never sees a half-written result file.

Every file the package writes goes through :func:`atomic_write`: the bytes go to a temporary file
``.<name>.<pid>-<host>.<random>.tmp`` in the target's directory, which is flushed, fsync'd and
renamed over the target (``os.replace``, atomic on POSIX and Windows).  A process killed at any
moment (even by SIGKILL) therefore leaves either the previous file or the new one, never a mix; what
it can leave is its temporary file.  Such leftovers are recognised by the writer's process id and
host in their name and removed by the next write of the same file and by :func:`remove_stale_temps`
(which ``sweep`` and ``reproduce`` call on their directories); a temporary file of a process that is
still running is never touched.
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import select
import shutil
import socket
import stat
import tempfile
from pathlib import Path
from typing import IO, Any, Callable

import numpy as np

from ocp_crawl.checks import finite_or_none

#: tag of this host in temporary names: a leftover is only judged by its writer's pid on the same
#: host
HOST_TAG = hashlib.sha1(socket.gethostname().encode("utf-8", "replace")).hexdigest()[:8]
#: ``.<name>.<pid>-<host>.<random>.tmp``: the temporary files of :func:`atomic_write` (and of
#: temp_prefix)
TEMP_RE = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)-(?P<host>[0-9a-f]{8})\.[^./]+\.tmp$")


def temp_prefix(name: str) -> str:
    """Prefix of a temporary file or directory (the caller adds a random part and ``.tmp``) for
    ``name``."""
    return f".{name}.{os.getpid()}-{HOST_TAG}."


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    # os.kill(pid, 0) would terminate the process on Windows: assume it is alive
    if os.name == "nt":
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):  # alive, another user's; or not a pid at all: leave it
        return True
    return True


def is_stale_temp(name: str, target: str | None = None) -> bool:
    """True if ``name`` is a temporary file (or directory) of a writer on this host that no longer
    runs; with ``target``, only the temporary files of that target name."""
    m = TEMP_RE.match(name)
    if m is None or m["host"] != HOST_TAG or (target is not None and m["name"] != target):
        return False
    return not _alive(int(m["pid"]))


def _remove(path: Path) -> bool:
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    except FileNotFoundError:
        pass
    except OSError:
        return False
    return True


def remove_stale_temps(directory: str | os.PathLike, target: str | None = None) -> list[Path]:
    """Remove the temporary files left in ``directory`` by killed writers (see the module
    docstring).

    Only names of the form ``.<name>.<pid>-<host>.<random>.tmp`` whose process is gone on this host
    are removed; returns them.  A missing or unreadable directory removes nothing.
    """
    directory = Path(directory)
    try:
        names = os.listdir(directory)
    except OSError:
        return []
    removed = []
    for name in names:
        if name.endswith(".tmp") and is_stale_temp(name, target) and _remove(directory / name):
            removed.append(directory / name)
    return removed


def _fsync_dir(directory: Path) -> None:
    """Make a rename in ``directory`` durable (POSIX); a no-op where directories cannot be
    opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write(path: str | os.PathLike, write: Callable[[IO[bytes]], Any]) -> Path:
    """Call ``write(fh)`` on a temporary file in the target's directory, then rename it over
    ``path``.

    The temporary file lives in the same directory so that ``os.replace`` is a rename on one file
    system (atomic on POSIX and Windows); on any error it is removed and the target is untouched.
    Leftovers of earlier writers of ``path`` that were killed are removed first.  An OSError (a full
    disk, ...) is raised again with ``path`` as its file name, so that the message names the file.
    """
    path = Path(path)
    try:
        _write_replace(path, write)
    except OSError as exc:
        # name the target (a full disk says only "No space left on device"; mkstemp names its
        # temporary file)
        raise naming(exc, path) from exc
    _fsync_dir(path.parent)
    return path


def naming(exc: OSError, path: str | os.PathLike) -> OSError:
    """A copy of ``exc`` with ``path`` as its file name (the same errno, hence the same OSError
    subclass, and reason), so that its message names the file written."""
    return OSError(exc.errno, exc.strerror or " ".join(str(exc).split()) or type(exc).__name__,
                   str(path))


def _write_replace(path: Path, write: Callable[[IO[bytes]], Any]) -> None:
    """The temporary file of :func:`atomic_write`, written and renamed over ``path`` (removed on any
    error)."""
    remove_stale_temps(path.parent, path.name)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=temp_prefix(path.name), suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            # mkstemp makes the file private (0600); results are ordinary files, readable by others
            os.chmod(tmp, path.stat().st_mode & 0o777 if path.exists() else 0o644)
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


#: how long an input that is a named pipe may stay without data before it is refused [s] (no writer:
#: refused instead of waiting for ever)
PIPE_WAIT_S = 10.0


def read_bounded(path: str | os.PathLike, limit: int) -> bytes:
    """The bytes of the input file ``path``, at most ``limit + 1`` of them (the caller refuses
    more).

    An endless file (/dev/zero) stops at the limit.  A named pipe is opened without waiting for a
    writer and read once data (or the end) arrives, at most :data:`PIPE_WAIT_S` later (then refused:
    no writer).  Every failure is an OSError whose ``strerror`` says why (a path with a NUL
    character included, which ``open`` reports as a ValueError).
    """
    # POSIX; Windows has no named pipes in the file system
    nonblocking = getattr(os, "O_NONBLOCK", 0)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0) | nonblocking)
    except ValueError as exc:
        raise OSError(errno.EINVAL, f"invalid path ({exc})") from None
    with os.fdopen(fd, "rb") as fh:
        if nonblocking:
            if (stat.S_ISFIFO(os.fstat(fd).st_mode)
                    and not select.select([fd], [], [], PIPE_WAIT_S)[0]):
                raise OSError(errno.ETIMEDOUT,
                              f"a named pipe with nothing written to it within {PIPE_WAIT_S:g} s "
                              "(no writer?)")
            os.set_blocking(fd, True)   # opened without waiting for a writer; now read as usual
        return fh.read(limit + 1)


def jsonable(obj: Any) -> Any:
    """Plain JSON types: numpy scalars and arrays converted, non-finite floats as null (strict
    JSON)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return finite_or_none(obj)
    if obj is None or isinstance(obj, str):
        return obj
    if hasattr(obj, "items"):
        return jsonable(dict(obj.items()))
    return str(obj)


def write_json(path: str | os.PathLike, data: Any) -> Path:
    text = json.dumps(jsonable(data), indent=2, allow_nan=False) + "\n"
    return atomic_write(path, lambda fh: fh.write(text.encode("utf-8")))


def write_npz(path: str | os.PathLike, arrays: dict[str, np.ndarray]) -> Path:
    return atomic_write(path, lambda fh: np.savez(fh, **arrays))


def write_set(out: str | os.PathLike, write: Callable[[Path], Any], *,
              overwrite: bool = True) -> list[Path]:
    """All or nothing: ``write(staging)`` writes a command's files into a staging directory, which
    then takes the place of ``out``; returns the final paths of what ``write`` returned.

    Without ``out`` (or with ``out`` empty) the staging directory
    ``.<name>.<pid>-<host>.<random>.tmp`` is made next to ``out`` and renamed to ``out`` at the end
    (one rename: ``out`` is absent or complete).  Into an ``out`` that holds other files the staging
    directory is made inside ``out`` and, once every file is complete, its files are renamed into
    place (renames only: no write can fail any more).  On any error the staging directory is removed
    and ``out`` keeps its earlier contents; an OSError names the file as it would have been in
    ``out``.  ``overwrite`` false refuses (FileExistsError) a file that appeared in ``out``
    meanwhile, before anything is moved.  A killed writer leaves only its staging directory, removed
    as a stale temporary by the next write of ``out`` (and by :func:`remove_stale_temps`).
    """
    out = Path(out)
    # into an existing directory unless it is empty (a symbolic link to one is kept, not replaced)
    into = out.is_dir() and (out.is_symlink() or any(True for _ in os.scandir(out)))
    base = out if into else out.parent
    base.mkdir(parents=True, exist_ok=True)
    name = out.resolve().name or "out"   # "." or "/" have no name of their own
    remove_stale_temps(base, None if into else name)
    staging = Path(tempfile.mkdtemp(dir=base, prefix=temp_prefix(name), suffix=".tmp"))
    try:
        os.chmod(staging, 0o755)   # mkdtemp makes it private; results are readable by others
        written = write(staging)
        finals = [out / Path(p).relative_to(staging) for p in written]
        if not overwrite:
            _refuse_existing(staging, out)
        if into:
            _move_into(staging, out)
        else:
            _rename_dir(staging, out)
    except OSError as exc:
        _remove(staging)
        name = exc.filename
        if name is not None and str(name).startswith(str(staging)):
            final = str(out) + str(name)[len(str(staging)):]
            raise OSError(exc.errno, exc.strerror or str(exc), final) from exc
        raise
    except BaseException:
        _remove(staging)
        raise
    _remove(staging)
    _fsync_dir(base)
    return finals


def _refuse_existing(staging: Path, out: Path) -> None:
    for root, _, files in os.walk(staging):
        for name in files:
            target = out / Path(root, name).relative_to(staging)
            if os.path.lexists(target):
                raise FileExistsError(errno.EEXIST, "exists", str(target))


def _rename_dir(staging: Path, out: Path) -> None:
    """Rename the staging directory to ``out`` (absent, or an empty directory: replaced)."""
    try:
        os.replace(staging, out)
    except OSError:
        if not out.is_dir():
            raise
        os.rmdir(out)   # empty (checked by the caller); Windows cannot rename over a directory
        os.replace(staging, out)


def _move_into(staging: Path, out: Path) -> None:
    """Rename the entries of ``staging`` into ``out``: a folder absent there as a whole, the
    others entry by entry."""
    for entry in sorted(os.scandir(staging), key=lambda e: e.name):
        target = out / entry.name
        if entry.is_dir(follow_symlinks=False) and target.is_dir():
            _move_into(Path(entry.path), target)
        else:
            os.replace(entry.path, target)
