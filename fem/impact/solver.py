r"""Dynamic impact of the pin in its bore: implicit time integration with the contact terms
of fem.contact.

Equations of motion (plane strain, per unit length)
---------------------------------------------------
The pin (an elastic annulus around a rigid hub) and the housing (an elastic annulus clamped at
its outer edge) carry the consistent mass matrix of P1 elements,

    m(u, v) = int_Omega rho u . v dx,        rho = rho_pin on the pin, rho_bore on the housing,

next to the stiffness a(u, v) of fem.elasticity. The hub is the pin's rigid core: its nodes
move with one translation U. With T the map from the reduced unknowns q (every dof, the hub's
nodes replaced by one master node that carries U; the other hub dofs unused, held at 0) to
the displacements u = T q,

    M_q = T^T M T + m_hub I_U,    K_q = T^T K T,    m_hub = rho_pin pi r_hub^2 + hub_mass,

and the equations of motion are M_q q'' + T^T f_int(T q) + f_c(T q) = 0 (the contact forces
f_c act on the surfaces only, where T is the identity). The housing's outer edge is clamped.

Mass redistribution (default; impact.surface_mass = "redistributed")
-------------------------------------------------------------------
The nodes of the two contact surfaces carry no mass: the cells that touch them lump their
mass rho A onto their other vertices in equal shares (total mass and momentum exact; the
centre of mass of such a cell moves by less than its size). This is the idea of Khenous,
Laborde & Renard [KhenousLabordeRenard2008]: a massless contact node is in equilibrium at
the end of every step, so it does not ring between the penalty and its own mass (with the
consistent mass, a surface node of 6e-5 kg/m on a penalty spring of 1e13 N/m^2 has a period
of 15 ns, a tenth of the step; measured on the steel pin at 1 m/s: the force history's
step-to-step jitter halves, 53 % -> 27 % of the peak, and e moves by 3e-4).

Generalized-alpha (Chung & Hulbert 1993 [ChungHulbert1993])
-----------------------------------------------------------
The WBZ (Bossak) member of the family [WoodBossakZienkiewicz1980], whose internal and contact
forces are taken at the end of the step (alpha_f = 0: a massless node is in equilibrium at
t_{n+1}, not on average over the step), with the parameters of Chung & Hulbert for the
spectral radius rho_inf at infinite frequency:

    alpha_m = (rho_inf - 1) / (rho_inf + 1),  gamma = 1/2 - alpha_m,  beta = (1 - alpha_m)^2 / 4,

    M_q a_{n+1-alpha_m} + F(q_{n+1}) = 0,      a_{n+1-alpha_m} = (1 - alpha_m) a_{n+1} + alpha_m a_n,
    q_{n+1} = q_n + dt v_n + dt^2 ((1/2 - beta) a_n + beta a_{n+1}),
    v_{n+1} = v_n + dt ((1 - gamma) a_n + gamma a_{n+1}),

F = T^T (f_int + f_c). Second order, unconditionally stable for the linear part; rho_inf = 1
(the default) is Newmark's trapezoidal rule (beta = 1/4, gamma = 1/2), rho_inf < 1 damps the
frequencies near 1/dt. Newton on q_{n+1} (PETSc SNES, MUMPS) with the Jacobian
J = (1 - alpha_m)/(beta dt^2) M_q + K_q + K_c, its linear solves GMRES on the MUMPS factors
of an earlier J, kept by the load stepper's rule (fem.solver.KeptLU.refresh: while the GMRES
iterations spent on them stay within a factorisation's worth) and taken afresh at a new
step size (the mass term changes everywhere). Measured on the study's steel pin at 1 m/s:
153 factorisations for 322 Jacobians, 9.0 s against 10.3 s with a factorisation each (a
triangular solve costs 2-3.5 ms, a factorisation of the 13.9k dofs 20 ms, and GMRES takes
about three solves to its 1e-8).

The predictor
-------------
Newton starts each step from the secant through the last two converged states,
q_{n+1} = q_n + h (q_n - q_{n-1}) / h_{n-1} (exact in free flight; the flight before t = 0 gives
the first step its q_{-1}). The Taylor guess q_n + h v_n + h^2 a_n / 2 reads the scheme's
velocity and acceleration, which at rho_inf = 1 are not damped at the highest frequencies
and at the massless surface nodes (no inertia: v and a follow from q alone and alternate from
step to step); that guess put the surface nodes off their contact, the first Newton step
changed the set of nodes in contact, and Newton took 3-5 iterations a step in contact.
Measured on the study's steel pin at 1 m/s (c = 10 um): 518 -> 267 Newton iterations over
131 steps (median 4 -> 2 a step), 19.5 -> 10.3 s, e the same to 3e-5; into the elasto-plastic
6061-O bore (c = 0.5 mm) at 1 m/s 885 -> 209 (median 9 -> 2), at 5 m/s 2243 -> 436 (median
16 -> 4, and none of the 17 cutbacks: the nodes no longer leave and enter the contact between
iterates), 239 -> 51 s. The quadratic through
the last three states took 308 (its extrapolation amplifies that alternation), the secant at
the surface nodes with the Taylor guess elsewhere 272.

Energy book
-----------
At rho_inf = 1 the scheme conserves energy exactly up to the contact: with beta = 1/4,
gamma = 1/2, q_{n+1} - q_n = dt (v_n + v_{n+1}) / 2, so the kinetic energy changes by
(q_{n+1} - q_n) . M_q (a_n + a_{n+1}) / 2 = -(q_{n+1} - q_n) . (F_n + F_{n+1}) / 2, and

    E_0 = K + U + W_p + W_c + D_num,

K = v . M_q v / 2 the kinetic energy, U the stored elastic energy (u . K u / 2 for linear
elasticity; int sigma : C^-1 : sigma / 2 dx for an elasto-plastic body, fem.plasticity),
W_p the plastic work (0 for an elastic body), W_c the work the
bodies did on the contact, summed by the same trapezoidal rule, (u_{n+1} - u_n) .
(f_c,n + f_c,n+1) / 2, and D_num the scheme's dissipation (0 at rho_inf = 1 up to Newton's
tolerance). The penalty contact stores Pi_c = sum_i w_i eps <-g_i>^2 / 2 (the augmented
Lagrangian, which holds the penetration below its gap tolerance, next to nothing): W_c -
Pi_c is the energy the contact's time integration lost or made. The book's residual is
E_0 - K - U - W_p - Pi_c, the whole error of the impact. The book holds for plastic bodies
too because both sides use the trapezoidal rule: the internal work of a step,
(u_{n+1} - u_n) . (f_int,n + f_int,n+1) / 2, is exactly the change of U plus the plastic
work of the step as fem.plasticity integrates it (one quadrature point per P1 cell, C^-1
linear). After separation the pin flies off with the momentum p of its mass m, so

    e = -p . d / (m v_0),    E_wave = K + U - |p|^2 / (2 m),

the energy left in the two bodies as vibration, waves and (plastic bodies) locked residual
stress; e^2 = 1 - (E_wave + W_p + residual)/E_0.

With friction (contact.friction > 0) the contact also dissipates W_f, the sum over the
steps of the return map's sum w sigma . slip (fem.contact), and Pi_c holds the stick springs'
sum w |sigma|^2 / (2 eps_T) too; the book's residual is then E_0 - K - U - W_p - Pi_c - W_f.

Energy control of the step
--------------------------
Where does W_c - Pi_c come from? Not from steps in steady contact: there the penalty force
is linear in the gap and the trapezoidal rule is exact but for the curvature of the bore
(measured below 1e-9 E_0 per step). It comes from the steps in which nodes enter (or leave)
the contact: a node that touches at t_n + theta h carries at t_{n+1} a force f that the
trapezoidal rule lets act over the whole step, so the contact does f g_n / 2 of work that no
spring stores (g_n, the node's gap at t_n, is of order v h). Summed over the steps of the
loading, that is (the force newly carried) x v h / 2: first order in h, independent of the
mesh, and concentrated at the start of the contact, where the conformal arc opens faster than
the waves run. Measured on the steel pin (c = 10 um) at 1 m/s, 100 steps over the contact,
on the tests' coarse mesh (contact_size 0.2 mm):
3.3e-3 E_0 in all, 1.6e-3 of it in the first step in contact (19 nodes enter), 3.4e-3 in the
first seven steps, -1.2e-4 in the steps where nodes leave; 1.7e-3 at 200 steps, 8e-4 at 400.
The integration lost this energy (K + U + W_c closes to 1e-8): it would have gone into the
bodies' vibration.

So the step is chosen by what it loses, as an error-controlled integrator chooses it by its
local error: a step whose |dW_c - dW_f - dPi_c| exceeds step_loss = energy_tolerance E_0 /
steps_per_contact (the estimated contact divided into dt's) is undone and repeated with
0.9 h / sqrt(ratio) (the loss of one step grows as h^2: both f and g_n are of order h), and
after a step the next grows by the same rule, up to 2 h and dt (and never below dt / 64).
Equal loss per step is the cheapest allocation: with a loss rate r(t) h per unit time,
the number of steps int dt / h at a given total loss int r h dt is least for h ~ r^(-1/2),
i.e. r h^2, the loss of one step, the same for every step. Steps that lose nothing stay
at dt. Measured on the same impact at energy_tolerance 1e-3: the book's residual 3.3e-3 -> 5.6e-5 of E_0 (largest over the run
1.8e-4), 127 steps instead of 95 (21 repeated, the shortest dt / 16), e moves by 1e-4.
adaptive_steps = false keeps every step at dt.

The bodies' material is the shared interface of fem.elasticity.Elasticity and
fem.plasticity.ElastoPlastic (internal_force, tangent, elastic_energy, commit(x) -> plastic
work, snapshot / restore). An elastic material's tangent is constant, so A below is built
once per time step size; an elasto-plastic one's is rebuilt at every Newton iterate once a
point flows (before that it is the elastic K: below the yield stress the impact is the
elastic one to the last bit).

Steps and failures
------------------
With an elasto-plastic body, a Newton iterate far from the solution (nodes entering contact
under the stiff penalty) can reach the yield stress where the converged state does not, and
the soft plastic tangent sends the next iterate further (measured: a perfectly plastic bore
at Y = 175 MPa, never reached by a converged step, failed its first steps in contact with
full Newton steps), or full steps cycle between two iterates, a node or point flipping
state at each (measured: a 12 t/m link at 14 mm/s, past first yield, the residual
alternating 2.3e4 / 2.9e6 N/m for 25 iterations). Such a step is solved again with the l2
line search (the step length that minimises |F|^2 along the Newton direction, from a secant
of its slope: it breaks the cycle, and the slow impact converges at the default settings),
then with a backtracking one (as the quasi-static stepper does, fem.solver; on the slow
impact it crept and failed), before it is cut. Until a point has yielded, a step that full
Newton steps solve is left alone, so a plastic body that never yields is the elastic one to
the last bit; once full steps have failed a step, the later steps start with the l2 search
(measured on the 1 m/s impact into the 6061-O bore: before first flow, full steps failed 19
steps in a row, 50 iterations each with the retry on held patches; leaving them out took
the impact from 2078 to 1173 Newton iterations, 72 to 42 s, e the same to 1e-10). Once a
point has yielded, full steps are no longer tried (with the secant predictor, below, they
would solve as many steps: 445 against 447 Newton iterations on the 5 m/s impact into the
6061-O bore, the same time).
A step whose Newton (or Uzawa) iteration fails is halved, up to solver.max_cutbacks times in
a row (the next steps grow back towards dt); if that fails too, the run stops, keeps every
converged step and says where and why (an incomplete run).
"""

