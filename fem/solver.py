"""Load stepping: the hub crosses the clearance, then pushes the pin into the bore.

Each load step solves  K u + f_c(u) = 0  (free dofs), u = prescribed (hub, clamped edge),
with PETSc SNES: Newton, full steps, the tangent K_bc + K_c (fem.contact says which terms of
K_c are kept), MUMPS LU. The starting guess extrapolates the last two converged states by
half a secant step: the contact arc grows sub-linearly with the approach, so a full secant
step over-predicts the arc and Newton spends its iterations releasing nodes. Measured on
10-step curves for clearances 1e-6 to 5e-4 m: 3 Newton iterations per step with half a
step, 5-7 with a full one.

augmented-lagrangian: after each Newton solve the multipliers take the converged pressure
(Uzawa) until the largest penetration is below `gap_tolerance`; they start each step from
the extrapolation of the last two steps, so one or two solves per step usually suffice.

A step whose Newton (or Uzawa) iteration fails is retried from the last converged state
with half the increment, up to `max_cutbacks` times per load step (converged intermediate
steps are kept and count towards it). If it still fails the run stops,
keeps every converged step, and says where and why (`Stop`).
"""

import time
from dataclasses import dataclass, field

import dolfinx_solver  # noqa: F401  (loads PETSc's libraries; precedes petsc4py)
import numpy as np
from petsc4py import PETSc

from fem.contact import ContactState, PinBoreContact
from fem.elasticity import Elasticity

PREDICTOR_RATIO = 0.5
SNES_REASONS = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if not k.startswith("_")}


@dataclass
class StepResult:
    """One converged load step."""

    approach: float              # m, hub displacement beyond first touch
    force: float                 # N/m, hub reaction along the load direction
    newton_iterations: int       # summed over Uzawa updates
    uzawa_iterations: int
    gap_violation: float         # m, largest penetration
    reasons: list[str]
    contact: ContactState
    wall_time: float


@dataclass
class Stop:
    """Why a run ended before its last step."""

    approach: float
    message: str


@dataclass
class Run:
    steps: list[StepResult] = field(default_factory=list)
    stop: Stop | None = None
    cutbacks: int = 0


class LoadStepper:
    def __init__(self, elasticity: Elasticity, contact: PinBoreContact, *, clearance, direction,
                 method, gap_tolerance, newton_max_it, uzawa_max_it, max_cutbacks, force_atol):
        self.el, self.contact = elasticity, contact
        self.clearance, self.direction = clearance, np.asarray(direction, dtype=float)
        self.method, self.gap_tolerance = method, gap_tolerance
        self.uzawa_max_it = uzawa_max_it if method == "augmented-lagrangian" else 1
        self.max_cutbacks = max_cutbacks
        self.x = elasticity.K.createVecRight()
        self.work = self.x.duplicate()
        self.snes = self._make_snes(newton_max_it, force_atol)

    def _make_snes(self, max_it, force_atol):
        comm = self.el.mesh.comm
        J = self.el.K_bc.duplicate(copy=True)
        J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        snes = PETSc.SNES().create(comm)
        snes.setOptionsPrefix("pinbore_")
        snes.setType("newtonls")
        snes.getLineSearch().setType("basic")
        snes.setTolerances(atol=force_atol, rtol=1e-9, stol=1e-14, max_it=max_it)
        # Nodes entering contact under a stiff penalty can raise the residual a thousandfold
        # for an iteration; that is not divergence. max_it and the cutbacks catch real failure.
        snes.setDivergenceTolerance(PETSc.UNLIMITED)
        snes.setFunction(self._residual, self.x.duplicate())
        snes.setJacobian(self._jacobian, J)
        ksp = snes.getKSP()
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        snes.setFromOptions()
        return snes

    def _residual(self, snes, x, F):
        self.el.internal_force(x, F)
        self.contact.add_residual(x, F)
        F.assemble()
        self.el.zero_prescribed(F)

    def _jacobian(self, snes, x, J, P):
        J.zeroEntries()
        J.axpy(1.0, self.el.K_bc, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self.contact.add_tangent(x, J)
        J.assemble()

    def run(self, approaches, progress=None, on_step=None) -> Run:
        """Solve for each approach in turn (m, increasing); cut back and retry on failure.

        on_step(x, pressure, approach) is called after every converged step.
        """
        approaches = [float(a) for a in approaches]
        run = Run()
        touch = self.el.pin_translation(self.clearance * self.direction)  # exact: no force yet
        history = [(0.0, touch, np.zeros_like(self.contact.lam))]
        target_index, target, cuts = 0, approaches[0], 0
        while target_index < len(approaches):
            outcome = self._attempt(history, target)
            if isinstance(outcome, StepResult):
                run.steps.append(outcome)
                if on_step is not None:
                    on_step(self.x, outcome.contact.pressure, target)
                history = history[-1:] + [(target, self.x.copy(), self.contact.lam.copy())]
                if target == approaches[target_index]:
                    target_index, cuts = target_index + 1, 0
                    if progress is not None:
                        progress.update(1)
                if target_index < len(approaches):
                    target = approaches[target_index]
                continue
            cuts += 1
            run.cutbacks += 1
            if cuts > self.max_cutbacks:
                run.stop = Stop(target, f"{outcome}; gave up after {self.max_cutbacks} cutbacks "
                                        f"at approach {target:.6g} m")
                history[-1][1].copy(self.x)  # leave the last converged state in x
                self.contact.lam = history[-1][2]
                break
            target = 0.5 * (history[-1][0] + target)
        return run

    def _predict(self, history, target):
        """Half-secant extrapolation of displacements and multipliers (see module docstring)."""
        approach, x, lam = history[-1]
        if len(history) == 1:
            guess = x + self.el.pin_translation(target * self.direction)
            return guess, lam.copy()
        approach_0, x_0, lam_0 = history[-2]
        ratio = PREDICTOR_RATIO * (target - approach) / (approach - approach_0)
        guess = x + ratio * (x - x_0)
        return guess, np.maximum(lam + ratio * (lam - lam_0), 0.0)

    def _attempt(self, history, target) -> StepResult | str:
        """One load step; a StepResult, or the reason it failed."""
        start = time.perf_counter()
        guess, self.contact.lam = self._predict(history, target)
        guess.copy(self.x)
        self.el.set_boundary_values(self.x, self.hub_at(target))
        newton, reasons = 0, []
        for uzawa in range(1, self.uzawa_max_it + 1):
            self.snes.solve(None, self.x)
            reason = self.snes.getConvergedReason()
            newton += self.snes.getIterationNumber()
            reasons.append(SNES_REASONS.get(reason, str(reason)))
            if reason < 0:
                return f"Newton failed ({reasons[-1]}) after {newton} iterations"
            state = self.contact.state(self.x)
            violation = float(np.max(-state.gap, initial=0.0))
            if self.method == "penalty" or violation <= self.gap_tolerance:
                break
            self.contact.lam = state.pressure
        else:
            return (f"augmented Lagrangian left a penetration of {violation:.3g} m "
                    f"> gap_tolerance {self.gap_tolerance:.3g} m after {self.uzawa_max_it} updates")
        force = float(self.el.hub_reaction(self.x, self.work) @ self.direction)
        return StepResult(target, force, newton, uzawa, violation, reasons, state,
                          time.perf_counter() - start)

    def hub_at(self, approach: float) -> np.ndarray:
        return (self.clearance + approach) * self.direction
