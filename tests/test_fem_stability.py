"""Stress tests of the Newton iteration: clearances over three decades, first load steps
from a tenth of the approach to all of it, penalties from soft to stiff. Every run must
converge without cutting a step back, in a bounded number of iterations."""

import itertools

import pytest
from conftest import Solved, with_clearance

CLEARANCES = [1e-6, 1e-5, 1e-4, 5e-4, 1e-3]
STEPS = [1, 3, 10]
PENALTY_FACTORS = [10.0, 100.0, 1000.0]
QUICK = [(1e-6, 1, 1000.0), (1e-6, 3, 10.0), (1e-4, 1, 10.0), (1e-4, 3, 1000.0),
         (1e-3, 1, 1000.0), (1e-3, 3, 10.0)]


def converges_cleanly(clearance, steps, penalty_factor):
    solved = Solved(with_clearance(clearance, load={"steps": steps, "max_approach": 1e-5},
                                   contact={"method": "penalty", "penalty_factor": penalty_factor}))
    iterations = [s.newton_iterations for s in solved.run.steps]
    assert solved.run.cutbacks == 0
    assert iterations[0] <= 12, iterations          # from first touch (measured 6-11)
    assert max(iterations[1:], default=0) <= 6, iterations  # later steps (measured 2-6)


@pytest.mark.parametrize("clearance, steps, penalty_factor", QUICK)
def test_newton_is_robust(clearance, steps, penalty_factor):
    converges_cleanly(clearance, steps, penalty_factor)


@pytest.mark.slow
@pytest.mark.parametrize("clearance, steps, penalty_factor",
                         sorted(set(itertools.product(CLEARANCES, STEPS, PENALTY_FACTORS)) - set(QUICK)))
def test_newton_is_robust_everywhere(clearance, steps, penalty_factor):
    converges_cleanly(clearance, steps, penalty_factor)
