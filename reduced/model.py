"""From a reduced scene to the arrays of the compiled kernel, with consistent initial
conditions (clearance joints start centred, velocities from the constraints)."""

import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.calibration import lawsfile
from pinbore.core.errors import InputError
from pinbore.laws import dissipative, elastic
from pinbore.laws.sliced import sliced
from pinbore.laws.tables import log_grid, split_compliance
from pinbore.reduced import kernel
from pinbore.reduced.layout import (
    CONTINUOUS, COULOMB, COULOMB_MU, DAHL, DAHL_MU, DAHL_SIGMA, DRIVE_ANGLE, DRIVE_BODY, DRIVE_COLUMNS,
    DRIVE_SPEED, ENERGY_STATES, IWAN, IWAN_K1, IWAN_K2, IWAN_MU, JOINT_BEARING_BODY,
    JOINT_BEARING_RADIUS, JOINT_BEARING_X, JOINT_BEARING_Y, JOINT_CHI, JOINT_CLEARANCE, JOINT_COLUMNS,
    CHI_POINTS, JOINT_CHI_LOG_SPEED, JOINT_CHI_STEP, JOINT_CHI_TABLE,
    JOINT_FRICTION_LAW, JOINT_IMPACT, JOINT_JOURNAL_BODY, JOINT_JOURNAL_X, JOINT_JOURNAL_Y,
    JOINT_REST_SPEED, JOINT_RESTITUTION, JOINT_STATE, LATCH, LINEAR, LINEAR_ALPHA, LINEAR_MU_STATIC,
    LUGRE, LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_SIGMA0, LUGRE_SIGMA1, LUGRE_SIGMA2,
    LUGRE_STRIBECK_SPEED, NEWTON, NO_FRICTION, POISSON, PRISMATIC_ANGLE, PRISMATIC_AXIS_ANGLE,
    PRISMATIC_AXIS_X, PRISMATIC_AXIS_Y, PRISMATIC_BODY, PRISMATIC_COLUMNS, PRISMATIC_X, PRISMATIC_Y,
    REGULARISATION_V0, REGULARISATION_V1, REVOLUTE_BODY_I, REVOLUTE_BODY_J, REVOLUTE_COLUMNS,
    REVOLUTE_X_I, REVOLUTE_X_J, REVOLUTE_Y_I, REVOLUTE_Y_J, SPRING, STOP, STRIBECK, STRIBECK_MU_MIN,
    STRIBECK_MU_STATIC, STRIBECK_V_MIN, TORSION_BODY_I, TORSION_BODY_J, TORSION_COLUMNS,
    TORSION_DAMPING, TORSION_FREE_ANGLE, TORSION_KIND, TORSION_STIFFNESS, KernelArgs, row)
from pinbore.reduced.scene import GROUND, MAX_STEPS, ReducedScene

GRID_POINTS = 600
GRID_LOW = 1e-12       # m, smallest tabulated penetration (power law below)
SPEED_FLOOR = 1e-3     # m/s, smallest impact speed in chi delta'/v0 (grazing contacts)
BLOW_UP_FRACTION = 0.1  # a penetration beyond this fraction of the journal radius stops a run
STEPS_PER_PERIOD = 300  # default dopri5_fixed step: this fraction of the shortest period


