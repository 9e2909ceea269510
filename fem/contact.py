r"""Pin-on-bore contact: node-to-curved-patch gap, penalty and augmented Lagrangian, Coulomb
friction; 2D (plane strain) and 3D.

Kinematics
----------
The pin surface nodes are the slaves, the bore surface is the master. In the reference
configuration the bore is the circle of radius R_i about the axis (3D: the cylinder
0 <= z <= L, its radius widened near the ends by an optional edge relief delta(z); 2D, a
worn joint: the curve r(Theta) = R_i + e(Theta), its wear beyond the circle R_i,
meshes.worn); its nodes sit on a grid of angles Theta_k (and levels Z_l in 3D). Between bore
nodes the deformed bore is the *curved* patch

    2D:  Y(xi)      = r(Theta) e_r(Theta) + N_a(xi) u_a,   Theta = Theta_k + xi dTheta_k,  N = (1 - xi, xi)
    3D:  Y(xi, eta) = (R_i + delta(z)) e_r(Theta_k + xi dTheta_k) + z e_z + N_a(xi, eta) u_a,
                      z = Z_l + eta dZ_l,  N bilinear over the four corner nodes,

the exact surface plus the interpolated displacement, so there is no faceting error
(a straight chord would sit h^2/(8 R) inside the circle: 1 % of a 10 um approach on a 10 mm
bore meshed at 0.09 mm). (In 3D the FE trace of the bore's displacement is linear on the
triangles of the grid's quads; the bilinear interpolation differs from it by O(h^2 grad^2 u).)
A pin node at x is projected onto the closest point of the bore, (x - Y) . Y_,a = 0 for each
surface coordinate zeta_a (Newton in zeta, moving to the next patch when zeta leaves
[0, 1]; past the bore's ends the end patches are continued a little, beyond that a node is
out of contact), and the
normal gap (positive open, negative penetrating) is

    g = (Y(zeta) - x) . nu,    nu = outward unit normal of the bore at zeta.

At the closest point dg/dzeta = 0, so dg/dx = -nu and dg/du_a = N_a nu: the forces on the
pin node and on the bore nodes are equal and opposite and the gap does not change under a
common rigid translation. Linear momentum is conserved exactly.

Constraint enforcement (nodal collocation)
------------------------------------------
The contact potential is a sum over pin nodes, each weighted by its tributary length w_i
(2D: half the two adjacent edges, m, per unit length; 3D: that length times half the two
adjacent layers, m^2):

    Pi_c = sum_i w_i / (2 eps) <lambda_i - eps g_i>^2,       p_i = <lambda_i - eps g_i>,

with <.> = max(., 0) and eps the penalty stiffness (Pa/m). lambda = 0 is the pure penalty
method; the augmented Lagrangian (Uzawa) updates lambda_i <- p_i between Newton solves until
the largest penetration is below a tolerance, so the converged gap does not depend on eps.
p_i is the contact pressure (Pa) at node i. Residual and tangent:

    f_c = dPi_c/dU = -sum_i w_i p_i dg_i/dU,
    K_c = sum_i w_i [ eps H(p_i) dg_i/dU (x) dg_i/dU  +  p_i (I - nu nu) / rho  (x)  b b^T ],

    (3D: (I - nu nu) replaced by t t, t the unit tangent along the circumference)

b = (1, -N_a) over (pin node, bore nodes a) and rho the distance of Y from the axis, the
radius of curvature (a worn bore: the deformed patch's own, |Y'|^3 / (Y' x Y''), which the
worn surface's curvature sets). The residual is exact. The second term is the curvature of the bore
acting on the relative displacement x - Y; the tangent leaves out the change of nu with the bore
displacements, terms of relative size |g|/h (about 1e-6 at a converged state, h the element
size), so Newton still converges quadratically to that level. Kept in, such terms are of
both signs at the large penetrations of a first guess and made Newton cycle; without them the
first contact step takes 4-8 iterations (measured over clearances 1e-6 to 5e-4 m and first
increments 1e-6 to 1e-5 m). Nodal collocation (rather than Gauss points) is what the contact
notes measured to converge in 3-5 iterations with P1 elements.

Coulomb friction (return map on a tangential penalty, active-set Newton)
------------------------------------------------------------------------
The tangential position of pin node i on the bore is the position of its closest point in
the bore's reference (material) coordinates: the arc length s_i = R_i Theta_c,
Theta_c = Theta_k + xi dTheta_k (3D: and the axial position Z_c = Z_l + eta dZ_l; a worn
bore: the arc length of its reference curve, exact at its nodes and linear in xi between).
A step from the converged state n (s_n, shear sigma_n) is a backward-Euler return map of an
elastic-plastic interface (vectors of the surface coordinates in 3D, radial return):

    sigma_trial = Lambda_i + eps_T (s_i - s_n,i),
    sigma_i     = sigma_trial                        if |sigma_trial| <= mu p_i   (stick)
                  mu p_i sigma_trial/|sigma_trial|   otherwise                     (slip),

sigma (Pa) the shear the pin exerts on the bore along +Theta (+z) (the bore holds the pin
back with -sigma), eps_T = eps. Penalty: Lambda = sigma_n, so a stuck node creeps by the
elastic slip (sigma - sigma_n)/eps_T. Augmented Lagrangian: Lambda is a multiplier updated
with the normal one (Lambda <- sigma, Uzawa) until every stuck node moved less than the gap
tolerance over the step, so stick is exact and slip is Coulomb's. Residual and tangent, with
ds/dU = diag(R dTheta, dZ) A^-1 df/dU from the closest-point conditions
f_a = (x - Y) . Y_,a = 0, A_ab = Y_,a . Y_,b - (x - Y) . Y_,ab:

    f_T = sum_i w_i sigma_i . ds_i/dU,
    K_T = sum_i w_i eps_T ds_i/dU (x) ds_i/dU                                         (stick)
          sum_i w_i ds_i/dU (x) [mu n dp_i/dU + mu p_i/|trial| (I - n n) eps_T ds_i/dU]   (slip),

n = sigma_trial/|sigma_trial|, dp/dU = -eps dg/dU (in 2D I - n n = 0); the slip tangent
is unsymmetric (MUMPS takes it as it is).

Newton on the plain return map cycled (a node near the stick/slip boundary flips between
the branches, or slips one way, then the other; a softer stick, eps_T = eps / 10, did not
cure it and made the tangential Uzawa iteration contract only 4-fold per update). What
converges: the primal-dual active-set rule of Hueber, Stadler & Wohlmuth [HueberStadlerWohlmuth2008]
(`active_set`: a slipping node keeps slipping while its trial shear exceeds the bound and
does not turn back, and sticks otherwise) applied at the first ACTIVE_SET_UPDATES residual
evaluations of a Newton solve; then the stick/slip set and the set of nodes in contact are
kept, Newton solves a smooth problem, and if the sets of the solution differ, the next solve
(the Uzawa loop of the solver) starts from them. Measured: 4-8 Newton iterations per 2D
push step, 8-12 while the arc goes from stick to slip, 3-5 at full slip; in 3D friction
costs 1.4x the frictionless solve of the same push (bench/fem3d.csv). The dissipated work of a step,
w sigma . (sigma_trial - sigma)/eps_T, is >= 0 node by node. Without friction (mu = 0)
none of this is assembled.

Parallel runs
-------------
The surfaces hold a few thousand nodes (2D) to some ten thousand (3D): every rank gathers
their displacements, rank 0 computes the contact terms and adds them to the distributed
PETSc residual and Jacobian with global indices (PETSc communicates off-process entries at
assembly).
"""

