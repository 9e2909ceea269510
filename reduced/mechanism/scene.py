"""Mechanism scenes, SI units: `kind = "planar"`, a planar mechanism (vectors [x, y], bodies
of mass and inertia, angles in degrees), and `kind = "spatial"`, a spatial one (vectors
[x, y, z], 3 x 3 inertia tensors, orientations as Euler parameters or rotation matrices).
What the two share is written once here: torsion springs, stops and latches, linear
spring-dampers, harmonic loads and a shaken drive, the integrator, the outputs, and the rules
across a scene (names, run size, a periodic forcing). A clearance joint's table is its type's
(reduced.mechanism.joints: the revolute joint, the spatial table of the cylindrical and
spherical ones, the translational joint of both kinds), on the contact laws and materials
they share (reduced.mechanism.joints.contact).

Body positions, angles and velocities are initial guesses for the centres of mass; pinbore
makes them consistent with the joints before integrating (a clearance joint starts closed
unless it starts "placed"). Points and axes of a body are in its own frame (origin at its
centre of mass), those of the ground global. Validating a scene needs neither the compiled
core nor DOLFINx: a bad scene costs a fraction of a second.
"""

import math
from typing import Annotated, ClassVar, Literal

import numpy as np
import pydantic

from pinbore.core.scene import Strict
from pinbore.reduced.mechanism import joints, layout
from pinbore.reduced.mechanism.joints.contact import FILE_LAWS
from pinbore.reduced.mechanism.joints.journal import SpatialClearanceJoint
from pinbore.reduced.mechanism.joints.revolute import ClearanceJoint
from pinbore.reduced.mechanism.joints.translational import translational_joint
from pinbore.reduced.mechanism.vectors import Matrix3, Quaternion, Vector, Vector3, unit_axis

GROUND = "ground"
# What a run may ask for, refused at validation when exceeded: it could not finish (the
# integrator stops at MAX_STEPS; a fixed step needs duration / max_step of them) or would not
# fit in memory (every sample is a row of timeseries.csv).
MAX_STEPS = 5_000_000
MAX_SAMPLES = 2_000_000
# a scene's tables of clearance joints (each a list of its types' scene models), in the order
# of their contacts
CLEARANCE_TABLES = ("clearance_joints", "translational_joints")
UNIT = 1e-9   # how far from unit length (or orthonormal) rotation data may be


def rotation_matrix(p) -> np.ndarray:
    """A(p) of unit Euler parameters p = (e0, e1, e2, e3) ([Nikravesh1988] ch. 6), in the
    operations of the spatial body kind's A(p) in the compiled core (cpp/mechanism/spatial.h),
    so that both give the same numbers."""
    e0, e1, e2, e3 = (float(c) for c in p)
    a = np.array([[e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2],
                  [e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1],
                  [e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5]])
    return a * 2.0


def spring(vector):
    """The linear spring-damper of a planar (`vector` of 2) or spatial (3) scene."""

    class Spring(Strict):
        """A linear spring-damper between point_i of body_i and point_j of body_j (body frames;
        on the ground, global): the tension T = k (L - L0) + c L' pulls the two points
        together along the line between them (L their distance, L0 free_length)."""

        body_i: str
        point_i: vector
        body_j: str
        point_j: vector
        stiffness: float = pydantic.Field(ge=0, description="N/m, k")
        damping: float = pydantic.Field(default=0.0, ge=0, description="N s/m, c")
        free_length: float = pydantic.Field(gt=0, description="m, L0")

    return Spring


