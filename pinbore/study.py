"""`pinbore study STUDY.toml --out DIR`: a scene's parameters swept or sampled, every point run,
the quantities it collects tabulated, with their statistics, Sobol indices and tolerance band.

The study file (a strict model: unknown keys are refused):

    base = "../scenes/reduced/slider_crank_flores2004.toml"   # relative to the study file
    confidence = 0.95                                          # of every interval
    [set]                          # fixed changes to the base scene (a key may be new)
    duration = 0.012
    [parameters."clearance_joints.0.journal_radius"]           # a dotted key of the scene
    distribution = { kind = "uniform", low = 9.4e-3, high = 9.6e-3 }
    [parameters."clearance_joints.0.restitution"]
    values = [0.7, 0.9]            # or grid = { start, stop, num }
    [sampling]
    method = "monte_carlo"         # grid | monte_carlo | lhs | sobol | saltelli
    points = 200                   # random plans (saltelli: N base rows, N (d + 2) runs)
    seed = 1
    [[collect]]
    name = "peak_force_N"
    path = "clearance_joints.rod_slider.peak_normal_force_N"   # into the point's result
    [[collect]]                    # or a statistic of a mechanism's time-series column
    name = "jitter_rad_per_s"
    column = "crank_omega_rad_per_s"
    statistic = "std"              # max min max_abs peak_to_peak mean rms std final
    window_s = [0.006, 0.012]      # optional (s)
    [limit]                        # optional: P(quantity > threshold), against target
    quantity = "peak_force_N"
    threshold = 2.0e4
    target = 0.05
    [surrogate]                    # optional (random plans): a polynomial chaos of this
    degree = 4                     # total degree in the parameters: its Sobol indices
    [tolerance]                    # optional: the widest band of a uniform parameter
    parameter = "clearance_joints.0.journal_radius"
    limit = { quantity = "peak_force_N", threshold = 5.0e4 }
    target = 0.01

A point runs through the stage of its base scene's `kind` (pinbore.stages: any stage that
takes a scene kind), and its result is what that stage writes: the summary of `pinbore
reduced` (summary.json, computed in process, no files; with the statistics of its collected
columns under `series`), impact.json of `pinbore impact`, modes.json of `pinbore modes`,
summary.json of `pinbore wear`, result.json of `pinbore fem` with the last row of its curve
under `curve_last`.

Every point's scene is validated before any run (a point that breaks a rule is one line
naming the point, the key and the rule; exit 2, nothing written). The points run in parallel
through the one sweep engine of the package (pinbore.core.sweep: long-lived local processes or a
Dask cluster), cached by content: the name of a point's cache file is the SHA-256 of its stage,
its whole scene, the files the scene names and the source of the code that runs it (the
modules its stage's model, runner and point function import, read by pinbore.core.codedeps,
and the class Point here), so a
rerun runs only new or changed points, and a killed study resumes. A failed point is marked
in results.csv with its reason; the command then exits 1 and keeps the others.

Writes DIR/results.csv (and, from PARQUET_ROWS points, the same table as DIR/results.parquet:
typed columns that pandas, Polars, DuckDB or Dask read without parsing text),
DIR/summary.json, DIR/statistics.json, DIR/histograms.png, DIR/exceedance.png and, for a
saltelli plan, DIR/sobol.csv and DIR/sobol.png, for a
tolerance DIR/tolerance.json and DIR/tolerance.png. The statistics are those of
pinbore.core.uq, over the points whose status is "complete".
"""

import csv
import hashlib
import inspect
import itertools
import json
import math
import subprocess
import sys
import time
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import pydantic

from pinbore.core import scene as scenes
from pinbore.core import sweep, uq
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.core.codedeps import code_hash, installed_graph, stage_code
from pinbore.core.scene import Strict
from pinbore.core.sweep import digest_files, get, named_files, put
from pinbore.stages import STAGE, of_scene, resolve

SPEC_KEYS = ("values", "grid", "distribution")
# a parameter's key the base scene does not have
ABSENT = (f"{sweep.ABSENT} (a key its default leaves out, such as a flexible body's modes, is "
          "given a value under [set] first)")
# the files of an FE or impact point's run kept in DIR/points/<name>/ (its data; not its plots)
KEPT_SUFFIXES = (".csv", ".json")
# the number of points from which the results table is also written as Parquet (pyarrow)
PARQUET_ROWS = 1000
# a label of a case or a value: a part of a point's name, and so of a folder's
LabelText = Annotated[str, pydantic.Field(pattern=r"^[A-Za-z0-9_.+-]*$")]


def point_code(stage: str) -> list[str]:
    """The code that may decide a point's result: its stage's scene model, runner and point
    function (pinbore.stages), read with what they import (core.codedeps: the import closure,
    lazy imports and the compiled core included); the class Point is hashed beside it (not the
    rest of this module: a new plot reruns nothing). An edit of the multibody engine so
    reruns no FE point."""
    return stage_code(installed_graph(), stage, ("point",))


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


