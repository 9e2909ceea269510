"""The options of `pinbore dynamics`: one model per analysis, built by the CLI and checked
before any work. A broken rule is one line `pinbore dynamics: --option: rule` on stderr, exit
code 2, and nothing written (no OUT, no OUT-cache); valid command lines become typed,
frozen options with the defaults they had."""

import math
import tomllib
from pathlib import Path

import pydantic
import pytest
from conftest import ROOT

from pinbore import cli, stages
from pinbore.core.parallel import default_workers
from pinbore.reduced.dynamics import analyses, studies

FLORES = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
BIFURCATION = ["--analysis", "bifurcation", "--parameter", "clearance"]
CLEARANCES = ["--range", "1e-4", "5e-4"]
DESIGN = ["--analysis", "design", *CLEARANCES]
SPEEDS = ["--speeds", "2000", "5000", "4"]

# (options after the scene, the option named, the rule's words)
BAD = [
    # ranges: finite, LOW < HIGH, physical
    ([*BIFURCATION, "--range", "1e-4", "inf"], "--range", "HIGH must be a finite number"),
    ([*BIFURCATION, "--range", "nan", "5e-4"], "--range", "LOW must be a finite number"),
    ([*BIFURCATION, "--range", "5e-4", "1e-4"], "--range", "HIGH must exceed LOW"),
    ([*BIFURCATION, "--range", "0", "5e-4"], "--range", "clearance must be > 0"),
    (["--analysis", "bifurcation", "--parameter", "friction", "--range", "-0.1", "0.2"], "--range",
     "friction must be >= 0"),
    (["--analysis", "bifurcation", "--parameter", "speed", "--range", "-100", "3000"], "--range",
     "speed must be > 0"),
    (["--analysis", "design", "--range", "-0.0001", "5e-4", *SPEEDS], "--range", "clearance must be > 0"),
    ([*DESIGN, "--speeds", "5000", "2000", "4"], "--speeds", "HIGH must exceed LOW"),
    ([*DESIGN, "--speeds", "0", "5000", "4"], "--speeds", "speed must be > 0"),
    ([*DESIGN, "--speeds", "2000", "inf", "4"], "--speeds", "HIGH must be a finite number"),
    ([*DESIGN, "--speeds", "2000", "5000", "0"], "--speeds", "N must be at least 1"),
    ([*DESIGN, "--speeds", "2000", "5000", "2.5"], "--speeds", "N must be a whole number"),
    ([*DESIGN, *SPEEDS, "--max-force", "-1"], "--max-force", "must be > 0"),
    ([*DESIGN, *SPEEDS, "--max-deviation", "nan"], "--max-deviation", "must be > 0"),
    # counts
    ([*BIFURCATION, *CLEARANCES, "--points", "0"], "--points", "at least 2"),
    ([*BIFURCATION, *CLEARANCES, "--points", "1"], "--points", "at least 2"),
    (["--analysis", "poincare", "--periods", "0"], "--periods", "at least 1"),
    (["--analysis", "lyapunov", "--transient", "-1"], "--transient", "at least 0"),
    (["--analysis", "shooting", "--multiple", "0"], "--multiple", "at least 1"),
    ([*BIFURCATION, *CLEARANCES, "--workers", "-1"], "--workers", "at least 1"),
    ([*BIFURCATION, *CLEARANCES, "--workers", "0"], "--workers", "at least 1"),
    # where the sweep runs and caches
    ([*BIFURCATION, *CLEARANCES, "--scheduler", "tcp://localhost:8786", "--workers", "2"], "--workers",
     "not used with --scheduler"),
    ([*BIFURCATION, *CLEARANCES, "--scheduler", " "], "--scheduler", "must be a scheduler's address"),
    ([*BIFURCATION, *CLEARANCES, "--cache", "{tmp}/a_file"], "--cache", "is an existing file"),
    ([*BIFURCATION, *CLEARANCES, "--cache", "{tmp}/out/cache"], "--cache", "lies in --out"),
    # what an analysis needs
    (["--analysis", "bifurcation", *CLEARANCES], "--parameter",
     "--analysis bifurcation needs it (a dotted key of the scene, or one of clearance, speed, friction, "
     "frequency, amplitude)"),
    ([*BIFURCATION[:3], "drive..speed_rpm", *CLEARANCES], "--parameter",
     "'drive..speed_rpm' must be a dotted key of the scene (e.g. drive.speed_rpm) or one of clearance"),
    ([*BIFURCATION], "--range", "--analysis bifurcation needs it"),
    (["--analysis", "design", *SPEEDS], "--range", "--analysis design needs it"),
    ([*DESIGN], "--speeds", "--analysis design needs it"),
    # options the analysis does not use
    (["--analysis", "poincare", "--parameter", "clearance"], "--parameter", "not used by --analysis poincare"),
    (["--analysis", "poincare", "--workers", "2"], "--workers", "not used by --analysis poincare"),
    (["--analysis", "lyapunov", "--max-force", "100"], "--max-force", "not used by --analysis lyapunov"),
    (["--analysis", "shooting", "--periods", "10"], "--periods", "not used by --analysis shooting"),
    (["--analysis", "shooting", "--cache", "{tmp}/cache"], "--cache", "not used by --analysis shooting"),
    ([*BIFURCATION, *CLEARANCES, "--multiple", "2"], "--multiple", "not used by --analysis bifurcation"),
    ([*BIFURCATION, *CLEARANCES, *SPEEDS], "--speeds", "not used by --analysis bifurcation"),
    ([*DESIGN, *SPEEDS, "--parameter", "speed"], "--parameter", "not used by --analysis design"),
    # continuation
    (["--analysis", "continuation", "--parameter", "speed", "--range", "2000", "5000", "--step", "0"],
     "--step", "must be a finite number > 0"),
    (["--analysis", "continuation", "--parameter", "speed", "--range", "2000", "5000", "--step", "-5"],
     "--step", "must be a finite number > 0"),
    (["--analysis", "continuation", "--parameter", "frequency", "--range", "0", "5"], "--range",
     "frequency must be > 0"),
    (["--analysis", "continuation", "--parameter", "speed", "--range", "2000", "5000", "--sweeps", "-1"],
     "--sweeps", "at least 0"),
    (["--analysis", "continuation", "--parameter", "speed", "--range", "2000", "5000", "--workers", "2"],
     "--workers", "not used by --analysis continuation"),
    (["--analysis", "continuation", "--range", "2000", "5000"], "--parameter",
     "--analysis continuation needs it"),
    # the scene at both ends of a swept range
    ([*BIFURCATION, "--range", "1e-4", "0.05"], "--range",
     "slider_crank_flores2004.toml with clearance 0.05: clearance_joints.0.journal_radius"),
    (["--analysis", "bifurcation", "--parameter", "drive.speed_rpm", "--range", "0", "5000"], "--range",
     "slider_crank_flores2004.toml with drive.speed_rpm 0: drive.speed_rpm: must not be 0"),
]


