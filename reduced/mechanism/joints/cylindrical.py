"""The cylindrical clearance joint of a spatial mechanism: a journal in a bore of its length,
cut into slices along it (SLICED; with rigid impacts its two ends, AXIS_RADIAL), with optional
shoulders (PLANE, two-sided, frictionless); closed by a revolute on the bore's axis, or by a
spherical joint when the journal starts tilted against its bore. Its scene model is the
spatial table's (reduced.mechanism.joints.journal).
"""

import math

import numpy as np

from pinbore.core.errors import InputError
from pinbore.laws import elastic
from pinbore.reduced.mechanism.joints.bore import SpatialBore, sliced_parts
from pinbore.reduced.mechanism.layout import (
    AXIS_RADIAL, CONTACT_BEARING_AXIS, CONTACT_BEARING_REFERENCE, CONTACT_CLEARANCE,
    CONTACT_COMPLIANCE, CONTACT_END_LENGTH, CONTACT_FRICTION_ON, CONTACT_JOURNAL_AXIS,
    CONTACT_JOURNAL_POINT, CONTACT_JOURNAL_REFERENCE, CONTACT_KIND, CONTACT_LENGTH, CONTACT_SCALE,
    CONTACT_SIDE, CONTACT_SLICES, CONTACT_STIFFNESS, PLANE, SLICED)
from pinbore.reduced.mechanism.vectors import unit_axis

PARALLEL = 1e-9   # |1 - |u_b . u_j|| below which a journal's axis is aligned with its bore's


def reference(axis) -> np.ndarray:
    """The direction normal to an axis u (a body frame's) from which its section's angle runs:
    the frame's x axis made normal to u (y if u lies near x): x - (x . u) u, normalised. Along
    z it is x, the planar joint's angle's origin."""
    u = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.eye(3)[0] if abs(u[0]) < 0.9 else np.eye(3)[1]
    f = helper - (helper @ u) * u
    return f / np.linalg.norm(f)


