"""Numbers and tables as text for ``report.md`` and the statement checks (markdown)."""
from __future__ import annotations

import numpy as np

from ocp_crawl.checks import finite_or_none
from ocp_crawl.studies.common import MM


def num(x: float, fmt: str = ".3f") -> str:
    """A number, or "n/a" when it could not be computed (e.g. the normalising run failed)."""
    x = finite_or_none(x)
    return "n/a" if x is None else format(x, fmt)


def rel(ours: float, paper: float) -> str:
    """ours/paper - 1, or "-" where the paper's value is too small for a ratio to mean anything."""
    return f"{ours / paper - 1:+.1%}" if np.isfinite(ours) and abs(paper) >= 0.05 else "-"


def fmt_mm(S: float) -> str:
    """A distance S [m] in mm with two decimals, or "failed" when it is not finite."""
    # + 0.0 turns a rounded -0.00 into 0.00
    return "failed" if not np.isfinite(S) else f"{round(MM * S, 2) + 0.0:.2f} mm"


def runs_text(runs, var: str) -> str:
    """Outcome runs (from :func:`~ocp_crawl.studies.common.outcome_runs`) as "name for var = a..b; ..."."""
    return "; ".join(f"{name} for {var} = {a:.3g}" + (f"..{b:.3g}" if b != a else "") for name, a, b, _ in runs)


def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table ("|" in cells becomes "/")."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c).replace("|", "/") for c in r) + " |" for r in rows]
    return "\n".join(lines)


def counts_text(counts: dict[str, int]) -> str:
    """Status counts as "success 12, fold 3"."""
    return ", ".join(f"{k} {v}" for k, v in counts.items())
