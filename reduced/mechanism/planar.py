r"""Planar bodies: the body kind of a planar mechanism (scenes kind = "planar"); its
equations, which the compiled core computes (cpp/mechanism/planar.h), and what only Python
does of it: the scene's bodies and ideal joints as the model's arrays, the consistent initial
state, the outputs' columns and the flows' coordinates.

Coordinates q = (x, y, phi) of each body's centre of mass, velocities q' = (x', y', w), and
M = diag(m, m, J): the velocity columns of the constraint Jacobian are the coordinates' rates,
a body point s (body frame) is at P = r + A(phi) s with velocity r' + w k x A s and the
velocity part of its acceleration -w^2 A s. Angles are measured without bound (phi_j - phi_i),
so a drive or a spring needs no principal value.

A flexible body in Buckens' mean-axis frame (fem.modes.reduction: the deformation moves
neither its centre of mass nor its axes to first order), coordinates (x, y, phi, eta): its
kinetic energy [Shabana2005]

    T = m |r'|^2 / 2 + J(eta) phi'^2 / 2 + phi' g(eta) . eta' + |eta'|^2 / 2,
    J = I0 + 2 s1 . eta + eta^T Q eta,   g = S^T eta,

Q = S_xx + S_yy - K_G,zz: the deformed body's inertia less its foreshortening, the geometric
stiffening [WallrappSchwertassek1991] written as the loss of inertia it is, so that the
equations stay Lagrange's of one energy. Lagrange's equations, j1 = s1 + Q eta:

    m r'' = F,
    J phi'' + g . eta'' = N - 2 phi' j1 . eta',
    g phi'' + eta'' = Q_eta + phi'^2 j1 + 2 phi' S^ eta' - omega^2 eta - 2 zeta omega eta'

(S^ antisymmetric; gravity acts on the centre of mass alone: the mean axis). A point of the
body moves with the frame of its nearest interface (tied rigidly, fem.modes.reduction),
u = T_k eta + (R_k eta) k x (s - x_k); its mass block [[J, g^T], [g, I]] inverts in closed
form.
"""

import math

import numpy as np

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import layout
from pinbore.reduced.mechanism.kernel import constraint_values
from pinbore.reduced.mechanism.layout import ANGLE, DOT2, POINT
from pinbore.reduced.mechanism.flexible import FlexibleGeometry
from pinbore.reduced.mechanism.scene import GROUND, clearance_points

RIGID_COLUMNS = 8     # what a run's record keeps of a body's row: x, y, phi, cos, sin, x', y', w
MODES = 24            # at most, a flexible body (scene.FLEXIBLE_MODES)
INTERFACES = 4        # at most, a flexible body's interfaces tied to joints
COLUMNS = 3           # velocity columns of a rigid body: x', y', w (a flexible body's modes follow)


# ---- a planar scene as the model's arrays (reduced.mechanism.model.build asks these)
PROJECT_FIRST = False   # an accepted step's events are read before its projection (layout.Args)


class Geometry(FlexibleGeometry):
    """A planar scene's bodies and ideal joints as the model's arrays: the coordinates (a
    flexible body's modal coordinates after its x, y, phi), the mass, the primitive
    constraints, torsion elements, and the consistent initial state (a clearance joint's
    closing and contacts are its type's, reduced.mechanism.joints)."""

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
            if j.guides_a_slider:
                found.append((j.body, j.point, "joints.point"))
            else:
                found += [(j.body_i, j.point_i, "joints.point_i"), (j.body_j, j.point_j, "joints.point_j")]
        found += clearance_points(scene)
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
                for j in scene.joints if not j.guides_a_slider]
        rows += [r for closure in closures for r in closure]
        for j in scene.joints:
            if j.guides_a_slider:
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
    """A flexible body's row of Args.flex: modes n, interfaces, I0, then omega^2, the modal
    damping 2 zeta omega, s1 = s_xx + s_yy (n each), Q = S_xx + S_yy - K_G (n x n), S^ =
    S_xy - S_yx (n x n), and per interface x_k (2), T_k (x: n, y: n), R_k (n): the order of
    the core's Planar::flex_column."""
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
    slider = next((j for j in model.scene.joints if j.guides_a_slider), None)
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