class CylindricalClearance(SpatialBore):
    """A cylindrical clearance joint (SpatialClearanceJoint of type "cylindrical")."""

    def check(self) -> None:
        """Both axes and the length given, the axes nonzero; shoulders need their clearance
        and their stiffness."""
        c = self.c
        if c.bearing_axis is None or c.journal_axis is None or c.length is None:
            raise ValueError("bearing_axis, journal_axis and length are required by a "
                             "cylindrical clearance joint")
        unit_axis(c.bearing_axis, "bearing_axis")
        unit_axis(c.journal_axis, "journal_axis")
        if (c.axial_clearance is None) != (c.axial_stiffness is None):
            raise ValueError("axial_clearance and axial_stiffness go together (shoulders)")

    def fits(self, key: str, rotations: dict) -> None:
        """A journal whose axis is tilted against its bore's at the start (a misaligned joint;
        it starts centred) fits only if its ends stay inside the clearance there:
        (L / 2) sin(tilt) < c."""
        c = self.c
        axes = [rotations[name] @ unit_axis(axis, "axis")
                for name, axis in ((c.bearing_body, c.bearing_axis), (c.journal_body, c.journal_axis))]
        sine = float(np.linalg.norm(np.cross(*axes)))
        clearance = c.bearing_radius - c.journal_radius
        if 0.5 * c.length * sine >= clearance:
            raise ValueError(
                f"{key} ({c.name}): the journal, tilted by "
                f"{math.degrees(math.asin(min(sine, 1.0))):.3g} deg against its bore, does not "
                f"fit: centred, its ends lie (L/2) sin(tilt) = {0.5 * c.length * sine:.4g} m "
                f"off the bore's axis, beyond the radial clearance {clearance:.4g} m")

    def closing(self, geometry) -> list:
        """A revolute on the bore's axis, or, when the journal's axis is tilted against the
        bore's at the start (a misaligned joint), a spherical joint at the bore's centre: the
        journal centred, its tilt left to the other joints (a revolute could not close)."""
        c = self.c
        u_b = np.array(unit_axis(c.bearing_axis, "bearing_axis"))
        u_j = np.array(unit_axis(c.journal_axis, "journal_axis"))
        tilted = abs(abs((geometry.rot[c.bearing_body] @ u_b) @ (geometry.rot[c.journal_body] @ u_j)) - 1) > PARALLEL
        return geometry.ideal("spherical" if tilted else "revolute", c.bearing_body, c.journal_body,
                              c.bearing_point, c.journal_point, u_b, u_j, "clearance_joints")

    def contacts(self, geometry, deltas, laws_data, source):
        """The journal along its bore (SLICED, with its bore's and its journal's reference
        directions, the origins of a worn profile's angle; with rigid impacts its two ends
        against the bore's axis, AXIS_RADIAL) and its shoulders (PLANE, two-sided,
        frictionless); the force per length (N/m, per_length) its slices carry at `deltas`.
        A worn journal's bore takes no bulk compliance (one InputError line)."""
        c = self.c
        radial = self.radial(geometry)
        u_b = unit_axis(c.bearing_axis, "bearing_axis")
        u_j = unit_axis(c.journal_axis, "journal_axis")
        if c.impact == "continuous":
            scale, end, bulk, table = self.per_length(deltas, laws_data, source)
            if bulk > 0 and c.wear_file is not None:
                raise InputError(f"{source}: clearance joint {c.name}: wear_file: a worn journal's "
                                 f"bore takes no bulk compliance, and {c.normal_law!r} has "
                                 f"{bulk:.3g} m^2/N; give a sliced law without it")
            out = [radial | {CONTACT_KIND: SLICED, CONTACT_BEARING_AXIS: u_b, CONTACT_JOURNAL_AXIS: u_j,
                             CONTACT_LENGTH: c.length, CONTACT_SLICES: c.slices,
                             CONTACT_END_LENGTH: end, CONTACT_SCALE: scale, CONTACT_COMPLIANCE: bulk,
                             CONTACT_BEARING_REFERENCE: list(reference(u_b)),
                             CONTACT_JOURNAL_REFERENCE: list(reference(u_j))}]
        else:   # the journal's two ends against the bore's axis
            table = np.full(deltas.size, np.nan)   # rigid: no law, never evaluated
            out = [radial | {CONTACT_KIND: AXIS_RADIAL, CONTACT_BEARING_AXIS: u_b,
                             CONTACT_JOURNAL_POINT: list(np.asarray(c.journal_point)
                                                         + side * 0.5 * c.length * np.asarray(u_j))}
                   for side in (-1.0, 1.0)]
        if c.axial_clearance is not None:
            out.append(radial | {CONTACT_KIND: PLANE, CONTACT_BEARING_AXIS: u_b,
                                 CONTACT_CLEARANCE: c.axial_clearance,
                                 CONTACT_STIFFNESS: c.axial_stiffness if c.impact == "continuous" else 0.0,
                                 CONTACT_SIDE: 0.0, CONTACT_FRICTION_ON: 0.0})
        return out, table

    def per_length(self, deltas, laws_data, source):
        """(scale a, end length e, bulk compliance c_b (m^2/N), the per-length force f (N/m)
        the slices carry at deltas: a sliced law's local law f_loc, laws.sliced)."""
        c = self.c
        if c.normal_law == "hertz_point":   # the point law spread evenly over the length
            return 1.0, 0.0, 0.0, elastic.hertz_point(deltas, c.elastic_joint()) / c.length
        if c.normal_law.startswith("sliced:"):
            from pinbore.laws.tables import split_compliance   # noqa: PLC0415 (compiled: a scene validates without it)

            law, per_length = sliced_parts(c, deltas, laws_data, source)
            bulk = law.bulk_compliance_m2_per_N
            if bulk > 0:   # the slices carry the local law; the engine moves the bore (laws.sliced)
                grid_log0, grid_step = math.log(deltas[0]), math.log(deltas[1] / deltas[0])
                local_log0, local_step, local_table = split_compliance(
                    grid_log0, grid_step, np.log(per_length), bulk)
                per_length = np.exp(np.interp(   # on the model's grid: log-log, as the lookup
                    np.log(deltas), local_log0 + local_step * np.arange(local_table.size),
                    local_table, right=np.nan))
            return law.scale, law.end_length_m, bulk, per_length
        return 1.0, 0.0, 0.0, self.per_length_law(deltas, laws_data, source)

    def roles(self, rows) -> dict:
        """The journal across its bore (its slices, or its two ends), and its shoulders
        (the last contact, when it has them) along it."""
        rows = list(rows)
        axial = rows[-1:] if self.c.axial_clearance is not None else []
        return {"main": [k for k in rows if k not in axial], "axial": axial}

    def across(self) -> tuple:
        """Two directions normal to the bore's axis u: its reference direction f (reference)
        and u x f."""
        u = np.asarray(self.c.bearing_axis, float) / np.linalg.norm(self.c.bearing_axis)
        f = reference(u)
        return f, np.cross(u, f)
