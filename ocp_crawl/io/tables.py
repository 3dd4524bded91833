"""One CSV convention for every input and measurement file.

A table is a CSV file whose first non-comment row is a header; every column name carries its unit
in square brackets, ``phase [-]``, ``tau1 [N m]``, ``phi1 [deg]``, ``S [mm]``, ``sigma_S [mm]``.
Lines starting with ``#`` are comments (free text, e.g. provenance). Values are decimal numbers;
an empty cell is an error (a missing measurement is a missing row, not a blank).

:func:`read_table` checks the header against the columns a caller asks for (name and physical
dimension), converts every column to SI units and keeps the file line of every row, so that an
error names the file and the line: ``data.csv:7: column 'tau1 [N m]': 'abc' is not a number``.
:func:`write_table` writes the same convention back with full precision (``repr`` of every float),
so that a file read back gives the very same numbers.
"""
from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from ocp_crawl.checks import parse_number
from ocp_crawl.io.files import atomic_write, read_bounded

#: Accepted units per physical dimension, with their factor to the SI unit (angles to rad).
UNITS: dict[str, dict[str, float]] = {
    "dimensionless": {"-": 1.0, "1": 1.0},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "torque": {"N m": 1.0, "N mm": 1e-3, "mN m": 1e-3},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "bar": 1e5, "MPa": 1e6},
    "time": {"s": 1.0, "ms": 1e-3},
    "frequency": {"Hz": 1.0},
    "energy": {"J": 1.0, "mJ": 1e-3},
    "force": {"N": 1.0, "mN": 1e-3},
    "mass": {"kg": 1.0, "g": 1e-3},
    "stiffness": {"N m/rad": 1.0},
}

#: The unit every column is converted to, per dimension.
SI_UNIT = {"dimensionless": "-", "angle": "rad", "torque": "N m", "length": "m", "pressure": "Pa",
           "time": "s",
           "frequency": "Hz", "energy": "J", "force": "N", "mass": "kg", "stiffness": "N m/rad"}

_HEADER = re.compile(r"^\s*([^\[\]]*?)\s*\[\s*([^\[\]]*?)\s*\]\s*$")
MAX_TABLE_BYTES = 16 * 2**20


class TableError(ValueError):
    """A table file breaks the convention; ``str(exc)`` is one line
    ``FILE[:LINE]: what is wrong``."""

    def __init__(self, path: str | os.PathLike, message: str, line: int | None = None):
        self.path, self.line, self.reason = str(path), line, message
        # a NUL or newline in the name
        shown = self.path if self.path.isprintable() else ascii(self.path)
        where = f"{shown}:{line}" if line is not None else shown
        super().__init__(f"{where}: {message}")


@dataclass(frozen=True)
class Table:
    """A table read from a file: columns in SI units, with the units as written and the row lines.

    Attributes
    ----------
    path : str
        The file read.
    columns : dict[str, numpy.ndarray]
        Column name (without unit) -> values converted to SI (angles in rad).
    units : dict[str, str]
        Column name -> unit as written in the header.
    lines : numpy.ndarray of int
        The 1-based file line of every row (for messages about a row).
    """

    path: str
    columns: dict[str, np.ndarray]
    units: dict[str, str]
    lines: np.ndarray = field(repr=False)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def __len__(self) -> int:
        return len(self.lines)

    def line_of(self, row: int) -> int:
        """The file line of row ``row`` (0-based)."""
        return int(self.lines[row])

    def error(self, message: str, row: int | None = None) -> TableError:
        """A :class:`TableError` about this file (and row ``row`` if given), to raise."""
        return TableError(self.path, message, None if row is None else self.line_of(row))


def split_header(cell: str) -> tuple[str, str] | None:
    """``'tau1 [N m]'`` -> ``('tau1', 'N m')``; ``None`` when the cell has no ``[unit]``."""
    m = _HEADER.match(cell)
    if m is None or not m.group(1):
        return None
    return m.group(1), " ".join(m.group(2).split())


def _rows(path: Path) -> list[tuple[int, list[str]]]:
    """Non-comment, non-blank CSV rows with their 1-based line numbers."""
    try:
        raw = read_bounded(path, MAX_TABLE_BYTES)
        if len(raw) > MAX_TABLE_BYTES:
            raise TableError(path, f"file larger than {MAX_TABLE_BYTES // 2**20} MiB")
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise TableError(path, f"not UTF-8 text ({exc.reason})") from None
    except OSError as exc:
        raise TableError(path, exc.strerror or type(exc).__name__) from None
    out = []
    for lineno, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            cells = next(csv.reader([line]))
        except csv.Error as exc:
            raise TableError(path, f"not CSV ({exc})", lineno) from None
        out.append((lineno, [c.strip() for c in cells]))
    return out