import time
from dataclasses import dataclass, field

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import dolfinx
import dolfinx.fem.petsc
import numpy as np
import scipy.sparse
import ufl
from petsc4py import PETSc

from pinbore.fem.elasticity import Elasticity, piecewise
from pinbore.fem.post import angle_from, half_angle
from pinbore.fem.solver import KeptLU, contact_solve, jacobian_matrix, newton_solver
from pinbore.meshes.model import HOUSING, PIN


def generalized_alpha(rho_inf: float) -> tuple[float, float, float]:
    """(alpha_m, gamma, beta) of the generalized-alpha family in its WBZ (Bossak)
    member, alpha_f = 0 [WoodBossakZienkiewicz1980], with the parameters of Chung & Hulbert
    1993 for the spectral radius rho_inf in [0, 1] [ChungHulbert1993]:
    alpha_m = (rho_inf - 1)/(rho_inf + 1), gamma = 1/2 - alpha_m, beta = (1 - alpha_m)^2 / 4."""
    alpha_m = (rho_inf - 1) / (rho_inf + 1)
    return alpha_m, 0.5 - alpha_m, 0.25 * (1 - alpha_m) ** 2


def mass_matrix(elasticity: Elasticity, cell_tags, rho_pin: float, rho_bore: float,
                massless: np.ndarray | None = None) -> PETSc.Mat:
    """Mass matrix of m(u, v) = int rho u . v dx (kg/m per dof pair): consistent, or with
    the nodes `massless` (block indices) carrying no mass: the cells that touch them lump
    their mass rho A onto their other vertices, in equal shares (total mass and momentum
    exact; see the module docstring, mass redistribution)."""
    V, mesh = elasticity.V, elasticity.mesh
    cells = V.dofmap.list
    rho_cell = np.zeros(len(cells))
    rho_cell[cell_tags.find(PIN)], rho_cell[cell_tags.find(HOUSING)] = rho_pin, rho_bore
    touching = (np.zeros(len(cells), bool) if massless is None
                else np.isin(cells, massless).any(axis=1))
    Q = dolfinx.fem.functionspace(mesh, ("DG", 0))
    rho = dolfinx.fem.Function(Q)
    rho.x.array[:] = np.where(touching, 0.0, rho_cell)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    M = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(rho * ufl.inner(u, v) * ufl.dx))
    M.assemble()
    if touching.any():
        X = V.tabulate_dof_coordinates()[:, :2]
        corners = X[cells[touching]]                                      # (n, 3, 2)
        edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
        mass = rho_cell[touching] * 0.5 * np.abs(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])
        takers = ~np.isin(cells[touching], massless)
        takers[~takers.any(axis=1)] = True   # a cell with every vertex massless keeps them
        share = (mass / takers.sum(axis=1))[:, None] * takers
        nodal = np.bincount(cells[touching].ravel(), share.ravel(), minlength=X.shape[0])
        diagonal = M.createVecRight()
        diagonal.setArray(np.repeat(nodal, elasticity.dim))
        M.setDiagonal(diagonal, addv=PETSc.InsertMode.ADD_VALUES)
        M.assemble()
    return M


