r"""The compiled core of the spatial model: rigid bodies in 3D, ideal joints, clearance joints.

Bodies. Each body has its centre of mass r and Euler parameters p = (e0, e1, e2, e3), |p| = 1
([Nikravesh1988] ch. 6), with the rotation matrix

    A(p) = 2 [(e0^2 - 1/2) I + e e^T + e0 e~],     e = (e1, e2, e3),

and G(p) = [-e, -e~ + e0 I] (3 x 4), so that the angular velocity in the body frame is
w' = 2 G p' and, since G' p' = 0, w'' = 2 G p''. The state holds (r, p) and their rates (7
coordinates a body, the planar model's layout, reduced.spatial_layout). The dynamics are
written in the body velocities v = (r', w), w = A w' global:

    m r'' = m g + F + Phi_r^T lambda_r ...     M v' + D^T lambda = Q(q, v, t),
    J w' + w x (J w) = N,   J = A J' A^T        (Euler's equations, gyroscopic term in Q),
    D v' = gamma - 2 a Phi' - a^2 Phi          (Baumgarte, as the planar model),

D the constraint Jacobian against v, lambda from the Schur system (D M^-1 D^T) lambda =
D M^-1 Q - gamma~, M = diag(m I, J) block-diagonal with an explicit inverse. The Euler
parameters then follow from p'' = G^T w''/2 + k p, where G^T G = I - p p^T leaves the
component along p to the normalisation constraint (p^T p - 1)/2 = 0: p^T p'' = -p'^T p' (and
its Baumgarte terms), Nikravesh's augmented formulation reduced to the body velocities. After
every accepted step the parameters are normalised and the positions and velocities projected
onto the constraints (one mass-weighted Gauss-Newton step each, as the planar model), so
neither drift accumulates.

Ideal joints are built of primitive constraints ([Nikravesh1988] ch. 7): a point of body i on
a point of body j (3 rows), a vector of i normal to a vector of j (dot-1), a vector of i
normal to the line between two points (dot-2); a spherical joint is one point, a universal
one point and a dot-1 (the cross axes stay normal), a revolute one point and two dot-1, a
cylindrical two dot-1 and two dot-2, a prismatic the cylindrical plus a dot-1 that stops the
rotation about the axis, a fixed joint a point and three dot-1. The drive prescribes the
relative angle about a joint's axis, theta = atan2(c_i . b_j, a_i . b_j) = angle0 + omega t,
with c_i = u_i x a_i. Each row gives its value, its Jacobian against (r'_k, w_k), its
explicit time rate and gamma, the velocity terms of its second derivative with the sign
changed: for a body point P = r + s, P'' = r'' + w' x s + w x (w x s); for a body vector a,
a'' = w' x a + w x (w x a).

Clearance joints (continuous contact only):
- cylindrical: a journal (axis u_j through the point P_j) in a bore of length L (axis u_b
  through its mid-plane centre P_b, radius R_b, clearance c = R_b - R_j). The bore is cut
  into n slices (pinbore.laws.sliced.slice_geometry: offset z_i from the mid-plane, weight
  w_i = L/n + e at each end slice). At slice i the journal's axis point X_i = P_j + z_i u_j
  has the eccentricity e_i = X_i - P_b - z_i u_b; its component across the bore has length
  |e_i^perp|, the normal n_i = e_i^perp/|e_i^perp| and the penetration delta_i = |e_i^perp|
  - c. A journal tilted by theta in the plane of its eccentricity e0 gives exactly
  delta_i = (e0 - c) + sin(theta) z_i: the sliced law (pinbore.laws.sliced) with its
  small-angle tilt read as sin(theta). Each slice carries a (f_el(delta_i) (1 + chi
  delta_i'/v0)) w_i, a the law's stiffness factor, f_el the per-length law (N/m, a table of
  pinbore.laws.tables), chi the hysteresis factor ([LankaraniNikravesh1990] and the Hunt-
  Crossley family of pinbore.laws.dissipative, hysteresis_force; damping_law = "calibrated":
  the chi that rebounds with the laws file's e(v0) at the channel's impact speed, the
  planar kernel's joint_chi), v0 the approach rate when the joint's radial contact began. The force -f n_i acts on the journal at X_i and +f n_i on
  the bore at B_i = X_i - e_i^perp, its point on the bore's axis: delta_i' = n_i . (v_J(X_i)
  - v_B(B_i)) exactly, so the forces do the work of the law, and X_i - B_i is along n_i, so
  the pair has no moment. Friction of the static laws of pinbore.laws.friction (the
  regularised Coulomb [Ambrosio2003], Stribeck, linear) acts at the contact point
  C_i = B_i + R_b n_i against the slip there (the relative velocity of the journal's and the
  bore's material points, less its normal part), on both bodies at the same point.
  Bulk compliance (a sliced law with c_b > 0, pinbore.laws.sliced "The section in 2D"): the
  slices carry the law's local part and the bore's axis moves across by d, the root of
  d = c_b F(d) / L with F the slices' resultant, solved per evaluation in the bore's section
  (laws.sliced.bore_displacement: e_i^perp = a0 + z_i a1, a0 = perp(P_j - P_b),
  a1 = perp(u_j - u_b)); the slices then see e_i^perp - d, act at B_i = X_i - (e_i^perp - d)
  on the bore, and their rate is taken at fixed d (d is in equilibrium, so the law's energy
  changes by the slices' work alone, and an aligned journal gets the planar law's force and
  damping exactly). |e_i^perp| is convex in z_i, so the deepest slice is an end slice: the
  onsets look at the two end slices, and a joint whose end slices are free skips the slice
  loop.
  Shoulders (the project's own law; no source is cited for it): with an axial clearance c_a
  the journal point's axial offset s = (P_j - P_b) . u_b is free within |s| <= c_a; beyond,
  a linear penalty k_a (|s| - c_a) with the joint's hysteresis factor pushes it back along
  u_b, acting at P_j on both bodies (again exactly the work of the law, no moment); a
  calibrated joint's shoulders take chi of its e(v0) at the axial impact speed (the FE
  impacts were radial: for the shoulders' faces that e is unverified).
- spherical: a ball (centre P_j) in a socket (centre P_s), delta = |P_j - P_s| - c, the Hertz
  point law of pinbore.laws.elastic (hertz_point) with the damping and friction above
  ([FloresLankarani2010]; [Tian2009]), acting at the contact point P_s + R_b n.
Each joint has two contact channels (radial or spherical; axial), whose onsets the
integrator locates as the planar model does (no law is evaluated in free flight: a channel
whose deepest point is out of contact adds nothing) and whose impact speeds it records.

Torsion elements act on the relative angle about a body-fixed axis, measured like the drive:
springs, stops and latches with the planar model's law (reduced.kernel.torsion_law).
The integrators are reduced.integrator's: this module overloads its hooks for SpatialArgs.
The body states sit in one array (spatial_layout.BODY_*), which the helpers take, and row
arrays are read in place: every array a compiled helper reads out of a bundle, or a row view
it makes, has its references counted, which had made the right-hand side several times
slower. Measured on the Flores slider-crank: 4.4 us a right-hand side with the step's work,
3.6 times the planar kernel (README, Spatial model).
"""

