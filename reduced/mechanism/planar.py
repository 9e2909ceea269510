r"""Planar rigid bodies: the body kind of a planar mechanism (scenes kind = "reduced").

Coordinates q = (x, y, phi) of each body's centre of mass, velocities q' = (x', y', w), and
M = diag(m, m, J): the velocity columns of the constraint Jacobian are the coordinates' rates,
a body point s (body frame) is at P = r + A(phi) s with velocity r' + w k x A s and the
velocity part of its acceleration -w^2 A s. Angles are measured without bound (phi_j - phi_i),
so a drive or a spring needs no principal value. The equations of motion, the joints and the
contacts are reduced.mechanism.engine's; this module implements reduced.mechanism.bodies for
its marker layout.PLANAR and for vectors of two components.
"""

import math

import numba
import numpy as np

from pinbore.core.compiled import beside, follow_compiled_in
from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import bodies, layout
from pinbore.reduced.mechanism.layout import ANGLE, DOT2, POINT
from pinbore.reduced.mechanism.flexible import FlexibleGeometry
from pinbore.reduced.mechanism.scene import GROUND
from pinbore.reduced.mechanism.linalg import schur_within_envelope
from pinbore.reduced.mechanism.vectors import _plane

# a body's row in Work.bodies: the rigid motion, then (every body) its first velocity column
# and modes n (0: rigid), then a flexible body's J(eta), sigma = J - g.g, eta, eta', g (MODES
# each) and its interfaces (FACE columns each, from FACES)
X, Y, PHI, COS, SIN, VX, VY, W = range(8)
RIGID_COLUMNS = 8     # what a run's record keeps of a row (reduced.mechanism.outputs)
FIRST, NMODES, NFACES, INERTIA, SIGMA = 8, 9, 10, 11, 12
MODES = 24            # at most, a flexible body (scene.FLEXIBLE_MODES)
INTERFACES = 4        # at most, a flexible body's interfaces tied to joints
ETA = 13
ETA_RATE, GVEC = ETA + MODES, ETA + 2 * MODES
FACES = ETA + 3 * MODES
# an interface: its centre x_k (body frame), its frame's displacement T_k eta and turn
# R_k eta, their rates, then the mode shapes T_k (x: MODES, y: MODES) and R_k
F_CENTRE, F_MOVE, F_TURN, F_MOVE_RATE, F_TURN_RATE, F_T, F_R = 0, 2, 4, 5, 7, 8, 8 + 2 * MODES
FACE = 8 + 3 * MODES
BODY_COLUMNS = FACES + INTERFACES * FACE
COLUMNS = 3   # velocity columns of a rigid body: x', y', w (a flexible body's modes follow)

# a flexible body's constants in its row of Args.flex (reduced.mechanism.model; a rigid body's
# row is zero): modes n, interfaces, I0 = I_xx + I_yy, then flex_column's blocks
C_MODES, C_FACES, C_I0 = 0, 1, 2


@numba.njit(cache=True, _nrt=False)
def flex_column(n, block, k):
    """The first column in Args.flex of a flexible body's constant block (n its modes):
    0 omega^2, 1 the modal damping 2 zeta omega, 2 s1 = s_xx + s_yy (n each), 3 the inertia
    quadratic Q = S_xx + S_yy - K_G (n x n), 4 the gyroscopic S^ = S_xy - S_yx (n x n), 5 the
    interface k: x_k (2), T_k (x: n, y: n), R_k (n)."""
    if block < 3:
        return 3 + block * n
    if block < 5:
        return 3 + 3 * n + (block - 3) * n * n
    return 3 + 3 * n + 2 * n * n + k * (2 + 3 * n)


def planar(kind) -> bool:
    return getattr(kind, "instance_class", None) is layout.PlanarKind


# ---- a flexible body's interfaces: a point of the body moves with the frame of its nearest
# interface (tied rigidly, fem.modes.reduction), u = T_k eta + (R_k eta) k x (s - x_k)
@numba.njit(cache=True, _nrt=False)
def flexible(states, b):
    return b >= 0 and states[b, NMODES] > 0.0


@numba.njit(cache=True, _nrt=False)
def face_of(states, b, s):
    """The column where body b's interface nearest the body point s starts."""
    best, at = math.inf, FACES
    for k in range(int(states[b, NFACES])):
        f = FACES + k * FACE
        d = (s[0] - states[b, f]) ** 2 + (s[1] - states[b, f + 1]) ** 2
        if d < best:
            best, at = d, f
    return at


@numba.njit(cache=True, _nrt=False)
def deformed(states, b, f, s):
    """(s + u, u') of the body point s on the interface at column f (body frame)."""
    e0, e1 = s[0] - states[b, f], s[1] - states[b, f + 1]
    turn, rate = states[b, f + F_TURN], states[b, f + F_TURN_RATE]
    return ((s[0] + states[b, f + F_MOVE] - turn * e1, s[1] + states[b, f + F_MOVE + 1] + turn * e0),
            (states[b, f + F_MOVE_RATE] - rate * e1, states[b, f + F_MOVE_RATE + 1] + rate * e0))


