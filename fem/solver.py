"""Load stepping: the hub crosses the clearance, pushes the pin into the bore, then
(optionally) turns it, pushes it sideways or (3D) tilts it with the approach held.

A load point is (approach (m), rotation (rad), tangential push (m), tilt (rad)); the hub sits
at (c + approach) d + push d_perp, turned by the rotation and tilted by the tilt
(fem.elasticity.rigid_motion).

Each load step solves  K u + f_c(u) = 0  (free dofs), u = prescribed (hub, clamped edge),
with PETSc SNES: Newton, full steps, the tangent J = K_bc + K_c (fem.contact says which terms
of K_c are kept). The linear solver is GMRES on J, preconditioned by the MUMPS LU factors of
an earlier J. K_bc never changes and K_c changes only at the pin nodes whose contact state
changed (in or out of contact, stick or slip): a change of low rank at each such node, which
costs GMRES iterations on the kept factors: about one per node without friction (measured
at 48k dofs: 19, 22 and 48 changed nodes took 19, 22 and 33 iterations), several per
stick-slip flip (19 flips took 80). So the factors are kept while the GMRES iterations spent
on them, with those the next solve is expected to take (the changed nodes times the
iterations per changed node of the solves so far, or the last solve's), stay within what a
factorisation costs in applications of the factors (KeptLU times both: about 30 at 17k-28k
dofs, 50 at 88k in 3D; never fewer than MIN_WORTH); then J is refactored (fresh factors
solve in one iteration). Spending on the kept factors what a factorisation would cost
before paying for one costs at most twice the best choice made knowing the iterations to
come.
Why not always refactor: in 3D the contact couplings double the factors of K_bc (1.3e8
entries at 88k dofs against 6.7e7), and a factorisation costs 20-30 triangular solves
(serial: 0.7 s against 0.02 s at 28k dofs, 5.3 s against 0.25 s at 88k). Measured on the 3D
push of bench/fem3d.py: the same Newton iterations and forces (to 1e-9); at 88k dofs 6 of 16
linear solves refactored, 62 s serial and 37 s on 2 ranks (116 s and 66 s when every
Jacobian was factorised); with friction at 28k dofs 14 of 23, 19.5 s (21 s). A
plastic tangent changes wherever points flow; the same rule keeps its factors (2D, 32k dofs,
a load-unload curve: 54 factorisations for 110 Newton iterations, the same time as one each).

The first step's guess moves the pin rigidly, but not by the whole push: by the travel at
which its overlap with the bore spans the contact arc estimated for that push
(fem.model.first_shift). The whole push overlaps an arc far wider than the contact's, and
Newton spent its first iterations releasing nodes (88k dofs: 8 iterations and 7
factorisations, now 4 and 3 with a factorisation kept for 8 changed nodes, 4 and 2 with
the factors kept by cost, above; the 2D shipped scenes 7-10 iterations, now 2-6).

The later steps' starting guess extrapolates the last two converged states by half a secant step: the contact arc grows sub-linearly with the approach, so a full secant
step over-predicts the arc and Newton spends its iterations releasing nodes. Measured on
10-step curves for clearances 1e-6 to 5e-4 m: 3 Newton iterations per step with half a
step, 5-7 with a full one.

augmented-lagrangian: after each Newton solve the multipliers take the converged pressure
(and shear) (Uzawa) until the largest penetration, and the largest motion of a stuck node,
is below `gap_tolerance`; they start each step from the extrapolation of the last two
steps, so one or two solves per step usually suffice. With friction (either method), a
solve whose kept active sets differ from those of its solution is followed by another
(fem.contact.PinBoreContact.start_solve). The predictor extrapolates
along the programme only while the step continues the previous one; at a change of
programme (push to rotation) it starts from the last state with only the hub moved: moving
the pin rigidly with the hub sent every stuck node past its bound and Newton cycled.

A step whose Newton (or Uzawa) iteration fails is retried from the last converged state
with half the increment, up to `max_cutbacks` times per load step (converged intermediate
steps are kept and count towards it). If it still fails the run stops,
keeps every converged step, and says where and why (`Stop`).
"""

