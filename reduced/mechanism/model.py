"""From a mechanism scene of any kind to the arrays of the compiled engine
(reduced.mechanism.kernel), with consistent initial conditions, written once: the laws file,
the tables of the normal laws, the contacts of every clearance joint with their damping and
friction, the torsion elements, the spring-dampers and harmonic loads, the friction states,
the fixed step. What only a kind knows (its bodies' coordinates and mass, its ideal joints
as primitive constraints, how a state is moved onto the constraints) comes from its body
kind's module (reduced.mechanism.kinds: planar or spatial); what only a clearance joint's
type knows (the ideal joint that closes it, its contacts, its law's table) from its type's
module (reduced.mechanism.joints).
"""

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.core.scene import named_file
from pinbore.laws import dissipative, lawsfile
from pinbore.laws.tables import log_grid
from pinbore.reduced.mechanism import joints, kinds, layout
from pinbore.reduced.mechanism.layout import (
    CHI_POINTS, CONTACT_BEARING_BODY, CONTACT_CHI, CONTACT_CHI_LOG_SPEED, CONTACT_CHI_STEP,
    CONTACT_CHI_TABLE, CONTACT_CLEARANCE, CONTACT_COLUMNS, CONTACT_FRICTION_LAW, CONTACT_FRICTION_ON,
    CONTACT_IMPACT, CONTACT_JOINT, CONTACT_JOURNAL_BODY, CONTACT_KIND, CONTACT_REST_SPEED,
    CONTACT_RESTITUTION, CONTACT_SLICES, CONTACT_STATE, CONTACT_TABLE, CONTINUOUS, COULOMB,
    COULOMB_MU, DAHL, DAHL_MU, DAHL_SIGMA, ENERGY_STATES, IWAN, IWAN_K1, IWAN_K2, IWAN_MU, LATCH,
    LINEAR, LINEAR_ALPHA, LINEAR_MU_STATIC, LUGRE, LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_SIGMA0,
    LUGRE_SIGMA1, LUGRE_SIGMA2, LUGRE_STRIBECK_SPEED, NEWTON, NO_FRICTION, POISSON, PRIMITIVE_COLUMNS,
    REGULARISATION_V0, REGULARISATION_V1, SLICED, SPRING, STOP, STRIBECK, STRIBECK_MU_MIN,
    STRIBECK_MU_STATIC, STRIBECK_V_MIN, TORSION_BODY_I, TORSION_BODY_J, TORSION_COLUMNS,
    TORSION_DAMPING, TORSION_KIND, TORSION_STIFFNESS, row)
from pinbore.reduced.mechanism.scene import GROUND, MAX_STEPS, clearance_joints

GRID_POINTS = 600
GRID_LOW = 1e-12       # m, smallest tabulated penetration (power law below)
SPEED_FLOOR = 1e-3     # m/s, smallest impact speed in chi delta'/v0 (grazing contacts)
STEPS_PER_PERIOD = 300  # default dopri5_fixed step: this fraction of the shortest period
IMPACT = {"continuous": CONTINUOUS, "newton": NEWTON, "poisson": POISSON}
TORSION_KINDS = {"spring": SPRING, "stop": STOP, "latch": LATCH}


