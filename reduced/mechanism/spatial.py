r"""Spatial rigid bodies: the body kind of a spatial mechanism (scenes kind = "spatial").

Each body has its centre of mass r and Euler parameters p = (e0, e1, e2, e3), |p| = 1
([Nikravesh1988] ch. 6), with the rotation matrix

    A(p) = 2 [(e0^2 - 1/2) I + e e^T + e0 e~],     e = (e1, e2, e3),

and G(p) = [-e, -e~ + e0 I] (3 x 4), so that the angular velocity in the body frame is
w' = 2 G p' and, since G' p' = 0, w'' = 2 G p''. The state holds (r, p) and their rates (7
coordinates a body). The dynamics are written in the body velocities v = (r', w), w = A w'
global, the velocity columns of the constraint Jacobian:

    m r'' = m g + F + ...,     J w' + w x (J w) = N,   J = A J' A^T  (Euler's equations),

M = diag(m I, J) block-diagonal with an explicit inverse. The Euler parameters then follow
from p'' = G^T w''/2 + k p, where G^T G = I - p p^T leaves the component along p to the
normalisation constraint (p^T p - 1)/2 = 0: p^T p'' = -p'^T p' (and its Baumgarte terms),
Nikravesh's augmented formulation reduced to the body velocities. After every accepted step
the parameters are normalised (`normalise`), and a step onto the constraints turns a body by
a small rotation vector (`turn`). Relative angles are atan2 of two dot products, taken modulo
2 pi. A body point s' is at P = r + A s', with velocity r' + w x s and the velocity part of
its acceleration w x (w x s). This module implements reduced.mechanism.bodies for
its marker layout.SPATIAL and for vectors of three components. Every array a compiled helper reads
out of a bundle, or a row view it makes, has its references counted: the body states sit in
one array read in place.
"""

import math

import numba
import numpy as np

from pinbore.core.compiled import beside, follow_compiled_in
from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import bodies, layout
from pinbore.reduced.mechanism.bodies import dot1
from pinbore.reduced.mechanism.layout import ANGLE, DOT1, DOT2, POINT
from pinbore.reduced.mechanism.flexible import FlexibleGeometry
from pinbore.reduced.mechanism.scene import GROUND, rotation_matrix, unit_axis
from pinbore.reduced.mechanism.linalg import schur_within_envelope
from pinbore.reduced.mechanism.vectors import _space, add, cross, dot, scaled, sub

# a body's row in Work.bodies: position, rotation matrix (row-major), velocity, angular
# velocity (global), global inverse inertia A J'^-1 A^T (row-major; a flexible body's: of
# sigma = J(eta) - G G^T, the angular block of M^-1), then (every body) its first velocity
# column, first coordinate and modes n (0: rigid), then a flexible body's J(eta) and G(eta)
# (body frame), eta, eta' and its interfaces (FACE columns each, from FACES)
BODY_POS, BODY_ROT, BODY_VEL, BODY_OMEGA, BODY_JINV = 0, 3, 12, 15, 18
RIGID_COLUMNS = BODY_OMEGA + 3   # what a run's record keeps of a body's row (its angular velocity)
FIRST, COORD, NMODES, NFACES, JBODY = 27, 28, 29, 30, 31
MODES = 24            # at most, a flexible body (scene.FLEXIBLE_MODES)
INTERFACES = 4        # at most, a flexible body's interfaces
GMAT = JBODY + 9      # G[a, j] at GMAT + a MODES + j
ETA = GMAT + 3 * MODES
ETA_RATE = ETA + MODES
FACES = ETA_RATE + MODES
# an interface: its centre x_k, its frame's displacement T_k eta and small turn R_k eta, their
# rates (body frame), the mode shapes T_k[a, j] and R_k[a, j] (a MODES + j)
F_CENTRE, F_MOVE, F_TURN, F_MOVE_RATE, F_TURN_RATE, F_T = 0, 3, 6, 9, 12, 15
F_R = F_T + 3 * MODES
FACE = F_R + 3 * MODES
BODY_COLUMNS = FACES + INTERFACES * FACE
COORDINATES = 7   # r, p (a flexible body's modal coordinates follow)
COLUMNS = 6       # velocity columns a body: v, w (a flexible body's modes follow)

# a flexible body's constants in its row of Args.flex (reduced.mechanism.model; a rigid
# body's row is zero): modes n, interfaces, then flex_column's blocks
C_MODES, C_FACES = 0, 1


@numba.njit(cache=True, _nrt=False)
def flex_column(n, block, k):
    """The first column in Args.flex of a flexible body's constant block (n its modes): 0
    omega^2, 1 the modal damping 2 zeta omega (n each), 2 the second moments I_ab (9), 3 s_ab[k]
    ((3 a + b) n + k), 4 S_ab[j, k] ((3 a + b) n^2 + j n + k), 5 the stiffening K_G,ab[j, k]
    (alike), 6 the interface k: x_k (3), T_k[a, j] (a n + j), R_k[a, j]."""
    if block < 2:
        return 2 + block * n
    if block == 2:
        return 2 + 2 * n
    if block == 3:
        return 11 + 2 * n
    if block < 6:
        return 11 + 11 * n + (block - 4) * 9 * n * n
    return 11 + 11 * n + 18 * n * n + k * (3 + 6 * n)


def spatial(kind) -> bool:
    return getattr(kind, "instance_class", None) is layout.SpatialKind


@numba.njit(cache=True, _nrt=False)
def vec3(a, i):
    return (a[i], a[i + 1], a[i + 2])


@numba.njit(cache=True, _nrt=False)
def row3(rows, b, k):
    """Three entries of row b of a 2D array from column k."""
    return (rows[b, k], rows[b, k + 1], rows[b, k + 2])


@numba.njit(cache=True, _nrt=False)
def matvec(m, b, a):
    """m[b] a, the 3 x 3 matrix b of a stack m read in place."""
    return (m[b, 0, 0] * a[0] + m[b, 0, 1] * a[1] + m[b, 0, 2] * a[2],
            m[b, 1, 0] * a[0] + m[b, 1, 1] * a[1] + m[b, 1, 2] * a[2],
            m[b, 2, 0] * a[0] + m[b, 2, 1] * a[1] + m[b, 2, 2] * a[2])


# ---- Euler parameters
@numba.njit(cache=True, _nrt=False)
def rotation(p, out):
    """A(p) into out (3 x 3) for unit p = (e0, e1, e2, e3)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    out[0, 0], out[0, 1], out[0, 2] = e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2
    out[1, 0], out[1, 1], out[1, 2] = e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1
    out[2, 0], out[2, 1], out[2, 2] = e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5
    out *= 2.0


@numba.njit(cache=True, _nrt=False)
def g_times(p, pd):
    """G(p) p' (3)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return (-e1 * pd[0] + e0 * pd[1] + e3 * pd[2] - e2 * pd[3],
            -e2 * pd[0] - e3 * pd[1] + e0 * pd[2] + e1 * pd[3],
            -e3 * pd[0] + e2 * pd[1] - e1 * pd[2] + e0 * pd[3])


@numba.njit(cache=True, _nrt=False)
def gt_times(p, w):
    """G(p)^T w (4)."""
    e0, e1, e2, e3 = p[0], p[1], p[2], p[3]
    return (-e1 * w[0] - e2 * w[1] - e3 * w[2], e0 * w[0] - e3 * w[1] + e2 * w[2],
            e3 * w[0] + e0 * w[1] - e1 * w[2], -e2 * w[0] + e1 * w[1] + e0 * w[2])


@numba.njit(cache=True, _nrt=False)
def unit_parameters(q, i):
    """The Euler parameters q[i .. i + 3], normalised (4-tuple)."""
    n = math.sqrt(q[i] ** 2 + q[i + 1] ** 2 + q[i + 2] ** 2 + q[i + 3] ** 2)
    return (q[i] / n, q[i + 1] / n, q[i + 2] / n, q[i + 3] / n)


@numba.njit(cache=True, _nrt=False)
def flexible(states, b):
    return b >= 0 and states[b, NMODES] > 0.0


