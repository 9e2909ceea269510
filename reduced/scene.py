"""The reduced (multibody) scene, `kind = "reduced"`: planar rigid bodies, ideal joints, a
drive, revolute clearance joints, the integrator and what to write. SI units.

Body positions, angles and velocities are initial guesses for the centres of mass; pinbore
makes them consistent with the joints (the clearance joints start centred: positions closed,
velocities free) before integrating.
"""

from typing import Annotated, Literal

import pydantic

from pinbore.core.scene import Strict
from pinbore.laws.dissipative import HYSTERESIS
from pinbore.laws import elastic
from pinbore.laws.elastic import PUBLISHED

GROUND = "ground"
# What a run may ask for, refused at validation when exceeded: it could not finish (the
# integrator stops at MAX_STEPS; a fixed step needs duration / max_step of them) or would not
# fit in memory (every sample is a row of timeseries.csv).
MAX_STEPS = 5_000_000
MAX_SAMPLES = 2_000_000
ELASTIC_LAWS = ["hertz_point"] + sorted(PUBLISHED)
DAMPING_LAWS = ["none"] + sorted(HYSTERESIS) + ["calibrated"]   # calibrated: laws file

Vector = Annotated[list[float], pydantic.Field(min_length=2, max_length=2)]


class Body(Strict):
    name: str
    mass: float = pydantic.Field(gt=0, description="kg")
    inertia: float = pydantic.Field(gt=0, description="kg m^2 about the centre of mass")
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


class Prismatic(Strict):
    """The body slides along a fixed line through axis_point with direction axis_deg,
    without rotating; `point` (body frame) stays on the line."""

    type: Literal["prismatic"]
    body: str
    point: Vector = [0.0, 0.0]
    axis_point: Vector = [0.0, 0.0]
    axis_deg: float = 0.0


class Drive(Strict):
    """Constant angular speed of a body: angle = angle0 + omega t."""

    body: str
    speed_rpm: float
    angle0_deg: float = 0.0


class Regularised(Strict):
    """Below v0 the friction force vanishes, between v0 and v1 it grows linearly to its full
    value [Ambrosio2003]: the static laws need it to be continuous at zero slip."""

    v0: float = pydantic.Field(default=1e-4, gt=0, description="m/s")
    v1: float = pydantic.Field(default=1e-3, gt=0, description="m/s")

    @pydantic.model_validator(mode="after")
    def _speeds(self):
        if self.v1 <= self.v0:
            raise ValueError("v1 must exceed v0")
        return self


class CoulombFriction(Regularised):
    """F_t = mu c_d(|v|) F_n (Ambrosio's regularised Coulomb)."""

    law: Literal["coulomb_ambrosio"]
    mu: float = pydantic.Field(ge=0)


class StribeckFriction(Regularised):
    """Polynomial Stribeck ([ThomsenFidlin2003]; [Cao2013] eq. 14): mu_static at rest, mu_min at |v| = v_min."""

    law: Literal["stribeck"]
    mu_static: float = pydantic.Field(ge=0)
    mu_min: float = pydantic.Field(ge=0)
    v_min: float = pydantic.Field(gt=0, description="m/s")


class LinearFriction(Regularised):
    """mu = mu_static + alpha |v| ([Cao2013] eq. 15)."""

    law: Literal["linear"]
    mu_static: float = pydantic.Field(ge=0)
    alpha: float = pydantic.Field(ge=0, description="s/m")


class LuGreFriction(Strict):
    """LuGre normalised by the normal force: F_t = F_n (sigma0 z + sigma1 z' + sigma2 v),
    z' = v - sigma0 |v| z / g(v), g = mu_coulomb + (mu_static - mu_coulomb) exp(-(v/v_s)^2).
    Both coefficients > 0 (g divides the bristle rate); a joint without friction has no
    friction table."""

    law: Literal["lugre"]
    mu_coulomb: float = pydantic.Field(gt=0)
    mu_static: float = pydantic.Field(gt=0)
    stribeck_speed: float = pydantic.Field(gt=0, description="m/s")
    sigma0: float = pydantic.Field(gt=0, description="1/m")
    sigma1: float = pydantic.Field(default=0.0, ge=0, description="s/m")
    sigma2: float = pydantic.Field(default=0.0, ge=0, description="s/m")


