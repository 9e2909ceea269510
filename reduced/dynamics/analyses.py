"""The options of `pinbore dynamics`: one model per analysis, validated before any work.

Each model holds exactly the options its analysis uses, with their defaults and rules; it is
strict and frozen like the scene models, so an analysis receives typed options and cannot
change them. An option the analysis does not use is an error, and so is a missing one it
needs. `parse` builds a model from the options given (keyed by field name: `--max-force` is
`max_force`) and turns the first broken rule into one line `--option: rule`.

Models: `PoincareOptions`, `LyapunovOptions` and `ShootingOptions` (one run of the mechanism),
`ContinuationOptions` (a branch of periodic orbits), `BifurcationOptions` and `DesignOptions`
(sweeps, run in parallel and cached point by point).
Their shared bases: `Analysis` (--out, --transient), `Sampled` (+ --periods), `Sweep`
(+ --points, and the sweep engine's --scheduler, --workers, --cache: core.sweep.Runner).

Rules: counts are whole numbers (--transient >= 0; --periods, --multiple, --workers,
--speeds N >= 1; --points >= 2; --sweeps >= 0); a range LOW HIGH is finite with LOW < HIGH;
--parameter is a dotted key of the scene or a shorthand (pinbore.reduced.dynamics.parameters),
and a shorthand's range stays physical (clearance > 0 m, speed > 0 rpm, friction mu >= 0,
frequency > 0 Hz, amplitude factor > 0); a continuation's --step is finite and > 0; a design
threshold is > 0 (inf, the default: no threshold); --workers, --scheduler and --cache follow
the rules of core.sweep.Runner (local processes or a Dask cluster, not both; the cache folder,
default OUT-cache, no existing file and outside OUT, which is replaced when a run completes).
What the options need of the scene (a drive, the parameter's keys, a valid scene at both ends
of every swept range) is checked against the scene by `pinbore.reduced.dynamics.studies`.
"""

import math
from pathlib import Path
from typing import Annotated, NamedTuple

import pydantic

from pinbore.core.errors import InputError
from pinbore.core.scene import Strict
from pinbore.core.sweep import Runner
from pinbore.reduced.dynamics import parameters


def at_least(minimum: int) -> pydantic.AfterValidator:
    """The rule of a count: a whole number >= minimum."""
    def check(value: int) -> int:
        if value < minimum:
            raise ValueError(f"at least {minimum} (got {value})")
        return value
    return pydantic.AfterValidator(check)


class Span(NamedTuple):
    """LOW HIGH of a swept range."""

    low: float
    high: float


class SpeedGrid(NamedTuple):
    """LOW HIGH N: N drive speeds (rpm) from LOW to HIGH."""

    low: float
    high: float
    count: int


