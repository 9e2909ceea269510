"""The reduced (multibody) scene, `kind = "reduced"`: planar rigid bodies, ideal joints, a
drive, revolute clearance joints, the integrator and what to write. SI units.

Body positions, angles and velocities are initial guesses for the centres of mass; pinbore
makes them consistent with the joints (the clearance joints start centred: positions closed,
velocities free) before integrating.
"""

from typing import Annotated, Literal

import pydantic

from laws.dissipative import HYSTERESIS
from laws.elastic import PUBLISHED
from pinbore.scene import Strict

GROUND = "ground"
ELASTIC_LAWS = ["hertz_point"] + sorted(PUBLISHED)
DAMPING_LAWS = ["none"] + sorted(HYSTERESIS)
FRICTION_LAWS = ["none", "coulomb_ambrosio"]

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


class ClearanceJoint(Strict):
    """A revolute joint with radial clearance: the journal (on journal_body) moves freely
    inside the bearing (on bearing_body) and meets its wall through the contact laws."""

    name: str
    bearing_body: str
    bearing_point: Vector
    journal_body: str
    journal_point: Vector
    bearing_radius: float = pydantic.Field(gt=0)
    journal_radius: float = pydantic.Field(gt=0)
    length: float | None = pydantic.Field(default=None, gt=0,
                                          description="axial length (m): per-length laws x L")
    E: float = pydantic.Field(gt=0)
    nu: float = pydantic.Field(gt=-1, lt=0.5)
    normal_law: str
    damping_law: str = "none"
    restitution: float = pydantic.Field(default=1.0, gt=0, le=1)
    friction_law: str = "none"
    friction_coefficient: float = pydantic.Field(default=0.0, ge=0)
    friction_v0: float = pydantic.Field(default=1e-4, gt=0, description="m/s, Ambrosio")
    friction_v1: float = pydantic.Field(default=1e-3, gt=0, description="m/s, Ambrosio")
    start: Literal["ideal", "free"] = "ideal"  # centred; moving with the ideal joint, or free

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.journal_radius >= self.bearing_radius:
            raise ValueError("journal_radius must be smaller than bearing_radius (clearance > 0)")
        if not (self.normal_law in ELASTIC_LAWS or self.normal_law.startswith("calibrated:")):
            raise ValueError(f"normal_law {self.normal_law!r} is unknown; valid: "
                             f"{', '.join(ELASTIC_LAWS)}, calibrated:<law in laws.json>")
        if self.normal_law != "hertz_point" and self.length is None:
            raise ValueError(f"length is required by normal_law {self.normal_law!r} (a force per "
                             "unit length)")
        if self.damping_law not in DAMPING_LAWS:
            raise ValueError(f"damping_law {self.damping_law!r} is unknown; valid: "
                             f"{', '.join(DAMPING_LAWS)}")
        if self.friction_law not in FRICTION_LAWS:
            raise ValueError(f"friction_law {self.friction_law!r} is unknown; valid: "
                             f"{', '.join(FRICTION_LAWS)}")
        if self.friction_v1 <= self.friction_v0:
            raise ValueError("friction_v1 must exceed friction_v0")
        return self


class Integrator(Strict):
    method: Literal["dopri5"] = "dopri5"
    rtol: float = pydantic.Field(default=1e-6, gt=0, lt=1)
    atol: float = pydantic.Field(default=1e-9, gt=0)
    max_step: float = pydantic.Field(default=1e-4, gt=0)
    baumgarte: float = pydantic.Field(default=50.0, gt=0, description="1/s")


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
    integrator: Integrator = Integrator()
    output: Output = Output()

    @pydantic.model_validator(mode="after")
    def _names(self):
        names = [b.name for b in self.bodies]
        if len(set(names)) != len(names) or GROUND in names:
            raise ValueError(f"bodies: names must be unique and not {GROUND!r}")
        known = set(names) | {GROUND}
        used = [(j.body_i, "joints.body_i") for j in self.joints if j.type == "revolute"]
        used += [(j.body_j, "joints.body_j") for j in self.joints if j.type == "revolute"]
        used += [(j.body, "joints.body") for j in self.joints if j.type == "prismatic"]
        used += [(c.bearing_body, "clearance_joints.bearing_body") for c in self.clearance_joints]
        used += [(c.journal_body, "clearance_joints.journal_body") for c in self.clearance_joints]
        if self.drive:
            used.append((self.drive.body, "drive.body"))
        for name, key in used:
            if name not in known:
                raise ValueError(f"{key}: unknown body {name!r}; bodies: {', '.join(sorted(known))}")
        if any(c.normal_law.startswith("calibrated:") for c in self.clearance_joints) \
                and self.laws_file is None:
            raise ValueError("laws_file is required by a calibrated:<law> normal law")
        return self