@dataclass
class Model:
    scene: ReducedScene
    names: list[str]
    minv: np.ndarray
    gravity: np.ndarray
    revolute: np.ndarray
    prismatic: np.ndarray
    drive: np.ndarray
    joints: np.ndarray
    grid_log0: float
    grid_step: float
    tables: np.ndarray
    calibration: dict | None      # the laws file, when a calibrated law is used
    torsion: np.ndarray           # (k, TORSION_COLUMNS): see reduced.layout
    friction_states: int          # integrator states of LuGre, Dahl (1) and Iwan (2) joints
    y0: np.ndarray

    @property
    def nq(self) -> int:
        return self.minv.size

    def kernel_args(self, speeds=None, latched=None, mode=None, drive=None) -> KernelArgs:
        """The arguments of kernel.rhs and kernel.integrate: impact speeds (default: the
        floor), latch flags and contact modes (the integrator's, given here to evaluate a
        recorded step or to continue a run; copied, as the integrator updates them in place),
        and the drive row (default: the scene's)."""
        nj, nt = self.joints.shape[0], self.torsion.shape[0]
        gravity_x, gravity_y = self.gravity
        return KernelArgs(
            nq=self.nq, minv=self.minv, gravity_x=gravity_x, gravity_y=gravity_y, revolute=self.revolute,
            prismatic=self.prismatic, drive=self.drive if drive is None else drive,
            baumgarte=self.scene.integrator.baumgarte, joints=self.joints,
            speeds=np.full(nj, SPEED_FLOOR) if speeds is None else np.array(speeds, float),
            grid_log0=self.grid_log0, grid_step=self.grid_step, tables=self.tables, torsion=self.torsion,
            latched=np.zeros(nt) if latched is None else np.array(latched, float),
            mode=np.zeros(nj, np.int64) if mode is None else np.array(mode, np.int64))

    def elastic_energy(self, joint: int, delta: float) -> float:
        """U(delta) of joint's law (table_energy)."""
        return table_energy(self.tables[joint], self.grid_log0, self.grid_step, delta)


def table_energy(log_f, grid_log0: float, grid_step: float, delta: float) -> float:
    """U(delta) = int_0^delta F_el of a law tabulated as ln F (pinbore.laws.tables), exact for
    the log-log interpolant the dynamics use: on a segment F = F_i (d / d_i)^s_i, whose
    integral is F_i d_i ((d/d_i)^(s_i+1) - 1)/(s_i+1); below the grid the first segment's power
    law continues to 0."""
    if delta <= 0:
        return 0.0
    d = np.exp(grid_log0 + grid_step * np.arange(log_f.size))
    f = np.exp(log_f)
    slope = np.diff(log_f) / grid_step
    x = (math.log(delta) - grid_log0) / grid_step
    i = min(max(int(math.floor(x)), 0), log_f.size - 2)
    below = f[0] * d[0] / (slope[0] + 1)
    whole = f[:i] * d[:i] * ((d[1:i + 1] / d[:i]) ** (slope[:i] + 1) - 1) / (slope[:i] + 1)
    if delta < d[0]:
        return below * (delta / d[0]) ** (slope[0] + 1)
    part = f[i] * d[i] * ((delta / d[i]) ** (slope[i] + 1) - 1) / (slope[i] + 1)
    return float(below + whole.sum() + part)


def shortest_period(model: Model) -> float:
    """The shortest natural period 2 pi sqrt(m / k) (s) of the scene's compliant elements, inf
    if it has none. A continuous clearance joint: m the reduced mass of its two bodies, k the
    secant stiffness F(d)/d of its normal law at a penetration d equal to the clearance (the
    deepest a clean run reaches, reduced/verdict.py; the stiffest point of a hardening law). A
    torsion element: the reduced inertia of its bodies and its stiffness."""
    def reduced(column, i, j):
        inverse = sum(model.minv[3 * int(b) + column] for b in (i, j) if b >= 0)
        return 1 / inverse if inverse > 0 else math.inf
    periods = []
    deltas = np.exp(model.grid_log0 + model.grid_step * np.arange(model.tables.shape[1]))
    for row_, table, c in zip(model.joints, model.tables, model.scene.clearance_joints):
        if c.impact != "continuous":
            continue
        reach = np.isfinite(table) & (deltas <= row_[JOINT_CLEARANCE])
        if reach.any():
            d = deltas[reach][-1]
            stiffness = math.exp(table[reach][-1]) / d
            periods.append(2 * math.pi * math.sqrt(
                reduced(0, row_[JOINT_BEARING_BODY], row_[JOINT_JOURNAL_BODY]) / stiffness))
    for t in model.torsion:
        if t[TORSION_STIFFNESS] > 0:
            periods.append(2 * math.pi * math.sqrt(
                reduced(2, t[TORSION_BODY_I], t[TORSION_BODY_J]) / t[TORSION_STIFFNESS]))
    return min(periods, default=math.inf)