@numba.njit(cache=True, _nrt=False)
def undeformed(states, b, f, s):
    """The body point whose deformed place is s (body frame), on the interface at column f,
    from the interface centre: d = s - x_k - T_k eta turned back by the inverse of
    I + theta k x, (I - theta k x) d / (1 + theta^2), returned unscaled with its factor:
    ((I - theta k x) d, 1 / (1 + theta^2))."""
    turn = states[b, f + F_TURN]
    e0 = s[0] - states[b, f] - states[b, f + F_MOVE]
    e1 = s[1] - states[b, f + 1] - states[b, f + F_MOVE + 1]
    k = 1.0 / (1.0 + turn * turn)
    return e0 + turn * e1, e1 - turn * e0, k


@numba.njit(cache=True, _nrt=False)
def turned_back(states, b, v):
    """A^T v: a global vector in body b's floating frame."""
    c, sn = states[b, COS], states[b, SIN]
    return c * v[0] + sn * v[1], -sn * v[0] + c * v[1]


@numba.njit(cache=True, _nrt=False)
def modal_columns(jac, row, states, b, f, e, l, rho, sign, column):
    """Add sign (l . (T_k,j + R_k,j k x e) + rho R_k,j) to the modal columns of a row: l the
    row's linear coefficient in the body frame, e the point from the interface centre, rho the
    rotation part of its angular coefficient."""
    lk = l[1] * e[0] - l[0] * e[1]
    for j in range(int(states[b, NMODES])):
        r = states[b, f + F_R + j]
        jac[row, column + j] += sign * (l[0] * states[b, f + F_T + j] + l[1] * states[b, f + F_T + MODES + j]
                                       + r * (lk + rho))


# ---- points and vectors
@numba.njit(cache=True, _nrt=False)
def arm(states, b, s):
    """A(phi) s of body b (the cosine and sine of its angle in its row)."""
    c, sn = states[b, COS], states[b, SIN]
    return c * s[0] - sn * s[1], sn * s[0] + c * s[1]


@numba.njit(cache=True, _nrt=False)
def point_state(states, b, s):
    if b < 0:
        return s, (0.0, 0.0), (0.0, 0.0), (0.0, 0.0)
    w = states[b, W]
    if flexible(states, b):   # P = r + A (s + u), P' = r' + w k x A(s + u) + A u'
        place, rate = deformed(states, b, face_of(states, b, s), s)
        a, v = arm(states, b, place), arm(states, b, rate)
        return ((states[b, X] + a[0], states[b, Y] + a[1]),
                (states[b, VX] - w * a[1] + v[0], states[b, VY] + w * a[0] + v[1]),
                (-(a[0] * w * w) - 2 * w * v[1], -(a[1] * w * w) + 2 * w * v[0]), a)
    a = arm(states, b, s)
    w2 = w * w
    return ((states[b, X] + a[0], states[b, Y] + a[1]),
            (states[b, VX] - w * a[1], states[b, VY] + w * a[0]), (-(a[0] * w2), -(a[1] * w2)), a)


@numba.njit(cache=True, _nrt=False)
def vector_state(states, b, s, v):
    if b < 0:
        return v, (0.0, 0.0), (0.0, 0.0)
    w = states[b, W]
    if flexible(states, b):   # turned with the interface's frame by R_k eta
        f = face_of(states, b, s)
        turn = states[b, f + F_TURN]
        w = w + states[b, f + F_TURN_RATE]
        c, sn = math.cos(turn), math.sin(turn)
        a = arm(states, b, (c * v[0] - sn * v[1], sn * v[0] + c * v[1]))
        return a, (-w * a[1], w * a[0]), (-(a[0] * w * w), -(a[1] * w * w))
    a = arm(states, b, v)
    w2 = w * w
    return a, (-w * a[1], w * a[0]), (-(a[0] * w2), -(a[1] * w2))


@numba.njit(cache=True, _nrt=False)
def material_velocity(states, b, x):
    if b < 0:
        return (0.0, 0.0)
    w = states[b, W]
    v = (states[b, VX] - w * (x[1] - states[b, Y]), states[b, VY] + w * (x[0] - states[b, X]))
    if flexible(states, b):
        s = turned_back(states, b, (x[0] - states[b, X], x[1] - states[b, Y]))
        f = face_of(states, b, s)
        e0, e1, k = undeformed(states, b, f, s)
        rate = states[b, f + F_TURN_RATE] * k
        u = arm(states, b, (states[b, f + F_MOVE_RATE] - rate * e1, states[b, f + F_MOVE_RATE + 1] + rate * e0))
        return v[0] + u[0], v[1] + u[1]
    return v


@numba.njit(cache=True, _nrt=False)
def put(jac, row, states, b, s, linear, angular, sign, offsets):
    if b < 0:
        return
    c = offsets[b]
    jac[row, c] += sign * linear[0]
    jac[row, c + 1] += sign * linear[1]
    jac[row, c + 2] += sign * angular
    if flexible(states, b):
        f = face_of(states, b, s)
        place = deformed(states, b, f, s)[0]
        l = turned_back(states, b, linear)
        rho = angular - (place[0] * l[1] - place[1] * l[0])   # less the point's arm x linear
        modal_columns(jac, row, states, b, f, (s[0] - states[b, f], s[1] - states[b, f + 1]), l, rho, sign,
                      c + COLUMNS)


