"""The spherical clearance joint of a spatial mechanism: a ball in its socket, one RADIAL
contact on the Hertz point law (its normal force at the two centres, friction at the contact
point), closed by the ideal ball joint of the two centres. Its scene model is the spatial
table's (reduced.mechanism.joints.journal).
"""

import numpy as np

from pinbore.laws import elastic
from pinbore.reduced.mechanism.joints.bore import SpatialBore
from pinbore.reduced.mechanism.layout import CONTACT_KIND, RADIAL


class SphericalClearance(SpatialBore):
    """A spherical clearance joint (SpatialClearanceJoint of type "spherical")."""

    def check(self) -> None:
        """No axes, length, shoulders or worn profile; a continuous contact takes the point
        law, and not the laws file's restitution."""
        c = self.c
        if c.bearing_axis is not None or c.journal_axis is not None or \
                c.length is not None or c.axial_clearance is not None:
            raise ValueError("a spherical clearance joint takes no axes, length or shoulders")
        if c.wear_file is not None:
            raise ValueError("wear_file: a spherical joint takes no worn profile (a worn bore and "
                             "pin are a journal's: type = \"cylindrical\")")
        if c.impact != "continuous":
            return
        if c.normal_law != "hertz_point":
            raise ValueError("normal_law: a spherical joint takes 'hertz_point' (a point law)")
        if c.damping_law == "calibrated":
            # the laws file's e(v0) comes from plane-strain impacts of a pin in a bore (a line
            # contact per unit length); a ball's point contact is another impact
            raise ValueError("damping_law 'calibrated' is for cylindrical joints: the laws file's "
                             "e(v0) is fitted on line-contact impacts of a pin in a bore, not of "
                             "a ball in a socket")

    def closing(self, geometry) -> list:
        """The ideal ball joint of the socket's and the ball's centres."""
        c = self.c
        return geometry.ideal("spherical", c.bearing_body, c.journal_body, c.bearing_point,
                              c.journal_point, np.zeros(3), np.zeros(3), "clearance_joints")

    def contacts(self, geometry, deltas, laws_data, source):
        """One RADIAL contact (its normal force at the two centres, friction at the contact
        point); the force of the Hertz point law (N) at `deltas`."""
        c = self.c
        table = np.full(deltas.size, np.nan)   # rigid: no law, never evaluated
        if c.impact == "continuous":
            table = elastic.hertz_point(deltas, c.elastic_joint())
        return [self.radial(geometry) | {CONTACT_KIND: RADIAL}], table