import math

import numba
import numpy as np
from numba.extending import overload

from pinbore.core.compiled import follow_compiled_in
from pinbore.laws import dissipative, friction, sliced, tables
from pinbore.reduced import integrator, kernel, layout, spatial_layout
from pinbore.reduced.integrator import log_impact
from pinbore.reduced.kernel import LATCH_TOL, cholesky_solve, joint_chi, joint_friction, torsion_law
from pinbore.reduced.layout import (
    DISSIPATED, JOINT_BEARING_RADIUS, JOINT_CLEARANCE, JOINT_FRICTION_LAW, LATCH, NO_FRICTION, TORSION_BODY_I,
    TORSION_BODY_J, TORSION_FREE_ANGLE, TORSION_KIND, WORK_IN, Contacts)
from pinbore.reduced.spatial_layout import (
    ANGLE, AXIAL, BODY_COLUMNS, BODY_JINV, BODY_OMEGA, BODY_POS, BODY_ROT, BODY_VEL, CHANNELS, CYLINDER, DOT1, DOT2, POINT, PRIM_A_I, PRIM_ANGLE0, PRIM_B_J,
    PRIM_BODY_I, PRIM_BODY_J, PRIM_C_I, PRIM_KIND, PRIM_S_I, PRIM_S_J, PRIM_SPEED,
    PRIMITIVE_ROWS, RADIAL, SJ_COMPLIANCE,
    SJ_AXIAL_CLEARANCE, SJ_AXIAL_STIFFNESS, SJ_BEARING_AXIS, SJ_BEARING_BODY, SJ_BEARING_POINT,
    SJ_END_LENGTH, SJ_JOURNAL_AXIS, SJ_JOURNAL_BODY, SJ_JOURNAL_POINT, SJ_KIND, SJ_LENGTH,
    SJ_SCALE, SJ_SLICES, TORSION_A_I, TORSION_B_J, TORSION_C_I, Depth, SpatialArgs, SpatialWork)


# ---- small vectors as tuples (no allocation)
@numba.njit(cache=True)
def vec(a, i):
    return (a[i], a[i + 1], a[i + 2])


@numba.njit(cache=True)
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@numba.njit(cache=True)
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@numba.njit(cache=True)
def scaled(a, k):
    return (k * a[0], k * a[1], k * a[2])


@numba.njit(cache=True)
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@numba.njit(cache=True)
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@numba.njit(cache=True)
def matvec(m, b, a):
    """m[b] a, the 3 x 3 matrix b of a stack m read in place (a view would count references)."""
    return (m[b, 0, 0] * a[0] + m[b, 0, 1] * a[1] + m[b, 0, 2] * a[2],
            m[b, 1, 0] * a[0] + m[b, 1, 1] * a[1] + m[b, 1, 2] * a[2],
            m[b, 2, 0] * a[0] + m[b, 2, 1] * a[1] + m[b, 2, 2] * a[2])


# ---- Euler parameters
@numba.njit(cache=True)
def rotation(p, out):
    """A(p) into out (3 x 3) for unit p = (e0, e1, e2, e3)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    out[0, 0], out[0, 1], out[0, 2] = e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2
    out[1, 0], out[1, 1], out[1, 2] = e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1
    out[2, 0], out[2, 1], out[2, 2] = e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5
    out *= 2.0


@numba.njit(cache=True)
def g_times(p, pd):
    """G(p) p' (3)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return (-e1 * pd[0] + e0 * pd[1] + e3 * pd[2] - e2 * pd[3],
            -e2 * pd[0] - e3 * pd[1] + e0 * pd[2] + e1 * pd[3],
            -e3 * pd[0] + e2 * pd[1] - e1 * pd[2] + e0 * pd[3])


@numba.njit(cache=True)
def gt_times(p, w):
    """G(p)^T w (4)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return (-e1 * w[0] - e2 * w[1] - e3 * w[2], e0 * w[0] - e3 * w[1] + e2 * w[2],
            e3 * w[0] + e0 * w[1] - e1 * w[2], -e2 * w[0] + e1 * w[1] + e0 * w[2])


@numba.njit(cache=True)
def unit_parameters(q, b):
    """The Euler parameters of body b, normalised (4-tuple)."""
    i = 7 * b + 3
    n = math.sqrt(q[i] ** 2 + q[i + 1] ** 2 + q[i + 2] ** 2 + q[i + 3] ** 2)
    return (q[i] / n, q[i + 1] / n, q[i + 2] / n, q[i + 3] / n)


@numba.njit(cache=True)
def body_states(y, args, work):
    """Position, rotation matrix, velocity, global angular velocity w = A 2 G p' and global
    inverse inertia A J'^-1 A^T of every body into the workspace's body rows
    (spatial_layout.BODY_*: one array, so that the helpers that read them take one array)."""
    nq = args.nq
    bodies, inertia_inv = work.bodies, args.inertia_inv
    for b in range(bodies.shape[0]):
        p = unit_parameters(y, b)
        e0, e1, e2, e3 = p
        a = ((e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2),
             (e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1),
             (e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5))
        for r in range(3):
            for c in range(3):
                bodies[b, BODY_ROT + 3 * r + c] = 2.0 * a[r][c]
        w_body = scaled(g_times(p, vec(y, nq + 7 * b + 3) + (y[nq + 7 * b + 6],)), 2.0)
        w = turned(bodies, b, w_body)
        for k in range(3):
            bodies[b, BODY_POS + k] = y[7 * b + k]
            bodies[b, BODY_VEL + k] = y[nq + 7 * b + k]
            bodies[b, BODY_OMEGA + k] = w[k]
        for r in range(3):       # A J'^-1 A^T written out: a 3 x 3 matmul allocates
            ar = row3(bodies, b, BODY_ROT + 3 * r)
            t0 = ar[0] * inertia_inv[b, 0, 0] + ar[1] * inertia_inv[b, 1, 0] + ar[2] * inertia_inv[b, 2, 0]
            t1 = ar[0] * inertia_inv[b, 0, 1] + ar[1] * inertia_inv[b, 1, 1] + ar[2] * inertia_inv[b, 2, 1]
            t2 = ar[0] * inertia_inv[b, 0, 2] + ar[1] * inertia_inv[b, 1, 2] + ar[2] * inertia_inv[b, 2, 2]
            for c in range(r + 1):
                ac = row3(bodies, b, BODY_ROT + 3 * c)
                v = t0 * ac[0] + t1 * ac[1] + t2 * ac[2]
                bodies[b, BODY_JINV + 3 * r + c] = bodies[b, BODY_JINV + 3 * c + r] = v


@numba.njit(cache=True)
def row3(rows, b, k):
    """Three entries of row b of a 2D array from column k."""
    return (rows[b, k], rows[b, k + 1], rows[b, k + 2])


@numba.njit(cache=True)
def block_times(bodies, b, k, a):
    """The 3 x 3 block of body b's row from column k (row-major) times a."""
    return (dot(row3(bodies, b, k), a), dot(row3(bodies, b, k + 3), a),
            dot(row3(bodies, b, k + 6), a))