@dataclass
class Model:
    """A mechanism ready to integrate: its scene and kind, the names of its bodies, the
    compiled engine's arrays (layout.Args, `args()`), the clearance joints in the order of
    their contacts and each joint's contacts (a range of rows), the laws file if a law came
    from it, the initial state y0 and the drive's primitive row (None: no drive)."""

    scene: object
    kind: kinds.Kind
    names: list[str]
    base: layout.Args
    joints: list                  # the scene's clearance joints, in the order of `contacts`
    contact_rows: list[range]     # per clearance joint, its rows of base.contacts
    calibration: object | None
    drive_row: int | None
    friction_states: int          # how many states the friction laws add to y
    y0: np.ndarray = field(default_factory=lambda: np.empty(0))
    closures: list = field(default_factory=list)   # an ideal twin's closing joints (in primitives)
    geometry: object = None       # the body kind's Geometry of the scene (its `index` of bodies)

    @property
    def nq(self) -> int:
        return self.base.nq

    @property
    def contacts(self) -> np.ndarray:
        return self.base.contacts

    @property
    def primitives(self) -> np.ndarray:
        return self.base.primitives

    @property
    def torsion(self) -> np.ndarray:
        return self.base.torsion

    def args(self, speeds=None, latched=None, mode=None, primitives=None) -> layout.Args:
        """The arguments of the engine: impact speeds per contact (default: the floor), latch
        flags and contact modes (given here to evaluate a recorded step or to continue a run;
        copied, as the integrator updates them in place), and the primitives (default: the
        scene's)."""
        nc, nt = self.contacts.shape[0], self.torsion.shape[0]
        return self.base._replace(
            speeds=np.full(nc, SPEED_FLOOR) if speeds is None else np.array(speeds, float),
            latched=np.zeros(nt) if latched is None else np.array(latched, float),
            mode=np.zeros(nc, np.int64) if mode is None else np.array(mode, np.int64),
            primitives=self.primitives if primitives is None else primitives)

    def elastic_energy(self, k: int, delta):
        """U(delta) of contact k's tabulated law (table_energy); a linear law's k delta^2 / 2
        (J; delta in m, a number or an array)."""
        stiffness = self.contacts[k, layout.CONTACT_STIFFNESS]
        if stiffness > 0:
            return 0.5 * stiffness * np.maximum(delta, 0.0) ** 2
        return table_energy(self.base.tables[int(self.contacts[k, CONTACT_TABLE])],
                            self.base.grid_log0, self.base.grid_step, delta)


def table_energy(log_f, grid_log0: float, grid_step: float, delta):
    """U(delta) = int_0^delta F_el of a law tabulated as ln F (pinbore.laws.tables), exact for
    the log-log interpolant the dynamics use: on a segment F = F_i (d / d_i)^s_i, whose
    integral is F_i d_i ((d/d_i)^(s_i+1) - 1)/(s_i+1); below the grid the first segment's power
    law continues to 0. delta: a number or an array (m); 0 where delta <= 0."""
    d = np.exp(grid_log0 + grid_step * np.arange(log_f.size))
    f = np.exp(log_f)
    slope = np.diff(log_f) / grid_step
    below = f[0] * d[0] / (slope[0] + 1)
    segment = f[:-1] * d[:-1] * ((d[1:] / d[:-1]) ** (slope + 1) - 1) / (slope + 1)
    at_node = below + np.concatenate(([0.0], np.cumsum(segment)))   # U(d_i)
    x = np.asarray(delta, float)
    positive = np.maximum(x, d[0] * 1e-300)
    i = np.clip(np.floor((np.log(positive) - grid_log0) / grid_step).astype(np.int64), 0, log_f.size - 2)
    inside = at_node[i] + f[i] * d[i] * ((positive / d[i]) ** (slope[i] + 1) - 1) / (slope[i] + 1)
    first = below * (positive / d[0]) ** (slope[0] + 1)
    energy = np.where(x <= 0, 0.0, np.where(x < d[0], first, inside))
    return float(energy) if energy.ndim == 0 else energy