def harmonic_load(vector, angular):
    """The harmonic load of a planar (`vector` of 2, a torque about the plane's normal) or
    spatial (3, a torque vector) scene."""

    class HarmonicLoad(Strict):
        """A force F cos(2 pi f t + phase) at `point` of `body` (body frame) and a torque
        T cos(2 pi f t + phase) on the body, the amplitudes F (N) and T (N m) global; several
        loads on one body sum their harmonics. On a flexible body the load acts at its
        interface nearest the point."""

        body: str
        point: vector = [0.0] * (3 if vector is Vector3 else 2)
        force: vector = [0.0] * (3 if vector is Vector3 else 2)
        torque: angular = [0.0, 0.0, 0.0] if vector is Vector3 else 0.0
        frequency_hz: float = pydantic.Field(gt=0, description="Hz, f")
        phase_deg: float = 0.0

        @pydantic.model_validator(mode="after")
        def _acts(self):
            torque = self.torque if isinstance(self.torque, list) else [self.torque]
            if not any(self.force) and not any(torque):
                raise ValueError("force, torque: a load needs a nonzero force or torque amplitude")
            return self

    return HarmonicLoad


class Harmonic(Strict):
    """One harmonic of a shaken drive: A sin(2 pi f t + phase)."""

    amplitude_deg: float = pydantic.Field(gt=0, description="deg, A")
    frequency_hz: float = pydantic.Field(gt=0, description="Hz, f")
    phase_deg: float = 0.0


class Integrator(Strict):
    """dopri5: explicit, adaptive, contact onsets located (the default); rosenbrock23: linearly
    implicit and L-stable (Shampine-Reichelt), for stiff contact laws or springs;
    dopri5_fixed: the step fixed_step throughout, no error control or event location (only for
    comparing against); without fixed_step, 1/300 of the shortest contact or torsion period
    of the scene (reduced.mechanism.model.fixed_step)."""

    method: Literal["dopri5", "rosenbrock23", "dopri5_fixed"] = "dopri5"
    rtol: float = pydantic.Field(default=1e-6, gt=0, lt=1)
    atol: float = pydantic.Field(default=1e-9, gt=0)
    max_step: float = pydantic.Field(default=1e-4, gt=0, description="s, the adaptive methods' bound")
    fixed_step: float | None = pydantic.Field(default=None, gt=0, description="s, dopri5_fixed only")
    baumgarte: float = pydantic.Field(default=50.0, gt=0, description="1/s")

    @pydantic.model_validator(mode="after")
    def _fixed_step(self):
        if self.fixed_step is not None and self.method != "dopri5_fixed":
            raise ValueError(f"fixed_step is used by method = 'dopri5_fixed' only, not {self.method!r}")
        return self


class OutputPoint(Strict):
    """A named point of a body (`position` in the body frame, m, at the centre of mass): its
    global position and its elastic displacement in the body's floating frame (a flexible
    body's; a rigid body's is zero) are columns of the run's time series."""

    name: str = pydantic.Field(pattern=r"^[A-Za-z0-9_]+$")
    body: str
    position: list[float] = pydantic.Field(min_length=2, max_length=3)


class Output(Strict):
    sample_time: float = pydantic.Field(default=2e-5, gt=0, description="s between samples")
    plots: bool = True
    points: list[OutputPoint] = []


def check_fixed_steps(duration: float, step: float) -> None:
    """Refuse a fixed step that needs more than MAX_STEPS steps over the duration."""
    steps = duration / step
    if steps > MAX_STEPS:
        raise ValueError(f"integrator.fixed_step: a fixed step of {step:.3g} s needs {steps:.3g} "
                         f"steps, more than {MAX_STEPS:.0e}: a longer step or a shorter duration")


def check_run_size(scene) -> None:
    """Refuse a run that would not fit in memory (samples) or could not finish (fixed steps)."""
    samples = scene.duration / scene.output.sample_time
    if samples > MAX_SAMPLES:
        raise ValueError(f"output.sample_time: {samples:.3g} samples over the duration, more "
                         f"than {MAX_SAMPLES:.0e}: sample less often or shorten the duration")
    if scene.integrator.fixed_step is not None:
        check_fixed_steps(scene.duration, scene.integrator.fixed_step)


