r"""Pin-on-bore contact: node-to-curved-segment gap, penalty and augmented Lagrangian.

Kinematics
----------
The pin surface nodes are the slaves, the bore surface is the master. In the reference
configuration the bore is the circle of radius R_i about the origin; its nodes sit at the
angles Theta_k. Between bore nodes k and k+1 the deformed bore is the *curved* segment

    Y(xi) = R_i e_r(Theta_k + xi dTheta) + (1 - xi) u_k + xi u_{k+1},      0 <= xi <= 1,

the exact circle plus the linearly interpolated displacement, so there is no faceting error
(a straight chord would sit h^2/(8 R) inside the circle: 1 % of a 10 um approach on a 10 mm
bore meshed at 0.09 mm). A pin node at x is projected onto the closest point of the bore,
(x - Y(xi)) . Y'(xi) = 0 (Newton in xi, moving to the next segment when xi leaves [0, 1]),
and the normal gap (positive open, negative penetrating) is

    g = (Y(xi) - x) . nu,    nu = outward unit normal of the bore at xi.

At the closest point dg/dxi = 0, so dg/dx = -nu, dg/du_k = (1 - xi) nu, dg/du_{k+1} = xi nu:
the forces on the pin node and on the bore nodes are equal and opposite and the gap does not
change under a common rigid translation. Linear momentum is conserved exactly.

Constraint enforcement (nodal collocation)
------------------------------------------
The contact potential is a sum over pin nodes, each weighted by its tributary length w_i
(half the two adjacent edges, m; per unit length in plane strain):

    Pi_c = sum_i w_i / (2 eps) <lambda_i - eps g_i>^2,       p_i = <lambda_i - eps g_i>,

with <.> = max(., 0) and eps the penalty stiffness (Pa/m). lambda = 0 is the pure penalty
method; the augmented Lagrangian (Uzawa) updates lambda_i <- p_i between Newton solves until
the largest penetration is below a tolerance, so the converged gap does not depend on eps.
p_i is the contact pressure (Pa) at node i. Residual and tangent:

    f_c = dPi_c/dU = -sum_i w_i p_i dg_i/dU,
    K_c = sum_i w_i [ eps H(p_i) dg_i/dU (x) dg_i/dU  +  p_i (I - nu nu) / rho  (x)  b b^T ],

b = (1, -(1 - xi), -xi) over (pin node, bore node k, bore node k+1) and rho = |Y| the radius
of curvature. The residual is exact. The second term is the curvature of the bore acting on
the relative displacement x - Y; the tangent leaves out the change of nu with the bore
displacements, terms of relative size |g|/h (about 1e-6 at a converged state, h the element
size), so Newton still converges quadratically to that level. Kept in, such terms are of
both signs at the large penetrations of a first guess and made Newton cycle; without them the
first contact step takes 4-8 iterations (measured over clearances 1e-6 to 5e-4 m and first
increments 1e-6 to 1e-5 m). Nodal collocation (rather than Gauss points) is what the contact
notes measured to converge in 3-5 iterations with P1 elements.

Coulomb friction (return map on a tangential penalty, active-set Newton)
------------------------------------------------------------------------
The tangential position of pin node i on the bore is the arc length of its closest point in
the bore's reference (material) coordinate, s_i = R_i Theta_c, Theta_c = Theta_k + xi dTheta.
A step from the converged state n (s_n, shear sigma_n) is a backward-Euler return map of an
elastic-plastic interface:

    sigma_trial = Lambda_i + eps_T (s_i - s_n,i),
    sigma_i     = sigma_trial                   if |sigma_trial| <= mu p_i   (stick)
                  mu p_i sign(sigma_trial)      otherwise                     (slip),

sigma (Pa) the shear the pin exerts on the bore along +Theta (the bore holds the pin back
with -sigma), eps_T = eps / 10. Penalty: Lambda = sigma_n, so a stuck node creeps by the
elastic slip (sigma - sigma_n)/eps_T. Augmented Lagrangian: Lambda is a multiplier updated
with the normal one (Lambda <- sigma, Uzawa) until every stuck node moved less than the gap
tolerance over the step, so stick is exact and slip is Coulomb's. Residual and tangent, with
ds/dU = R dTheta (df/dU) / D from the closest-point condition f = (x - Y) . Y' = 0,
D = |Y'|^2 - (x - Y) . Y'':

    f_T = sum_i w_i sigma_i ds_i/dU,
    K_T = sum_i w_i eps_T ds_i/dU (x) ds_i/dU                                    (stick)
          sum_i w_i mu sign(sigma_i) ds_i/dU (x) dp_i/dU,  dp/dU = -eps dg/dU      (slip),

the slip tangent being unsymmetric (MUMPS takes it as it is). Newton on the plain return map
cycled (a node near the stick/slip boundary flips between the branches, or slips one way,
then the other); what converges (7-10 iterations per push step, 3-5 per rotation step) is
the primal-dual active-set rule of Hueber, Stadler & Wohlmuth (2008) applied at every
residual evaluation: a slipping node keeps slipping while its slip goes the way of its
shear and sticks otherwise (`active_set`). A stiffer stick (eps_T = eps) also made Newton
cycle. The dissipated work of a step, w sigma (sigma_trial - sigma)/eps_T, is >= 0 node by
node. Without friction (mu = 0) none of this is assembled.

Parallel runs
-------------
The surfaces hold a few thousand nodes at most: every rank gathers their displacements,
rank 0 computes the contact terms and adds them to the distributed PETSc residual and
Jacobian with global indices (PETSc communicates off-process entries at assembly).
Friction (slip along xi) and 3D (bore patches in angle and axial position) enter here as
more local variables per node with the same gather-compute-add structure.
"""