# ---- the build
def build(scene, source: str, base: Path, ideal: bool = False) -> Model:
    """The model of a validated scene of any kind; `ideal`: its ideal twin, every clearance
    joint replaced by the ideal joint that closes it (a revolute, a ball joint, a prismatic
    guide), its initial state consistent with those too. One InputError line for a scene that cannot be built (a disconnected mechanism, a
    law the laws file lacks, joints that cannot all close)."""
    kind = kinds.of_scene(scene)
    body_kind = kind.bodies()
    names = [b.name for b in scene.bodies]
    index = {name: i for i, name in enumerate(names)} | {GROUND: -1}
    check_connected(scene, names)
    geometry = body_kind.Geometry(scene, index, source, base)
    clearances = clearance_joints(scene)
    types = [joints.of(c) for c in clearances]
    closures = [t.closing(geometry) for t in types] if ideal else []
    primitives, drive_row = geometry.primitives(closures)
    profile = drive_segments(scene.drive)
    laws_data = None if ideal else laws_file(scene, base, source)
    grid_log0, grid_step, deltas = log_grid(GRID_LOW, table_reach(scene), GRID_POINTS)
    contacts, tables, rows, wear = [], [], [], []
    for j, (c, t) in enumerate([] if ideal else zip(clearances, types)):
        law = law_columns(c, laws_data, source)
        geometries, table = joint_contacts(geometry, t, deltas, laws_data, source)
        worn = t.worn(base, source)
        start = len(contacts)
        for i, g in enumerate(geometries):
            if i in worn:
                g = g | worn_columns(wear, *worn[i])
            contacts.append(row(CONTACT_COLUMNS, law | g | {CONTACT_JOINT: j, CONTACT_TABLE: len(tables)}))
        tables.append(np.log(table))
        rows.append(range(start, len(contacts)))
    contacts = np.array(contacts, float).reshape(-1, CONTACT_COLUMNS)
    states = assign_friction_states(contacts, geometry.nq, kind.dimension)
    masses, minv, inertia = geometry.mass()
    args = layout.Args(
        nq=geometry.nq, like=(0.0,) * kind.dimension,
        project_first=body_kind.PROJECT_FIRST, masses=masses, minv=minv, inertia=inertia,
        inertia_inv=np.linalg.inv(inertia) if kind.dimension == 3 else inertia,
        gravity=np.asarray(scene.gravity, float), offsets=geometry.offsets(),
        primitives=np.array(primitives, float).reshape(-1, PRIMITIVE_COLUMNS),
        baumgarte=scene.integrator.baumgarte, contacts=contacts,
        speeds=np.full(contacts.shape[0], SPEED_FLOOR), grid_log0=grid_log0, grid_step=grid_step,
        tables=np.array(tables).reshape(len(tables), GRID_POINTS),
        torsion=torsion_rows(geometry, scene),
        latched=np.zeros(len(scene.torsion)), mode=np.zeros(contacts.shape[0], np.int64),
        profile=profile, flex=geometry.flex(), springs=spring_rows(geometry, scene),
        loads=load_rows(geometry, scene), wear=worn_rows(wear))
    model = Model(scene, kind, names, args, [] if ideal else clearances, rows, laws_data, drive_row,
                  states, closures=closures, geometry=geometry)
    model.y0 = geometry.place(model, [] if ideal else [(t.closing(geometry), c.start)
                                                       for c, t in zip(clearances, types)])
    if scene.integrator.method == "dopri5_fixed":
        fixed_step(model, source)   # refuses a default step that cannot finish, before any work
    elif scene.integrator.method == "dopri5":
        resolvable(model, source)
    return model


def worn_columns(wear: list, bore, pin) -> dict:
    """A worn contact's columns: its bore's and its pin's rows of Args.wear (appended to
    `wear`; one plus their index)."""
    wear += [np.asarray(bore, float), np.asarray(pin, float)]
    return {layout.CONTACT_BORE_WEAR: len(wear) - 1, layout.CONTACT_PIN_WEAR: len(wear)}


def worn_rows(wear: list) -> np.ndarray:
    """Args.wear: the worn profiles, a row each (all of one length; none: an empty array)."""
    if not wear:
        return np.zeros((0, 1))
    if len({w.size for w in wear}) != 1:
        raise InputError("the worn joints' profiles must have the same number of angles")
    return np.array(wear)


STEPS_PER_PERIOD_LEAST = 2   # no method follows a vibration in fewer steps a period


def resolvable(model: Model, source: str = "scene") -> None:
    """One InputError line, before any work, when the shortest period of the scene's compliant
    elements (shortest_period: a light body on a stiff contact) would need more than MAX_STEPS
    steps over the duration even at STEPS_PER_PERIOD_LEAST steps a period, the element engaged
    throughout: DOPRI5, explicit, cannot step over the period, and would work until it stops at
    MAX_STEPS (a spatial body of 1e-12 kg on the Flores joint: a period of 1.6e-10 s, 6e8
    steps; 1e-6 kg runs, 7.6e5 steps). The L-stable rosenbrock23 is not held to the period."""
    period = shortest_period(model)
    needed = model.scene.duration * STEPS_PER_PERIOD_LEAST / period
    if needed > MAX_STEPS:
        raise InputError(f"{source}: bodies: the shortest contact or torsion period, {period:.3g} s "
                         f"(a body's mass or inertia against a stiffness), needs at least "
                         f"{needed:.3g} steps over the duration, more than {MAX_STEPS:.0e}: the "
                         "mass ratio cannot be resolved by the explicit dopri5 (make the body "
                         "heavier, the duration shorter, or use method = 'rosenbrock23')")