def fixed_step(model: Model, source: str = "scene") -> float:
    """The step of dopri5_fixed (s): the scene's integrator.fixed_step, or 1/300 of the shortest
    period. Without event location the error depends on where the steps fall against a contact
    onset: on the Flores slider-crank (period 47.5 us) the first peak force is 0.1-2.5 % off at
    T/100 and within 0.2 % at five steps around T/300 (0.16 us; 1e-8-rtol DOPRI5 as reference);
    max_step when the scene has no compliant element. One InputError line when the derived
    step would need more than MAX_STEPS steps, or when a clearance joint has rigid impacts
    (no period: the step must be given)."""
    s = model.scene.integrator
    if s.fixed_step is not None:
        return s.fixed_step
    rigid = [c.name for c in model.scene.clearance_joints if c.impact != "continuous"]
    if rigid:
        raise InputError(f"{source}: integrator.fixed_step: required by method = 'dopri5_fixed' "
                         f"with rigid impacts ({', '.join(rigid)}): they have no contact period "
                         "to derive a step from")
    step = min(shortest_period(model) / STEPS_PER_PERIOD, s.max_step)
    if model.scene.duration / step > MAX_STEPS:
        raise InputError(f"{source}: integrator.fixed_step: the default fixed step {step:.3g} s "
                         f"(1/300 of the shortest contact or torsion period) needs "
                         f"{model.scene.duration / step:.3g} steps, more than {MAX_STEPS:.0e}: "
                         "use method = 'dopri5' or a shorter duration")
    return step


def build(scene: ReducedScene, source: str, base: Path) -> Model:
    names = [b.name for b in scene.bodies]
    index = {name: i for i, name in enumerate(names)} | {GROUND: -1}
    _check_connected(scene, names)
    minv = np.array([[1 / b.mass, 1 / b.mass, 1 / b.inertia] for b in scene.bodies]).ravel()
    revolute = np.array([revolute_row(j, index) for j in scene.joints if j.type == "revolute"],
                        float).reshape(-1, REVOLUTE_COLUMNS)
    prismatic = np.array([prismatic_row(j, index, scene) for j in scene.joints if j.type == "prismatic"],
                         float).reshape(-1, PRISMATIC_COLUMNS)
    drive = np.array(row(DRIVE_COLUMNS, {DRIVE_BODY: index[scene.drive.body],
                                         DRIVE_SPEED: scene.drive.speed_rpm * 2 * math.pi / 60,
                                         DRIVE_ANGLE: math.radians(scene.drive.angle0_deg)})
                     if scene.drive else row(DRIVE_COLUMNS, {DRIVE_BODY: -1.0}))
    laws_data = _laws_file(scene, base, source)
    joints, tables, friction_states = [], [], 0
    # penetrations up to a tenth of the journal radius are tabulated; beyond, the run has blown up
    top = max((BLOW_UP_FRACTION * c.journal_radius for c in scene.clearance_joints), default=1.0)
    grid_log0, grid_step, deltas = log_grid(GRID_LOW, top, GRID_POINTS)
    for c in scene.clearance_joints:
        code, parameters, states = friction_block(c.friction)
        parameters |= damping_block(c, laws_data, source)
        state = -1
        if states:
            state = 2 * len(minv) + ENERGY_STATES + friction_states
            friction_states += states
        (bearing_x, bearing_y), (journal_x, journal_y) = c.bearing_point, c.journal_point
        joints.append(row(JOINT_COLUMNS, {
            JOINT_BEARING_BODY: index[c.bearing_body], JOINT_BEARING_X: bearing_x,
            JOINT_BEARING_Y: bearing_y, JOINT_JOURNAL_BODY: index[c.journal_body],
            JOINT_JOURNAL_X: journal_x, JOINT_JOURNAL_Y: journal_y,
            JOINT_CLEARANCE: c.bearing_radius - c.journal_radius,
            JOINT_BEARING_RADIUS: c.bearing_radius, JOINT_FRICTION_LAW: code,
            JOINT_STATE: state, JOINT_IMPACT: IMPACT[c.impact], JOINT_RESTITUTION: c.restitution,
            JOINT_REST_SPEED: c.rest_speed} | parameters))
        if c.impact == "continuous":
            force = normal_force(c, deltas, laws_data, source)
            force[deltas > BLOW_UP_FRACTION * c.journal_radius] = np.nan
        else:
            force = np.full(GRID_POINTS, np.nan)   # rigid: no law, never evaluated
        tables.append(np.log(force))
    model = Model(scene, names, minv, np.asarray(scene.gravity, float), revolute, prismatic, drive,
                  np.array(joints, float).reshape(-1, JOINT_COLUMNS), grid_log0, grid_step,
                  np.array(tables).reshape(len(joints), GRID_POINTS), laws_data,
                  torsion_rows(scene, index), friction_states, np.empty(0))
    model.y0 = initial_state(model)
    if scene.integrator.method == "dopri5_fixed":
        fixed_step(model, source)   # refuses a default step that cannot finish, before any work
    return model