def column_statistic(times: np.ndarray, values: np.ndarray, statistic: str,
                     window=None) -> float:
    """A statistic of a time series sampled at the run's accepted steps (times s, values in
    the column's unit), over the window [start, end] s (default: the whole run): max, min,
    max_abs, peak_to_peak and final of the step values; mean, rms and std weighted by time
    (trapezoidal rule over the steps, whose sizes vary), e.g. the rms of an attitude rate
    about its mean after a latch. NaN when the window holds fewer than two steps."""
    start, end = window if window is not None else (times[0], times[-1])
    inside = (times >= start) & (times <= end)
    t, x = times[inside], values[inside]
    if t.size < 2:
        return math.nan
    if statistic in ("max", "min", "max_abs", "peak_to_peak", "final"):
        return float({"max": np.max(x), "min": np.min(x), "max_abs": np.max(np.abs(x)),
                      "peak_to_peak": np.ptp(x), "final": x[-1]}[statistic])
    weights = np.zeros(t.size)
    weights[1:] += np.diff(t) / 2
    weights[:-1] += np.diff(t) / 2
    mean = float(weights @ x / (t[-1] - t[0]))
    if statistic == "mean":
        return mean
    if statistic == "rms":
        return math.sqrt(float(weights @ x**2 / (t[-1] - t[0])))
    return math.sqrt(max(float(weights @ (x - mean) ** 2 / (t[-1] - t[0])), 0.0))


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


class Options(sweep.Runner):
    """The command line's options: the sweep engine's (core.sweep.Runner: --out, --scheduler,
    --workers, --cache) and the study's own."""

    ranks: int = pydantic.Field(default=1, ge=1)   # MPI ranks of an FE point
    force: bool = False   # a plan of more than MAX_POINTS points


def options(given: dict) -> Options:
    """The command line's options validated; a broken rule is one InputError line
    `--option: rule`."""
    try:
        return Options.model_validate({k: v for k, v in given.items() if v is not None})
    except pydantic.ValidationError as err:
        first = err.errors()[0]
        option = "--" + str(first["loc"][0]).replace("_", "-") if first["loc"] else "options"
        raise InputError(f"{option}: {first['msg'].removeprefix('Value error, ')}") from None


def inputs(study_file) -> list[Path]:
    """The files a study reads: itself, its base scene and the files that names (none when
    the study cannot be read: running it says why)."""
    path = Path(study_file)
    try:
        base = path.parent / scenes.read_toml(path)["base"]
    except (InputError, KeyError, TypeError):
        return [path]
    return [path, base, *scenes.referenced_files(base)]


# ---- the study file and its points

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




def value_labels(study: Study, rows: int) -> list[tuple[str, ...]]:
    """Per row of the plan (`matrix`, `rows` rows), the labels of its parameters' values (""
    where a parameter has none, and for random plans)."""
    specs = list(study.parameters.values())
    if study.sampling.method != "grid" or not specs:
        return [("",) * len(specs)] * rows
    counts = [len(p.values) if p.values is not None else p.grid.num for p in specs]
    index = uq.grid([range(n) for n in counts]).astype(int)
    return [tuple(p.labels[k] if p.labels else "" for p, k in zip(specs, row)) for row in index]


MAX_POINTS = 100_000   # a plan's points before it is built (each a scene in memory), unless --force


def planned_points(study: Study) -> int:
    """The points the study's plan has, counted before it is built: a grid's values and cases
    multiplied, a random plan's points (saltelli: N (d + 2))."""
    s = study.sampling
    if s.method != "grid":
        return s.points * (len(study.parameters) + 2 if s.method == "saltelli" else 1)
    count = 1
    for p in study.parameters.values():
        count *= len(p.values) if p.values is not None else p.grid.num
    for cases in study.cases.values():
        count *= len(cases)
    return count


def matrix(study: Study) -> np.ndarray:
    """The plan: one row per point, one column per parameter (in the study's order)."""
    specs = list(study.parameters.values())
    s = study.sampling
    if s.method == "grid" and not specs:
        return np.zeros((1, 0))   # the cases alone: one row of no parameter
    if s.method == "grid":
        return uq.grid([p.values if p.values is not None else p.grid.values() for p in specs])
    return uq.plan(s.method, [p.distribution.frozen() for p in specs], s.points, s.seed)


