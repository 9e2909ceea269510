r"""Spatial bodies: the body kind of a spatial mechanism (scenes kind = "spatial"); its
equations, which the compiled core computes (cpp/mechanism/spatial.h), and what only Python
does of it: the scene's bodies and ideal joints as the model's arrays, the consistent initial
state, the outputs' columns and the flows' coordinates.

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
its acceleration w x (w x s).

A flexible body (its modal coordinates eta in Buckens' mean-axis frame, fem.modes.reduction),
its kinetic energy [Shabana2005], w' the angular velocity in the body frame:

    T = m |r'|^2 / 2 + w'^T J(eta) w' / 2 + w'^T G(eta) eta' + |eta'|^2 / 2,
    I_ab(eta) = I_ab + (s_ab + s_ba) . eta + eta^T S_ab eta,
    J = tr(I) 1 - I - [eta^T K_G,ab eta],   G[a, :] = eta^T S^_a,  S^_a = e_abc S_bc,

the geometric stiffening [WallrappSchwertassek1991] as the loss of inertia of the
foreshortening (one Lagrangian: energy and momenta kept). Euler's and Lagrange's equations
(h = J w' + G eta', the angular momentum about the centre of mass):

    J w'' + G eta'' = N' - w' x h - J' w',
    G^T w'' + eta'' = Q + dT/deta (w' terms) + 2 sum_a w'_a S^_a eta' - omega^2 eta - 2 zeta omega eta',

with w'' = A^T (dw/dt) (w = A w'); gravity acts on the centre of mass alone. A point of the
body moves with the frame of its nearest interface, u = T_k eta + (R_k eta) x (s - x_k).
"""

import math

import numpy as np

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import kernel, layout
from pinbore.reduced.mechanism.layout import ANGLE, DOT1, DOT2, POINT
from pinbore.reduced.mechanism.flexible import FlexibleGeometry
from pinbore.reduced.mechanism.scene import GROUND, clearance_points, rotation_matrix
from pinbore.reduced.mechanism.vectors import unit_axis

# a body's row in the core's Work.bodies (cpp/mechanism/spatial.h): position, rotation matrix
# (row-major), velocity, angular velocity (global), global inverse inertia, then the core's own
BODY_POS, BODY_ROT, BODY_VEL, BODY_OMEGA, BODY_JINV = 0, 3, 12, 15, 18
BODY_COLUMNS = 796
MODES = 24            # at most, a flexible body (scene.FLEXIBLE_MODES)
INTERFACES = 4        # at most, a flexible body's interfaces
COORDINATES = 7   # r, p (a flexible body's modal coordinates follow)
COLUMNS = 6       # velocity columns a body: v, w (a flexible body's modes follow)


def gt_times(p, w) -> tuple:
    """G(p)^T w (4): the Euler parameters' rates of the body-frame angular velocity 2 w."""
    e0, e1, e2, e3 = p
    return (-e1 * w[0] - e2 * w[1] - e3 * w[2], e0 * w[0] - e3 * w[1] + e2 * w[2],
            e3 * w[0] + e0 * w[1] - e1 * w[2], -e2 * w[0] + e1 * w[1] + e0 * w[2])


def strain_energy(model, q) -> np.ndarray:
    """The flexible bodies' strain energy at the steps (J)."""
    return model.geometry.strain_energy(model.names, q)


def constants(flexible) -> np.ndarray:
    """A flexible body's row of Args.flex: modes n, interfaces, omega^2, 2 zeta omega, the
    second moments I_ab, s_ab, S_ab, K_G,ab, and per interface x_k, T_k, R_k (the order of the
    core's Spatial::flex_column)."""
    b, n = flexible.body, flexible.n
    omega = b.omega[:n]
    parts = [[n, len(b.interfaces)], omega ** 2, 2 * flexible.ratios * omega, b.second_moments,
             b.s[:, :, :n], b.S[:, :, :n, :n], flexible.stiffening_matrices]
    for k in range(len(b.interfaces)):
        parts += [flexible.centres[k], b.interface_translation[k, :, :n], b.interface_rotation[k, :, :n]]
    return np.concatenate([np.asarray(p, float).ravel() for p in parts])


# ---- a spatial scene as the model's arrays (reduced.mechanism.model.build asks these)
RIGID_COLUMNS = BODY_OMEGA + 3   # what a run's record keeps of a body's row (its angular velocity)
PROJECT_FIRST = True    # an accepted step is projected before its events are read (layout.Args)


class Geometry(FlexibleGeometry):
    """A spatial scene's bodies and ideal joints as the model's arrays: the coordinates, the
    mass, the primitive constraints ([Nikravesh1988] ch. 7) of an ideal joint (`ideal`, which
    the clearance joints' types close theirs with, reduced.mechanism.joints), torsion
    elements, and the consistent initial state."""

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
        found += clearance_points(scene)
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
            rows += self.ideal(j.type, j.body_i, j.body_j, j.point_i, j.point_j, np.array(u_i),
                               np.array(u_j), self.source)
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

    def ideal(self, kind, body_i, body_j, point_i, point_j, u_i, u_j, source) -> list:
        """The primitive constraints of an ideal joint of `kind` (joint_primitives) between the
        bodies named body_i and body_j, at their points point_i and point_j, u_i and u_j unit
        axes in their frames (any for a spherical joint)."""
        return joint_primitives(kind, self.index[body_i], self.index[body_j], point_i, point_j, u_i,
                                u_j, self.rot[body_i], self.rot[body_j], source)

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
            work = kernel.workspace(args)
            for _ in range(50):
                if not kernel.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
                    break
            _, phi, _ = kernel.constraint_values(0.0, y, args)
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
    guide = next((j for j in model.scene.joints if j.guides_a_slider), None)
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
    Gauss-Newton projection, kernel.project_onto_constraints)."""
    y = y.copy()
    work = kernel.workspace(args)
    for _ in range(50):
        if not kernel.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
            break
    return y

