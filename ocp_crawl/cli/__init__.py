"""Command line ``ocp-crawl``: argument parsing and printing only; every command calls a library
function.

The command modules register their commands in :data:`~ocp_crawl.cli.app.COMMANDS` when imported
here.
"""
# the command modules register their commands when imported
from ocp_crawl.cli import (fit_commands, init_command, optimize_command, run_commands,  # noqa: F401
                           study_commands, warmup_command)
from ocp_crawl.cli import codesign_command, dynamics_command  # noqa: F401
from ocp_crawl.cli.app import COMMANDS, main

__all__ = ["COMMANDS", "main"]
