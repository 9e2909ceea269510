"""The `pinbore` command: one subcommand per stage, plus the report.

Bad input prints one line `pinbore <command>: <file>: <key>: <rule>` and exits with 2.
"""

import argparse
import math
import os
import signal
import sys
import tempfile
import traceback
from pathlib import Path

from pinbore.core.errors import InputError
from pinbore.core.output import (Terminated, clear_stop_signal, declared_command, declared_inputs,
                                 exit_now, reserved, stop_signal)
from pinbore.core.scene import referenced_files


def _mesh(args) -> int:
    from pinbore.core import scene as scenes
    from pinbore.core.output import atomic_directory
    from pinbore.fem.scene import FemScene, worn_joint   # no DOLFINx to mesh

    scene = scenes.load(FemScene, args.scene)   # validated before Gmsh and matplotlib load
    worn = worn_joint(scene, Path(args.scene).parent, args.scene)   # its wear file, if any
    from pinbore.meshes import run as mesh_run

    with atomic_directory(args.out) as tmp:
        mesh_run.write(scene.geometry, scene.sizing_of(worn), scene.load.direction_deg,
                       scene.mesh_options, tmp, worn)
    return 0


def _fem(args) -> int:
    from pinbore.core import scene as scenes
    from pinbore.fem.scene import FemScene   # the scene model only: no DOLFINx yet

    scene = scenes.load(FemScene, args.scene)
    from pinbore.fem import run as fem_run

    return fem_run.run(args.scene, args.out, scene=scene)


def _impact(args) -> int:
    from pinbore.core import scene as scenes
    from pinbore.fem.impact.scene import ImpactScene   # the scene model only: no DOLFINx yet

    scene = scenes.load(ImpactScene, args.scene)
    from pinbore.fem.impact import run as impact_run

    return impact_run.run(args.scene, args.out, scene)


def _modes(args) -> int:
    from pinbore.core import scene as scenes
    from pinbore.fem.modes.scene import ModesScene   # the scene model only: no DOLFINx yet

    scene = scenes.load(ModesScene, args.scene)
    from pinbore.fem.modes import run as modes_run

    return modes_run.run(args.scene, args.out, scene)


def _calibrate(args) -> int:
    from pinbore.calibration import run as calibration_run

    return calibration_run.run(args.curves, args.out, args.length, args.per_length, args.impacts)


def _reduced(args) -> int:
    from pinbore.reduced.mechanism import run as reduced_run

    return reduced_run.run(args.scene, args.out)


def _wear(args) -> int:
    from pinbore.reduced.wear import run as wear_run

    return wear_run.run(args.scene, args.out)


def _dynamics(args) -> int:
    """Validate the options of the chosen analysis (its model in the table of analyses),
    then run it with them."""
    from pinbore.reduced.dynamics import analyses, studies

    model, _ = studies.ANALYSES[args.analysis]
    options = analyses.parse(model, _options_given(args), args.analysis)
    return studies.run(args.scene, args.analysis, options)


def _options_given(args) -> dict:
    """The options given to `pinbore dynamics`, keyed by their model's field names (an option
    left out is absent from `args`); an option of several values as a tuple."""
    skip = {"command", "func", "scene", "analysis"}
    return {name: tuple(value) if isinstance(value, list) else value
            for name, value in vars(args).items() if name not in skip}


def _export(args) -> int:
    from pinbore import export

    return export.run(args.laws, args.to, args.out, args.scene, args.joint, args.law)


def _study(args) -> int:
    from pinbore import study

    options = study.options({"out": args.out, "workers": args.workers, "ranks": args.ranks,
                             "scheduler": args.scheduler, "cache": args.cache, "force": args.force})
    return study.run(args.study, options)


def _report(args) -> int:
    from pinbore import report

    _, problems = report.build(args.build, args.out)
    for line in problems:
        print(f"pinbore report: {line}", file=sys.stderr)
    return 1 if problems else 0


