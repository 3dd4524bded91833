"""NLP layer (above ``model``, below ``sim``): IPOPT plumbing (the status table, building and
calling a solver, the option sets), the process's heap and BLAS threads around a solve
(``process.py``), the one relaxation homotopy shared by the MPCC step and the gait OCP, and the
compiled evaluation of an NLP's per-step kernel (``codegen.py``)."""
from ocp_crawl.io.lazy import lazy_exports

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "KernelBuild": "ocp_crawl.nlp.codegen", "compiled_kernel": "ocp_crawl.nlp.codegen",
    "kernel_library": "ocp_crawl.nlp.codegen",
    "Homotopy": "ocp_crawl.nlp.homotopy", "Run": "ocp_crawl.nlp.homotopy",
    "Solve": "ocp_crawl.nlp.homotopy",
    "Stage": "ocp_crawl.nlp.homotopy", "Start": "ocp_crawl.nlp.homotopy",
    "schedule": "ocp_crawl.nlp.homotopy",
    "FAILURE_KINDS": "ocp_crawl.nlp.ipopt", "IPOPT_RETURN_STATUS": "ocp_crawl.nlp.ipopt",
    "IpoptCall": "ocp_crawl.nlp.ipopt", "Solvers": "ocp_crawl.nlp.ipopt",
    "SolverOutcome": "ocp_crawl.nlp.ipopt", "call_ipopt": "ocp_crawl.nlp.ipopt",
    "check_ipopt_options": "ocp_crawl.nlp.ipopt", "ipopt_solvers": "ocp_crawl.nlp.ipopt",
    "ipopt_status": "ocp_crawl.nlp.ipopt", "result_status": "ocp_crawl.nlp.ipopt",
}

__all__ = [
    "KernelBuild", "compiled_kernel", "kernel_library", "Homotopy", "Run", "Solve", "Stage",
    "Start", "schedule", "FAILURE_KINDS", "IPOPT_RETURN_STATUS", "IpoptCall",
    "Solvers", "SolverOutcome", "call_ipopt", "check_ipopt_options", "ipopt_solvers",
    "ipopt_status", "result_status",
]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
