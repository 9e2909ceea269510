"""The study file's schema: a strict model of every table (unknown keys are refused; a broken
rule is one InputError line naming the key), read by `load`, and the files a study reads
(`inputs`). The study file's keys are described in pinbore.study."""

import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import pydantic

from pinbore.core import scene as scenes
from pinbore.core import uq
from pinbore.core.errors import InputError
from pinbore.core.scene import Strict

SPEC_KEYS = ("values", "grid", "distribution")
# a label of a case or a value: a part of a point's name, and so of a folder's
LabelText = Annotated[str, pydantic.Field(pattern=r"^[A-Za-z0-9_.+-]*$")]


class Grid(Strict):
    start: float
    stop: float
    num: int = pydantic.Field(ge=2)

    def values(self) -> list[float]:
        return np.linspace(self.start, self.stop, self.num).tolist()


class Distribution(Strict):
    """uniform (low, high), normal (mean, std), lognormal (median, sigma of ln), truncnormal
    (mean, std, low, high)."""

    kind: Literal["uniform", "normal", "lognormal", "truncnormal"]
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = pydantic.Field(default=None, gt=0)
    median: float | None = pydantic.Field(default=None, gt=0)
    sigma: float | None = pydantic.Field(default=None, gt=0)

    @pydantic.model_validator(mode="after")
    def _keys(self):
        needed = {"uniform": ("low", "high"), "normal": ("mean", "std"),
                  "lognormal": ("median", "sigma"), "truncnormal": ("mean", "std", "low", "high")}[self.kind]
        given = {k for k in ("low", "high", "mean", "std", "median", "sigma") if getattr(self, k) is not None}
        if set(needed) != given:
            raise ValueError(f"a {self.kind} distribution takes {', '.join(needed)} (given: "
                             f"{', '.join(sorted(given)) or 'none'})")
        if "low" in needed and not self.low < self.high:
            raise ValueError(f"low must be below high (got {self.low:g}, {self.high:g})")
        return self

    def frozen(self):
        return uq.distribution(self.kind, **self.model_dump(exclude_none=True, exclude={"kind"}))