def run_cli(options: list[str], tmp_path: Path, capsys, scene: Path = FLORES) -> tuple[int, str]:
    """`pinbore dynamics SCENE OPTIONS --out TMP/out` in this process: exit code, stderr."""
    options = [o.replace("{tmp}", str(tmp_path)) for o in options]
    code = cli.main(["dynamics", str(scene), *options, "--out", str(tmp_path / "out")])
    return code, capsys.readouterr().err


def nothing_written(tmp_path: Path) -> bool:
    return not (tmp_path / "out").exists() and not (tmp_path / "out-cache").exists() \
        and not (tmp_path / "cache").exists()


@pytest.mark.parametrize("options, option, rule", BAD, ids=[" ".join(b[0]) for b in BAD])
def test_a_broken_rule_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, options, option, rule):
    (tmp_path / "a_file").write_text("not a folder")
    code, err = run_cli(options, tmp_path, capsys)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1
    assert err.startswith(f"pinbore dynamics: {option}: ") and rule in err, err
    assert nothing_written(tmp_path)
    assert (tmp_path / "a_file").read_text() == "not a folder"


@pytest.mark.parametrize("edit, rule", [
    (lambda d: d.pop("drive"), "a periodic analysis needs a periodic forcing"),
    (lambda d: d["drive"].update(speed_rpm=0.0), "drive.speed_rpm: must not be 0"),
])
def test_a_scene_without_a_turning_drive_is_one_line_exit_2(tmp_path, capsys, write_scene, edit, rule):
    data = tomllib.loads(FLORES.read_text())
    edit(data)
    code, err = run_cli(["--analysis", "poincare"], tmp_path, capsys, scene=write_scene(data))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert rule in err
    assert nothing_written(tmp_path)


def given(*options: str) -> dict:
    """The options the CLI gives the model for a `pinbore dynamics` command line."""
    return stages.options_given(cli.parser().parse_args(["dynamics", str(FLORES), *options]))


