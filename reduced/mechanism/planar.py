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

from pinbore.reduced.mechanism import bodies, layout
from pinbore.reduced.mechanism.linalg import schur_within_envelope
from pinbore.reduced.mechanism.vectors import _plane, _scalar

# a body's row in Work.bodies
X, Y, PHI, COS, SIN, VX, VY, W = range(8)
BODY_COLUMNS = 8
COLUMNS = 3   # velocity columns a body: x', y', w


def planar(kind) -> bool:
    return getattr(kind, "instance_class", None) is layout.PlanarKind


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
    a = arm(states, b, s)
    w = states[b, W]
    w2 = w * w
    return ((states[b, X] + a[0], states[b, Y] + a[1]),
            (states[b, VX] - w * a[1], states[b, VY] + w * a[0]), (-(a[0] * w2), -(a[1] * w2)), a)


@numba.njit(cache=True, _nrt=False)
def vector_state(states, b, v):
    if b < 0:
        return v, (0.0, 0.0), (0.0, 0.0)
    a = arm(states, b, v)
    w = states[b, W]
    w2 = w * w
    return a, (-w * a[1], w * a[0]), (-(a[0] * w2), -(a[1] * w2))


@numba.njit(cache=True, _nrt=False)
def material_velocity(states, b, x):
    if b < 0:
        return (0.0, 0.0)
    w = states[b, W]
    return states[b, VX] - w * (x[1] - states[b, Y]), states[b, VY] + w * (x[0] - states[b, X])


@numba.njit(cache=True, _nrt=False)
def put(jac, row, b, linear, angular, sign, offsets):
    if b < 0:
        return
    c = offsets[b]
    jac[row, c] += sign * linear[0]
    jac[row, c + 1] += sign * linear[1]
    jac[row, c + 2] += sign * angular


@numba.njit(cache=True, _nrt=False)
def push(force, states, b, f, x, offsets):
    if b < 0:
        return
    c = offsets[b]
    force[c] += f[0]
    force[c + 1] += f[1]
    force[c + 2] += (x[0] - states[b, X]) * f[1] - (x[1] - states[b, Y]) * f[0]


@numba.njit(cache=True, _nrt=False)
def push_torque(force, b, torque, offsets):
    if b >= 0:
        force[offsets[b] + 2] += torque


@numba.njit(cache=True, _nrt=False)
def centripetal_term(states, b, arm_, a):
    """a . (-w^2 A s), written (a . A s) w^2 with its sign (0 for the ground)."""
    if b < 0:
        return 0.0
    w = states[b, W]
    return -((a[0] * arm_[0] + a[1] * arm_[1]) * (w * w))


@numba.njit(cache=True, _nrt=False)
def relative_rotation(states, bi, bj, a_i, b_j, c_i, offset, drift):
    phi_i = phi_j = w_i = w_j = 0.0   # the ground's
    if bi >= 0:
        phi_i, w_i = states[bi, PHI], states[bi, W]
    if bj >= 0:
        phi_j, w_j = states[bj, PHI], states[bj, W]
    return ((phi_j - phi_i) - offset) - drift, -1.0, w_j - w_i, 0.0


@numba.njit(cache=True, _nrt=False)
def body_columns(like):
    return BODY_COLUMNS


@numba.njit(cache=True, _nrt=False)
def centripetal_gap(states, a, bi, arm_i, c_i, bj, arm_j, c_j):
    return centripetal_term(states, bj, arm_j, a) - centripetal_term(states, bi, arm_i, a)


@numba.njit(cache=True, _nrt=False)
def rotation_axis(states, bi, a_i, c_i):
    return 1.0


@numba.njit(cache=True, _nrt=False)
def row_rate(rate, jac, i, b, states, velocities, offsets, like):
    for c in range(offsets[b], offsets[b + 1]):
        rate += jac[i, c] * velocities[c]
    return rate


