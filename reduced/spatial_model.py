"""From a spatial scene to the arrays of the spatial kernel, with consistent initial conditions:
every ideal joint becomes primitive constraints (reduced.spatial_kernel), the clearance joints
start closed (journal centred and aligned, ball centred) and the velocities are projected
onto the constraints, as the planar model does (reduced.model)."""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.laws import elastic
from pinbore.laws.tables import log_grid, split_compliance
from pinbore.reduced import spatial_kernel
from pinbore.reduced.layout import (ENERGY_STATES, JOINT_BEARING_RADIUS, JOINT_CLEARANCE, JOINT_FRICTION_LAW, TORSION_BODY_I,
                                    TORSION_BODY_J, TORSION_DAMPING, TORSION_FREE_ANGLE,
                                    TORSION_KIND, TORSION_STIFFNESS, row)
from pinbore.reduced.model import (BLOW_UP_FRACTION, GRID_LOW, GRID_POINTS, SPEED_FLOOR,
                                   TORSION_KINDS, damping_block, friction_block, laws_path,
                                   per_length_force,
                                   sliced_parts, table_energy)
from pinbore.core import scene as scenes
from pinbore.reduced.spatial_layout import (
    ANGLE, CHANNELS, CYLINDER, DOT1, DOT2, POINT, PRIM_A_I, PRIM_ANGLE0, PRIM_B_J, PRIM_BODY_I,
    PRIM_BODY_J, PRIM_C_I, PRIM_KIND, PRIM_S_I, PRIM_S_J, PRIM_SPEED, PRIMITIVE_COLUMNS,
    SJ_AXIAL_CLEARANCE, SJ_AXIAL_STIFFNESS, SJ_BEARING_AXIS, SJ_BEARING_BODY, SJ_BEARING_POINT,
    SJ_COMPLIANCE,
    SJ_END_LENGTH, SJ_JOURNAL_AXIS, SJ_JOURNAL_BODY, SJ_JOURNAL_POINT, SJ_KIND, SJ_LENGTH,
    SJ_SCALE, SJ_SLICES, SPATIAL_JOINT_COLUMNS, SPATIAL_TORSION_COLUMNS, SPHERE, TORSION_A_I,
    TORSION_B_J, TORSION_C_I, SpatialArgs)
from pinbore.reduced.scene import GROUND
from pinbore.reduced.spatial_scene import SpatialScene, rotation_matrix, unit_axis


PARALLEL = 1e-9   # |1 - |u_b . u_j|| below which a journal's axis is aligned with its bore's


@dataclass
class SpatialModel:
    scene: SpatialScene
    names: list[str]
    masses: np.ndarray
    inertia: np.ndarray
    primitives: np.ndarray
    joints: np.ndarray
    grid_log0: float
    grid_step: float
    tables: np.ndarray
    calibration: object | None
    torsion: np.ndarray
    y0: np.ndarray

    @property
    def nq(self) -> int:
        return 7 * self.masses.size

    def kernel_args(self, speeds=None, latched=None, primitives=None) -> SpatialArgs:
        """The arguments of the spatial kernel (impact speeds per contact channel, latch flags:
        copied, the integrator updates them in place)."""
        nj, nt = self.joints.shape[0], self.torsion.shape[0]
        return SpatialArgs(
            nq=self.nq, masses=self.masses, inertia=self.inertia,
            inertia_inv=np.linalg.inv(self.inertia), gravity=np.asarray(self.scene.gravity, float),
            primitives=self.primitives if primitives is None else primitives,
            baumgarte=self.scene.integrator.baumgarte, joints=self.joints,
            speeds=np.full(CHANNELS * nj, SPEED_FLOOR) if speeds is None else np.array(speeds, float),
            grid_log0=self.grid_log0, grid_step=self.grid_step, tables=self.tables,
            torsion=self.torsion,
            latched=np.zeros(nt) if latched is None else np.array(latched, float),
            mode=np.zeros(nj, np.int64))

    def elastic_energy(self, joint: int, delta: float) -> float:
        """U(delta) of the per-length (or point) law of a joint (reduced.model.table_energy)."""
        return table_energy(self.tables[joint], self.grid_log0, self.grid_step, delta)


