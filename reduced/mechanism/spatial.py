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

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import bodies, layout
from pinbore.reduced.mechanism.bodies import dot1
from pinbore.reduced.mechanism.layout import ANGLE, DOT1, DOT2, POINT
from pinbore.reduced.mechanism.scene import GROUND, rotation_matrix, unit_axis
from pinbore.reduced.mechanism.linalg import schur_within_envelope
from pinbore.reduced.mechanism.vectors import _space, add, cross, dot, scaled, sub

# a body's row in Work.bodies: position, rotation matrix (row-major), velocity, angular
# velocity (global), global inverse inertia A J'^-1 A^T (row-major)
BODY_POS, BODY_ROT, BODY_VEL, BODY_OMEGA, BODY_JINV = 0, 3, 12, 15, 18
BODY_COLUMNS = 27
COORDINATES = 7   # r, p
COLUMNS = 6       # velocity columns a body: v, w


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
def unit_parameters(q, b):
    """The Euler parameters of body b, normalised (4-tuple)."""
    i = COORDINATES * b + 3
    n = math.sqrt(q[i] ** 2 + q[i + 1] ** 2 + q[i + 2] ** 2 + q[i + 3] ** 2)
    return (q[i] / n, q[i + 1] / n, q[i + 2] / n, q[i + 3] / n)


@numba.njit(cache=True, _nrt=False)
def body_states(kind, y, nq, inertia_inv, flex, offsets, states, velocities):
    """Position, rotation matrix, velocity, global angular velocity w = A 2 G p' and global
    inverse inertia A J'^-1 A^T of every body into its row (BODY_*)."""
    for b in range(states.shape[0]):
        p = unit_parameters(y, b)
        e0, e1, e2, e3 = p
        a = ((e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2),
             (e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1),
             (e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5))
        for r in range(3):
            for c in range(3):
                states[b, BODY_ROT + 3 * r + c] = 2.0 * a[r][c]
        w_body = scaled(g_times(p, vec3(y, nq + COORDINATES * b + 3) + (y[nq + COORDINATES * b + 6],)), 2.0)
        w = turned(states, b, w_body)
        for k in range(3):
            states[b, BODY_POS + k] = y[COORDINATES * b + k]
            states[b, BODY_VEL + k] = y[nq + COORDINATES * b + k]
            states[b, BODY_OMEGA + k] = w[k]
        for r in range(3):       # A J'^-1 A^T written out: a 3 x 3 matmul allocates
            ar = row3(states, b, BODY_ROT + 3 * r)
            t0 = ar[0] * inertia_inv[b, 0, 0] + ar[1] * inertia_inv[b, 1, 0] + ar[2] * inertia_inv[b, 2, 0]
            t1 = ar[0] * inertia_inv[b, 0, 1] + ar[1] * inertia_inv[b, 1, 1] + ar[2] * inertia_inv[b, 2, 1]
            t2 = ar[0] * inertia_inv[b, 0, 2] + ar[1] * inertia_inv[b, 1, 2] + ar[2] * inertia_inv[b, 2, 2]
            for c in range(r + 1):
                ac = row3(states, b, BODY_ROT + 3 * c)
                v = t0 * ac[0] + t1 * ac[1] + t2 * ac[2]
                states[b, BODY_JINV + 3 * r + c] = states[b, BODY_JINV + 3 * c + r] = v


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
    """A J'^-1 A^T a (global)."""
    return block_times(states, b, BODY_JINV, a)


# ---- points and vectors
@numba.njit(cache=True, _nrt=False)
def point_state(states, b, s_body):
    if b < 0:
        return s_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    s = turned(states, b, s_body)
    w = row3(states, b, BODY_OMEGA)
    ws = cross(w, s)
    return (add(row3(states, b, BODY_POS), s), add(row3(states, b, BODY_VEL), ws), cross(w, ws), s)