def damping_block(c, laws_data, source) -> dict:
    """The damping columns of a clearance joint's row: chi of a published hysteresis law for
    the joint's restitution, or (damping_law = "calibrated") the table of chi(v0) over the
    speed range of the laws file's restitution law: at CHI_POINTS speeds equally spaced in
    ln v0, chi = laws.dissipative.hysteresis_for_restitution(e(v0)) (kernel.joint_chi
    interpolates it, held at the ends)."""
    if c.damping_law != "calibrated":
        chi = 0.0 if c.damping_law == "none" else dissipative.HYSTERESIS[c.damping_law](c.restitution)
        return {JOINT_CHI: chi}
    law = calibrated_restitution(c, laws_data, source)
    low, high = (math.log(v) for v in law.speed_range_m_per_s)
    speeds = np.exp(np.linspace(low, high, CHI_POINTS))
    chis = [dissipative.hysteresis_for_restitution(law.restitution(v)) for v in speeds]
    block = {JOINT_CHI: chis[0], JOINT_CHI_LOG_SPEED: low,
             JOINT_CHI_STEP: (high - low) / (CHI_POINTS - 1) if high > low else 1.0}
    return block | {JOINT_CHI_TABLE + i: chi for i, chi in enumerate(chis)}


def calibrated_restitution(c, laws_data, source) -> lawsfile.RestitutionLaw:
    """The laws file's restitution law for the clearance joint c (damping_law =
    "calibrated"): the one fitted on impacts of its radii and of its journal's and bearing's
    E and nu; none, or several (joints differing only in densities or mass per length, which
    the multibody joint does not know), is one InputError line."""
    j = c.elastic_joint()
    where = f"{source}: clearance_joints.{c.name}.damping_law: 'calibrated'"
    if laws_data is None or not laws_data.restitution:
        raise InputError(f"{where} needs a laws_file with a restitution law "
                         "(pinbore calibrate --impacts IMPACT.json ...)")
    found = laws_data.restitution_for(j.r_bore, j.r_pin, j.E_pin, j.nu_pin, j.E_bore, j.nu_bore)
    if len(found) != 1:
        what = "no restitution law" if not found else f"{len(found)} restitution laws"
        raise InputError(f"{where}: {what} of the laws file fits the joint (bearing_radius "
                         f"{j.r_bore:.6g} m, journal_radius {j.r_pin:.6g} m, journal E {j.E_pin:.4g} "
                         f"Pa nu {j.nu_pin:.4g}, bearing E {j.E_bore:.4g} Pa nu {j.nu_bore:.4g}); "
                         f"the file has: {'; '.join(laws_data.restitution)}")
    return next(iter(found.values()))


IMPACT = {"continuous": CONTINUOUS, "newton": NEWTON, "poisson": POISSON}
TORSION_KINDS = {"spring": SPRING, "stop": STOP, "latch": LATCH}


def revolute_row(j, index) -> list:
    (x_i, y_i), (x_j, y_j) = j.point_i, j.point_j
    return row(REVOLUTE_COLUMNS, {
        REVOLUTE_BODY_I: index[j.body_i], REVOLUTE_X_I: x_i, REVOLUTE_Y_I: y_i,
        REVOLUTE_BODY_J: index[j.body_j], REVOLUTE_X_J: x_j, REVOLUTE_Y_J: y_j})