from collections.abc import Callable
from dataclasses import dataclass, fields

import dolfinx_solver  # noqa: F401  (loads PETSc's libraries; precedes petsc4py)
import numpy as np
import scipy.sparse
from petsc4py import PETSc

from pinbore.meshes.model import Relief


# --- the bore: reference geometry, curved patches, closest points (vectorized over nodes) ------

def bracket(theta: np.ndarray, bore_angles: np.ndarray):
    """Segment k (bore nodes k, k+1 mod M) containing each angle, and the local coordinate xi.

    bore_angles: sorted reference angles of the bore nodes in [-pi, pi).
    """
    closed = np.append(bore_angles, bore_angles[0] + 2 * np.pi)
    t = np.where(theta < bore_angles[0], theta + 2 * np.pi, theta)
    k = np.clip(np.searchsorted(closed, t, side="right") - 1, 0, bore_angles.size - 1)
    return k, (t - closed[k]) / (closed[k + 1] - closed[k])


@dataclass
class BoreSurface:
    """The bore as curved patches: reference radius and node grid (angles, and in 3D the
    levels z with the ends of the bore at levels[0] and `end`), the edge relief, and the
    current node displacements (M * L, dim), level by level."""

    radius: float
    angles: np.ndarray                   # (M,) sorted, in [-pi, pi)
    displacement: np.ndarray             # (M * L, dim)
    levels: np.ndarray | None = None     # (L,) sorted, 3D only
    relief: Relief | None = None
    end: float | None = None             # z of the bore's far end (the last level, or beyond
                                         # it when a symmetry plane cuts the model)
    continuation: float = 0.5            # of the end layers, past the ends (closest_point):
                                         # half a layer where the pin ends with the bore, a
                                         # twentieth where it runs on beyond
    wear: Callable | None = None         # 2D, a worn bore: theta -> (e, e', e''), its radius
                                         # beyond `radius` (m) at the angles theta, with its
                                         # slope and curvature (m/rad, m/rad^2)

    def __post_init__(self):
        self.widths = np.diff(np.append(self.angles, self.angles[0] + 2 * np.pi))
        self.dim = 2 if self.levels is None else 3
        if self.wear is not None and self.dim == 3:
            raise ValueError("a worn bore is planar (2D)")
        # material coordinate s along the circumference: s = R Theta on a round bore; on a
        # worn one the reference curve's arc length from Theta_0, linear within a patch
        # (exact at the nodes), so that ds/dzeta is the patch's length
        if self.wear is None:
            self.starts, self.arcs = self.radius * self.angles, self.radius * self.widths
            self.perimeter = 2 * np.pi * self.radius
        else:
            self.arcs = self._arc_lengths()
            self.starts = self.radius * self.angles[0] + np.concatenate([[0.0], np.cumsum(self.arcs)[:-1]])
            self.perimeter = float(self.arcs.sum())

    def _arc_lengths(self, order: int = 8) -> np.ndarray:
        """The length (m) of each patch of the worn reference curve, int |X0'| dTheta by
        Gauss-Legendre of `order` points."""
        nodes, weights = np.polynomial.legendre.leggauss(order)
        theta = self.angles[:, None] + 0.5 * (1 + nodes[None, :]) * self.widths[:, None]
        e, slope, _ = self.wear(theta.ravel())
        speed = np.hypot(self.radius + e, slope).reshape(theta.shape)
        return 0.5 * self.widths * (speed @ weights)

    def worn(self, theta):
        """The radius beyond `radius` (m) at the angles theta, its slope and curvature: 0 on a
        round bore."""
        if self.wear is None:
            zero = np.zeros_like(theta)
            return zero, zero, zero
        return self.wear(theta)

    def corners(self, k, l):
        """Node indices (n, 2 or 4) of patches (k, l)."""
        m = self.angles.size
        k1 = (k + 1) % m
        if self.dim == 2:
            return np.stack([k, k1], axis=1)
        return np.stack([l * m + k, l * m + k1, (l + 1) * m + k, (l + 1) * m + k1], axis=1)

    def shape(self, zeta):
        """Shape functions N (n, c), their derivatives dN (n, p, c) and ddN (n, p, p, c)."""
        xi = zeta[:, 0]
        if self.dim == 2:
            n = np.stack([1 - xi, xi], axis=1)
            dn = np.broadcast_to(np.array([[-1.0, 1.0]]), (xi.size, 1, 2))
            return n, dn, np.zeros((xi.size, 1, 1, 2))
        eta = zeta[:, 1]
        n = np.stack([(1 - xi) * (1 - eta), xi * (1 - eta), (1 - xi) * eta, xi * eta], axis=1)
        dn = np.stack([np.stack([-(1 - eta), 1 - eta, -eta, eta], axis=1),
                       np.stack([-(1 - xi), -xi, 1 - xi, xi], axis=1)], axis=1)
        ddn = np.zeros((xi.size, 2, 2, 4))
        ddn[:, 0, 1] = ddn[:, 1, 0] = [1.0, -1.0, -1.0, 1.0]
        return n, dn, ddn

    def reference(self, k, l, zeta):
        """The undeformed surface X0 (n, d) and its derivatives (n, p, d), (n, p, p, d)."""
        width = self.widths[k]
        theta = self.angles[k] + zeta[:, 0] * width
        e_r = np.stack([np.cos(theta), np.sin(theta)], axis=1)
        e_t = np.stack([-e_r[:, 1], e_r[:, 0]], axis=1)
        if self.dim == 2:   # X0 = r(Theta) e_r, r = R + e(Theta) (a round bore: e = 0)
            e, slope, curve = self.worn(theta)
            r = self.radius + e
            x0 = r[:, None] * e_r
            dx0 = ((r * width)[:, None] * e_t + (slope * width)[:, None] * e_r)[:, None, :]
            ddx0 = (((curve - r) * width**2)[:, None] * e_r
                    + (2 * slope * width**2)[:, None] * e_t)[:, None, None, :]
            return x0, dx0, ddx0
        height = np.diff(self.levels)[l]
        z = self.levels[l] + zeta[:, 1] * height
        if self.relief is None:
            delta = slope = curve = np.zeros_like(z)
        else:
            delta, slope, curve = self.relief.profile(z, self.levels[0], self.end)
        r = self.radius + delta
        zero, one = np.zeros_like(z)[:, None], np.ones_like(z)[:, None]

        def lift(v, axial):
            return np.concatenate([v, axial], axis=1)

        x0 = lift(r[:, None] * e_r, z[:, None])
        d_xi = lift((r * width)[:, None] * e_t, zero)
        d_eta = lift((height * slope)[:, None] * e_r, height[:, None] * one)
        dd_xixi = lift(-(r * width**2)[:, None] * e_r, zero)
        dd_xieta = lift((width * height * slope)[:, None] * e_t, zero)
        dd_etaeta = lift((height**2 * curve)[:, None] * e_r, zero)
        dx0 = np.stack([d_xi, d_eta], axis=1)
        ddx0 = np.stack([np.stack([dd_xixi, dd_xieta], 1), np.stack([dd_xieta, dd_etaeta], 1)], 1)
        return x0, dx0, ddx0

    def curvature_radius(self, y, dy, ddy) -> np.ndarray:
        """The bore's radius of curvature (m) at points Y of its patches (2D), with their
        derivatives: |Y| on a round bore (its radius, to the bore's strain); on a worn one
        the deformed patch's own, |Y'|^3 / (Y' x Y'') (negative where the worn bore bulges
        towards the pin, inf where it is straight)."""
        if self.wear is None:
            return np.linalg.norm(y[:, :2], axis=1)
        d1, d2 = dy[:, 0], ddy[:, 0, 0]
        cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
        with np.errstate(divide="ignore"):
            return np.linalg.norm(d1, axis=1) ** 3 / cross

    def point(self, k, l, zeta):
        """Y (n, d), Y_,a (n, p, d), Y_,ab (n, p, p, d) and N (n, c), dN (n, p, c) on patches
        (k, l) at the surface coordinates zeta (n, p)."""
        x0, dx0, ddx0 = self.reference(k, l, zeta)
        n, dn, ddn = self.shape(zeta)
        u = self.displacement[self.corners(k, l)]                 # (n, c, d)
        return (x0 + np.einsum("nc,ncd->nd", n, u), dx0 + np.einsum("npc,ncd->npd", dn, u),
                ddx0 + np.einsum("npqc,ncd->npqd", ddn, u), n, dn)

    def position(self, k, l, zeta, previous):
        """Material coordinates s (n, p) of surface points: arc length R Theta (a worn bore:
        the reference curve's, linear within a patch; unwrapped next to `previous`) and, in
        3D, the axial position z (m)."""
        s = self.starts[k] + zeta[:, 0] * self.arcs[k]
        period = self.perimeter
        s = s - period * np.round((s - previous[:, 0]) / period)
        if self.dim == 2:
            return s[:, None]
        return np.stack([s, self.levels[l] + zeta[:, 1] * np.diff(self.levels)[l]], axis=1)

    def metric(self, k, l):
        """d s / d zeta (n, p): R dTheta_k, a worn bore's patch length (and dZ_l)."""
        arc = self.arcs[k]
        if self.dim == 2:
            return arc[:, None]
        return np.stack([arc, np.diff(self.levels)[l]], axis=1)


