"""The command ``warmup``: every compiled function of the package built into the cache."""
from __future__ import annotations

import argparse
import json
import sys

from ocp_crawl.cli.app import EXIT_FAILURE, EXIT_OK, PROG, BadInput, err, register
from ocp_crawl.io.files import jsonable


def _warmup_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the list")


@register("warmup",
          "prebuild the compiled-library cache (e.g. before a sweep on a fresh cluster node)",
          _warmup_args)
def cmd_warmup(args: argparse.Namespace) -> int:
    from ocp_crawl.model.compiled import CacheError
    from ocp_crawl.sweep.warmup import warmup

    try:
        result = warmup()
    except CacheError as exc:  # OCP_CRAWL_CACHE names no usable directory
        raise BadInput(str(exc)) from None
    counts = {state: result.count(state) for state in ("built", "cached", "not compiled")}
    if args.json:
        print(json.dumps(jsonable({"cache": str(result.cache), "disabled": result.disabled,
                                   **counts, "seconds": round(result.seconds, 3),
                                   "functions": [vars(f) for f in result.functions]})))
    else:
        print(f"compiled-library cache {result.cache}")
        for f in result.functions:
            library = f.library.name if f.library else "-"
            print(f"  {f.state:<12} {f.function:<28} {library} ({f.seconds:.2f} s)")
        print(f"{len(result.functions)} compiled functions: {counts['built']} built, "
              f"{counts['cached']} already cached, {counts['not compiled']} not compiled "
              f"({result.seconds:.1f} s)")
    if result.disabled:
        print(f"{PROG}: OCP_CRAWL_NO_COMPILE is set: nothing compiled (CasADi evaluates the "
              "functions)", file=sys.stderr)
    elif not result.ok:
        # a full disk is not a missing compiler: result.failure says which, naming the file
        err(f"{result.failure}: the functions are evaluated by CasADi, which is slower")
        return EXIT_FAILURE
    return EXIT_OK