class Plan:
    """The study's points: the plan's values and each point's validated scene data."""

    def __init__(self, path: Path, study: Study):
        self.path, self.study = Path(path), study
        self.base_path = (self.path.parent / study.base)
        base = scenes.read_toml(self.base_path)
        source = str(self.base_path)
        for key, value in study.set.items():
            try:
                put(base, key, value, create=True)
            except KeyError as err:
                raise InputError(f"{path}: set.{key}: {err.args[0]}") from None
        self.stage, base = of_scene(base, source)
        self.stage.validate(base, f"{path}: the base scene {source} with [set]")
        self.names = list(study.parameters)
        for name in self.names:
            try:
                put(json.loads(json.dumps(base)), name, 0.0, absent=ABSENT)
            except KeyError as err:
                raise InputError(f"{path}: parameters.{name}: {err.args[0]}") from None
        groups = list(study.cases)
        rows = matrix(study)
        row_labels = value_labels(study, len(rows))
        values, self.cases, self.point_names, self.scenes = [], [], [], []
        for combo in itertools.product(*(study.cases[g] for g in groups)):
            for row, labels in zip(rows, row_labels):
                data = json.loads(json.dumps(base))
                for group, case in zip(groups, combo):
                    for key, value in case.settings.items():
                        try:
                            put(data, key, value, create=True)
                        except KeyError as err:
                            raise InputError(f"{path}: cases.{group}.{case.label}: {err.args[0]}") from None
                for name, value in zip(self.names, row):
                    put(data, name, float(value))
                where = ", ".join([f"{g} = {c.label}" for g, c in zip(groups, combo)]
                                  + [f"{n} = {v:.6g}" for n, v in zip(self.names, row)])
                self.stage.validate(data, f"{path}: point {len(self.scenes)} ({where})")
                values.append(row)
                self.cases.append({g: c.label for g, c in zip(groups, combo)})
                self.point_names.append("_".join(
                    part for part in (study.name_prefix, *(c.label for c in combo), *labels) if part))
                self.scenes.append(data)
        self.values = np.array(values)
        labelled = bool(groups) or any(p.labels for p in study.parameters.values())
        if not labelled:
            self.point_names = ["_".join(part for part in (study.name_prefix, f"point{i:04d}") if part)
                                for i in range(len(self.scenes))]
        seen = {}
        for i, name in enumerate(self.point_names):
            if name in seen:
                raise InputError(f"{path}: points {seen[name]} and {i} share the name {name!r}: label "
                                 "the values of every parameter that varies (parameters.<key>.labels)")
            seen[name] = i
        self.check_collect()
        self.columns = [(c.name, c.column, c.statistic, c.window_s)
                        for c in study.collect if c.column is not None]
        files = digest_files([*scenes.referenced_files(self.base_path),
                              *named_files(self.scenes, self.base_path.parent)])
        code = (code_hash(*point_code(self.stage.name))
                + hashlib.sha256(inspect.getsource(Point).encode()).hexdigest())
        self.keys = sweep.point_keys(self.stage.name, self.scenes, files, code, self.columns)

    def check_collect(self) -> None:
        """A mechanism's summary (a stage whose points have time series) is known before the
        run: every collected path must name one of its keys (a joint by its name), and a
        column must begin with the name of one of its bodies, clearance joints or output
        points (its whole name is checked in the run, whose columns it is). Columns are a
        mechanism's only."""
        columns = [(i, c) for i, c in enumerate(self.study.collect) if c.column is not None]
        if not self.stage.series:
            if columns:
                raise InputError(f"{self.path}: collect.{columns[0][0]}.column: only a "
                                 f"mechanism's time series has columns (this base is a "
                                 f"{self.stage.name} scene)")
            return
        from pinbore.reduced.mechanism.summary import JointPeaks, Summary   # noqa: PLC0415
        scene = self.scenes[0]
        joints = {j["name"] for j in scene.get("clearance_joints", [])} | \
                 {j["name"] for j in scene.get("translational_joints", [])}
        stems = {b["name"] for b in scene.get("bodies", [])} | joints | \
                {f"{p['body']}_{p['name']}" for p in scene.get("output", {}).get("points", [])}
        for i, c in columns:
            if not any(c.column.startswith(f"{stem}_") for stem in stems):
                raise InputError(f"{self.path}: collect.{i}.column: {c.column!r} is no column of "
                                 "the mechanism's time series (a column begins with a body, "
                                 f"clearance joint or output point: {', '.join(sorted(stems))})")
            durations = [d["duration"] for d in self.scenes if isinstance(d.get("duration"), (int, float))]
            if c.window_s is not None and durations and c.window_s[0] >= min(durations):
                raise InputError(f"{self.path}: collect.{i}.window_s: starts at {c.window_s[0]:g} s, "
                                 f"after the shortest run's end ({min(durations):g} s): no sample in it")
        for i, c in enumerate(self.study.collect):
            if c.path is None:
                continue
            parts = c.path.split(".")
            ok = parts[0] in Summary.model_fields
            if ok and parts[0] == "clearance_joints":
                ok = len(parts) == 3 and parts[1] in joints and parts[2] in JointPeaks.model_fields
            elif ok and parts[0] == "energy_balance":
                ok = len(parts) == 2
            elif ok:
                ok = len(parts) == 1
            if not ok:
                raise InputError(f"{self.path}: collect.{i}.path: {c.path!r} is no number of a "
                                 "mechanism's summary.json (e.g. clearance_joints.<joint name>."
                                 "peak_normal_force_N, impacts, energy_balance.dissipated_J)")