@numba.njit(cache=True, _nrt=False)
def vector_state(states, b, s, a_body):
    if b < 0:
        return a_body, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    a = turned(states, b, a_body)
    w = row3(states, b, BODY_OMEGA)
    wa = cross(w, a)
    return a, wa, cross(w, wa)


@numba.njit(cache=True, _nrt=False)
def material_velocity(states, b, x):
    if b < 0:
        return (0.0, 0.0, 0.0)
    return add(row3(states, b, BODY_VEL), cross(row3(states, b, BODY_OMEGA), sub(x, row3(states, b, BODY_POS))))


@numba.njit(cache=True, _nrt=False)
def put(jac, row, states, b, s, linear, angular, sign, offsets):
    if b < 0:
        return
    col = offsets[b]
    for k in range(3):
        jac[row, col + k] += sign * linear[k]
        jac[row, col + 3 + k] += sign * angular[k]


@numba.njit(cache=True, _nrt=False)
def push(force, states, b, f, x, offsets):
    if b < 0:
        return
    torque = cross(sub(x, row3(states, b, BODY_POS)), f)
    col = offsets[b]
    for c in range(3):
        force[col + c] += f[c]
        force[col + 3 + c] += torque[c]


@numba.njit(cache=True, _nrt=False)
def push_torque(force, states, b, s, torque, offsets):
    if b < 0:
        return
    col = offsets[b]
    for c in range(3):
        force[col + 3 + c] += torque[c]


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
    """Gravity and the gyroscopic torque -w x (J w) of each body."""
    for b in range(masses.size):
        w = row3(states, b, BODY_OMEGA)
        jw = turned(states, b, matvec(inertia, b, unturned(states, b, w)))
        gyro = cross(w, jw)
        for c in range(3):
            force[COLUMNS * b + c] = masses[b] * gravity[c]
            force[COLUMNS * b + 3 + c] = -gyro[c]
    return 0.0


@numba.njit(cache=True, _nrt=False)
def fill_schur(kind, masses, minv, offsets, states, jac, mjac, schur, row_bodies, first, m):
    """M^-1 D^T (rows of mjac): a row has nonzero columns for its two bodies only, and M^-1
    (block-diagonal: m I and the global inverse inertia) acts on those."""
    for i in range(m):
        for side in range(2):
            b = row_bodies[i, side]
            if b < 0:
                continue
            col = offsets[b]
            angular = inverse_inertia_times(states, b, (jac[i, col + 3], jac[i, col + 4], jac[i, col + 5]))
            for c in range(3):
                mjac[i, col + c] = jac[i, col + c] / masses[b]
                mjac[i, col + 3 + c] = angular[c]
    schur_within_envelope(jac, mjac, schur, row_bodies, first, offsets, m, False)


@numba.njit(cache=True, _nrt=False)
def state_rates(kind, y, dy, nq, masses, minv, baumgarte, states, force):
    """Velocities, accelerations r'' = F / m and the Euler parameters' second derivatives
    p'' = G^T (A^T w')/2 + k p with their normalisation and its Baumgarte terms."""
    alpha = baumgarte
    for b in range(masses.size):
        i = COORDINATES * b
        for c in range(3):
            dy[i + c] = y[nq + i + c]
            dy[nq + i + c] = force[COLUMNS * b + c] / masses[b]
        for c in range(4):
            dy[i + 3 + c] = y[nq + i + 3 + c]
        wd = inverse_inertia_times(states, b, vec3(force, COLUMNS * b + 3))   # w' (global)
        p = unit_parameters(y, b)
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
def normalise(kind, y, nq, nb):
    """Euler parameters to unit length, their rates normal to them."""
    for b in range(nb):
        i = COORDINATES * b + 3
        n = math.sqrt(y[i] ** 2 + y[i + 1] ** 2 + y[i + 2] ** 2 + y[i + 3] ** 2)
        along = 0.0
        for c in range(4):
            y[i + c] /= n
            along += y[i + c] * y[nq + i + c]
        for c in range(4):
            y[nq + i + c] -= along * y[i + c]