def drive_segments(drive) -> np.ndarray:
    """A shaken drive's harmonics (layout.HARM_*, a row each), or the segments (layout.SEG_*)
    of a drive's angle table (none without either): the cubic spline through the table's
    angles, measured from the first, with SciPy's not-a-knot ends (a motion cubic in time is
    followed exactly), and after the last pair a segment at the last rate; one a pair, in
    the rows the drive's profile columns name."""
    if drive is not None and drive.harmonics is not None:
        return np.array([layout.row(layout.PROFILE_COLUMNS, {
            layout.HARM_AMPLITUDE: math.radians(h.amplitude_deg),
            layout.HARM_OMEGA: 2 * math.pi * h.frequency_hz,
            layout.HARM_PHASE: math.radians(h.phase_deg)}) for h in drive.harmonics])
    if drive is None or drive.angle_table is None:
        return np.empty((0, layout.PROFILE_COLUMNS))
    from scipy.interpolate import CubicSpline   # noqa: PLC0415

    times = np.array([t for t, _ in drive.angle_table])
    angles = np.radians([a for _, a in drive.angle_table])
    spline = CubicSpline(times, angles - angles[0], bc_type="not-a-knot")
    c3, c2, c1, c0 = spline.c
    end = times[-1]
    segments = np.column_stack([times[:-1], c0, c1, c2, c3])
    return np.vstack([segments, [end, float(spline(end)), float(spline(end, 1)), 0.0, 0.0]])


def table_reach(scene) -> float:
    """How deep the laws' tables reach (m; one grid for all): the deepest reach of the
    scene's journals and balls (1 m without any), or of its sliders if deeper."""
    top = max((joints.of(c).reach() for c in scene.clearance_joints), default=1.0)
    return max([top] + [joints.of(c).reach() for c in scene.translational_joints])


def joint_contacts(geometry, joint, deltas, laws_data, source):
    """(the geometry columns of each contact of a clearance joint (its type's
    base.Clearance), the force its table holds at `deltas`: N, or N/m for a journal along its
    bore; NaN beyond the joint's reach, where the run has blown up)."""
    geometries, table = joint.contacts(geometry, deltas, laws_data, source)
    table = np.array(table, float)
    table[deltas > joint.reach()] = np.nan
    return geometries, table


def assign_friction_states(contacts: np.ndarray, nq: int, dimension: int) -> int:
    """Each contact of a state law its states in y, after q, q' and the energy integrals:
    LuGre and Dahl one, Iwan two (travel, stretch), of a component each in the plane and
    three in space, per slice of a SLICED contact. Returns how many there are."""
    index = 2 * nq + ENERGY_STATES
    for k in range(contacts.shape[0]):
        law = int(contacts[k, CONTACT_FRICTION_LAW])
        if law not in (LUGRE, DAHL, IWAN) or contacts[k, CONTACT_FRICTION_ON] == 0:
            contacts[k, CONTACT_STATE] = -1
            continue
        count = (2 if law == IWAN else 1) * (1 if dimension == 2 else 3)
        if int(contacts[k, CONTACT_KIND]) == SLICED:
            count *= int(contacts[k, CONTACT_SLICES])
        contacts[k, CONTACT_STATE] = index
        index += count
    return index - 2 * nq - ENERGY_STATES


def law_columns(c, laws_data, source) -> dict:
    """The contact-law columns of every contact of the clearance joint c: impact model,
    restitution, rest speed, friction law and its parameters, the damping block."""
    law = {CONTACT_IMPACT: IMPACT[c.impact], CONTACT_RESTITUTION: c.restitution,
           CONTACT_REST_SPEED: c.rest_speed, CONTACT_FRICTION_ON: 1.0}
    code, parameters = friction_block(c.friction)
    law |= {CONTACT_FRICTION_LAW: code} | parameters
    if c.impact == "continuous":
        law |= damping_block(c, laws_data, source)
    else:
        law |= {CONTACT_CHI: 0.0}
    return law


