"""A study's plan: the matrix of its points' parameter values, their labels and names, each
point's validated scene data and cache key (`Plan`), and one point's scene (`point_scene`)."""

import hashlib
import inspect
import itertools
import json
from pathlib import Path

import numpy as np

from pinbore.core import scene as scenes
from pinbore.core import sweep, uq
from pinbore.core.codedeps import code_hash
from pinbore.core.errors import InputError
from pinbore.core.sweep import digest_files, named_files, put
from pinbore.stages import of_scene
from pinbore.study import point as point_module
from pinbore.study.point import Point, point_code
from pinbore.study.schema import Study, load

# a parameter's key the base scene does not have
ABSENT = (f"{sweep.ABSENT} (a key its default leaves out, such as a flexible body's modes, is "
          "given a value under [set] first)")


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
                + hashlib.sha256(inspect.getsource(point_module).encode()).hexdigest())
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