def point_scene(study_file, name: str, out=None) -> dict:
    """The scene data of the point `name` of a study (validated), e.g. one calibration curve's
    FE scene; with `out`, also written there as a TOML scene file (the names of files it
    refers to made absolute)."""
    path = Path(study_file)
    plan = Plan(path, load(path))
    if name not in plan.point_names:
        raise InputError(f"{path}: no point named {name!r} (points: {', '.join(plan.point_names)})")
    data = plan.scenes[plan.point_names.index(name)]
    if out is not None:
        scenes.write_scene(out, data, plan.base_path.parent)
    return data


# ---- one point, in a worker

class Point:
    """Runs one point's scene data in this process through its stage's point function
    (pinbore.stages: Stage.point) and returns {"status", "reason", "seconds", "result"}:
    status "complete", "suspect" (the run's verdict doubts it), "incomplete" (it stopped
    early) or "failed" (an error; reason says which)."""

    def __init__(self, stage: str, base: Path, source: str, columns=(), ranks: int = 1):
        # the base scene's folder, absolute where the study starts (a worker may run elsewhere)
        self.stage, self.base, self.source = stage, Path(base).absolute(), source
        self.columns = list(columns)   # (name, column, statistic, window) of a mechanism's series
        self.ranks = ranks             # of a point of an MPI stage: mpiexec -n ranks pinbore <stage>

    def __call__(self, data: dict) -> dict:
        start = time.perf_counter()
        try:
            status, reason, result = resolve(STAGE[self.stage].point)(data, self)
        except Exception as err:   # noqa: BLE001 (a point that fails is marked, the study goes on)
            status, reason, result = "failed", f"{type(err).__name__}: {err}", {}
        return {"status": status, "reason": reason, "seconds": time.perf_counter() - start,
                "result": result}

    def series(self, steps: dict) -> dict:
        """The statistics of the collected columns of a time series (name -> value)."""
        out = {}
        for name, column, statistic, window in self.columns:
            if column not in steps:
                raise KeyError(f"column {column!r}: not in the time series (columns: "
                               f"{', '.join(k for k in steps if k != 'time_s')})")
            out[name] = column_statistic(steps["time_s"], steps[column], statistic, window)
        return out

    def in_folder(self, data, read):
        """Run the stage's command on the point's scene, written as a scene file in a
        temporary folder (core.scene.scene_file: names of files made absolute), and read
        its result from the folder it wrote: read(out) -> dict."""
        with scenes.scene_file(data, self.base, f"{self.source} (a point's scene)") as path:
            out = path.parent / "out"
            code = self._run(path, out)
            if not out.is_dir():
                return "failed", f"the run wrote nothing (exit {code})", {}
            result = read(out)
            result["files"] = {f.name: f.read_text() for f in sorted(out.iterdir())
                               if f.suffix in KEPT_SUFFIXES}
        if code == 0:
            return "complete", "", result
        status = result.get("status") if result.get("status") in ("incomplete", "suspect") else "failed"
        reason = "; ".join(result.get("verdict") or []) or str(result.get("stop") or f"exit {code}")
        return status, reason, result

    def _run(self, path: Path, out: Path) -> int:
        """The stage's command on the scene file, in process or, with ranks, as `pinbore
        <stage>` on that many MPI processes (MPICH's mpiexec beside this Python, as the venv
        has it, else on PATH); its exit code."""
        if self.ranks == 1:
            return STAGE[self.stage].run_scene(path, out)
        mpiexec = Path(sys.executable).parent / "mpiexec"
        command = [str(mpiexec) if mpiexec.exists() else "mpiexec", "-n", str(self.ranks),
                   sys.executable, "-m", "pinbore.cli", self.stage, str(path), "--out", str(out)]
        return subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode


# ---- the command

def command(args) -> int:
    """`pinbore study` on its parsed arguments (pinbore.stages)."""
    given = {"out": args.out, "workers": args.workers, "ranks": args.ranks,
             "scheduler": args.scheduler, "cache": args.cache, "force": args.force}
    return run(args.study, options(given))