class Parameter(Strict):
    """One of: a list of values, a grid, or a distribution."""

    values: list[float] | None = pydantic.Field(default=None, min_length=1)
    grid: Grid | None = None
    distribution: Distribution | None = None
    labels: list[LabelText] | None = None   # one per value: the points' names (grid plans)

    @pydantic.model_validator(mode="after")
    def _one(self):
        given = [k for k in SPEC_KEYS if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of values, grid, distribution (given: {', '.join(given) or 'none'})")
        if self.labels is not None:
            if self.distribution is not None:
                raise ValueError("labels name the values of a list or a grid, not of a distribution")
            count = len(self.values) if self.values is not None else self.grid.num
            if len(self.labels) != count:
                raise ValueError(f"labels: one per value ({count}), given {len(self.labels)}")
        return self


class Case(Strict):
    """One case of a group: its label and the keys it sets (dotted, as in [set]: any value,
    a key may be new)."""

    label: LabelText
    settings: dict[str, object] = {}

    @pydantic.model_validator(mode="before")
    @classmethod
    def _keys(cls, data):
        """A case's table is its label beside the keys it sets."""
        if isinstance(data, dict) and "settings" not in data:
            return {"label": data.get("label"), "settings": {k: v for k, v in data.items() if k != "label"}}
        return data


class Sampling(Strict):
    method: Literal["grid", "monte_carlo", "lhs", "sobol", "saltelli"] = "grid"
    points: int | None = pydantic.Field(default=None, ge=1)
    seed: int = pydantic.Field(default=0, ge=0)


class Surrogate(Strict):
    """A polynomial chaos of each quantity in the parameters (core.uq.chaos), fitted on the
    points of a random plan: its Sobol indices, mean and spread, and its leave-one-out error."""

    degree: int = pydantic.Field(ge=1, le=20)


STATISTICS = ("max", "min", "max_abs", "peak_to_peak", "mean", "rms", "std", "final")


class Collect(Strict):
    """A quantity of each point: a number of its result (`path`), or a statistic of one of a
    mechanism's time series over a window of time (`column`, `statistic`, `window_s`)."""

    name: str = pydantic.Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")
    path: str | None = pydantic.Field(default=None, min_length=1)
    column: str | None = pydantic.Field(default=None, min_length=1)
    statistic: Literal[STATISTICS] | None = None
    window_s: list[float] | None = pydantic.Field(default=None, min_length=2, max_length=2)

    @pydantic.model_validator(mode="after")
    def _one(self):
        if (self.path is None) == (self.column is None):
            raise ValueError("give a path (a number of the result) or a column (of the time "
                             "series), not both")
        if self.column is None and (self.statistic is not None or self.window_s is not None):
            raise ValueError("statistic and window_s go with a column")
        if self.column is not None and self.statistic is None:
            raise ValueError(f"a column needs its statistic ({', '.join(STATISTICS)})")
        if self.window_s is not None and not 0 <= self.window_s[0] < self.window_s[1]:
            raise ValueError(f"window_s: [start, end] with 0 <= start < end (got {self.window_s})")
        return self

    @property
    def where(self) -> str:
        """Where the quantity sits in a point's result."""
        return self.path if self.column is None else f"series.{self.name}"


class Threshold(Strict):
    quantity: str
    threshold: float


class Limit(Threshold):
    target: float = pydantic.Field(default=0.01, gt=0, lt=1)


class Tolerance(Strict):
    parameter: str
    limit: Threshold
    target: float = pydantic.Field(default=0.01, gt=0, lt=1)
    confidence: float = pydantic.Field(default=0.95, gt=0, lt=1)


class Study(Strict):
    base: str
    confidence: float = pydantic.Field(default=0.95, gt=0, lt=1)
    set: dict[str, object] = {}
    cases: dict[str, list[Case]] = {}   # groups of cases, every combination (grid plans)
    name_prefix: LabelText = ""        # of every point's name
    parameters: dict[str, Parameter] = {}   # with cases, may be empty: a grid of the cases
    sampling: Sampling = Sampling()
    collect: list[Collect] = pydantic.Field(min_length=1)
    limit: Limit | None = None
    tolerance: Tolerance | None = None
    surrogate: Surrogate | None = None

    @pydantic.model_validator(mode="after")
    def _plan(self):
        method, specs = self.sampling.method, self.parameters
        if not specs and (method != "grid" or not self.cases):
            raise ValueError("parameters: give at least one (a grid of cases alone may have none)")
        if method == "grid":
            wrong = [k for k, p in specs.items() if p.distribution is not None]
            if wrong:
                raise ValueError(f"sampling.method: grid takes values or a grid; {wrong[0]} has a distribution")
            if self.sampling.points is not None:
                raise ValueError("sampling.points: a grid runs every combination of the values; "
                                 "give no points")
            for group, cases in self.cases.items():
                if not cases:
                    raise ValueError(f"cases.{group}: give at least one case")
                labels = [c.label for c in cases]
                if len(set(labels)) != len(labels):
                    raise ValueError(f"cases.{group}: two cases have one label")
        else:
            if self.cases:
                raise ValueError(f"cases: go with sampling.method grid (every combination), not {method}")
            wrong = [k for k, p in specs.items() if p.distribution is None]
            if wrong:
                raise ValueError(f"sampling.method: {method} samples distributions; {wrong[0]} has none")
            if self.sampling.points is None:
                raise ValueError(f"sampling.points: {method} needs the number of points")
        names = [c.name for c in self.collect]
        if len(set(names)) != len(names):
            raise ValueError("collect: two quantities have one name")
        for where, quantity in (("limit", self.limit), ("tolerance.limit", self.tolerance and self.tolerance.limit)):
            if quantity is not None and quantity.quantity not in names:
                raise ValueError(f"{where}.quantity: {quantity.quantity!r} is not collected "
                                 f"(collect: {', '.join(names)})")
        if self.surrogate is not None:
            if method not in ("monte_carlo", "lhs", "sobol"):
                raise ValueError(f"surrogate: fits the points of a random plan (monte_carlo, lhs, "
                                 f"sobol), not of {method}")
            terms = math.comb(len(specs) + self.surrogate.degree, self.surrogate.degree)
            if self.sampling.points < 2 * terms:
                raise ValueError(f"surrogate.degree: {self.surrogate.degree} in {len(specs)} "
                                 f"parameters is {terms} terms: it needs sampling.points >= "
                                 f"{2 * terms} (given {self.sampling.points})")
        if self.tolerance is not None:
            spec = specs.get(self.tolerance.parameter)
            if spec is None or spec.distribution is None or spec.distribution.kind != "uniform":
                raise ValueError(f"tolerance.parameter: {self.tolerance.parameter!r} must be a "
                                 "parameter with a uniform distribution (its widest band)")
            if method != "monte_carlo":
                raise ValueError("tolerance: needs sampling.method monte_carlo (the binomial "
                                 "bound holds for independent draws)")
        return self


def inputs(study_file) -> list[Path]:
    """The files a study reads: itself, its base scene and the files that names (none when
    the study cannot be read: running it says why)."""
    path = Path(study_file)
    try:
        base = path.parent / scenes.read_toml(path)["base"]
    except (InputError, KeyError, TypeError):
        return [path]
    return [path, base, *scenes.referenced_files(base)]


def flatten(table: dict, prefix: str = "", stop=lambda value: False) -> dict:
    """Nested TOML tables as dotted keys (`a.0.b = 1` or `[a."0"] b = 1` -> {"a.0.b": 1});
    a table for which stop(table) holds is a value."""
    flat = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict) and not stop(value):
            flat |= flatten(value, name + ".", stop)
        else:
            flat[name] = value
    return flat


def load(path: Path) -> Study:
    """The study file validated (one InputError line naming the key and the rule)."""
    data = scenes.read_toml(path)
    if isinstance(data.get("parameters"), dict):
        data["parameters"] = flatten(data["parameters"],
                                     stop=lambda t: any(k in t for k in SPEC_KEYS))
    if isinstance(data.get("set"), dict):
        data["set"] = flatten(data["set"])
    if isinstance(data.get("cases"), dict):
        data["cases"] = {group: [flatten(c) if isinstance(c, dict) else c for c in cases]
                         if isinstance(cases, list) else cases
                         for group, cases in data["cases"].items()}
    return scenes.validate(Study, data, str(path))