def test_the_makefile_command_lines_become_typed_options():
    poincare = analyses.parse(analyses.PoincareOptions, given(
        "--analysis", "poincare", "--transient", "50", "--periods", "100", "--out", "build/p"), "poincare")
    assert poincare == analyses.PoincareOptions(out=Path("build/p"), transient=50, periods=100)
    bifurcation = analyses.parse(analyses.BifurcationOptions, given(
        *BIFURCATION, *CLEARANCES, "--points", "40", "--transient", "30", "--periods", "30",
        "--out", "build/b", "--cache", "build/c"), "bifurcation")
    assert (bifurcation.parameter, bifurcation.range, bifurcation.points) == ("clearance", (1e-4, 5e-4), 40)
    assert (bifurcation.cache, bifurcation.workers, bifurcation.scheduler) == \
        (Path("build/c"), default_workers(), None)
    design = analyses.parse(analyses.DesignOptions, given(
        *DESIGN, "--points", "5", *SPEEDS, "--transient", "10", "--periods", "10",
        "--max-force", "20000", "--max-deviation", "1.0", "--out", "build/d"), "design")
    assert design.speeds == (2000.0, 5000.0, 4) and isinstance(design.speeds.count, int)
    assert (design.max_force, design.max_deviation, design.cache) == (20000.0, 1.0, Path("build/d-cache"))


def test_left_out_options_take_the_defaults_they_had():
    shooting = analyses.parse(analyses.ShootingOptions, given("--analysis", "shooting", "--out", "o"), "shooting")
    assert (shooting.transient, shooting.multiple) == (50, 1)
    design = analyses.parse(analyses.DesignOptions, given(*DESIGN, *SPEEDS, "--out", "o"), "design")
    assert (design.transient, design.periods, design.points) == (50, 50, 50)
    assert design.max_force == design.max_deviation == math.inf


def test_options_are_frozen():
    options = analyses.PoincareOptions(out=Path("o"))
    with pytest.raises(pydantic.ValidationError):
        options.periods = 3


def test_the_table_of_analyses_matches_the_parser():
    """Every analysis the parser offers has its model and function; every option the parser
    offers belongs to some model, and every model field is an option."""
    dynamics = cli.parser()._subparsers._group_actions[0].choices["dynamics"]
    actions = {a.dest: a for a in dynamics._actions if a.dest not in ("help", "scene")}
    assert set(actions.pop("analysis").choices) == set(studies.ANALYSES)
    assert actions["parameter"].choices is None   # a dotted key of the scene, or a shorthand
    fields = {name for model, _ in studies.ANALYSES.values() for name in model.model_fields}
    assert fields == set(actions)
    assert all(issubclass(model, analyses.Analysis) and callable(function)
               for model, function in studies.ANALYSES.values())


def test_an_unreachable_scheduler_is_one_line_and_leaves_nothing(tmp_path, capsys):
    """Nothing listens on the discard port of the loopback: the sweep cannot start, and says so
    before its cache folder exists."""
    pytest.importorskip("distributed")
    code, err = run_cli(["--analysis", "bifurcation", "--parameter", "clearance", "--range", "1e-4",
                         "2e-4", "--points", "2", "--transient", "1", "--periods", "1",
                         "--scheduler", "tcp://127.0.0.1:9"], tmp_path, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "--scheduler tcp://127.0.0.1:9: cannot reach the Dask scheduler" in err
    assert nothing_written(tmp_path)


IMPACT_OSCILLATOR = ROOT / "scenes" / "reduced" / "impact_oscillator.toml"


@pytest.mark.parametrize("scene, edit, options, rule", [
    (FLORES, None, ["--parameter", "frequency", "--range", "1", "5"],
     "--parameter frequency: the scene has no harmonic loads or shaken drive"),
    (IMPACT_OSCILLATOR, None, ["--parameter", "speed", "--range", "1", "5"],
     "--parameter speed: the scene has no drive turning at constant speed"),
    (IMPACT_OSCILLATOR, None, ["--parameter", "frequency", "--range", "15", "20"],
     "--range: the branch starts at the scene's frequency 14, outside 15 20"),
    (IMPACT_OSCILLATOR, None, ["--parameter", "loads.0.frequency_hz", "--range", "15", "20"],
     "--range: the branch starts at the scene's loads.0.frequency_hz 14, outside 15 20"),
    (IMPACT_OSCILLATOR, lambda d: d["loads"][0].update(frequency_hz=0.0), ["--parameter", "amplitude",
     "--range", "0.5", "2"], "loads.0.frequency_hz"),
    (IMPACT_OSCILLATOR, lambda d: d["loads"].append(dict(d["loads"][0], frequency_hz=20.0)),
     ["--parameter", "amplitude", "--range", "0.5", "2"], "frequency 20 Hz is not a whole multiple"),
], ids=["frequency-without-excitation", "speed-without-drive", "start-outside-range", "key-start-outside-range",
        "frequency-zero", "incommensurate"])
def test_a_continuation_the_scene_cannot_take_is_one_line_exit_2(tmp_path, capsys, write_scene, scene, edit,
                                                                 options, rule):
    data = tomllib.loads(scene.read_text())
    if edit:
        edit(data)
    code, err = run_cli(["--analysis", "continuation", *options], tmp_path, capsys, scene=write_scene(data))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert rule in err
    assert nothing_written(tmp_path)