def rigid_hub_map(elasticity: Elasticity) -> tuple[PETSc.Mat, np.ndarray, np.ndarray]:
    """T (u = T q): the identity, but every hub node's dofs taken from one master node's;
    the master's rows and the other hub rows (serial numbering)."""
    dim = elasticity.dim
    n = elasticity.K.getSize()[0]
    hub = np.sort(elasticity.dofs["hub"])
    master, slaves = hub[0], hub[1:]
    columns = np.arange(n)
    slave_rows = (slaves[:, None] * dim + np.arange(dim)).ravel()
    columns[slave_rows] = (master * dim + np.tile(np.arange(dim), slaves.size))
    csr = scipy.sparse.csr_matrix((np.ones(n), (np.arange(n), columns)), shape=(n, n))
    T = PETSc.Mat().createAIJ(size=(n, n), csr=(csr.indptr.astype(PETSc.IntType),
                                                 csr.indices.astype(PETSc.IntType), csr.data),
                              comm=PETSc.COMM_SELF)
    T.assemble()
    return (T, (master * dim + np.arange(dim)).astype(PETSc.IntType),
            slave_rows.astype(PETSc.IntType))


@dataclass
class Record:
    """One time point of the impact (forces and energies per unit length)."""

    time: float                 # s
    approach: float             # m, hub travel along d beyond first touch (< 0 before)
    force: float                # N/m, contact resultant on the bore along d
    hub_velocity: float         # m/s, along d
    pin_velocity: float         # m/s, the pin's momentum along d over its mass
    half_angle: float           # rad
    min_gap: float              # m, smallest gap over the pin's nodes (< 0: penetration)
    kinetic: float              # J/m
    strain: float               # J/m, stored elastic energy
    plastic_work: float         # J/m, dissipated by plastic flow so far
    max_plastic_strain: float   # the largest equivalent plastic strain
    contact_energy: float       # J/m, stored by the penalty (Pi_c)
    contact_work: float         # J/m, done on the contact so far (W_c)
    friction_work: float        # J/m, dissipated by friction so far (W_f)
    newton_iterations: int
    time_step: float            # s