def check_names(scene, used) -> None:
    """Body names unique and not the ground; every (name, key) of `used` a body or the ground;
    clearance and named joints named once each; a laws file where a law needs one."""
    names = [b.name for b in scene.bodies]
    if len(set(names)) != len(names) or GROUND in names:
        raise ValueError(f"bodies: names must be unique and not {GROUND!r}")
    known = set(names) | {GROUND}
    used = list(used) + [(p.body, "output.points.body") for p in scene.output.points]
    points = [(p.body, p.name) for p in scene.output.points]
    if len(set(points)) != len(points):
        raise ValueError("output.points: a body's points must have different names")
    for name, key in used:
        if name not in known:
            raise ValueError(f"{key}: unknown body {name!r}; bodies: {', '.join(sorted(known))}")
        if name == GROUND and key in ("drive.body", "joints.body", "output.points.body", "loads.body"):
            raise ValueError(f"{key}: must be a moving body, not {GROUND!r}")
    joints = [c.name for c in clearance_joints(scene)]
    twice = sorted({n for n in joints if joints.count(n) > 1})
    if twice:
        raise ValueError(f"clearance_joints, translational_joints: names must be unique "
                         f"({', '.join(twice)} given twice): each names its outputs")
    named = [j.name for j in scene.joints if getattr(j, "name", None)]
    twice = sorted({n for n in named if named.count(n) > 1})
    if twice:
        raise ValueError(f"joints: names must be unique ({', '.join(twice)} given twice): a drive "
                         "names the joint it turns")
    laws = [c for c in scene.clearance_joints if c.impact == "continuous"]
    if any(c.normal_law.startswith(FILE_LAWS) for c in laws) and scene.laws_file is None:
        raise ValueError("laws_file is required by a calibrated:<law> or sliced:<law> normal law")
    if any(c.damping_law == "calibrated" for c in laws) and scene.laws_file is None:
        raise ValueError("laws_file is required by damping_law = 'calibrated'")


def clearance_joints(scene) -> list:
    """The scene's clearance joints, table by table (CLEARANCE_TABLES): revolute, cylindrical,
    spherical, then translational."""
    return [c for table in CLEARANCE_TABLES for c in getattr(scene, table)]


def clearance_points(scene) -> list[tuple]:
    """(body, point, key) of the bearing's and the journal's point of every clearance joint."""
    return [found for table in CLEARANCE_TABLES for c in getattr(scene, table)
            for found in ((c.bearing_body, c.bearing_point, f"{table}.bearing_point"),
                          (c.journal_body, c.journal_point, f"{table}.journal_point"))]


def body_references(scene) -> list[tuple[str, str]]:
    """(body name, key) of every body the clearance joints and torsion elements name."""
    used = [(c.bearing_body, f"{table}.bearing_body") for table in CLEARANCE_TABLES
            for c in getattr(scene, table)]
    used += [(c.journal_body, f"{table}.journal_body") for table in CLEARANCE_TABLES
             for c in getattr(scene, table)]
    used += [(t.body_i, "torsion.body_i") for t in scene.torsion]
    used += [(t.body_j, "torsion.body_j") for t in scene.torsion]
    used += [(s.body_i, "springs.body_i") for s in scene.springs]
    used += [(s.body_j, "springs.body_j") for s in scene.springs]
    used += [(load.body, "loads.body") for load in scene.loads]
    return used


FLEXIBLE_MODES = 24   # at most, the modes a flexible body keeps (the body kinds' MODES)