@numba.njit(cache=True, _nrt=False)
def push(force, states, b, f, x, offsets):
    if b < 0:
        return
    c = offsets[b]
    force[c] += f[0]
    force[c + 1] += f[1]
    force[c + 2] += (x[0] - states[b, X]) * f[1] - (x[1] - states[b, Y]) * f[0]
    if flexible(states, b):   # the modes' generalised force (A (T_k + R_k k x e))^T f
        s = turned_back(states, b, (x[0] - states[b, X], x[1] - states[b, Y]))
        face = face_of(states, b, s)
        e0, e1, k = undeformed(states, b, face, s)
        l = turned_back(states, b, f)
        lk = (l[1] * e0 - l[0] * e1) * k
        for j in range(int(states[b, NMODES])):
            force[c + COLUMNS + j] += (l[0] * states[b, face + F_T + j] + l[1] * states[b, face + F_T + MODES + j]
                                       + states[b, face + F_R + j] * lk)


@numba.njit(cache=True, _nrt=False)
def push_torque(force, states, b, s, torque, offsets):
    if b < 0:
        return
    force[offsets[b] + 2] += torque
    if flexible(states, b):
        f = face_of(states, b, s)
        for j in range(int(states[b, NMODES])):
            force[offsets[b] + COLUMNS + j] += torque * states[b, f + F_R + j]


@numba.njit(cache=True, _nrt=False)
def centripetal_term(states, b, arm_, a, c):
    """a . c, the velocity part of a point's acceleration (0 for the ground): a rigid body's
    -w^2 A s, written (a . A s) w^2 with its sign."""
    if b < 0:
        return 0.0
    if flexible(states, b):
        return a[0] * c[0] + a[1] * c[1]
    w = states[b, W]
    return -((a[0] * arm_[0] + a[1] * arm_[1]) * (w * w))


@numba.njit(cache=True, _nrt=False)
def frame_angle(states, b, s):
    """(angle, rate) of body b's frame at the body point s (the ground's: 0)."""
    if b < 0:
        return 0.0, 0.0
    if flexible(states, b):
        f = face_of(states, b, s)
        return states[b, PHI] + states[b, f + F_TURN], states[b, W] + states[b, f + F_TURN_RATE]
    return states[b, PHI], states[b, W]


@numba.njit(cache=True, _nrt=False)
def relative_rotation(states, bi, bj, s_i, s_j, a_i, b_j, c_i, offset, drift):
    phi_i, w_i = frame_angle(states, bi, s_i)
    phi_j, w_j = frame_angle(states, bj, s_j)
    return ((phi_j - phi_i) - offset) - drift, -1.0, w_j - w_i, 0.0


@numba.njit(cache=True, _nrt=False)
def body_columns(like):
    return BODY_COLUMNS


@numba.njit(cache=True, _nrt=False)
def centripetal_gap(states, a, bi, arm_i, c_i, bj, arm_j, c_j):
    return centripetal_term(states, bj, arm_j, a, c_j) - centripetal_term(states, bi, arm_i, a, c_i)


@numba.njit(cache=True, _nrt=False)
def rotation_axis(states, bi, s_i, a_i, c_i):
    return 1.0


@numba.njit(cache=True, _nrt=False)
def row_rate(rate, jac, i, b, states, velocities, offsets, like):
    for c in range(offsets[b], offsets[b + 1]):
        rate += jac[i, c] * velocities[c]
    return rate


# ---- the whole body (the signatures of reduced.mechanism.bodies: the unused arrays are
# other kinds'). A flexible body in Buckens' mean-axis frame (fem.modes.reduction: the
# deformation moves neither its centre of mass nor its axes to first order), coordinates
# (x, y, phi, eta): its kinetic energy [Shabana2005]
#     T = m |r'|^2 / 2 + J(eta) phi'^2 / 2 + phi' g(eta) . eta' + |eta'|^2 / 2,
#     J = I0 + 2 s1 . eta + eta^T Q eta,   g = S^T eta,
# Q = S_xx + S_yy - K_G,zz: the deformed body's inertia less its foreshortening, the
# geometric stiffening [WallrappSchwertassek1991] written as the loss of inertia it is, so
# that the equations stay Lagrange's of one energy. Lagrange's equations, j1 = s1 + Q eta:
#     m r'' = F,
#     J phi'' + g . eta'' = N - 2 phi' j1 . eta',
#     g phi'' + eta'' = Q_eta + phi'^2 j1 + 2 phi' S^ eta' - omega^2 eta - 2 zeta omega eta'
# (S^ antisymmetric; gravity acts on the centre of mass alone: the mean axis).
@numba.njit(cache=True, _nrt=False)
def body_states(kind, y, nq, inertia_inv, flex, offsets, states, velocities):
    for b in range(states.shape[0]):
        c = offsets[b]
        phi = y[c + 2]
        states[b, X], states[b, Y], states[b, PHI] = y[c], y[c + 1], phi
        states[b, COS], states[b, SIN] = math.cos(phi), math.sin(phi)
        states[b, VX], states[b, VY] = y[nq + c], y[nq + c + 1]
        states[b, W] = y[nq + c + 2]
        states[b, FIRST] = c
        n = offsets[b + 1] - c - COLUMNS
        states[b, NMODES] = n
        if n > 0:
            flexible_state(y, nq, flex, b, c + COLUMNS, n, states)
    for j in range(nq):
        velocities[j] = y[nq + j]


