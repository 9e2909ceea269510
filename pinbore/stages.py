"""The stages of pinbore, in one registry: what each `pinbore` command runs, the scene kinds it
takes and their models, the files it reads and writes, its typed result, how a study point
runs it and what it adds to the report. The command line (pinbore.cli), the Python API
(pinbore.api), the study (pinbore.study), the report (pinbore.report) and make's dependencies
(pinbore.core.codedeps, which reads this module with `ast`) all read STAGES; none of them
branches on a stage's or a kind's name.

A stage names its code by string, "module:name", loaded when it runs: validating a scene
imports its model's module alone (pydantic), so bad input answers before DOLFINx, Gmsh or
matplotlib load. A scene stage's runner is `run(scene_path, out) -> exit code`; a command
with options of its own (its `arguments` in pinbore.cli) runs `run(args)` on its parsed
arguments. A stage added is one entry of STAGES.
"""

import importlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.scene import referenced_files


def resolve(entry: str):
    """The object an entry names: "module:name" (name dotted for an attribute of one)."""
    module, _, name = entry.partition(":")
    found = importlib.import_module(module)
    for part in name.split("."):
        found = getattr(found, part)
    return found


@dataclass(frozen=True)
class Section:
    """A section of the report: its heading and the function that writes it from what its
    stage wrote, f(build_dir, bench_dir) -> HTML."""

    heading: str
    function: str


@dataclass(frozen=True)
class Stage:
    """A stage: a `pinbore` command, and what the API, the study, the report and make know of
    it. A scene stage (one with a model) reads one scene file; the runner validates it again,
    as it does when called from Python."""

    name: str                          # the command: `pinbore <name>`
    summary: str                       # its line in `pinbore --help`
    description: str                   # its `--help`
    run: str                           # scene stage: run(scene_path, out); else run(args)
    inputs: Callable                   # args -> the files it reads (which --out may not hold)
    outputs: tuple[str, ...] = ()      # the files it always writes in --out
    model: str | None = None           # a scene stage's model: a pydantic class, or a
                                       # function (data, source) -> scene
    kinds: tuple[str, ...] = ()        # the scene kinds that run through this stage
    kindless: str | None = None        # a scene of its kind has no `kind`, but this table
    arguments: str | None = None       # pinbore.cli's function that adds its own options
    result: tuple[str, str] | None = None   # (file in out, its reader): pinbore.run's answer
    point: str | None = None           # a study point: f(data, study.Point) -> (status, reason, result)
    series: bool = False               # a point's result has time series to collect from
    mpi: bool = False                  # its points may run on MPI ranks (study --ranks)
    sections: tuple[Section, ...] = ()   # its sections of the report
    answers: tuple[str, ...] = ()      # f(build_dir) -> [(question, answer HTML)], the first screen
    uses: tuple[str, ...] = ()         # the fields of every stage whose code it runs too (a point:
                                       # its model, runner and point function)

    @property
    def takes_scene(self) -> bool:
        """Whether its command reads one scene file (its arguments: SCENE --out DIR)."""
        return self.model is not None

    def validate(self, data: dict, source: str):
        """The scene of the data, validated by the stage's model (one InputError line)."""
        model = resolve(self.model)
        if isinstance(model, type):
            return scenes.validate(model, scenes.normal_kind(data, source), source)
        return model(data, source)

    def load(self, path):
        """Read and validate a scene file of this stage."""
        return self.validate(scenes.read_toml(path), str(path))

    def run_scene(self, scene_path, out) -> int:
        """Validate the scene, then load the runner and run it (its exit code)."""
        self.load(scene_path)
        return resolve(self.run)(scene_path, out)

    def command(self, args) -> int:
        """`pinbore <name>` on its parsed arguments."""
        return self.run_scene(args.scene, args.out) if self.takes_scene else resolve(self.run)(args)

    def read_result(self, out):
        """The typed result the stage wrote in `out`."""
        file, reader = self.result
        return resolve(reader)(Path(out) / file)


# ---- what a command reads

def _scene_inputs(args) -> list:
    """A scene and every file it names (its laws file, ...)."""
    return [args.scene, *referenced_files(args.scene)]