def _scene_command(sub, name, func, summary, description):
    """A subcommand that reads one scene file and writes an output directory."""
    command = sub.add_parser(name, help=summary, description=description)
    command.add_argument("scene", help="scene file (TOML)")
    command.add_argument("--out", required=True, metavar="DIR",
                         help="output directory (replaced when complete)")
    command.set_defaults(func=func)


class OneLineParser(argparse.ArgumentParser):
    """argparse whose usage errors are one line (`pinbore fem: error: ...`) and exit 2."""

    def error(self, message):
        print(f"{self.prog}: error: {message} (see {self.prog} --help)", file=sys.stderr)
        sys.exit(2)


def version() -> str:
    """The installed pinbore's version (its package metadata)."""
    from importlib.metadata import PackageNotFoundError, version as installed   # noqa: PLC0415

    try:
        return installed("pinbore")
    except PackageNotFoundError:
        return "unknown (not installed)"


def positive_length(text: str) -> float:
    """A length in metres: a finite number above zero."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r}: must be a finite length above 0 m")
    return value


def _dynamics_command(sub) -> None:
    """`pinbore dynamics`. Its options have no argparse defaults (an option left out is absent
    from the parsed arguments): the options model of the analysis holds the defaults and the
    rules, and rejects an option that the analysis does not use."""
    from pinbore.reduced.dynamics.analyses import ContinuationOptions, Sampled, Sweep
    from pinbore.reduced.dynamics.parameters import NAMES

    def default(model, name):
        return model.model_fields[name].default

    d = sub.add_parser("dynamics", help="Poincare maps, bifurcations, Lyapunov exponents, shooting, "
                       "continuation, design maps",
                       description="Nonlinear dynamics of a periodically forced mechanism with "
                                   "clearance joints (a drive at constant speed, a shaken drive, "
                                   "harmonic loads), sampled once per forcing period; write "
                                   "DIR/summary.json with tables and plots of the analysis.",
                       argument_default=argparse.SUPPRESS)
    d.add_argument("scene", help="mechanism scene file (TOML, planar or spatial) with a periodic forcing")
    d.add_argument("--analysis", required=True,
                   choices=["poincare", "bifurcation", "lyapunov", "shooting", "continuation", "design"])
    d.add_argument("--out", required=True, type=Path, metavar="DIR",
                   help="output directory (replaced when complete)")
    d.add_argument("--parameter", metavar="KEY",
                   help="bifurcation, continuation: the parameter, a dotted key of the scene "
                        f"(drive.speed_rpm, clearance_joints.0.friction.mu) or one of {NAMES} "
                        "(m, rpm, mu, Hz, a factor)")
    d.add_argument("--range", type=float, nargs=2, metavar=("LOW", "HIGH"),
                   help="bifurcation, continuation: parameter range; design: clearance range (m)")
    d.add_argument("--points", type=int, help=f"sweep points (default {default(Sweep, 'points')}); "
                   f"continuation: most orbits (default {default(ContinuationOptions, 'points')})")
    d.add_argument("--step", type=float, help="continuation: first step in the parameter's units "
                   "(default: 1/100 of the range)")
    d.add_argument("--sweeps", type=int, help="continuation: values of an up- and a down-sweep by "
                   "direct integration (default 0: none)")
    d.add_argument("--speeds", type=float, nargs=3, metavar=("LOW", "HIGH", "N"),
                   help="design: drive speeds (rpm)")
    d.add_argument("--transient", type=int,
                   help=f"drive periods discarded before sampling (default {default(Sampled, 'transient')})")
    d.add_argument("--periods", type=int, help=f"periods sampled (default {default(Sampled, 'periods')})")
    d.add_argument("--multiple", type=int, help="shooting, continuation: orbit period in forcing periods")
    d.add_argument("--max-force", type=float, help="design: threshold (N)")
    d.add_argument("--max-deviation", type=float,
                   help="design: threshold of the slider acceleration deviation (RMS / ideal RMS)")
    _runner_options(d)
    d.set_defaults(func=_dynamics)


def _runner_options(command) -> None:
    """--workers, --scheduler, --cache of a command whose points run in parallel, cached
    (pinbore.core.parallel)."""
    command.add_argument("--workers", type=int, help="local processes (default: the cores)")
    command.add_argument("--scheduler", metavar="ADDRESS",
                         help="run the points on this Dask scheduler instead of local processes")
    command.add_argument("--cache", type=Path, metavar="DIR",
                         help="per-point results, for reruns and resuming (default: OUT-cache)")


def parser() -> argparse.ArgumentParser:
    p = OneLineParser(prog="pinbore", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"pinbore {version()}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _scene_command(sub, "mesh", _mesh, "build the gmsh model of an FE scene: mesh.msh, preview.png",
                   "Build the 2D or 3D gmsh model of an FE scene; write DIR/mesh.msh and "
                   "DIR/preview.png.")
    _scene_command(sub, "fem", _fem,
                   "solve a 2D or 3D FE contact scene: curve.csv, pressure.csv, result.json",
                   "Solve the (frictional) pin-in-bore contact of an FE scene; write "
                   "DIR/curve.csv, DIR/pressure.csv, DIR/result.json and, when the scene asks, "
                   "DIR/fields.xdmf and pictures (2D: contact.png; 3D: pressure_map.png, "
                   "axial_profile.png). Runs under mpiexec -n N.")
    _scene_command(sub, "impact", _impact,
                   "the pin flies into the bore and rebounds: history.csv, impact.json",
                   "Integrate the dynamic impact of an impact scene (kind = \"impact\", plane "
                   "strain): the pin with its mass hits the bore at the impact speed and "
                   "rebounds; write DIR/history.csv, DIR/impact.json (restitution, contact "
                   "duration, peak force, energy book) and DIR/force_time.png.")
    _scene_command(sub, "modes", _modes,
                   "reduce a body's FE model to a flexible body: body.npz, modes.json",
                   "Mesh a body (a link or a panel), assemble its mass and stiffness with "
                   "DOLFINx, reduce it (Craig-Bampton with rigid interfaces, then the reduced "
                   "body's free modes, SLEPc) and write DIR/body.npz (modes, frequencies, the "
                   "floating frame's inertia invariants, interface frames: what a mechanism "
                   "reads), DIR/modes.json and DIR/mode_shapes.png.")
    c = sub.add_parser("calibrate", help="fit and rank the contact laws on FE curves: laws.json",
                       description="Fit every contact law to FE load-approach curves (2D, per "
                                   "unit length; each curve.csv with its result.json beside it) "
                                   "and rank them; 3D curves (force and tilting moment) calibrate "
                                   "the sliced law of a finite pin on the 2D law; FE impacts "
                                   "(--impacts) give the restitution e(v0) of damping_law = "
                                   "\"calibrated\"; write DIR/laws.json, DIR/ranking.csv, "
                                   "DIR/curves.png, DIR/errors.png [, DIR/restitution.png].")
    c.add_argument("curves", nargs="+", help="curve.csv files written by `pinbore fem`")
    c.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced when complete)")
    c.add_argument("--length", type=positive_length, default=None,
                   help="axial length (m) for the laws that need one; default: the bore diameter")
    c.add_argument("--per-length", default=None, metavar="LAW",
                   help="per-length law of the sliced 3D law: section (the 2D FE curve of the "
                        "3D curves' own plane section), a published law or calibrated:<law>; "
                        "default: section when every 3D curve's section is among the 2D "
                        "curves, else the 2D-fitted law of least RMS error")
    c.add_argument("--impacts", nargs="+", default=[], metavar="IMPACT_JSON",
                   help="impact.json files written by `pinbore impact` (one per impact speed): "
                        "fit the restitution e(v0) into laws.json")
    c.set_defaults(func=_calibrate)
    _scene_command(sub, "reduced", _reduced,
                   "integrate a mechanism with clearance joints: timeseries.csv, summary.json",
                   "Integrate a planar (scene kind = \"planar\") or spatial (kind = "
                   "\"spatial\") mechanism with clearance joints; write DIR/timeseries.csv, "
                   "DIR/summary.json and plots.")
    _dynamics_command(sub)
    _scene_command(sub, "wear", _wear,
                   "Archard wear of a mechanism's clearance joint on its FE pressure: wear.csv",
                   "Wear a planar mechanism's revolute clearance joint over `cycles` periods of "
                   "its forcing by Archard's law, on the contact pressure of the joint's FE run "
                   "under the joint's force over its last period (scene kind = \"wear\"); write "
                   "DIR/wear.csv (the bore's and the pin's worn depth against angle), "
                   "DIR/summary.json and DIR/wear.png.")
    e = sub.add_parser("export", help="the calibrated laws as tables for another multibody code",
                       description="Tabulate the calibrated contact laws of a laws file for one "
                                   "joint (the file's curves' joint, or a mechanism scene's "
                                   "clearance joint) on the multibody model's grid: "
                                   "DIR/<law>.csv (approach, force), DIR/damping.csv (chi "
                                   "against the impact speed), DIR/export.json (joint, units, "
                                   "validity); --to exudyn adds DIR/pinbore_exudyn.py, the "
                                   "clearance joint for Exudyn.")
    e.add_argument("laws", help="laws.json written by `pinbore calibrate`")
    e.add_argument("--to", required=True, choices=["table", "exudyn"],
                   help="table: the CSV tables; exudyn: the tables and the Exudyn adapter")
    e.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced when complete)")
    e.add_argument("--scene", default=None, help="a mechanism scene whose clearance joint the law is for")
    e.add_argument("--joint", default=None, metavar="NAME",
                   help="the scene's clearance joint (default: its only one)")
    e.add_argument("--law", default=None, metavar="NAME",
                   help="one fitted law (default: the joint's calibrated normal law, or every law)")
    e.set_defaults(func=_export)
    st = sub.add_parser("study", help="run a scene over a grid or a sample of its parameters: "
                        "results.csv, statistics.json, sobol.csv, tolerance.json",
                        description="Run the base scene of a study file (TOML: base, [parameters], "
                                    "[sampling], [[collect]], [limit], [tolerance]) at every point "
                                    "of its grid or sample, in parallel and cached by content; "
                                    "write DIR/results.csv, DIR/statistics.json (confidence "
                                    "intervals, exceedance), DIR/sobol.csv (saltelli plans), "
                                    "DIR/tolerance.json and plots. See docs/study.md.")
    st.add_argument("study", help="study file (TOML)")
    st.add_argument("--out", required=True, type=Path, metavar="DIR",
                    help="output directory (replaced when complete)")
    _runner_options(st)
    st.add_argument("--force", action="store_true",
                    help="run a plan of more points than pinbore.study.MAX_POINTS (100,000)")
    st.add_argument("--ranks", type=int, default=None, metavar="N",
                    help="MPI ranks of each FE point (mpiexec -n N pinbore fem; default 1)")
    st.set_defaults(func=_study)
    r = sub.add_parser("report", help="build the HTML report from the results under build/",
                       description="Collect the results under BUILD into one self-contained "
                                   "HTML page, OUT/index.html.")
    r.add_argument("--build", default="build", help="where the stage results are (default: build)")
    r.add_argument("--out", default="build/report", help="report directory (default: build/report)")
    r.set_defaults(func=_report)
    return p


def _scene_inputs(args) -> list:
    """A scene and every file it names (its laws file, ...)."""
    return [args.scene, *referenced_files(args.scene)]


def _wear_inputs(args) -> list:
    """A wear scene, the files it names, the result.json beside its FE curve and the files
    its mechanism scene names."""
    from pinbore.core.scene import named_files, read_toml

    files = _scene_inputs(args)
    try:
        data = read_toml(args.scene)
    except InputError:
        return files   # reading it for the run says why
    for key, path in (("curve_file", "result.json"), ("mechanism_file", None)):
        if isinstance(data.get(key), str):
            (named,) = named_files({key: data[key]}, Path(args.scene).parent)
            files += [named.parent / path] if path else referenced_files(named)
    return files


def _study_inputs(path) -> list:
    """A study file, its base scene and every file that names."""
    from pinbore import study

    return study.inputs(path)


# What each command reads, which its --out must not hold (core.output.declared_inputs): every
# command has its line (tests/test_outputs.py enumerates the parser's commands against it).
INPUTS = {
    "mesh": _scene_inputs, "fem": _scene_inputs, "impact": _scene_inputs,
    "modes": _scene_inputs, "reduced": _scene_inputs, "dynamics": _scene_inputs,
    "calibrate": lambda args: [*args.curves, *args.impacts],
    "export": lambda args: [args.laws, *([args.scene, *referenced_files(args.scene)]
                                         if args.scene else [])],
    "wear": _wear_inputs,
    "study": lambda args: _study_inputs(args.study),
    "report": lambda args: [args.build, "bench"],
}


def _trace_file(command: str) -> Path:
    """Write the current exception's traceback to a file; its path."""
    handle, name = tempfile.mkstemp(prefix=f"pinbore-{command}-", suffix=".trace.txt")
    with os.fdopen(handle, "w") as f:
        traceback.print_exc(file=f)
    return Path(name)