@numba.njit(cache=True, _nrt=False)
def inertia_terms(flex, b, n, y, q, k):
    """(g_k = (S^T eta)_k, eta_k (2 s1_k + (Q eta)_k)): the k-th term of g and of J - I0 of
    flexible body b, its modal coordinates from y[q]."""
    s1, quad, gyro = flex_column(n, 2, 0), flex_column(n, 3, 0), flex_column(n, 4, 0)
    g, qe = 0.0, 0.0
    for j in range(n):
        g += y[q + j] * flex[b, gyro + j * n + k]
        qe += flex[b, quad + k * n + j] * y[q + j]
    return g, y[q + k] * (2 * flex[b, s1 + k] + qe)


@numba.njit(cache=True, _nrt=False)
def flexible_state(y, nq, flex, b, q, n, states):
    """eta, eta', g = S^T eta, J(eta), sigma = J - g.g and the interfaces' frames into body
    b's row (its modal coordinates from y[q])."""
    inertia = flex[b, C_I0]
    gg = 0.0
    for j in range(n):
        states[b, ETA + j], states[b, ETA_RATE + j] = y[q + j], y[nq + q + j]
    for k in range(n):
        g, term = inertia_terms(flex, b, n, y, q, k)
        states[b, GVEC + k] = g
        gg += g * g
        inertia += term
    states[b, INERTIA], states[b, SIGMA] = inertia, inertia - gg
    faces = int(flex[b, C_FACES])
    states[b, NFACES] = faces
    for k in range(faces):
        at, f = flex_column(n, 5, k), FACES + k * FACE
        states[b, f], states[b, f + 1] = flex[b, at], flex[b, at + 1]
        move, turn = (0.0, 0.0), 0.0
        move_rate, turn_rate = (0.0, 0.0), 0.0
        for j in range(n):
            tx, ty, r = flex[b, at + 2 + j], flex[b, at + 2 + n + j], flex[b, at + 2 + 2 * n + j]
            states[b, f + F_T + j], states[b, f + F_T + MODES + j], states[b, f + F_R + j] = tx, ty, r
            e, ed = y[q + j], y[nq + q + j]
            move = (move[0] + tx * e, move[1] + ty * e)
            move_rate = (move_rate[0] + tx * ed, move_rate[1] + ty * ed)
            turn += r * e
            turn_rate += r * ed
        states[b, f + F_MOVE], states[b, f + F_MOVE + 1], states[b, f + F_TURN] = move[0], move[1], turn
        states[b, f + F_MOVE_RATE], states[b, f + F_MOVE_RATE + 1] = move_rate
        states[b, f + F_TURN_RATE] = turn_rate


@numba.njit(cache=True, _nrt=False)
def body_forces(kind, masses, minv, inertia, gravity, flex, states, force):
    """Gravity, m g, on each body (a rigid body's mass is 1 / minv); a flexible body's
    quadratic velocity, elastic and damping forces. Returns the power the modal damping
    dissipates."""
    power = 0.0
    for b in range(states.shape[0]):
        c = int(states[b, FIRST])
        n = int(states[b, NMODES])
        if n == 0:
            force[c] = gravity[0] / minv[c]
            force[c + 1] = gravity[1] / minv[c + 1]
            force[c + 2] = 0.0
            continue
        force[c], force[c + 1] = masses[b] * gravity[0], masses[b] * gravity[1]
        omega2, damping = flex_column(n, 0, 0), flex_column(n, 1, 0)
        s1, quad, gyro = flex_column(n, 2, 0), flex_column(n, 3, 0), flex_column(n, 4, 0)
        w = states[b, W]
        coupling = 0.0
        for k in range(n):
            j1, spin = flex[b, s1 + k], 0.0
            for j in range(n):
                j1 += flex[b, quad + k * n + j] * states[b, ETA + j]
                spin += flex[b, gyro + k * n + j] * states[b, ETA_RATE + j]
            rate = states[b, ETA_RATE + k]
            coupling += j1 * rate
            force[c + COLUMNS + k] = (w * w * j1 + 2 * w * spin - flex[b, omega2 + k] * states[b, ETA + k]
                                      - flex[b, damping + k] * rate)
            power += flex[b, damping + k] * rate * rate
        force[c + 2] = -2 * w * coupling
    return power


@numba.njit(cache=True, _nrt=False)
def rotation_part(states, b, v_phi, v_eta_dot_g):
    """a = (v_phi - g . v_eta) / sigma: the angular part of M^-1 v of flexible body b, whose
    block [[J, g^T], [g, I]] inverts in closed form (the modal part is v_eta - g a)."""
    return (v_phi - v_eta_dot_g) / states[b, SIGMA]


