"""Problem files: the schema (keys, units, rules), overrides, the validated Problem and running
it."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "PAPER_GAIT": "ocp_crawl.problem.run", "no_start_reason": "ocp_crawl.problem.run",
    "ocp_settings": "ocp_crawl.problem.run", "paper_problem": "ocp_crawl.problem.run",
    "optimize_problem": "ocp_crawl.problem.run",
    "codesign_problem": "ocp_crawl.problem.codesign",
    "run_problem": "ocp_crawl.problem.run",
    "SCHEMA": "ocp_crawl.problem.schema", "SECTIONS": "ocp_crawl.problem.schema",
    "TORQUE_SOLVERS": "ocp_crawl.problem.schema", "Key": "ocp_crawl.problem.keys",
    "ProblemError": "ocp_crawl.problem.keys", "format_value": "ocp_crawl.problem.messages",
    "schema_markdown": "ocp_crawl.problem.schema",
    "Problem": "ocp_crawl.problem.problem", "load_problem": "ocp_crawl.problem.problem",
    "problem_from_dict": "ocp_crawl.problem.problem",
    "apply_overrides": "ocp_crawl.problem.overrides",
    "parse_override": "ocp_crawl.problem.overrides",
    "read_toml": "ocp_crawl.problem.overrides", "set_values": "ocp_crawl.problem.overrides",
    "shipped_problem": "ocp_crawl.problem.shipped", "shipped_problems": "ocp_crawl.problem.shipped",
    "write_problems": "ocp_crawl.problem.shipped",
}

__all__ = [
    "PAPER_GAIT", "SCHEMA", "SECTIONS", "TORQUE_SOLVERS", "Key", "Problem", "ProblemError",
    "apply_overrides", "codesign_problem",
    "format_value", "load_problem", "no_start_reason", "ocp_settings", "optimize_problem",
    "paper_problem", "parse_override",
    "problem_from_dict", "read_toml", "run_problem", "schema_markdown", "set_values",
    "shipped_problem", "shipped_problems", "write_problems",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