@numba.njit(cache=True, _nrt=False)
def body_states(kind, y, nq, inertia_inv, flex, offsets, states, velocities):
    """Position, rotation matrix, velocity, global angular velocity w = A 2 G p' and global
    inverse inertia A J'^-1 A^T of every body into its row (BODY_*); a flexible body's
    modal state (flexible_state); the velocity of each column (r', w, eta') into
    `velocities`."""
    for b in range(states.shape[0]):
        c = offsets[b]
        q = c + b   # its first coordinate: 7 + n coordinates, 6 + n velocity columns a body
        p = unit_parameters(y, q + 3)
        e0, e1, e2, e3 = p
        a = ((e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2),
             (e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1),
             (e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5))
        for r in range(3):
            for k in range(3):
                states[b, BODY_ROT + 3 * r + k] = 2.0 * a[r][k]
        w_body = scaled(g_times(p, vec3(y, nq + q + 3) + (y[nq + q + 6],)), 2.0)
        w = turned(states, b, w_body)
        for k in range(3):
            states[b, BODY_POS + k] = y[q + k]
            states[b, BODY_VEL + k] = y[nq + q + k]
            states[b, BODY_OMEGA + k] = w[k]
            velocities[c + k], velocities[c + 3 + k] = y[nq + q + k], w[k]
        n = offsets[b + 1] - c - COLUMNS
        states[b, FIRST], states[b, COORD], states[b, NMODES] = c, q, n
        for j in range(n):
            velocities[c + COLUMNS + j] = y[nq + q + COORDINATES + j]
        if n > 0:
            flexible_state(y, nq, flex, b, q + COORDINATES, n, states)
            continue
        for r in range(3):       # A J'^-1 A^T written out: a 3 x 3 matmul allocates
            ar = row3(states, b, BODY_ROT + 3 * r)
            t0 = ar[0] * inertia_inv[b, 0, 0] + ar[1] * inertia_inv[b, 1, 0] + ar[2] * inertia_inv[b, 2, 0]
            t1 = ar[0] * inertia_inv[b, 0, 1] + ar[1] * inertia_inv[b, 1, 1] + ar[2] * inertia_inv[b, 2, 1]
            t2 = ar[0] * inertia_inv[b, 0, 2] + ar[1] * inertia_inv[b, 1, 2] + ar[2] * inertia_inv[b, 2, 2]
            for k in range(r + 1):
                ac = row3(states, b, BODY_ROT + 3 * k)
                v = t0 * ac[0] + t1 * ac[1] + t2 * ac[2]
                states[b, BODY_JINV + 3 * r + k] = states[b, BODY_JINV + 3 * k + r] = v


# ---- a flexible body in Buckens' mean-axis frame (fem.modes.reduction), coordinates (r, p,
# eta), its kinetic energy [Shabana2005], w' the angular velocity in the body frame:
#     T = m |r'|^2 / 2 + w'^T J(eta) w' / 2 + w'^T G(eta) eta' + |eta'|^2 / 2,
#     I_ab(eta) = I_ab + (s_ab + s_ba) . eta + eta^T S_ab eta,
#     J = tr(I) 1 - I - [eta^T K_G,ab eta],   G[a, :] = eta^T S^_a,  S^_a = e_abc S_bc,
# the geometric stiffening [WallrappSchwertassek1991] as the loss of inertia of the
# foreshortening (one Lagrangian: energy and momenta kept). Euler's and Lagrange's equations
# (h = J w' + G eta', the angular momentum about the centre of mass):
#     J w'' + G eta'' = N' - w' x h - J' w',
#     G^T w'' + eta'' = Q + dT/deta (w' terms) + 2 sum_a w'_a S^_a eta' - omega^2 eta - 2 zeta omega eta',
# with w'' = A^T (dw/dt) (w = A w'); gravity acts on the centre of mass alone.
@numba.njit(cache=True, _nrt=False)
def second_moment(flex, b, n, src, at, a, c):
    """I_ac(eta) of flexible body b (eta = src[at .. at + n - 1])."""
    s_block, big_s = flex_column(n, 3, 0), flex_column(n, 4, 0)
    v = flex[b, flex_column(n, 2, 0) + 3 * a + c]
    ac, ca = 3 * a + c, 3 * c + a
    for k in range(n):
        e = src[at + k]
        quad = 0.0
        for j in range(n):
            quad += flex[b, big_s + ac * n * n + k * n + j] * src[at + j]
        v += e * (flex[b, s_block + ac * n + k] + flex[b, s_block + ca * n + k] + quad)
    return v


@numba.njit(cache=True, _nrt=False)
def stiffening_term(flex, b, n, src, at, a, c):
    """eta^T K_G,ac eta."""
    kg = flex_column(n, 5, 0) + (3 * a + c) * n * n
    v = 0.0
    for k in range(n):
        for j in range(n):
            v += src[at + k] * flex[b, kg + k * n + j] * src[at + j]
    return v


@numba.njit(cache=True, _nrt=False)
def gyroscopic(flex, b, n, a, j, m):
    """S^_a[j, m] = e_abc S_bc[j, m]."""
    big_s = flex_column(n, 4, 0)
    b1, b2 = (a + 1) % 3, (a + 2) % 3
    return (flex[b, big_s + (3 * b1 + b2) * n * n + j * n + m]
            - flex[b, big_s + (3 * b2 + b1) * n * n + j * n + m])


@numba.njit(cache=True, _nrt=False)
def inertia_of(flex, b, n, src, at):
    """J(eta) (9-tuple, row-major, body frame)."""
    i00, i11, i22 = (second_moment(flex, b, n, src, at, 0, 0), second_moment(flex, b, n, src, at, 1, 1),
                     second_moment(flex, b, n, src, at, 2, 2))
    i01, i02, i12 = (second_moment(flex, b, n, src, at, 0, 1), second_moment(flex, b, n, src, at, 0, 2),
                     second_moment(flex, b, n, src, at, 1, 2))
    trace = i00 + i11 + i22
    k00, k11, k22 = (stiffening_term(flex, b, n, src, at, 0, 0), stiffening_term(flex, b, n, src, at, 1, 1),
                     stiffening_term(flex, b, n, src, at, 2, 2))
    k01, k02, k12 = (stiffening_term(flex, b, n, src, at, 0, 1), stiffening_term(flex, b, n, src, at, 0, 2),
                     stiffening_term(flex, b, n, src, at, 1, 2))
    return (trace - i00 - k00, -i01 - k01, -i02 - k02, -i01 - k01, trace - i11 - k11, -i12 - k12,
            -i02 - k02, -i12 - k12, trace - i22 - k22)


@numba.njit(cache=True, _nrt=False)
def g_row(flex, b, n, src, at, a, m):
    """G[a, m] = sum_j eta_j S^_a[j, m]."""
    v = 0.0
    for j in range(n):
        v += src[at + j] * gyroscopic(flex, b, n, a, j, m)
    return v