@dataclass
class Projection:
    """Closest points: patch (k, l), surface coordinates zeta (n, p), and whether the point
    lies on the bore (False beyond its ends)."""

    k: np.ndarray
    l: np.ndarray
    zeta: np.ndarray
    inside: np.ndarray

    def take(self, index):
        return Projection(*(getattr(self, f.name)[index] for f in fields(self)))


def closest_point(x: np.ndarray, bore: BoreSurface, newton_steps: int = 4, hops: int = 8,
                  held: np.ndarray | None = None, band: float = 0.0):
    """The closest bore point to each x (n, d), a Projection. With `held` (a patch index k per
    point, from the last projection), each point starts on its held patch and leaves it only
    when its closest point lies more than `band` of the patch beyond its edges (hysteresis:
    PinBoreContact.hold_patches)."""
    k, xi = bracket(np.arctan2(x[:, 1], x[:, 0]), bore.angles)
    if held is not None:
        k = held.copy()
        xi = np.zeros_like(xi)
    if bore.dim == 2:
        l, zeta = np.zeros_like(k), xi[:, None]
    else:
        top = bore.levels.size - 2
        l = np.clip(np.searchsorted(bore.levels, x[:, 2], side="right") - 1, 0, top)
        zeta = np.stack([xi, (x[:, 2] - bore.levels[l]) / np.diff(bore.levels)[l]], axis=1)
    m = bore.angles.size
    for _ in range(hops):
        for _ in range(newton_steps):
            y, dy, ddy, _, _ = bore.point(k, l, zeta)
            r = x - y
            f = np.einsum("nd,npd->np", r, dy)
            a = np.einsum("npd,nqd->npq", dy, dy) - np.einsum("nd,npqd->npq", r, ddy)
            zeta = zeta + np.linalg.solve(a, f[..., None])[..., 0]
        below, above = zeta[:, 0] < -band, zeta[:, 0] > 1 + band
        k = np.where(below, (k - 1) % m, np.where(above, (k + 1) % m, k))
        zeta[:, 0] = np.where(below, 1.0, np.where(above, 0.0, zeta[:, 0]))
        moved = below | above
        if bore.dim == 3:
            down, up = (zeta[:, 1] < 0) & (l > 0), (zeta[:, 1] > 1) & (l < top)
            l = np.where(down, l - 1, np.where(up, l + 1, l))
            zeta[:, 1] = np.where(down, 1.0, np.where(up, 0.0, zeta[:, 1]))
            moved |= down | up
        if not moved.any():
            break
    inside = np.ones(len(x), dtype=bool)
    zeta[:, 0] = np.clip(zeta[:, 0], -band, 1.0 + band)
    if bore.dim == 3:
        # Past the bore's ends the end patches continue smoothly (a pin node that moves a
        # little beyond the end keeps its contact; cutting it off there made Newton cycle);
        # further than bore.continuation of the end layer, the node is out of contact.
        c = bore.continuation
        inside = (zeta[:, 1] >= -c) & (zeta[:, 1] <= 1 + c)
        zeta[:, 1] = np.clip(zeta[:, 1], -c, 1 + c)
    return Projection(k, l, zeta, inside)


