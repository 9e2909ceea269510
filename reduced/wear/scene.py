"""The scene of `pinbore wear`: a planar mechanism with a revolute clearance joint, that
joint's FE run, the two surfaces' wear coefficients and how many cycles wear them. Read
without the mechanism built or the FE files read.

    kind = "wear"
    mechanism_file = "..."   a planar mechanism scene (kind = "planar") with a periodic forcing
    joint = "rod_slider"     its revolute clearance joint
    pressure_file = "..."    the joint's 2D FE run (pinbore fem): its pressure.csv
    curve_file = "..."       and its curve.csv (result.json beside it)
    compliance_file = "..."  and its compliance.csv (with [coupling] pressure = "worn")
    length = 0.02            m, the pin's length in the bore
    cycles = 1e5             forcing periods of use
    [bore] / [pin]           wear_coefficient (m^2/N): Archard's K / H
    [coupling]               tolerance (m), first_jump (cycles): the worn joint fed back
"""

from typing import Literal

import pydantic

from pinbore.core.scene import Strict


class Surface(Strict):
    """One surface of the joint (the bore's or the pin's)."""

    wear_coefficient: float = pydantic.Field(
        ge=0, le=1e-9, description="m^2/N (m^3/(N m)): Archard's K / H, the volume worn per "
        "unit load and distance slid; 0: a surface that does not wear")


class Coupling(Strict):
    """The worn joint fed back: the mechanism runs on its worn bore and pin as they wear,
    updated by cycle jumping (reduced.wear.jumping), each jump as long as its error estimate
    stays within the tolerance."""

    tolerance: float = pydantic.Field(ge=1e-8, le=1e-3, description=(
        "m: the error estimate of a jump's depth at any angle (from 10 nm: a jump's error "
        "falls as its size squared, so each halving costs about 1.4 times the runs, and below "
        "that the runs of 1e5 cycles of a worn joint number in the thousands)"))
    first_jump: float | None = pydantic.Field(default=None, gt=0, description=(
        "cycles of the first jump (default: a twentieth of the cycles)"))
    pressure: Literal["new", "worn"] = pydantic.Field(default="new", description=(
        "the contact pressure the wear follows: \"new\", the FE run's of the new joint (its "
        "pressure_file) at every load; \"worn\", the joint's own as it wears, its worn "
        "surfaces' contact solved on the FE run's surface compliance (the scene's "
        "compliance_file; fem.compliance.Conformal) on a grid of the load's directions in the "
        "bore's and the pin's frames (reduced.wear.pressure.worn_tables)"))


class WearScene(Strict):
    """Archard wear of a planar mechanism's revolute clearance joint over `cycles` periods of
    its forcing, on the pressure of the joint's FE run (reduced.wear.profile)."""

    kind: Literal["wear"]
    mechanism_file: str
    joint: str
    pressure_file: str
    curve_file: str
    compliance_file: str | None = pydantic.Field(default=None, description=(
        "the FE run's compliance.csv (pinbore fem, a 2D elastic round joint): the surface "
        "compliance the worn joint's pressure is solved on; read by coupling.pressure = "
        "\"worn\" only, which needs it"))
    length: float = pydantic.Field(gt=0, le=10.0, description="m, the pin's length in its bore: "
                                   "the mechanism's force over it is the FE run's load per unit length")
    cycles: float = pydantic.Field(gt=0, le=1e10, description="periods of the forcing worn through")
    bore: Surface
    pin: Surface
    periods: int | None = pydantic.Field(default=None, ge=2, le=1000, description=(
        "forcing periods each mechanism run lasts: the first is dropped (its transient) and "
        "the rest averaged into the wear of a cycle (default: the mechanism scene's duration). "
        "More periods give a rate of wear less scattered by the motion's irregularity."))
    points: int = pydantic.Field(default=720, ge=36, le=100_000,
                                 description="angles around each surface the depth is given at")
    coupling: Coupling | None = pydantic.Field(default=None, description=(
        "the worn joint fed back into the mechanism (default: one-way, the new joint's motion)"))

    @pydantic.model_validator(mode="after")
    def _compliance(self):
        worn = self.coupling is not None and self.coupling.pressure == "worn"
        if worn and self.compliance_file is None:
            raise ValueError("compliance_file: coupling.pressure = \"worn\" needs the FE run's "
                             "compliance.csv (pinbore fem of the round joint)")
        if not worn and self.compliance_file is not None:
            raise ValueError("compliance_file: read only by coupling.pressure = \"worn\"")
        return self
