"""The scene table of a spatial clearance joint (`[[clearance_joints]]` of a spatial scene):
a journal in its bore (type "cylindrical") or a ball in its socket ("spherical"), one table
for both, each type's rules in its module (reduced.mechanism.joints.cylindrical, .spherical).
"""

from typing import Literal

import pydantic

from pinbore.reduced.mechanism import joints
from pinbore.reduced.mechanism.joints.contact import (ContactLaw, JointMaterials, WornSurfaces,
                                                     check_normal_law)
from pinbore.reduced.mechanism.vectors import Vector3


class SpatialClearanceJoint(JointMaterials, ContactLaw, WornSurfaces):
    """cylindrical: a journal (axis journal_axis through journal_point) in a bore of `length`
    (axis bearing_axis through its mid-plane centre bearing_point), sliced into `slices`, with
    optional shoulders (axial_clearance, axial_stiffness); spherical: a ball (centre
    journal_point) in a socket (centre bearing_point). The normal law: a per-length law of
    pinbore.laws.elastic, hertz_point (cylindrical: spread evenly over the length), or
    calibrated:/sliced: from the laws file; or rigid impacts (a cylindrical journal's two
    ends, and its shoulders). Radii, length, E, nu, bearing_E, bearing_nu: as in the planar
    joint (JointMaterials); a cylindrical journal's worn bore and pin: wear_file
    (WornSurfaces). It starts closed (journal centred and aligned, ball centred:
    "ideal", moving with the ideal joint, or "free", velocities as given) or where the bodies
    put it ("placed")."""

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
    start: Literal["ideal", "free", "placed"] = "ideal"

    @pydantic.model_validator(mode="after")
    def _geometry(self):
        joints.of(self).check()   # the rules of its type (cylindrical, spherical)
        if self.impact == "continuous":
            check_normal_law(self.normal_law)
        return self
