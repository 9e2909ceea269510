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

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import bodies, layout
from pinbore.reduced.mechanism.layout import ANGLE, DOT2, POINT
from pinbore.reduced.mechanism.scene import GROUND
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


# planar bodies implement reduced.mechanism.bodies for their marker and 2-vectors
bodies.implement_kind(globals(), {"kind": planar, "vector": _plane, "angular": _scalar})


# ---- a planar scene as the model's arrays (reduced.mechanism.model.build asks these)
MARKER = layout.PLANAR
PROJECT_FIRST = False   # an accepted step's events are read before its projection (layout.Args)


class Geometry:
    """A planar scene's bodies and ideal joints as the model's arrays: the coordinates, the
    mass, the primitive constraints, a revolute clearance joint's contact, torsion elements,
    and the consistent initial state."""

    def __init__(self, scene, index, source):
        self.scene, self.index, self.source = scene, index, source
        self.nq = COLUMNS * len(scene.bodies)

    def mass(self):
        """(masses, 1/m, 1/m, 1/J per velocity column, inertia: J in [0, 0] of a 3 x 3 per body)."""
        bodies = self.scene.bodies
        minv = np.array([[1 / b.mass, 1 / b.mass, 1 / b.inertia] for b in bodies]).ravel()
        inertia = np.zeros((len(bodies), 3, 3))
        inertia[:, 0, 0] = [b.inertia for b in bodies]
        return np.array([b.mass for b in bodies], float), minv, inertia

    def offsets(self) -> np.ndarray:
        return COLUMNS * np.arange(len(self.scene.bodies) + 1)

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
                rows.append(primitive(ANGLE, -1, b, angle0=math.radians(scene.bodies[b].angle_deg)))
        if scene.drive is None:
            return rows, None
        rows.append(primitive(ANGLE, -1, index[scene.drive.body], speed=scene.drive.speed,
                              angle0=math.radians(scene.drive.angle0_deg),
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
                layout.TORSION_C_I: [0.0, 1.0]}

    def inverse_inertia(self, b, t) -> float:
        return 1 / self.scene.bodies[b].inertia

    def place(self, model, closings) -> np.ndarray:
        """Positions satisfying the ideal joints (an ideal twin's closures among them) with the
        clearance joints that start "ideal" or "free" closed (least change from the scene's guesses), and the scene's velocities
        projected onto Phi_q q' = -Phi_t (least change in kinetic-energy norm) of the ideal
        joints and those that start "ideal" ("placed" joints keep their positions)."""
        scene = self.scene
        q = np.array([[*b.position, math.radians(b.angle_deg)] for b in scene.bodies]).ravel()
        qd = np.array([[*b.velocity, b.omega] for b in scene.bodies]).ravel()
        minv = model.base.minv
        closed = self.primitives(model.closures + [rows for rows, start in closings
                                                   if start in ("ideal", "free")])[0]
        q, _, gap = project(model, q, qd, closed, minv)
        if gap >= 1e-14:
            raise InputError("joints: the bodies cannot be placed so that every joint closes "
                             f"(largest gap {gap:.3g} m)")
        closed = self.primitives(model.closures + [rows for rows, start in closings if start == "ideal"])[0]
        _, qd, _ = project(model, q, qd, closed, minv)
        return np.concatenate([q, qd, np.zeros(layout.ENERGY_STATES), np.zeros(model.friction_states)])


def primitive(kind, bi, bj, s_i=(0.0, 0.0), s_j=(0.0, 0.0), a_i=(0.0, 0.0), b_j=(0.0, 0.0),
              c_i=(0.0, 0.0), speed=0.0, angle0=0.0, profile=None) -> list:
    """A primitive constraint's row (layout.PRIM_*) of planar vectors (`profile`: a drive's
    profile columns)."""
    return layout.row(layout.PRIMITIVE_COLUMNS, (profile or {}) | {
        layout.PRIM_KIND: kind, layout.PRIM_BODY_I: bi, layout.PRIM_BODY_J: bj,
        layout.PRIM_SPEED: speed, layout.PRIM_ANGLE0: angle0, layout.PRIM_S_I: list(s_i),
        layout.PRIM_S_J: list(s_j), layout.PRIM_A_I: list(a_i), layout.PRIM_B_J: list(b_j),
        layout.PRIM_C_I: list(c_i)})


def project(model, q, qd, primitives, minv, t=0.0):
    """The nearest consistent state: positions moved least onto Phi(q, t) = 0 (Gauss-Newton),
    velocities projected onto Phi_q q' = -Phi_t with least change in kinetic-energy norm.
    Returns (q, q', largest remaining position gap)."""
    from pinbore.reduced.mechanism.engine import constraint_values   # noqa: PLC0415 (compiled)

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
        q -= jac.T @ np.linalg.lstsq(jac @ jac.T, phi, rcond=None)[0]
    y[:nq] = q
    jac, _, phi_t = constraint_values(t, y, args)
    if jac.shape[0]:
        scaled = jac * minv
        qd -= scaled.T @ np.linalg.lstsq(scaled @ jac.T, jac @ qd + phi_t, rcond=None)[0]
    return q, qd, gap


# ---- a planar run's outputs (reduced.mechanism.outputs asks these)
def motion_columns(names, q, qd, qdd, bodies) -> dict:
    """Each body's coordinates, rates and accelerations at the steps (columns by name)."""
    cols = {}
    keys = ((q, (("x", "m"), ("y", "m"), ("angle", "rad"))),
            (qd, (("vx", "m_per_s"), ("vy", "m_per_s"), ("omega", "rad_per_s"))),
            (qdd, (("ax", "m_per_s2"), ("ay", "m_per_s2"), ("alpha", "rad_per_s2"))))
    for b, name in enumerate(names):
        for values, what in keys:
            for i, (key, unit) in enumerate(what):
                cols[f"{name}_{key}_{unit}"] = values[:, COLUMNS * b + i]
    return cols


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
    row = primitives[model.drive_row]
    b = int(row[layout.PRIM_BODY_J])
    if b >= 0:
        x[COLUMNS * b + 2] -= row[layout.PRIM_ANGLE0]
    return x


def flow_consistent(model, y, args) -> np.ndarray:
    """y with q moved least onto the constraints of args.primitives, then q' projected
    (`project`)."""
    nq = model.nq
    y = y.copy()
    y[:nq], y[nq:2 * nq], _ = project(model, y[:nq], y[nq:2 * nq], args.primitives, model.base.minv)
    return y