def _header(path: Path, lineno: int, cells: list[str]) -> list[tuple[str, str]]:
    names = []
    for cell in cells:
        split = split_header(cell)
        if split is None:
            raise TableError(path, f"header cell {cell!r} has no unit: write it as 'name [unit]' "
                                   "(use [-] for a pure number)", lineno)
        if split[0] in (n for n, _ in names):
            raise TableError(path, f"column {split[0]!r} appears twice in the header", lineno)
        names.append(split)
    return names


def _factor(path: Path, lineno: int, name: str, unit: str, dimension: str) -> float:
    units = UNITS[dimension]
    if unit not in units:
        raise TableError(path, f"column {name!r}: unit [{unit}] is not a {dimension} unit (one of "
                               f"{', '.join('[' + u + ']' for u in units)})", lineno)
    return units[unit]


def _number(path: Path, lineno: int, name: str, unit: str, text: str) -> float:
    try:
        value = parse_number(text)
    except ValueError:
        raise TableError(path, f"column '{name} [{unit}]': {text!r} is not a number",
                         lineno) from None
    if not math.isfinite(value):
        raise TableError(path, f"column '{name} [{unit}]': {text} is not a finite number", lineno)
    return value


def read_table(path: str | os.PathLike, required: Mapping[str, str],
               optional: Mapping[str, str] | None = None,
               *, min_rows: int = 1, allow_extra: bool = False) -> Table:
    """Read a CSV table of the package's convention, checked and converted to SI units.

    Parameters
    ----------
    path : str or path-like
        The CSV file.
    required : mapping of str to str
        Column name (without unit) -> physical dimension (a key of :data:`UNITS`, e.g. ``"angle"``).
        Every one must be in the header.
    optional : mapping of str to str, optional
        Columns that may be present, same form.
    min_rows : int
        The fewest data rows accepted.
    allow_extra : bool
        Accept (and keep, unconverted) columns not named in ``required``/``optional``.

    Returns
    -------
    Table
        Columns in SI units (angles in rad), units as written, the file line of every row.

    Raises
    ------
    TableError
        With a one-line message naming the file and, where there is one, the line.
    """
    path = Path(path)
    known = {**(optional or {}), **required}
    rows = _rows(path)
    if not rows:
        columns = required or known   # a file of optional columns only: name them
        raise TableError(path, "no header row (expected 'name [unit]' cells, e.g. " + ", ".join(
            repr(f"{n} [{SI_UNIT[d]}]") for n, d in list(columns.items())[:4]) + ")")
    head_line, head = rows[0]
    names = _header(path, head_line, head)
    present = [n for n, _ in names]
    missing = [n for n in required if n not in present]
    if missing:
        raise TableError(path,
                         f"missing column(s) {', '.join(repr(m) for m in missing)} (header has "
                         f"{', '.join(repr(c) for c in head)})", head_line)
    extra = [n for n in present if n not in known]
    if extra and not allow_extra:
        raise TableError(path, f"unknown column(s) {', '.join(repr(e) for e in extra)} (expected "
                               f"{', '.join(repr(k) for k in known)})", head_line)
    factors = [_factor(path, head_line, n, u, known[n]) if n in known else 1.0 for n, u in names]
    data, lines = [], []
    for lineno, cells in rows[1:]:
        if len(cells) != len(names):
            raise TableError(path, f"{len(cells)} cells where the header has {len(names)} columns",
                             lineno)
        data.append([_number(path, lineno, n, u, c) * f
                     for (n, u), c, f in zip(names, cells, factors)])
        lines.append(lineno)
    if len(data) < min_rows:
        raise TableError(path, f"{len(data)} data row(s); at least {min_rows} needed")
    arr = np.array(data, dtype=float).reshape(len(data), len(names))
    return Table(str(path), {n: arr[:, j].copy() for j, (n, _) in enumerate(names)},
                 {n: u for n, u in names}, np.array(lines, dtype=int))


def table_text(columns: Sequence[tuple[str, str, Iterable[float]]],
               comments: Sequence[str] = ()) -> str:
    """The CSV text of ``columns`` = [(name, unit, values), ...] with full precision (``repr``
    floats)."""
    cols = [(n, u, [float(v) for v in vals]) for n, u, vals in columns]
    lengths = {len(v) for _, _, v in cols}
    if len(lengths) > 1:
        raise ValueError(f"columns of unequal length {sorted(lengths)}")
    buf = io.StringIO()
    for c in comments:
        buf.write(f"# {c}\n")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow([f"{n} [{u}]" for n, u, _ in cols])
    for row in zip(*(v for _, _, v in cols)):
        writer.writerow([repr(x) for x in row])
    return buf.getvalue()


def write_table(path: str | os.PathLike, columns: Sequence[tuple[str, str, Iterable[float]]],
                comments: Sequence[str] = ()) -> Path:
    """Write ``columns`` = [(name, unit, values), ...] as a CSV table of the convention, atomically.

    Values are written as given (no unit conversion) with full precision; ``comments`` become
    leading ``# `` lines. Returns the path written.
    """
    data = table_text(columns, comments).encode("utf-8")
    return atomic_write(path, lambda f: f.write(data))