def _wear_inputs(args) -> list:
    """A wear scene, the files it names, the result.json beside its FE curve and the files
    its mechanism scene names."""
    files = _scene_inputs(args)
    try:
        data = scenes.read_toml(args.scene)
    except InputError:
        return files   # reading it for the run says why
    for key, path in (("curve_file", "result.json"), ("mechanism_file", None)):
        if isinstance(data.get(key), str):
            (named,) = scenes.named_files({key: data[key]}, Path(args.scene).parent)
            files += [named.parent / path] if path else referenced_files(named)
    return files


def _calibrate_inputs(args) -> list:
    return [*args.curves, *args.impacts]


def _export_inputs(args) -> list:
    return [args.laws, *([args.scene, *referenced_files(args.scene)] if args.scene else [])]


def _study_inputs(args) -> list:
    """A study file, its base scene and every file that names (pinbore.study, which reads
    this registry: loaded by name)."""
    return resolve("pinbore.study.schema:inputs")(args.study)


def _report_inputs(args) -> list:
    return [args.build, "bench"]


# ---- the commands with options of their own

def calibrate(args) -> int:
    from pinbore.calibration import run   # noqa: PLC0415

    return run.run(args.curves, args.out, args.length, args.per_length, args.impacts)


def dynamics(args) -> int:
    """Validate the options of the chosen analysis (its model in the table of analyses),
    then run it with them."""
    from pinbore.reduced.dynamics import analyses, studies   # noqa: PLC0415

    model, _ = studies.ANALYSES[args.analysis]
    return studies.run(args.scene, args.analysis, analyses.parse(model, options_given(args), args.analysis))


def options_given(args) -> dict:
    """The options given to `pinbore dynamics`, keyed by their model's field names (an option
    left out is absent from `args`); an option of several values as a tuple."""
    skip = {"command", "scene", "analysis"}
    return {name: tuple(value) if isinstance(value, list) else value
            for name, value in vars(args).items() if name not in skip}


def export(args) -> int:
    from pinbore import export as exporting   # noqa: PLC0415

    return exporting.run(args.laws, args.to, args.out, args.scene, args.joint, args.law)


# ---- a study point of each stage (pinbore.study.point.Point: in_folder, series)

def fem_point(data, point):
    """result.json, with the last row of curve.csv under `curve_last`."""
    def read(out):
        result = json.loads((out / "result.json").read_text())
        rows = (out / "curve.csv").read_text().splitlines()
        result["curve_last"] = {k: float(v) for k, v in zip(rows[0].split(","), rows[-1].split(","))
                                if k != "stage"}
        return result
    return point.in_folder(data, read)


def impact_point(data, point):
    """impact.json."""
    return point.in_folder(data, lambda out: json.loads((out / "impact.json").read_text()))


def modes_point(data, point):
    """modes.json (the reduced body's frequencies, mass, the reduction's error)."""
    return point.in_folder(data, lambda out: json.loads((out / "modes.json").read_text()))


def wear_point(data, point):
    """The wear run's summary.json."""
    return point.in_folder(data, lambda out: json.loads((out / "summary.json").read_text()))


def mechanism_point(data, point):
    """The mechanism's summary, computed in process (no files), with the statistics of the
    collected time-series columns under `series`."""
    from pinbore.reduced.mechanism import kinds   # noqa: PLC0415
    from pinbore.reduced.mechanism.run import summarised   # noqa: PLC0415 (compiled)

    _, _, series, summary = summarised(kinds.validate(data, point.source), point.source, point.base)
    stop = summary.stop.reason if summary.stop else "; ".join(summary.verdict)
    result = json.loads(summary.model_dump_json())
    result["series"] = point.series(series["steps"])
    return summary.status, stop, result


# ---- the registry, in the order of `pinbore --help` and of the report