from dataclasses import dataclass

import dolfinx_solver  # noqa: F401  (loads PETSc's libraries; precedes petsc4py)
import numpy as np
from petsc4py import PETSc


# --- local kinematics: pin nodes against curved bore segments, vectorized over nodes ---------

def bracket(theta: np.ndarray, bore_angles: np.ndarray):
    """Segment k (bore nodes k, k+1 mod M) containing each angle, and the local coordinate xi.

    bore_angles: sorted reference angles of the bore nodes in [-pi, pi).
    """
    closed = np.append(bore_angles, bore_angles[0] + 2 * np.pi)
    t = np.where(theta < bore_angles[0], theta + 2 * np.pi, theta)
    k = np.clip(np.searchsorted(closed, t, side="right") - 1, 0, bore_angles.size - 1)
    return k, (t - closed[k]) / (closed[k + 1] - closed[k])


@dataclass
class Segments:
    """The bore as curved segments: reference radius, node angles and current displacements."""

    radius: float
    angles: np.ndarray          # (M,) sorted, in [-pi, pi)
    displacement: np.ndarray    # (M, 2)

    def __post_init__(self):
        self.widths = np.diff(np.append(self.angles, self.angles[0] + 2 * np.pi))

    def point(self, k, xi):
        """Y(xi), Y'(xi) and Y''(xi) on segments k."""
        width = self.widths[k]
        theta = self.angles[k] + xi * width
        e_r = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        e_t = np.stack([-e_r[:, 1], e_r[:, 0]], axis=1)
        u0, u1 = self.displacement[k], self.displacement[(k + 1) % self.angles.size]
        y = self.radius * e_r + (1 - xi)[:, None] * u0 + xi[:, None] * u1
        dy = (self.radius * width)[:, None] * e_t + (u1 - u0)
        ddy = -(self.radius * width**2)[:, None] * e_r
        return y, dy, ddy