class DahlFriction(Strict):
    """Dahl ([Dahl1976]; [Cao2013] eq. 16, alpha = 1) normalised by the normal force: F_t = F_n m,
    m' = sigma (1 - (m / mu) sgn v) v."""

    law: Literal["dahl"]
    mu: float = pydantic.Field(gt=0)
    sigma: float = pydantic.Field(gt=0, description="1/m")


class IwanFriction(Strict):
    """Bilinear Iwan element ([Iwan1966]; [Cao2013] eq. 13) along the contact: a spring k1 in series with a
    Coulomb slider of strength mu F_n, in parallel with a spring k2; it starts unloaded at
    every new contact. For joints that oscillate rather than turn (k2 resists travel)."""

    law: Literal["iwan_bilinear"]
    mu: float = pydantic.Field(ge=0)
    k1: float = pydantic.Field(gt=0, description="N/m")
    k2: float = pydantic.Field(default=0.0, ge=0, description="N/m")


Friction = Annotated[CoulombFriction | StribeckFriction | LinearFriction | LuGreFriction
                     | DahlFriction | IwanFriction, pydantic.Field(discriminator="law")]


FILE_LAWS = ("calibrated:", "sliced:")   # normal laws read from the scene's laws file


class JointMaterials(Strict):
    """The radii and elastic constants of a clearance joint, planar or spatial: what its
    elastic law and its calibrated restitution (damping_law = "calibrated", matched on these
    in the laws file) are chosen by."""

    bearing_radius: float = pydantic.Field(gt=0)
    journal_radius: float = pydantic.Field(gt=0)
    length: float | None = pydantic.Field(default=None, gt=0,
                                          description="axial length (m): per-length laws x L")
    E: float = pydantic.Field(gt=0, description="Pa, the journal's (and the bearing's unless "
                                               "bearing_E is given)")
    nu: float = pydantic.Field(gt=-1, lt=0.5)
    bearing_E: float | None = pydantic.Field(default=None, gt=0, description="Pa; default E")
    bearing_nu: float | None = pydantic.Field(default=None, gt=-1, lt=0.5, description="default nu")

    def elastic_joint(self) -> elastic.Joint:
        """The joint of the elastic laws: radii, the bearing's and the journal's E and nu."""
        return elastic.Joint(self.bearing_radius, self.journal_radius,
                             self.E if self.bearing_E is None else self.bearing_E,
                             self.nu if self.bearing_nu is None else self.bearing_nu,
                             self.E, self.nu, self.length)


class ClearanceJoint(JointMaterials):
    """A revolute joint with radial clearance: the journal (on journal_body) moves freely
    inside the bearing (on bearing_body) and meets its wall through the contact laws."""

    name: str
    bearing_body: str
    bearing_point: Vector
    journal_body: str
    journal_point: Vector
    normal_law: str | None = None
    damping_law: str = "none"
    restitution: float = pydantic.Field(default=1.0, ge=0, le=1)
    friction: Friction | None = None
    # ideal: centred, moving with the ideal joint; free: centred, velocities as given;
    # placed: where the bodies' positions put it, velocities as given
    start: Literal["ideal", "free", "placed"] = "ideal"
    # "continuous": the normal and damping laws act while the journal penetrates;
    # "newton" / "poisson": rigid impacts with restitution `restitution`, and below
    # rest_speed (approach rate x restitution) the contact is held until it would pull
    impact: Literal["continuous", "newton", "poisson"] = "continuous"
    rest_speed: float = pydantic.Field(default=1e-3, gt=0, description="m/s")

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.journal_radius >= self.bearing_radius:
            raise ValueError("journal_radius must be smaller than bearing_radius (clearance > 0)")
        if self.impact != "continuous":
            if self.friction is not None or self.normal_law is not None or self.damping_law != "none":
                raise ValueError(f"impact = {self.impact!r} is a rigid, frictionless impact model: "
                                 "give no normal_law, damping_law or friction")
            return self
        if self.normal_law is None:
            raise ValueError("normal_law is required by impact = 'continuous'")
        if self.restitution == 0 and self.damping_law not in ("none", "calibrated"):
            raise ValueError("restitution must be > 0 for a continuous damping law")
        if not (self.normal_law in ELASTIC_LAWS or self.normal_law.startswith(FILE_LAWS)):
            raise ValueError(f"normal_law {self.normal_law!r} is unknown; valid: "
                             f"{', '.join(ELASTIC_LAWS)}, calibrated:<law in laws.json>, "
                             "sliced:<3D law in laws.json>")
        if self.normal_law != "hertz_point" and self.length is None:
            raise ValueError(f"length is required by normal_law {self.normal_law!r} (a force per "
                             "unit length)")
        if self.damping_law not in DAMPING_LAWS:
            raise ValueError(f"damping_law {self.damping_law!r} is unknown; valid: "
                             f"{', '.join(DAMPING_LAWS)}")
        return self


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