@dataclass
class Kinematics:
    """Pin positions x, closest points, gaps g (m, +inf beyond the bore's ends), outward
    normals nu, circumferential unit tangents t, radii of curvature rho (m), and at the
    closest points Y, its derivatives and the shape functions."""

    x: np.ndarray
    projection: Projection
    gap: np.ndarray
    normal: np.ndarray
    tangent: np.ndarray
    rho: np.ndarray
    y: np.ndarray
    dy: np.ndarray
    ddy: np.ndarray
    n: np.ndarray
    dn: np.ndarray

    def take(self, index):
        """The same quantities at a subset of the nodes."""
        return Kinematics(*(getattr(self, f.name)[index] if f.name != "projection"
                            else self.projection.take(index) for f in fields(self)))


def kinematics(x: np.ndarray, bore: BoreSurface, held: np.ndarray | None = None,
               band: float = 0.0) -> Kinematics:
    """Project the pin nodes x (n, d) onto the bore (closest_point: `held` patches and their
    `band`) and measure gaps and normals."""
    proj = closest_point(x, bore, held=held, band=band)
    y, dy, ddy, n, dn = bore.point(proj.k, proj.l, proj.zeta)
    if bore.dim == 2:
        nu = np.stack([dy[:, 0, 1], -dy[:, 0, 0]], axis=1)
    else:
        nu = np.cross(dy[:, 0], dy[:, 1])
    nu /= np.linalg.norm(nu, axis=1)[:, None]
    t = dy[:, 0] / np.linalg.norm(dy[:, 0], axis=1)[:, None]
    g = np.where(proj.inside, np.einsum("nd,nd->n", y - x, nu), np.inf)
    rho = (bore.curvature_radius(y, dy, ddy) if bore.dim == 2
           else np.linalg.norm(y[:, :2], axis=1))
    return Kinematics(x, proj, g, nu, t, rho, y, dy, ddy, n, dn)


def slip_gradient(kin: Kinematics, bore: BoreSurface) -> np.ndarray:
    """ds/dU (n, p, (1 + c) d) of the material coordinates s of the closest points over
    (pin node, bore corner nodes), from the closest-point conditions (x - Y) . Y_,a = 0."""
    r = kin.x - kin.y
    a = np.einsum("npd,nqd->npq", kin.dy, kin.dy) - np.einsum("nd,npqd->npq", r, kin.ddy)
    pin = kin.dy[:, :, None, :]                                               # (n, p, 1, d)
    corners = (-np.einsum("nc,npd->npcd", kin.n, kin.dy)
               + np.einsum("npc,nd->npcd", kin.dn, r))                        # (n, p, c, d)
    df = np.concatenate([pin, corners], axis=2).reshape(len(r), a.shape[1], -1)
    proj = kin.projection
    return bore.metric(proj.k, proj.l)[:, :, None] * np.linalg.solve(a, df)


def pressure(lam, penalty, g):
    """Nodal contact pressure p = <lambda - eps g> (Pa)."""
    return np.maximum(lam - penalty * g, 0.0)


