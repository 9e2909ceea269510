"""Stress tests of the Newton iteration: clearances over three decades, first load steps
from a tenth of the approach to all of it, penalties from soft to stiff. Every run must
converge without cutting a step back, in a bounded number of iterations."""

import itertools

import numpy as np

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
    assert iterations[0] <= 12, iterations          # from first touch (measured 2-7)
    assert max(iterations[1:], default=0) <= 6, iterations  # later steps (measured 2-6)


@pytest.mark.parametrize("clearance, steps, penalty_factor", QUICK)
def test_newton_is_robust(clearance, steps, penalty_factor):
    converges_cleanly(clearance, steps, penalty_factor)


@pytest.mark.slow
@pytest.mark.parametrize("clearance, steps, penalty_factor",
                         sorted(set(itertools.product(CLEARANCES, STEPS, PENALTY_FACTORS)) - set(QUICK)))
def test_newton_is_robust_everywhere(clearance, steps, penalty_factor):
    converges_cleanly(clearance, steps, penalty_factor)


def test_overlap_shift_spans_the_arc():
    """A rigid pin moved by c + overlap_shift(phi) has its surface point at +-phi exactly on
    the bore circle (the edge of the overlap), and the small-clearance form c (1/cos phi - 1)."""
    from pinbore.fem.model import overlap_shift

    r_bore = 10e-3
    for clearance, phi in [(1e-5, 0.37), (5e-4, 0.05), (2e-3, 1.2)]:
        r_pin = r_bore - clearance
        centre = clearance + overlap_shift(phi, r_pin, clearance)
        point = np.array([centre + r_pin * np.cos(phi), r_pin * np.sin(phi)])
        assert np.hypot(*point) == pytest.approx(r_bore, rel=1e-13)
    assert overlap_shift(0.37, 10e-3 - 1e-6, 1e-6) == pytest.approx(1e-6 * (1 / np.cos(0.37) - 1),
                                                                    rel=1e-3)


class WholePush(dict):
    """A Solved hook that makes the first step's guess move the pin by the whole push."""

    def __setitem__(self, key, stepper):
        stepper.first_shift = None


@pytest.mark.parametrize("clearance", [1e-5, 5e-4])
def test_first_guess_changes_the_path_not_the_solution(clearance):
    """The first step's guess (fem.model.first_shift) spares Newton iterations and leaves the
    solution alone: the forces agree with the guess of the whole rigid push to Newton's
    tolerance (1e-9 E* d on the nodal forces; 1e-7 of the force is far above it)."""
    data = with_clearance(clearance, load={"steps": 2, "max_approach": 1e-5})
    guessed, whole = Solved(data), Solved(data, hook=WholePush())
    np.testing.assert_allclose(guessed.forces, whole.forces, rtol=1e-7)
    assert guessed.run.steps[0].newton_iterations < whole.run.steps[0].newton_iterations


def test_a_failed_factorisation_fails_the_linear_solve():
    """A Jacobian that MUMPS cannot factorise (a zero pivot) fails GMRES on the kept factors
    (their application returns NaN, and GMRES reads the preconditioner's failure), so Newton
    fails and the load step is cut back. Before, GMRES called a direction it never computed
    converged (CONVERGED_ATOL)."""
    import dolfinx_solver  # noqa: F401
    from mpi4py import MPI
    from petsc4py import PETSc

    from pinbore.fem.solver import KeptLU

    singular = PETSc.Mat().createAIJ([3, 3], nnz=1, comm=MPI.COMM_SELF)
    for i, value in enumerate([1.0, 0.0, 1.0]):
        singular.setValue(i, i, value)
    singular.assemble()
    lu = KeptLU(MPI.COMM_SELF)
    lu.factor(singular)
    ksp = PETSc.KSP().create(MPI.COMM_SELF)
    ksp.setType("gmres")
    ksp.setOperators(singular)
    ksp.getPC().setType("python")
    ksp.getPC().setPythonContext(lu)
    b = singular.createVecLeft()
    b.set(1.0)
    x = b.duplicate()
    ksp.solve(b, x)
    assert ksp.getConvergedReason() == PETSc.KSP.ConvergedReason.DIVERGED_PCSETUP_FAILED
