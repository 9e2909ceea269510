r"""Pin-on-bore contact: node-to-segment gap in polar form, penalty and augmented Lagrangian.

Kinematics
----------
The pin surface nodes are the slaves, the bore surface is the master. Both surfaces are
circles about the origin in the reference configuration (radii R_j and R_i). A pin node at
current position x (reference X, displacement u) sits at the polar angle theta(x) and radius
r = |x|. The deformed bore surface is described by its radial displacement a(theta),
interpolated linearly in angle between the bore nodes k, k+1 that bracket theta:

    a(theta) = (1 - xi) a_k + xi a_{k+1},   xi = (theta - Theta_k) / (Theta_{k+1} - Theta_k),
    a_k = u_k . e_r(Theta_k),

and the normal gap (positive open, negative penetrating) is

    g(x, a_k, a_{k+1}) = R_i + a(theta(x)) - |x|.

This is exact for the undeformed circles (no faceting error however coarse the mesh far from
the arc) and first order in the bore deformation: the tangential displacement of the bore
(u_theta, about the approach) shifts a(theta) by u_theta a'(theta)/R, a product of two small
quantities. The pin may slide over many bore segments (it moves the whole clearance), and the
segment is searched anew at every evaluation.

Constraint enforcement (nodal collocation)
------------------------------------------
The contact potential is a sum over pin nodes, each weighted by its tributary length w_i
(half the two adjacent edges, m; per unit length in plane strain):

    Pi_c = sum_i w_i / (2 eps) <lambda_i - eps g_i>^2,       p_i = <lambda_i - eps g_i>,

with <.> = max(., 0) and eps the penalty stiffness (Pa/m). lambda = 0 is the pure penalty
method; the augmented Lagrangian (Uzawa) updates lambda_i <- p_i between Newton solves until
the largest penetration is below a tolerance, so the converged gap does not depend on eps.
p_i is the contact pressure (Pa) at node i. Residual and consistent tangent:

    f_c = dPi_c/dU = -sum_i w_i p_i dg_i/dU,
    K_c = sum_i w_i [ eps H(p_i) dg_i/dU (x) dg_i/dU  -  p_i d^2 g_i/dU^2 ].

The residual is exact. In d^2 g/dU^2 we keep the curvature of the circle, (I - e_r e_r)/r, and
linearize with the segment coordinate xi held fixed over an iteration, as node-to-segment
codes commonly do: the dropped terms come from xi(theta(x)) and are of relative size |g|/h
(about 1e-6 at a converged state, h the element size), so Newton still converges
quadratically to that level. At the large penetrations of a first guess they are of both
signs and made Newton cycle; dropping them took the first contact step from up to 25 failed
iterations to 4-8 (measured over clearances 1e-6 to 5e-4 m and first increments 1e-6 to
1e-5 m). Nodal collocation (rather than Gauss points) is what the contact notes measured to
converge in 3-5 iterations with P1 elements.

Parallel runs
-------------
The surfaces hold a few thousand nodes at most: every rank gathers their displacements,
rank 0 computes the contact terms and adds them to the distributed PETSc residual and
Jacobian with global indices (PETSc communicates off-process entries at assembly).
Friction and 3D enter here as more local variables per node (tangential slip; axial position
on the bore) with the same gather-compute-add structure.
"""

from dataclasses import dataclass

import numpy as np
import dolfinx_solver  # noqa: F401  (loads PETSc's libraries; precedes petsc4py)
from petsc4py import PETSc


# --- local kinematics: one pin node against one bore segment, vectorized over nodes -------------

def polar(x: np.ndarray):
    """Radius, angle, radial and tangential unit vectors of points x (n, 2)."""
    r = np.hypot(x[:, 0], x[:, 1])
    theta = np.arctan2(x[:, 1], x[:, 0])
    e_r = x / r[:, None]
    e_t = np.stack([-e_r[:, 1], e_r[:, 0]], axis=1)
    return r, theta, e_r, e_t


def bracket(theta: np.ndarray, bore_angles: np.ndarray):
    """Segment k (bore nodes k, k+1 mod M) containing each angle, and the local coordinate xi.

    bore_angles: sorted reference angles of the bore nodes in [-pi, pi).
    """
    closed = np.append(bore_angles, bore_angles[0] + 2 * np.pi)
    t = np.where(theta < bore_angles[0], theta + 2 * np.pi, theta)
    k = np.clip(np.searchsorted(closed, t, side="right") - 1, 0, bore_angles.size - 1)
    width = closed[k + 1] - closed[k]
    return k, (t - closed[k]) / width, width


def gap(radius_bore, x, a_k, a_k1, xi):
    """g = R_i + (1 - xi) a_k + xi a_k1 - |x|  (m, positive open)."""
    return radius_bore + (1 - xi) * a_k + xi * a_k1 - np.hypot(x[:, 0], x[:, 1])