import time
from dataclasses import dataclass, field

import dolfinx_solver  # noqa: F401  (loads PETSc's libraries; precedes petsc4py)
import numpy as np
import scipy.sparse
from mpi4py import MPI
from petsc4py import PETSc

from pinbore.fem import curve
from pinbore.fem.contact import ContactState, PinBoreContact
from pinbore.fem.elasticity import Elasticity
from pinbore.fem.scene import Reload, Unload

PREDICTOR_RATIO = 0.5
LINEAR_RTOL = 1e-8            # of each Newton step's linear solve (relative)
MIN_WORTH = 8                 # GMRES iterations a factorisation is always worth
REUSE_MAX_ITERATIONS = 80     # GMRES iterations on a kept factorisation before giving up
UNLOAD_FORCE_TOLERANCE = 1e-4   # of the force at the top: the unloading has reached zero force
UNLOAD_SEARCH_STEPS = 20        # steps of the search for zero force before it gives up
SNES_REASONS = {v: k for k, v in vars(PETSc.SNES.ConvergedReason).items() if not k.startswith("_")}


@dataclass
class StepResult:
    """One converged load step."""

    point: np.ndarray            # (approach (m), rotation (rad), tangential push (m), tilt (rad))
    force: np.ndarray            # N/m (3D: N), hub force on the pin along (d, d_perp)
    torque: float                # N m/m (3D: N m), friction torque about the pin's axis
    moment: float                # N m (3D), hub moment on the pin about the tilt axis (0 in 2D)
    dissipated: float            # J/m (3D: J), frictional work of this step
    newton_iterations: int       # summed over Uzawa updates
    uzawa_iterations: int
    factorizations: int          # LU factorisations of the Jacobian (the others reused one)
    gap_violation: float         # m, largest penetration
    reasons: list[str]
    contact: ContactState
    wall_time: float
    stage: str = ""              # of pinbore.fem.curve.STAGES
    plastic_work: float = 0.0    # J/m (3D: J), plastic work of this step
    max_plastic_strain: float = 0.0
    residual_approach: float = float("nan")  # m, last step of an unloading: zero force here

    @property
    def approach(self) -> float:
        return float(self.point[0])


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
                 method, gap_tolerance, newton_max_it, uzawa_max_it, max_cutbacks, force_atol,
                 couplings, material=None, first_shift=None):
        """material: the bodies' internal forces, tangent and state (internal_force,
        add_tangent, commit, snapshot, restore, max_plastic_strain): the Elasticity itself
        (constant stiffness, no state) unless given (fem.plasticity.ElastoPlastic).
        first_shift(d): how far (m) the first step's guess moves the pin rigidly for a push
        of the hub by d (module docstring; fem.model.first_shift); None: by d."""
        self.el, self.contact = elasticity, contact
        self.material = elasticity if material is None else material
        self.first_shift = first_shift
        self.clearance, self.direction = clearance, np.asarray(direction, dtype=float)
        self.across = np.zeros_like(self.direction)      # e_z x direction
        self.across[:2] = -self.direction[1], self.direction[0]
        self.method, self.gap_tolerance = method, gap_tolerance
        self.augmented = method == "augmented-lagrangian"
        self.uzawa_max_it = uzawa_max_it if self.augmented or contact.friction else 1
        self.max_cutbacks = max_cutbacks
        self.prescribed = elasticity.prescribed_rows()
        self.copies = 2 if elasticity.symmetric else 1  # a half model reports the whole pin
        self.x = elasticity.K.createVecRight()
        self.work = self.x.duplicate()
        self.snes = self._make_snes(newton_max_it, force_atol, couplings)
        if self.material.plastic and contact.friction is None:
            # A point at the edge of the plastic zone, beside a node entering contact, can
            # flip between the elastic and the plastic branch from one iterate to the next
            # and Newton cycles (measured: a two-cycle at 1.25e4 N/m on the first push step,
            # two cutbacks); a backtracking line search breaks the cycle.
            self.snes.getLineSearch().setType("bt")

    def _make_snes(self, max_it, force_atol, couplings):
        self.lu = KeptLU(self.el.mesh.comm)
        return newton_solver(self.el.mesh.comm, jacobian_matrix(self.el.K_bc, couplings),
                             self._residual, self._jacobian, self.x, max_it, force_atol,
                             kept=self.lu)

    def _residual(self, snes, x, F):
        self.material.internal_force(x, F)
        self.contact.add_residual(x, F)
        F.assemble()
        self.el.zero_prescribed(F)

    def _jacobian(self, snes, x, J, P):
        J.zeroEntries()
        self.material.add_tangent(x, J)
        kind = self.contact.add_tangent(x, J)
        J.assemble()
        J.zeroRows(self.prescribed, diag=1.0)  # contact terms on a plane of symmetry
        self.lu.refresh(J, snes.getKSP(), kind)

    @property
    def factorizations(self) -> int:
        return self.lu.factorizations

    def run(self, programme, progress=None, on_step=None) -> Run:
        """Solve for each load point of the programme in turn (see the module docstring; an
        Unload or Reload item stands for the steps it takes); cut back and retry on failure.
        on_step(x, step) is called after every converged step."""
        self._run, self._progress, self._on_step = Run(), progress, on_step
        touch = self.el.pin_rigid_motion(self.clearance * self.direction)  # exact: no force yet
        self.contact.commit(self.contact.state(touch))
        self._history = [(np.zeros(4), touch, self.contact.snapshot(), self.material.snapshot())]
        for item in programme:
            if isinstance(item, Unload):
                done = self._unload(item.steps)
            elif isinstance(item, Reload):
                start = self._history[-1][0]
                done = all(self._reach(np.append(a, start[1:]), curve.RELOAD, count=True)
                           for a in np.linspace(start[0], item.approach, item.steps + 1)[1:])
            else:
                point = np.asarray(item, dtype=float)
                done = self._reach(point, curve.stage(point), count=True)
            if not done:
                break
        return self._run

    def _reach(self, final, stage: str, accept=None, count=False):
        """Converge the load point `final`, halving the step on failure (the converged
        intermediate steps are kept); True, or False when it gave up (Run.stop says where
        and why), or the StepResult of a converged step that `accept` refused (the state
        stays at the last accepted step). count: a step of the progress bar."""
        target, cuts = final, 0
        while True:
            outcome = self._attempt(self._history, target)
            if isinstance(outcome, StepResult):
                outcome.stage = stage
                if accept is not None and not accept(outcome):
                    return outcome
                self._accept(outcome)
                if np.array_equal(target, final):
                    if count and self._progress is not None:
                        self._progress.update(1)
                    return True
                target = final
                continue
            cuts += 1
            self._run.cutbacks += 1
            if cuts > self.max_cutbacks:
                self._run.stop = Stop(float(target[0]), f"{outcome}; gave up after "
                                      f"{self.max_cutbacks} cutbacks at load point {describe(target)}")
                _, x, contact, material = self._history[-1]
                x.copy(self.x)  # leave the last converged state in x
                self.contact.restore(contact)
                self.material.restore(material)
                return False
            target = 0.5 * (self._history[-1][0] + target)

    def _accept(self, step: StepResult) -> None:
        """Commit a converged step: contact and material state, the run's list, history."""
        self.contact.commit(step.contact)
        step.plastic_work = self.copies * self.material.commit(self.x)
        step.max_plastic_strain = self.material.max_plastic_strain()
        self._run.steps.append(step)
        if self._on_step is not None:
            self._on_step(self.x, step)
        self._history = self._history[-1:] + [(step.point, self.x.copy(), self.contact.snapshot(),
                                               self.material.snapshot())]

    def _unload(self, steps: int) -> bool:
        """From the last step, move the hub back until the hub force returns to zero: `steps`
        - 1 steps planned for equal decrements of the force along the curve (the next approach
        from the secant of the last two unloading steps), then a search for the approach where
        the contact opens (secant steps on the curve, bisection when a step overshoots into
        free flight), until the force is below UNLOAD_FORCE_TOLERANCE of the force at the top.
        The last step's residual_approach is the curve's zero extrapolated along that secant.

        The unloading curve is convex (the contact narrows as the force falls), so a secant
        from above lands short of the zero: the search approaches it from the loaded side."""
        last = self._run.steps[-1] if self._run.steps else None
        if last is None or last.force[0] <= 0:
            self._run.stop = Stop(0.0, "unload: no force to unload from")
            return False
        top = last.force[0]
        tolerance = UNLOAD_FORCE_TOLERANCE * top
        # before the first unloading step: twice the loading secant (unloading is elastic, stiffer)
        before = self._run.steps[-2] if len(self._run.steps) > 1 else None
        slope = 2 * (top / last.approach if before is None or last.approach <= before.approach
                     else (top - before.force[0]) / (last.approach - before.approach))
        free = -self.clearance          # below it the pin is surely free (concentric at -c)
        in_contact = lambda step: bool(np.any(step.contact.pressure > 0))  # noqa: E731
        planned = 1
        for _ in range(steps - 1 + UNLOAD_SEARCH_STEPS):
            point, force = self._history[-1][0], self._run.steps[-1].force[0]
            if planned >= steps and force <= tolerance:
                break
            drop = force / max(steps - planned + 1, 1) if planned < steps else force
            target = point[0] - drop / slope
            if target <= free:   # the secant points into free flight: halve the distance
                target = 0.5 * (free + point[0])
            outcome = self._reach(np.append(target, point[1:]), curve.UNLOAD, accept=in_contact)
            if outcome is False:
                return False
            if isinstance(outcome, StepResult):   # the contact opened: the zero lies above
                free = target
                continue
            if planned < steps:
                planned += 1
                if self._progress is not None:
                    self._progress.update(1)
            done = self._run.steps[-1]
            slope = (force - done.force[0]) / (point[0] - done.approach)
        else:
            self._run.stop = Stop(float(self._history[-1][0][0]),
                                  f"unload: the force did not fall below {tolerance:.3g} within "
                                  f"{UNLOAD_SEARCH_STEPS} steps of the search for zero force")
            return False
        done = self._run.steps[-1]
        done.residual_approach = done.approach - done.force[0] / slope
        if self._progress is not None:
            self._progress.update(1)
        return True

    def _predict(self, history, target):
        """Half-secant extrapolation of displacements and multipliers while the step
        continues the previous one; at a change of programme the last state (the hub alone
        moves); at the first step the pin moved rigidly towards the bore (first_shift)."""
        point, x, snapshot, _ = history[-1]
        self.contact.restore(snapshot)
        step = target - point
        if len(history) > 1:
            point_0, x_0, snapshot_0, _ = history[-2]
            previous = point - point_0
            along = float(step @ previous) / float(previous @ previous)
            if np.allclose(step - along * previous, 0.0, atol=1e-12 * np.abs(step).max()):
                ratio = PREDICTOR_RATIO * float(step @ previous) / float(previous @ previous)
                self.contact.extrapolate(snapshot_0, ratio, self.augmented)
                return x + ratio * (x - x_0)
            return x.copy()  # a new programme: only the hub moves (the pin is held by friction)
        shift = step[0] if self.first_shift is None else self.first_shift(step[0])
        return x + self.el.pin_rigid_motion(shift * self.direction + step[2] * self.across,
                                            step[1], step[3])

    def _attempt(self, history, target) -> StepResult | str:
        """One load step; a StepResult, or the reason it failed."""
        start, factorizations = time.perf_counter(), self.factorizations
        self._predict(history, target).copy(self.x)
        self.el.set_boundary_values(self.x, self.hub_shift(target), target[1], target[3])
        solved = contact_solve(self.snes, self.x, self.contact, self.augmented,
                               self.uzawa_max_it, self.gap_tolerance)
        if isinstance(solved, str):
            return solved
        newton, uzawa, reasons, state, violation = solved
        self.material.internal_force(self.x, self.work)
        force, moment = self.el.hub_reaction(self.work)
        # a half model: twice its force; its moment about the mid-plane cancels the mirror half's
        force, moment = self.copies * force, (moment if self.copies == 1 else 0.0)
        torque = self.copies * self.contact.torque(self.x, self.hub_shift(target))
        return StepResult(target, np.array([force @ self.direction, force @ self.across]), torque,
                          moment,
                          self.copies * state.dissipated(self.contact.weights), newton, uzawa,
                          self.factorizations - factorizations, violation, reasons, state,
                          time.perf_counter() - start)

    def hub_shift(self, point) -> np.ndarray:
        return (self.clearance + point[0]) * self.direction + point[2] * self.across