def run(study_file, options: Options) -> int:
    """`pinbore study`: validate the study and every point, run them (cached), write the
    outputs. 0, or 1 when a point failed (the others are kept)."""
    path = Path(study_file)
    study = load(path)
    if (count := planned_points(study)) > MAX_POINTS and not options.force:
        raise InputError(f"{path}: the plan has {count:.3g} points, more than {MAX_POINTS:,} (each a "
                         "scene in memory before the first runs): fewer values or sampling.points, "
                         "or --force")
    plan = Plan(path, study)
    if options.ranks > 1 and not plan.stage.mpi:
        raise InputError(f"--ranks: MPI ranks run FE points (pinbore fem); {path}'s points are "
                         f"{plan.stage.name} runs, which run on one process")
    inputs = [path, plan.base_path, options.cache, *named_files(plan.scenes, plan.base_path.parent)]
    # --out is checked against every file a point reads, and locked, before the points run
    with atomic_directory(options.out, inputs=inputs) as tmp:
        start = time.perf_counter()
        task = Point(plan.stage.name, plan.base_path.parent, str(plan.base_path), plan.columns, options.ranks)
        records, fresh = sweep.run(task, plan.scenes, plan.keys, options, desc="study")
        wall = time.perf_counter() - start
        rows = table(plan, records, fresh)
        write_results(tmp / "results.csv", plan, rows)
        parquet = write_parquet(tmp / "results.parquet", plan, rows) if len(rows) >= PARQUET_ROWS else None
        for name, record in zip(plan.point_names, records):
            if record["result"].get("files"):
                (tmp / "points" / name).mkdir(parents=True)
                for file, text in record["result"]["files"].items():
                    (tmp / "points" / name / file).write_text(text)
        stats = statistics(plan, rows)
        (tmp / "statistics.json").write_text(json.dumps(stats, indent=2) + "\n")
        if study.sampling.method != "grid":   # a grid's points are chosen, not drawn
            figures_of(tmp, plan, rows, stats)
        failed = [r for r in rows if r["status"] != "complete"]
        summary = {"study_file": str(path), "base": str(plan.base_path), "stage": plan.stage.name,
                   "points": len(rows), "ran": sum(fresh), "from_cache": len(rows) - sum(fresh),
                   "complete": len(rows) - len(failed), "failed": len(failed),
                   "wall_time_s": wall, "point_seconds": sum(r["seconds"] for r in rows if r["ran"]),
                   "cache": str(options.cache)}
        if parquet is not None:
            summary["parquet"] = parquet
        if study.tolerance is not None:
            answer = tolerance(plan, rows)
            (tmp / "tolerance.json").write_text(json.dumps(answer, indent=2) + "\n")
            tolerance_figure(tmp / "tolerance.png", answer)
            summary["tolerance_half_width"] = answer["half_width"]
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    if failed:
        print(f"pinbore study: {path}: {len(failed)} of {len(rows)} points did not complete "
              f"(first: point {failed[0]['point']}: {failed[0]['status']}: {failed[0]['reason']}); "
              f"see {options.out}/results.csv", file=sys.stderr)
        return 1
    return 0


def table(plan: Plan, records: list[dict], fresh: list[bool]) -> list[dict]:
    """One row per point: its values, status, reason, quantities, whether it ran now."""
    rows = []
    for i, (values, record, ran, key) in enumerate(zip(plan.values, records, fresh, plan.keys)):
        row = {"point": i, "name": plan.point_names[i], **plan.cases[i],
               **dict(zip(plan.names, map(float, values))),
               "status": record["status"], "reason": record["reason"], "ran": ran,
               "seconds": record["seconds"], "key": key[:16]}
        for c in plan.study.collect:
            try:
                row[c.name] = float(get(record["result"], c.where))
            except (KeyError, TypeError, ValueError):
                row[c.name] = math.nan
                if row["status"] == "complete":
                    row["status"], row["reason"] = "failed", f"{c.where}: not in the result"
        rows.append(row)
    return rows


def results_header(plan: Plan) -> list[str]:
    return ["point", "name", *plan.study.cases, *plan.names, *(c.name for c in plan.study.collect),
            "status", "reason", "ran", "seconds", "key"]


def write_results(path: Path, plan: Plan, rows: list[dict]) -> None:
    from pinbore.reduced.dynamics.plots import write_table   # noqa: PLC0415

    header = results_header(plan)
    write_table(path, header, [[r[h] for h in header] for r in rows])


def write_parquet(path: Path, plan: Plan, rows: list[dict]) -> str:
    """The results table as Parquet (the columns of results.csv: the point an int64, ran a
    bool, the parameters, quantities and seconds float64, the rest strings), written with
    pyarrow (the optional extra `parquet`, in requirements.lock); without pyarrow, nothing is
    written and the answer says why."""
    try:
        import pyarrow as pa   # noqa: PLC0415
        import pyarrow.parquet as pq   # noqa: PLC0415
    except ImportError:
        print(f"pinbore study: {len(rows)} points: results.parquet not written (pyarrow is not "
              "installed: pip install 'pinbore[parquet]'); results.csv has the same table", file=sys.stderr)
        return "not written: pyarrow is not installed"
    numbers = {*plan.names, *(c.name for c in plan.study.collect), "seconds"}
    columns = {}
    for h in results_header(plan):
        values = [r[h] for r in rows]
        if h == "point":
            columns[h] = pa.array(values, type=pa.int64())
        elif h == "ran":
            columns[h] = pa.array(values, type=pa.bool_())
        elif h in numbers:
            columns[h] = pa.array(values, type=pa.float64())
        else:
            columns[h] = pa.array([str(v) for v in values], type=pa.string())
    pq.write_table(pa.table(columns), path)
    return path.name


def complete(rows, name) -> np.ndarray:
    return np.array([r[name] for r in rows if r["status"] == "complete"], dtype=float)


def sampled(plan: Plan, rows: list[dict]) -> list[dict]:
    """The rows the statistics and their figures take: every point, but of a Saltelli plan
    only the blocks A and B (its blocks AB_i repeat their coordinates, and the intervals count
    independent draws)."""
    return rows[:2 * plan.study.sampling.points] if plan.study.sampling.method == "saltelli" else rows