@numba.njit(cache=True, _nrt=False)
def solve_row(states, b, c, n, src, dst, i):
    """dst[i, columns of b] = M_b^-1 src[i, columns of b] (body b flexible, from column c)."""
    g = 0.0
    for j in range(n):
        g += states[b, GVEC + j] * src[i, c + COLUMNS + j]
    a = rotation_part(states, b, src[i, c + 2], g)
    dst[i, c + 2] = a
    for j in range(n):
        dst[i, c + COLUMNS + j] = src[i, c + COLUMNS + j] - states[b, GVEC + j] * a


@numba.njit(cache=True, _nrt=False)
def solve_vector(states, b, c, n, src, dst, at):
    """dst[at + columns of b] = M_b^-1 src[columns of b] (the translation's 1/m left to the
    caller)."""
    g = 0.0
    for j in range(n):
        g += states[b, GVEC + j] * src[c + COLUMNS + j]
    a = rotation_part(states, b, src[c + 2], g)
    dst[at + c + 2] = a
    for j in range(n):
        dst[at + c + COLUMNS + j] = src[c + COLUMNS + j] - states[b, GVEC + j] * a


@numba.njit(cache=True, _nrt=False)
def fill_schur(kind, masses, minv, offsets, states, jac, mjac, schur, row_bodies, first, m):
    for i in range(m):
        for side in range(2):
            b = row_bodies[i, side]
            if b >= 0:
                for c in range(offsets[b], offsets[b + 1]):
                    mjac[i, c] = jac[i, c] * minv[c]
                if states[b, NMODES] > 0:
                    solve_row(states, b, offsets[b], int(states[b, NMODES]), jac, mjac, i)
    schur_within_envelope(jac, mjac, schur, row_bodies, first, offsets, m, True)


@numba.njit(cache=True, _nrt=False)
def state_rates(kind, y, dy, nq, masses, minv, baumgarte, states, force):
    for j in range(nq):
        dy[j] = y[nq + j]
        dy[nq + j] = minv[j] * force[j]
    for b in range(states.shape[0]):
        if states[b, NMODES] > 0:
            solve_vector(states, b, int(states[b, FIRST]), int(states[b, NMODES]), force, dy, nq)


@numba.njit(cache=True, _nrt=False)
def mass_weighted_step(y, start, jac, minv, mjac, states, x, m, scale):
    """y[start:start + nq] -= scale M^-1 Phi_q^T x: the least change (in the mass metric) along
    the rows (a flexible body's M^-1 Phi_q^T from mjac, fill_schur's)."""
    for b in range(states.shape[0]):
        c0, n = int(states[b, FIRST]), int(states[b, NMODES])
        for c in range(c0, c0 + COLUMNS + n):
            v = 0.0
            if n > 0 and c >= c0 + 2:
                for i in range(m):
                    v += mjac[i, c] * x[i]
                y[start + c] -= scale * v
                continue
            for i in range(m):
                v += jac[i, c] * x[i]
            y[start + c] -= scale * minv[c] * v


@numba.njit(cache=True, _nrt=False)
def position_step(kind, y, nq, minv, jac, mjac, x, states, m):
    mass_weighted_step(y, 0, jac, minv, mjac, states, x, m, 1.0)


@numba.njit(cache=True, _nrt=False)
def velocity_step(kind, y, nq, minv, jac, mjac, x, states, m, scale):
    mass_weighted_step(y, nq, jac, minv, mjac, states, x, m, scale)


@numba.njit(cache=True, _nrt=False)
def normalise(kind, y, nq, offsets):
    pass


@numba.njit(cache=True, _nrt=False)
def kinetic_energy(kind, y, nq, masses, minv, inertia, flex, offsets):
    """Sum of m v^2 / 2 + J w^2 / 2; a flexible body's T (above)."""
    energy = 0.0
    for b in range(offsets.size - 1):
        c = offsets[b]
        n = offsets[b + 1] - c - COLUMNS
        if n == 0:
            for i in range(c, c + COLUMNS):
                energy += 0.5 * y[nq + i] ** 2 / minv[i]
            continue
        q, w = c + COLUMNS, y[nq + c + 2]
        inertia_, coupling, modal = flex[b, C_I0], 0.0, 0.0
        for k in range(n):
            g, term = inertia_terms(flex, b, n, y, q, k)
            inertia_ += term
            coupling += g * y[nq + q + k]
            modal += y[nq + q + k] ** 2
        energy += (0.5 * masses[b] * (y[nq + c] ** 2 + y[nq + c + 1] ** 2) + 0.5 * inertia_ * w * w
                   + w * coupling + 0.5 * modal)
    return energy


# planar bodies implement reduced.mechanism.bodies for their marker and 2-vectors
bodies.implement_kind(globals(), {"kind": planar, "vector": _plane})


# ---- a planar scene as the model's arrays (reduced.mechanism.model.build asks these)
MARKER = layout.PLANAR
PROJECT_FIRST = False   # an accepted step's events are read before its projection (layout.Args)


