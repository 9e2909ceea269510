"""A pin in its bore, what the revolute (planar), cylindrical and spherical (spatial) clearance
joints share: how deep their laws reach, the columns of a contact between a journal (a ball)
and its bore, a per-length normal law, the axial columns of a journal in space, and a
`sliced:<group>` law of the laws file.
"""

import math

import numpy as np

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism.joints.base import BLOW_UP_FRACTION, Clearance
from pinbore.reduced.mechanism.layout import (
    CONTACT_BEARING_BODY, CONTACT_BEARING_POINT, CONTACT_CLEARANCE, CONTACT_JOURNAL_BODY,
    CONTACT_JOURNAL_POINT, CONTACT_RADIUS)


class Bore(Clearance):
    """A journal (a ball) in its bore: its scene model has the radii and materials of
    reduced.mechanism.joints.contact.JointMaterials."""

    def reach(self) -> float:
        """A tenth of the journal's radius (m)."""
        return BLOW_UP_FRACTION * self.c.journal_radius

    def radial(self, geometry) -> dict:
        """The columns every contact of the journal in its bore has: the two bodies, the
        bearing's and the journal's centres, the radial clearance and the bearing's radius."""
        c = self.c
        return {CONTACT_BEARING_BODY: geometry.index[c.bearing_body],
                CONTACT_JOURNAL_BODY: geometry.index[c.journal_body],
                CONTACT_BEARING_POINT: list(c.bearing_point),
                CONTACT_JOURNAL_POINT: list(c.journal_point),
                CONTACT_CLEARANCE: c.bearing_radius - c.journal_radius,
                CONTACT_RADIUS: c.bearing_radius}

    def worn(self, base, source: str) -> dict:
        """Its worn bore and pin (wear_file), if it has them: its first contact's (the planar
        journal's RADIAL contact, the spatial journal's SLICED one)."""
        if self.c.wear_file is None:
            return {}
        from pinbore.core.scene import named_file   # noqa: PLC0415
        from pinbore.laws import wearfile   # noqa: PLC0415

        profiles = wearfile.read(named_file(self.c.wear_file, base),
                                 f"{source}: clearance joint {self.c.name}: wear_file")
        return {0: (profiles.bore, profiles.pin)}

    def per_length_law(self, deltas, laws_data, source) -> np.ndarray:
        """The force per length (N/m) of the joint's per-length normal law at `deltas`: a law
        of pinbore.laws.elastic or the laws file's calibrated:<law>
        (lawsfile.per_length_force)."""
        from pinbore.laws.lawsfile import per_length_force   # noqa: PLC0415 (a scene validates without it)

        c = self.c
        return per_length_force(c.normal_law, laws_data, deltas, c.elastic_joint(),
                                f"{source}: clearance_joints.normal_law")


class SpatialBore(Bore):
    """A journal or a ball in its bore in space: every one has the two axial columns (a
    journal's shoulders; -inf and 0 without them)."""

    def columns(self, across: dict, roles: dict, seen: dict) -> dict:
        """The penetration and normal force across the joint, then the deepest axial
        penetration and the axial force, then the friction force."""
        axial, depths = roles["axial"], seen["depths"]
        return {"penetration_m": across["penetration_m"], "normal_force_N": across["normal_force_N"],
                "axial_penetration_m": depths[:, axial].max(axis=1) if axial else np.full(depths.shape[0], -np.inf),
                "axial_force_N": seen["normals"][:, axial].sum(axis=1),
                "friction_force_N": across["friction_force_N"]}


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
        from pinbore.laws.lawsfile import per_length_force   # noqa: PLC0415 (a scene validates without it)

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