STAGES = (
    Stage(name="mesh", summary="build the gmsh model of an FE scene: mesh.msh, preview.png",
          description="Build the 2D or 3D gmsh model of an FE scene; write DIR/mesh.msh and "
                      "DIR/preview.png.",
          model="pinbore.fem.scene:FemScene", run="pinbore.fem.mesh:run", inputs=_scene_inputs,
          outputs=("mesh.msh", "preview.png")),
    Stage(name="fem", summary="solve a 2D or 3D FE contact scene: curve.csv, pressure.csv, result.json",
          description="Solve the (frictional) pin-in-bore contact of an FE scene; write "
                      "DIR/curve.csv, DIR/pressure.csv, DIR/result.json, a 2D elastic round "
                      "joint's surface compliance DIR/compliance.csv and, when the scene asks, "
                      "DIR/fields.xdmf and pictures (2D: contact.png; 3D: pressure_map.png, "
                      "axial_profile.png). Runs under mpiexec -n N.",
          kinds=("fem",), model="pinbore.fem.scene:FemScene", run="pinbore.fem.run:run",
          inputs=_scene_inputs, outputs=("curve.csv", "pressure.csv", "result.json"),
          result=("curve.csv", "pinbore.fem.curve:read"), point="pinbore.stages:fem_point", mpi=True,
          sections=(Section("FE contact", "pinbore.fem.report:section"),)),
    Stage(name="impact", summary="the pin flies into the bore and rebounds: history.csv, impact.json",
          description="Integrate the dynamic impact of an impact scene (kind = \"impact\", plane "
                      "strain): the pin with its mass hits the bore at the impact speed and "
                      "rebounds; write DIR/history.csv, DIR/impact.json (restitution, contact "
                      "duration, peak force, energy book) and DIR/force_time.png.",
          kinds=("impact",), model="pinbore.fem.impact.scene:ImpactScene",
          run="pinbore.fem.impact.run:run", inputs=_scene_inputs,
          outputs=("history.csv", "impact.json", "force_time.png"),
          result=("impact.json", "pinbore.fem.impact.file:read_summary"),
          point="pinbore.stages:impact_point",
          sections=(Section("dynamic impacts", "pinbore.fem.impact.report:section"),)),
    Stage(name="modes", summary="reduce a body's FE model to a flexible body: body.npz, modes.json",
          description="Mesh a body (a link or a panel), assemble its mass and stiffness with "
                      "DOLFINx, reduce it (Craig-Bampton with rigid interfaces, then the reduced "
                      "body's free modes, SLEPc) and write DIR/body.npz (modes, frequencies, the "
                      "floating frame's inertia invariants, interface frames: what a mechanism "
                      "reads), DIR/modes.json and DIR/mode_shapes.png.",
          kinds=("modes",), kindless="body", model="pinbore.fem.modes.scene:ModesScene",
          run="pinbore.fem.modes.run:run", inputs=_scene_inputs,
          outputs=("body.npz", "modes.json", "mode_shapes.png"),
          result=("body.npz", "pinbore.fem.modes.file:read"), point="pinbore.stages:modes_point",
          sections=(Section("flexible bodies", "pinbore.fem.modes.report:section"),)),
    Stage(name="calibrate", summary="fit and rank the contact laws on FE curves: laws.json",
          description="Fit every contact law to FE load-approach curves (2D, per unit length; "
                      "each curve.csv with its result.json beside it) and rank them; 3D curves "
                      "(force and tilting moment) calibrate the sliced law of a finite pin on the "
                      "2D law; FE impacts (--impacts) give the restitution e(v0) of damping_law = "
                      "\"calibrated\"; write DIR/laws.json, DIR/ranking.csv, DIR/curves.png, "
                      "DIR/errors.png [, DIR/restitution.png].",
          run="pinbore.stages:calibrate", arguments="pinbore.cli:calibrate_arguments",
          inputs=_calibrate_inputs, outputs=("laws.json", "ranking.csv", "curves.png", "errors.png"),
          sections=(Section("calibration", "pinbore.calibration.report:section"),),
          answers=("pinbore.calibration.report:answers",)),
    Stage(name="reduced", summary="integrate a mechanism with clearance joints: timeseries.csv, summary.json",
          description="Integrate a planar (scene kind = \"planar\") or spatial (kind = "
                      "\"spatial\") mechanism with clearance joints; write DIR/timeseries.csv, "
                      "DIR/summary.json and plots.",
          kinds=("planar", "spatial"), model="pinbore.reduced.mechanism.kinds:validate",
          run="pinbore.reduced.mechanism.run:run", inputs=_scene_inputs,
          outputs=("timeseries.csv", "summary.json"),
          result=("summary.json", "pinbore.reduced.mechanism.summary:read"),
          point="pinbore.stages:mechanism_point", series=True,
          sections=(Section("reduced models", "pinbore.reduced.report:section"),),
          answers=("pinbore.reduced.report:answers",)),
    Stage(name="dynamics", summary="Poincare maps, bifurcations, Lyapunov exponents, shooting, "
                                   "continuation, design maps",
          description="Nonlinear dynamics of a periodically forced mechanism with clearance joints "
                      "(a drive at constant speed, a shaken drive, harmonic loads), sampled once "
                      "per forcing period; write DIR/summary.json with tables and plots of the "
                      "analysis.",
          run="pinbore.stages:dynamics", arguments="pinbore.cli:dynamics_arguments",
          inputs=_scene_inputs, outputs=("summary.json",),
          sections=(Section("nonlinear dynamics", "pinbore.reduced.report:dynamics_section"),)),
    Stage(name="wear", summary="Archard wear of a mechanism's clearance joint on its FE pressure: wear.csv",
          description="Wear a planar mechanism's revolute clearance joint over `cycles` periods of "
                      "its forcing by Archard's law, on the contact pressure of the joint's FE run "
                      "under the joint's force over its last period (scene kind = \"wear\"); write "
                      "DIR/wear.csv (the bore's and the pin's worn depth against angle), "
                      "DIR/summary.json and DIR/wear.png.",
          kinds=("wear",), model="pinbore.reduced.wear.scene:WearScene",
          run="pinbore.reduced.wear.run:run", inputs=_wear_inputs,
          outputs=("wear.csv", "summary.json", "wear.png"),
          result=("summary.json", "pinbore.reduced.wear.summary:read"), point="pinbore.stages:wear_point",
          sections=(Section("wear", "pinbore.reduced.wear.report:section"),)),
    Stage(name="export", summary="the calibrated laws as tables for another multibody code",
          description="Tabulate the calibrated contact laws of a laws file for one joint (the "
                      "file's curves' joint, or a mechanism scene's clearance joint) on the "
                      "multibody model's grid: DIR/<law>.csv (approach, force), DIR/damping.csv "
                      "(chi against the impact speed), DIR/export.json (joint, units, validity); "
                      "--to exudyn adds DIR/pinbore_exudyn.py, the clearance joint for Exudyn.",
          run="pinbore.stages:export", arguments="pinbore.cli:export_arguments",
          inputs=_export_inputs, outputs=("export.json",)),
    Stage(name="study", summary="run a scene over a grid or a sample of its parameters: results.csv, "
                                "statistics.json, sobol.csv, tolerance.json",
          description="Run the base scene of a study file (TOML: base, [parameters], [sampling], "
                      "[[collect]], [limit], [tolerance]) through its stage at every point of its "
                      "grid or sample, in parallel and cached by content; write DIR/results.csv, "
                      "DIR/summary.json, DIR/statistics.json (confidence intervals, exceedance), DIR/sobol.csv "
                      "(saltelli plans), DIR/tolerance.json and plots. See docs/study.md.",
          run="pinbore.study.runner:command", arguments="pinbore.cli:study_arguments", inputs=_study_inputs,
          outputs=("results.csv", "summary.json", "statistics.json"),
          sections=(Section("studies", "pinbore.study.report:section"),),
          answers=("pinbore.study.report:answers",),
          uses=("point",)),
    Stage(name="report", summary="build the HTML report from the results under build/",
          description="Collect the results under BUILD into one self-contained HTML page, "
                      "OUT/index.html.",
          run="pinbore.report:command", arguments="pinbore.cli:report_arguments", inputs=_report_inputs,
          outputs=("index.html",), uses=("sections", "answers")),
)
STAGE = {stage.name: stage for stage in STAGES}


def of_scene(data: dict, source: str) -> tuple[Stage, dict]:
    """The stage that runs a scene's data, by its `kind` (a former name read with a warning:
    core.scene.normal_kind) or, for a stage whose scenes have none, by its table; and the data
    with its kind's name. One InputError line for another kind."""
    data = scenes.normal_kind(data, source)
    kind = data.get("kind")
    for stage in STAGES:
        if kind in stage.kinds or kind is None and stage.kindless is not None and stage.kindless in data:
            return stage, data
    kindless = "; ".join(f"a {s.name} scene: a [{s.kindless}] table" for s in STAGES if s.kindless)
    raise InputError(f"{source}: kind: {kind!r} is unknown; valid: "
                     f"{', '.join(k for s in STAGES for k in s.kinds)} ({kindless})")


def with_result() -> dict[str, Stage]:
    """The scene stages whose typed result pinbore.run reads back."""
    return {stage.name: stage for stage in STAGES if stage.result is not None}


def sections() -> list[Section]:
    """The report's sections, stage by stage."""
    return [section for stage in STAGES for section in stage.sections]


def answers() -> list[str]:
    """The functions of the report's first screen, stage by stage."""
    return [function for stage in STAGES for function in stage.answers]