def normals(u):
    """Two unit vectors f, g = u x f normal to the unit vector u (a right-handed triad)."""
    u = np.asarray(u, float)
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    f = np.cross(u, helper)
    f /= np.linalg.norm(f)
    return f, np.cross(u, f)


def primitive(kind, bi, bj, s_i=(0, 0, 0), s_j=(0, 0, 0), a_i=(0, 0, 0), b_j=(0, 0, 0),
              c_i=(0, 0, 0), speed=0.0, angle0=0.0) -> list:
    out = row(PRIMITIVE_COLUMNS, {PRIM_KIND: kind, PRIM_BODY_I: bi, PRIM_BODY_J: bj,
                                  PRIM_SPEED: speed, PRIM_ANGLE0: angle0})
    for column, v in ((PRIM_S_I, s_i), (PRIM_S_J, s_j), (PRIM_A_I, a_i), (PRIM_B_J, b_j),
                      (PRIM_C_I, c_i)):
        out[column:column + 3] = [float(c) for c in v]
    return out


def joint_primitives(kind, bi, bj, s_i, s_j, u_i, u_j, a_i, a_j, source) -> list:
    """The primitive constraints of an ideal joint (spatial_kernel docstring); a_i, a_j the
    bodies' initial rotation matrices (u_i, u_j unit, in body frames)."""
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


def per_length_table(c, deltas, laws_data, source):
    """(scale a, end length e, bulk compliance c_b (m^2/N), the per-length force f (N/m) the
    slices carry at deltas: a sliced law's local law f_loc, laws.sliced) of a cylindrical
    joint, or (1, 0, 0, F (N)) of a spherical one."""
    joint = c.elastic_joint()
    if c.type == "spherical":
        return 1.0, 0.0, 0.0, elastic.hertz_point(deltas, joint)
    if c.normal_law == "hertz_point":   # the point law spread evenly over the length
        return 1.0, 0.0, 0.0, elastic.hertz_point(deltas, joint) / c.length
    if c.normal_law.startswith("sliced:"):
        law, per_length = sliced_parts(c, deltas, laws_data, source)
        bulk = law.bulk_compliance_m2_per_N
        if bulk > 0:   # the slices carry the local law; the kernel moves the bore (laws.sliced)
            grid_log0, grid_step = math.log(deltas[0]), math.log(deltas[1] / deltas[0])
            local_log0, local_step, local_table = split_compliance(
                grid_log0, grid_step, np.log(per_length), bulk)
            per_length = np.exp(np.interp(   # on the model's grid: log-log, as the lookup
                np.log(deltas), local_log0 + local_step * np.arange(local_table.size),
                local_table, right=np.nan))
        return law.scale, law.end_length_m, bulk, per_length
    return 1.0, 0.0, 0.0, per_length_force(c.normal_law, laws_data, deltas, joint,
                                           f"{source}: clearance_joints.normal_law")