class MaybeFlexible(Strict):
    """What makes a body flexible, for both kinds: modes_file, the reduced body `pinbore
    modes` wrote (body.npz; its mass and inertia come from there, its frame is the mean-axis
    frame at its centre of mass, with the mesh's axes); the first `modes` of its modes (all
    by default), each damped by damping_ratio (one ratio, or one a mode), with the geometric
    stiffening of its spin unless stiffening = false. A joint, drive, spring or contact on a
    flexible body acts on the frame of the body's interface nearest its point. Without
    modes_file the body is rigid and needs its mass and inertia."""

    modes_file: str | None = None
    modes: int | None = pydantic.Field(default=None, ge=1, le=FLEXIBLE_MODES)
    damping_ratio: float | list[Annotated[float, pydantic.Field(ge=0)]] = pydantic.Field(default=0.0)
    stiffening: bool = True

    @pydantic.model_validator(mode="after")
    def _rigid_or_flexible(self):
        if self.modes_file is None:
            for key in ("mass", "inertia"):
                if getattr(self, key) is None:
                    raise ValueError(f"{key}: a rigid body needs its {key} (or a flexible body its "
                                     "modes_file)")
            if self.modes is not None or self.damping_ratio != 0.0 or not self.stiffening:
                raise ValueError("modes, damping_ratio, stiffening: for a flexible body, with its "
                                 "modes_file")
            return self
        for key in ("mass", "inertia"):
            if getattr(self, key) is not None:
                raise ValueError(f"{key}: a flexible body's {key} comes from its modes_file; "
                                 "leave it out")
        ratios = self.damping_ratio if isinstance(self.damping_ratio, list) else [self.damping_ratio]
        if any(r < 0 or not math.isfinite(r) for r in ratios):
            raise ValueError("damping_ratio: must be >= 0 (a ratio of critical damping)")
        if isinstance(self.damping_ratio, list) and self.modes is not None \
                and len(self.damping_ratio) != self.modes:
            raise ValueError(f"damping_ratio: one ratio or one a mode ({self.modes} modes), "
                             f"not {len(self.damping_ratio)}")
        return self

    @property
    def flexible(self) -> bool:
        return self.modes_file is not None


# ---- planar scenes (kind = "planar")
class Body(MaybeFlexible):
    """A rigid body (mass, inertia) or a flexible one (MaybeFlexible)."""

    name: str
    mass: float | None = pydantic.Field(default=None, gt=0, description="kg")
    inertia: float | None = pydantic.Field(default=None, gt=0, description="kg m^2 about the centre of mass")
    position: Vector = [0.0, 0.0]
    angle_deg: float = 0.0
    velocity: Vector = [0.0, 0.0]
    omega: float = 0.0


class Revolute(Strict):
    """Ideal pin between point_i of body_i and point_j of body_j (points in body frames;
    on the ground, in the global frame)."""

    type: Literal["revolute"]
    body_i: str
    point_i: Vector
    body_j: str
    point_j: Vector

    guides_a_slider: ClassVar[bool] = False   # a pin, not a slider's guide

    @property
    def linked(self) -> tuple[str, str]:
        """The two bodies the joint links."""
        return self.body_i, self.body_j


class Prismatic(Strict):
    """The body slides along a fixed line through axis_point with direction axis_deg,
    without rotating; `point` (body frame) stays on the line."""

    type: Literal["prismatic"]
    body: str
    point: Vector = [0.0, 0.0]
    axis_point: Vector = [0.0, 0.0]
    axis_deg: float = 0.0

    guides_a_slider: ClassVar[bool] = True   # the body slides along its line

    @property
    def linked(self) -> tuple[str, str]:
        """The two bodies the joint links: the slider and the ground, its guide."""
        return self.body, GROUND


