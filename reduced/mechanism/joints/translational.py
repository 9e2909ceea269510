"""The translational clearance joint, of both kinds: a slider in its guide, its four corners
each a PLANE contact against the guide's face on its side, on a corner's law (a rounded
corner on a flat, or a power law) or rigid impacts; closed by the ideal guide (a DOT2 and a
DOT1); its outputs add the slider's offset across its guide, its tilt and each corner's
columns.
"""

from typing import Literal

import numpy as np
import pydantic

from pinbore.laws import elastic
from pinbore.reduced.mechanism.joints.base import BLOW_UP_FRACTION, Clearance
from pinbore.reduced.mechanism.joints.contact import ContactLaw
from pinbore.reduced.mechanism.layout import (
    CONTACT_AT_CONTACT, CONTACT_BEARING_AXIS, CONTACT_BEARING_BODY, CONTACT_BEARING_POINT,
    CONTACT_CLEARANCE, CONTACT_JOURNAL_BODY, CONTACT_JOURNAL_POINT, CONTACT_KIND, CONTACT_SIDE, DOT1,
    DOT2, PLANE, PRIM_A_I, PRIM_B_J, PRIM_BODY_I, PRIM_BODY_J, PRIM_KIND, PRIM_S_I, PRIM_S_J,
    PRIMITIVE_COLUMNS, row)
from pinbore.reduced.mechanism.vectors import Vector3, unit_axis

CORNER_LAWS = ["hertz_point", "power"]   # a slider's corner on its guide's face
# a translational joint's corners: (end along the slider's axis, side across it), in the order
# of its contacts and of their outputs corner1..corner4
CORNERS = ((-1.0, 1.0), (1.0, 1.0), (-1.0, -1.0), (1.0, -1.0))


def translational_joint(vector):
    """The translational clearance joint of a planar (`vector` of 2) or spatial (3) scene."""
    space = vector is Vector3

    class TranslationalJoint(ContactLaw):
        """A slider (on journal_body) in a guide (on bearing_body) with clearance: a rectangle
        of half-length a along its axis and half-width b across it, between the guide's two
        faces at b + c on either side of the guide's axis (through bearing_point, along
        bearing_axis; in space the faces are normal to bearing_normal). Its four corners
        meet the face on their side through the contact laws, each a contact of its own:
        normal_law "hertz_point" (a corner rounded to corner_radius on a flat face:
        F = (4/3) E* sqrt(r) delta^1.5, E* of the slider's and the guide's E and nu) or
        "power" (F = stiffness delta^exponent), or rigid impacts. The slider's centre
        (journal_point) and its axis (journal_axis; in space journal_normal across it) are
        in its own frame. It starts centred and aligned (start "ideal": moving with the ideal
        prismatic joint; "free": velocities as given) or where the bodies put it ("placed")."""

        name: str
        type: Literal["translational"] = "translational"
        bearing_body: str
        bearing_point: vector
        bearing_axis: vector
        journal_body: str
        journal_point: vector = [0.0] * (3 if space else 2)
        journal_axis: vector
        if space:
            bearing_normal: Vector3
            journal_normal: Vector3
        half_length: float = pydantic.Field(gt=0, description="m, a")
        half_width: float = pydantic.Field(gt=0, description="m, b")
        clearance: float = pydantic.Field(gt=0, description="m, c: the gap on each side, centred")
        E: float | None = pydantic.Field(default=None, gt=0, description="Pa, the slider's (hertz_point)")
        nu: float | None = pydantic.Field(default=None, gt=-1, lt=0.5)
        bearing_E: float | None = pydantic.Field(default=None, gt=0, description="Pa; default E")
        bearing_nu: float | None = pydantic.Field(default=None, gt=-1, lt=0.5)
        corner_radius: float | None = pydantic.Field(default=None, gt=0, description="m (hertz_point)")
        stiffness: float | None = pydantic.Field(default=None, gt=0, description="N/m^exponent (power)")
        exponent: float = pydantic.Field(default=1.5, ge=1, le=3)
        start: Literal["ideal", "free", "placed"] = "ideal"

        @pydantic.model_validator(mode="after")
        def _geometry(self):
            unit_axis(self.bearing_axis, "bearing_axis")
            unit_axis(self.journal_axis, "journal_axis")
            if space:
                for axis, normal in (("bearing_axis", "bearing_normal"), ("journal_axis", "journal_normal")):
                    u, n = unit_axis(getattr(self, axis), axis), unit_axis(getattr(self, normal), normal)
                    if abs(np.dot(u, n)) > 1e-9:
                        raise ValueError(f"{normal}: must be normal to {axis}")
            if self.impact != "continuous":
                return self
            if self.normal_law not in CORNER_LAWS:
                raise ValueError(f"normal_law {self.normal_law!r} is not a law of a corner on a "
                                 f"face; valid: {', '.join(CORNER_LAWS)}")
            if self.damping_law == "calibrated":
                raise ValueError("damping_law 'calibrated' is the laws file's e(v0) of a pin in a "
                                 "bore, not of a slider's corner on a face")
            needs = {"hertz_point": ("corner_radius", "E", "nu"), "power": ("stiffness",)}[self.normal_law]
            missing = [key for key in needs if getattr(self, key) is None]
            if missing:
                raise ValueError(f"{', '.join(missing)} required by normal_law {self.normal_law!r}")
            return self

        def gap(self) -> float:
            """The clearance c on each side (m)."""
            return self.clearance

        def effective_modulus(self) -> float:
            """E* of the slider's and the guide's materials (Pa)."""
            e_b = self.E if self.bearing_E is None else self.bearing_E
            nu_b = self.nu if self.bearing_nu is None else self.bearing_nu
            return 1.0 / ((1 - self.nu ** 2) / self.E + (1 - nu_b ** 2) / e_b)

    return TranslationalJoint