def closest_point(x: np.ndarray, bore: Segments, newton_steps: int = 4, hops: int = 8):
    """Segment k and coordinate xi of the closest bore point to each x (n, 2)."""
    k, xi = bracket(np.arctan2(x[:, 1], x[:, 0]), bore.angles)
    m = bore.angles.size
    for _ in range(hops):
        for _ in range(newton_steps):
            y, dy, ddy = bore.point(k, xi)
            f = np.einsum("ni,ni->n", x - y, dy)
            df = -np.einsum("ni,ni->n", dy, dy) + np.einsum("ni,ni->n", x - y, ddy)
            xi = xi - f / df
        below, above = xi < 0, xi > 1
        if not (below.any() or above.any()):
            break
        k = np.where(below, (k - 1) % m, np.where(above, (k + 1) % m, k))
        xi = np.where(below, 1.0, np.where(above, 0.0, xi))
    return k, np.clip(xi, 0.0, 1.0)


def gap_and_normal(x: np.ndarray, bore: Segments, k, xi):
    """Gap g = (Y - x) . nu (m), the outward normal nu and the radius of curvature |Y|."""
    y, dy, _ = bore.point(k, xi)
    nu = np.stack([dy[:, 1], -dy[:, 0]], axis=1) / np.linalg.norm(dy, axis=1)[:, None]
    return np.einsum("ni,ni->n", y - x, nu), nu, np.linalg.norm(y, axis=1)


def pressure(lam, penalty, g):
    """Nodal contact pressure p = <lambda - eps g> (Pa)."""
    return np.maximum(lam - penalty * g, 0.0)


def slip_gradient(x: np.ndarray, bore: Segments, k, xi) -> np.ndarray:
    """ds/dU (n, 6) of the arc length s = R Theta_c of the closest point, over
    (pin node, bore node k, bore node k+1), from (x - Y(xi)) . Y'(xi) = 0."""
    y, dy, ddy = bore.point(k, xi)
    d = np.einsum("ni,ni->n", dy, dy) - np.einsum("ni,ni->n", x - y, ddy)
    df = np.stack([dy, -(1 - xi)[:, None] * dy - (x - y), -xi[:, None] * dy + (x - y)], axis=1)
    return (bore.radius * bore.widths[k] / d)[:, None] * df.reshape(-1, 6)


def active_set(trial, bound, p, status, sign):
    """Shear (Pa) and state of each node at an iterate, given the active set of the last
    one (status, sign) and the slip bound mu p (Pa).

    The primal-dual active-set rule of Hueber, Stadler & Wohlmuth (2008): a node that was
    slipping keeps slipping (shear = sign * bound) while its slip, trial - sign * bound, goes
    the way of its shear, and sticks otherwise; any other node in contact sticks if
    |trial| <= bound and slips along sign(trial) if not; a node with p = 0 is open. A
    converged state is the backward-Euler return map sigma = clip(trial, -bound, bound).
    """
    slipping = (status == SLIP) & (sign != 0)
    keeps = slipping & (np.sign(trial - sign * bound) * sign >= 0)
    stuck = np.where(slipping, ~keeps, np.abs(trial) <= bound) & (bound > 0)
    direction = np.where(keeps, sign, np.sign(trial))
    shear = np.where(p > 0, np.where(stuck, trial, direction * bound), 0.0)
    return shear, np.where(p > 0, np.where(stuck, STICK, SLIP), OPEN)


OPEN, STICK, SLIP = 0, 1, 2
STATE_NAMES = ("open", "stick", "slip")
TANGENTIAL_PENALTY_RATIO = 0.1  # eps_T / eps: a stiffer stick made Newton cycle