@numba.njit(cache=True)
def turned(bodies, b, a):
    """A a: a body-frame vector of body b in global axes."""
    return block_times(bodies, b, BODY_ROT, a)


@numba.njit(cache=True)
def unturned(bodies, b, a):
    """A^T a: a global vector in body b's axes."""
    return add(add(scaled(row3(bodies, b, BODY_ROT), a[0]), scaled(row3(bodies, b, BODY_ROT + 3), a[1])),
               scaled(row3(bodies, b, BODY_ROT + 6), a[2]))


@numba.njit(cache=True)
def inverse_inertia_times(bodies, b, a):
    """A J'^-1 A^T a (global)."""
    return block_times(bodies, b, BODY_JINV, a)


@numba.njit(cache=True)
def point_state(bodies, b, s_body):
    """A body point s' (the ground: a global point): (P, its velocity, w x (w x s), s = A s'
    the arm from the centre of mass)."""
    if b < 0:
        return s_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    s = turned(bodies, b, s_body)
    w = row3(bodies, b, BODY_OMEGA)
    ws = cross(w, s)
    return (add(row3(bodies, b, BODY_POS), s), add(row3(bodies, b, BODY_VEL), ws), cross(w, ws),
            s)


@numba.njit(cache=True)
def vector_state(bodies, b, a_body):
    """A body vector a' (the ground: global): (a = A a', a' rate w x a, w x (w x a))."""
    if b < 0:
        return a_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    a = turned(bodies, b, a_body)
    w = row3(bodies, b, BODY_OMEGA)
    wa = cross(w, a)
    return a, wa, cross(w, wa)


@numba.njit(cache=True)
def material_velocity(bodies, b, x):
    """Velocity (global) of the material point of body b at the global point x."""
    if b < 0:
        return (0.0, 0.0, 0.0)
    return add(row3(bodies, b, BODY_VEL),
               cross(row3(bodies, b, BODY_OMEGA), sub(x, row3(bodies, b, BODY_POS))))


@numba.njit(cache=True)
def put(jac, row, b, linear, angular, sign):
    """Add sign (linear, angular) to the Jacobian columns (r', w) of body b."""
    if b < 0:
        return
    for k in range(3):
        jac[row, 6 * b + k] += sign * linear[k]
        jac[row, 6 * b + 3 + k] += sign * angular[k]


ZERO = (0.0, 0.0, 0.0)


@numba.njit(cache=True)
def dot1(bodies, bi, a_body, bj, b_body):
    """a_i . b_j: (value, coefficient k of w_i (-k: w_j), rate, velocity part of its second
    derivative)."""
    a, ad, ac = vector_state(bodies, bi, a_body)
    b, bd, bc = vector_state(bodies, bj, b_body)
    return dot(a, b), cross(a, b), dot(ad, b) + dot(a, bd), dot(ac, b) + 2 * dot(ad, bd) + dot(a, bc)


@numba.njit(cache=True)
def constraint_count(primitives):
    m = 0
    for k in range(primitives.shape[0]):
        m += 3 if int(primitives[k, PRIM_KIND]) == POINT else 1
    return m


@numba.njit(cache=True)
def fill_constraints(t, work, primitives, alpha):
    """Jacobian D (against (r'_k, w_k)), Phi, Phi_t and gamma - 2 a Phi' - a^2 Phi into the
    workspace (body states current). Returns the number of rows."""
    jac, phi, phi_t, rhs_c, row_bodies = work.jac, work.phi, work.phi_t, work.rhs_c, work.row_bodies
    bodies = work.bodies
    for i in range(jac.shape[0]):   # the rows' bodies' columns (the others stay zero)
        for side in range(2):
            b = row_bodies[i, side]
            if b >= 0:
                for c in range(6 * b, 6 * b + 6):
                    jac[i, c] = 0.0
    row = 0
    for k in range(primitives.shape[0]):
        # entries read in place: a row view of `primitives` would count its references
        kind, bi, bj = (int(primitives[k, PRIM_KIND]), int(primitives[k, PRIM_BODY_I]),
                        int(primitives[k, PRIM_BODY_J]))
        if kind == POINT:
            pi, _, ci, si = point_state(bodies, bi, row3(primitives, k, PRIM_S_I))
            pj, _, cj, sj = point_state(bodies, bj, row3(primitives, k, PRIM_S_J))
            for c in range(3):
                unit = (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0, 1.0 if c == 2 else 0.0)
                put(jac, row + c, bi, unit, cross(si, unit), 1.0)
                put(jac, row + c, bj, unit, cross(sj, unit), -1.0)
                phi[row + c], phi_t[row + c], rhs_c[row + c] = pi[c] - pj[c], 0.0, cj[c] - ci[c]
            row += 3
            continue
        if kind == DOT1:
            value, coefficient, _, acc = dot1(bodies, bi, row3(primitives, k, PRIM_A_I), bj, row3(primitives, k, PRIM_B_J))
            put(jac, row, bi, ZERO, coefficient, 1.0)
            put(jac, row, bj, ZERO, coefficient, -1.0)
            phi[row], phi_t[row], rhs_c[row] = value, 0.0, -acc
        elif kind == DOT2:
            a, ad, ac = vector_state(bodies, bi, row3(primitives, k, PRIM_A_I))
            pi, vi, ci, si = point_state(bodies, bi, row3(primitives, k, PRIM_S_I))
            pj, vj, cj, sj = point_state(bodies, bj, row3(primitives, k, PRIM_S_J))
            d, dd = sub(pj, pi), sub(vj, vi)
            put(jac, row, bi, scaled(a, -1.0), cross(a, add(d, si)), 1.0)
            put(jac, row, bj, a, cross(sj, a), 1.0)
            phi[row], phi_t[row] = dot(a, d), 0.0
            rhs_c[row] = -(dot(ac, d) + 2 * dot(ad, dd) + dot(a, sub(cj, ci)))
        else:   # ANGLE: theta = atan2(s, c) = angle0 + speed t
            c_, kc, cd, cacc = dot1(bodies, bi, row3(primitives, k, PRIM_A_I), bj, row3(primitives, k, PRIM_B_J))
            s_, ks, sd, sacc = dot1(bodies, bi, row3(primitives, k, PRIM_C_I), bj, row3(primitives, k, PRIM_B_J))
            rho2 = s_ * s_ + c_ * c_
            coefficient = scaled(sub(scaled(ks, c_), scaled(kc, s_)), 1.0 / rho2)
            put(jac, row, bi, ZERO, coefficient, 1.0)
            put(jac, row, bj, ZERO, coefficient, -1.0)
            rate = (c_ * sd - s_ * cd) / rho2
            gap = math.atan2(s_, c_) - primitives[k, PRIM_ANGLE0] - primitives[k, PRIM_SPEED] * t
            phi[row] = gap - 2 * math.pi * math.floor(gap / (2 * math.pi) + 0.5)
            phi_t[row] = -primitives[k, PRIM_SPEED]
            rhs_c[row] = -(c_ * sacc - s_ * cacc) / rho2 + 2 * rate * (s_ * sd + c_ * cd) / rho2
        row += 1
    for i in range(row):
        rhs_c[i] -= 2 * alpha * constraint_rate(work, i) + alpha * alpha * phi[i]
    return row


