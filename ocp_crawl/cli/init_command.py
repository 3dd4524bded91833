"""The command ``init``: write the shipped example problem files into DIR/problems/."""
from __future__ import annotations

import argparse
import json

from ocp_crawl.cli.app import EXIT_OK, BadInput, UsageError, io_message, register
from ocp_crawl.cli.common import force_arg
from ocp_crawl.problem.shipped import INIT_SUBDIR, init_plan, shipped_problems, write_problems


def _directory(text: str) -> str:
    """argparse type of DIR: a non-empty path."""
    if not text.strip():
        raise UsageError(f"DIR {text!r} is invalid: an empty path; give a directory (default: the current one)")
    return text


def _init_args(p: argparse.ArgumentParser) -> None:
    names = ", ".join(shipped_problems())
    p.description = (f"Write the example problem files shipped with the package ({names}) into DIR/{INIT_SUBDIR}/ "
                     f"(default DIR: the current directory, giving ./{INIT_SUBDIR}/), so that the README's commands "
                     f"run as written, e.g. 'ocp-crawl simulate {INIT_SUBDIR}/paper_gait.toml'. Existing files are "
                     "never overwritten without --force: the command refuses (exit 2, naming the file) before "
                     "writing anything. Each file is written atomically.")
    p.add_argument("dir", metavar="DIR", nargs="?", default=".", type=_directory,
                   help=f"directory that receives the {INIT_SUBDIR}/ folder (default: the current directory)")
    p.add_argument("--json", action="store_true",
                   help='print one JSON object {"directory": ..., "files": [...]} listing the written files')
    force_arg(p, f"problem files already in DIR/{INIT_SUBDIR}/")


@register("init", f"write the example problem files into DIR/{INIT_SUBDIR}/ (default ./{INIT_SUBDIR}/)", _init_args)
def cmd_init(args: argparse.Namespace) -> int:
    try:
        init_plan(args.dir, force=args.force)  # every check, before any file is written
    except FileExistsError as exc:
        raise BadInput(f"{exc.filename}: exists; pass --force to overwrite it (nothing was written)") from None
    except OSError as exc:
        raise BadInput(f"DIR {args.dir}: cannot write the problem files: {io_message(exc)}") from None
    files = write_problems(args.dir, force=args.force)
    if args.json:
        print(json.dumps({"directory": str(args.dir), "files": [str(f) for f in files]}))
    else:
        print("wrote      " + ", ".join(str(f) for f in files))
        print(f"next       ocp-crawl simulate {files[0].parent / 'paper_gait.toml'}")
    return EXIT_OK