def build(scene: SpatialScene, source: str, base: Path) -> SpatialModel:
    names = [b.name for b in scene.bodies]
    index = {name: i for i, name in enumerate(names)} | {GROUND: -1}
    rot = {GROUND: np.eye(3)} | {b.name: rotation_matrix(b.parameters()) for b in scene.bodies}
    masses = np.array([b.mass for b in scene.bodies], float)
    inertia = np.array([b.inertia for b in scene.bodies], float)
    prims = []
    named = {}
    for j in scene.joints:
        u_i = unit_axis(j.axis_i, "axis_i") if j.axis_i else [0, 0, 1]
        u_j = unit_axis(j.axis_j, "axis_j") if j.axis_j else [0, 0, 1]
        prims += joint_primitives(j.type, index[j.body_i], index[j.body_j], j.point_i, j.point_j,
                                  np.array(u_i), np.array(u_j), rot[j.body_i], rot[j.body_j], source)
        if j.name:
            named[j.name] = (j, np.array(u_i))
    if scene.drive is not None:
        j, u_i = named[scene.drive.joint]
        f, g = normals(u_i)
        prims.append(primitive(ANGLE, index[j.body_i], index[j.body_j], a_i=f,
                               b_j=rot[j.body_j].T @ rot[j.body_i] @ f, c_i=g,
                               speed=scene.drive.speed_rpm * 2 * math.pi / 60))
    laws_data = _laws_file(scene, base, source)
    top = max((BLOW_UP_FRACTION * c.journal_radius for c in scene.clearance_joints), default=1.0)
    grid_log0, grid_step, deltas = log_grid(GRID_LOW, top, GRID_POINTS)
    joints, tables = [], []
    for c in scene.clearance_joints:
        code, parameters, _ = friction_block(c.friction)
        parameters |= damping_block(c, laws_data, source)   # chi, or the calibrated chi(v0)
        scale, end, bulk, force = per_length_table(c, deltas, laws_data, source)
        force = np.array(force, float)
        force[deltas > BLOW_UP_FRACTION * c.journal_radius] = np.nan
        values = {SJ_KIND: CYLINDER if c.type == "cylindrical" else SPHERE,
                  SJ_BEARING_BODY: index[c.bearing_body], SJ_JOURNAL_BODY: index[c.journal_body],
                  JOINT_CLEARANCE: c.bearing_radius - c.journal_radius,
                  JOINT_BEARING_RADIUS: c.bearing_radius, JOINT_FRICTION_LAW: code,
                  SJ_LENGTH: c.length or 0.0, SJ_SLICES: c.slices, SJ_END_LENGTH: end,
                  SJ_SCALE: scale, SJ_COMPLIANCE: bulk, SJ_AXIAL_CLEARANCE: c.axial_clearance or 0.0,
                  SJ_AXIAL_STIFFNESS: c.axial_stiffness or 0.0} | parameters
        out = row(SPATIAL_JOINT_COLUMNS, values)
        out[SJ_BEARING_POINT:SJ_BEARING_POINT + 3] = c.bearing_point
        out[SJ_JOURNAL_POINT:SJ_JOURNAL_POINT + 3] = c.journal_point
        if c.type == "cylindrical":
            out[SJ_BEARING_AXIS:SJ_BEARING_AXIS + 3] = unit_axis(c.bearing_axis, "bearing_axis")
            out[SJ_JOURNAL_AXIS:SJ_JOURNAL_AXIS + 3] = unit_axis(c.journal_axis, "journal_axis")
        joints.append(out)
        tables.append(np.log(force))
    torsion = []
    for t in scene.torsion:
        u = np.array(unit_axis(t.axis_i, "axis_i"))
        f, g = normals(u)
        out = row(SPATIAL_TORSION_COLUMNS, {
            TORSION_BODY_I: index[t.body_i], TORSION_BODY_J: index[t.body_j],
            TORSION_STIFFNESS: t.stiffness, TORSION_DAMPING: t.damping,
            TORSION_FREE_ANGLE: math.radians(t.free_angle_deg), TORSION_KIND: TORSION_KINDS[t.type]})
        out[TORSION_A_I:TORSION_A_I + 3] = f
        out[TORSION_C_I:TORSION_C_I + 3] = g
        out[TORSION_B_J:TORSION_B_J + 3] = rot[t.body_j].T @ rot[t.body_i] @ f
        torsion.append(out)
    model = SpatialModel(scene, names, masses, inertia,
                         np.array(prims, float).reshape(-1, PRIMITIVE_COLUMNS),
                         np.array(joints, float).reshape(-1, SPATIAL_JOINT_COLUMNS), grid_log0,
                         grid_step, np.array(tables).reshape(len(joints), GRID_POINTS), laws_data,
                         np.array(torsion, float).reshape(-1, SPATIAL_TORSION_COLUMNS), np.empty(0))
    model.y0 = initial_state(model, index, rot, source)
    return model


def ideal_kind(c, bore_axis, journal_axis) -> str:
    """The ideal joint that closes a clearance joint: spherical for a ball; for a journal a
    revolute on the bore's axis, or, when the journal's axis is tilted against the bore's at
    the start (a misaligned joint, global axes given), a spherical joint at the bore's
    centre: the journal centred, its tilt left to the other joints (a revolute could not
    close)."""
    if c.type == "spherical" or abs(abs(bore_axis @ journal_axis) - 1) > PARALLEL:
        return "spherical"
    return "revolute"