def active_set(trial, bound, p, status, direction):
    """Shear (n, p) (Pa) and state of each node at an iterate, given the active set of the
    last one (status, slip direction) and the slip bound mu p (Pa).

    The primal-dual active-set rule of Hueber, Stadler & Wohlmuth (2008): a node that was
    slipping keeps slipping (shear = bound * trial/|trial|) while |trial| exceeds the bound
    and trial does not turn back against its slip direction (by more than 90 deg), and
    sticks otherwise (in 2D: a node never slips back in one iterate); any other node in
    contact sticks if |trial| <= bound and slips if not; a node with p = 0 is open. A
    converged state is the backward-Euler return map.
    """
    size = np.linalg.norm(trial, axis=1)
    slipping = (status == SLIP) & (np.abs(direction).sum(axis=1) > 0)
    keeps = slipping & (size >= bound) & (np.einsum("np,np->n", trial, direction) > 0)
    stuck = np.where(slipping, ~keeps, size <= bound) & (bound > 0)
    unit = trial / np.maximum(size, np.finfo(float).tiny)[:, None]
    shear = np.where((p > 0)[:, None], np.where(stuck[:, None], trial, bound[:, None] * unit), 0.0)
    return shear, np.where(p > 0, np.where(stuck, STICK, SLIP), OPEN)


OPEN, STICK, SLIP = 0, 1, 2
STATE_NAMES = ("open", "stick", "slip")
TANGENTIAL_PENALTY_RATIO = 1.0  # eps_T / eps
ACTIVE_SET_UPDATES = 5          # per Newton solve (see PinBoreContact.start_solve)
HELD_BAND = 0.05                # of a patch: how far a held projection may run past its edge


@dataclass
class Friction:
    """Coulomb friction at the pin nodes: coefficient, tangential penalty (Pa/m), the
    converged state n (bore coordinates s_n (m), shear sigma_n (Pa), both (n, p)), the
    multiplier Lambda (= sigma_n with the penalty method), and the active set of the current
    Newton iterate: the state and slip direction of each node."""

    mu: float
    penalty: float
    s_n: np.ndarray
    sigma_n: np.ndarray
    multiplier: np.ndarray
    status: np.ndarray
    direction: np.ndarray

    @classmethod
    def at_rest(cls, mu, penalty, n, p):
        zero = np.zeros((n, p))
        return cls(mu, penalty, zero, zero.copy(), zero.copy(), np.full(n, OPEN), zero.copy())

    def trial(self, s):
        return self.multiplier + self.penalty * (s - self.s_n)

    def freeze(self, state) -> None:
        size = np.linalg.norm(state.shear, axis=1)
        self.status = state.status.copy()
        self.direction = state.shear / np.maximum(size, np.finfo(float).tiny)[:, None]

    def settled(self, state) -> bool:
        """The iterate's active set is the one the return map gives at the solution."""
        return bool(np.array_equal(state.status, self.status))

    def saved(self):
        return tuple(a.copy() for a in (self.s_n, self.sigma_n, self.status, self.direction))

    def load(self, saved) -> None:
        self.s_n, self.sigma_n, self.status, self.direction = (a.copy() for a in saved)
        self.multiplier = self.sigma_n.copy()


# --- the two surfaces of a mesh and the assembly of the contact terms --------------------------

@dataclass
class ContactState:
    """What one evaluation found at the pin nodes (arrays over pin nodes, sorted by level and
    angle)."""

    gap: np.ndarray        # m
    pressure: np.ndarray   # Pa
    angle: np.ndarray      # rad, current polar angle of the node
    position: np.ndarray   # m, (n, p) material coordinates s of the closest bore point
    shear: np.ndarray      # Pa, (n, p) on the bore along +theta (and +z) (0 without friction)
    status: np.ndarray     # OPEN, STICK or SLIP
    slip: np.ndarray       # m, (n, p) plastic slip of this step, (sigma_trial - sigma) / eps_T
    normal: np.ndarray     # (n, d) outward unit normal of the bore at the closest point

    def dissipated(self, weights) -> float:
        """Work dissipated by friction over the step (J/m in 2D, J in 3D): sum w sigma . slip
        >= 0."""
        return float(np.sum(weights * np.einsum("np,np->n", self.shear, self.slip)))

    def stored(self, weights, penalty: float, tangential_penalty: float = 0.0) -> float:
        """Energy held by the penalty springs (J/m in 2D, J in 3D): sum w (eps <-g>^2 +
        |sigma|^2 / eps_T) / 2, the normal penetration and the regularised stick (its shear
        sigma = eps_T times the elastic part of the tangential displacement)."""
        normal = penalty * np.maximum(-self.gap, 0.0) ** 2
        if tangential_penalty > 0:
            normal = normal + np.einsum("np,np->n", self.shear, self.shear) / tangential_penalty
        return float(np.sum(weights * normal) / 2)


