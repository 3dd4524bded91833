"""Problem files: the schema (keys, units, rules), overrides, the validated Problem and running it."""
from ocp_crawl.problem.overrides import apply_overrides, parse_override, read_toml, set_values
from ocp_crawl.problem.problem import Problem, load_problem, problem_from_dict
from ocp_crawl.problem.run import PAPER_GAIT, no_start_reason, ocp_settings, paper_problem, run_problem
from ocp_crawl.problem.schema import (SCHEMA, SECTIONS, TORQUE_SOLVERS, Key, ProblemError, format_value,
                                     schema_markdown)
from ocp_crawl.problem.shipped import shipped_problem, shipped_problems, write_problems

__all__ = ["PAPER_GAIT", "SCHEMA", "SECTIONS", "TORQUE_SOLVERS", "Key", "Problem", "ProblemError", "apply_overrides",
           "format_value", "load_problem", "no_start_reason", "ocp_settings", "paper_problem", "parse_override",
           "problem_from_dict", "read_toml", "run_problem", "schema_markdown", "set_values"]
__all__ += ["shipped_problem", "shipped_problems", "write_problems"]