def gap_derivatives(x, a_k, a_k1, xi, width):
    """Gradient (n, 4) of g in (x, y, a_k, a_k1), and the curvature part (n, 2, 2) of its Hessian.

    The gradient is exact: -e_r tilted by the slope of the deformed bore, plus the
    interpolation weights. The Hessian keeps d2|x|/dx2 = (I - e_r e_r)/r, the curvature of the
    circle, and holds the segment coordinate xi fixed (see module docstring).
    """
    r, _, e_r, e_t = polar(x)
    slope = (a_k1 - a_k) / width  # da/dtheta on the segment
    grad = np.empty((x.shape[0], 4))
    grad[:, :2] = -e_r + (slope / r)[:, None] * e_t
    grad[:, 2] = 1 - xi
    grad[:, 3] = xi
    return grad, -np.einsum("ni,nj->nij", e_t, e_t) / r[:, None, None]


def pressure(lam, penalty, g):
    """Nodal contact pressure p = <lambda - eps g> (Pa)."""
    return np.maximum(lam - penalty * g, 0.0)


# --- the two surfaces of a mesh and the assembly of the contact terms --------------------------

@dataclass
class ContactState:
    """What one evaluation found at the pin nodes (arrays over pin nodes, sorted by angle)."""

    gap: np.ndarray        # m
    pressure: np.ndarray   # Pa
    angle: np.ndarray      # rad, current polar angle of the node


class PinBoreContact:
    """Contact terms between the pin-surface and bore-surface nodes of a P1 vector space.

    pin_dofs / bore_dofs: local block (node) indices in V owned by this rank.
    """

    def __init__(self, V, pin_dofs, bore_dofs, bore_radius, penalty, template: PETSc.Vec):
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
        self.pin_X, pin_nodes = self.pin_X[order_p], pin_nodes[order_p]
        self.bore_angles, bore_X, bore_nodes = bore_angle[order_b], bore_X[order_b], bore_nodes[order_b]
        self.bore_e_r = bore_X / np.hypot(bore_X[:, 0], bore_X[:, 1])[:, None]
        self.weights = tributary_lengths(self.pin_X)
        bs = V.dofmap.index_map_bs
        self.pin_rows = (bs * pin_nodes[:, None] + np.arange(2)).astype(PETSc.IntType)
        self.bore_rows = (bs * bore_nodes[:, None] + np.arange(2)).astype(PETSc.IntType)
        self.lam = np.zeros(len(self.pin_X))
        self._scatter, self._local = self._make_scatter(template)

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
        u_pin, u_bore = self._surface_displacements(u)
        x = self.pin_X + u_pin
        a = np.einsum("ni,ni->n", u_bore, self.bore_e_r)
        theta = np.arctan2(x[:, 1], x[:, 0])
        k, xi, width = bracket(theta, self.bore_angles)
        k1 = (k + 1) % a.size
        return x, theta, a, k, k1, xi, width

    def state(self, u: PETSc.Vec) -> ContactState:
        x, theta, a, k, k1, xi, _ = self._kinematics(u)
        g = gap(self.bore_radius, x, a[k], a[k1], xi)
        return ContactState(g, pressure(self.lam, self.penalty, g), theta)

    def _local_terms(self, u: PETSc.Vec, with_tangent: bool):
        """Active nodes: global rows (n, 6) and residual (n, 6) [, tangent (n, 6, 6)]."""
        x, _, a, k, k1, xi, width = self._kinematics(u)
        g = gap(self.bore_radius, x, a[k], a[k1], xi)
        p = pressure(self.lam, self.penalty, g)
        act = np.flatnonzero(p > 0)
        grad, curvature = gap_derivatives(x[act], a[k[act]], a[k1[act]], xi[act], width[act])
        # (x, y, a_k, a_k1) -> the six displacement dofs of pin node, bore node k, bore node k1
        T = np.zeros((act.size, 4, 6))
        T[:, 0, 0] = T[:, 1, 1] = 1.0
        T[:, 2, 2:4] = self.bore_e_r[k[act]]
        T[:, 3, 4:6] = self.bore_e_r[k1[act]]
        rows = np.concatenate([self.pin_rows[act], self.bore_rows[k[act]],
                               self.bore_rows[k1[act]]], axis=1)
        w, pa = self.weights[act], p[act]
        residual = np.einsum("n,nij,ni->nj", -w * pa, T, grad)
        if not with_tangent:
            return rows, residual, None
        local = self.penalty * np.einsum("ni,nj->nij", grad, grad)
        local[:, :2, :2] -= pa[:, None, None] * curvature
        local *= w[:, None, None]
        return rows, residual, np.einsum("nki,nkl,nlj->nij", T, local, T)

    def add_residual(self, u: PETSc.Vec, F: PETSc.Vec) -> None:
        """F += f_c(u). Collective; call F.assemble() afterwards."""
        if self.comm.rank == 0:
            rows, residual, _ = self._local_terms(u, with_tangent=False)
            F.setValues(rows.ravel(), residual.ravel(), addv=PETSc.InsertMode.ADD_VALUES)

    def add_tangent(self, u: PETSc.Vec, J: PETSc.Mat) -> None:
        """J += K_c(u). Collective; call J.assemble() afterwards."""
        if self.comm.rank == 0:
            rows, _, tangent = self._local_terms(u, with_tangent=True)
            for r, block in zip(rows, tangent):
                J.setValues(r, r, block, addv=PETSc.InsertMode.ADD_VALUES)


def tributary_lengths(points: np.ndarray) -> np.ndarray:
    """Half the summed lengths of the two edges at each node of a closed polygon (m)."""
    edges = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return 0.5 * (edges + np.roll(edges, 1))