def statistics(plan: Plan, rows: list[dict]) -> dict:
    """Per quantity: uq.describe over the complete points; the limit's exceedance; Sobol
    indices for a saltelli plan (every point must be complete: a hole breaks the blocks)."""
    study, conf = plan.study, plan.study.confidence
    out = {"confidence": conf, "method": study.sampling.method,
           "complete_points": sum(r["status"] == "complete" for r in rows), "points": len(rows),
           "quantities": {}}
    sample = sampled(plan, rows)
    if study.sampling.method == "saltelli":
        out["statistics_of"] = "the A and B blocks of the Saltelli plan"
    for c in study.collect:
        y = complete(sample, c.name)
        out["quantities"][c.name] = uq.describe(y, conf) if len(y) else {"points": 0}
    if study.limit is not None and out["complete_points"]:
        lim = study.limit
        e = uq.exceedance(complete(sample, lim.quantity), lim.threshold, conf)
        upper = uq.clopper_pearson(e.exceeding, e.points, conf, "upper")[1]
        out["limit"] = {"quantity": lim.quantity, "threshold": lim.threshold, "target": lim.target,
                        "probability": e.probability, "interval": [e.low, e.high],
                        "exceeding": e.exceeding, "points": e.points, "upper_bound": upper,
                        "meets_target": upper <= lim.target}
    if study.surrogate is not None:
        out["surrogate"] = surrogates(plan, rows)
    if study.sampling.method == "saltelli":
        out["sobol"] = {}
        if out["complete_points"] == len(rows):
            for c in study.collect:
                s = uq.sobol([r[c.name] for r in rows], len(plan.names), conf, seed=study.sampling.seed)
                out["sobol"][c.name] = {
                    name: {"first": s["first"][j], "first_interval": s["first_interval"][j].tolist(),
                           "total": s["total"][j], "total_interval": s["total_interval"][j].tolist()}
                    for j, name in enumerate(plan.names)}
        else:
            out["sobol_missing"] = "not every point completed: the Saltelli blocks have holes"
    return json.loads(json.dumps(out, default=float))


def surrogates(plan: Plan, rows: list[dict]) -> dict:
    """Per quantity, the polynomial chaos (core.uq.chaos) of the complete points, each
    parameter's value mapped to the unit interval by its distribution's CDF: the leave-one-out
    error (of the variance), mean, standard deviation and Sobol indices by parameter."""
    dists = [p.distribution.frozen() for p in plan.study.parameters.values()]
    done = [i for i, r in enumerate(rows) if r["status"] == "complete"]
    u = np.column_stack([d.cdf(plan.values[done, j]) for j, d in enumerate(dists)])
    out = {}
    for c in plan.study.collect:
        y = np.array([rows[i][c.name] for i in done], dtype=float)
        try:
            fit = uq.chaos(u, y, plan.study.surrogate.degree)
        except ValueError as err:
            out[c.name] = {"missing": str(err)}
            continue
        out[c.name] = {"degree": plan.study.surrogate.degree, "terms": len(fit.indices),
                       "points": len(y), "loo_error": fit.loo_error, "mean": fit.mean,
                       "std": math.sqrt(fit.variance),
                       "first": dict(zip(plan.names, fit.first.tolist())),
                       "total": dict(zip(plan.names, fit.total.tolist()))}
    return out


def tolerance(plan: Plan, rows: list[dict]) -> dict:
    """The widest band of the tolerance's parameter that meets its target (uq.tolerance_band)
    over the complete points."""
    t = plan.study.tolerance
    d = plan.study.parameters[t.parameter].distribution
    ok = [r for r in rows if r["status"] == "complete"]
    answer = uq.tolerance_band([r[t.parameter] for r in ok], [r[t.limit.quantity] for r in ok],
                               0.5 * (d.low + d.high), 0.5 * (d.high - d.low), t.limit.threshold,
                               t.target, t.confidence)
    return {"parameter": t.parameter, "centre": 0.5 * (d.low + d.high), "quantity": t.limit.quantity,
            "threshold": t.limit.threshold, "target": t.target, "confidence": t.confidence,
            "method": "the sampled points inside each narrower band (independent uniform draws "
                      "over it); one-sided Clopper-Pearson upper bound <= target", **answer}


# ---- figures