def contact_solve(snes, x, contact, augmented: bool, uzawa_max_it: int, gap_tolerance: float):
    """Newton solves from x (updated in place) with the contact's Uzawa and friction updates
    between them, until the penetration (and stuck-node slip) is within gap_tolerance
    (augmented Lagrangian) and the friction's active sets settle. (newton iterations, uzawa
    updates, SNES reasons, contact state, largest penetration (m)), or why it failed.

    If that fails, it is solved once more from the same start with the contact's projection
    held on its patches (PinBoreContact.hold_patches: a pin node at a kink of the deformed
    bore can alternate between two patches and make Newton cycle, at any step size). A step
    solved so keeps them held until the next solve, so that what the stepper then reads of
    the contact (its state, forces) is that of the solution; solves that converge without
    are left exactly as they were."""
    contact.hold_patches(False)
    start, saved = x.copy(), contact.snapshot()
    try:
        solved = _contact_solve(snes, x, contact, augmented, uzawa_max_it, gap_tolerance)
        if not isinstance(solved, str):
            return solved
        start.copy(x)
        contact.restore(saved)
        contact.hold_patches(True)
        held = _contact_solve(snes, x, contact, augmented, uzawa_max_it, gap_tolerance)
        if not isinstance(held, str):
            return held
        contact.hold_patches(False)
        return solved
    finally:
        start.destroy()


