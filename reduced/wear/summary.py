"""summary.json of `pinbore wear`: written and read back (the report) through one model, whose
ranges a file changed by hand fails (one line naming the key)."""

from pathlib import Path

import pydantic

from pinbore.core.scene import Strict, read_json

SUMMARY = "summary.json"


class SurfaceWear(Strict):
    """What one surface lost."""

    wear_coefficient_m2_per_N: float = pydantic.Field(ge=0)
    volume_m3: float = pydantic.Field(ge=0)
    max_depth_m: float = pydantic.Field(ge=0)
    at_deg: float = pydantic.Field(ge=-180, le=180, description="where, in the surface's frame")


class Jump(Strict):
    """A kept jump of the coupled wear: the cycles reached, its size, its error estimate, and
    the joint there (the deepest wear, the bore's worn volume, the peak contact force of a
    cycle of the run on it and the largest force of the run's first impact)."""

    cycles: float = pydantic.Field(ge=0)
    size: float = pydantic.Field(ge=0)
    error_m: float = pydantic.Field(ge=0)
    bore_max_depth_m: float = pydantic.Field(ge=0)
    pin_max_depth_m: float = pydantic.Field(ge=0)
    volume_m3: float = pydantic.Field(ge=0)
    peak_force_N: float = pydantic.Field(ge=0)
    first_impact_force_N: float = pydantic.Field(ge=0)


class WearSummary(Strict):
    scene_file: str
    mechanism_file: str
    joint: str
    cycles: float = pydantic.Field(gt=0)
    period_s: float = pydantic.Field(gt=0)
    periods_averaged: int = pydantic.Field(ge=1, description="the run's periods a cycle is the mean of")
    length_m: float = pydantic.Field(gt=0)
    sliding_distance_in_contact_per_cycle_m: float = pydantic.Field(ge=0)
    peak_force_per_length_N_per_m: float = pydantic.Field(ge=0)
    fe_force_range_N_per_m: list[float] = pydantic.Field(min_length=2, max_length=2)
    extrapolated: bool
    bore: SurfaceWear
    pin: SurfaceWear
    coupled: bool = pydantic.Field(description="the mechanism ran on its worn joint (cycle jumping)")
    pressure: str = pydantic.Field(default="new", description=(
        "the contact pressure worn by: \"new\", the new joint's FE run's; \"worn\", the worn "
        "joint's own on the FE's surface compliance"))
    worn_contacts_solved: int = pydantic.Field(default=0, ge=0, description=(
        "pressure \"worn\": the worn joint's loads solved over the runs"))
    worn_contacts_unresolved: int = pydantic.Field(default=0, ge=0, description=(
        "of those, the ones pressing no patch of 3 points or more of the compliance's grid "
        "(the contact narrower than it resolves)"))
    mechanism_runs: int = pydantic.Field(ge=1)
    refused_jumps: int = pydantic.Field(ge=0)
    jumps: list[Jump]


def write(path: Path, summary: WearSummary) -> None:
    path.write_text(summary.model_dump_json(indent=2) + "\n")


def read(path) -> WearSummary:
    return read_json(WearSummary, path, "wear")
