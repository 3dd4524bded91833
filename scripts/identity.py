"""Record what the code computes, and compare two records: a refactoring must not move a number.

    python scripts/identity.py record before.json            # everything (the OCP files: minutes)
    python scripts/identity.py record before.json --skip ocp reproduce --random 50
    python scripts/identity.py compare before.json after.json

A record holds, by category, the numbers of: ``random`` (seeded random event-solver problems over
robots, both gravity conventions and the harmonic, pulse and samples waveforms: status, S, W+, the
event phases), ``demo`` (``ocp-crawl demo``'s summaries), ``reproduce`` (``reproduce --quick``'s
numbers.json) and ``ocp`` (the shipped OCP files, harmonic baseline only: the replayed optimum).
``compare`` flattens both to leaves and reports, per category, the largest relative difference of
the numbers and every leaf whose text differs; the simulators must agree to :data:`TOL` ``["sim"]``,
the optima to ``TOL["ocp"]``.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: relative tolerances of compare: the simulators' numbers, the optima
TOL = {"sim": 1e-12, "ocp": 1e-9}
#: the OCP files recorded and the keys kept of their optimize --json
OCP_FILES = ("ocp_max_speed.toml", "ocp_min_cot.toml", "ocp_robust.toml")
OCP_KEYS = ("status", "S_replay", "W_plus_replay", "T_ocp", "v_replay", "CoT_plus_replay",
            "objective_value_replay")
CATEGORIES = ("random", "demo", "reproduce", "ocp")


def _cli(*args: str) -> str:
    out = subprocess.run([sys.executable, "-m", "ocp_crawl", *args], capture_output=True, text=True,
                         cwd=ROOT, env=dict(os.environ, MPLBACKEND="Agg"))
    if out.returncode not in (0, 1):
        raise SystemExit(f"ocp-crawl {' '.join(args)} failed: {out.stderr.strip()}")
    return out.stdout


def _problem(rng: random.Random) -> dict:
    """A random valid-looking problem: paper-like robot, any gravity, one of three waveforms."""
    robot = {"M": rng.uniform(0.02, 0.2), "L": rng.uniform(0.05, 0.2),
             "beta": rng.uniform(0.6, 1.6), "mu1": rng.uniform(0.2, 0.6),
             "mu2": rng.uniform(0.2, 0.6)}
    robot["k"] = rng.uniform(0.5, 20.0) * robot["M"] * 9.81 * robot["L"]
    kind = rng.choice(["harmonic", "pulse", "samples"])
    gait = {"gamma_deg": rng.uniform(70, 110), "psi_deg": rng.uniform(-180, 180)}
    if kind == "harmonic":
        gait["A_deg"] = rng.uniform(5, 35)
    elif kind == "pulse":
        gait.update(waveform="pulse", A_deg=rng.uniform(5, 35), rise=rng.uniform(0.05, 0.5),
                    duty=rng.uniform(0, 1))
    else:
        n = rng.randint(4, 12)
        phase = sorted(rng.uniform(0, 1) for _ in range(n))
        gait = {"waveform": "samples", "phase": phase,
                "phi1_ref_deg": [rng.uniform(60, 120) for _ in phase],
                "phi2_ref_deg": [rng.uniform(60, 120) for _ in phase]}
    return {"robot": robot, "gait": gait,
            "model": {"gravity": rng.choice(["physical", "paper"])}}


def record_random(count: int, seed: int = 20261129) -> list:
    from ocp_crawl import ProblemError, problem_from_dict, run_problem

    rng, out = random.Random(seed), []
    while len(out) < count:
        data = _problem(rng)
        try:
            problem = problem_from_dict(data)
        except ProblemError:
            continue
        r = run_problem(problem)
        out.append({"problem": data, "status": r.status_name, "S": r.S, "W_plus": r.W_plus,
                    "events": [e.t for e in r.steady_events()] if r.success else []})
    return out


def record_demo() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        _cli("demo", "--out", tmp)
        return {str(p.relative_to(tmp)): json.loads(p.read_text())
                for p in sorted(Path(tmp).rglob("*.json"))}


def record_reproduce() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        _cli("reproduce", "--quick", "--out", tmp, "--jobs", "2", "--no-progress")
        return json.loads((Path(tmp) / "numbers.json").read_text())


def record_ocp() -> dict:
    out = {}
    for name in OCP_FILES:
        data = json.loads(_cli("optimize", f"problems/{name}", "--json", "--set",
                               "ocp.baselines=\"harmonic\""))
        out[name] = {k: data.get(k) for k in OCP_KEYS}
    return out


def leaves(x, path=""):
    """(path, value) of every leaf of nested dicts and lists."""
    if isinstance(x, dict):
        for k, v in x.items():
            yield from leaves(v, f"{path}/{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from leaves(v, f"{path}[{i}]")
    else:
        yield path, x


#: leaves that are wall-clock times, not numbers of the code (left out of the comparison)
TIMINGS = ("elapsed_s", "time_s")


def _timing(path: str) -> bool:
    return any(part.endswith(TIMINGS) for part in path.split("/"))


def compare(a: dict, b: dict) -> bool:
    ok = True
    for cat in CATEGORIES:
        if cat not in a or cat not in b:
            print(f"{cat:10s} not in both records")
            continue
        la = {p: v for p, v in leaves(a[cat]) if not _timing(p)}
        lb = {p: v for p, v in leaves(b[cat]) if not _timing(p)}
        worst, where, texts = 0.0, "", [p for p in la.keys() ^ lb.keys()]
        for p in la.keys() & lb.keys():
            x, y = la[p], lb[p]
            numbers = isinstance(x, float) and isinstance(y, float)
            if numbers and math.isfinite(x) and math.isfinite(y):
                d = abs(x - y) / max(abs(x), abs(y), 1e-300) if x != y else 0.0
                worst, where = (d, p) if d > worst else (worst, where)
            elif x != y and not (x != x and y != y):   # (NaN equals NaN here)
                texts.append(p)
        tol = TOL["ocp" if cat == "ocp" else "sim"]
        passed = worst <= tol and not texts
        ok &= passed
        print(f"{cat:10s} {len(la):6d} leaves  largest relative difference {worst:.3g} "
              f"(tolerance {tol:g}) {where}  differing leaves {len(texts)}  "
              f"{'PASS' if passed else 'FAIL'}")
        for p in sorted(texts)[:10]:
            print(f"    {p}: {la.get(p)!r} -> {lb.get(p)!r}")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="record the numbers of this tree")
    rec.add_argument("out", type=Path)
    rec.add_argument("--random", type=int, default=200, help="random event-solver problems")
    rec.add_argument("--skip", nargs="*", default=[], choices=CATEGORIES)
    cmp_ = sub.add_parser("compare", help="compare two records")
    cmp_.add_argument("old", type=Path)
    cmp_.add_argument("new", type=Path)
    args = ap.parse_args(argv)
    if args.command == "compare":
        old, new = (json.loads(p.read_text()) for p in (args.old, args.new))
        return 0 if compare(old, new) else 1
    recorders = {"random": lambda: record_random(args.random), "demo": record_demo,
                 "reproduce": record_reproduce, "ocp": record_ocp}
    data = {cat: recorders[cat]() for cat in CATEGORIES if cat not in args.skip}
    args.out.write_text(json.dumps(data, allow_nan=True, indent=1))
    print(f"wrote {args.out}: {', '.join(data)}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    raise SystemExit(main())