def _contact_solve(snes, x, contact, augmented: bool, uzawa_max_it: int, gap_tolerance: float):
    newton, reasons = 0, []
    for uzawa in range(1, uzawa_max_it + 1):
        contact.start_solve()
        snes.solve(None, x)
        reason = snes.getConvergedReason()
        newton += snes.getIterationNumber()
        reasons.append(SNES_REASONS.get(reason, str(reason)))
        if reason < 0:
            return f"Newton failed ({reasons[-1]}) after {newton} iterations"
        state = contact.state(x)
        violation = float(np.max(-state.gap, initial=0.0))
        worst = max(violation, contact.stick_violation(state)) if augmented else 0.0
        if worst <= gap_tolerance and contact.friction_settled(state):
            return newton, uzawa, reasons, state, violation
        contact.update_friction(state)
        if augmented:
            contact.update_multipliers(state)
    return (f"augmented Lagrangian left a penetration (or stuck-node slip) of "
            f"{worst:.3g} m > gap_tolerance {gap_tolerance:.3g} m after {uzawa_max_it} updates")


def newton_solver(comm, J: PETSc.Mat, residual, jacobian, template: PETSc.Vec, max_it: int,
                  force_atol: float, kept: "KeptLU | None" = None) -> PETSc.SNES:
    """PETSc SNES: Newton with full steps, the callbacks residual(snes, x, F) and
    jacobian(snes, x, J, P) into J, converged at |F| <= force_atol (or rtol 1e-9). The
    linear solver: MUMPS LU of every J, or with `kept` GMRES preconditioned by its factors,
    which the jacobian callback refreshes (kept.factor) when they no longer serve."""
    snes = PETSc.SNES().create(comm)
    snes.setOptionsPrefix("pinbore_")
    snes.setType("newtonls")
    snes.getLineSearch().setType("basic")
    snes.setTolerances(atol=force_atol, rtol=1e-9, stol=1e-14, max_it=max_it)
    # Nodes entering contact under a stiff penalty can raise the residual a thousandfold
    # for an iteration; that is not divergence. max_it and the cutbacks catch real failure.
    snes.setDivergenceTolerance(PETSc.UNLIMITED)
    snes.setFunction(residual, template.duplicate())
    snes.setJacobian(jacobian, J)
    ksp = snes.getKSP()
    pc = ksp.getPC()
    if kept is None:
        ksp.setType("preonly")
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
    else:
        # Fresh factors converge in one GMRES iteration. A solve that reaches max_it is an
        # inexact Newton step (CONVERGED_ITS; the next iteration refactors); a failed
        # factorisation fails the Newton solve, and the step is cut back.
        ksp.setType("gmres")
        ksp.setTolerances(rtol=LINEAR_RTOL, atol=0.0, max_it=REUSE_MAX_ITERATIONS)
        ksp.setGMRESRestart(REUSE_MAX_ITERATIONS)
        PETSc.Options().setValue(f"{snes.getOptionsPrefix()}ksp_converged_maxits", True)
        pc.setType("python")
        pc.setPythonContext(kept)
    snes.setFromOptions()
    return snes


