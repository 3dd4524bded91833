"""CSV cells of the sweep's files: exact round trip (floats by repr), so a resumed sweep writes the
same file."""
from __future__ import annotations

import csv
import io
import json
import math
from typing import Any, Sequence

import numpy as np

from ocp_crawl.io.files import jsonable
from ocp_crawl.status import Status
from ocp_crawl.sweep.settings import SweepError, SweepSettings
from ocp_crawl.sweep.grid import schema_key


def cell(value: Any) -> str:
    """A value as CSV cell text: "" for None and NaN, floats by repr, one-line strings, JSON for
    lists."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        x = float(value)
        return "" if math.isnan(x) else repr(x)
    if isinstance(value, str):
        return " ".join(value.splitlines())  # one line per row keeps the journal line-oriented
    return json.dumps(jsonable(value), separators=(",", ":"), allow_nan=False)


def parse_cell(text: str) -> Any:
    """Inverse of :func:`cell` for columns of unknown type (extra columns)."""
    if text == "":
        return math.nan
    if text in ("true", "false"):
        return text == "true"
    if text[0] in "[{":
        try:
            return json.loads(text)
        except json.JSONDecodeError:
            return text
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text



def _status(text: str) -> str:
    """A status cell: the label of a :class:`~ocp_crawl.status.Status` as written (ValueError for
    any other text)."""
    # from_label takes any case; the files hold the lower-case label
    if Status.from_label(text).label != text:
        raise ValueError(f"unknown status {text!r}; valid: {', '.join(s.label for s in Status)}")
    return text


def _parser(settings: SweepSettings, column: str):
    if column in settings.keys:
        kind = schema_key(column, column).type
        return kind if kind is not float else float
    if column in ("S", "W_plus", "CoT_plus"):
        return lambda t: math.nan if t == "" else float(t)
    if column == "status":
        return _status
    if column == "message":
        return str
    return parse_cell


def row_line(cells: Sequence[str]) -> str:
    """One CSV line (with its newline) of cell texts."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(cells)
    return buf.getvalue()


def parse_rows(lines: Sequence[str], columns: Sequence[str], settings: SweepSettings, where: str,
               first_line: int) -> list[dict[str, Any]]:
    """Rows of CSV ``lines`` (the first is line ``first_line`` of ``where``), typed per column;
    SweepError names the line of a malformed row."""
    parsers = [_parser(settings, c) for c in columns]
    out = []
    for n, cells in enumerate(csv.reader(lines), first_line):
        if len(cells) != len(columns):
            raise SweepError(f"{where}:{n}: malformed row ({len(cells)} fields, expected "
                             f"{len(columns)}); start the sweep again with --force")
        try:
            row = {c: p(t) for c, p, t in zip(columns, parsers, cells)}
            success = Status.SUCCESS.label
            if row.get("status") == success and "S" in row and not math.isfinite(row["S"]):
                raise ValueError(f"status {success!r} with an empty S (every success has a stride)")
            out.append(row)
        except ValueError as exc:
            raise SweepError(f"{where}:{n}: malformed row: {exc}; start the sweep again with "
                             "--force") from None
    return out