def prismatic_row(j, index, scene) -> list:
    (x, y), (axis_x, axis_y) = j.point, j.axis_point
    return row(PRISMATIC_COLUMNS, {
        PRISMATIC_BODY: index[j.body], PRISMATIC_X: x, PRISMATIC_Y: y, PRISMATIC_AXIS_X: axis_x,
        PRISMATIC_AXIS_Y: axis_y, PRISMATIC_AXIS_ANGLE: math.radians(j.axis_deg),
        PRISMATIC_ANGLE: math.radians(scene.bodies[index[j.body]].angle_deg)})


def torsion_rows(scene, index) -> np.ndarray:
    """Torsion springs, stops and latches; angles relative to the bodies' initial relative angle."""
    angle = {b.name: math.radians(b.angle_deg) for b in scene.bodies} | {GROUND: 0.0}
    return np.array([row(TORSION_COLUMNS, {
        TORSION_BODY_I: index[t.body_i], TORSION_BODY_J: index[t.body_j],
        TORSION_STIFFNESS: t.stiffness, TORSION_DAMPING: t.damping,
        TORSION_FREE_ANGLE: angle[t.body_j] - angle[t.body_i] + math.radians(t.free_angle_deg),
        TORSION_KIND: TORSION_KINDS[t.type]})
        for t in scene.torsion], float).reshape(-1, TORSION_COLUMNS)


def friction_block(f):
    """(law code, {joint column: parameter}, number of integrator states) of a friction table
    (the columns: reduced.layout). The static laws carry their regularisation speeds v0, v1."""
    if f is None:
        return NO_FRICTION, {}, 0
    if f.law == "coulomb_ambrosio":
        return COULOMB, {COULOMB_MU: f.mu, REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}, 0
    if f.law == "stribeck":
        return STRIBECK, {STRIBECK_MU_STATIC: f.mu_static, STRIBECK_MU_MIN: f.mu_min,
                          STRIBECK_V_MIN: f.v_min, REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}, 0
    if f.law == "linear":
        return LINEAR, {LINEAR_MU_STATIC: f.mu_static, LINEAR_ALPHA: f.alpha,
                        REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}, 0
    if f.law == "lugre":
        return LUGRE, {LUGRE_MU_COULOMB: f.mu_coulomb, LUGRE_MU_STATIC: f.mu_static,
                       LUGRE_STRIBECK_SPEED: f.stribeck_speed, LUGRE_SIGMA0: f.sigma0,
                       LUGRE_SIGMA1: f.sigma1, LUGRE_SIGMA2: f.sigma2}, 1
    if f.law == "dahl":
        return DAHL, {DAHL_MU: f.mu, DAHL_SIGMA: f.sigma}, 1
    return IWAN, {IWAN_K1: f.k1, IWAN_K2: f.k2, IWAN_MU: f.mu}, 2


def normal_force(c, deltas, laws_data, source) -> np.ndarray:
    """Elastic normal force (N) of a clearance joint at the penetrations `deltas`; a
    calibrated law is that of the laws file (`laws_data`, calibration/lawsfile.py) times
    the joint's length."""
    joint = c.elastic_joint()
    if c.normal_law == "hertz_point":
        return elastic.hertz_point(deltas, joint)
    if c.normal_law.startswith("calibrated:"):
        return per_length_force(c.normal_law, laws_data, deltas, joint,
                                f"{source}: clearance_joints.normal_law") * c.length
    if c.normal_law.startswith("sliced:"):
        # a straight pin (no tilt in the planar model): every slice at the same approach, so
        # one slice of width L + 2 end_length gives the sliced sum (laws.sliced, theta = 0,
        # no relief): F = scale (L + 2 e) f_loc(d - c_b F / L), tabulated on the grid of
        # `deltas`
        law, per_length = sliced_parts(c, deltas, laws_data, source)
        grid_log0 = math.log(deltas[0])
        grid_step = math.log(deltas[1] / deltas[0])
        bulk = law.bulk_compliance_m2_per_N
        local = split_compliance(grid_log0, grid_step, np.log(per_length), bulk)
        return np.array([sliced(d, 0.0, c.length, 1, *local, 0.0, 0.0, law.end_length_m,
                                law.scale, bulk)[0] for d in deltas])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the range is enforced by the table (NaN beyond it)
        return elastic.PUBLISHED[c.normal_law](deltas, joint) * c.length