@numba.njit(cache=True)
def constraint_rate(work, i):
    """Phi' of constraint row i: D_i v + Phi_t (the row's two bodies only)."""
    jac, bodies = work.jac, work.bodies
    rate = work.phi_t[i]
    for side in range(2):
        b = work.row_bodies[i, side]
        if b >= 0:
            for c in range(3):
                rate += (jac[i, 6 * b + c] * bodies[b, BODY_VEL + c]
                         + jac[i, 6 * b + 3 + c] * bodies[b, BODY_OMEGA + c])
    return rate


@numba.njit(cache=True)
def fill_schur(args, work, m):
    """M^-1 D^T (rows of work.mjac) and the lower triangle of the Schur matrix D M^-1 D^T of
    the first m rows, within its envelope (work.first: what kernel.cholesky_solve reads). A row
    has nonzero columns for its two bodies only (work.row_bodies), so M^-1 (block-diagonal:
    m I and the global inverse inertia) acts on those, and two rows couple only through a body
    they share."""
    jac, mjac, schur, states, bodies = work.jac, work.mjac, work.schur, work.bodies, work.row_bodies
    masses = args.masses
    for i in range(m):   # columns of other bodies than the row's: zero since the workspace
        for side in range(2):
            b = bodies[i, side]
            if b < 0:
                continue
            angular = inverse_inertia_times(states, b, (jac[i, 6 * b + 3], jac[i, 6 * b + 4],
                                                         jac[i, 6 * b + 5]))
            for c in range(3):
                mjac[i, 6 * b + c] = jac[i, 6 * b + c] / masses[b]
                mjac[i, 6 * b + 3 + c] = angular[c]
    first = work.first
    for i in range(m):
        for k in range(first[i], i + 1):   # the envelope (constraint_pattern); left of it: 0
            v = 0.0
            for side in range(2):
                b = bodies[i, side]
                if b >= 0 and (b == bodies[k, 0] or b == bodies[k, 1]):
                    for c in range(6 * b, 6 * b + 6):
                        v += jac[i, c] * mjac[k, c]
            schur[i, k] = v


# ---- clearance joints
@numba.njit(cache=True)
def perpendicular(u):
    """A unit vector normal to the unit vector u."""
    a0, a1, a2 = abs(u[0]), abs(u[1]), abs(u[2])
    helper = (1.0, 0.0, 0.0) if a0 <= a1 and a0 <= a2 else \
        ((0.0, 1.0, 0.0) if a1 <= a2 else (0.0, 0.0, 1.0))
    f = cross(u, helper)
    return scaled(f, 1.0 / math.sqrt(dot(f, f)))


@numba.njit(cache=True)
def bore_section(bodies, joint):
    """A cylindrical joint in its bore's section (module docstring): (P_j, u_j, the
    mid-plane eccentricity a0 = perp(P_j - P_b), the lean a1 = perp(u_j - u_b)), perp the part
    normal to u_b: the journal's axis point X(z) = P_j + z u_j is off the bore's axis by
    a0 + z a1 across it."""
    bb, bj = int(joint[SJ_BEARING_BODY]), int(joint[SJ_JOURNAL_BODY])
    pb = point_state(bodies, bb, vec(joint, SJ_BEARING_POINT))[0]
    ub = vector_state(bodies, bb, vec(joint, SJ_BEARING_AXIS))[0]
    pj = point_state(bodies, bj, vec(joint, SJ_JOURNAL_POINT))[0]
    uj = vector_state(bodies, bj, vec(joint, SJ_JOURNAL_AXIS))[0]
    e, lean = sub(pj, pb), sub(uj, ub)
    return pj, uj, ub, sub(e, scaled(ub, dot(e, ub))), sub(lean, scaled(ub, dot(lean, ub)))


@numba.njit(cache=True)
def end_offset(joint):
    """The offset z' of the last slice from the mid-plane (m; the first's is -z')."""
    slices = int(joint[SJ_SLICES])
    return sliced.slice_geometry(slices - 1, joint[SJ_LENGTH], slices, 0.0)[0]


@numba.njit(cache=True)
def slice_rate(bodies, joint, n, x, b):
    """The approach rate n . (v_journal(x) - v_bore(b)) of the material points x, b (m/s)."""
    return dot(n, sub(material_velocity(bodies, int(joint[SJ_JOURNAL_BODY]), x),
                      material_velocity(bodies, int(joint[SJ_BEARING_BODY]), b)))


@numba.njit(cache=True)
def radial_depth(bodies, joint):
    """The deepest slice of a cylindrical joint with the bore unmoved (layout.Depth). Across
    the bore the journal's axis is off by |a0 + z' a1|, convex in z', so the deepest slice
    is an end slice: two slices are looked at, whatever the slicing."""
    pj, uj, _, a0, a1 = bore_section(bodies, joint)
    z = end_offset(joint)
    plus, minus = add(a0, scaled(a1, z)), sub(a0, scaled(a1, z))
    if dot(minus, minus) > dot(plus, plus):
        z, plus = -z, minus
    size = math.sqrt(dot(plus, plus))
    n = scaled(plus, 1.0 / size) if size > 0.0 else (1.0, 0.0, 0.0)
    x = add(pj, scaled(uj, z))
    return Depth(size - joint[JOINT_CLEARANCE], slice_rate(bodies, joint, n, x, sub(x, plus)))