def check_body_names(scene, used) -> None:
    """Body names unique and not the ground; every (name, key) of `used` a body or the ground;
    a laws file where a normal law needs one."""
    names = [b.name for b in scene.bodies]
    if len(set(names)) != len(names) or GROUND in names:
        raise ValueError(f"bodies: names must be unique and not {GROUND!r}")
    known = set(names) | {GROUND}
    for name, key in used:
        if name not in known:
            raise ValueError(f"{key}: unknown body {name!r}; bodies: {', '.join(sorted(known))}")
        if name == GROUND and key in ("drive.body", "joints.body"):
            raise ValueError(f"{key}: must be a moving body, not {GROUND!r}")
    if any((c.normal_law or "").startswith(FILE_LAWS) for c in scene.clearance_joints) \
            and scene.laws_file is None:
        raise ValueError("laws_file is required by a calibrated:<law> or sliced:<law> normal law")
    if any(c.damping_law == "calibrated" for c in scene.clearance_joints) and scene.laws_file is None:
        raise ValueError("laws_file is required by damping_law = 'calibrated'")


class Integrator(Strict):
    """dopri5: explicit, adaptive, contact onsets located (the default); rosenbrock23: linearly
    implicit and L-stable (Shampine-Reichelt), for stiff contact laws or springs;
    dopri5_fixed: the step fixed_step throughout, no error control or event location (only for
    comparing against); without fixed_step, 1/300 of the shortest contact or torsion period
    of the scene (reduced.model.fixed_step)."""

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


class Output(Strict):
    sample_time: float = pydantic.Field(default=2e-5, gt=0, description="s between samples")
    plots: bool = True


class ReducedScene(Strict):
    kind: Literal["reduced"]
    duration: float = pydantic.Field(gt=0)
    gravity: Vector = [0.0, 0.0]
    laws_file: str | None = None
    bodies: list[Body] = pydantic.Field(min_length=1)
    joints: list[Revolute | Prismatic] = []
    drive: Drive | None = None
    clearance_joints: list[ClearanceJoint] = []
    torsion: list[TorsionSpring] = []
    integrator: Integrator = Integrator()
    output: Output = Output()

    @pydantic.model_validator(mode="after")
    def _bounded(self):
        check_run_size(self)
        return self

    @pydantic.model_validator(mode="after")
    def _names(self):
        used = [(j.body_i, "joints.body_i") for j in self.joints if j.type == "revolute"]
        used += [(j.body_j, "joints.body_j") for j in self.joints if j.type == "revolute"]
        used += [(j.body, "joints.body") for j in self.joints if j.type == "prismatic"]
        used += [(c.bearing_body, "clearance_joints.bearing_body") for c in self.clearance_joints]
        used += [(c.journal_body, "clearance_joints.journal_body") for c in self.clearance_joints]
        used += [(t.body_i, "torsion.body_i") for t in self.torsion]
        used += [(t.body_j, "torsion.body_j") for t in self.torsion]
        if self.drive:
            used.append((self.drive.body, "drive.body"))
        check_body_names(self, used)
        return self