@dataclass
class ImpactRun:
    records: list[Record] = field(default_factory=list)
    stop: str | None = None      # why the run ended early (None: it ended as planned)
    cutbacks: int = 0            # steps halved because they failed
    energy_rejections: int = 0   # steps repeated smaller because the contact lost too much
    momentum: np.ndarray | None = None   # kg m/s per m, the pin's momentum at the end
    steps_in_contact: int = 0
    factorizations: int = 0      # LU factorisations of the Jacobian (the others kept ones)
    wall_time: float = 0.0


class ImpactStepper:
    """The pin (mass m, speed v0 along d) flies across `initial_gap` into the bore and
    rebounds; generalized-alpha with Newton per step (see the module docstring)."""

    def __init__(self, elasticity: Elasticity, contact, cell_tags, *, rho_pin, rho_bore,
                 hub_radius, hub_mass, clearance, direction, speed, dt, rho_inf, initial_gap, t_end,
                 method, gap_tolerance, newton_max_it, uzawa_max_it, max_cutbacks, force_atol,
                 couplings, massless_surfaces=True, material=None, step_loss=None,
                 min_step=None):
        self.el, self.contact = elasticity, contact
        self.material = elasticity if material is None else material
        self.direction = np.asarray(direction, dtype=float)
        self.clearance, self.speed, self.dt, self.t_end = clearance, speed, dt, t_end
        self.initial_gap = initial_gap
        self.augmented = method == "augmented-lagrangian"
        self.gap_tolerance = gap_tolerance
        self.uzawa_max_it = uzawa_max_it if self.augmented or contact.friction else 1
        self.max_cutbacks = max_cutbacks
        self.min_step = dt / 64 if min_step is None else min_step
        self.alpha_m, self.gamma, self.beta = generalized_alpha(rho_inf)

        self.T, self.master, slaves = rigid_hub_map(elasticity)
        self.hub_mass = rho_pin * np.pi * hub_radius**2 + hub_mass
        surface = np.concatenate([elasticity.dofs["pin_surface"], elasticity.dofs["bore_surface"]])
        M = mass_matrix(elasticity, cell_tags, rho_pin, rho_bore,
                        surface if massless_surfaces else None)
        self.M = M.PtAP(self.T)
        self.M.setValues(self.master, self.master, self.hub_mass * np.eye(len(self.master)),
                         addv=PETSc.InsertMode.ADD_VALUES)
        self.M.assemble()
        self.K = elasticity.K.PtAP(self.T)    # the elastic stiffness, reduced once
        rows = np.setdiff1d(elasticity.prescribed_rows(), self.master)
        self.prescribed = rows.astype(PETSc.IntType)

        vec = elasticity.K.createVecRight
        self.q, self.v, self.a = vec(), vec(), vec()            # state at t_n (reduced)
        self.q0, self.v0, self.a0 = vec(), vec(), vec()
        self.q_last, self.q_last0 = vec(), vec()   # q_{n-1} (the predictor's secant), saved
        self.h_last = self.h_last0 = dt            # the step from t_{n-1} to t_n
        self.x, self.u, self.f, self.work = vec(), vec(), vec(), vec()
        self.u.set(0.0)
        self.fc, self.fc0, self.u0, self.inertia = vec(), vec(), vec(), vec()
        # d on every pin node: u-space (the contact resultant) and q-space (the momentum)
        self.along_pin = elasticity.pin_rigid_motion(self.direction)
        self.along_pin_q = self.along_pin.copy()
        self.along_pin_q.setValues(slaves, np.zeros(len(slaves)))
        self.along_pin_q.assemble()
        self.M.mult(self.along_pin_q, self.work)
        self.mass = self.work.dot(self.along_pin_q)   # the FE pin's mass (kg/m)
        self.impact_energy = 0.5 * self.mass * speed**2  # E_0 (J/m)
        # energy control (module docstring): the largest loss of the contact's integration
        # over one step (J/m; step_loss is its fraction of E_0; None: fixed steps)
        self.step_loss = None if step_loss is None else step_loss * self.impact_energy
        self.mask = self._q_mask()
        self.A, self.A_dt, self.A_elastic = None, None, True
        self._A_version, self._A_in_J, self._displaced = 0, -1, None
        self.cM, self.Kt_q = None, None
        # the unused hub rows are empty after the reduction: their diagonal is kept for the
        # identity rows of the prescribed dofs
        unused = np.stack([slaves, slaves], axis=1)
        self.J = jacobian_matrix(self._effective(dt), np.concatenate([couplings, unused]))
        self.A_J = self.J.duplicate()
        self.lu = KeptLU(elasticity.mesh.comm)
        self.factored_h = None   # the step size of the kept factors
        self.snes = newton_solver(elasticity.mesh.comm, self.J, self._residual, self._jacobian,
                                  self.x, newton_max_it, force_atol, kept=self.lu)
        self.h = dt   # the step being solved
        self.full_steps_failed = False   # a plastic body's full Newton steps failed a step

    # --- the step's algebra ---------------------------------------------------------------

    def _effective(self, dt) -> PETSc.Mat:
        """A = (1 - alpha_m)/(beta dt^2) M_q + K_q, the Jacobian without the
        contact: with the elastic stiffness (cached for the last dt) while the material's
        tangent is K, else with T^T K_t(u) T at the current u. The scaled mass (with the
        pattern of M_q + K_q) is kept for the last dt, the reduced tangent's matrix reused:
        a plastic step rebuilds A at every Newton iterate (copying and adding with new
        patterns each time cost an eighth of a plastic impact)."""
        tangent = self.material.tangent(self.u)
        elastic = tangent is self.el.K
        if self.A_dt != dt or not (elastic and self.A_elastic):
            same = PETSc.Mat.Structure.SAME_NONZERO_PATTERN
            if self.A_dt != dt:
                if self.cM is None:   # the pattern of M_q + K_q, once
                    self.cM = self.M.copy()
                    self.cM.axpy(0.0, self.K, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
                self.cM.zeroEntries()
                self.cM.axpy((1 - self.alpha_m) / (self.beta * dt**2), self.M,
                             structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            if self.A is None:
                self.A = self.cM.copy()
            else:
                self.cM.copy(self.A, structure=same)
            if elastic:
                K = self.K
            else:
                K = self.Kt_q = tangent.PtAP(self.T, result=self.Kt_q)
            self.A.axpy(1.0, K, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            self.A_dt, self.A_elastic = dt, elastic
            self._A_version += 1
        return self.A

    def _acceleration(self, q: PETSc.Vec, out: PETSc.Vec) -> None:
        """a_{n+1} of the Newmark relation for q_{n+1} = q."""
        h, b = self.h, self.beta
        q.copy(out)
        out.axpy(-1.0, self.q)
        out.axpy(-h, self.v)
        out.scale(1.0 / (b * h * h))
        out.axpy(-(0.5 / b - 1.0), self.a)

    def _displace(self, q: PETSc.Vec) -> None:
        """u = T q, unless u already holds it: Newton asks for the residual and then the
        Jacobian at the same iterate, and the material's return map and the contact's
        closest points, keyed on u's state, are then computed once."""
        key = (q.handle, q.stateGet())
        if key != self._displaced:
            self.T.mult(q, self.u)
            self._displaced = (q.handle, q.stateGet())

    def _forces(self, q: PETSc.Vec, F: PETSc.Vec) -> None:
        """u = T q; F = T^T (f_int(u) + f_c(u))."""
        self._displace(q)
        self.material.internal_force(self.u, self.f)
        self.contact.add_residual(self.u, self.f)
        self.f.assemble()
        self.T.multTranspose(self.f, F)

    def _residual(self, snes, x, R):
        """R = M_q a_{n+1-alpha_m} + F(q_{n+1}), q_{n+1} = x."""
        self._forces(x, R)
        self._acceleration(x, self.work)
        self.work.scale(1 - self.alpha_m)
        self.work.axpy(self.alpha_m, self.a)
        self.M.mult(self.work, self.inertia)
        R.axpy(1.0, self.inertia)
        R.setValues(self.prescribed, np.zeros(len(self.prescribed)))
        R.assemble()

    def _jacobian(self, snes, x, J, P):
        self._displace(x)
        A = self._effective(self.h)
        if self._A_in_J != self._A_version:   # A in J's pattern, copied whole below
            self.A_J.zeroEntries()
            self.A_J.axpy(1.0, A, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
            self._A_in_J = self._A_version
        self.A_J.copy(J, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        kind = self.contact.add_tangent(self.u, J)
        J.assemble()
        J.zeroRows(self.prescribed, diag=1.0)
        # the factors of an earlier J serve GMRES while little changed (fem.solver.KeptLU);
        # a new step size changes the mass term everywhere
        if self.lu.refresh(J, snes.getKSP(), kind, stale=self.h != self.factored_h):
            self.factored_h = self.h

    # --- state ---------------------------------------------------------------------------

    def start(self) -> None:
        """t = 0: the pin (and hub) shifted to `initial_gap` short of touching, moving at v0
        along d; the housing at rest; no force, so no acceleration; no contact or plastic
        work yet."""
        shift = self.el.pin_rigid_motion((self.clearance - self.initial_gap) * self.direction)
        self.q.set(0.0)
        self.q.axpy(1.0, shift)
        self.q.pointwiseMult(self.q, self.mask)
        self.along_pin_q.copy(self.v)
        self.v.scale(self.speed)
        self.a.set(0.0)
        # the flight before t = 0, for the first step's predictor (exact in free flight)
        self.q.copy(self.q_last)
        self.q_last.axpy(-self.dt, self.v)
        self.h_last = self.dt
        self._displace(self.q)
        self.contact_force(self.u, self.fc)
        self.t, self.contact_work, self.plastic_work, self.friction_work = 0.0, 0.0, 0.0, 0.0

    def _q_mask(self) -> PETSc.Vec:
        """1 on the reduced unknowns, 0 on the unused hub dofs."""
        mask = self.along_pin_q.duplicate()
        mask.set(1.0)
        unused = np.setdiff1d(self.el.prescribed_rows(), self.master)
        hub = np.setdiff1d(unused, self._clamped())
        mask.setValues(hub, np.zeros(len(hub)))
        mask.assemble()
        return mask

    def _clamped(self) -> np.ndarray:
        dim = self.el.dim
        return (np.asarray(self.el.dofs["housing_edge"])[:, None] * dim + np.arange(dim)).ravel()

    def contact_force(self, u: PETSc.Vec, out: PETSc.Vec) -> None:
        """out = f_c(u), the contact's internal forces alone."""
        out.set(0.0)
        self.contact.add_residual(u, out)
        out.assemble()

    def _save(self):
        for a, b in ((self.q, self.q0), (self.v, self.v0), (self.a, self.a0),
                     (self.fc, self.fc0), (self.q_last, self.q_last0)):
            a.copy(b)
        self.h_last0 = self.h_last
        return self.contact.snapshot(), self.material.snapshot()

    def _load(self, snapshot) -> None:
        for a, b in ((self.q0, self.q), (self.v0, self.v), (self.a0, self.a),
                     (self.fc0, self.fc), (self.q_last0, self.q_last)):
            a.copy(b)
        self.h_last = self.h_last0
        contact, material = snapshot
        self.contact.restore(contact)
        self.material.restore(material)

    def step(self, h: float) -> "Record | str":
        """Advance by h: the Record of the new state, or why the step failed (the state is
        then unchanged)."""
        self.h = h
        snapshot = self._save()
        before = (snapshot, self.t, self.contact_work, self.plastic_work, self.friction_work)
        self.T.mult(self.q, self.u0)
        for search in self._line_searches():
            self.predict(h, self.x)
            self.snes.getLineSearch().setType(search)
            solved = contact_solve(self.snes, self.x, self.contact, self.augmented,
                                   self.uzawa_max_it, self.gap_tolerance)
            if not isinstance(solved, str):
                break
            self.full_steps_failed |= search == "basic" and self.material.plastic
            self._load(snapshot)
        if isinstance(solved, str):
            return solved
        newton, _, _, state, _ = solved
        a_new = self.work
        self._acceleration(self.x, a_new)
        self.v.axpy(h * (1 - self.gamma), self.a)
        self.v.axpy(h * self.gamma, a_new)
        a_new.copy(self.a)
        self.q.copy(self.q_last)
        self.h_last = h
        self.x.copy(self.q)
        self._displace(self.q)
        self.contact_force(self.u, self.fc)
        self.contact.commit(state)
        self.plastic_work += self.material.commit(self.u)
        if self.contact.friction is not None:
            self.friction_work += state.dissipated(self.contact.weights)
        self.t += h
        self.contact_work += 0.5 * self._increment_dot()
        self._before = before
        return self.record(self.t, newton, state)

    def predict(self, h: float, out: PETSc.Vec) -> None:
        """Newton's starting guess for q_{n+1}: the secant through the last two converged
        states, q_n + h (q_n - q_{n-1}) / h_{n-1} (module docstring, the predictor)."""
        self.q.copy(out)
        out.scale(1.0 + h / self.h_last)
        out.axpy(-h / self.h_last, self.q_last)

    def _line_searches(self) -> tuple[str, ...]:
        """The line searches a step tries in turn (module docstring, steps and failures):
        full Newton steps alone for an elastic body; for a plastic one, full steps first
        while they keep solving the steps and no point has yielded (so that a body that
        never reaches its yield stress is the elastic one to the last bit), then the l2
        search and the backtracking one; once a point has yielded, or full steps failed a
        step (an iterate reached the yield stress and they cycled), they are left out."""
        if not self.material.plastic:
            return ("basic",)
        if self.full_steps_failed or self.material.max_plastic_strain() > 0:
            return ("l2", "bt")
        return ("basic", "l2", "bt")

    def undo(self) -> None:
        """Back to the state before the last step that step() solved."""
        snapshot, self.t, self.contact_work, self.plastic_work, self.friction_work = self._before
        self._load(snapshot)

    def record(self, t: float, newton: int, state) -> Record:
        """The time point t of the current state."""
        self._displace(self.q)
        d, m = self.direction, self.master
        hub = self.q.getValues(m)
        self.M.mult(self.v, self.work)
        kinetic = 0.5 * self.work.dot(self.v)
        momentum = self.work.dot(self.along_pin_q)
        friction = self.contact.friction
        return Record(
            time=t, approach=float(hub @ d[:len(m)]) - self.clearance,
            force=self.fc.dot(self.along_pin), hub_velocity=float(self.v.getValues(m) @ d[:len(m)]),
            pin_velocity=momentum / self.mass,
            half_angle=half_angle(angle_from(np.degrees(np.arctan2(d[1], d[0])), state.angle),
                                  state.pressure),
            min_gap=float(np.min(state.gap)), kinetic=kinetic,
            strain=self.material.elastic_energy(self.u), plastic_work=self.plastic_work,
            max_plastic_strain=self.material.max_plastic_strain(),
            contact_energy=state.stored(self.contact.weights, self.contact.penalty,
                                        0.0 if friction is None else friction.penalty),
            contact_work=self.contact_work, friction_work=self.friction_work,
            newton_iterations=newton, time_step=self.h)

    def momentum(self) -> np.ndarray:
        """The pin's momentum (kg m/s per m) along x and y: M_q v summed over the pin's dofs."""
        self.M.mult(self.v, self.work)
        dim = self.el.dim
        along = [self.el.pin_rigid_motion(np.eye(dim)[i]) for i in range(dim)]
        for vec in along:
            vec.pointwiseMult(vec, self.mask)
        return np.array([self.work.dot(vec) for vec in along])

    # --- the run ---------------------------------------------------------------------------

    def run(self, progress=None) -> ImpactRun:
        """From t = 0 until the pin has left the bore and flown on for a while (a tenth of
        the steps in contact, at least 5), or t_end. A step that fails is halved, up to
        max_cutbacks times in a row; a step whose contact loses more than step_loss is
        repeated smaller (module docstring, energy control); after a step the next one grows
        back towards dt."""
        start = time.perf_counter()
        self.start()
        run = ImpactRun()
        run.records.append(self.record(0.0, 0, self.contact.state(self.u)))
        touched, after, h, failures = False, 0, self.dt, 0
        while self.t < self.t_end * (1 - 1e-12):
            outcome = self.step(h)
            if isinstance(outcome, str):
                if failures >= self.max_cutbacks:
                    run.stop = (f"at t = {self.t:.6g} s: {outcome} at the step {h:.3g} s "
                                f"after {failures} halvings")
                    break
                failures += 1
                run.cutbacks += 1
                h /= 2
                continue
            ratio = self.loss_ratio(run.records[-1], outcome)
            if ratio > 1 and h > self.min_step * (1 + 1e-9):
                self.undo()
                run.energy_rejections += 1
                h = self.next_step(h, ratio)
                continue
            failures = 0
            run.records.append(outcome)
            h = self.next_step(h, ratio)
            in_contact = outcome.force > 0
            touched |= in_contact
            run.steps_in_contact += int(in_contact)
            after = 0 if in_contact else after + int(touched)
            if progress is not None:
                progress.update(1)
            if touched and after >= max(5, run.steps_in_contact // 10):
                break
        else:
            run.stop = (f"the pin had not left the bore by t = {self.t:.6g} s "
                        f"(impact.max_contact_durations)" if touched else
                        f"the pin had not reached the bore by t = {self.t:.6g} s")
        run.momentum = self.momentum()
        run.factorizations = self.lu.factorizations
        run.wall_time = time.perf_counter() - start
        return run

    def loss_ratio(self, before: Record, after: Record) -> float:
        """What the contact's time integration lost or made over the step between two
        records, |dW_c - dW_f - dPi_c|, over step_loss (0 without energy control)."""
        if self.step_loss is None:
            return 0.0
        loss = ((after.contact_work - before.contact_work)
                - (after.friction_work - before.friction_work)
                - (after.contact_energy - before.contact_energy))
        return abs(loss) / self.step_loss

    def next_step(self, h: float, ratio: float) -> float:
        """The step after one of size h whose loss was ratio times step_loss: the loss of a
        step grows as h^2 (module docstring), so 0.9 h / sqrt(ratio), within [h/5, 2h] and
        [min_step, dt]."""
        factor = 2.0 if ratio <= 0.25 else min(2.0, max(0.2, 0.9 / np.sqrt(ratio)))
        return min(self.dt, max(self.min_step, h * factor))

    def _increment_dot(self) -> float:
        """(u_{n+1} - u_n) . (f_c,n + f_c,n+1): twice the trapezoidal contact work of the
        step (u_n and f_c,n saved by step())."""
        self.u.copy(self.work)
        self.work.axpy(-1.0, self.u0)
        total = self.fc.copy()
        total.axpy(1.0, self.fc0)
        return self.work.dot(total)