@numba.njit(cache=True, _nrt=False)
def turn(y, b, rotation_vector):
    """Turn body b by a small global rotation vector: p <- (cos(|r|/2), sin(|r|/2) r/|r|) p."""
    angle = math.sqrt(dot(rotation_vector, rotation_vector))
    if angle == 0.0:
        return
    k = math.sin(0.5 * angle) / angle
    a0, a = math.cos(0.5 * angle), scaled(rotation_vector, k)
    i = COORDINATES * b + 3
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
    rotation part; level 1 changes the velocities and the parameters' rates."""
    nb = states.shape[0]
    for b in range(nb):
        step = (column_step(mjac, x, m, COLUMNS * b, scale), column_step(mjac, x, m, COLUMNS * b + 1, scale),
                column_step(mjac, x, m, COLUMNS * b + 2, scale), column_step(mjac, x, m, COLUMNS * b + 3, scale),
                column_step(mjac, x, m, COLUMNS * b + 4, scale), column_step(mjac, x, m, COLUMNS * b + 5, scale))
        if level == 0:
            for c in range(3):
                y[COORDINATES * b + c] += step[c]
            turn(y, b, (step[3], step[4], step[5]))
        else:
            for c in range(3):
                y[nq + COORDINATES * b + c] += step[c]
            w = add(row3(states, b, BODY_OMEGA), (step[3], step[4], step[5]))
            pd = gt_times(unit_parameters(y, b), scaled(unturned(states, b, w), 0.5))
            for c in range(4):
                y[nq + COORDINATES * b + 3 + c] = pd[c]
    normalise(None, y, nq, nb)


@numba.njit(cache=True, _nrt=False)
def position_step(kind, y, nq, minv, jac, mjac, x, states, m):
    mass_weighted_step(y, nq, mjac, x, states, m, 0, 1.0)


@numba.njit(cache=True, _nrt=False)
def velocity_step(kind, y, nq, minv, jac, mjac, x, states, m, scale):
    mass_weighted_step(y, nq, mjac, x, states, m, 1, scale)


@numba.njit(cache=True, _nrt=False)
def kinetic_energy(kind, y, nq, masses, minv, inertia, flex, offsets):
    """1/2 m v.v + 1/2 w'.J' w' of every body (w' = 2 G p' in the body frame)."""
    energy = 0.0
    for b in range(masses.size):
        i = COORDINATES * b
        v = vec3(y, nq + i)
        p = unit_parameters(y, b)
        w = scaled(g_times(p, vec3(y, nq + i + 3) + (y[nq + i + 6],)), 2.0)
        energy += 0.5 * masses[b] * dot(v, v) + 0.5 * dot(w, matvec(inertia, b, w))
    return energy


# spatial bodies implement reduced.mechanism.bodies for their marker and 3-vectors (the
# ground's vectors global when turned)
bodies.implement_kind(globals() | {"turned": turned_any, "unturned": unturned_any},
                      {"kind": spatial, "vector": _space})


def strain_energy(model, q) -> np.ndarray:
    """The bodies' strain energy at the steps (J): rigid bodies, none."""
    return np.zeros(q.shape[0])


# ---- a spatial scene as the model's arrays (reduced.mechanism.model.build asks these)
MARKER = layout.SPATIAL
RIGID_COLUMNS = BODY_OMEGA + 3   # what a run's record keeps of a body's row (its angular velocity)
PROJECT_FIRST = True    # an accepted step is projected before its events are read (layout.Args)
PARALLEL = 1e-9   # |1 - |u_b . u_j|| below which a journal's axis is aligned with its bore's


