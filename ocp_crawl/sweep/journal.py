"""The files of a sweep directory: settings.json, the journal, results.csv and summary.json.

The journal (``results.partial.csv``) gets one line per finished point in completion order,
written to the operating system as it arrives, so that a killed run loses only the points in
flight; a line torn by a kill is cut off by the resuming run.  It is fsync'd when a row arrives
:data:`FSYNC_SECONDS` or more after the last fsync, and when the sweep stops: an fsync costs ~4 ms,
as much as a fast point, and guards only against a crash of the machine (not of the process), which
may lose the rows written since the last fsync (the resumed sweep computes them again).  One writer
at a time (an advisory ``flock`` on ``.sweep.lock``, released when its process dies).
"""
from __future__ import annotations

import csv
import json
import os
import sys
import time
from pathlib import Path
from typing import IO, Any, Sequence

from ocp_crawl.io.files import naming, remove_stale_temps, write_json
from ocp_crawl.status import Status
from ocp_crawl.sweep.cells import cell, parse_rows, row_line
from ocp_crawl.sweep.settings import SweepError, SweepSettings

#: the files of a sweep's output directory: its settings, the journal of finished rows (appended
#: as they finish, read by --resume), the rows in grid order, the summary
SETTINGS_FILE, JOURNAL_FILE, RESULTS_FILE, SUMMARY_FILE = (
    "settings.json", "results.partial.csv", "results.csv", "summary.json")
LOCK_FILE = ".sweep.lock"

#: longest time between two fsyncs of the journal while rows arrive [s]
FSYNC_SECONDS = 1.0