class DriveProfile(Strict):
    """How a drive's angle runs from its start, theta(t): at the constant speed speed_rpm
    (theta = omega t); reaching speed_rpm by the smooth spin-up over spin_up_s (spin_up_angle,
    then constant); or through the table angle_table of (time (s), angle (deg)) pairs from
    time 0, a cubic spline through them (rate and acceleration continuous, a motion cubic in
    time followed exactly; after the last pair the angle runs on at its last rate: its
    acceleration steps to zero there), theta measured from the table's first angle; or shaken,
    the support's harmonic motion theta = sum A (sin(2 pi f t + phase) - sin(phase)) of the
    `harmonics` (base excitation: a bus's attitude oscillation, a rotary shaker)."""

    speed_rpm: float | None = None
    spin_up_s: float | None = pydantic.Field(default=None, gt=0)
    angle_table: list[Annotated[list[float], pydantic.Field(min_length=2, max_length=2)]] | None = None
    harmonics: list[Harmonic] | None = pydantic.Field(default=None, min_length=1)

    @pydantic.model_validator(mode="after")
    def _profile(self):
        given = [self.speed_rpm is not None, self.angle_table is not None, self.harmonics is not None]
        if sum(given) != 1:
            raise ValueError("give speed_rpm (constant, or reached by spin_up_s), angle_table or "
                             "harmonics, one of them")
        if self.spin_up_s is not None and self.speed_rpm is None:
            raise ValueError("spin_up_s: the spin-up reaches speed_rpm: give it")
        table = self.angle_table
        if table is not None:
            times = [t for t, _ in table]
            if len(table) < 2 or table[0] != [0.0, 0.0]:
                raise ValueError("angle_table: at least two (time (s), angle (deg)) pairs, the "
                                 "first (0, 0): angles from the drive's start")
            if any(b <= a for a, b in zip(times, times[1:])):
                raise ValueError("angle_table: the times must increase strictly")
        return self

    @property
    def speed(self) -> float:
        """The constant speed, or the one the spin-up reaches (rad/s); 0 for a table."""
        return 0.0 if self.speed_rpm is None else self.speed_rpm * 2 * math.pi / 60

    def profile_columns(self) -> dict:
        """The drive primitive's profile columns (layout.PRIM_PROFILE...): a table's segments
        are rows 0 .. n - 1 of Args.profile (reduced.mechanism.model.drive_segments: one a
        pair, the last running on)."""
        if self.angle_table is not None:
            return {layout.PRIM_PROFILE: layout.TABLE, layout.PRIM_PROFILE_TIME: 0,
                    layout.PRIM_PROFILE_ROWS: len(self.angle_table)}
        if self.harmonics is not None:
            return {layout.PRIM_PROFILE: layout.HARMONIC, layout.PRIM_PROFILE_TIME: 0,
                    layout.PRIM_PROFILE_ROWS: len(self.harmonics)}
        if self.spin_up_s is not None:
            return {layout.PRIM_PROFILE: layout.SPIN_UP, layout.PRIM_PROFILE_TIME: self.spin_up_s}
        return {layout.PRIM_PROFILE: layout.CONSTANT_SPEED}

    @property
    def constant(self) -> bool:
        """A drive at constant speed from the start (what a Poincare section per revolution
        needs)."""
        return self.speed_rpm is not None and self.spin_up_s is None


class Drive(DriveProfile):
    """A body's angle driven: angle = angle0 + theta(t) (DriveProfile); on a flexible body, the
    angle of its frame at `point` (body frame; default: its first interface), the hub a
    flexible appendage is clamped to."""

    body: str
    angle0_deg: float = 0.0
    point: Vector | None = None


class TorsionSpring(Strict):
    """A torque between two bodies on their relative angle phi = phi_j - phi_i (deg from the
    initial configuration): spring  T = -k (phi - free_angle) - c phi'  on body j (and -T on
    i); stop: the same only while phi > free_angle, and never pulling; latch: nothing until
    phi first passes free_angle, then the spring-damper both ways (a catch that holds)."""

    type: Literal["spring", "stop", "latch"]
    body_i: str
    body_j: str
    stiffness: float = pydantic.Field(ge=0, description="N m / rad")
    damping: float = pydantic.Field(default=0.0, ge=0, description="N m s / rad")
    free_angle_deg: float = 0.0
    # on a flexible body: the point (body frame) whose interface frame the element turns
    # (default: the body's first interface)
    point_i: Vector | None = None
    point_j: Vector | None = None


TranslationalJoint = translational_joint(Vector)
Spring = spring(Vector)
Load = harmonic_load(Vector, float)