@numba.njit(cache=True, _nrt=False)
def inverse3(m):
    """The inverse of a 3 x 3 matrix (9-tuple, row-major) by its adjugate."""
    c00, c01, c02 = m[4] * m[8] - m[5] * m[7], m[5] * m[6] - m[3] * m[8], m[3] * m[7] - m[4] * m[6]
    det = m[0] * c00 + m[1] * c01 + m[2] * c02
    return ((c00 / det, (m[2] * m[7] - m[1] * m[8]) / det, (m[1] * m[5] - m[2] * m[4]) / det),
            (c01 / det, (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det),
            (c02 / det, (m[1] * m[6] - m[0] * m[7]) / det, (m[0] * m[4] - m[1] * m[3]) / det))


@numba.njit(cache=True, _nrt=False)
def flexible_state(y, nq, flex, b, q, n, states):
    """eta, eta', J(eta), G(eta), the global inverse of sigma = J - G G^T and the interfaces'
    frames into body b's row (its modal coordinates from y[q])."""
    for j in range(n):
        states[b, ETA + j], states[b, ETA_RATE + j] = y[q + j], y[nq + q + j]
    inertia = inertia_of(flex, b, n, y, q)
    for k in range(9):
        states[b, JBODY + k] = inertia[k]
    for a in range(3):
        for m in range(n):
            states[b, GMAT + a * MODES + m] = g_row(flex, b, n, y, q, a, m)
    s00 = inertia[0] - g_dot(states, b, n, 0, 0)
    s01 = inertia[1] - g_dot(states, b, n, 0, 1)
    s02 = inertia[2] - g_dot(states, b, n, 0, 2)
    s11 = inertia[4] - g_dot(states, b, n, 1, 1)
    s12 = inertia[5] - g_dot(states, b, n, 1, 2)
    s22 = inertia[8] - g_dot(states, b, n, 2, 2)
    inv = inverse3((s00, s01, s02, s01, s11, s12, s02, s12, s22))
    for r in range(3):   # A sigma^-1 A^T
        ar = row3(states, b, BODY_ROT + 3 * r)
        t = (ar[0] * inv[0][0] + ar[1] * inv[1][0] + ar[2] * inv[2][0],
             ar[0] * inv[0][1] + ar[1] * inv[1][1] + ar[2] * inv[2][1],
             ar[0] * inv[0][2] + ar[1] * inv[1][2] + ar[2] * inv[2][2])
        for k in range(r + 1):
            v = dot(t, row3(states, b, BODY_ROT + 3 * k))
            states[b, BODY_JINV + 3 * r + k] = states[b, BODY_JINV + 3 * k + r] = v
    faces = int(flex[b, C_FACES])
    states[b, NFACES] = faces
    for k in range(faces):
        at, f = flex_column(n, 6, k), FACES + k * FACE
        for a in range(3):
            states[b, f + F_CENTRE + a] = flex[b, at + a]
            move = turn = move_rate = turn_rate = 0.0
            for j in range(n):
                t, r = flex[b, at + 3 + a * n + j], flex[b, at + 3 + 3 * n + a * n + j]
                states[b, f + F_T + a * MODES + j], states[b, f + F_R + a * MODES + j] = t, r
                move += t * y[q + j]
                turn += r * y[q + j]
                move_rate += t * y[nq + q + j]
                turn_rate += r * y[nq + q + j]
            states[b, f + F_MOVE + a], states[b, f + F_TURN + a] = move, turn
            states[b, f + F_MOVE_RATE + a], states[b, f + F_TURN_RATE + a] = move_rate, turn_rate


@numba.njit(cache=True, _nrt=False)
def g_dot(states, b, n, a, c):
    """(G G^T)[a, c] of body b's row."""
    v = 0.0
    for m in range(n):
        v += states[b, GMAT + a * MODES + m] * states[b, GMAT + c * MODES + m]
    return v


@numba.njit(cache=True, _nrt=False)
def block_times(states, b, k, a):
    """The 3 x 3 block of body b's row from column k (row-major) times a."""
    return (dot(row3(states, b, k), a), dot(row3(states, b, k + 3), a),
            dot(row3(states, b, k + 6), a))


@numba.njit(cache=True, _nrt=False)
def turned(states, b, a):
    """A a: a body-frame vector of body b in global axes."""
    return block_times(states, b, BODY_ROT, a)


@numba.njit(cache=True, _nrt=False)
def unturned(states, b, a):
    """A^T a: a global vector in body b's axes."""
    return add(add(scaled(row3(states, b, BODY_ROT), a[0]), scaled(row3(states, b, BODY_ROT + 3), a[1])),
               scaled(row3(states, b, BODY_ROT + 6), a[2]))


@numba.njit(cache=True, _nrt=False)
def inverse_inertia_times(states, b, a):
    """A J'^-1 A^T a (global; a flexible body's A sigma^-1 A^T)."""
    return block_times(states, b, BODY_JINV, a)


@numba.njit(cache=True, _nrt=False)
def modal_g(states, b, src, at):
    """G v (body frame) of v = src[at .. at + n - 1]."""
    out = (0.0, 0.0, 0.0)
    for m in range(int(states[b, NMODES])):
        v = src[at + m]
        out = (out[0] + states[b, GMAT + m] * v, out[1] + states[b, GMAT + MODES + m] * v,
               out[2] + states[b, GMAT + 2 * MODES + m] * v)
    return out


@numba.njit(cache=True, _nrt=False)
def modal_g_row(states, b, src, row, at):
    """G v (body frame) of v = src[row, at .. at + n - 1] (read in place: a row view would
    count its references)."""
    out = (0.0, 0.0, 0.0)
    for m in range(int(states[b, NMODES])):
        v = src[row, at + m]
        out = (out[0] + states[b, GMAT + m] * v, out[1] + states[b, GMAT + MODES + m] * v,
               out[2] + states[b, GMAT + 2 * MODES + m] * v)
    return out


# ---- a flexible body's interfaces: a point of the body moves with the frame of its nearest
# interface (tied rigidly, fem.modes.reduction), u = T_k eta + (R_k eta) x (s - x_k)
@numba.njit(cache=True, _nrt=False)
def face_of(states, b, s):
    """The column where body b's interface nearest the body point s starts."""
    best, at = math.inf, FACES
    for k in range(int(states[b, NFACES])):
        f = FACES + k * FACE
        d = (s[0] - states[b, f]) ** 2 + (s[1] - states[b, f + 1]) ** 2 + (s[2] - states[b, f + 2]) ** 2
        if d < best:
            best, at = d, f
    return at


@numba.njit(cache=True, _nrt=False)
def deformed(states, b, f, s):
    """(s + u, u') of the body point s on the interface at column f (body frame)."""
    e = sub(s, row3(states, b, f + F_CENTRE))
    return (add(add(s, row3(states, b, f + F_MOVE)), cross(row3(states, b, f + F_TURN), e)),
            add(row3(states, b, f + F_MOVE_RATE), cross(row3(states, b, f + F_TURN_RATE), e)))


@numba.njit(cache=True, _nrt=False)
def undeformed(states, b, f, s):
    """The body point whose deformed place is s (body frame), from the interface centre, on
    the interface at column f: e = s - x_k - T_k eta turned back by the inverse of
    I + theta x (theta = R_k eta), (e - theta x e + (theta . e) theta) / (1 + |theta|^2)."""
    theta = row3(states, b, f + F_TURN)
    e = sub(sub(s, row3(states, b, f + F_CENTRE)), row3(states, b, f + F_MOVE))
    return scaled(add(sub(e, cross(theta, e)), scaled(theta, dot(theta, e))),
                  1.0 / (1.0 + dot(theta, theta)))


@numba.njit(cache=True, _nrt=False)
def modal_columns(jac, row, states, b, f, e, l, rho, sign, column):
    """Add sign (l . (T_k,j + R_k,j x e) + rho . R_k,j) to the modal columns of a row: l the
    row's linear coefficient in the body frame, e the point from the interface centre, rho the
    rotation part of its angular coefficient (body frame)."""
    arm = add(cross(e, l), rho)   # R_j . (e x l) + R_j . rho
    for j in range(int(states[b, NMODES])):
        t = (states[b, f + F_T + j], states[b, f + F_T + MODES + j], states[b, f + F_T + 2 * MODES + j])
        r = (states[b, f + F_R + j], states[b, f + F_R + MODES + j], states[b, f + F_R + 2 * MODES + j])
        jac[row, column + j] += sign * (dot(l, t) + dot(arm, r))


@numba.njit(cache=True, _nrt=False)
def modal_forces(force, states, b, f, e, l, torque, column):
    """Add the modes' generalised force of a force l (body frame) at e from the interface
    centre and a torque (body frame) on its frame: T_k^T l + R_k^T (e x l + torque)."""
    arm = add(cross(e, l), torque)
    for j in range(int(states[b, NMODES])):
        t = (states[b, f + F_T + j], states[b, f + F_T + MODES + j], states[b, f + F_T + 2 * MODES + j])
        r = (states[b, f + F_R + j], states[b, f + F_R + MODES + j], states[b, f + F_R + 2 * MODES + j])
        force[column + j] += dot(l, t) + dot(arm, r)


# ---- points and vectors
@numba.njit(cache=True, _nrt=False)
def point_state(states, b, s_body):
    if b < 0:
        return s_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    w = row3(states, b, BODY_OMEGA)
    if flexible(states, b):   # P = r + A (s + u), P' = r' + w x A (s + u) + A u'
        place, rate = deformed(states, b, face_of(states, b, s_body), s_body)
        s, v = turned(states, b, place), turned(states, b, rate)
        ws = cross(w, s)
        return (add(row3(states, b, BODY_POS), s), add(add(row3(states, b, BODY_VEL), ws), v),
                add(cross(w, ws), scaled(cross(w, v), 2.0)), s)
    s = turned(states, b, s_body)
    ws = cross(w, s)
    return (add(row3(states, b, BODY_POS), s), add(row3(states, b, BODY_VEL), ws), cross(w, ws), s)


@numba.njit(cache=True, _nrt=False)
def vector_state(states, b, s, a_body):
    if b < 0:
        return a_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    w = row3(states, b, BODY_OMEGA)
    if flexible(states, b):
        # turned with the interface's frame by its small turn R_k eta: a = A (a0 + theta x a0)
        # turns at W = w + A theta', and W' = w' + A theta'' + w x A theta' (A theta' is
        # given in the turning body): the velocity terms of a'' = W' x a + W x (W x a) are
        # (w x A theta') x a + W x (W x a)
        f = face_of(states, b, s)
        a_body = add(a_body, cross(row3(states, b, f + F_TURN), a_body))
        a = turned(states, b, a_body)
        turn = turned(states, b, row3(states, b, f + F_TURN_RATE))
        big = add(w, turn)
        wa = cross(big, a)
        return a, wa, add(cross(big, wa), cross(cross(w, turn), a))
    a = turned(states, b, a_body)
    wa = cross(w, a)
    return a, wa, cross(w, wa)


@numba.njit(cache=True, _nrt=False)
def material_velocity(states, b, x):
    if b < 0:
        return (0.0, 0.0, 0.0)
    arm = sub(x, row3(states, b, BODY_POS))
    v = add(row3(states, b, BODY_VEL), cross(row3(states, b, BODY_OMEGA), arm))
    if flexible(states, b):
        s = unturned(states, b, arm)
        f = face_of(states, b, s)
        rate = add(row3(states, b, f + F_MOVE_RATE),
                   cross(row3(states, b, f + F_TURN_RATE), undeformed(states, b, f, s)))
        return add(v, turned(states, b, rate))
    return v


@numba.njit(cache=True, _nrt=False)
def put(jac, row, states, b, s, linear, angular, sign, offsets):
    if b < 0:
        return
    col = offsets[b]
    for k in range(3):
        jac[row, col + k] += sign * linear[k]
        jac[row, col + 3 + k] += sign * angular[k]
    if flexible(states, b):
        f = face_of(states, b, s)
        place = deformed(states, b, f, s)[0]
        l = unturned(states, b, linear)
        rho = sub(unturned(states, b, angular), cross(place, l))   # less the point's arm x linear
        modal_columns(jac, row, states, b, f, sub(s, row3(states, b, f + F_CENTRE)), l, rho, sign,
                      col + COLUMNS)


@numba.njit(cache=True, _nrt=False)
def push(force, states, b, f, x, offsets):
    if b < 0:
        return
    arm = sub(x, row3(states, b, BODY_POS))
    torque = cross(arm, f)
    col = offsets[b]
    for c in range(3):
        force[col + c] += f[c]
        force[col + 3 + c] += torque[c]
    if flexible(states, b):
        s = unturned(states, b, arm)
        face = face_of(states, b, s)
        modal_forces(force, states, b, face, undeformed(states, b, face, s), unturned(states, b, f),
                     (0.0, 0.0, 0.0), col + COLUMNS)


@numba.njit(cache=True, _nrt=False)
def push_torque(force, states, b, s, torque, offsets):
    if b < 0:
        return
    col = offsets[b]
    for c in range(3):
        force[col + 3 + c] += torque[c]
    if flexible(states, b):
        modal_forces(force, states, b, face_of(states, b, s), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                     unturned(states, b, torque), col + COLUMNS)


@numba.njit(cache=True, _nrt=False)
def relative_rotation(states, bi, bj, s_i, s_j, a_i, b_j, c_i, offset, drift):
    """atan2(c_i . b_j, a_i . b_j) less offset and drift, modulo 2 pi, with its Jacobian
    coefficient, rate and the velocity part of its second derivative."""
    c_, kc, cd, cacc = dot1(states, bi, s_i, a_i, bj, s_j, b_j)
    s_, ks, sd, sacc = dot1(states, bi, s_i, c_i, bj, s_j, b_j)
    rho2 = s_ * s_ + c_ * c_
    coefficient = scaled(sub(scaled(ks, c_), scaled(kc, s_)), 1.0 / rho2)
    rate = (c_ * sd - s_ * cd) / rho2
    gap = math.atan2(s_, c_) - offset - drift
    angle = gap - 2 * math.pi * math.floor(gap / (2 * math.pi) + 0.5)
    return angle, coefficient, rate, -(c_ * sacc - s_ * cacc) / rho2 + 2 * rate * (s_ * sd + c_ * cd) / rho2


@numba.njit(cache=True, _nrt=False)
def body_columns(like):
    return BODY_COLUMNS


@numba.njit(cache=True, _nrt=False)
def centripetal_gap(states, a, bi, arm_i, c_i, bj, arm_j, c_j):
    return dot(a, sub(c_j, c_i))


@numba.njit(cache=True, _nrt=False)
def rotation_axis(states, bi, s_i, a_i, c_i):
    return cross(vector_state(states, bi, s_i, a_i)[0], vector_state(states, bi, s_i, c_i)[0])


@numba.njit(cache=True, _nrt=False)
def row_rate(rate, jac, i, b, states, velocities, offsets, like):
    col = offsets[b]
    for c in range(3):
        rate += (jac[i, col + c] * states[b, BODY_VEL + c]
                 + jac[i, col + 3 + c] * states[b, BODY_OMEGA + c])
    for j in range(int(states[b, NMODES])):
        rate += jac[i, col + COLUMNS + j] * states[b, ETA_RATE + j]
    return rate


@numba.njit(cache=True, _nrt=False)
def turned_any(states, b, a):
    """turned, the ground's vectors global."""
    return turned(states, b, a) if b >= 0 else a


@numba.njit(cache=True, _nrt=False)
def unturned_any(states, b, a):
    """unturned, the ground's vectors global."""
    return unturned(states, b, a) if b >= 0 else a


# ---- the whole body (the signatures of reduced.mechanism.bodies: the unused arrays are
# other kinds')
@numba.njit(cache=True, _nrt=False)
def body_forces(kind, masses, minv, inertia, gravity, flex, states, force):
    """Gravity and the gyroscopic torque -w x (J w) of each body; a flexible body's
    quadratic velocity, elastic and damping forces (flexible_forces). Returns the power the
    modal damping dissipates."""
    power = 0.0
    for b in range(masses.size):
        col = int(states[b, FIRST])
        if states[b, NMODES] > 0:
            for c in range(3):
                force[col + c] = masses[b] * gravity[c]
            power += flexible_forces(flex, b, states, force, col)
            continue
        w = row3(states, b, BODY_OMEGA)
        jw = turned(states, b, matvec(inertia, b, unturned(states, b, w)))
        gyro = cross(w, jw)
        for c in range(3):
            force[col + c] = masses[b] * gravity[c]
            force[col + 3 + c] = -gyro[c]
    return power


@numba.njit(cache=True, _nrt=False)
def moment_rate(flex, b, n, states, a, c):
    """d/dt I_ac(eta) = (s_ac + s_ca) . eta' + eta'^T S_ac eta + eta^T S_ac eta'; with the
    stiffening's d/dt (eta^T K_G,ac eta) second."""
    s_block, big_s, kg = flex_column(n, 3, 0), flex_column(n, 4, 0), flex_column(n, 5, 0)
    ac, ca = 3 * a + c, 3 * c + a
    v, k_rate = 0.0, 0.0
    for k in range(n):
        ek, rk = states[b, ETA + k], states[b, ETA_RATE + k]
        v += rk * (flex[b, s_block + ac * n + k] + flex[b, s_block + ca * n + k])
        for j in range(n):
            ej, rj = states[b, ETA + j], states[b, ETA_RATE + j]
            sv = flex[b, big_s + ac * n * n + k * n + j]
            v += sv * (rk * ej + ek * rj)
            k_rate += 2 * rk * flex[b, kg + ac * n * n + k * n + j] * ej
    return v, k_rate


@numba.njit(cache=True, _nrt=False)
def flexible_forces(flex, b, states, force, col):
    """The rotation's -w x A h' - A J' w' (global) and the modes' w'^T (dJ/deta) w' / 2 +
    2 sum_a w'_a S^_a eta' - omega^2 eta - 2 zeta omega eta' into body b's columns from col;
    returns the power of the modal damping."""
    n = int(states[b, NMODES])
    omega2, damping = flex_column(n, 0, 0), flex_column(n, 1, 0)
    s_block, big_s, kg = flex_column(n, 3, 0), flex_column(n, 4, 0), flex_column(n, 5, 0)
    w = row3(states, b, BODY_OMEGA)
    wb = unturned(states, b, w)
    jw = block_times(states, b, JBODY, wb)
    h = add(jw, modal_g_row(states, b, states, b, ETA_RATE))
    # J' w' (body): J'_ac = delta_ac tr(I') - I'_ac - (eta^T K_G,ac eta)'
    i00, k00 = moment_rate(flex, b, n, states, 0, 0)
    i11, k11 = moment_rate(flex, b, n, states, 1, 1)
    i22, k22 = moment_rate(flex, b, n, states, 2, 2)
    i01, k01 = moment_rate(flex, b, n, states, 0, 1)
    i02, k02 = moment_rate(flex, b, n, states, 0, 2)
    i12, k12 = moment_rate(flex, b, n, states, 1, 2)
    trace = i00 + i11 + i22
    jd = ((trace - i00 - k00, -i01 - k01, -i02 - k02), (-i01 - k01, trace - i11 - k11, -i12 - k12),
          (-i02 - k02, -i12 - k12, trace - i22 - k22))
    jdw = (dot(jd[0], wb), dot(jd[1], wb), dot(jd[2], wb))
    torque = add(cross(w, turned(states, b, h)), turned(states, b, jdw))
    for c in range(3):
        force[col + 3 + c] = -torque[c]
    ww = dot(wb, wb)
    power = 0.0
    for k in range(n):
        centrifugal = 0.0   # w'^T (dJ/deta_k) w' / 2
        for a in range(3):
            for c in range(3):
                ac = 3 * a + c
                d = flex[b, s_block + ac * n + k]
                kgk = 0.0
                for j in range(n):
                    d += flex[b, big_s + ac * n * n + k * n + j] * states[b, ETA + j]
                    kgk += flex[b, kg + ac * n * n + k * n + j] * states[b, ETA + j]
                if a == c:
                    centrifugal += ww * d
                centrifugal -= wb[a] * wb[c] * (d + kgk)
        spin = 0.0
        for a in range(3):
            for m in range(n):
                spin += wb[a] * gyroscopic(flex, b, n, a, k, m) * states[b, ETA_RATE + m]
        rate = states[b, ETA_RATE + k]
        force[col + COLUMNS + k] = (centrifugal + 2 * spin - flex[b, omega2 + k] * states[b, ETA + k]
                                    - flex[b, damping + k] * rate)
        power += flex[b, damping + k] * rate * rate
    return power


@numba.njit(cache=True, _nrt=False)
def fill_schur(kind, masses, minv, offsets, states, jac, mjac, schur, row_bodies, first, m):
    """M^-1 D^T (rows of mjac): a row has nonzero columns for its two bodies only, and M^-1
    (block-diagonal: m I and the global inverse inertia; a flexible body's rotation and modes
    coupled: the angular part a = sigma^-1 (v_w - B v_eta), B = A G, the modal part
    v_eta - B^T a) acts on those."""
    for i in range(m):
        for side in range(2):
            b = row_bodies[i, side]
            if b < 0:
                continue
            col = offsets[b]
            w = (jac[i, col + 3], jac[i, col + 4], jac[i, col + 5])
            if states[b, NMODES] > 0:
                w = sub(w, turned(states, b, modal_g_row(states, b, jac, i, col + COLUMNS)))
            a = inverse_inertia_times(states, b, w)
            for c in range(3):
                mjac[i, col + c] = jac[i, col + c] / masses[b]
                mjac[i, col + 3 + c] = a[c]
            ab = unturned(states, b, a)
            for j in range(int(states[b, NMODES])):
                mjac[i, col + COLUMNS + j] = jac[i, col + COLUMNS + j] - (
                    states[b, GMAT + j] * ab[0] + states[b, GMAT + MODES + j] * ab[1]
                    + states[b, GMAT + 2 * MODES + j] * ab[2])
    schur_within_envelope(jac, mjac, schur, row_bodies, first, offsets, m, False)


@numba.njit(cache=True, _nrt=False)
def state_rates(kind, y, dy, nq, masses, minv, baumgarte, states, force):
    """Velocities, accelerations r'' = F / m and the Euler parameters' second derivatives
    p'' = G^T (A^T w')/2 + k p with their normalisation and its Baumgarte terms; a flexible
    body's modal accelerations."""
    alpha = baumgarte
    for b in range(masses.size):
        i, col, n = int(states[b, COORD]), int(states[b, FIRST]), int(states[b, NMODES])
        for c in range(3):
            dy[i + c] = y[nq + i + c]
            dy[nq + i + c] = force[col + c] / masses[b]
        for c in range(4):
            dy[i + 3 + c] = y[nq + i + 3 + c]
        w = vec3(force, col + 3)
        if n > 0:
            w = sub(w, turned(states, b, modal_g(states, b, force, col + COLUMNS)))
        wd = inverse_inertia_times(states, b, w)   # w' (global)
        ab = unturned(states, b, wd)
        for j in range(n):   # eta'' = Q_eta - B^T w'
            dy[i + COORDINATES + j] = y[nq + i + COORDINATES + j]
            dy[nq + i + COORDINATES + j] = force[col + COLUMNS + j] - (
                states[b, GMAT + j] * ab[0] + states[b, GMAT + MODES + j] * ab[1]
                + states[b, GMAT + 2 * MODES + j] * ab[2])
        p = unit_parameters(y, i + 3)
        pd = vec3(y, nq + i + 3) + (y[nq + i + 6],)
        half = gt_times(p, scaled(unturned(states, b, wd), 0.5))
        pp = p[0] ** 2 + p[1] ** 2 + p[2] ** 2 + p[3] ** 2
        raw = vec3(y, i + 3) + (y[i + 6],)
        norm2 = raw[0] ** 2 + raw[1] ** 2 + raw[2] ** 2 + raw[3] ** 2
        along = (-(pd[0] ** 2 + pd[1] ** 2 + pd[2] ** 2 + pd[3] ** 2)
                 - 2 * alpha * (raw[0] * pd[0] + raw[1] * pd[1] + raw[2] * pd[2] + raw[3] * pd[3])
                 - 0.5 * alpha * alpha * (norm2 - 1.0)) / pp
        for c in range(4):
            dy[nq + i + 3 + c] = half[c] + along * p[c]


@numba.njit(cache=True, _nrt=False)
def normalise(kind, y, nq, offsets):
    """Euler parameters to unit length, their rates normal to them."""
    for b in range(offsets.size - 1):
        normalise_at(y, nq, offsets[b] + b + 3)


@numba.njit(cache=True, _nrt=False)
def normalise_at(y, nq, i):
    """The Euler parameters at y[i] to unit length, their rates normal to them."""
    n = math.sqrt(y[i] ** 2 + y[i + 1] ** 2 + y[i + 2] ** 2 + y[i + 3] ** 2)
    along = 0.0
    for c in range(4):
        y[i + c] /= n
        along += y[i + c] * y[nq + i + c]
    for c in range(4):
        y[nq + i + c] -= along * y[i + c]


@numba.njit(cache=True, _nrt=False)
def turn(y, i, rotation_vector):
    """Turn a body (its Euler parameters at y[i]) by a small global rotation vector:
    p <- (cos(|r|/2), sin(|r|/2) r/|r|) p."""
    angle = math.sqrt(dot(rotation_vector, rotation_vector))
    if angle == 0.0:
        return
    k = math.sin(0.5 * angle) / angle
    a0, a = math.cos(0.5 * angle), scaled(rotation_vector, k)
    b0, bv = y[i], (y[i + 1], y[i + 2], y[i + 3])
    v = add(add(scaled(bv, a0), scaled(a, b0)), cross(a, bv))
    y[i], y[i + 1], y[i + 2], y[i + 3] = a0 * b0 - dot(a, bv), v[0], v[1], v[2]


@numba.njit(cache=True, _nrt=False)
def column_step(mjac, x, m, column, scale):
    """-scale (M^-1 D^T x) in one velocity column."""
    step = 0.0
    for i in range(m):
        step -= mjac[i, column] * x[i]
    return step * scale if scale != 1.0 else step


@numba.njit(cache=True, _nrt=False)
def mass_weighted_step(y, nq, mjac, x, states, m, level, scale):
    """-scale M^-1 D^T x per body: level 0 moves the centres and turns the bodies by the
    rotation part (a flexible body's modal coordinates by theirs); level 1 changes the
    velocities and the parameters' rates (and the modal rates)."""
    nb = states.shape[0]
    for b in range(nb):
        col, i, n = int(states[b, FIRST]), int(states[b, COORD]), int(states[b, NMODES])
        step = (column_step(mjac, x, m, col, scale), column_step(mjac, x, m, col + 1, scale),
                column_step(mjac, x, m, col + 2, scale), column_step(mjac, x, m, col + 3, scale),
                column_step(mjac, x, m, col + 4, scale), column_step(mjac, x, m, col + 5, scale))
        if level == 0:
            for c in range(3):
                y[i + c] += step[c]
            turn(y, i + 3, (step[3], step[4], step[5]))
            for j in range(n):
                y[i + COORDINATES + j] += column_step(mjac, x, m, col + COLUMNS + j, scale)
        else:
            for c in range(3):
                y[nq + i + c] += step[c]
            w = add(row3(states, b, BODY_OMEGA), (step[3], step[4], step[5]))
            pd = gt_times(unit_parameters(y, i + 3), scaled(unturned(states, b, w), 0.5))
            for c in range(4):
                y[nq + i + 3 + c] = pd[c]
            for j in range(n):
                y[nq + i + COORDINATES + j] += column_step(mjac, x, m, col + COLUMNS + j, scale)
    for b in range(nb):
        normalise_at(y, nq, int(states[b, COORD]) + 3)


@numba.njit(cache=True, _nrt=False)
def position_step(kind, y, nq, minv, jac, mjac, x, states, m):
    mass_weighted_step(y, nq, mjac, x, states, m, 0, 1.0)


@numba.njit(cache=True, _nrt=False)
def velocity_step(kind, y, nq, minv, jac, mjac, x, states, m, scale):
    mass_weighted_step(y, nq, mjac, x, states, m, 1, scale)


@numba.njit(cache=True, _nrt=False)
def kinetic_energy(kind, y, nq, masses, minv, inertia, flex, offsets):
    """1/2 m v.v + 1/2 w'.J' w' of every body (w' = 2 G p' in the body frame); a flexible
    body's w'^T J(eta) w' / 2 + w'^T G eta' + |eta'|^2 / 2."""
    energy = 0.0
    for b in range(masses.size):
        i = offsets[b] + b
        v = vec3(y, nq + i)
        p = unit_parameters(y, i + 3)
        w = scaled(g_times(p, vec3(y, nq + i + 3) + (y[nq + i + 6],)), 2.0)
        n = offsets[b + 1] - offsets[b] - COLUMNS
        if n == 0:
            energy += 0.5 * masses[b] * dot(v, v) + 0.5 * dot(w, matvec(inertia, b, w))
            continue
        q = i + COORDINATES
        j = inertia_of(flex, b, n, y, q)
        jw = (j[0] * w[0] + j[1] * w[1] + j[2] * w[2], j[3] * w[0] + j[4] * w[1] + j[5] * w[2],
              j[6] * w[0] + j[7] * w[1] + j[8] * w[2])
        coupling, modal = 0.0, 0.0
        for a in range(3):
            for mm in range(n):
                coupling += w[a] * g_row(flex, b, n, y, q, a, mm) * y[nq + q + mm]
        for mm in range(n):
            modal += y[nq + q + mm] ** 2
        energy += 0.5 * masses[b] * dot(v, v) + 0.5 * dot(w, jw) + coupling + 0.5 * modal
    return energy


# spatial bodies implement reduced.mechanism.bodies for their marker and 3-vectors (the
# ground's vectors global when turned)
bodies.implement_kind(globals() | {"turned": turned_any, "unturned": unturned_any},
                      {"kind": spatial, "vector": _space})


def strain_energy(model, q) -> np.ndarray:
    """The flexible bodies' strain energy at the steps (J)."""
    return model.geometry.strain_energy(model.names, q)


def constants(flexible) -> np.ndarray:
    """A flexible body's row of Args.flex (flex_column)."""
    b, n = flexible.body, flexible.n
    omega = b.omega[:n]
    parts = [[n, len(b.interfaces)], omega ** 2, 2 * flexible.ratios * omega, b.second_moments,
             b.s[:, :, :n], b.S[:, :, :n, :n], flexible.stiffening_matrices]
    for k in range(len(b.interfaces)):
        parts += [flexible.centres[k], b.interface_translation[k, :, :n], b.interface_rotation[k, :, :n]]
    return np.concatenate([np.asarray(p, float).ravel() for p in parts])


# ---- a spatial scene as the model's arrays (reduced.mechanism.model.build asks these)
MARKER = layout.SPATIAL
RIGID_COLUMNS = BODY_OMEGA + 3   # what a run's record keeps of a body's row (its angular velocity)
PROJECT_FIRST = True    # an accepted step is projected before its events are read (layout.Args)
PARALLEL = 1e-9   # |1 - |u_b . u_j|| below which a journal's axis is aligned with its bore's


class Geometry(FlexibleGeometry):
    """A spatial scene's bodies and ideal joints as the model's arrays: the coordinates, the
    mass, the primitive constraints ([Nikravesh1988] ch. 7), the contacts of a cylindrical or
    spherical clearance joint, torsion elements, and the consistent initial state."""

    DIM, RIGID_COLUMNS, RIGID_COORDINATES, MODES, INTERFACES = 3, COLUMNS, COORDINATES, MODES, INTERFACES

    def __init__(self, scene, index, source, base=None):
        self.scene, self.index, self.source = scene, index, source
        self.rot = {GROUND: np.eye(3)} | {b.name: rotation_matrix(b.parameters()) for b in scene.bodies}
        self.read_flexible(scene, index, source, base)
        self.nq = int(self.columns[-1]) + len(scene.bodies)   # 7 + n coordinates a body

    def attachments(self):
        """(body, point, key) of every point a joint, spring or contact fixes on a body (a
        drive turns its joint's points)."""
        scene, found = self.scene, []
        for j in scene.joints:
            found += [(j.body_i, j.point_i, "joints.point_i"), (j.body_j, j.point_j, "joints.point_j")]
        for table in ("clearance_joints", "translational_joints"):
            for c in getattr(scene, table):
                found += [(c.bearing_body, c.bearing_point, f"{table}.bearing_point"),
                          (c.journal_body, c.journal_point, f"{table}.journal_point")]
        for t in scene.torsion:
            found += [(t.body_i, self.frame_point(t.body_i, t.point_i), "torsion.point_i"),
                      (t.body_j, self.frame_point(t.body_j, t.point_j), "torsion.point_j")]
        return found

    def mass(self):
        """(masses, no per-column inverse masses, inertia tensors in the body frames: a flexible
        body's undeformed)."""
        bodies = self.scene.bodies
        inertia = [self.flexible[b.name].inertia if b.flexible else b.inertia for b in bodies]
        masses = [self.flexible[b.name].mass if b.flexible else b.mass for b in bodies]
        return (np.array(masses, float), np.zeros(int(self.columns[-1])), np.array(inertia, float))

    def coordinate(self, b: int) -> int:
        """Body b's first coordinate in q."""
        return int(self.columns[b]) + b

    @staticmethod
    def constants(flexible) -> np.ndarray:
        return constants(flexible)

    def primitives(self, closures):
        """Every ideal joint's primitives, the clearance joints closed by `closures`, then the
        drive (the relative angle of its joint's bodies about the joint's axis): (rows, the
        drive's row or None)."""
        index, rot = self.index, self.rot
        rows, named = [], {}
        for j in self.scene.joints:
            u_i = unit_axis(j.axis_i, "axis_i") if j.axis_i else [0, 0, 1]
            u_j = unit_axis(j.axis_j, "axis_j") if j.axis_j else [0, 0, 1]
            rows += joint_primitives(j.type, index[j.body_i], index[j.body_j], j.point_i, j.point_j,
                                     np.array(u_i), np.array(u_j), rot[j.body_i], rot[j.body_j],
                                     self.source)
            if j.name:
                named[j.name] = (j, np.array(u_i))
        rows += [r for closure in closures for r in closure]
        if self.scene.drive is None:
            return rows, None
        j, u_i = named[self.scene.drive.joint]
        f, g = normals(u_i)
        rows.append(primitive(ANGLE, index[j.body_i], index[j.body_j], j.point_i, j.point_j, a_i=f,
                              b_j=rot[j.body_j].T @ rot[j.body_i] @ f, c_i=g,
                              speed=self.scene.drive.speed, profile=self.scene.drive.profile_columns()))
        return rows, len(rows) - 1

    def closing(self, c) -> list:
        """A clearance joint closed (ideal_kind): a revolute on the bore's axis, or a
        spherical joint for a ball or a misaligned journal."""
        u_b = np.array(unit_axis(c.bearing_axis, "bearing_axis")) if c.bearing_axis else np.zeros(3)
        u_j = np.array(unit_axis(c.journal_axis, "journal_axis")) if c.journal_axis else np.zeros(3)
        kind = ideal_kind(c, self.rot[c.bearing_body] @ u_b, self.rot[c.journal_body] @ u_j)
        return joint_primitives(kind, self.index[c.bearing_body], self.index[c.journal_body],
                                c.bearing_point, c.journal_point, u_b, u_j, self.rot[c.bearing_body],
                                self.rot[c.journal_body], "clearance_joints")

    def contacts(self, c, deltas, laws_data, source):
        """A ball: one RADIAL contact (its normal force at the two centres, friction at the
        contact point); a journal: the journal along its bore (SLICED; with rigid impacts its
        two ends, AXIS_RADIAL) and its shoulders (PLANE, two-sided, frictionless): the
        contacts' geometry and the force (N) or force per length (N/m) of its law at
        `deltas`."""
        from pinbore.reduced.mechanism.model import per_length_table   # noqa: PLC0415 (model imports us)

        bb, bj = self.index[c.bearing_body], self.index[c.journal_body]
        base = {layout.CONTACT_BEARING_BODY: bb, layout.CONTACT_JOURNAL_BODY: bj,
                layout.CONTACT_BEARING_POINT: list(c.bearing_point),
                layout.CONTACT_JOURNAL_POINT: list(c.journal_point),
                layout.CONTACT_CLEARANCE: c.bearing_radius - c.journal_radius,
                layout.CONTACT_RADIUS: c.bearing_radius}
        table = np.full(deltas.size, np.nan)   # rigid: no law, never evaluated
        scale = end = bulk = 0.0
        if c.impact == "continuous":
            scale, end, bulk, table = per_length_table(c, deltas, laws_data, source)
        if c.type == "spherical":
            return [base | {layout.CONTACT_KIND: layout.RADIAL}], table
        u_b = unit_axis(c.bearing_axis, "bearing_axis")
        u_j = unit_axis(c.journal_axis, "journal_axis")
        if c.impact == "continuous":
            out = [base | {layout.CONTACT_KIND: layout.SLICED, layout.CONTACT_BEARING_AXIS: u_b,
                           layout.CONTACT_JOURNAL_AXIS: u_j, layout.CONTACT_LENGTH: c.length,
                           layout.CONTACT_SLICES: c.slices, layout.CONTACT_END_LENGTH: end,
                           layout.CONTACT_SCALE: scale, layout.CONTACT_COMPLIANCE: bulk}]
        else:   # the journal's two ends against the bore's axis
            out = [base | {layout.CONTACT_KIND: layout.AXIS_RADIAL, layout.CONTACT_BEARING_AXIS: u_b,
                           layout.CONTACT_JOURNAL_POINT: list(np.asarray(c.journal_point)
                                                              + side * 0.5 * c.length * np.asarray(u_j))}
                   for side in (-1.0, 1.0)]
        if c.axial_clearance is not None:
            out.append(base | {layout.CONTACT_KIND: layout.PLANE, layout.CONTACT_BEARING_AXIS: u_b,
                               layout.CONTACT_CLEARANCE: c.axial_clearance,
                               layout.CONTACT_STIFFNESS: c.axial_stiffness if c.impact == "continuous" else 0.0,
                               layout.CONTACT_SIDE: 0.0, layout.CONTACT_FRICTION_ON: 0.0})
        return out, table

    def torsion(self, t) -> dict:
        """The relative angle about u_i = a_i x c_i (body i) from a_i to b_j (body j: a_i
        in its frame at the start), beyond the free angle."""
        u = np.array(unit_axis(t.axis_i, "axis_i"))
        f, g = normals(u)
        return {layout.TORSION_FREE_ANGLE: math.radians(t.free_angle_deg), layout.TORSION_A_I: list(f),
                layout.TORSION_C_I: list(g),
                layout.TORSION_B_J: list(self.rot[t.body_j].T @ self.rot[t.body_i] @ f),
                layout.TORSION_S_I: self.frame_point(t.body_i, t.point_i),
                layout.TORSION_S_J: self.frame_point(t.body_j, t.point_j)}

    def inverse_inertia(self, b, t) -> float:
        """u . J^-1 u of body b about a torsion element's axis u (body i's axis, in b's frame)."""
        body = self.scene.bodies[b]
        u = self.rot[body.name].T @ self.rot[t.body_i] @ np.array(unit_axis(t.axis_i, "axis_i"))
        inertia = self.flexible[body.name].inertia if body.flexible else body.inertia
        return float(u @ np.linalg.solve(np.array(inertia), u))

    def place(self, model, closings) -> np.ndarray:
        """Positions on the ideal joints with the clearance joints that start "ideal" or
        "free" closed (mass-weighted least change from the scene's guesses); then the
        velocities as given (each body's r' and global w, on the positions found), projected
        onto the ideal joints and the clearance joints that start "ideal" (those that start
        "free" keep their relative velocity; "placed" ones keep their positions too)."""
        from pinbore.reduced.mechanism import kernel as engine   # noqa: PLC0415 (the engine)

        s = self.scene
        nb = len(s.bodies)
        nq = COORDINATES * nb   # placed as rigid bodies: a flexible body starts undeformed, at
        #                         rest in its frame, where its mass matrix is the rigid one's
        rigid = dict(nq=nq, offsets=COLUMNS * np.arange(nb + 1), flex=np.zeros((nb, 0)),
                     minv=np.zeros(COLUMNS * nb))
        y = np.concatenate([np.concatenate([[*b.position, *b.parameters()] for b in s.bodies]),
                            np.zeros(nq + layout.ENERGY_STATES + model.friction_states)])
        for starts in (("ideal", "free"), ("ideal",)):
            for k, b in enumerate(s.bodies):   # the given velocities at the current orientation
                p = y[7 * k + 3:7 * k + 7] / np.linalg.norm(y[7 * k + 3:7 * k + 7])
                w_body = rotation_matrix(p).T @ np.array(b.omega, float)
                y[nq + 7 * k:nq + 7 * k + 7] = [*b.velocity, *gt_times(p, tuple(0.5 * w_body))]
            extra = [r for rows, start in closings if start in starts for r in rows]
            primitives = np.vstack([model.primitives,
                                    np.array(extra, float).reshape(-1, layout.PRIMITIVE_COLUMNS)])
            args = model.args(primitives=primitives)._replace(**rigid)
            work = engine.workspace(args)
            for _ in range(50):
                if not engine.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
                    break
            _, phi, _ = engine.constraint_values(0.0, y, args)
            gap = np.max(np.abs(phi), initial=0.0)
            if gap >= 1e-12:
                raise InputError(f"{self.source}: joints: the bodies cannot be placed so that "
                                 f"every joint closes (largest gap {gap:.3g})")
        return self.with_modes(y, nq)

    def with_modes(self, y, rigid_nq) -> np.ndarray:
        """A state of the bodies as rigid (7 coordinates each) with the flexible bodies'
        modal coordinates and rates (zero) inserted."""
        q, qd, rest = y[:rigid_nq], y[rigid_nq:2 * rigid_nq], y[2 * rigid_nq:]
        parts = ([], [])
        for b, body in enumerate(self.scene.bodies):
            zeros = np.zeros(self.modes(body.name))
            parts[0].extend([q[7 * b:7 * b + 7], zeros])
            parts[1].extend([qd[7 * b:7 * b + 7], zeros])
        return np.concatenate(parts[0] + parts[1] + [rest])


def ideal_kind(c, bore_axis, journal_axis) -> str:
    """The ideal joint that closes a clearance joint: spherical for a ball; for a journal a
    revolute on the bore's axis, or, when the journal's axis is tilted against the bore's at
    the start (a misaligned joint, global axes given), a spherical joint at the bore's
    centre: the journal centred, its tilt left to the other joints (a revolute could not
    close)."""
    if c.type == "spherical" or abs(abs(bore_axis @ journal_axis) - 1) > PARALLEL:
        return "spherical"
    return "revolute"


def normals(u):
    """Two unit vectors f, g = u x f normal to the unit vector u (a right-handed triad)."""
    u = np.asarray(u, float)
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    f = np.cross(u, helper)
    f /= np.linalg.norm(f)
    return f, np.cross(u, f)


def primitive(kind, bi, bj, s_i=(0, 0, 0), s_j=(0, 0, 0), a_i=(0, 0, 0), b_j=(0, 0, 0),
              c_i=(0, 0, 0), speed=0.0, angle0=0.0, profile=None) -> list:
    """A primitive constraint's row (layout.PRIM_*; `profile`: a drive's profile columns)."""
    out = layout.row(layout.PRIMITIVE_COLUMNS, (profile or {}) | {layout.PRIM_KIND: kind, layout.PRIM_BODY_I: bi,
                                                layout.PRIM_BODY_J: bj, layout.PRIM_SPEED: speed,
                                                layout.PRIM_ANGLE0: angle0})
    for column, v in ((layout.PRIM_S_I, s_i), (layout.PRIM_S_J, s_j), (layout.PRIM_A_I, a_i),
                      (layout.PRIM_B_J, b_j), (layout.PRIM_C_I, c_i)):
        out[column:column + 3] = [float(c) for c in v]
    return out


def joint_primitives(kind, bi, bj, s_i, s_j, u_i, u_j, a_i, a_j, source) -> list:
    """The primitive constraints of an ideal joint (engine docstring); a_i, a_j the bodies'
    initial rotation matrices (u_i, u_j unit, in body frames)."""
    point = primitive(POINT, bi, bj, s_i, s_j)
    if kind == "spherical":
        return [point]
    if kind == "fixed":
        ex, ey, ez = np.eye(3)
        in_j = a_j.T @ a_i   # body i's axes in body j's frame
        return [point, primitive(DOT1, bi, bj, s_i, s_j, a_i=ey, b_j=in_j @ ex),
                primitive(DOT1, bi, bj, s_i, s_j, a_i=ez, b_j=in_j @ ex),
                primitive(DOT1, bi, bj, s_i, s_j, a_i=ez, b_j=in_j @ ey)]
    if kind == "universal":
        if abs((a_i @ u_i) @ (a_j @ u_j)) > 1e-9:
            raise InputError(f"{source}: joints.axis_j: the cross arms of a universal joint must "
                             "be normal to each other at the start")
        return [point, primitive(DOT1, bi, bj, s_i, s_j, a_i=u_i, b_j=u_j)]
    if abs(abs((a_i @ u_i) @ (a_j @ u_j)) - 1) > 1e-9:
        raise InputError(f"{source}: joints.axis_j: the axes of a {kind} joint must be parallel "
                         "at the start")
    f, g = normals(u_i)
    aligned = [primitive(DOT1, bi, bj, s_i, s_j, a_i=f, b_j=u_j),
               primitive(DOT1, bi, bj, s_i, s_j, a_i=g, b_j=u_j)]
    if kind == "revolute":
        return [point] + aligned
    line = [primitive(DOT2, bi, bj, s_i, s_j, a_i=f), primitive(DOT2, bi, bj, s_i, s_j, a_i=g)]
    if kind == "cylindrical":
        return aligned + line
    return aligned + line + [primitive(DOT1, bi, bj, s_i, s_j, a_i=g, b_j=a_j.T @ a_i @ f)]   # prismatic


# ---- a spatial run's outputs (reduced.mechanism.outputs asks these)
def motion_columns(model, q, qd, qdd, bodies) -> dict:
    """Each body's position, Euler parameters, velocity, global angular velocity (from the
    body states `bodies`, per step) and acceleration at the steps (columns by name), a
    flexible body's modal coordinates eta_j (m sqrt(kg)), and each output point's elastic
    displacement in its body's frame and its global position."""
    cols = {}
    geometry = model.geometry
    for b, name in enumerate(model.names):
        first = geometry.coordinate(b)
        for i, key in enumerate(("x_m", "y_m", "z_m", "e0_1", "e1_1", "e2_1", "e3_1")):
            cols[f"{name}_{key}"] = q[:, first + i]
        for i, key in enumerate(("vx_m_per_s", "vy_m_per_s", "vz_m_per_s")):
            cols[f"{name}_{key}"] = qd[:, first + i]
        for i, key in enumerate(("wx_rad_per_s", "wy_rad_per_s", "wz_rad_per_s")):
            cols[f"{name}_{key}"] = bodies[:, b, BODY_OMEGA + i]
        for i, key in enumerate(("ax_m_per_s2", "ay_m_per_s2", "az_m_per_s2")):
            cols[f"{name}_{key}"] = qdd[:, first + i]
        for j in range(geometry.modes(name)):
            cols[f"{name}_eta{j + 1}_m_sqrt_kg"] = q[:, first + COORDINATES + j]
    for point, b, shape in geometry.points:
        first = geometry.coordinate(b)
        p = q[:, first + 3:first + 7]
        p = p / np.linalg.norm(p, axis=1)[:, None]
        u = (np.zeros((q.shape[0], 3)) if shape is None
             else q[:, first + COORDINATES:first + COORDINATES + shape.shape[1]] @ shape.T)
        local = np.asarray(point.position + [0.0] * (3 - len(point.position)), float) + u
        x = np.einsum("kij,kj->ki", np.array([rotation_matrix(e) for e in p]).reshape(-1, 3, 3), local)
        for i, axis in enumerate("xyz"):
            cols[f"{point.body}_{point.name}_u{axis}_m"] = u[:, i]
            cols[f"{point.body}_{point.name}_{axis}_m"] = q[:, first + i] + x[:, i]
    return cols


def drive_angle(model, cols):
    """None: a spatial run's pictures are against time."""
    return None


def slider_acceleration(model, cols):
    """The acceleration (m/s^2) of the first prismatic joint's slider along the guide's axis
    at the start (exact for a guide on the ground), None without one."""
    guide = next((j for j in model.scene.joints if j.type == "prismatic"), None)
    if guide is None:
        return None
    body_i = {b.name: b for b in model.scene.bodies}.get(guide.body_i)
    axis = np.asarray(guide.axis_i, float) / np.linalg.norm(guide.axis_i)
    if body_i is not None:
        axis = rotation_matrix(body_i.parameters()) @ axis
    slider = guide.body_i if guide.body_j == GROUND else guide.body_j
    return sum(axis[k] * cols[f"{slider}_a{c}_m_per_s2"] for k, c in enumerate("xyz"))


# ---- a spatial mechanism seen once per drive period (reduced.dynamics.flow asks these)
WRAPPED_ANGLES = True   # the drive holds its relative angle modulo 2 pi: no shift a period


def flow_scale(model, length, omega) -> np.ndarray:
    """The scales of the coordinates, per body: its centre by the clearance c; its Euler
    parameters by c / (2 k), k its radius of gyration sqrt(trace J / 3m) (a small turn
    d theta changes p by d theta / 2 and moves a point at k by k d theta); their rates by
    c omega the same way; a flexible body's modal coordinates by c sqrt(m) (a mode moving the
    body by c: its modes are M-normalised)."""
    base = model.base
    gyration = np.sqrt(np.trace(base.inertia, axis1=1, axis2=2) / (3 * base.masses))
    per_body = np.concatenate([np.concatenate([np.ones(3), np.full(4, 0.5 / gyration[b]),
                                               np.full(model.geometry.modes(name), np.sqrt(base.masses[b]))])
                               for b, name in enumerate(model.names)])
    return length * np.concatenate([per_body, per_body * abs(omega)])


def flow_signs(model, y) -> np.ndarray:
    """+1, or -1 on the Euler parameters (and their rates) of a body whose largest parameter
    in magnitude is negative (p and -p are one orientation; a turn of 2 pi changes the
    sign)."""
    nq = model.nq
    signs = np.ones(2 * nq)
    for b in range(len(model.names)):
        i = model.geometry.coordinate(b) + 3
        p = y[i:i + 4]
        if p[np.argmax(np.abs(p))] < 0:
            signs[i:i + 4] = -1.0
            signs[nq + i:nq + i + 4] = -1.0
    return signs


def flow_coordinates(model, y, primitives) -> np.ndarray:
    """r, p and their rates, p of one sign (flow_signs)."""
    x = y[:2 * model.nq]
    return x * flow_signs(model, x)


def flow_consistent(model, y, args) -> np.ndarray:
    """y made consistent with the ideal joints and the drive (Euler parameters normalised;
    Gauss-Newton projection, engine.project_onto_constraints)."""
    from pinbore.reduced.mechanism import kernel as engine   # noqa: PLC0415 (the engine imports us)

    y = y.copy()
    work = engine.workspace(args)
    for _ in range(50):
        if not engine.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
            break
    return y


# numba's cache follows this file only: the compiled code here also calls into (or reads the
# constants of) these files, and is compiled afresh when they change (core.compiled)
follow_compiled_in(globals(), beside(__file__, "bodies", "layout", "vectors", "linalg", "planar"))