def figures_of(folder: Path, plan: Plan, rows: list[dict], stats: dict) -> None:
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    names = [c.name for c in plan.study.collect]
    conf = plan.study.confidence
    rows = sampled(plan, rows)
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.5), squeeze=False)
    for ax, name in zip(axes[0], names):
        y = complete(rows, name)
        if len(y):
            ax.hist(y, bins=max(5, min(50, int(math.sqrt(len(y))))), color="tab:blue", alpha=0.8)
            ax.axvline(stats["quantities"][name]["mean"], color="k", label="mean")
        ax.set_xlabel(name)
        ax.set_ylabel("points")
    save_png(fig, folder / "histograms.png", layout=True)
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.5), squeeze=False)
    for ax, name in zip(axes[0], names):
        y = complete(rows, name)
        if len(y):
            curve = uq.exceedance_curve(y, conf)
            ax.step(curve[:, 0], curve[:, 1], where="post", label="P(Y > y)")
            ax.fill_between(curve[:, 0], curve[:, 2], curve[:, 3], step="post", alpha=0.3,
                            label=f"{conf:.0%} Clopper-Pearson")
            ax.set_yscale("log")
        lim = plan.study.limit
        if lim is not None and lim.quantity == name:
            ax.axvline(lim.threshold, color="r", ls="--")
            ax.axhline(lim.target, color="r", ls=":")
        ax.set_xlabel(name)
        ax.set_ylabel("exceedance probability")
        ax.legend(fontsize=7)
    save_png(fig, folder / "exceedance.png", layout=True)
    if stats.get("sobol"):
        sobol_outputs(folder, plan, stats["sobol"], plt, save_png)


def sobol_outputs(folder, plan, sobol, plt, save_png) -> None:
    from pinbore.reduced.dynamics.plots import write_table   # noqa: PLC0415

    write_table(folder / "sobol.csv", ["quantity", "parameter", "first", "first_low", "first_high",
                                       "total", "total_low", "total_high"],
                [[q, p, s["first"], *s["first_interval"], s["total"], *s["total_interval"]]
                 for q, by in sobol.items() for p, s in by.items()])
    fig, axes = plt.subplots(1, len(sobol), figsize=(5 * len(sobol), 3.5), squeeze=False)
    x = np.arange(len(plan.names))
    for ax, (q, by) in zip(axes[0], sobol.items()):
        for shift, order in ((-0.2, "first"), (0.2, "total")):
            v = np.array([by[p][order] for p in plan.names])
            ci = np.array([by[p][f"{order}_interval"] for p in plan.names])
            ax.bar(x + shift, v, 0.4, yerr=[v - ci[:, 0], ci[:, 1] - v], capsize=3, label=order)
        ax.set_xticks(x, plan.names, rotation=20, fontsize=7)
        ax.set_title(q)
        ax.legend()
    save_png(fig, folder / "sobol.png", layout=True)


def tolerance_figure(path: Path, answer: dict) -> None:
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(5, 3.5))
    if answer["curve"]:
        c = np.array(answer["curve"], dtype=float)
        ax.plot(c[:, 0], c[:, 3], label="upper bound on P(exceed)")
    ax.axhline(answer["target"], color="r", ls=":", label="target")
    if answer["half_width"] is not None:
        ax.axvline(answer["half_width"], color="k", ls="--", label="largest band")
    ax.set_xlabel(f"half-width of {answer['parameter']}")
    ax.set_yscale("log")
    ax.legend(fontsize=7)
    save_png(fig, path, layout=True)


# ---- the report's section on the studies under build/study (make study)
CHAOS_HOLDS = 0.05   # a chaos whose leave-one-out error is above this share of the variance misses
                    # more than a twentieth of it: its indices are not shown as an answer


def _studies(build_dir: Path) -> list[Path]:
    return sorted(p.parent for p in (Path(build_dir) / "study").glob("*/summary.json"))


def answers(build_dir: Path) -> list[tuple[str, str]]:
    """The report's first screen: each study's [limit] (the exceedance probability with its
    interval, against its target) and [tolerance] (the widest band) answers."""
    out = []
    for folder in _studies(build_dir):
        stats = json.loads((folder / "statistics.json").read_text())
        limit = stats.get("limit")
        if limit:
            low, high = limit["interval"]
            out.append((f"P({limit['quantity']} &gt; {limit['threshold']:.4g}), {folder.name}",
                        f"{limit['probability']:.3f} [{low:.3f}, {high:.3f}] against a target of "
                        f"{limit['target']:g}: {'met' if limit['meets_target'] else 'not shown to be met'} "
                        f"({limit['points']} points, {stats['confidence']:.0%} confidence)"))
        for quantity, indices in stats.get("sobol", {}).items():
            name, top = max(indices.items(), key=lambda item: item[1]["total"])
            low, high = top["total_interval"]
            out.append((f"What drives {quantity}, {folder.name}",
                        f"{name}: total-order Sobol index {top['total']:.2f} [{low:.2f}, {high:.2f}] "
                        f"(first order {top['first']:.2f}; of {len(indices)} inputs)"))
        for quantity, c in stats.get("surrogate", {}).items():
            if "total" not in c:
                continue
            name = max(c["total"], key=c["total"].get)
            held = c["loo_error"] <= CHAOS_HOLDS
            out.append((f"What drives {quantity}, {folder.name} (polynomial chaos)",
                        f"{name}: total-order Sobol index {c['total'][name]:.2f} (first order "
                        f"{c['first'][name]:.2f}); the chaos's leave-one-out error "
                        f"{c['loo_error']:.1g} of the variance"
                        + ("" if held else ": the chaos does not hold, nor its indices")))
        if (folder / "tolerance.json").exists():
            t = json.loads((folder / "tolerance.json").read_text())
            band = (f"&plusmn;{t['half_width']:.3g} about {t['centre']:.4g}" if t["half_width"]
                    else "no band of the sample")
            out.append((f"Tolerance of {t['parameter']}, {folder.name}",
                        f"{band} keeps P({t['quantity']} &gt; {t['threshold']:.4g}) &le; "
                        f"{t['target']:g} with {t['confidence']:.0%} confidence "
                        f"({t['exceeding_in_band']} of {t['points_in_band']} points in it above)"))
    return out