class MechanismScene(Strict):
    """What a mechanism scene of every kind has: its duration, laws file, integrator and
    outputs (a kind's scene adds its bodies, joints, drive, clearance joints, torsion)."""

    duration: float = pydantic.Field(gt=0)
    laws_file: str | None = None
    integrator: Integrator = Integrator()
    output: Output = Output()

    @pydantic.model_validator(mode="after")
    def _bounded(self):
        check_run_size(self)
        return self

    def excitation_frequencies(self) -> list[float]:
        """The frequencies (Hz) of the harmonic loads and of a shaken drive's harmonics."""
        shaken = self.drive.harmonics if self.drive is not None and self.drive.harmonics else []
        return [e.frequency_hz for e in self.loads] + [h.frequency_hz for h in shaken]

    def forcing_period(self) -> float:
        """The period (s) of the mechanism's forcing, what a periodic analysis samples once a
        period: a drive at constant speed turns once in it, and every harmonic load and
        shaken drive's harmonic repeats a whole number of times in it; without a drive, the
        period of the lowest excitation frequency. ValueError with the rule when the forcing
        is not periodic (none, a spin-up or an angle table, a drive standing still, or
        frequencies that are not whole multiples of the fundamental)."""
        frequencies = self.excitation_frequencies()
        drive = self.drive
        if drive is not None and drive.harmonics is None:
            if not drive.constant:
                raise ValueError("drive: a periodic analysis needs a drive at constant speed or "
                                 "shaken (a spin-up or an angle table gives the motion no period)")
            if drive.speed_rpm == 0:
                raise ValueError("drive.speed_rpm: must not be 0 for a periodic analysis (a drive "
                                 "that stands still has no revolution to sample)")
            fundamental = abs(drive.speed_rpm) / 60.0
        elif frequencies:
            fundamental = min(frequencies)
        else:
            raise ValueError("a periodic analysis needs a periodic forcing: a drive at constant "
                             "speed, a shaken drive (drive.harmonics) or harmonic loads (loads)")
        for f in frequencies:
            ratio = f / fundamental
            if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
                raise ValueError(f"loads, drive.harmonics: frequency {f:g} Hz is not a whole "
                                 f"multiple of the forcing's fundamental {fundamental:g} Hz: the "
                                 "motion has no common period")
        return 1.0 / fundamental


class PlanarScene(MechanismScene):
    kind: Literal["planar"]
    gravity: Vector = [0.0, 0.0]
    bodies: list[Body] = pydantic.Field(min_length=1)
    joints: list[Revolute | Prismatic] = []
    drive: Drive | None = None
    clearance_joints: list[ClearanceJoint] = []
    translational_joints: list[TranslationalJoint] = []
    torsion: list[TorsionSpring] = []
    springs: list[Spring] = []
    loads: list[Load] = []

    @pydantic.model_validator(mode="after")
    def _names(self):
        pins = [j for j in self.joints if not j.guides_a_slider]
        used = [(j.body_i, "joints.body_i") for j in pins]
        used += [(j.body_j, "joints.body_j") for j in pins]
        used += [(j.body, "joints.body") for j in self.joints if j.guides_a_slider]
        used += body_references(self)
        if self.drive:
            used.append((self.drive.body, "drive.body"))
        check_names(self, used)
        return self