class Geometry:
    """A spatial scene's bodies and ideal joints as the model's arrays: the coordinates, the
    mass, the primitive constraints ([Nikravesh1988] ch. 7), the contacts of a cylindrical or
    spherical clearance joint, torsion elements, and the consistent initial state."""

    def __init__(self, scene, index, source, base=None):
        self.scene, self.index, self.source = scene, index, source
        self.nq = COORDINATES * len(scene.bodies)
        self.rot = {GROUND: np.eye(3)} | {b.name: rotation_matrix(b.parameters()) for b in scene.bodies}

    def mass(self):
        """(masses, no per-column inverse masses, inertia tensors in the body frames)."""
        bodies = self.scene.bodies
        return (np.array([b.mass for b in bodies], float), np.zeros(COLUMNS * len(bodies)),
                np.array([b.inertia for b in bodies], float))

    def offsets(self) -> np.ndarray:
        return COLUMNS * np.arange(len(self.scene.bodies) + 1)

    def coordinate(self, b: int) -> int:
        """Body b's first coordinate in q."""
        return COORDINATES * b

    def flex(self) -> np.ndarray:
        """Args.flex: no flexible bodies in space (yet): an empty row per body."""
        return np.zeros((len(self.scene.bodies), 0))

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
        rows.append(primitive(ANGLE, index[j.body_i], index[j.body_j], a_i=f,
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
                layout.TORSION_B_J: list(self.rot[t.body_j].T @ self.rot[t.body_i] @ f)}

    def inverse_inertia(self, b, t) -> float:
        """u . J^-1 u of body b about a torsion element's axis u (body i's axis, in b's frame)."""
        body = self.scene.bodies[b]
        u = self.rot[body.name].T @ self.rot[t.body_i] @ np.array(unit_axis(t.axis_i, "axis_i"))
        return float(u @ np.linalg.solve(np.array(body.inertia), u))

    def place(self, model, closings) -> np.ndarray:
        """Positions on the ideal joints with the clearance joints that start "ideal" or
        "free" closed (mass-weighted least change from the scene's guesses); then the
        velocities as given (each body's r' and global w, on the positions found), projected
        onto the ideal joints and the clearance joints that start "ideal" (those that start
        "free" keep their relative velocity; "placed" ones keep their positions too)."""
        from pinbore.reduced.mechanism import engine   # noqa: PLC0415 (compiled)

        s = self.scene
        nq = self.nq
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
            args = model.args(primitives=primitives)
            work = engine.workspace(args)
            for _ in range(50):
                if not engine.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
                    break
            _, phi, _ = engine.constraint_values(0.0, y, args)
            gap = np.max(np.abs(phi), initial=0.0)
            if gap >= 1e-12:
                raise InputError(f"{self.source}: joints: the bodies cannot be placed so that "
                                 f"every joint closes (largest gap {gap:.3g})")
        return y


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
        return [point, primitive(DOT1, bi, bj, a_i=ey, b_j=in_j @ ex),
                primitive(DOT1, bi, bj, a_i=ez, b_j=in_j @ ex),
                primitive(DOT1, bi, bj, a_i=ez, b_j=in_j @ ey)]
    if kind == "universal":
        if abs((a_i @ u_i) @ (a_j @ u_j)) > 1e-9:
            raise InputError(f"{source}: joints.axis_j: the cross arms of a universal joint must "
                             "be normal to each other at the start")
        return [point, primitive(DOT1, bi, bj, a_i=u_i, b_j=u_j)]
    if abs(abs((a_i @ u_i) @ (a_j @ u_j)) - 1) > 1e-9:
        raise InputError(f"{source}: joints.axis_j: the axes of a {kind} joint must be parallel "
                         "at the start")
    f, g = normals(u_i)
    aligned = [primitive(DOT1, bi, bj, a_i=f, b_j=u_j), primitive(DOT1, bi, bj, a_i=g, b_j=u_j)]
    if kind == "revolute":
        return [point] + aligned
    line = [primitive(DOT2, bi, bj, s_i, s_j, a_i=f), primitive(DOT2, bi, bj, s_i, s_j, a_i=g)]
    if kind == "cylindrical":
        return aligned + line
    return aligned + line + [primitive(DOT1, bi, bj, a_i=g, b_j=a_j.T @ a_i @ f)]   # prismatic


# ---- a spatial run's outputs (reduced.mechanism.outputs asks these)
def motion_columns(model, q, qd, qdd, bodies) -> dict:
    """Each body's position, Euler parameters, velocity, global angular velocity (from the
    body states `bodies`, per step) and acceleration at the steps (columns by name), and the
    output points' positions (their elastic displacement: zero, the bodies are rigid)."""
    cols = {}
    for point in model.scene.output.points:
        b = model.names.index(point.body)
        p = q[:, COORDINATES * b + 3:COORDINATES * b + 7]
        p = p / np.linalg.norm(p, axis=1)[:, None]
        x = np.einsum("kij,j->ki", np.array([rotation_matrix(e) for e in p]).reshape(-1, 3, 3),
                      np.asarray(point.position + [0.0] * (3 - len(point.position)), float))
        for i, axis in enumerate("xyz"):
            cols[f"{point.body}_{point.name}_u{axis}_m"] = np.zeros(q.shape[0])
            cols[f"{point.body}_{point.name}_{axis}_m"] = q[:, COORDINATES * b + i] + x[:, i]
    for b, name in enumerate(model.names):
        first = COORDINATES * b
        for i, key in enumerate(("x_m", "y_m", "z_m", "e0_1", "e1_1", "e2_1", "e3_1")):
            cols[f"{name}_{key}"] = q[:, first + i]
        for i, key in enumerate(("vx_m_per_s", "vy_m_per_s", "vz_m_per_s")):
            cols[f"{name}_{key}"] = qd[:, first + i]
        for i, key in enumerate(("wx_rad_per_s", "wy_rad_per_s", "wz_rad_per_s")):
            cols[f"{name}_{key}"] = bodies[:, b, BODY_OMEGA + i]
        for i, key in enumerate(("ax_m_per_s2", "ay_m_per_s2", "az_m_per_s2")):
            cols[f"{name}_{key}"] = qdd[:, first + i]
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
    c omega the same way."""
    base = model.base
    gyration = np.sqrt(np.trace(base.inertia, axis1=1, axis2=2) / (3 * base.masses))
    per_body = np.concatenate([np.full((base.masses.size, 3), 1.0),
                               np.repeat(0.5 / gyration[:, None], 4, axis=1)], axis=1).ravel()
    return length * np.concatenate([per_body, per_body * abs(omega)])


def flow_signs(model, y) -> np.ndarray:
    """+1, or -1 on the Euler parameters (and their rates) of a body whose largest parameter
    in magnitude is negative (p and -p are one orientation; a turn of 2 pi changes the
    sign)."""
    nq = model.nq
    signs = np.ones(2 * nq)
    for b in range(len(model.names)):
        p = y[COORDINATES * b + 3:COORDINATES * b + 7]
        if p[np.argmax(np.abs(p))] < 0:
            signs[COORDINATES * b + 3:COORDINATES * b + 7] = -1.0
            signs[nq + COORDINATES * b + 3:nq + COORDINATES * b + 7] = -1.0
    return signs


def flow_coordinates(model, y, primitives) -> np.ndarray:
    """r, p and their rates, p of one sign (flow_signs)."""
    x = y[:2 * model.nq]
    return x * flow_signs(model, x)


def flow_consistent(model, y, args) -> np.ndarray:
    """y made consistent with the ideal joints and the drive (Euler parameters normalised;
    Gauss-Newton projection, engine.project_onto_constraints)."""
    from pinbore.reduced.mechanism import engine   # noqa: PLC0415 (the engine imports us)

    y = y.copy()
    work = engine.workspace(args)
    for _ in range(50):
        if not engine.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
            break
    return y