@numba.njit(cache=True)
def cylinder_slices(bodies, joint, table, grid_log0, grid_step, approaches, weights):
    """The slices of a cylindrical joint with the bore moved by its bulk compliance
    (laws.sliced.bore_displacement; 0 without): each slice's approach delta_i into
    `approaches` (m) and its weight a w_i into `weights` (m); returns the bore's displacement
    (3, global; NaN beyond the law's table). For the outputs."""
    _, _, ub, a0, a1 = bore_section(bodies, joint)
    f, g, ax, ay, bx, by = section_frame(ub, a0, a1)
    length, slices, clearance = joint[SJ_LENGTH], int(joint[SJ_SLICES]), joint[JOINT_CLEARANCE]
    dx, dy = sliced.bore_displacement(ax, ay, bx, by, clearance, False, length, slices,
                                      grid_log0, grid_step, table, 0.0, 0.0, joint[SJ_END_LENGTH],
                                      joint[SJ_SCALE], joint[SJ_COMPLIANCE])
    for i in range(slices):
        approaches[i] = sliced.slice_contact(i, dx, dy, ax, ay, bx, by, clearance, False, length,
                                             slices, grid_log0, grid_step, table, 0.0, 0.0)[1]
        weights[i] = joint[SJ_SCALE] * sliced.slice_geometry(i, length, slices,
                                                             joint[SJ_END_LENGTH])[2]
    return add(scaled(f, dx), scaled(g, dy))


@numba.njit(cache=True)
def section_frame(ub, a0, a1):
    """The bore's section in 2D: unit f, g = u_b x f across the bore (f along a0 where the
    journal is off centre) and a0, a1 in them: (f, g, a0_f, a0_g, a1_f, a1_g)."""
    size = math.sqrt(dot(a0, a0))
    f = scaled(a0, 1.0 / size) if size > 0.0 else perpendicular(ub)
    g = cross(ub, f)
    return f, g, dot(a0, f), dot(a0, g), dot(a1, f), dot(a1, g)