# ---- the whole body (the signatures of reduced.mechanism.bodies: the unused arrays are
# other kinds')
@numba.njit(cache=True, _nrt=False)
def body_states(kind, y, nq, inertia_inv, states, velocities):
    for b in range(nq // COLUMNS):
        phi = y[COLUMNS * b + 2]
        states[b, X], states[b, Y], states[b, PHI] = y[COLUMNS * b], y[COLUMNS * b + 1], phi
        states[b, COS], states[b, SIN] = math.cos(phi), math.sin(phi)
        states[b, VX], states[b, VY] = y[nq + COLUMNS * b], y[nq + COLUMNS * b + 1]
        states[b, W] = y[nq + COLUMNS * b + 2]
    for j in range(nq):
        velocities[j] = y[nq + j]


@numba.njit(cache=True, _nrt=False)
def body_forces(kind, masses, minv, inertia, gravity, states, force):
    """Gravity, m g, on each body (its mass is 1 / minv)."""
    for b in range(minv.size // COLUMNS):
        force[COLUMNS * b] = gravity[0] / minv[COLUMNS * b]
        force[COLUMNS * b + 1] = gravity[1] / minv[COLUMNS * b + 1]
        force[COLUMNS * b + 2] = 0.0


@numba.njit(cache=True, _nrt=False)
def fill_schur(kind, masses, minv, offsets, states, jac, mjac, schur, row_bodies, first, m):
    for i in range(m):
        for side in range(2):
            b = row_bodies[i, side]
            if b >= 0:
                for c in range(offsets[b], offsets[b + 1]):
                    mjac[i, c] = jac[i, c] * minv[c]
    schur_within_envelope(jac, mjac, schur, row_bodies, first, offsets, m, True)


@numba.njit(cache=True, _nrt=False)
def state_rates(kind, y, dy, nq, masses, minv, baumgarte, states, force):
    for j in range(nq):
        dy[j] = y[nq + j]
        dy[nq + j] = minv[j] * force[j]


@numba.njit(cache=True, _nrt=False)
def mass_weighted_step(y, start, jac, minv, x, m, nq, scale):
    """y[start:start + nq] -= scale M^-1 Phi_q^T x: the least change (in the mass metric) along
    the rows."""
    for c in range(nq):
        v = 0.0
        for i in range(m):
            v += jac[i, c] * x[i]
        y[start + c] -= scale * minv[c] * v


@numba.njit(cache=True, _nrt=False)
def position_step(kind, y, nq, minv, jac, mjac, x, states, m):
    mass_weighted_step(y, 0, jac, minv, x, m, nq, 1.0)


@numba.njit(cache=True, _nrt=False)
def velocity_step(kind, y, nq, minv, jac, mjac, x, states, m, scale):
    mass_weighted_step(y, nq, jac, minv, x, m, nq, scale)


@numba.njit(cache=True, _nrt=False)
def normalise(kind, y, nq, nb):
    pass


@numba.njit(cache=True, _nrt=False)
def kinetic_energy(kind, y, nq, masses, minv, inertia):
    energy = 0.0
    for i in range(nq):
        energy += 0.5 * y[nq + i] ** 2 / minv[i]
    return energy


# what planar bodies implement of reduced.mechanism.bodies, and the argument it is chosen by
for _name, _on in (("body_columns", "like"), ("point_state", "s"), ("vector_state", "v"),
                   ("material_velocity", "x"), ("put", "linear"), ("push", "f"),
                   ("push_torque", "torque"), ("centripetal_gap", "a"),
                   ("relative_rotation", "a_i"), ("rotation_axis", "a_i"), ("row_rate", "like"),
                   ("body_states", "kind"), ("body_forces", "kind"), ("fill_schur", "kind"),
                   ("state_rates", "kind"), ("position_step", "kind"), ("velocity_step", "kind"),
                   ("normalise", "kind"), ("kinetic_energy", "kind")):
    bodies.implement(getattr(bodies, _name), globals()[_name],
                     _scalar if _on == "torque" else planar if _on == "kind" else _plane, _on)