# ---- spatial scenes (kind = "spatial")
class SpatialBody(MaybeFlexible):
    """A body in space, rigid or flexible (MaybeFlexible). Orientation: `orientation` (Euler
    parameters [e0, e1, e2, e3], unit) or `rotation` (a 3 x 3 rotation matrix, rows), one or
    neither (identity). Inertia of a rigid body: the 3 x 3 tensor about the centre of mass in
    the body frame (symmetric, positive definite, its principal moments obeying the triangle
    inequality J1 + J2 >= J3)."""

    name: str
    mass: float | None = pydantic.Field(default=None, gt=0, description="kg")
    inertia: Matrix3 | None = pydantic.Field(default=None, description="kg m^2, about the centre of mass, body frame")
    position: Vector3 = [0.0, 0.0, 0.0]
    orientation: Quaternion | None = None
    rotation: Matrix3 | None = None
    velocity: Vector3 = [0.0, 0.0, 0.0]
    omega: Vector3 = pydantic.Field(default=[0.0, 0.0, 0.0], description="rad/s, global frame")

    @pydantic.model_validator(mode="after")
    def _physical(self):
        if self.inertia is None:   # a flexible body's, from its modes file
            return self._orientation()
        j = np.array(self.inertia)
        if not np.allclose(j, j.T, rtol=0, atol=1e-12 * max(np.abs(j).max(), 1e-300)):
            raise ValueError("inertia: the tensor must be symmetric")
        moments = np.linalg.eigvalsh(j)
        if moments[0] <= 0:
            raise ValueError(f"inertia: the tensor must be positive definite (principal moments "
                             f"{', '.join(f'{m:.3g}' for m in moments)})")
        if moments[0] + moments[1] < moments[2] * (1 - 1e-9):
            raise ValueError(f"inertia: principal moments {', '.join(f'{m:.3g}' for m in moments)} "
                             "break the triangle inequality J1 + J2 >= J3 (no rigid body has them)")
        return self._orientation()

    def _orientation(self):
        if self.orientation is not None and self.rotation is not None:
            raise ValueError("orientation and rotation: give one of them")
        if self.orientation is not None:
            norm = math.sqrt(sum(c * c for c in self.orientation))
            if abs(norm - 1) > UNIT:
                raise ValueError(f"orientation: Euler parameters must have unit length (|p| = {norm:.12g})")
        if self.rotation is not None:
            a = np.array(self.rotation)
            if np.abs(a @ a.T - np.eye(3)).max() > UNIT or np.linalg.det(a) < 0:
                raise ValueError("rotation: must be a rotation matrix (orthonormal rows, "
                                 "determinant +1)")
        return self

    def parameters(self) -> list[float]:
        """Euler parameters of the initial orientation."""
        if self.orientation is not None:
            return list(self.orientation)
        if self.rotation is None:
            return [1.0, 0.0, 0.0, 0.0]
        a = np.array(self.rotation)
        # the largest of the four squares first (numerically safe; [Nikravesh1988] sec. 6.3)
        squares = [(1 + np.trace(a)) / 4, (1 + 2 * a[0, 0] - np.trace(a)) / 4,
                   (1 + 2 * a[1, 1] - np.trace(a)) / 4, (1 + 2 * a[2, 2] - np.trace(a)) / 4]
        k = int(np.argmax(squares))
        e = [0.0] * 4
        e[k] = math.sqrt(squares[k])
        pairs = {0: (a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]),
                 1: (a[2, 1] - a[1, 2], a[1, 0] + a[0, 1], a[0, 2] + a[2, 0]),
                 2: (a[0, 2] - a[2, 0], a[1, 0] + a[0, 1], a[2, 1] + a[1, 2]),
                 3: (a[1, 0] - a[0, 1], a[0, 2] + a[2, 0], a[2, 1] + a[1, 2])}
        others = [i for i in range(4) if i != k]
        for i, value in zip(others, pairs[k]):
            e[i] = value / (4 * e[k])
        return e


class Joint(Strict):
    """An ideal joint between body_i and body_j at point_i = point_j (at the start), axes
    axis_i, axis_j (revolute, cylindrical, prismatic: the joint axis; universal: the two cross
    arms, normal to each other; spherical and fixed take none)."""

    name: str | None = None
    type: Literal["spherical", "revolute", "cylindrical", "prismatic", "universal", "fixed"]
    body_i: str
    point_i: Vector3
    axis_i: Vector3 | None = None
    body_j: str
    point_j: Vector3
    axis_j: Vector3 | None = None

    @pydantic.model_validator(mode="after")
    def _axes(self):
        needs = self.type in ("revolute", "cylindrical", "prismatic", "universal")
        if needs and (self.axis_i is None or self.axis_j is None):
            raise ValueError(f"axis_i and axis_j are required by a {self.type} joint")
        if not needs and (self.axis_i is not None or self.axis_j is not None):
            raise ValueError(f"a {self.type} joint takes no axes")
        if needs:
            unit_axis(self.axis_i, "axis_i")
            unit_axis(self.axis_j, "axis_j")
        return self

    @property
    def guides_a_slider(self) -> bool:
        """A prismatic joint: body_j slides along body_i's axis."""
        return self.type == "prismatic"

    @property
    def turns(self) -> bool:
        """A revolute or cylindrical joint: a drive may turn its bodies about its axis."""
        return self.type in ("revolute", "cylindrical")

    @property
    def linked(self) -> tuple[str, str]:
        """The two bodies the joint links."""
        return self.body_i, self.body_j