def friction_block(f):
    """(law code, {contact column: parameter}) of a friction table (the columns:
    reduced.mechanism.layout). The static laws carry their regularisation speeds v0, v1."""
    if f is None:
        return NO_FRICTION, {}
    if f.law == "coulomb_ambrosio":
        return COULOMB, {COULOMB_MU: f.mu, REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}
    if f.law == "stribeck":
        return STRIBECK, {STRIBECK_MU_STATIC: f.mu_static, STRIBECK_MU_MIN: f.mu_min,
                          STRIBECK_V_MIN: f.v_min, REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}
    if f.law == "linear":
        return LINEAR, {LINEAR_MU_STATIC: f.mu_static, LINEAR_ALPHA: f.alpha,
                        REGULARISATION_V0: f.v0, REGULARISATION_V1: f.v1}
    if f.law == "lugre":
        return LUGRE, {LUGRE_MU_COULOMB: f.mu_coulomb, LUGRE_MU_STATIC: f.mu_static,
                       LUGRE_STRIBECK_SPEED: f.stribeck_speed, LUGRE_SIGMA0: f.sigma0,
                       LUGRE_SIGMA1: f.sigma1, LUGRE_SIGMA2: f.sigma2}
    if f.law == "dahl":
        return DAHL, {DAHL_MU: f.mu, DAHL_SIGMA: f.sigma}
    return IWAN, {IWAN_K1: f.k1, IWAN_K2: f.k2, IWAN_MU: f.mu}


def damping_block(c, laws_data, source) -> dict:
    """The damping columns of a clearance joint's contacts: chi of a published hysteresis law
    for the joint's restitution, or (damping_law = "calibrated") the table of chi(v0) over the
    speed range of the laws file's restitution law: at CHI_POINTS speeds equally spaced in
    ln v0, chi = laws.dissipative.hysteresis_for_restitution(e(v0)) (engine.contact_chi
    interpolates it, held at the ends)."""
    if c.damping_law != "calibrated":
        chi = 0.0 if c.damping_law == "none" else dissipative.HYSTERESIS[c.damping_law](c.restitution)
        return {CONTACT_CHI: chi}
    law = calibrated_restitution(c, laws_data, source)
    low, high = (math.log(v) for v in law.speed_range_m_per_s)
    speeds = np.exp(np.linspace(low, high, CHI_POINTS))
    chis = [dissipative.hysteresis_for_restitution(law.restitution(v)) for v in speeds]
    block = {CONTACT_CHI: chis[0], CONTACT_CHI_LOG_SPEED: low,
             CONTACT_CHI_STEP: (high - low) / (CHI_POINTS - 1) if high > low else 1.0}
    return block | {CONTACT_CHI_TABLE + i: chi for i, chi in enumerate(chis)}


def calibrated_restitution(c, laws_data, source) -> lawsfile.RestitutionLaw:
    """The laws file's restitution law for the clearance joint c (damping_law =
    "calibrated"), lawsfile.joint_restitution."""
    return lawsfile.joint_restitution(laws_data, c.elastic_joint(),
                                      f"{source}: clearance_joints.{c.name}.damping_law: 'calibrated'")


# ---- the laws file
def laws_path(scene, base: Path) -> Path | None:
    """Where the scene's laws file is (relative to the scene's folder `base`), if it has one."""
    if scene.laws_file is None:
        return None
    return named_file(scene.laws_file, base)


def laws_file(scene, base: Path, source: str) -> lawsfile.LawsFile | None:
    """The scene's laws file, validated."""
    path = laws_path(scene, base)
    return None if path is None else lawsfile.read(path, f"{source}: laws_file: {path}")


# ---- torsion, connectivity, the fixed step
def torsion_rows(geometry, scene) -> np.ndarray:
    """Torsion springs, stops and latches: the law's columns, and the kind's vectors and free
    angle (geometry.torsion: the relative angle measured from the initial configuration)."""
    rows = [row(TORSION_COLUMNS, {
        TORSION_BODY_I: geometry.index[t.body_i], TORSION_BODY_J: geometry.index[t.body_j],
        TORSION_STIFFNESS: t.stiffness, TORSION_DAMPING: t.damping,
        TORSION_KIND: TORSION_KINDS[t.type]} | geometry.torsion(t)) for t in scene.torsion]
    return np.array(rows, float).reshape(-1, TORSION_COLUMNS)


def spring_rows(geometry, scene) -> np.ndarray:
    """The linear spring-dampers (layout.SPRING_*)."""
    rows = [row(layout.SPRING_COLUMNS, {
        layout.SPRING_BODY_I: geometry.index[e.body_i], layout.SPRING_BODY_J: geometry.index[e.body_j],
        layout.SPRING_S_I: list(e.point_i), layout.SPRING_S_J: list(e.point_j),
        layout.SPRING_STIFFNESS: e.stiffness, layout.SPRING_DAMPING: e.damping,
        layout.SPRING_LENGTH: e.free_length}) for e in scene.springs]
    return np.array(rows, float).reshape(-1, layout.SPRING_COLUMNS)