def sliced_parts(c, deltas, laws_data, source):
    """(the law, its per-length law f (N/m) at deltas) of a clearance joint's
    `sliced:<group>` law; one InputError line for an unknown group, a joint too short for
    the end lengths, or radii other than those of a law on its section's FE curve. The
    per-length law takes the materials and law length it was calibrated with (the scene's
    radii: the clearance is the joint's own)."""
    name = c.normal_law.split(":", 1)[1]
    if name not in laws_data.sliced:
        raise InputError(f"{source}: clearance_joints.normal_law: {c.normal_law!r} is not a "
                         "3D law of the laws file; valid: "
                         f"{', '.join('sliced:' + k for k in laws_data.sliced) or 'none (no 3D curves)'}")
    law = laws_data.sliced[name]
    if c.length + 2 * law.end_length_m <= 0:
        raise InputError(f"{source}: clearance_joints.length: {c.length:g} m is too short for "
                         f"{c.normal_law!r}, whose end lengths ({law.end_length_m:.3g} m each) "
                         "leave no length to carry the load")
    if law.section is None:
        calibrated_joint = law.joint.joint(c.bearing_radius, c.journal_radius)
        return law, per_length_force(law.per_length_law, laws_data, deltas, calibrated_joint,
                                     f"{source}: laws file: sliced.{name}.per_length_law")
    # the 2D FE curve of the calibrated section: valid for its own radii only
    if not (math.isclose(c.bearing_radius, law.joint.r_bore, rel_tol=1e-9)
            and math.isclose(c.journal_radius, law.joint.r_pin, rel_tol=1e-9)):
        raise InputError(
            f"{source}: clearance_joints.bearing_radius, journal_radius: {c.normal_law!r} is "
            f"built on the FE curve of its own section (radii {law.joint.r_bore:g} m and "
            f"{law.joint.r_pin:g} m); use those radii, or a sliced law calibrated with "
            "--per-length calibrated:<law>")
    return law, law.section.force(deltas)


