"""The spatial multibody scene, `kind = "spatial"`: rigid bodies in 3D, ideal joints, a drive,
cylindrical and spherical clearance joints, torsion elements, the integrator and what to
write. SI units; vectors are [x, y, z]; points and axes of a body are in its own frame (the
frame of its principal or any axes, origin at the centre of mass), those of the ground global.

Orientation: `orientation` (Euler parameters [e0, e1, e2, e3], unit) or `rotation` (a 3 x 3
rotation matrix, rows), one or neither (identity). Inertia: `inertia`, the 3 x 3 tensor about
the centre of mass in the body frame (symmetric, positive definite, its principal moments
obeying the triangle inequality J1 + J2 >= J3). Positions and velocities are initial guesses
that pinbore makes consistent with the joints, as in the planar model.
"""

import math
from typing import Annotated, Literal

import numpy as np
import pydantic

from pinbore.core.scene import Strict
from pinbore.reduced.scene import (DAMPING_LAWS, ELASTIC_LAWS, FILE_LAWS, GROUND,
                                   CoulombFriction, Integrator, JointMaterials, LinearFriction,
                                   Output, StribeckFriction, check_body_names, check_run_size)

Vector3 = Annotated[list[float], pydantic.Field(min_length=3, max_length=3)]
Quaternion = Annotated[list[float], pydantic.Field(min_length=4, max_length=4)]
Matrix3 = Annotated[list[Vector3], pydantic.Field(min_length=3, max_length=3)]
UNIT = 1e-9   # how far from unit length (or orthonormal) rotation data may be


def unit_axis(v, key):
    """v (a nonzero axis) normalised; one rule line otherwise."""
    n = math.sqrt(sum(c * c for c in v))
    if n == 0:
        raise ValueError(f"{key}: an axis must have nonzero length")
    return [c / n for c in v]


def rotation_matrix(p) -> np.ndarray:
    """A(p) of unit Euler parameters p (the spatial kernel's, reduced.spatial_kernel.rotation)."""
    from pinbore.reduced import spatial_kernel   # compiled: loaded when a rotation is needed
    out = np.empty((3, 3))
    spatial_kernel.rotation(np.asarray(p, float), out)
    return out


class Body(Strict):
    name: str
    mass: float = pydantic.Field(gt=0, description="kg")
    inertia: Matrix3 = pydantic.Field(description="kg m^2, about the centre of mass, body frame")
    position: Vector3 = [0.0, 0.0, 0.0]
    orientation: Quaternion | None = None
    rotation: Matrix3 | None = None
    velocity: Vector3 = [0.0, 0.0, 0.0]
    omega: Vector3 = pydantic.Field(default=[0.0, 0.0, 0.0], description="rad/s, global frame")

    @pydantic.model_validator(mode="after")
    def _physical(self):
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


class Drive(Strict):
    """The relative angle of a revolute or cylindrical joint's bodies about its axis turns at a
    constant speed from its initial value: angle = speed t."""

    joint: str
    speed_rpm: float


Friction = Annotated[CoulombFriction | StribeckFriction | LinearFriction,
                     pydantic.Field(discriminator="law")]


class ClearanceJoint(JointMaterials):
    """cylindrical: a journal (axis journal_axis through journal_point) in a bore of `length`
    (axis bearing_axis through its mid-plane centre bearing_point), sliced into `slices`, with
    optional shoulders (axial_clearance, axial_stiffness); spherical: a ball (centre
    journal_point) in a socket (centre bearing_point). The normal law: a per-length law of
    pinbore.laws.elastic, hertz_point (cylindrical: spread evenly over the length), or
    calibrated:/sliced: from the laws file. Radii, length, E, nu, bearing_E, bearing_nu: as
    in the planar joint (reduced.scene.JointMaterials)."""

    name: str
    type: Literal["cylindrical", "spherical"]
    bearing_body: str
    bearing_point: Vector3
    bearing_axis: Vector3 | None = None
    journal_body: str
    journal_point: Vector3
    journal_axis: Vector3 | None = None
    slices: int = pydantic.Field(default=8, ge=1, le=256)
    axial_clearance: float | None = pydantic.Field(default=None, gt=0, description="m")
    axial_stiffness: float | None = pydantic.Field(default=None, gt=0, description="N/m")
    normal_law: str
    damping_law: str = "none"
    restitution: float = pydantic.Field(default=1.0, gt=0, le=1)
    friction: Friction | None = None
    # ideal: closed (journal centred and aligned), moving with the ideal joint; free: closed,
    # velocities as given
    start: Literal["ideal", "free"] = "ideal"

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.journal_radius >= self.bearing_radius:
            raise ValueError("journal_radius must be smaller than bearing_radius (the journal "
                             "must fit its bore: clearance > 0)")
        if self.type == "cylindrical":
            if self.bearing_axis is None or self.journal_axis is None or self.length is None:
                raise ValueError("bearing_axis, journal_axis and length are required by a "
                                 "cylindrical clearance joint")
            unit_axis(self.bearing_axis, "bearing_axis")
            unit_axis(self.journal_axis, "journal_axis")
            if (self.axial_clearance is None) != (self.axial_stiffness is None):
                raise ValueError("axial_clearance and axial_stiffness go together (shoulders)")
        else:
            if self.bearing_axis is not None or self.journal_axis is not None or \
                    self.length is not None or self.axial_clearance is not None:
                raise ValueError("a spherical clearance joint takes no axes, length or shoulders")
            if self.normal_law != "hertz_point":
                raise ValueError("normal_law: a spherical joint takes 'hertz_point' (a point law)")
        if not (self.normal_law in ELASTIC_LAWS or self.normal_law.startswith(FILE_LAWS)):
            raise ValueError(f"normal_law {self.normal_law!r} is unknown; valid: "
                             f"{', '.join(ELASTIC_LAWS)}, calibrated:<law in laws.json>, "
                             "sliced:<3D law in laws.json>")
        if self.damping_law not in DAMPING_LAWS:
            raise ValueError(f"damping_law {self.damping_law!r} is unknown; valid: "
                             f"{', '.join(DAMPING_LAWS)}")
        if self.damping_law == "calibrated" and self.type == "spherical":
            # the laws file's e(v0) comes from plane-strain impacts of a pin in a bore (a line
            # contact per unit length); a ball's point contact is another impact
            raise ValueError("damping_law 'calibrated' is for cylindrical joints: the laws file's "
                             "e(v0) is fitted on line-contact impacts of a pin in a bore, not of "
                             "a ball in a socket")
        return self


