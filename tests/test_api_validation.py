"""The API refuses what the files and the command line refuse: one validation for both.

An unsorted or oversized ``t_eval``, a sampled signal of more knots than a period may hold, and
``resume`` (or ``force``) without the directory it would act on are ValueErrors naming the argument
and the rule, not silently sorted, computed or ignored.
"""
import numpy as np
import pytest

from ocp_crawl.model.sampled import MAX_KNOTS, PeriodicLinear, PeriodicPchip
from ocp_crawl.problem import paper_problem, run_problem
from ocp_crawl.sim.assemble import MAX_OUTPUT_PHASES
from ocp_crawl.studies.common import SweepOptions
from ocp_crawl.studies.reproduce import reproduce
from ocp_crawl.sweep import run_sweep


@pytest.mark.parametrize("drive", ["torque", "angles"])
def test_an_unsorted_t_eval_is_refused(drive):
    problem = paper_problem([f"gait.drive={drive}"])
    with pytest.raises(ValueError, match=r"t_eval must be sorted .* t_eval\[1\] = 0.5 "
                                         r"followed by t_eval\[2\] = 0.25"):
        run_problem(problem, t_eval=[0.0, 0.5, 0.25, 1.0])


def test_a_t_eval_beyond_the_bound_is_refused_before_any_work():
    bound = f"t_eval has {MAX_OUTPUT_PHASES + 1} phases, at most {MAX_OUTPUT_PHASES}"
    with pytest.raises(ValueError, match=bound):
        run_problem(paper_problem(), t_eval=np.linspace(0.0, 1.0, MAX_OUTPUT_PHASES + 1))


def test_the_largest_t_eval_is_computed():
    res = run_problem(paper_problem(), t_eval=np.linspace(0.0, 1.0, MAX_OUTPUT_PHASES))
    assert res.success and res.t.size == MAX_OUTPUT_PHASES


@pytest.mark.parametrize("cls", [PeriodicLinear, PeriodicPchip])
def test_a_signal_of_too_many_knots_is_refused(cls):
    t = np.arange(MAX_KNOTS + 1) / (MAX_KNOTS + 1)
    with pytest.raises(ValueError, match=f"t_knots must be a 1-D array of . to {MAX_KNOTS} phases"):
        cls(t, np.zeros((2, t.size)))
    cls(t[:MAX_KNOTS], np.zeros((2, MAX_KNOTS)))


@pytest.mark.parametrize("flag", ["resume", "force"])
def test_run_sweep_refuses_resume_or_force_without_out_dir(flag):
    with pytest.raises(ValueError, match=f"{flag}=True .* out_dir is None"):
        run_sweep(paper_problem(), {"gait.psi_deg": [45.0]}, **{flag: True})


def test_sweep_options_and_reproduce_refuse_resume_without_out_dir(tmp_path):
    with pytest.raises(ValueError, match="resume=True .* out_dir is None"):
        SweepOptions(resume=True)
    with pytest.raises(ValueError, match="resume=True .* out_dir is None"):
        reproduce(tmp_path, quick=True, sweep=SweepOptions(resume=True))