def load_rows(geometry, scene) -> np.ndarray:
    """The harmonic loads (layout.LOAD_*): a planar torque about the plane's normal is the
    third component of the row's torque."""
    rows = [row(layout.LOAD_COLUMNS, {
        layout.LOAD_BODY: geometry.index[e.body], layout.LOAD_POINT: list(e.point),
        layout.LOAD_FORCE: list(e.force),
        layout.LOAD_TORQUE: list(e.torque) if isinstance(e.torque, list) else [0.0, 0.0, e.torque],
        layout.LOAD_OMEGA: 2 * math.pi * e.frequency_hz, layout.LOAD_PHASE: math.radians(e.phase_deg)})
        for e in scene.loads]
    return np.array(rows, float).reshape(-1, layout.LOAD_COLUMNS)


def check_connected(scene, names) -> None:
    """Every body must be linked to the others (through joints, clearance joints, torsion
    elements, the drive, the ground)."""
    links = {name: set() for name in names + [GROUND]}
    pairs = [j.linked for j in scene.joints]
    pairs += [(c.bearing_body, c.journal_body) for c in clearance_joints(scene)]
    pairs += [(t.body_i, t.body_j) for t in scene.torsion]
    pairs += [(e.body_i, e.body_j) for e in scene.springs]
    if scene.drive is not None and hasattr(scene.drive, "body"):
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


def shortest_period(model: Model) -> float:
    """The shortest natural period 2 pi sqrt(m / k) (s) of the scene's compliant elements, inf
    if it has none. A continuous contact: m the reduced mass of its two bodies, k the secant
    stiffness F(d)/d of its normal law at a penetration d equal to the clearance (the deepest
    a clean run reaches, reduced.mechanism.verdict; the stiffest point of a hardening law).
    A torsion element: the reduced inertia of its bodies about its axis and its stiffness; a
    spring-damper: the reduced mass of its bodies and its stiffness. A flexible body: its
    highest mode kept, 2 pi / omega_n."""
    geometry = model.geometry
    masses = model.base.masses

    def reduced(i, j, inverse):
        total = sum(inverse(int(b)) for b in (i, j) if b >= 0)
        return 1 / total if total > 0 else math.inf
    periods = []
    deltas = np.exp(model.base.grid_log0 + model.base.grid_step * np.arange(model.base.tables.shape[1]))
    for c, rows in zip(model.joints, model.contact_rows):
        if c.impact != "continuous":
            continue
        k = rows[0]
        table = model.base.tables[int(model.contacts[k, CONTACT_TABLE])]
        reach = np.isfinite(table) & (deltas <= model.contacts[k, CONTACT_CLEARANCE])
        if reach.any():
            d = deltas[reach][-1]
            stiffness = math.exp(table[reach][-1]) / d
            if int(model.contacts[k, CONTACT_KIND]) == SLICED:   # a per-length law over the bore
                stiffness *= model.contacts[k, layout.CONTACT_LENGTH] * model.contacts[k, layout.CONTACT_SCALE]
            periods.append(2 * math.pi * math.sqrt(reduced(
                model.contacts[k, CONTACT_BEARING_BODY], model.contacts[k, CONTACT_JOURNAL_BODY],
                lambda b: 1 / masses[b]) / stiffness))
    for t, element in zip(model.torsion, model.scene.torsion):   # a row each, in the scene's order
        if t[TORSION_STIFFNESS] > 0:
            periods.append(2 * math.pi * math.sqrt(reduced(
                t[TORSION_BODY_I], t[TORSION_BODY_J], lambda b: geometry.inverse_inertia(b, element))
                / t[TORSION_STIFFNESS]))
    for e in model.base.springs:   # the reduced mass of its bodies along the line
        if e[layout.SPRING_STIFFNESS] > 0:
            periods.append(2 * math.pi * math.sqrt(reduced(
                e[layout.SPRING_BODY_I], e[layout.SPRING_BODY_J], lambda b: 1 / masses[b])
                / e[layout.SPRING_STIFFNESS]))
    periods += [2 * math.pi / f.body.omega[f.n - 1] for f in getattr(geometry, "flexible", {}).values()]
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
    rigid = [c.name for c in model.joints if c.impact != "continuous"]
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

