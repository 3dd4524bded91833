"""Numbers and tables as text for ``report.md`` and the statement checks (markdown)."""
from __future__ import annotations

import numpy as np

from ocp_crawl.checks import finite_or_none
from ocp_crawl.io import units


def num(x: float, fmt: str = ".3f") -> str:
    """A number, or "n/a" when it could not be computed (e.g. the normalising run failed); a value
    that rounds to zero prints without a sign (never "-0.000")."""
    x = finite_or_none(x)
    if x is None:
        return "n/a"
    text = format(x, fmt)
    mantissa = text.split("e")[0]
    return text if any(ch in "123456789" for ch in mantissa) else format(abs(x), fmt)


def dec(x: float, decimals: int = 2) -> str:
    """A number with ``decimals`` decimals for a table cell, "-" when it is missing; zero never
    prints as -0.00."""
    return units.fixed(x, decimals)


def threshold_text(k_ratio: float, digits: int = 4) -> str:
    """A stiffness threshold k/(M g L) as "0.1004 M g L", or "none found" when it is NaN."""
    return f"{k_ratio:.{digits}f} M g L" if np.isfinite(k_ratio) else "none found"


def rel(ours: float, paper: float) -> str:
    """ours/paper - 1, or "-" where the paper's value is too small for a ratio to mean anything."""
    # rounded first (+ 0.0): a difference below 0.05 % prints as +0.0%, never -0.0%
    return (f"{round(ours / paper - 1, 3) + 0.0:+.1%}" if np.isfinite(ours) and abs(paper) >= 0.05
            else "-")


def fmt_mm(S: float) -> str:
    """A distance S [m] in mm with two decimals, or "failed" when it is not finite."""
    return units.distance(S, 2) if np.isfinite(S) else "failed"


def runs_text(runs, var: str) -> str:
    """Outcome runs (from :func:`~ocp_crawl.studies.common.outcome_runs`) as "name for var = a..b;
    ..."."""
    return "; ".join(f"{name} for {var} = {a:.3g}"
                     + (f"..{b:.3g}" if b != a else "") for name, a, b, _ in runs)


def _cell(text) -> str:
    # an escaped bar stays inside its cell (|S| renders as |S|, not as a column break)
    return str(text).replace("|", "\\|")


def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table, a blank line before it; a "|" in the header or a cell is escaped
    ("\\|")."""
    lines = ["", "| " + " | ".join(_cell(h) for h in header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def counts_text(counts: dict[str, int]) -> str:
    """Status counts as "success 12, fold 3"."""
    return ", ".join(f"{k} {v}" for k, v in counts.items())