def section(build_dir: Path, bench_dir: Path) -> str:
    """Each study's statistics (mean, spread and quantiles with their intervals), its
    figures and its answers."""
    import html as markup   # noqa: PLC0415

    from pinbore.core.html import figure, note, png_data, table   # noqa: PLC0415

    parts = ["<h2>Studies: uncertainty and tolerance</h2>",
             "<p>A scene run over a sample of its inputs (<code>pinbore study</code>): the "
             "statistics of each collected quantity with their confidence intervals, the "
             "exceedance of a limit, Sobol indices and the tolerance band (docs/study.md).</p>"]
    studies = _studies(build_dir)
    if not studies:
        return "".join(parts) + note("No studies under build/study: run <code>make study</code>.")
    for folder in studies:
        s = json.loads((folder / "summary.json").read_text())
        stats = json.loads((folder / "statistics.json").read_text())
        parts.append(f"<h3>{markup.escape(folder.name)}</h3><p>{s['complete']} of {s['points']} "
                     f"points complete ({stats['method']}), base scene "
                     f"<code>{markup.escape(str(s['base']))}</code>.</p>")
        if stats["method"] == "grid":   # chosen points: their table, not a distribution
            results = list(csv.DictReader((folder / "results.csv").read_text().splitlines()))
            quantities = list(stats["quantities"])
            parts.append(table(["point", *quantities, "status"],
                               [[r["name"], *(f"{float(r[q]):.5g}" for q in quantities), r["status"]]
                                for r in results]))
            continue
        untrusted = set()

        def shown(name, value, spec):   # a statistic as the page shows it
            if isinstance(value, (int, float)) and math.isfinite(value):
                return format(value, spec)
            untrusted.add(name)
            return "not finite"

        rows = [[name, f"{shown(name, q['mean'], '.4g')} [{shown(name, q['mean_interval'][0], '.4g')}, "
                 f"{shown(name, q['mean_interval'][1], '.4g')}]",
                 shown(name, q["std"], ".3g"), shown(name, q["q05"], ".4g"), shown(name, q["q50"], ".4g"),
                 f"{shown(name, q['q95'], '.4g')} [{shown(name, q['q95_interval'][0], '.4g')}, "
                 f"{shown(name, q['q95_interval'][1], '.4g')}]"]
                for name, q in stats["quantities"].items()]
        parts.append(table(["quantity", f"mean [{stats['confidence']:.0%}]", "std", "5 %",
                            "median", f"95 % quantile [{stats['confidence']:.0%}]"], rows))
        if untrusted:
            parts.append(note(f"Not finite in statistics.json, so not shown as results: "
                              f"{markup.escape(', '.join(sorted(untrusted)))} (an interval of "
                              "too few points is not finite; otherwise the file was changed "
                              "or a point's value is not a number)."))
        if "statistics_of" in stats:
            parts.append(f"<p>Statistics of {stats['statistics_of']}.</p>")
        sobol = [[quantity, name, f"{i['first']:.2f} [{i['first_interval'][0]:.2f}, {i['first_interval'][1]:.2f}]",
                  f"{i['total']:.2f} [{i['total_interval'][0]:.2f}, {i['total_interval'][1]:.2f}]"]
                 for quantity, indices in stats.get("sobol", {}).items() for name, i in indices.items()]
        if sobol:
            parts.append(table(["quantity", "input", f"first order [{stats['confidence']:.0%}]",
                                f"total order [{stats['confidence']:.0%}]"], sobol))
        chaos = [[quantity, f"{c['degree']} ({c['terms']} terms)", f"{c['loo_error']:.2g}",
                  f"{c['mean']:.4g} ± {c['std']:.3g}",
                  ", ".join(f"{markup.escape(n)} {c['first'][n]:.2f} / {c['total'][n]:.2f}" for n in c["first"])]
                 for quantity, c in stats.get("surrogate", {}).items() if "degree" in c]
        if chaos:
            parts.append(table(["quantity", "chaos degree", "leave-one-out error / variance",
                                "mean ± std", "Sobol indices, first / total order"], chaos))
        for png, caption in (("histograms.png", "histograms of the collected quantities"),
                             ("exceedance.png", "exceedance curve: P(quantity > x)"),
                             ("sobol.png", "Sobol indices, first and total order"),
                             ("tolerance.png", "the exceedance's upper bound against the band")):
            if (folder / png).exists():
                parts.append(figure(png_data(folder / png), f"{markup.escape(folder.name)}: {caption}."))
    return "".join(parts)
