"""What every clearance joint of either kind shares: its contact laws (the normal and damping
laws by name, friction, the impact model) and the materials of a pin in its bore (radii, E,
nu), the scene tables each joint type's model (reduced.mechanism.joints) is made of. Pure
pydantic and the law names of pinbore.laws.elastic: validating them loads no compiled core.
"""

from typing import Annotated, Literal

import pydantic

from pinbore.core.scene import Strict
from pinbore.laws import elastic
from pinbore.laws.elastic import PUBLISHED

ELASTIC_LAWS = ["hertz_point"] + sorted(PUBLISHED)
# the hysteresis laws of pinbore.laws.dissipative.HYSTERESIS by name (a test holds the two
# lists equal)
HYSTERESIS_LAWS = ("flores", "gonthier", "herbert_mcwhannell", "hu_guo", "hunt_crossley",
                   "lankarani_nikravesh", "lee_wang", "zhiying_qishao")
DAMPING_LAWS = ["none", *HYSTERESIS_LAWS, "calibrated"]   # calibrated: laws file
FILE_LAWS = ("calibrated:", "sliced:")   # normal laws read from the scene's laws file


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
    friction table. In space z is a vector along the contact's tangent plane."""

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


class ContactLaw(Strict):
    """How a clearance joint's contacts carry their load. `impact = "continuous"`: the normal
    law (`normal_law`) and the damping law (`damping_law`, with the target `restitution`; or
    "calibrated": the laws file's e(v0)) act while a contact penetrates, and friction
    (`friction`) against its slip; "newton" / "poisson": rigid, frictionless impacts with
    restitution `restitution`, and below `rest_speed` (approach rate x restitution) the
    contact is held until it would pull (the three-state model)."""

    normal_law: str | None = None
    damping_law: str = "none"
    restitution: float = pydantic.Field(default=1.0, ge=0, le=1)
    friction: Friction | None = None
    impact: Literal["continuous", "newton", "poisson"] = "continuous"
    rest_speed: float = pydantic.Field(default=1e-3, gt=0, description="m/s")

    @pydantic.model_validator(mode="after")
    def _law(self):
        if self.impact != "continuous":
            if self.friction is not None or self.normal_law is not None or self.damping_law != "none":
                raise ValueError(f"impact = {self.impact!r} is a rigid, frictionless impact model: "
                                 "give no normal_law, damping_law or friction")
            return self
        if self.normal_law is None:
            raise ValueError("normal_law is required by impact = 'continuous'")
        if self.restitution == 0 and self.damping_law not in ("none", "calibrated"):
            raise ValueError("restitution must be > 0 for a continuous damping law")
        if self.damping_law not in DAMPING_LAWS:
            raise ValueError(f"damping_law {self.damping_law!r} is unknown; valid: "
                             f"{', '.join(DAMPING_LAWS)}")
        return self


class JointMaterials(Strict):
    """The radii and elastic constants of a revolute, cylindrical or spherical clearance
    joint: what its elastic law and its calibrated restitution (damping_law = "calibrated",
    matched on these in the laws file) are chosen by."""

    bearing_radius: float = pydantic.Field(gt=0)
    journal_radius: float = pydantic.Field(gt=0)
    length: float | None = pydantic.Field(default=None, gt=0,
                                          description="axial length (m): per-length laws x L")
    E: float = pydantic.Field(gt=0, description="Pa, the journal's (and the bearing's unless "
                                               "bearing_E is given)")
    nu: float = pydantic.Field(gt=-1, lt=0.5)
    bearing_E: float | None = pydantic.Field(default=None, gt=0, description="Pa; default E")
    bearing_nu: float | None = pydantic.Field(default=None, gt=-1, lt=0.5, description="default nu")

    def gap(self) -> float:
        """The radial clearance c = R_b - R_j (m)."""
        return self.bearing_radius - self.journal_radius

    def elastic_joint(self) -> elastic.Joint:
        """The joint of the elastic laws: radii, the bearing's and the journal's E and nu."""
        return elastic.Joint(self.bearing_radius, self.journal_radius,
                             self.E if self.bearing_E is None else self.bearing_E,
                             self.nu if self.bearing_nu is None else self.bearing_nu,
                             self.E, self.nu, self.length)

    @pydantic.model_validator(mode="after")
    def _fits(self):
        if self.journal_radius >= self.bearing_radius:
            raise ValueError("journal_radius must be smaller than bearing_radius (the journal "
                             "must fit its bore: clearance > 0)")
        return self


class WornSurfaces(Strict):
    """A journal's worn bore and pin (the revolute and the cylindrical joint's `wear_file`):
    each surface's worn depth against the angle of its own body's frame (laws.wearfile), a
    profile of the section, the same along a journal's axis. A worn journal meets its bore
    through its continuous contact law (the overlap's mean of order 4 on the round joint's
    scale, cpp/mechanism/worn.h): not with rigid impacts."""

    wear_file: str | None = pydantic.Field(default=None, description=(
        "a wear.csv (pinbore wear): the bore's and the pin's worn depth against angle in their "
        "bodies' frames (in space: about the bore's and the journal's axis from each one's "
        "reference direction, the body frame's x axis made normal to the axis, or y if the axis "
        "lies near x; the profile the same along the axis); the journal then meets its bore "
        "over the arc where the worn surfaces overlap (their overlap's mean of order 4 on the "
        "round joint's scale), which keeps the joint's law on a round profile"))

    @pydantic.model_validator(mode="after")
    def _worn(self):
        if self.wear_file is not None and self.impact != "continuous":
            raise ValueError("wear_file: a worn joint's contact is continuous (impact = "
                             "\"continuous\"), not a rigid impact")
        return self


def check_normal_law(law: str) -> None:
    """A normal law of the library or of the laws file."""
    if not (law in ELASTIC_LAWS or law.startswith(FILE_LAWS)):
        raise ValueError(f"normal_law {law!r} is unknown; valid: {', '.join(ELASTIC_LAWS)}, "
                         "calibrated:<law in laws.json>, sliced:<3D law in laws.json>")