def _decoded(raw: bytes, path: Path) -> str:
    """``raw`` (the bytes of ``path``) as UTF-8 text; bytes that are not UTF-8 are a damaged file
    like a garbage row: SweepError naming the file, the line and the byte."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise SweepError(f"{path}:{line}: not UTF-8 text (byte 0x{raw[exc.start]:02x}); the file "
                         "is damaged: start again with --force") from None


#: the first header cell of the journal: the flat index of the row's point
INDEX_COLUMN = "index [-]"


def check_header(path: Path, line: str, expected: Sequence[str], bare: Sequence[str]) -> None:
    """Every cell of the header ``line`` of ``path`` must be the column with its unit (``expected``)
    or its bare name (``bare``: a file written before the headers carried units, read the same);
    SweepError naming the first column that differs otherwise."""
    cells = next(csv.reader([line]))
    if len(cells) != len(expected):
        what = f"{len(cells)} columns, expected {len(expected)}: {', '.join(expected)}"
    else:
        wrong = [i for i, c in enumerate(cells) if c not in (expected[i], bare[i])]
        if not wrong:
            return
        what = f"column {wrong[0] + 1} is {cells[wrong[0]]!r}, expected {expected[wrong[0]]!r}"
    raise SweepError(f"{path}: columns differ from {SETTINGS_FILE} ({what}); "
                     "start again with --force")


class SweepStore:
    """The files of one sweep directory: settings, journal, results; one writer at a time."""

    def __init__(self, out_dir: Path):
        self.dir = out_dir
        self.settings_path = out_dir / SETTINGS_FILE
        self.journal_path = out_dir / JOURNAL_FILE
        self.results_path = out_dir / RESULTS_FILE
        self.summary_path = out_dir / SUMMARY_FILE
        self._journal: IO[str] | None = None  # open while writing (after begin)
        self._lock: IO[str] | None = None
        self._synced = 0.0  # time.monotonic() of the last fsync
        self._dirty = False  # lines written since

    # ---- reading
    def read_settings(self) -> SweepSettings:
        """The settings.json of the directory; SweepError if absent or malformed."""
        try:
            data = json.loads(_decoded(self.settings_path.read_bytes(), self.settings_path))
        except FileNotFoundError:
            raise SweepError(f"{self.dir}: no {SETTINGS_FILE}: not a sweep directory") from None
        except (OSError, json.JSONDecodeError) as exc:
            raise SweepError(f"{self.settings_path}: cannot read: {exc}") from None
        return SweepSettings.from_dict(data, str(self.settings_path))

    def read_done(self, settings: SweepSettings, repair: bool = False) -> dict[int, dict[str, Any]]:
        """Finished rows by flat index: all of results.csv, else those of the journal.

        ``repair`` (the writer only) cuts a line torn by a kill off the journal before appending to
        it.
        """
        done: dict[int, dict[str, Any]] = {}
        if self.results_path.exists():
            lines = _decoded(self.results_path.read_bytes(),
                             self.results_path).splitlines(keepends=True)
            if not lines:
                raise SweepError(f"{self.results_path}: empty file (no header); "
                                 "start again with --force")
            check_header(self.results_path, lines[0], settings.header(), settings.columns)
            rows = parse_rows(lines[1:], settings.columns, settings, str(self.results_path), 2)
            if len(rows) != settings.size:
                raise SweepError(f"{self.results_path}: {len(rows)} rows for {settings.size} "
                                 "points; start again with --force")
            for i, row in enumerate(rows):
                self._check_point(settings, i, row, self.results_path)
                # a point not computed is computed on --resume
                if row["status"] != Status.MISSING.label:
                    done[i] = row
        if self.journal_path.exists():
            for i, row in self._read_journal(settings, repair).items():
                done.setdefault(i, row)
        return done

    def _read_journal(self, settings: SweepSettings, repair: bool) -> dict[int, dict[str, Any]]:
        raw = self.journal_path.read_bytes()
        body, _, torn = raw.rpartition(b"\n")
        if torn and repair:
            # a run killed in the middle of writing a line: that point was not finished
            with open(self.journal_path, "r+b") as fh:
                fh.truncate(len(body) + 1 if body else 0)
        lines = _decoded(body + b"\n", self.journal_path).splitlines(keepends=True) if body else []
        columns = ("index",) + settings.columns
        if not lines:
            return {}
        check_header(self.journal_path, lines[0], (INDEX_COLUMN,) + settings.header(), columns)
        done: dict[int, dict[str, Any]] = {}
        for n, row in enumerate(parse_rows(lines[1:], columns, settings, str(self.journal_path), 2),
                                2):
            index = row.pop("index")
            if not isinstance(index, int) or not 0 <= index < settings.size:
                raise SweepError(f"{self.journal_path}:{n}: index {index!r} is not a point of the "
                                 "grid")
            self._check_point(settings, index, row, self.journal_path)
            if row["status"] != Status.MISSING.label:
                done.setdefault(index, row)
        return done

    @staticmethod
    def _check_point(settings: SweepSettings, index: int, row: dict, path: Path) -> None:
        expected = settings.point(index)
        if any(row[k] != v for k, v in expected.items()):
            raise SweepError(f"{path}: row of point {index} has grid values "
                             f"{[row[k] for k in expected]}, expected {list(expected.values())}; "
                             "start again with --force")

    # ---- writing
    def _acquire(self) -> None:
        try:
            import fcntl
        except ImportError:  # no advisory locks (Windows): one writer is then the user's business
            return
        self._lock = open(self.dir / LOCK_FILE, "a")
        try:
            fcntl.flock(self._lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self._lock.close()
            self._lock = None
            raise SweepError(f"{self.dir}: another sweep is writing to this directory") from None

    def open(self, settings: SweepSettings, resume: bool, force: bool) -> dict[int, dict[str, Any]]:
        """Start or resume the sweep's files; returns the finished rows (empty unless resuming)."""
        self.dir.mkdir(parents=True, exist_ok=True)
        self._acquire()
        try:
            remove_stale_temps(self.dir)  # temporary files of a killed run (see files.atomic_write)
            return self._open(settings, resume, force)
        except BaseException:
            self.close()
            raise

    def _open(self, settings: SweepSettings, resume: bool,
              force: bool) -> dict[int, dict[str, Any]]:
        ours = [p for p in (self.settings_path, self.journal_path, self.results_path) if p.exists()]
        done: dict[int, dict[str, Any]] = {}
        if resume and self.settings_path.exists():
            old = self.read_settings()
            diff = settings.differences(old)
            if diff:
                raise SweepError(f"{self.dir}: cannot resume: this sweep differs from its "
                                 f"{SETTINGS_FILE} (saved -> now: "
                                 f"{'; '.join(diff[:4])}{'; ...' if len(diff) > 4 else ''}); use "
                                 "another output directory, or --force to start over")
            done = self.read_done(settings, repair=True)
        elif resume and ours:
            raise SweepError(f"{self.dir}: cannot resume: no {SETTINGS_FILE} to check the settings "
                             "against; use --force to start over")
        elif ours and not force:
            raise SweepError(f"{self.dir}: already holds a sweep "
                             f"({', '.join(p.name for p in ours)}); continue it with --resume, or "
                             "overwrite it with --force")
        else:
            for p in (self.journal_path, self.results_path, self.summary_path):
                p.unlink(missing_ok=True)
            write_json(self.settings_path, settings.to_dict())
        # a journal killed before its header was complete is empty (repaired above): it needs the
        # header
        fresh = not self.journal_path.exists() or self.journal_path.stat().st_size == 0
        self._journal = open(self.journal_path, "a", encoding="utf-8", newline="")
        if fresh:
            self._write_line(row_line((INDEX_COLUMN,) + settings.header()), sync=True)
        return done

    def _write_line(self, line: str, sync: bool = False) -> None:
        assert self._journal is not None  # called while the journal is open
        try:
            self._journal.write(line)
            self._journal.flush()
            self._dirty = True
            if sync or time.monotonic() - self._synced >= FSYNC_SECONDS:
                self._sync()
        except OSError as exc:  # a full disk says only "No space left on device": name the journal
            raise naming(exc, self.journal_path) from exc

    def _sync(self) -> None:
        assert self._journal is not None  # called while the journal is open
        os.fsync(self._journal.fileno())
        self._synced, self._dirty = time.monotonic(), False

    def append(self, settings: SweepSettings, index: int, row: dict[str, Any]) -> None:
        """Journal the finished row of point ``index`` (flushed; fsync'd at most every
        FSYNC_SECONDS)."""
        self._write_line(row_line([str(index)] + [cell(row[c]) for c in settings.columns]))

    def finish(self, result) -> None:
        """Write results.csv and summary.json of the complete ``result`` (a SweepResult), then drop
        the journal."""
        result.to_csv(self.results_path)
        write_json(self.summary_path, result.summary())
        # results.csv holds every row now; a kill before this unlink leaves a journal that resume
        # ignores
        self.journal_path.unlink(missing_ok=True)
        self._dirty = False

    def close(self) -> None:
        """Close the journal and release the lock.  An OSError of the closing (the flush of a line
        a full disk refused) names the journal; after a failure it gives way to the error already
        on its way."""
        if self._journal is not None:
            try:
                if self._dirty:
                    self._sync()  # an interrupted sweep's rows, on disk for --resume
            except OSError:
                pass  # closing after a failure (a full disk, ...): the error is already on its way
            journal, self._journal = self._journal, None
            try:
                journal.close()
            except OSError as exc:
                if sys.exc_info()[0] is None:
                    raise naming(exc, self.journal_path) from exc
        if self._lock is not None:
            self._lock.close()  # releases the flock
            self._lock = None