def main(argv=None) -> int:
    """Run a command. Known errors print one line: bad input exits 2, Ctrl-C 130, SIGTERM
    143 wherever the command is (outputs under way are removed, nothing half written); anything
    unexpected prints one line with where its traceback was written, and exits 3."""
    args = parser().parse_args(argv)
    clear_stop_signal()
    try:
        # --out checked and locked, and stops made clean, before any work (core.output.reserved)
        with declared_command(args.command), declared_inputs(INPUTS[args.command](args)), \
                reserved(args.out):
            return args.func(args)
    except InputError as err:
        _close_progress_bars()
        print(f"pinbore {args.command}: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return _stopped(args.command, signal.SIGINT)
    except Terminated:
        return _stopped(args.command, signal.SIGTERM)
    except Exception as err:
        if stop_signal() is not None:   # the stop surfaced as a library's error
            return _stopped(args.command, stop_signal())
        # a bug, not bad input: one line, the trace kept for a report
        _close_progress_bars()
        print(f"pinbore {args.command}: internal error ({type(err).__name__}: {err}); "
              f"traceback in {_trace_file(args.command)}", file=sys.stderr)
        return 3


def _close_progress_bars() -> None:
    """Close the progress bars a stopped or failed run left open, so that the command's one
    line follows them on a line of its own (a bar left open is redrawn over it)."""
    tqdm = sys.modules.get("tqdm")
    for bar in list(getattr(getattr(tqdm, "tqdm", None), "_instances", None) or ()):
        try:
            bar.close()
        except Exception:   # noqa: BLE001 (a bar that cannot draw is no reason to fail)
            pass


def _stopped(command: str, signum: int) -> int:
    """One line for a run stopped by Ctrl-C or SIGTERM; the shell's exit code 128 + signal."""
    _close_progress_bars()
    word = "interrupted" if signum == signal.SIGINT else "terminated"
    print(f"pinbore {command}: {word}; outputs under way removed", file=sys.stderr)
    exit_now(128 + signum)   # a Gmsh mesher left running ends with the process
    return 128 + signum


if __name__ == "__main__":
    sys.exit(main())
