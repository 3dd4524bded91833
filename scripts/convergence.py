"""Convergence in N of the shipped OCP problems, checked against the convergence criteria below (run
by hand; the tables go into notes).

    python scripts/convergence.py                                  # the three problems,
                                                                     N = 50 100 200 400
    python scripts/convergence.py --problems ocp_max_speed --nodes 50 100 200

For each problem the OCP is solved at each N (:func:`ocp_crawl.ocp.convergence.converge_in_nodes`:
the first N from the harmonic baseline and its starts, each next one warm-started from the previous
optimum, every optimum judged by its event-driven replay) and the table is printed as
``ocp-crawl optimize FILE --nodes ...`` prints it, followed by the verdicts: the judge accepted
every N; the replayed objective at N = 100 and at N = 200 within 1 % of the finest N; no N worse
than the harmonic baseline by replay (beyond replay_tol).  Exit code 1 if a verdict fails.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ocp_crawl.cli.optimize_command import format_convergence
from ocp_crawl.ocp.convergence import converge_in_nodes
from ocp_crawl.problem import load_problem, ocp_settings

REPO = Path(__file__).resolve().parent.parent
PROBLEMS = ("ocp_max_speed", "ocp_min_cot", "ocp_robust")


def verdicts(table) -> list[tuple[str, bool]]:
    """The convergence criteria on a convergence table: (what, holds)."""
    rows = {r.nodes: r for r in table.rows}
    finest = table.rows[-1]
    out = [("the judge accepts every N", table.success)]
    for n in (100, 200):
        if n in rows and n != finest.nodes:
            close = abs(rows[n].value_replay
                        - finest.value_replay) <= 0.01 * abs(finest.value_replay)
            out.append((f"N = {n} within 1 % of N = {finest.nodes}", bool(close)))
    worse = [r.nodes for r in table.rows if not r.result.gain >= -r.result.settings.replay_tol]
    out.append(("no N worse than the harmonic baseline by replay"
                + (f" (worse: {worse})" if worse else ""), not worse))
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--problems", nargs="+", default=list(PROBLEMS),
                   help="problem files in problems/ (stems)")
    p.add_argument("--nodes", nargs="+", type=int, default=[50, 100, 200, 400],
                   help="strictly increasing N")
    args = p.parse_args(argv)
    ok = True
    for name in args.problems:
        problem = load_problem(REPO / "problems" / f"{name}.toml")
        t0 = time.perf_counter()
        table = converge_in_nodes(problem.robot, problem.gravity, ocp_settings(problem), args.nodes,
                                  log=lambda text: print(f"  {name}: {text}", file=sys.stderr,
                                                         flush=True))
        print(f"\n{name} ({time.perf_counter() - t0:.0f} s)\n{format_convergence(table.to_dict())}")
        for what, holds in verdicts(table):
            print(f"  {'PASS' if holds else 'FAIL'}  {what}")
            ok = ok and holds
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