@dataclass
class Friction:
    """Coulomb friction at the pin nodes: coefficient, tangential penalty (Pa/m), the
    converged state n (bore coordinate s_n (m), shear sigma_n (Pa)), the multiplier Lambda
    (= sigma_n with the penalty method), and the active set of the current Newton iterate:
    the state and slip direction of each node."""

    mu: float
    penalty: float
    s_n: np.ndarray
    sigma_n: np.ndarray
    multiplier: np.ndarray
    status: np.ndarray
    sign: np.ndarray

    @classmethod
    def at_rest(cls, mu, penalty, n):
        zero = np.zeros(n)
        return cls(mu, penalty, zero, zero.copy(), zero.copy(), np.full(n, OPEN), zero.copy())

    def trial(self, s):
        return self.multiplier + self.penalty * (s - self.s_n)

    def freeze(self, state) -> None:
        self.status, self.sign = state.status.copy(), np.sign(state.shear)

    def settled(self, state) -> bool:
        """The iterate's active set is the one the return map gives at the solution."""
        return bool(np.array_equal(state.status, self.status)
                    and np.array_equal(np.sign(state.shear), self.sign))

    def saved(self):
        return tuple(a.copy() for a in (self.s_n, self.sigma_n, self.status, self.sign))

    def load(self, saved) -> None:
        self.s_n, self.sigma_n, self.status, self.sign = (a.copy() for a in saved)
        self.multiplier = self.sigma_n.copy()


# --- the two surfaces of a mesh and the assembly of the contact terms --------------------------

@dataclass
class ContactState:
    """What one evaluation found at the pin nodes (arrays over pin nodes, sorted by angle)."""

    gap: np.ndarray        # m
    pressure: np.ndarray   # Pa
    angle: np.ndarray      # rad, current polar angle of the node
    position: np.ndarray   # m, arc length s of the closest bore point (material coordinate)
    shear: np.ndarray      # Pa, on the bore along +theta (0 without friction)
    status: np.ndarray     # OPEN, STICK or SLIP
    slip: np.ndarray       # m, plastic slip of this step, (sigma_trial - sigma) / eps_T

    def dissipated(self, weights) -> float:
        """Work dissipated by friction over the step (J/m): sum w sigma slip >= 0."""
        return float(np.sum(weights * self.shear * self.slip))