def closed(model: SpatialModel, index, rot, starts) -> np.ndarray:
    """The ideal primitives plus the clearance joints whose start is in `starts`, closed
    (cylindrical: a revolute on the bore axis; spherical: a spherical joint)."""
    extra = []
    for c in model.scene.clearance_joints:
        if c.start not in starts:
            continue
        u_b = np.array(unit_axis(c.bearing_axis, "bearing_axis")) if c.bearing_axis else np.zeros(3)
        u_j = np.array(unit_axis(c.journal_axis, "journal_axis")) if c.journal_axis else np.zeros(3)
        kind = ideal_kind(c, rot[c.bearing_body] @ u_b, rot[c.journal_body] @ u_j)
        extra += joint_primitives(kind, index[c.bearing_body], index[c.journal_body],
                                  c.bearing_point, c.journal_point, u_b, u_j, rot[c.bearing_body],
                                  rot[c.journal_body], "clearance_joints")
    return np.vstack([model.primitives, np.array(extra, float).reshape(-1, PRIMITIVE_COLUMNS)])


def initial_state(model: SpatialModel, index, rot, source) -> np.ndarray:
    """Positions on the ideal joints with the clearance joints closed (mass-weighted least
    change from the scene's guesses); then the velocities as given (each body's r' and global
    w, on the positions found), projected onto the ideal joints and the clearance joints that
    start "ideal" (those that start "free" keep their relative velocity)."""
    s = model.scene
    nq = model.nq
    y = np.concatenate([np.concatenate([[*b.position, *b.parameters()] for b in s.bodies]),
                        np.zeros(nq + ENERGY_STATES)])
    for starts in (("ideal", "free"), ("ideal",)):
        for k, b in enumerate(s.bodies):   # the given velocities at the current orientation
            p = y[7 * k + 3:7 * k + 7] / np.linalg.norm(y[7 * k + 3:7 * k + 7])
            w_body = rotation_matrix(p).T @ np.array(b.omega, float)
            y[nq + 7 * k:nq + 7 * k + 7] = [*b.velocity, *spatial_kernel.gt_times(p, tuple(0.5 * w_body))]
        args = model.kernel_args(primitives=closed(model, index, rot, starts))
        work = spatial_kernel.workspace(args)
        for _ in range(50):
            if not spatial_kernel.project_onto_constraints(0.0, y, args, work, 1e-14, 1e-14):
                break
        spatial_kernel.body_states(y, args, work)
        m = spatial_kernel.fill_constraints(0.0, work, args.primitives, 0.0)
        gap = np.max(np.abs(work.phi[:m]), initial=0.0)
        if gap >= 1e-12:
            raise InputError(f"{source}: joints: the bodies cannot be placed so that every joint "
                             f"closes (largest gap {gap:.3g})")
    return y


def _laws_file(scene, base: Path, source: str):
    from pinbore.calibration import lawsfile
    path = laws_path(scene, base)
    return None if path is None else lawsfile.read(path, f"{source}: laws_file: {path}")


def load(path: Path) -> SpatialScene:
    return scenes.load(SpatialScene, path)


def ideal_twin(scene: SpatialScene) -> SpatialScene:
    """The same mechanism with every clearance joint replaced by its ideal joint (ideal_kind:
    a revolute on the bore's axis, a spherical joint for a ball or a misaligned journal)."""
    data = scene.model_dump()
    rot = {GROUND: np.eye(3)} | {b.name: rotation_matrix(b.parameters()) for b in scene.bodies}
    for c in scene.clearance_joints:
        axes = (None, None) if c.type == "spherical" else (
            rot[c.bearing_body] @ unit_axis(c.bearing_axis, "bearing_axis"),
            rot[c.journal_body] @ unit_axis(c.journal_axis, "journal_axis"))
        kind = ideal_kind(c, *axes)
        ideal = {"type": kind, "body_i": c.bearing_body, "point_i": c.bearing_point,
                 "body_j": c.journal_body, "point_j": c.journal_point}
        if kind == "revolute":
            ideal |= {"axis_i": c.bearing_axis, "axis_j": c.journal_axis}
        data["joints"].append(ideal)
    data["clearance_joints"] = []
    return SpatialScene.model_validate(data)
