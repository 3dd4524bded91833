"""Command line ``ocp-crawl``: argument parsing and printing only; every command calls a library function.

The command modules register their commands in :data:`~ocp_crawl.cli.app.COMMANDS` when imported here.
"""
from ocp_crawl.cli import fit_commands, init_command, run_commands, study_commands  # noqa: F401  (they register the commands)
from ocp_crawl.cli.app import COMMANDS, main

__all__ = ["COMMANDS", "main"]