class PinBoreContact:
    """Contact terms between the pin-surface and bore-surface nodes of a P1 vector space.

    pin_dofs / bore_dofs: local block (node) indices in V owned by this rank. Every rank
    holds both surfaces whole, sorted by angle: pin_X, pin_nodes (global node indices),
    weights (tributary lengths), bore_angles, the multipliers lam and, with mu > 0, the
    friction state.
    """

    def __init__(self, V, pin_dofs, bore_dofs, bore_radius, penalty, template: PETSc.Vec,
                 friction: float = 0.0):
        self.comm = V.mesh.comm
        self.bore_radius = bore_radius
        self.penalty = penalty
        coords = V.tabulate_dof_coordinates()[:, :2]
        imap = V.dofmap.index_map
        gathered = [self._gather(coords[d], imap.local_to_global(d.astype(np.int32)))
                    for d in (pin_dofs, bore_dofs)]
        (self.pin_X, pin_nodes), (bore_X, bore_nodes) = gathered
        pin_angle = np.arctan2(self.pin_X[:, 1], self.pin_X[:, 0])
        bore_angle = np.arctan2(bore_X[:, 1], bore_X[:, 0])
        order_p, order_b = np.argsort(pin_angle), np.argsort(bore_angle)
        self.pin_X, self.pin_nodes = self.pin_X[order_p], pin_nodes[order_p]
        self.bore_angles, bore_nodes = bore_angle[order_b], bore_nodes[order_b]
        self.weights = tributary_lengths(self.pin_X)
        bs = V.dofmap.index_map_bs
        self.pin_rows = (bs * self.pin_nodes[:, None] + np.arange(2)).astype(PETSc.IntType)
        self.bore_rows = (bs * bore_nodes[:, None] + np.arange(2)).astype(PETSc.IntType)
        self.lam = np.zeros(len(self.pin_X))
        self._scatter, self._local = self._make_scatter(template)
        self.friction = (Friction.at_rest(friction, TANGENTIAL_PENALTY_RATIO * penalty,
                                          len(self.pin_X)) if friction > 0 else None)

    def _gather(self, coords, global_nodes):
        coords = np.concatenate(self.comm.allgather(coords))
        nodes = np.concatenate(self.comm.allgather(np.asarray(global_nodes, dtype=np.int64)))
        return coords, nodes

    def _make_scatter(self, template: PETSc.Vec):
        """A scatter that copies the surface displacements of a global vector to every rank."""
        rows = np.concatenate([self.pin_rows.ravel(), self.bore_rows.ravel()])
        local = PETSc.Vec().createSeq(rows.size, comm=PETSc.COMM_SELF)
        index = PETSc.IS().createGeneral(rows, comm=PETSc.COMM_SELF)
        return PETSc.Scatter().create(template, index, local, None), local

    def _surface_displacements(self, u: PETSc.Vec):
        self._scatter.scatter(u, self._local, addv=PETSc.InsertMode.INSERT,
                              mode=PETSc.ScatterMode.FORWARD)
        values = self._local.getArray(readonly=True)
        n_pin = self.pin_rows.size
        return values[:n_pin].reshape(-1, 2), values[n_pin:].reshape(-1, 2)

    def _kinematics(self, u: PETSc.Vec):
        """Current pin positions, closest bore points and gaps. Collective (gathers u)."""
        u_pin, u_bore = self._surface_displacements(u)
        x = self.pin_X + u_pin
        bore = Segments(self.bore_radius, self.bore_angles, u_bore)
        k, xi = closest_point(x, bore)
        g, nu, rho = gap_and_normal(x, bore, k, xi)
        return x, bore, k, xi, g, nu, rho

    def _position(self, bore: Segments, k, xi, previous):
        """Arc length R Theta_c (m) of the closest points, unwrapped next to `previous`."""
        s = bore.radius * (bore.angles[k] + xi * bore.widths[k])
        period = 2 * np.pi * bore.radius
        return s - period * np.round((s - previous) / period)

    def state(self, u: PETSc.Vec) -> ContactState:
        x, bore, k, xi, g, _, _ = self._kinematics(u)
        p = pressure(self.lam, self.penalty, g)
        f = self.friction
        if f is None:
            zero = np.zeros_like(g)
            return ContactState(g, p, np.arctan2(x[:, 1], x[:, 0]), zero, zero,
                                np.where(p > 0, SLIP, OPEN), zero)
        s = self._position(bore, k, xi, f.s_n)
        trial = f.trial(s)
        shear, status = active_set(trial, f.mu * p, p, f.status, f.sign)
        return ContactState(g, p, np.arctan2(x[:, 1], x[:, 0]), s, shear, status,
                            (trial - shear) / f.penalty)

    def commit(self, state: ContactState) -> None:
        """Make a converged state the start of the next step."""
        f = self.friction
        if f is not None:
            f.s_n, f.sigma_n, f.multiplier = state.position, state.shear, state.shear.copy()
            f.freeze(state)

    def snapshot(self):
        return self.lam.copy(), None if self.friction is None else self.friction.saved()

    def restore(self, snapshot) -> None:
        lam, friction = snapshot
        self.lam = lam.copy()
        if friction is not None:
            self.friction.load(friction)

    def stick_violation(self, state: ContactState) -> float:
        """Largest motion (m) of a stuck node over the step (0 with the penalty method the
        augmented Lagrangian drives it to)."""
        if self.friction is None:
            return 0.0
        moved = np.abs(state.position - self.friction.s_n)[state.status == STICK]
        return float(moved.max(initial=0.0))

    def friction_settled(self, state: ContactState) -> bool:
        return self.friction is None or self.friction.settled(state)

    def update_friction(self, state: ContactState) -> None:
        if self.friction is not None:
            self.friction.freeze(state)

    def update_multipliers(self, state: ContactState) -> None:
        """Uzawa: lambda <- p, Lambda <- sigma."""
        self.lam = state.pressure
        if self.friction is not None:
            self.friction.multiplier = state.shear.copy()

    def torque(self, u: PETSc.Vec, centre) -> float:
        """Moment (N m/m) about the axis through `centre` that balances the contact tractions
        on the pin, taken in the current configuration: the friction torque the hub applies
        (the normal tractions pass through the bore's axis and contribute only through the
        offset of the two axes). Collective."""
        act, _, residual, _ = self._local_terms(u, with_tangent=False)
        arm = self.pin_X[act] + self._surface_displacements(u)[0][act] - np.asarray(centre)
        return float(np.sum(arm[:, 0] * residual[:, 1] - arm[:, 1] * residual[:, 0]))

    def _local_terms(self, u: PETSc.Vec, with_tangent: bool):
        """Active nodes: their indices, global rows (n, 6) and residual (n, 6)
        [, tangent (n, 6, 6)]."""
        x, bore, k, xi, g, nu, rho = self._kinematics(u)
        p = pressure(self.lam, self.penalty, g)
        act = np.flatnonzero(p > 0)
        x, k, xi, nu, rho = x[act], k[act], xi[act], nu[act], rho[act]
        k1 = (k + 1) % self.bore_angles.size
        rows = np.concatenate([self.pin_rows[act], self.bore_rows[k], self.bore_rows[k1]], axis=1)
        b = np.stack([np.ones_like(xi), -(1 - xi), -xi], axis=1)       # x - Y(xi) weights
        grad = -(b[:, :, None] * nu[:, None, :]).reshape(-1, 6)        # dg/dU
        w, pa = self.weights[act], p[act]
        residual = -pa[:, None] * grad
        f = self.friction
        if f is not None:
            grad_s = slip_gradient(x, bore, k, xi)
            s = self._position(bore, k, xi, f.s_n[act])
            stuck = f.status[act] == STICK
            trial = f.multiplier[act] + f.penalty * (s - f.s_n[act])
            shear = np.where(stuck, trial, f.sign[act] * f.mu * pa)
            residual += shear[:, None] * grad_s
        residual *= w[:, None]
        if not with_tangent:
            return act, rows, residual, None
        tangential = (np.eye(2) - np.einsum("ni,nj->nij", nu, nu)) / rho[:, None, None]
        tangent = (self.penalty * np.einsum("ni,nj->nij", grad, grad)
                   + np.einsum("n,na,nb,nij->naibj", pa, b, b, tangential).reshape(-1, 6, 6))
        if f is not None:
            slip = ~stuck * f.mu * f.sign[act] * self.penalty   # d(sign mu p)/dU = -sign mu eps dg/dU
            tangent += (f.penalty * np.einsum("n,ni,nj->nij", stuck, grad_s, grad_s)
                        - np.einsum("n,ni,nj->nij", slip, grad_s, grad))
        return act, rows, residual, tangent * w[:, None, None]

    def add_residual(self, u: PETSc.Vec, F: PETSc.Vec) -> None:
        """F += f_c(u). Collective; call F.assemble() afterwards."""
        if self.friction is not None:
            self.friction.freeze(self.state(u))  # the active-set update of this iterate
        _, rows, residual, _ = self._local_terms(u, with_tangent=False)
        if self.comm.rank == 0:
            F.setValues(rows.ravel(), residual.ravel(), addv=PETSc.InsertMode.ADD_VALUES)

    def add_tangent(self, u: PETSc.Vec, J: PETSc.Mat) -> None:
        """J += K_c(u). Collective; call J.assemble() afterwards."""
        _, rows, _, tangent = self._local_terms(u, with_tangent=True)
        if self.comm.rank == 0:
            for r, block in zip(rows, tangent):
                J.setValues(r, r, block, addv=PETSc.InsertMode.ADD_VALUES)


def tributary_lengths(points: np.ndarray) -> np.ndarray:
    """Half the summed lengths of the two edges at each node of a closed polygon (m)."""
    edges = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return 0.5 * (edges + np.roll(edges, 1))
