"""The `pinbore` command: one subcommand per stage, from the mesh to the report.

Its subcommands, their help and what each runs and reads are the stage registry's
(pinbore.stages). Bad input prints one line `pinbore <command>: <file>: <key>: <rule>` and exits with 2.
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
from pinbore.stages import STAGE, STAGES, resolve


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


def dynamics_arguments(d) -> None:
    """`pinbore dynamics`. Its options have no argparse defaults (an option left out is absent
    from the parsed arguments): the options model of the analysis holds the defaults and the
    rules, and rejects an option that the analysis does not use."""
    from pinbore.reduced.dynamics.analyses import ContinuationOptions, Sampled, Sweep
    from pinbore.reduced.dynamics.parameters import NAMES

    def default(model, name):
        return model.model_fields[name].default

    d.argument_default = argparse.SUPPRESS
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


def _runner_options(command) -> None:
    """--workers, --scheduler, --cache of a command whose points run in parallel, cached
    (pinbore.core.parallel)."""
    command.add_argument("--workers", type=int, help="local processes (default: the cores)")
    command.add_argument("--scheduler", metavar="ADDRESS",
                         help="run the points on this Dask scheduler instead of local processes")
    command.add_argument("--cache", type=Path, metavar="DIR",
                         help="per-point results, for reruns and resuming (default: OUT-cache)")


def scene_arguments(command) -> None:
    """A command that reads one scene file and writes an output directory."""
    command.add_argument("scene", help="scene file (TOML)")
    command.add_argument("--out", required=True, metavar="DIR",
                         help="output directory (replaced when complete)")


def calibrate_arguments(c) -> None:
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


def export_arguments(e) -> None:
    e.add_argument("laws", help="laws.json written by `pinbore calibrate`")
    e.add_argument("--to", required=True, choices=["table", "exudyn"],
                   help="table: the CSV tables; exudyn: the tables and the Exudyn adapter")
    e.add_argument("--out", required=True, metavar="DIR", help="output directory (replaced when complete)")
    e.add_argument("--scene", default=None, help="a mechanism scene whose clearance joint the law is for")
    e.add_argument("--joint", default=None, metavar="NAME",
                   help="the scene's clearance joint (default: its only one)")
    e.add_argument("--law", default=None, metavar="NAME",
                   help="one fitted law (default: the joint's calibrated normal law, or every law)")


def study_arguments(st) -> None:
    st.add_argument("study", help="study file (TOML)")
    st.add_argument("--out", required=True, type=Path, metavar="DIR",
                    help="output directory (replaced when complete)")
    _runner_options(st)
    st.add_argument("--force", action="store_true",
                    help="run a plan of more points than pinbore.study.MAX_POINTS (100,000)")
    st.add_argument("--ranks", type=int, default=None, metavar="N",
                    help="MPI ranks of each FE point (mpiexec -n N pinbore fem; default 1)")


def report_arguments(r) -> None:
    r.add_argument("--build", default="build", help="where the stage results are (default: build)")
    r.add_argument("--out", default="build/report", help="report directory (default: build/report)")


def parser() -> argparse.ArgumentParser:
    """The command line: a subcommand per stage of the registry, in its order, with the
    stage's summary and description; a scene stage's arguments are SCENE --out DIR, another
    stage's its `arguments` function's."""
    p = OneLineParser(prog="pinbore", description=__doc__.splitlines()[0])
    p.add_argument("--version", action="version", version=f"pinbore {version()}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for stage in STAGES:
        command = sub.add_parser(stage.name, help=stage.summary, description=stage.description)
        (resolve(stage.arguments) if stage.arguments else scene_arguments)(command)
    return p


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
        stage = STAGE[args.command]
        with declared_command(args.command), declared_inputs(stage.inputs(args)), reserved(args.out):
            return stage.command(args)
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