class PinBoreContact:
    """Contact terms between the pin-surface and bore-surface nodes of a P1 vector space.

    pin_dofs / bore_dofs: local block (node) indices in V owned by this rank. Every rank
    holds both surfaces whole: pin_X, pin_nodes (global node indices), weights (tributary
    lengths or areas), the bore's grid, the multipliers lam and, with mu > 0, the friction
    state. 3D: `bore_end` is the bore's far end (m), `relief` its edge relief, `pin_frame`
    a rotation (3, 3) about the point (0, 0, pivot) that tilts the pin (its inverse takes
    the pin's nodes back onto their grid of angles and levels), and `pin_runs_on` says that
    the pin runs on beyond the bore's ends.
    """

    def __init__(self, V, pin_dofs, bore_dofs, bore_radius, penalty, template: PETSc.Vec,
                 friction: float = 0.0, relief: Relief | None = None, bore_end=None,
                 pin_frame=None, pivot: float = 0.0, pin_runs_on: bool = False,
                 bore_wear: Callable | None = None):
        self.comm = V.mesh.comm
        self.penalty = penalty
        self.dim = dim = V.mesh.geometry.dim
        coords = V.tabulate_dof_coordinates()[:, :dim]
        imap = V.dofmap.index_map
        (pin_X, pin_nodes), (bore_X, bore_nodes) = [
            self._gather(coords[d], imap.local_to_global(d.astype(np.int32)))
            for d in (pin_dofs, bore_dofs)]
        pin_ref = pin_X if pin_frame is None else untilt(pin_X, pin_frame, pivot)
        order_p, pin_grid = grid_order(pin_ref)
        order_b, bore_grid = grid_order(bore_X)
        self.pin_X, self.pin_nodes = pin_X[order_p], pin_nodes[order_p]
        self.pin_reference = pin_ref[order_p]   # untilted: on the grid of angles x levels
        self.pin_grid = pin_grid
        self.weights = tributary_weights(pin_ref[order_p], *pin_grid)
        angles, levels = bore_grid
        self.bore = BoreSurface(bore_radius, angles, np.zeros((len(bore_X), dim)), levels,
                                relief, bore_end if dim == 3 else None,
                                0.05 if pin_runs_on else 0.5, bore_wear)
        rows = np.arange(dim)
        self.pin_rows = (dim * self.pin_nodes[:, None] + rows).astype(PETSc.IntType)
        self.bore_rows = (dim * bore_nodes[order_b][:, None] + rows).astype(PETSc.IntType)
        self.lam = np.zeros(len(self.pin_X))
        self._scatter, self._local = self._make_scatter(template)
        self.friction = (Friction.at_rest(friction, TANGENTIAL_PENALTY_RATIO * penalty,
                                          len(self.pin_X), dim - 1) if friction > 0 else None)
        self.active_set_updates = 0   # left in the current Newton solve (see start_solve)
        self.holding, self.held = False, None   # projection onto held patches (hold_patches)
        self.normal_set = None        # the nodes in contact, once kept (see start_solve)
        self._kinematics_key, self._kinematics_last = None, None   # _kinematics' last

    def couplings(self, direction, half_angle: float, reach: int = 2) -> np.ndarray:
        """Global (row, column) dof pairs that the contact terms may couple and K may not:
        every pin node within half_angle of the load direction with the bore nodes of the
        `reach` patches around its reference closest point, and (3D) those bore nodes with
        the corners of their patches, both ways (for preallocation)."""
        angle = np.arctan2(self.pin_reference[:, 1], self.pin_reference[:, 0])
        near = np.abs(np.remainder(angle - np.arctan2(direction[1], direction[0]) + np.pi,
                                   2 * np.pi) - np.pi) <= half_angle
        k, _ = bracket(angle[near], self.bore.angles)
        m = self.bore.angles.size
        around = (k[:, None] + np.arange(-reach, reach + 2)) % m                     # (n, a)
        if self.dim == 2:
            bore = around
        else:
            levels = self.bore.levels
            l = np.clip(np.searchsorted(levels, self.pin_reference[near, 2]) - 1, 0, levels.size - 2)
            rings = np.clip(l[:, None] + np.arange(-1, 3), 0, levels.size - 1)       # (n, r)
            bore = (rings[:, :, None] * m + around[:, None, :]).reshape(len(k), -1)
        pairs = [(np.repeat(self.pin_rows[near], bore.shape[1], axis=0),
                  self.bore_rows[bore.ravel()])]
        if self.dim == 3:   # the corners of a patch, across its diagonals
            nodes = np.unique(bore)
            k, l = nodes % m, nodes // m
            corner = ((np.clip(l[:, None] + [0, 1, 1, -1], 0, levels.size - 1)) * m
                      + (k[:, None] + [1, 1, -1, 1]) % m)
            pairs.append((np.repeat(self.bore_rows[nodes], 4, axis=0),
                          self.bore_rows[corner.ravel()]))
        d = self.dim
        rows = np.concatenate([np.repeat(a, d, axis=1).ravel() for a, _ in pairs])
        cols = np.concatenate([np.tile(b, d).ravel() for _, b in pairs])
        return np.concatenate([np.stack([rows, cols], 1), np.stack([cols, rows], 1)])

    def mid_section(self) -> np.ndarray:
        """Indices of the pin nodes in the plane section (2D: all; 3D: the level nearest the
        pin's middle, the top level of a half model)."""
        if self.dim == 2:
            return np.arange(len(self.pin_X))
        angles, levels = self.pin_grid
        level = np.argmin(np.abs(levels - self.bore.end / 2))
        return np.arange(level * angles.size, (level + 1) * angles.size)

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
        return values[:n_pin].reshape(-1, self.dim), values[n_pin:].reshape(-1, self.dim)

    def _kinematics(self, u: PETSc.Vec) -> Kinematics:
        """Current pin positions, closest bore points and gaps. Collective (gathers u).
        Newton asks for the residual and then the tangent at the same iterate: the second
        call reuses the first (keyed on the vector and PETSc's count of its changes; not
        while the patches are held, whose projection depends on the last one)."""
        key = (u.handle, u.stateGet())
        if not self.holding and key == self._kinematics_key:
            self.bore.displacement = self._kinematics_last[1]
            return self._kinematics_last[0]
        u_pin, self.bore.displacement = self._surface_displacements(u)
        if not self.holding:
            kin = kinematics(self.pin_X + u_pin, self.bore)
            self._kinematics_key, self._kinematics_last = key, (kin, self.bore.displacement.copy())
            return kin
        kin = kinematics(self.pin_X + u_pin, self.bore, self.held, HELD_BAND)
        self.held = kin.projection.k
        return kin

    def hold_patches(self, on: bool) -> None:
        """Project every pin node, from its next projection on, first onto the bore patch it
        was last projected on, leaving it only beyond HELD_BAND of the patch (on), or afresh
        each time (off, the default). The deformed bore has a kink at each node: a pin node
        close to one, whose closest point lies just past the end of one patch and just before
        the start of the next, can alternate between the two (and their normals) from one
        Newton iterate to the next, and Newton cycles, at any step size (measured: a 2D
        impact at 0.3 m/s, the residual alternating 14.905 / 14.947 N/m, node 36 on patch 36,
        then 37, then 36). Held, the node keeps its patch (extended by the band) and the
        residual is smooth. The steppers hold them only for a step that failed without."""
        self.holding, self.held = on, None

    def _position(self, kin: Kinematics, previous):
        proj = kin.projection
        return self.bore.position(proj.k, proj.l, proj.zeta, previous)

    def state(self, u: PETSc.Vec) -> ContactState:
        return self._state(self._kinematics(u))

    def _state(self, kin: Kinematics) -> ContactState:
        g = kin.gap
        p = pressure(self.lam, self.penalty, g)
        angle = np.arctan2(kin.x[:, 1], kin.x[:, 0])
        f = self.friction
        if f is None:
            zero = np.zeros((len(g), self.dim - 1))
            return ContactState(g, p, angle, zero, zero, np.where(p > 0, SLIP, OPEN), zero,
                                kin.normal)
        s = self._position(kin, f.s_n)
        trial = f.trial(s)
        shear, status = active_set(trial, f.mu * p, p, f.status, f.direction)
        return ContactState(g, p, angle, s, shear, status, (trial - shear) / f.penalty,
                            kin.normal)

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

    def extrapolate(self, earlier, ratio: float, augmented: bool) -> None:
        """Multipliers of the next step from the current ones and those of an `earlier`
        snapshot: lambda and (augmented Lagrangian) Lambda + ratio (Lambda - Lambda_earlier).
        Only the starting values of the Uzawa iteration change, not its solution."""
        lam_0, friction_0 = earlier
        self.lam = np.maximum(self.lam + ratio * (self.lam - lam_0), 0.0)
        if self.friction is not None and augmented:
            f = self.friction
            f.multiplier = f.sigma_n + ratio * (f.sigma_n - friction_0[1])

    def stick_violation(self, state: ContactState) -> float:
        """Largest motion (m) of a stuck node over the step (0 with the penalty method the
        augmented Lagrangian drives it to)."""
        if self.friction is None:
            return 0.0
        moved = np.linalg.norm(state.position - self.friction.s_n, axis=1)
        return float(moved[state.status == STICK].max(initial=0.0))

    def start_solve(self) -> None:
        """With friction, let the next Newton solve update the active sets (stick/slip, and
        the nodes in contact) at its first ACTIVE_SET_UPDATES residual evaluations, then
        keep both: Newton then solves a smooth problem and converges, and a set that was
        still changing (nodes flipping between two states) is settled by the next solve."""
        self.active_set_updates = ACTIVE_SET_UPDATES
        self.normal_set = None

    def friction_settled(self, state: ContactState) -> bool:
        """Whether the last solve's active sets are those of its solution."""
        if self.friction is None:
            return True
        in_contact = self.normal_set is None or np.array_equal(state.pressure > 0, self.normal_set)
        return in_contact and self.friction.settled(state)

    def update_friction(self, state: ContactState) -> None:
        if self.friction is not None:
            self.friction.freeze(state)

    def update_multipliers(self, state: ContactState) -> None:
        """Uzawa: lambda <- p, Lambda <- sigma."""
        self.lam = state.pressure
        if self.friction is not None:
            self.friction.multiplier = state.shear.copy()

    def torque(self, u: PETSc.Vec, centre) -> float:
        """Moment (N m/m in 2D, N m in 3D) about the axis through `centre` (parallel to z)
        that balances the contact tractions on the pin, taken in the current configuration:
        the friction torque the hub applies (the normal tractions pass through the bore's
        axis and contribute only through the offset of the two axes). Collective."""
        kin = self._kinematics(u)
        act, _, residual, _ = self._local_terms(kin, with_tangent=False)
        arm = kin.x[act, :2] - np.asarray(centre)[:2]
        return float(np.sum(arm[:, 0] * residual[:, 1] - arm[:, 1] * residual[:, 0]))

    def _local_terms(self, kin: Kinematics, with_tangent: bool):
        """Active nodes: their indices, global rows (n, (1 + c) d) and residual (n, (1 + c) d)
        [, tangent (n, (1 + c) d, (1 + c) d)]."""
        if self.normal_set is None:
            p = pressure(self.lam, self.penalty, kin.gap)
            act = np.flatnonzero(p > 0)
        else:   # the kept set: its nodes are pressed by lambda - eps g, whatever its sign
            act = np.flatnonzero(self.normal_set & np.isfinite(kin.gap))
            p = np.zeros_like(kin.gap)
            p[act] = self.lam[act] - self.penalty * kin.gap[act]
        if act.size == 0:   # no node in contact (an unloading has opened it): no terms
            width = (1 + (2 if self.dim == 2 else 4)) * self.dim
            return (act, np.zeros((0, width), dtype=self.pin_rows.dtype), np.zeros((0, width)),
                    np.zeros((0, width, width)) if with_tangent else None)
        proj = kin.projection
        corners = self.bore.corners(proj.k[act], proj.l[act])
        rows = np.concatenate([self.pin_rows[act, None], self.bore_rows[corners]], axis=1)
        rows = rows.reshape(len(act), (1 + corners.shape[1]) * self.dim)
        b = np.concatenate([np.ones((len(act), 1)), -kin.n[act]], axis=1)    # x - Y weights
        nu = kin.normal[act]
        grad = -(b[:, :, None] * nu[:, None, :]).reshape(rows.shape)        # dg/dU
        w, pa = self.weights[act], p[act]
        residual = -pa[:, None] * grad
        f = self.friction
        if f is not None:
            sub = kin.take(act)
            grad_s = slip_gradient(sub, self.bore)                            # (n, p, rows)
            trial = f.multiplier[act] + f.penalty * (self._position(sub, f.s_n[act]) - f.s_n[act])
            size = np.linalg.norm(trial, axis=1)
            stuck = f.status[act] == STICK
            unit = np.divide(trial, size[:, None], out=np.zeros_like(trial), where=size[:, None] > 0)
            shear = np.where(stuck[:, None], trial, (f.mu * pa)[:, None] * unit)
            residual += np.einsum("np,npr->nr", shear, grad_s)
        residual *= w[:, None]
        if not with_tangent:
            return act, rows, residual, None
        t = kin.tangent[act]
        curvature = np.einsum("ni,nj->nij", t, t) / kin.rho[act][:, None, None]
        dofs = grad.shape[1]
        tangent = (self.penalty * np.einsum("ni,nj->nij", grad, grad)
                   + np.einsum("n,na,nb,nij->naibj", pa, b, b, curvature).reshape(-1, dofs, dofs))
        if f is not None:
            projector = np.eye(self.dim - 1) - np.einsum("np,nq->npq", unit, unit)
            ratio = np.divide(f.mu * pa, size, out=np.zeros_like(size), where=size > 0)
            slip_ds = f.penalty * ratio[:, None, None] * projector       # 0 in 2D
            d_shear = np.where(stuck[:, None, None],
                               f.penalty * grad_s,
                               -(f.mu * self.penalty) * np.einsum("np,nr->npr", unit, grad)
                               + np.einsum("npq,nqr->npr", slip_ds, grad_s))
            tangent += np.einsum("npr,nps->nrs", grad_s, d_shear)
        return act, rows, residual, tangent * w[:, None, None]

    def add_residual(self, u: PETSc.Vec, F: PETSc.Vec) -> None:
        """F += f_c(u). Collective; call F.assemble() afterwards."""
        kin = self._kinematics(u)
        if self.friction is not None and self.active_set_updates > 0:
            self.active_set_updates -= 1
            self.friction.freeze(self._state(kin))  # the active-set update of this iterate
        elif self.friction is not None and self.normal_set is None:
            self.normal_set = self._state(kin).pressure > 0
        _, rows, residual, _ = self._local_terms(kin, with_tangent=False)
        if self.comm.rank == 0:
            F.setValues(rows.ravel(), residual.ravel(), addv=PETSc.InsertMode.ADD_VALUES)

    def add_tangent(self, u: PETSc.Vec, J: PETSc.Mat) -> np.ndarray:
        """J += K_c(u). Collective; call J.assemble() afterwards. Returns the kind of term
        each pin node adds (OPEN: none; in contact: STICK without friction, else its stick
        or slip status): where two tangents differ."""
        act, rows, _, tangent = self._local_terms(self._kinematics(u), with_tangent=True)
        kind = np.full(len(self.pin_X), OPEN, dtype=np.int8)
        kind[act] = (STICK if self.friction is None
                     else np.where(self.friction.status[act] == STICK, STICK, SLIP))
        if self.comm.rank == 0 and len(rows):
            # all blocks in one call: summed into CSR rows (a call per node cost a third of
            # a 3D solve)
            size = rows.shape[1]
            coo = scipy.sparse.coo_matrix((tangent.ravel(), (np.repeat(rows, size, axis=1).ravel(),
                                                             np.tile(rows, size).ravel())))
            csr = coo.tocsr()
            used = np.flatnonzero(np.diff(csr.indptr))
            csr = csr[used]
            J.setValuesIJV(csr.indptr.astype(PETSc.IntType), csr.indices.astype(PETSc.IntType),
                           csr.data, addv=PETSc.InsertMode.ADD_VALUES,
                           rowmap=used.astype(PETSc.IntType))
        return kind