class Geometry(FlexibleGeometry):
    """A planar scene's bodies and ideal joints as the model's arrays: the coordinates (a
    flexible body's modal coordinates after its x, y, phi), the mass, the primitive
    constraints, a revolute clearance joint's contact, torsion elements, and the consistent
    initial state."""

    DIM, RIGID_COLUMNS, RIGID_COORDINATES, MODES, INTERFACES = 2, COLUMNS, COLUMNS, MODES, INTERFACES

    def __init__(self, scene, index, source, base=None):
        self.scene, self.index, self.source = scene, index, source
        self.read_flexible(scene, index, source, base)
        self.nq = int(self.columns[-1])

    def attachments(self):
        """(body, point, key) of every point a joint, drive, spring or contact fixes on a
        body."""
        scene, found = self.scene, []
        for j in scene.joints:
            if j.type == "revolute":
                found += [(j.body_i, j.point_i, "joints.point_i"), (j.body_j, j.point_j, "joints.point_j")]
            else:
                found.append((j.body, j.point, "joints.point"))
        for table in ("clearance_joints", "translational_joints"):
            for c in getattr(scene, table):
                found += [(c.bearing_body, c.bearing_point, f"{table}.bearing_point"),
                          (c.journal_body, c.journal_point, f"{table}.journal_point")]
        if scene.drive is not None:
            found.append((scene.drive.body, self.frame_point(scene.drive.body, scene.drive.point),
                          "drive.point"))
        for t in scene.torsion:
            found += [(t.body_i, self.frame_point(t.body_i, t.point_i), "torsion.point_i"),
                      (t.body_j, self.frame_point(t.body_j, t.point_j), "torsion.point_j")]
        return found

    def mass(self):
        """(masses, 1/m, 1/m, 1/J per velocity column (a flexible body's at eta = 0: 1/m,
        1/m, 1/I0, then 1 a mode), inertia: J (I0) in [0, 0] of a 3 x 3 per body)."""
        bodies = self.scene.bodies
        minv, masses, inertia = [], [], np.zeros((len(bodies), 3, 3))
        for b, body in enumerate(bodies):
            flexible = self.flexible.get(body.name)
            mass, j = (body.mass, body.inertia) if flexible is None else (flexible.mass, flexible.inertia)
            minv += [1 / mass, 1 / mass, 1 / j] + [1.0] * self.modes(body.name)
            masses.append(mass)
            inertia[b, 0, 0] = j
        return np.array(masses, float), np.array(minv, float), inertia

    def coordinate(self, b: int) -> int:
        """Body b's first coordinate in q."""
        return int(self.columns[b])

    @staticmethod
    def constants(flexible) -> np.ndarray:
        return constants(flexible)

    def primitives(self, closures):
        """The revolute joints (a point each), the clearance joints closed by `closures`,
        the prismatic joints (the body's point on the line, its angle held), the drive (the
        body's angle = angle0 + omega t): (rows, the drive's row or None)."""
        index, scene = self.index, self.scene
        rows = [primitive(POINT, index[j.body_i], index[j.body_j], s_i=j.point_i, s_j=j.point_j)
                for j in scene.joints if j.type == "revolute"]
        rows += [r for closure in closures for r in closure]
        for j in scene.joints:
            if j.type == "prismatic":
                axis = math.radians(j.axis_deg)
                b = index[j.body]
                rows.append(primitive(DOT2, -1, b, s_i=j.axis_point, s_j=j.point,
                                      a_i=(-math.sin(axis), math.cos(axis))))
                rows.append(primitive(ANGLE, -1, b, angle0=math.radians(scene.bodies[b].angle_deg),
                                      s_j=j.point))
        if scene.drive is None:
            return rows, None
        rows.append(primitive(ANGLE, -1, index[scene.drive.body], speed=scene.drive.speed,
                              angle0=math.radians(scene.drive.angle0_deg),
                              s_j=self.frame_point(scene.drive.body, scene.drive.point),
                              profile=scene.drive.profile_columns()))
        return rows, len(rows) - 1

    def closing(self, c) -> list:
        """A revolute clearance joint closed: the revolute of its bearing and journal centres."""
        return [primitive(POINT, self.index[c.bearing_body], self.index[c.journal_body],
                          s_i=c.bearing_point, s_j=c.journal_point)]

    def contacts(self, c, deltas, laws_data, source):
        """A revolute clearance joint: one RADIAL contact, its normal force and friction at
        the contact point on both bodies; the force of its law (N) at `deltas`."""
        from pinbore.reduced.mechanism.model import point_force   # noqa: PLC0415 (model imports us)

        geometry = {layout.CONTACT_KIND: layout.RADIAL,
                    layout.CONTACT_BEARING_BODY: self.index[c.bearing_body],
                    layout.CONTACT_JOURNAL_BODY: self.index[c.journal_body],
                    layout.CONTACT_BEARING_POINT: list(c.bearing_point),
                    layout.CONTACT_JOURNAL_POINT: list(c.journal_point),
                    layout.CONTACT_CLEARANCE: c.bearing_radius - c.journal_radius,
                    layout.CONTACT_RADIUS: c.bearing_radius, layout.CONTACT_AT_CONTACT: 1.0}
        if c.impact != "continuous":
            return [geometry], np.full(deltas.size, np.nan)   # rigid: no law, never evaluated
        return [geometry], point_force(c, deltas, laws_data, source)

    def torsion(self, t) -> dict:
        """The free angle relative to the bodies' initial relative angle (angles without
        bound: no vectors needed)."""
        angle = {b.name: math.radians(b.angle_deg) for b in self.scene.bodies} | {GROUND: 0.0}
        return {layout.TORSION_FREE_ANGLE: angle[t.body_j] - angle[t.body_i]
                + math.radians(t.free_angle_deg),
                layout.TORSION_A_I: [1.0, 0.0], layout.TORSION_B_J: [1.0, 0.0],
                layout.TORSION_C_I: [0.0, 1.0],
                layout.TORSION_S_I: self.frame_point(t.body_i, t.point_i) if t.body_i != GROUND else [0.0, 0.0],
                layout.TORSION_S_J: self.frame_point(t.body_j, t.point_j) if t.body_j != GROUND else [0.0, 0.0]}

    def inverse_inertia(self, b, t) -> float:
        """1/J of body b (a flexible body's undeformed I0)."""
        body = self.scene.bodies[b]
        return 1 / (self.flexible[body.name].inertia if body.flexible else body.inertia)

    def place(self, model, closings) -> np.ndarray:
        """Positions satisfying the ideal joints (an ideal twin's closures among them) with the
        clearance joints that start "ideal" or "free" closed (least change from the scene's guesses), and the scene's velocities
        projected onto Phi_q q' = -Phi_t (least change in kinetic-energy norm) of the ideal
        joints and those that start "ideal" ("placed" joints keep their positions)."""
        scene = self.scene
        q = np.concatenate([[*b.position, math.radians(b.angle_deg)] + [0.0] * self.modes(b.name)
                            for b in scene.bodies])
        qd = np.concatenate([[*b.velocity, b.omega] + [0.0] * self.modes(b.name) for b in scene.bodies])
        minv = model.base.minv
        closed = self.primitives(model.closures + [rows for rows, start in closings
                                                   if start in ("ideal", "free")])[0]
        rigid = np.ones(self.nq, bool)   # the bodies start undeformed and at rest in their frames
        for b, body in enumerate(scene.bodies):
            rigid[self.columns[b] + COLUMNS:self.columns[b + 1]] = False
        q, _, gap = project(model, q, qd, closed, minv, movable=rigid)
        if gap >= 1e-14:
            raise InputError("joints: the bodies cannot be placed so that every joint closes "
                             f"(largest gap {gap:.3g} m)")
        closed = self.primitives(model.closures + [rows for rows, start in closings if start == "ideal"])[0]
        _, qd, _ = project(model, q, qd, closed, minv, movable=rigid)
        return np.concatenate([q, qd, np.zeros(layout.ENERGY_STATES), np.zeros(model.friction_states)])