def _finite_and_increasing(span: Span | SpeedGrid) -> Span | SpeedGrid:
    """LOW and HIGH finite, LOW < HIGH."""
    for name, value in (("LOW", span.low), ("HIGH", span.high)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number (got {value})")
    if not span.high > span.low:
        raise ValueError(f"HIGH must exceed LOW (got {span.low:g} {span.high:g})")
    return span


def _whole_count(value):
    """--speeds arrives as three floats: N becomes an integer when it is a whole number."""
    if isinstance(value, tuple) and len(value) == 3 and isinstance(value[2], float):
        if value[2].is_integer():
            return (*value[:2], int(value[2]))
        raise ValueError(f"N must be a whole number (got {value[2]:g})")
    return value


def _speed_count(grid: SpeedGrid) -> SpeedGrid:
    if grid.count < 1:
        raise ValueError(f"N must be at least 1 (got {grid.count})")
    return grid


def physical(parameter: str, span: Span | SpeedGrid) -> Span | SpeedGrid:
    """The range of `parameter` within its physical bounds (LOW is the smallest value;
    parameters.physical)."""
    parameters.physical(parameter, span.low)
    return span


def parameter_range(span: Span, info: pydantic.ValidationInfo) -> Span:
    """A `range` validator: the range of the `parameter` given beside it, within its physical
    bounds (physical)."""
    parameter = info.data.get("parameter")
    return span if parameter is None else physical(parameter, span)


def _threshold(value: float) -> float:
    if not value > 0:
        raise ValueError(f"must be > 0, or inf for no threshold (got {value})")
    return value


Range = Annotated[Span, pydantic.AfterValidator(_finite_and_increasing)]
Parameter = Annotated[str, pydantic.AfterValidator(parameters.check_name)]
PARAMETER = f"a dotted key of the scene, or one of {parameters.NAMES}"
Speeds = Annotated[SpeedGrid, pydantic.BeforeValidator(_whole_count),
                   pydantic.AfterValidator(_finite_and_increasing), pydantic.AfterValidator(_speed_count)]
Threshold = Annotated[float, pydantic.AfterValidator(_threshold)]


class Analysis(Strict):
    """What every analysis uses: where its outputs go, and the drive periods discarded
    before it starts (the transient)."""

    # the options check their numbers themselves: a threshold may be inf (none), and a
    # range says which end is not finite
    model_config = pydantic.ConfigDict(allow_inf_nan=True)

    out: Path = pydantic.Field(description="the output directory")
    transient: Annotated[int, at_least(0)] = 50

    def swept(self) -> list[tuple[str, str, Span | SpeedGrid]]:
        """(option, parameter, range) of every scene parameter the analysis varies."""
        return []


class Sampled(Analysis):
    """An analysis that samples the mechanism over `periods` drive periods."""

    periods: Annotated[int, at_least(1)] = 50


class PoincareOptions(Sampled):
    """`--analysis poincare`: the Poincare map of `periods` revolutions, classified."""


class LyapunovOptions(Sampled):
    """`--analysis lyapunov`: the largest Lyapunov exponent over `periods` revolutions."""


class ShootingOptions(Analysis):
    """`--analysis shooting`: a periodic orbit of `multiple` drive periods by Newton, from
    the state after the transient (it samples no periods)."""

    multiple: Annotated[int, at_least(1)] = 1


class ContinuationOptions(Analysis):
    """`--analysis continuation`: the periodic orbits of `multiple` forcing periods followed
    in `parameter` from the scene's value across `range` both ways (pseudo-arclength, at
    most `points` orbits; the first step `step` in the parameter's units, default 1/100 of
    the range), with their Floquet multipliers and bifurcations; with `sweeps` N > 0, an
    up- and a down-sweep of N values by direct integration too (each value starting from
    the state the last one reached: `transient` periods, then `periods` sampled)."""

    parameter: Parameter = pydantic.Field(description=PARAMETER)
    range: Range = pydantic.Field(description="LOW HIGH of the continued parameter")
    multiple: Annotated[int, at_least(1)] = 1
    points: Annotated[int, at_least(2)] = 200
    step: float | None = None
    sweeps: Annotated[int, at_least(0)] = 0
    periods: Annotated[int, at_least(1)] = 20

    _physical = pydantic.field_validator("range")(parameter_range)

    @pydantic.field_validator("step")
    @classmethod
    def _step(cls, step: float | None) -> float | None:
        if step is not None and not (math.isfinite(step) and step > 0):
            raise ValueError(f"must be a finite number > 0 (got {step})")
        return step

    def swept(self):
        return [("range", self.parameter, self.range)]


class Sweep(Runner, Sampled):
    """A study of `points` values run through the sweep engine (core.sweep.Runner: on local
    processes, `workers`, or on the Dask cluster at `scheduler`, each point cached in `cache`
    as it is done)."""

    points: Annotated[int, at_least(2)] = 50


class BifurcationOptions(Sweep):
    """`--analysis bifurcation`: the Poincare samples and their classification at `points`
    values of `parameter` across `range`."""

    parameter: Parameter = pydantic.Field(description=PARAMETER)
    range: Range = pydantic.Field(description="LOW HIGH of the swept parameter")

    _physical = pydantic.field_validator("range")(parameter_range)

    def swept(self):
        return [("range", self.parameter, self.range)]


class DesignOptions(Sweep):
    """`--analysis design`: peak contact force, impacts and acceleration deviation on the
    grid of `points` clearances across `range` by the drive speeds `speeds`, and per speed
    the clearances within both thresholds."""

    range: Range = pydantic.Field(description="LOW HIGH: the clearances, m")
    speeds: Speeds = pydantic.Field(description="LOW HIGH N: the drive speeds, rpm")
    max_force: Threshold = math.inf
    max_deviation: Threshold = math.inf

    @pydantic.field_validator("range")
    @classmethod
    def _clearances(cls, span: Span) -> Span:
        return physical("clearance", span)

    @pydantic.field_validator("speeds")
    @classmethod
    def _speeds(cls, grid: SpeedGrid) -> SpeedGrid:
        return physical("speed", grid)

    def swept(self):
        return [("range", "clearance", self.range), ("speeds", "speed", self.speeds)]


def parse(model: type[Analysis], given: dict, analysis: str) -> Analysis:
    """`model` built from the options given (field name -> value; an option left out is
    absent and takes its default); the first broken rule becomes one InputError line
    `--option: rule`."""
    try:
        return model.model_validate(given)
    except pydantic.ValidationError as err:
        raise InputError(_line(model, err.errors()[0], analysis)) from None


def _line(model: type[Analysis], error: dict, analysis: str) -> str:
    """One pydantic error as `--option: rule`, the option named as on the command line."""
    field = str(error["loc"][0]) if error["loc"] else ""
    option = "--" + field.replace("_", "-")
    if error["type"] == "missing":
        what = model.model_fields[field].description
        return f"{option}: --analysis {analysis} needs it" + (f" ({what})" if what else "")
    if error["type"] == "extra_forbidden":
        return f"{option}: not used by --analysis {analysis}"
    return f"{option}: " + error["msg"].removeprefix("Value error, ").replace("Input should be", "must be")