class Torsion(Strict):
    """A torque about axis_i (body i's frame) on the relative angle of body j about it,
    measured from the initial configuration: spring, stop or latch as in the planar scene
    (reduced.scene.TorsionSpring)."""

    type: Literal["spring", "stop", "latch"]
    body_i: str
    body_j: str
    axis_i: Vector3
    stiffness: float = pydantic.Field(ge=0, description="N m / rad")
    damping: float = pydantic.Field(default=0.0, ge=0, description="N m s / rad")
    free_angle_deg: float = 0.0

    @pydantic.model_validator(mode="after")
    def _axis(self):
        unit_axis(self.axis_i, "axis_i")
        return self


class SpatialScene(Strict):
    kind: Literal["spatial"]
    duration: float = pydantic.Field(gt=0)
    gravity: Vector3 = [0.0, 0.0, 0.0]
    laws_file: str | None = None
    bodies: list[Body] = pydantic.Field(min_length=1)
    joints: list[Joint] = []
    drive: Drive | None = None
    clearance_joints: list[ClearanceJoint] = []
    torsion: list[Torsion] = []
    integrator: Integrator = Integrator()
    output: Output = Output()

    @pydantic.model_validator(mode="after")
    def _bounded(self):
        if self.integrator.method == "dopri5_fixed" and self.integrator.fixed_step is None:
            raise ValueError("integrator.fixed_step: required by method = 'dopri5_fixed' in a "
                             "spatial scene")
        check_run_size(self)
        return self

    @pydantic.model_validator(mode="after")
    def _journals_fit(self):
        """A journal whose axis is tilted against its bore's at the start (a misaligned joint;
        it starts centred) fits only if its ends stay inside the clearance there:
        (L / 2) sin(tilt) < c."""
        bodies = {b.name: b for b in self.bodies}
        for k, c in enumerate(self.clearance_joints):
            if c.type != "cylindrical" or c.bearing_body not in bodies | {GROUND: None} or \
                    c.journal_body not in bodies | {GROUND: None}:
                continue   # unknown bodies: _names says so
            axes = []
            for name, axis in ((c.bearing_body, c.bearing_axis), (c.journal_body, c.journal_axis)):
                rot = np.eye(3) if name == GROUND else rotation_matrix(bodies[name].parameters())
                axes.append(rot @ unit_axis(axis, "axis"))
            sine = float(np.linalg.norm(np.cross(*axes)))
            clearance = c.bearing_radius - c.journal_radius
            if 0.5 * c.length * sine >= clearance:
                raise ValueError(
                    f"clearance_joints.{k} ({c.name}): the journal, tilted by "
                    f"{math.degrees(math.asin(min(sine, 1.0))):.3g} deg against its bore, does not "
                    f"fit: centred, its ends lie (L/2) sin(tilt) = {0.5 * c.length * sine:.4g} m "
                    f"off the bore's axis, beyond the radial clearance {clearance:.4g} m")
        return self

    @pydantic.model_validator(mode="after")
    def _names(self):
        used = [(j.body_i, "joints.body_i") for j in self.joints]
        used += [(j.body_j, "joints.body_j") for j in self.joints]
        used += [(c.bearing_body, "clearance_joints.bearing_body") for c in self.clearance_joints]
        used += [(c.journal_body, "clearance_joints.journal_body") for c in self.clearance_joints]
        used += [(t.body_i, "torsion.body_i") for t in self.torsion]
        used += [(t.body_j, "torsion.body_j") for t in self.torsion]
        check_body_names(self, used)
        if self.drive is not None:
            driven = {j.name: j for j in self.joints if j.name}
            if self.drive.joint not in driven:
                raise ValueError(f"drive.joint: unknown joint {self.drive.joint!r}; named joints: "
                                 f"{', '.join(sorted(driven)) or 'none'}")
            if driven[self.drive.joint].type not in ("revolute", "cylindrical"):
                raise ValueError("drive.joint: must be a revolute or cylindrical joint (it turns "
                                 "about the joint's axis)")
        return self