def constants(flexible) -> np.ndarray:
    """A flexible body's row of Args.flex (flex_column)."""
    b, n = flexible.body, flexible.n
    omega = b.omega[:n]
    S = b.S[:, :, :n, :n]
    parts = [[n, len(b.interfaces), flexible.inertia], omega ** 2, 2 * flexible.ratios * omega,
             b.s[0, 0, :n] + b.s[1, 1, :n], (S[0, 0] + S[1, 1] - flexible.stiffening_matrices[2, 2]).ravel(),
             (S[0, 1] - S[1, 0]).ravel()]
    for k in range(len(b.interfaces)):
        parts += [flexible.centres[k], b.interface_translation[k, 0, :n],
                  b.interface_translation[k, 1, :n], b.interface_rotation[k, 2, :n]]
    return np.concatenate([np.asarray(p, float).ravel() for p in parts])


def primitive(kind, bi, bj, s_i=(0.0, 0.0), s_j=(0.0, 0.0), a_i=(0.0, 0.0), b_j=(0.0, 0.0),
              c_i=(0.0, 0.0), speed=0.0, angle0=0.0, profile=None) -> list:
    """A primitive constraint's row (layout.PRIM_*) of planar vectors (`profile`: a drive's
    profile columns)."""
    return layout.row(layout.PRIMITIVE_COLUMNS, (profile or {}) | {
        layout.PRIM_KIND: kind, layout.PRIM_BODY_I: bi, layout.PRIM_BODY_J: bj,
        layout.PRIM_SPEED: speed, layout.PRIM_ANGLE0: angle0, layout.PRIM_S_I: list(s_i),
        layout.PRIM_S_J: list(s_j), layout.PRIM_A_I: list(a_i), layout.PRIM_B_J: list(b_j),
        layout.PRIM_C_I: list(c_i)})


def project(model, q, qd, primitives, minv, t=0.0, movable=None):
    """The nearest consistent state: positions moved least onto Phi(q, t) = 0 (Gauss-Newton),
    velocities projected onto Phi_q q' = -Phi_t with least change in kinetic-energy norm (minv:
    M^-1's diagonal, exact for a flexible body undeformed); only the coordinates and rates
    `movable` (default all) change. Returns (q, q', largest remaining position gap)."""
    from pinbore.reduced.mechanism.kernel import constraint_values   # noqa: PLC0415 (the engine)

    q, qd = q.copy(), qd.copy()
    args = model.args(primitives=np.array(primitives, float).reshape(-1, layout.PRIMITIVE_COLUMNS),
                      mode=np.zeros(model.contacts.shape[0], np.int64))
    nq = q.size
    y = np.zeros(2 * nq + layout.ENERGY_STATES)
    gap = 0.0
    for _ in range(50):
        y[:nq] = q
        jac, phi, _ = constraint_values(t, y, args)
        gap = np.max(np.abs(phi), initial=0.0)
        if jac.shape[0] == 0 or gap < 1e-14:
            break
        if movable is not None:
            jac = jac * movable
        q -= jac.T @ np.linalg.lstsq(jac @ jac.T, phi, rcond=None)[0]
    y[:nq] = q
    jac, _, phi_t = constraint_values(t, y, args)
    if jac.shape[0]:
        scaled = jac * minv * (1.0 if movable is None else movable)
        qd -= scaled.T @ np.linalg.lstsq(scaled @ jac.T, jac @ qd + phi_t, rcond=None)[0]
    return q, qd, gap