@numba.njit(cache=True)
def axial_kinematics(bodies, joint):
    """Shoulders of a cylindrical joint: (penetration |s| - c_a, its rate, the axis u_b signed
    towards the journal's offset, the journal point P_j); -inf without shoulders."""
    if joint[SJ_AXIAL_CLEARANCE] <= 0.0:
        return -math.inf, 0.0, (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    bb, bj = int(joint[SJ_BEARING_BODY]), int(joint[SJ_JOURNAL_BODY])
    pb = point_state(bodies, bb, vec(joint, SJ_BEARING_POINT))[0]
    ub = vector_state(bodies, bb, vec(joint, SJ_BEARING_AXIS))[0]
    pj = point_state(bodies, bj, vec(joint, SJ_JOURNAL_POINT))[0]
    s = dot(sub(pj, pb), ub)
    u = ub if s >= 0.0 else scaled(ub, -1.0)
    rate = dot(u, sub(material_velocity(bodies, bj, pj), material_velocity(bodies, bb, pj)))
    return abs(s) - joint[SJ_AXIAL_CLEARANCE], rate, u, pj


@numba.njit(cache=True)
def sphere_kinematics(bodies, joint):
    """Ball in socket: (delta = |P_j - P_s| - c, its rate, n, P_j, P_s)."""
    bb, bj = int(joint[SJ_BEARING_BODY]), int(joint[SJ_JOURNAL_BODY])
    ps = point_state(bodies, bb, vec(joint, SJ_BEARING_POINT))[0]
    pj = point_state(bodies, bj, vec(joint, SJ_JOURNAL_POINT))[0]
    e = sub(pj, ps)
    size = math.sqrt(dot(e, e))
    n = scaled(e, 1.0 / size) if size > 0.0 else (1.0, 0.0, 0.0)
    rate = dot(n, sub(material_velocity(bodies, bj, pj), material_velocity(bodies, bb, ps)))
    return size - joint[JOINT_CLEARANCE], rate, n, pj, ps


@numba.njit(cache=True)
def channel_depth(bodies, joint, channel):
    """The deepest penetration of a contact channel and its approach rate (layout.Depth)."""
    if channel == AXIAL:
        if int(joint[SJ_KIND]) != CYLINDER:
            return Depth(-math.inf, 0.0)
        delta, rate, _, _ = axial_kinematics(bodies, joint)
        return Depth(delta, rate)
    if int(joint[SJ_KIND]) != CYLINDER:
        delta, rate, _, _, _ = sphere_kinematics(bodies, joint)
        return Depth(delta, rate)
    return radial_depth(bodies, joint)


@numba.njit(cache=True)
def push(force, bodies, b, f, x):
    """Add the force f (N, global) acting at the global point x to body b's force and torque."""
    if b < 0:
        return
    arm = sub(x, row3(bodies, b, BODY_POS))
    torque = cross(arm, f)
    for c in range(3):
        force[6 * b + c] += f[c]
        force[6 * b + 3 + c] += torque[c]


@numba.njit(cache=True)
def contact_force(force, bodies, joint, f_el, impact_speed, rate, n, x_journal, x_bearing):
    """One contact element (a slice, or the ball) in contact, its elastic force f_el (N; NaN
    beyond the law's table): the normal force f_el (1 + chi rate/v0) pushes the journal at
    x_journal along -n and the bearing at x_bearing along +n; friction acts at the contact
    point x_bearing + R_b n on both against the slip. Returns (normal force N, elastic force
    N, friction force N, dissipated power W)."""
    bb, bj = int(joint[SJ_BEARING_BODY]), int(joint[SJ_JOURNAL_BODY])
    f_n = dissipative.hysteresis_force(f_el, rate, impact_speed, joint_chi(joint, impact_speed))
    push(force, bodies, bj, scaled(n, -f_n), x_journal)
    push(force, bodies, bb, scaled(n, f_n), x_bearing)
    power = (f_n - f_el) * rate
    if int(joint[JOINT_FRICTION_LAW]) == NO_FRICTION:
        return f_n, f_el, 0.0, power
    contact = add(x_bearing, scaled(n, joint[JOINT_BEARING_RADIUS]))
    v = sub(material_velocity(bodies, bj, contact), material_velocity(bodies, bb, contact))
    slip = sub(v, scaled(n, dot(v, n)))
    speed = math.sqrt(dot(slip, slip))
    f_t = 0.0
    if speed > 0.0:
        f_t = joint_friction(joint, f_n, speed, 0.0)[0]
        push(force, bodies, bj, scaled(slip, -f_t / speed), contact)
        push(force, bodies, bb, scaled(slip, f_t / speed), contact)
        power += f_t * speed
    return f_n, f_el, f_t, power


@numba.njit(cache=True)
def joint_forces(force, bodies, joint, table, grid_log0, grid_step, radial_speed, axial_speed):
    """All the forces of a clearance joint into `force`: (radial or spherical normal force N,
    axial force N, friction force N, dissipated power W); NaN beyond the law's table."""
    normal = tangential = power = axial = 0.0
    if int(joint[SJ_KIND]) == CYLINDER:
        pj, uj, ub, a0, a1 = bore_section(bodies, joint)
        z = end_offset(joint)
        plus, minus = add(a0, scaled(a1, z)), sub(a0, scaled(a1, z))
        clearance = joint[JOINT_CLEARANCE]
        # the deepest slice is an end slice (radial_depth): skip the slices when it is free
        if max(dot(plus, plus), dot(minus, minus)) > clearance * clearance:
            f, g, ax, ay, bx, by = section_frame(ub, a0, a1)
            length, slices, scale = joint[SJ_LENGTH], int(joint[SJ_SLICES]), joint[SJ_SCALE]
            dx, dy = sliced.bore_displacement(ax, ay, bx, by, clearance, False, length, slices,
                                              grid_log0, grid_step, table, 0.0, 0.0,
                                              joint[SJ_END_LENGTH], scale, joint[SJ_COMPLIANCE])
            if not math.isfinite(dx):
                return math.nan, math.nan, math.nan, math.nan
            for i in range(slices):
                offset, approach, nx, ny, _, f_loc, _ = sliced.slice_contact(
                    i, dx, dy, ax, ay, bx, by, clearance, False, length, slices, grid_log0,
                    grid_step, table, 0.0, 0.0)
                if approach <= 0.0:
                    continue
                weight = sliced.slice_geometry(i, length, slices, joint[SJ_END_LENGTH])[2]
                n = add(scaled(f, nx), scaled(g, ny))
                x = add(pj, scaled(uj, offset))
                b = sub(x, scaled(n, approach + clearance))   # the bore's (moved) axis
                f_n, _, f_t, p = contact_force(force, bodies, joint, scale * weight * f_loc,
                                               radial_speed, slice_rate(bodies, joint, n, x, b),
                                               n, x, b)
                normal += f_n
                tangential += f_t
                power += p
        delta, rate, u, pj = axial_kinematics(bodies, joint)
        if delta > 0.0:
            f_el = joint[SJ_AXIAL_STIFFNESS] * delta
            axial = dissipative.hysteresis_force(f_el, rate, axial_speed, joint_chi(joint, axial_speed))
            push(force, bodies, int(joint[SJ_JOURNAL_BODY]), scaled(u, -axial), pj)
            push(force, bodies, int(joint[SJ_BEARING_BODY]), scaled(u, axial), pj)
            power += (axial - f_el) * rate
    else:
        delta, rate, n, pj, ps = sphere_kinematics(bodies, joint)
        if delta > 0.0:
            normal, _, tangential, power = contact_force(
                force, bodies, joint, tables.table_force(delta, grid_log0, grid_step, table),
                radial_speed, rate, n, pj, ps)
    return normal, axial, tangential, power


# ---- torsion elements
@numba.njit(cache=True)
def relative_angle(bodies, row):
    """Relative angle about body i's axis (atan2 of c_i . b_j and a_i . b_j) beyond the free
    angle, and its rate (w_j - w_i) . u_i."""
    bi, bj = int(row[TORSION_BODY_I]), int(row[TORSION_BODY_J])
    c_, kc, cd, _ = dot1(bodies, bi, vec(row, TORSION_A_I), bj, vec(row, TORSION_B_J))
    s_, ks, sd, _ = dot1(bodies, bi, vec(row, TORSION_C_I), bj, vec(row, TORSION_B_J))
    angle = math.atan2(s_, c_) - row[TORSION_FREE_ANGLE]
    angle -= 2 * math.pi * math.floor(angle / (2 * math.pi) + 0.5)
    return angle, (c_ * sd - s_ * cd) / (s_ * s_ + c_ * c_)


@numba.njit(cache=True)
def torsion_axis(bodies, row):
    """The axis u_i = a_i x c_i of a torsion element (global)."""
    bi = int(row[TORSION_BODY_I])
    a = vector_state(bodies, bi, vec(row, TORSION_A_I))[0]
    c = vector_state(bodies, bi, vec(row, TORSION_C_I))[0]
    return cross(a, c)


# ---- the right-hand side
@numba.njit(cache=True)
def workspace(args):
    nb, nj = args.masses.size, args.joints.shape[0]
    m = constraint_count(args.primitives)
    row_bodies, first = constraint_pattern(args.primitives, m)
    return SpatialWork(np.zeros((nb, BODY_COLUMNS)), np.zeros((m, 6 * nb)), np.zeros(m),
                       np.zeros(m), np.zeros(m), np.zeros((m, m)), np.zeros(6 * nb),
                       np.zeros(max(CHANNELS * nj, 1)), np.zeros((m, 6 * nb)), row_bodies, first)


@numba.njit(cache=True)
def constraint_pattern(primitives, m):
    """The fixed sparsity of the constraints: the two bodies of each row (-1: the ground or
    none; a row has nonzero Jacobian columns for these only), and the envelope of the Schur
    matrix D M^-1 D^T: first[i], the first row k <= i that shares a body with row i (rows
    couple only through a shared body). In a chain (the slider-crank: ground-crank,
    crank-rod, slider-ground, the drive) the envelope leaves out the blocks of bodies that
    share no joint, and kernel.cholesky_solve factors within it."""
    row_bodies = np.full((m, 2), -1, np.int64)
    row = 0
    for k in range(primitives.shape[0]):
        kind, bi, bj = (int(primitives[k, PRIM_KIND]), int(primitives[k, PRIM_BODY_I]),
                        int(primitives[k, PRIM_BODY_J]))
        for c in range(PRIMITIVE_ROWS[kind]):
            row_bodies[row + c, 0], row_bodies[row + c, 1] = bi, bj if bj != bi else -1
        row += PRIMITIVE_ROWS[kind]
    first = np.arange(m)
    for i in range(m):
        for k in range(i):
            if shares_body(row_bodies, i, k):
                first[i] = k
                break
    return row_bodies, first


@numba.njit(cache=True)
def shares_body(row_bodies, i, k):
    """Whether constraint rows i and k act on a common (moving) body."""
    for side in range(2):
        b = row_bodies[i, side]
        if b >= 0 and (b == row_bodies[k, 0] or b == row_bodies[k, 1]):
            return True
    return False


@numba.njit(cache=True)
def applied_forces(t, y, args, work):
    """Gravity, gyroscopic terms, clearance joints and torsion elements into work.force (6 a
    body); returns the dissipated power (NaN beyond a law's table). work.normal gets each
    channel's normal force."""
    masses, gravity, joints, torsion = args.masses, args.gravity, args.joints, args.torsion
    force, normal, speeds, bodies = work.force, work.normal, args.speeds, work.bodies
    for b in range(masses.size):
        w = row3(bodies, b, BODY_OMEGA)
        jw = turned(bodies, b, matvec(args.inertia, b, unturned(bodies, b, w)))
        gyro = cross(w, jw)
        for c in range(3):
            force[6 * b + c] = masses[b] * gravity[c]
            force[6 * b + 3 + c] = -gyro[c]
    normal[:] = 0.0
    dissipation = 0.0
    for k in range(joints.shape[0]):
        f_n, f_a, _, power = joint_forces(force, bodies, joints[k], args.tables[k], args.grid_log0,
                                          args.grid_step, speeds[CHANNELS * k],
                                          speeds[CHANNELS * k + 1])
        normal[CHANNELS * k], normal[CHANNELS * k + 1] = f_n, f_a
        dissipation += power
    for k in range(torsion.shape[0]):
        angle, rate = relative_angle(bodies, torsion[k])
        torque, power = torsion_law(angle, rate, torsion[k], args.latched[k] > 0)
        u = torsion_axis(bodies, torsion[k])
        for b, sign in ((int(torsion[k, TORSION_BODY_J]), 1.0), (int(torsion[k, TORSION_BODY_I]), -1.0)):
            if b >= 0:
                for c in range(3):
                    force[6 * b + 3 + c] += sign * torque * u[c]
        dissipation += power
    return dissipation


@numba.njit(cache=True)
def rhs(t, y, dy, args, work):
    """dy = f(t, y) (module docstring): velocities, the Euler parameters' second derivatives
    with their normalisation, dissipated power, power of the constraints."""
    nq, masses = args.nq, args.masses
    body_states(y, args, work)
    dissipation = applied_forces(t, y, args, work)
    if not math.isfinite(dissipation):
        dy[:] = math.nan   # penetration beyond the tabulated law: the integrator stops
        return
    force, rhs_c, jac = work.force, work.rhs_c, work.jac
    m = fill_constraints(t, work, args.primitives, args.baumgarte)
    work_in = 0.0
    if m > 0:
        fill_schur(args, work, m)
        mjac, row_bodies = work.mjac, work.row_bodies
        for i in range(m):   # (D M^-1 D^T) lambda = D M^-1 Q - gamma~
            v = -rhs_c[i]
            for side in range(2):
                b = row_bodies[i, side]
                if b >= 0:
                    for c in range(6 * b, 6 * b + 6):
                        v += mjac[i, c] * force[c]
            rhs_c[i] = v
        cholesky_solve(work.schur, rhs_c, m, work.first)
        for i in range(m):   # Q - D^T lambda
            for side in range(2):
                b = row_bodies[i, side]
                if b >= 0:
                    for c in range(6 * b, 6 * b + 6):
                        force[c] -= jac[i, c] * rhs_c[i]
            work_in += rhs_c[i] * work.phi_t[i]
    alpha = args.baumgarte
    for b in range(masses.size):
        for c in range(3):
            dy[7 * b + c] = y[nq + 7 * b + c]
            dy[nq + 7 * b + c] = force[6 * b + c] / masses[b]
        for c in range(4):
            dy[7 * b + 3 + c] = y[nq + 7 * b + 3 + c]
        wd = inverse_inertia_times(work.bodies, b, vec(force, 6 * b + 3))   # w' (global)
        p = unit_parameters(y, b)
        pd = vec(y, nq + 7 * b + 3) + (y[nq + 7 * b + 6],)
        half = gt_times(p, scaled(unturned(work.bodies, b, wd), 0.5))
        pp = p[0] ** 2 + p[1] ** 2 + p[2] ** 2 + p[3] ** 2
        raw = vec(y, 7 * b + 3) + (y[7 * b + 6],)
        norm2 = raw[0] ** 2 + raw[1] ** 2 + raw[2] ** 2 + raw[3] ** 2
        along = (-(pd[0] ** 2 + pd[1] ** 2 + pd[2] ** 2 + pd[3] ** 2)
                 - 2 * alpha * (raw[0] * pd[0] + raw[1] * pd[1] + raw[2] * pd[2] + raw[3] * pd[3])
                 - 0.5 * alpha * alpha * (norm2 - 1.0)) / pp
        for c in range(4):
            dy[nq + 7 * b + 3 + c] = half[c] + along * p[c]
    dy[2 * nq + DISSIPATED] = dissipation
    dy[2 * nq + WORK_IN] = work_in


def rhs_value(t, y, args):
    """(f(t, y), normal force per contact channel) as new arrays (Python-side convenience)."""
    dy, work = integrator.evaluate_once(workspace, rhs, t, y, args)
    return dy, work.normal[:CHANNELS * args.joints.shape[0]].copy()


# ---- projection onto the constraints
@numba.njit(cache=True)
def normalise(y, nq, nb):
    """Euler parameters to unit length, their rates normal to them."""
    for b in range(nb):
        i = 7 * b + 3
        n = math.sqrt(y[i] ** 2 + y[i + 1] ** 2 + y[i + 2] ** 2 + y[i + 3] ** 2)
        along = 0.0
        for c in range(4):
            y[i + c] /= n
            along += y[i + c] * y[nq + i + c]
        for c in range(4):
            y[nq + i + c] -= along * y[i + c]


@numba.njit(cache=True)
def turn(y, b, rotation_vector):
    """Turn body b by a small global rotation vector: p <- (cos(|r|/2), sin(|r|/2) r/|r|) p."""
    angle = math.sqrt(dot(rotation_vector, rotation_vector))
    if angle == 0.0:
        return
    k = math.sin(0.5 * angle) / angle
    a0, a = math.cos(0.5 * angle), scaled(rotation_vector, k)
    i = 7 * b + 3
    b0, bv = y[i], (y[i + 1], y[i + 2], y[i + 3])
    v = add(add(scaled(bv, a0), scaled(a, b0)), cross(a, bv))
    y[i], y[i + 1], y[i + 2], y[i + 3] = a0 * b0 - dot(a, bv), v[0], v[1], v[2]


@numba.njit(cache=True)
def project_onto_constraints(t, y, args, work, tolerance, rate_tolerance):
    """Normalise the Euler parameters; then one Gauss-Newton step of positions and one of
    velocities onto Phi = 0 and D v + Phi_t = 0, least change in the mass metric
    (dx = -M^-1 D^T (D M^-1 D^T)^-1 Phi), each only where the residual exceeds its
    tolerance (m, m/s). Returns whether a constraint was projected."""
    nq, nb = args.nq, args.masses.size
    rhs_c, mjac = work.rhs_c, work.mjac
    normalise(y, nq, nb)
    changed = False
    m = 0
    for level in range(2):
        if level == 0 or changed:   # positions unmoved: the Jacobian of level 0 holds
            body_states(y, args, work)
            m = fill_constraints(t, work, args.primitives, 0.0)
        largest = 0.0
        for i in range(m):
            if level == 0:
                rhs_c[i] = work.phi[i]
            else:
                rhs_c[i] = constraint_rate(work, i)
            largest = max(largest, abs(rhs_c[i]))
        if largest <= (tolerance if level == 0 else rate_tolerance):
            continue
        changed = True
        fill_schur(args, work, m)
        cholesky_solve(work.schur, rhs_c, m, work.first)
        step = np.zeros(6)
        for b in range(nb):
            step[:] = 0.0
            for c in range(6):
                for i in range(m):
                    step[c] -= mjac[i, 6 * b + c] * rhs_c[i]
            if level == 0:
                for c in range(3):
                    y[7 * b + c] += step[c]
                turn(y, b, (step[3], step[4], step[5]))
            else:
                for c in range(3):
                    y[nq + 7 * b + c] += step[c]
                w = add(row3(work.bodies, b, BODY_OMEGA), (step[3], step[4], step[5]))
                pd = gt_times(unit_parameters(y, b), scaled(unturned(work.bodies, b, w), 0.5))
                for c in range(4):
                    y[nq + 7 * b + 3 + c] = pd[c]
        normalise(y, nq, nb)
    return changed   # False: y normalised only, the body states of y in the workspace


# ---- the spatial mechanism's hooks of the integrator (reduced.integrator)
@numba.njit(cache=True)
def engage_latches(bodies, torsion, latched):
    """Latch every latch that has reached its angle (body states current)."""
    changed = False
    for r in range(torsion.shape[0]):
        if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH and \
                relative_angle(bodies, torsion[r])[0] > -LATCH_TOL:
            latched[r] = 1.0
            changed = True
    return changed


@numba.njit(cache=True)
def start(y, args, onset_tol):
    """Contact channels at t = 0 (latches given as engaged engage) and what to check:
    (no held contacts, no Iwan elements, latches)."""
    work = workspace(args)
    body_states(y, args, work)
    torsion = args.torsion
    latches = False
    for r in range(torsion.shape[0]):
        latches |= int(torsion[r, TORSION_KIND]) == LATCH
    engage_latches(work.bodies, torsion, args.latched)
    nc = CHANNELS * args.joints.shape[0]
    contacts = Contacts(np.zeros(nc), np.zeros(nc, np.bool_), np.zeros(nc), np.zeros(nc))
    for c in range(nc):
        contacts.depth[c] = channel_depth(work.bodies, args.joints[c // CHANNELS], c % CHANNELS).delta
        contacts.in_contact[c] = contacts.depth[c] > -onset_tol
    return contacts, (False, False, latches)


@numba.njit(cache=True)
def event_fraction(y, y_new, args, work, contacts, latches, onset_tol):
    """The fraction of a trial step that ends it at the first onset of a channel
    (integrator.onset_shortening) or at a latch's angle (secant); 1: none."""
    torsion, latched = args.torsion, args.latched
    body_states(y_new, args, work)
    shorten = 1.0
    for c in range(contacts.depth.size):
        if not contacts.in_contact[c]:
            d_new = channel_depth(work.bodies, args.joints[c // CHANNELS], c % CHANNELS).delta
            shorten = min(shorten, integrator.onset_shortening(contacts.depth[c], d_new, onset_tol))
    if latches:
        angles_new = np.empty(torsion.shape[0])
        for r in range(torsion.shape[0]):
            angles_new[r] = relative_angle(work.bodies, torsion[r])[0]
        body_states(y, args, work)
        for r in range(torsion.shape[0]):
            if latched[r] == 0.0 and int(torsion[r, TORSION_KIND]) == LATCH and angles_new[r] > LATCH_TOL:
                a_old = relative_angle(work.bodies, torsion[r])[0]
                shorten = min(shorten, 0.99 * (-a_old) / (angles_new[r] - a_old))
    return shorten


@numba.njit(cache=True)
def after_step(t, y, args, work, contacts, latches, onset_tol, speed_floor, rate_tol, log, impacts):
    """Accepted step: projection; each channel's depth, its onset (impact speed v0 at least
    speed_floor, logged) or separation; latches. Returns (changed, impacts, log)."""
    changed = project_onto_constraints(t, y, args, work, onset_tol, rate_tol)
    if changed:
        body_states(y, args, work)
    speeds = args.speeds
    for c in range(contacts.depth.size):
        depth = channel_depth(work.bodies, args.joints[c // CHANNELS], c % CHANNELS)
        contacts.depth[c] = depth.delta
        if not contacts.in_contact[c] and depth.delta > -onset_tol:
            contacts.in_contact[c] = True
            speeds[c] = max(depth.rate, speed_floor)
            impacts += 1
            log = log_impact(log, impacts, t, c // CHANNELS, depth.rate, 0.0)
            changed = True
        elif contacts.in_contact[c] and depth.delta < -onset_tol:
            contacts.in_contact[c] = False
    if latches:
        changed |= engage_latches(work.bodies, args.torsion, args.latched)
    return changed, impacts, log


def spatial(args) -> bool:
    return getattr(args, "instance_class", None) is SpatialArgs


@overload(integrator.new_workspace, inline="always")
def _new_workspace(args):
    if spatial(args):
        return lambda args: workspace(args)


@overload(integrator.evaluate, inline="always")
def _evaluate(t, y, dy, args, work):
    if spatial(args):
        return lambda t, y, dy, args, work: rhs(t, y, dy, args, work)


@overload(integrator.start, inline="always")
def _start(y, args, onset_tol):
    if spatial(args):
        return lambda y, args, onset_tol: start(y, args, onset_tol)


@overload(integrator.event_fraction, inline="always")
def _event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt):
    if spatial(args):
        return lambda y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt: \
            event_fraction(y, y_new, args, work, contacts, needs[2], onset_tol)


@overload(integrator.after_step, inline="always")
def _after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, log, impacts):
    if spatial(args):
        return lambda t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, log, \
            impacts: after_step(t, y, args, work, contacts, needs[2], onset_tol, speed_floor,
                                rate_tol, log, impacts)


integrate = integrator.integrate

# ---- the compiled code follows the laws, the layouts and the planar kernel's shared parts
COMPILED_IN = (friction.__file__, dissipative.__file__, tables.__file__, sliced.__file__,
               layout.__file__, spatial_layout.__file__, kernel.__file__, integrator.__file__)
follow_compiled_in(globals(), COMPILED_IN)
