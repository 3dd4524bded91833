"""Problem files: the schema (keys, units, rules), overrides and the validated Problem."""
from ocp_crawl.problem.core import (SCHEMA, Problem, ProblemError, apply_overrides, load_problem, paper_problem,
                                    problem_from_dict, run_problem, schema_markdown)

__all__ = ["SCHEMA", "Problem", "ProblemError", "apply_overrides", "load_problem", "paper_problem",
           "problem_from_dict", "run_problem", "schema_markdown"]