# ---- a planar run's outputs (reduced.mechanism.outputs asks these)
def motion_columns(model, q, qd, qdd, bodies) -> dict:
    """Each body's coordinates, rates and accelerations at the steps (columns by name), a
    flexible body's modal coordinates eta_j (m sqrt(kg), M-normalised modes), and each output
    point's elastic displacement in its body's frame and its global position."""
    cols = {}
    keys = ((q, (("x", "m"), ("y", "m"), ("angle", "rad"))),
            (qd, (("vx", "m_per_s"), ("vy", "m_per_s"), ("omega", "rad_per_s"))),
            (qdd, (("ax", "m_per_s2"), ("ay", "m_per_s2"), ("alpha", "rad_per_s2"))))
    geometry = model.geometry
    for b, name in enumerate(model.names):
        c = geometry.coordinate(b)
        for values, what in keys:
            for i, (key, unit) in enumerate(what):
                cols[f"{name}_{key}_{unit}"] = values[:, c + i]
        for j in range(geometry.modes(name)):
            cols[f"{name}_eta{j + 1}_m_sqrt_kg"] = q[:, c + COLUMNS + j]
    for point, b, shape in geometry.points:
        c = geometry.coordinate(b)
        u = np.zeros((q.shape[0], 2)) if shape is None else q[:, c + COLUMNS:c + COLUMNS + shape.shape[1]] @ shape.T
        local = np.asarray(point.position[:2], float) + u
        cos, sin = np.cos(q[:, c + 2]), np.sin(q[:, c + 2])
        key = f"{point.body}_{point.name}"
        cols[f"{key}_ux_m"], cols[f"{key}_uy_m"] = u[:, 0], u[:, 1]
        cols[f"{key}_x_m"] = q[:, c] + cos * local[:, 0] - sin * local[:, 1]
        cols[f"{key}_y_m"] = q[:, c + 1] + sin * local[:, 0] + cos * local[:, 1]
    return cols


def strain_energy(model, q) -> np.ndarray:
    """The flexible bodies' strain energy at the steps (J)."""
    return model.geometry.strain_energy(model.names, q)


def drive_angle(model, cols):
    """The driven body's angle from its start (deg), None without a drive."""
    drive = model.scene.drive
    if drive is None:
        return None
    return np.degrees(cols[f"{drive.body}_angle_rad"] - math.radians(drive.angle0_deg))


def slider_acceleration(model, cols):
    """The acceleration (m/s^2) of the first prismatic joint's body along its axis, None
    without one."""
    slider = next((j for j in model.scene.joints if j.type == "prismatic"), None)
    if slider is None:
        return None
    a = math.radians(slider.axis_deg)
    return cols[f"{slider.body}_ax_m_per_s2"] * math.cos(a) + cols[f"{slider.body}_ay_m_per_s2"] * math.sin(a)


# ---- a planar mechanism seen once per drive period (reduced.dynamics.flow asks these)
WRAPPED_ANGLES = False   # angles have no bound: the drive's angle0 turns on by 2 pi a period


def flow_scale(model, length, omega) -> np.ndarray:
    """The scales of the coordinates: positions and angles by the clearance c, their rates
    by c omega."""
    return np.concatenate([np.full(model.nq, length), np.full(model.nq, length * abs(omega))])


def flow_signs(model, y) -> np.ndarray:
    return np.ones(2 * model.nq)


def flow_coordinates(model, y, primitives) -> np.ndarray:
    """q and q', the driven body's angle taken relative to the drive's (angle0 of the
    period)."""
    x = y[:2 * model.nq].copy()
    if model.drive_row is None:
        return x
    row = primitives[model.drive_row]
    b = int(row[layout.PRIM_BODY_J])
    if b >= 0:
        x[model.geometry.coordinate(b) + 2] -= row[layout.PRIM_ANGLE0]
    return x


def flow_consistent(model, y, args) -> np.ndarray:
    """y with q moved least onto the constraints of args.primitives, then q' projected
    (`project`)."""
    nq = model.nq
    y = y.copy()
    y[:nq], y[nq:2 * nq], _ = project(model, y[:nq], y[nq:2 * nq], args.primitives, model.base.minv)
    return y


# numba's cache follows this file only: the compiled code here also calls into (or reads the
# constants of) these files, and is compiled afresh when they change (core.compiled)
follow_compiled_in(globals(), beside(__file__, "bodies", "layout", "vectors", "linalg", "spatial"))
