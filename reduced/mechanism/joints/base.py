"""The one interface of a clearance joint type: what the model's build, the outputs and the
flows ask of a joint, whatever its type. Each type's module (reduced.mechanism.joints) holds
a subclass of `Clearance`, which holds the joint's scene model; the registry
(reduced.mechanism.joints.TYPES) finds it by the joint's `type`.
"""

import numpy as np

BLOW_UP_FRACTION = 0.1  # a penetration beyond this fraction of the journal radius (of a
#                         slider's half-width) stops a run


class Clearance:
    """A clearance joint of one type: its scene model `c` (the type's table of the scene),
    with what its type knows of it. A subclass writes `reach`, `closing` and `contacts`; the
    rest has a default that most types keep."""

    def __init__(self, c):
        self.c = c

    def check(self) -> None:
        """The type's rules of its scene table beyond the table's own (ValueError, one rule):
        none by default (a table of one type holds its rules itself)."""

    def fits(self, key: str, rotations: dict) -> None:
        """ValueError (`key`: the joint's place in the scene) when the joint cannot start
        closed with its bodies in their initial orientations (rotations: body name -> 3 x 3
        rotation matrix, the ground's among them): it fits by default."""

    def reach(self) -> float:
        """The deepest penetration its law is tabulated to (m): beyond, the run has blown up."""
        raise NotImplementedError

    def closing(self, geometry) -> list:
        """The primitive rows (layout.PRIM_*) of the ideal joint that closes it, written
        against the body kind's Geometry of the scene (its `index` of bodies)."""
        raise NotImplementedError

    def contacts(self, geometry, deltas, laws_data, source):
        """(the geometry columns (layout.CONTACT_*) of each of its contacts, the force its law's
        table holds at the penetrations `deltas`: N, or N/m for a journal along its bore; NaN
        throughout with rigid impacts: no law, never evaluated)."""
        raise NotImplementedError

    def worn(self, base, source: str) -> dict:
        """The worn profiles its contacts run on: {contact (its index in `contacts`): (the
        bore's depths, the pin's depths) (m, at angles evenly spaced from -pi in the bearing's
        and the journal's frames)}; none by default (round surfaces)."""
        return {}

    def roles(self, rows) -> dict:
        """Its contacts' rows (`rows`, in the order of `contacts`) by role: "main" across the
        joint, "axial" along it (a journal's shoulders); every row across it by default."""
        return {"main": list(rows), "axial": []}

    def columns(self, across: dict, roles: dict, seen: dict) -> dict:
        """Its output columns at the steps, by name without the joint's: `across` (the
        deepest penetration and the normal and friction forces summed over its main
        contacts) and the type's own, from `seen` (reduced.mechanism.outputs.observed_steps:
        each contact's depths, normals, frictions, offsets per step) and its `roles`;
        `across` alone by default."""
        return across

    def across(self) -> tuple:
        """Two directions across the joint, in the bearing body's frame, along which the flows
        observe the journal's (slider's) centre: the frame's x and y by default."""
        x, y = np.eye(len(self.c.bearing_point))[:2]
        return x, y