# --- surface grids and their tributary weights -------------------------------------------------

def untilt(X: np.ndarray, frame: np.ndarray, pivot: float) -> np.ndarray:
    """Points X (n, 3) of the tilted pin taken back by the inverse of the rotation `frame`
    about (0, 0, pivot)."""
    centre = np.array([0.0, 0.0, pivot])
    return (X - centre) @ frame + centre


def grid_order(X: np.ndarray):
    """Order of surface nodes X (n, d) by level, then angle, and the grid: (angles (M,),
    levels (L,) or None in 2D). The nodes of an extruded surface share their angles at every
    level."""
    angle = np.arctan2(X[:, 1], X[:, 0])
    if X.shape[1] == 2:
        order = np.argsort(angle)
        return order, (angle[order], None)
    scale = np.abs(X[:, 2]).max() + 1.0
    levels, level = np.unique(np.round(X[:, 2] / scale, 12), return_inverse=True)
    order = np.lexsort((angle, level))
    per_level = np.bincount(level)
    if np.any(per_level != per_level[0]):
        raise ValueError("the surface nodes do not form a grid of angles x levels")
    first = order[:per_level[0]]
    return order, (angle[first], np.array([X[level == i, 2].mean() for i in range(levels.size)]))


def tributary_lengths(points: np.ndarray) -> np.ndarray:
    """Half the summed lengths of the two edges at each node of a closed polygon (m)."""
    edges = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    return 0.5 * (edges + np.roll(edges, 1))


def tributary_weights(X: np.ndarray, angles, levels) -> np.ndarray:
    """Tributary lengths (2D, m) or areas (3D, m^2) of surface nodes X sorted by grid_order:
    the polygon's tributary lengths times half the two adjacent layers."""
    if levels is None:
        return tributary_lengths(X)
    ring = tributary_lengths(X[:angles.size, :2])
    return (axial_widths(levels)[:, None] * ring[None, :]).ravel()


def axial_widths(levels: np.ndarray) -> np.ndarray:
    """Tributary axial length (m) of each level of a surface grid: half the two adjacent
    layers."""
    layers = np.diff(levels)
    return 0.5 * (np.append(layers, 0.0) + np.insert(layers, 0, 0.0))
