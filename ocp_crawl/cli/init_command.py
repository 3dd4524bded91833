"""The command ``init``: write the shipped example problem files and scripts into DIR/problems/ and
DIR/examples/."""
from __future__ import annotations

import argparse
import json

from ocp_crawl.cli.app import EXIT_OK, BadInput, UsageError, io_message, register
from ocp_crawl.cli.common import force_arg
from ocp_crawl.problem.shipped import init_plan, shipped_problems, write_problems


def _directory(text: str) -> str:
    """argparse type of DIR: a non-empty path."""
    if not text.strip():
        raise UsageError(f"DIR {text!r} is invalid: an empty path; give a directory (default: the "
                         "current one)")
    return text


def _init_args(p: argparse.ArgumentParser) -> None:
    names = ", ".join(shipped_problems())
    p.description = (f"Write the example problem files shipped with the package ({names}) into "
                     "DIR/problems/ and the examples gallery (Python scripts) into DIR/examples/ "
                     "(default DIR: the current directory, giving ./problems/ and ./examples/), so "
                     "that the documentation's commands run as written, e.g. 'ocp-crawl simulate "
                     "problems/paper_gait.toml'. Existing files are never overwritten without "
                     "--force: the command refuses (exit 2, naming the file) before writing "
                     "anything. Each file is written atomically.")
    p.add_argument("dir", metavar="DIR", nargs="?", default=".", type=_directory,
                   help="directory that receives the problems/ and examples/ folders (default: the "
                        "current directory)")
    p.add_argument("--json", action="store_true",
                   help='print one JSON object {"directory": ..., "files": [...]} listing the '
                        'written files')
    force_arg(p, "files already in DIR/problems/ and DIR/examples/")


@register("init",
          "write the example problem files and scripts into DIR/problems/ and DIR/examples/ "
          "(default: ./)",
          _init_args)
def cmd_init(args: argparse.Namespace) -> int:
    try:
        init_plan(args.dir, force=args.force)  # every check, before any file is written
    except FileExistsError as exc:
        raise BadInput(f"{exc.filename}: exists; pass --force to overwrite it (nothing was "
                       "written)") from None
    except OSError as exc:
        raise BadInput(f"DIR {args.dir}: cannot write the example files: "
                       f"{io_message(exc)}") from None
    files = write_problems(args.dir, force=args.force)
    if args.json:
        print(json.dumps({"directory": str(args.dir), "files": [str(f) for f in files]}))
    else:
        print("wrote      " + ", ".join(str(f) for f in files))
        print(f"next       ocp-crawl simulate {files[0].parent / 'paper_gait.toml'}")
    return EXIT_OK