class SpatialDrive(DriveProfile):
    """The relative angle of a revolute or cylindrical joint's bodies about its axis driven
    from its initial value: angle = theta(t) (DriveProfile)."""

    joint: str


class Torsion(Strict):
    """A torque about axis_i (body i's frame) on the relative angle of body j about it,
    measured from the initial configuration: spring, stop or latch as in the planar scene
    (TorsionSpring)."""

    type: Literal["spring", "stop", "latch"]
    body_i: str
    body_j: str
    axis_i: Vector3
    stiffness: float = pydantic.Field(ge=0, description="N m / rad")
    damping: float = pydantic.Field(default=0.0, ge=0, description="N m s / rad")
    free_angle_deg: float = 0.0
    # on a flexible body: the point (body frame) whose interface frame the element turns
    # (default: the body's first interface)
    point_i: Vector3 | None = None
    point_j: Vector3 | None = None

    @pydantic.model_validator(mode="after")
    def _axis(self):
        unit_axis(self.axis_i, "axis_i")
        return self


SpatialTranslationalJoint = translational_joint(Vector3)
SpatialSpring = spring(Vector3)
SpatialLoad = harmonic_load(Vector3, Vector3)


class SpatialScene(MechanismScene):
    kind: Literal["spatial"]
    gravity: Vector3 = [0.0, 0.0, 0.0]
    bodies: list[SpatialBody] = pydantic.Field(min_length=1)
    joints: list[Joint] = []
    drive: SpatialDrive | None = None
    clearance_joints: list[SpatialClearanceJoint] = []
    translational_joints: list[SpatialTranslationalJoint] = []
    torsion: list[Torsion] = []
    springs: list[SpatialSpring] = []
    loads: list[SpatialLoad] = []

    @pydantic.model_validator(mode="after")
    def _journals_fit(self):
        """Every clearance joint that starts closed fits where its bodies' initial orientations
        put it (its type's `fits`: a journal tilted against its bore must fit its clearance)."""
        bodies = {b.name: b for b in self.bodies}
        for k, c in enumerate(self.clearance_joints):
            if c.start == "placed" or c.bearing_body not in bodies | {GROUND: None} or \
                    c.journal_body not in bodies | {GROUND: None}:
                continue   # unknown bodies: _names says so
            rotations = {name: np.eye(3) if name == GROUND else rotation_matrix(bodies[name].parameters())
                         for name in (c.bearing_body, c.journal_body)}
            joints.of(c).fits(f"clearance_joints.{k}", rotations)
        return self

    @pydantic.model_validator(mode="after")
    def _names(self):
        used = [(j.body_i, "joints.body_i") for j in self.joints]
        used += [(j.body_j, "joints.body_j") for j in self.joints]
        used += body_references(self)
        check_names(self, used)
        if self.drive is not None:
            driven = {j.name: j for j in self.joints if j.name}
            if self.drive.joint not in driven:
                raise ValueError(f"drive.joint: unknown joint {self.drive.joint!r}; named joints: "
                                 f"{', '.join(sorted(driven)) or 'none'}")
            if not driven[self.drive.joint].turns:
                raise ValueError("drive.joint: must be a revolute or cylindrical joint (it turns "
                                 "about the joint's axis)")
        return self