class TranslationalClearance(Clearance):
    """A translational clearance joint (TranslationalJoint), in the plane or in space."""

    def reach(self) -> float:
        """A tenth of the slider's half-width (m)."""
        return BLOW_UP_FRACTION * self.c.half_width

    def frames(self):
        """The guide's axis u and face normal n (guide frame) and the slider's axis and normal
        (slider frame), unit; in the plane each normal is its axis turned a quarter turn."""
        c = self.c
        frames = []
        for axis, normal in ((c.bearing_axis, getattr(c, "bearing_normal", None)),
                             (c.journal_axis, getattr(c, "journal_normal", None))):
            u = np.array(unit_axis(axis, "axis"))
            n = np.array([-u[1], u[0]]) if normal is None else np.array(unit_axis(normal, "normal"))
            frames.append((u, n))
        return frames

    def closing(self, geometry) -> list:
        """The ideal guide: the slider's centre on the guide's axis (a dot-2 on the face
        normal) and its axis along the guide's (a dot-1: the slider's axis normal to the face
        normal); the rest of its motion is left to the other joints."""
        c = self.c
        (_, n_g), (u_s, _) = self.frames()
        bi, bj = geometry.index[c.bearing_body], geometry.index[c.journal_body]
        pad = [0.0] * (3 - len(n_g))
        return [row(PRIMITIVE_COLUMNS, {PRIM_KIND: DOT2, PRIM_BODY_I: bi, PRIM_BODY_J: bj,
                                        PRIM_S_I: list(c.bearing_point) + pad, PRIM_A_I: list(n_g) + pad,
                                        PRIM_S_J: list(c.journal_point) + pad}),
                row(PRIMITIVE_COLUMNS, {PRIM_KIND: DOT1, PRIM_BODY_I: bi, PRIM_BODY_J: bj,
                                        PRIM_A_I: list(n_g) + pad, PRIM_B_J: list(u_s) + pad})]

    def contacts(self, geometry, deltas, laws_data, source):
        """The four corners of the slider, each a PLANE contact against the guide's face on
        its side: the corner s0 + e a u_s + s b n_s (slider frame) at
        delta = s n_g.(X - P_g) - (b + c); the force of a corner's law (N, corner_force) at
        `deltas`."""
        c = self.c
        (_, n_g), (u_s, n_s) = self.frames()
        s0 = np.array(c.journal_point, float)
        out = []
        for end, side in CORNERS:
            corner = s0 + end * c.half_length * u_s + side * c.half_width * n_s
            out.append({CONTACT_KIND: PLANE, CONTACT_BEARING_BODY: geometry.index[c.bearing_body],
                        CONTACT_JOURNAL_BODY: geometry.index[c.journal_body],
                        CONTACT_BEARING_POINT: list(c.bearing_point), CONTACT_BEARING_AXIS: list(n_g),
                        CONTACT_JOURNAL_POINT: list(corner), CONTACT_SIDE: side,
                        CONTACT_CLEARANCE: c.half_width + c.clearance, CONTACT_AT_CONTACT: 1.0})
        return out, corner_force(c, deltas)

    def columns(self, across: dict, roles: dict, seen: dict) -> dict:
        """The columns across the joint, then the slider's offset across its guide and its
        tilt (slider_pose), then each corner's penetration, normal and friction force."""
        main = roles["main"]
        depths, normals, frictions = seen["depths"], seen["normals"], seen["frictions"]
        out = dict(across)
        out["offset_m"], out["tilt_rad"] = slider_pose(depths[:, main], self.c.half_length)
        for i, k in enumerate(main):
            out[f"corner{i + 1}_penetration_m"] = depths[:, k]
            out[f"corner{i + 1}_normal_force_N"] = normals[:, k]
            out[f"corner{i + 1}_friction_force_N"] = frictions[:, k]
        return out

    def across(self) -> tuple:
        """The guide's axis and its face normal."""
        return self.frames()[0]


def corner_force(c, deltas) -> np.ndarray:
    """The elastic force (N) of a slider's corner on its guide's face at the penetrations
    `deltas`: "hertz_point", a sphere of the corner's radius r on a flat,
    F = (4/3) E* sqrt(r) delta^1.5 ([Johnson1985] sec. 4.2, the point law's limit of an
    infinite bearing radius), or "power", F = stiffness delta^exponent. Rigid impacts: no law
    (NaN)."""
    if c.impact != "continuous":
        return np.full(deltas.size, np.nan)
    if c.normal_law == "hertz_point":
        return elastic.hertz_flat(deltas, c.corner_radius, c.effective_modulus())
    return c.stiffness * deltas ** c.exponent


def slider_pose(depth, half_length):
    """A slider's offset across its guide (m, along the guide's face normal n) and its tilt
    (rad, its axis against the guide's), exactly from its corners' penetrations (columns in
    the order of CORNERS): a corner (end e, side s) at C + e a u_s + s b n_s has
    delta = s (n.(C - P)) + e s a (u_s.n) + b (n_s.n) - (b + c), so the offset n.(C - P) is
    (d1 + d2 - d3 - d4)/4 and sin(tilt) = u_s.n = (d2 - d1 + d3 - d4)/(4a)."""
    d1, d2, d3, d4 = depth.T
    return (d1 + d2 - d3 - d4) / 4, np.arcsin(np.clip((d2 - d1 + d3 - d4) / (4 * half_length), -1, 1))