def per_length_force(name, laws_data, deltas, joint, where) -> np.ndarray:
    """P(d) (N/m) of a per-length law of the laws file (calibrated:<law>) or a published one;
    `where` names the key that gave `name` in the one-line error for an unknown law."""
    if not name.startswith("calibrated:"):
        if name not in elastic.PUBLISHED:
            raise InputError(f"{where}: {name!r} is not a published law; valid: "
                             f"{', '.join(elastic.PUBLISHED)}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the range is enforced by the table (NaN beyond it)
            return elastic.PUBLISHED[name](deltas, joint)
    law = name.split(":", 1)[1]
    fitted = laws_data.fitted()
    if law not in fitted:
        raise InputError(f"{where}: {name!r} is not a fitted law of the laws file; valid: "
                         f"calibrated:{', calibrated:'.join(fitted)}")
    return fitted[law].force(law, deltas, joint)


def laws_path(scene, base: Path) -> Path | None:
    """Where the scene's laws file is (relative to the scene's folder `base`), if it has one."""
    if scene.laws_file is None:
        return None
    return (base / scene.laws_file) if not Path(scene.laws_file).is_absolute() else Path(scene.laws_file)


def _laws_file(scene, base: Path, source: str) -> lawsfile.LawsFile | None:
    """The scene's laws file, validated."""
    path = laws_path(scene, base)
    return None if path is None else lawsfile.read(path, f"{source}: laws_file: {path}")


def _check_connected(scene, names) -> None:
    """Every body must be linked to the others (through joints, clearance joints, the ground)."""
    links = {name: set() for name in names + [GROUND]}
    pairs = [(j.body_i, j.body_j) if j.type == "revolute" else (j.body, GROUND) for j in scene.joints]
    pairs += [(c.bearing_body, c.journal_body) for c in scene.clearance_joints]
    pairs += [(t.body_i, t.body_j) for t in scene.torsion]
    if scene.drive:
        pairs.append((scene.drive.body, GROUND))
    for a, b in pairs:
        links[a].add(b)
        links[b].add(a)
    start = names[0]
    seen, todo = {start}, [start]
    while todo:
        for other in links[todo.pop()] - seen:
            seen.add(other)
            todo.append(other)
    lost = [n for n in names if n not in seen]
    if lost:
        raise InputError(f"bodies: {', '.join(lost)} not connected to {start} by any joint "
                         "(disconnected mechanism)")


# a clearance joint closed: the revolute joint of its bearing and journal centres
CLOSED = ((REVOLUTE_BODY_I, JOINT_BEARING_BODY), (REVOLUTE_X_I, JOINT_BEARING_X),
          (REVOLUTE_Y_I, JOINT_BEARING_Y), (REVOLUTE_BODY_J, JOINT_JOURNAL_BODY),
          (REVOLUTE_X_J, JOINT_JOURNAL_X), (REVOLUTE_Y_J, JOINT_JOURNAL_Y))


def _as_revolutes(model: Model, starts=("ideal", "free")) -> np.ndarray:
    """Ideal revolutes plus the clearance joints whose start is in `starts`, closed."""
    keep = [j for j, c in enumerate(model.scene.clearance_joints) if c.start in starts]
    closed = np.zeros((len(keep), REVOLUTE_COLUMNS))
    for revolute_column, joint_column in CLOSED:
        closed[:, revolute_column] = model.joints[keep, joint_column]
    return np.vstack([model.revolute, closed]) if closed.size else model.revolute


def project(q, qd, revolute, prismatic, drive, minv, t=0.0):
    """The nearest consistent state: positions moved least onto Phi(q, t) = 0 (Gauss-Newton),
    velocities projected onto Phi_q q' = -Phi_t with least change in kinetic-energy norm.
    Returns (q, q', largest remaining position gap)."""
    q, qd = q.copy(), qd.copy()
    zero = np.zeros_like(q)
    gap = 0.0
    for _ in range(50):
        jac, _, phi, _ = kernel.constraints(t, q, zero, revolute, prismatic, drive, 0.0)
        gap = np.max(np.abs(phi), initial=0.0)
        if jac.shape[0] == 0 or gap < 1e-14:
            break
        q -= jac.T @ np.linalg.lstsq(jac @ jac.T, phi, rcond=None)[0]
    jac, _, _, phi_t = kernel.constraints(t, q, zero, revolute, prismatic, drive, 0.0)
    if jac.shape[0]:
        scaled = jac * minv
        qd -= scaled.T @ np.linalg.lstsq(scaled @ jac.T, jac @ qd + phi_t, rcond=None)[0]
    return q, qd, gap


def initial_state(model: Model) -> np.ndarray:
    """Positions satisfying the ideal joints with the journals centred (least change from the
    scene's guesses), and the scene's velocities projected onto Phi_q q' = -Phi_t (least change
    in kinetic-energy norm) of the ideal joints and the clearance joints that start "ideal"
    ("placed" journals keep their positions)."""
    q = np.array([[*b.position, math.radians(b.angle_deg)] for b in model.scene.bodies]).ravel()
    qd = np.array([[*b.velocity, b.omega] for b in model.scene.bodies]).ravel()
    q, _, gap = project(q, qd, _as_revolutes(model), model.prismatic, model.drive, model.minv)
    if gap >= 1e-14:
        raise InputError("joints: the bodies cannot be placed so that every joint closes "
                         f"(largest gap {gap:.3g} m)")
    _, qd, _ = project(q, qd, _as_revolutes(model, ("ideal",)), model.prismatic, model.drive,
                       model.minv)
    return np.concatenate([q, qd, np.zeros(ENERGY_STATES), np.zeros(model.friction_states)])
