"""The revolute clearance joint of a planar mechanism: a journal in its bore, one RADIAL
contact, closed by the ideal revolute of the two centres; its outputs add the journal's
offset from the bearing's centre.
"""

import math
import warnings
from typing import Literal

import numpy as np
import pydantic

from pinbore.laws import elastic
from pinbore.reduced.mechanism.joints.bore import Bore, sliced_parts
from pinbore.reduced.mechanism.joints.contact import (ContactLaw, JointMaterials, WornSurfaces,
                                                     check_normal_law)
from pinbore.reduced.mechanism.layout import (
    CONTACT_AT_CONTACT, CONTACT_KIND, POINT, PRIM_BODY_I, PRIM_BODY_J, PRIM_KIND, PRIM_S_I,
    PRIM_S_J, PRIMITIVE_COLUMNS, RADIAL, row)
from pinbore.reduced.mechanism.vectors import Vector


class ClearanceJoint(JointMaterials, ContactLaw, WornSurfaces):
    """A revolute joint with radial clearance: the journal (on journal_body) moves freely
    inside the bearing (on bearing_body) and meets its wall through the contact laws."""

    name: str
    type: Literal["revolute"] = "revolute"
    bearing_body: str
    bearing_point: Vector
    journal_body: str
    journal_point: Vector
    # ideal: centred, moving with the ideal joint; free: centred, velocities as given;
    # placed: where the bodies' positions put it, velocities as given
    start: Literal["ideal", "free", "placed"] = "ideal"

    @pydantic.model_validator(mode="after")
    def _normal_law(self):
        if self.impact != "continuous":
            return self
        check_normal_law(self.normal_law)
        if self.normal_law != "hertz_point" and self.length is None:
            raise ValueError(f"length is required by normal_law {self.normal_law!r} (a force per "
                             "unit length)")
        return self


class RevoluteClearance(Bore):
    """A revolute clearance joint (ClearanceJoint) in the plane."""

    def closing(self, geometry) -> list:
        """The ideal revolute of its bearing and journal centres."""
        c = self.c
        return [row(PRIMITIVE_COLUMNS, {PRIM_KIND: POINT, PRIM_BODY_I: geometry.index[c.bearing_body],
                                        PRIM_BODY_J: geometry.index[c.journal_body],
                                        PRIM_S_I: list(c.bearing_point), PRIM_S_J: list(c.journal_point)})]

    def contacts(self, geometry, deltas, laws_data, source):
        """One RADIAL contact, its normal force and friction at the contact point on both
        bodies; the force of its law (N, `force`) at `deltas`."""
        c = self.c
        radial = self.radial(geometry) | {CONTACT_KIND: RADIAL, CONTACT_AT_CONTACT: 1.0}
        if c.impact != "continuous":
            return [radial], np.full(deltas.size, np.nan)   # rigid: no law, never evaluated
        return [radial], self.force(deltas, laws_data, source)

    def columns(self, across: dict, roles: dict, seen: dict) -> dict:
        """The journal's offset from the bearing's centre (ecc_x, ecc_y, m), then the columns
        across the joint."""
        offset = seen["offsets"][:, roles["main"][0]]
        return {"ecc_x_m": offset[:, 0], "ecc_y_m": offset[:, 1]} | across

    def force(self, deltas, laws_data, source) -> np.ndarray:
        """The elastic normal force (N) of the journal in its bore at the penetrations
        `deltas`: the Hertz point law, a per-length law (published or calibrated: the laws
        file's) times the joint's length, or a sliced:<group> law of a straight pin."""
        c = self.c
        joint = c.elastic_joint()
        if c.normal_law == "hertz_point":
            return elastic.hertz_point(deltas, joint)
        if c.normal_law.startswith("calibrated:"):
            return self.per_length_law(deltas, laws_data, source) * c.length
        if c.normal_law.startswith("sliced:"):
            # a straight pin (no tilt in the planar model): every slice at the same approach, so
            # one slice of width L + 2 end_length gives the sliced sum (laws.sliced, theta = 0,
            # no relief): F = scale (L + 2 e) f_loc(d - c_b F / L), tabulated on the grid of
            # `deltas`
            from pinbore.laws.sliced import sliced   # noqa: PLC0415 (compiled: a scene validates without it)
            from pinbore.laws.tables import split_compliance   # noqa: PLC0415

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
