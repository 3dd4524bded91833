"""NLP layer (above ``model``, below ``sim``): IPOPT plumbing (the status table, building and calling a
solver, the option sets) and the one relaxation homotopy shared by the MPCC step and the gait OCP."""
from ocp_crawl.nlp.homotopy import Homotopy, Run, Solve, Stage, Start, schedule
from ocp_crawl.nlp.ipopt import (FAILURE_KINDS, IPOPT_RETURN_STATUS, IpoptCall, SolverOutcome, call_ipopt,
                                 check_ipopt_options, ipopt_solvers, ipopt_status, result_status)

__all__ = ["Homotopy", "Run", "Solve", "Stage", "Start", "schedule", "FAILURE_KINDS", "IPOPT_RETURN_STATUS",
           "IpoptCall", "SolverOutcome", "call_ipopt", "check_ipopt_options", "ipopt_solvers", "ipopt_status",
           "result_status"]