class KeptLU:
    """A PETSc preconditioner (type "python") that applies the MUMPS LU factors of a copy of
    the Jacobian taken when the stepper calls factor(J); PETSc's own set-up, called whenever
    the Jacobian changes, keeps them. A failed factorisation fails the linear solve (its
    application returns NaN and the failure, which GMRES reads). It times its last
    factorisation and its applications (worth_iterations)."""

    def __init__(self, comm):
        self.comm = comm
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix("pinbore_lu_")
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        self.ksp.setFromOptions()
        self.P = None
        self.factor_time, self.apply_time, self.applies = 0.0, 0.0, 0
        self.factorizations, self.factored = 0, None   # and the contact terms they factorised
        self.spent = 0      # GMRES iterations on the present factors
        self.changed = 0    # nodes whose terms differed from the factors' at the last solve
        self.changes = np.zeros(2)  # changed nodes, GMRES iterations: sums over kept solves

    def refresh(self, J: PETSc.Mat, ksp: PETSc.KSP, kind: np.ndarray, stale: bool = False) -> bool:
        """Called with each new Jacobian J (collective): keep the factors of an earlier one
        as GMRES's preconditioner while the GMRES iterations spent on them and expected of
        the next solve (per pin node whose contact terms, `kind` of
        PinBoreContact.add_tangent, differ from the factorised ones, as many as the kept
        solves took so far; or the last solve's) stay within a factorisation's worth; else
        factorise J (module docstring). A plastic tangent changes wherever points flow,
        which the last solve's iterations tell; `stale`: J changed everywhere (a time
        integrator's new step size), factorise. Whether it factorised."""
        changed = (np.inf if self.factored is None or stale
                   else np.count_nonzero(kind != self.factored))
        worth = max(self.worth_iterations(), MIN_WORTH)
        last = ksp.getIterationNumber()
        if self.factored is not None:
            self.spent += last
            if self.changed > 0:
                self.changes += (self.changed, last)
        rate = max(1.0, self.changes[1] / self.changes[0]) if self.changes[0] else 1.0
        expected = max(changed * rate, last)
        refactor = (self.spent + expected > worth
                    or ksp.getConvergedReason() < 0)   # e.g. the kept factors had failed
        refactor = self.comm.allreduce(refactor, op=MPI.LOR)
        if refactor:
            self.factor(J)
            self.factored, self.spent = kind, 0
            self.factorizations += 1
        self.changed = 0 if self.factored is kind else changed
        return refactor

    def worth_iterations(self) -> float:
        """Applications of the factors that cost as much as the last factorisation (0 before
        both were measured)."""
        return self.factor_time * self.applies / self.apply_time if self.applies else 0.0

    def factor(self, J: PETSc.Mat) -> None:
        start = time.perf_counter()
        if self.P is not None and self.P.getInfo()["nz_used"] == J.getInfo()["nz_used"]:
            J.copy(self.P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        else:   # the first, or J gained entries (its pattern only grows): factorise anew
            self.P = J.copy()
            self.ksp.setOperators(self.P)
        self.ksp.setUp()
        self.ksp.getPC().setUp()   # factorise now (else at the first application), timed
        self.factor_time = time.perf_counter() - start

    def setUp(self, pc):
        pass

    def apply(self, pc, x, y):
        failed = self.ksp.getPC().getFailedReason()
        if failed:   # no factors: NaN, and GMRES reads the failure; Newton fails, cut back
            pc.setFailedReason(failed)
            y.set(np.nan)
            return
        start = time.perf_counter()
        self.ksp.solve(x, y)
        self.apply_time += time.perf_counter() - start
        self.applies += 1


def jacobian_matrix(K: PETSc.Mat, couplings: np.ndarray) -> PETSc.Mat:
    """A copy of K whose pattern also holds the (row, column) pairs the contact terms may
    couple (PinBoreContact.couplings), as explicit zeros.

    Inserting the contact terms into K's exact pattern reallocated the matrix row by row at
    the first Jacobian (2-3 s, a third of a 3D solve on 30k dofs, growing with the size)."""
    start, end = K.getOwnershipRange()
    indptr, columns, values = K.getValuesCSR()
    mine = couplings[(couplings[:, 0] >= start) & (couplings[:, 0] < end)]
    rows = np.concatenate([np.repeat(np.arange(start, end), np.diff(indptr)), mine[:, 0]])
    cols = np.concatenate([columns, mine[:, 1]])
    pattern = scipy.sparse.coo_matrix((np.ones(rows.size), (rows - start, cols)),
                                      shape=(end - start, K.getSize()[1])).tocsr()
    local = (pattern.indices >= start) & (pattern.indices < end)
    row_of = np.repeat(np.arange(end - start), np.diff(pattern.indptr))
    nnz = [np.bincount(row_of[part], minlength=end - start).astype(PETSc.IntType)
           for part in (local, ~local)]
    J = PETSc.Mat().createAIJ(K.getSizes(), nnz=tuple(nnz), comm=K.getComm())
    J.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    J.setOption(PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True)   # through zeroRows
    zero = np.zeros(pattern.nnz)
    J.setValuesIJV(pattern.indptr.astype(PETSc.IntType), pattern.indices.astype(PETSc.IntType),
                   zero, addv=PETSc.InsertMode.ADD_VALUES,
                   rowmap=np.arange(start, end, dtype=PETSc.IntType))
    J.setValuesCSR(indptr, columns, values, addv=PETSc.InsertMode.ADD_VALUES)
    J.assemble()
    return J


def describe(point) -> str:
    return (f"approach {point[0]:.6g} m, rotation {np.degrees(point[1]):.6g} deg, "
            f"tangential push {point[2]:.6g} m, tilt {np.degrees(point[3]):.6g} deg")
