"""pinbore never destroys a user's files: what --out may be, the lock between concurrent
runs, and the clean-up after Ctrl-C, SIGTERM and SIGKILL (core/output.py's rules)."""

import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import ROOT, pinbore

from pinbore.core.output import MARKER, _lock

SCENE = ROOT / "scenes" / "fem" / "steel_c100um.toml"


@pytest.fixture
def home(tmp_path):
    """A user's folder: a scene and a notes file beside it."""
    shutil.copy(SCENE, tmp_path / "scene.toml")
    (tmp_path / "notes.txt").write_text("my notes\n")
    (tmp_path / "a_file").write_text("keep me\n")
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "data.csv").write_text("1,2\n")
    return tmp_path


def snapshot(folder):
    return {p.relative_to(folder): (p.read_bytes() if p.is_file() else None)
            for p in sorted(folder.rglob("*"))}


# (--out, what the one line must say)
REFUSED = [
    (".", "must name a directory of its own"),
    ("", "must name a directory of its own"),
    ("scene.toml", "holds the input"),              # the scene itself
    ("{home}", "working directory or a folder above it"),
    ("a_file", "is a file"),
    ("foreign", "did not write"),
    ("a_file/sub", "is a file, not a directory"),
]


@pytest.mark.parametrize("out, rule", REFUSED, ids=[r[1][:20] + "|" + r[0] for r in REFUSED])
@pytest.mark.parametrize("command", ["mesh", "fem", "reduced"])
def test_a_refused_out_destroys_nothing(home, out, rule, command):
    scene = "scene.toml"
    if command == "reduced":
        shutil.copy(ROOT / "scenes" / "reduced" / "slider_crank_flores2004_ideal.toml", home / "scene.toml")
    before = snapshot(home)
    run = pinbore(command, scene, "--out", out.format(home=home), cwd=home)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and rule in lines[0], run.stderr
    assert snapshot(home) == before   # nothing changed, nothing added (no hidden temporaries)


def test_every_command_declares_what_it_reads():
    """One table (pinbore.stages.STAGES) names the files each command reads (Stage.inputs);
    the parser's commands are its stages, each with its inputs."""
    from pinbore import cli, stages

    commands = set(cli.parser()._subparsers._group_actions[0].choices)
    assert commands == set(stages.STAGE) and all(callable(s.inputs) for s in stages.STAGES)


def _impacts_home(home):
    """Two impact runs' directories (pinbore's own) A and B, and a curve."""
    for name in ("A", "B"):
        (home / name).mkdir()
        (home / name / MARKER).write_text("pinbore\n")
        for f in ("impact.json", "history.csv", "force_time.png"):
            (home / name / f).write_text(f"{name} {f}\n")
    (home / "curve.csv").write_text("x\n")
    return ["calibrate", "curve.csv", "--impacts", "A/impact.json", "B/impact.json", "--out", "B"]


def _laws_home(command):
    def setup(home):
        (home / "calib").mkdir()
        (home / "calib" / MARKER).write_text("pinbore\n")
        (home / "calib" / "laws.json").write_text("{}\n")
        text = (ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml").read_text()
        (home / "scene.toml").write_text(f'laws_file = "calib/laws.json"\n{text}')
        analysis = ["--analysis", "poincare"] if command == "dynamics" else []
        return [command, "scene.toml", *analysis, "--out", "calib"]
    return setup


def _report_home(out):
    def setup(home):
        (home / "build").mkdir()
        (home / "site").mkdir()
        (home / "site" / "index.html").write_text("<p>my page</p>\n")
        return ["report", "--build", "build", "--out", out]
    return setup


# a command whose --out holds a file it reads (declared in one place, pinbore.stages), or
# is a folder that is not pinbore's: refused, nothing touched
DESTRUCTIVE = [
    ("calibrate --out holding an --impacts run", _impacts_home, "holds the input B/impact.json"),
    ("dynamics --out holding the scene's laws file", _laws_home("dynamics"), "holds the input"),
    ("reduced --out holding the scene's laws file", _laws_home("reduced"), "holds the input"),
    ("report --out a foreign folder", _report_home("site"), "did not write"),
    ("report --out .", _report_home("."), "must name a directory of its own"),
    ("report --out the build folder", _report_home("build"), "holds the input build"),
]


@pytest.mark.parametrize("case, setup, rule", DESTRUCTIVE, ids=[d[0] for d in DESTRUCTIVE])
def test_an_out_holding_what_the_command_reads_is_refused(home, case, setup, rule):
    command = setup(home)
    before = snapshot(home)
    run = pinbore(*command, cwd=home)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and rule in lines[0], run.stderr
    assert snapshot(home) == before


def test_a_scene_names_its_files_relative_to_its_folder(tmp_path):
    from pinbore.core.scene import referenced_files

    (tmp_path / "s.toml").write_text('laws_file = "a/laws.json"\n[[bodies]]\nmodes_file = "/abs/body.npz"\n'
                                     '[x]\ncurve_files = ["c1.csv", 2]\nname = "n_file"\n')
    assert referenced_files(tmp_path / "s.toml") == [
        tmp_path / "a" / "laws.json", Path("/abs/body.npz"), tmp_path / "c1.csv"]
    (tmp_path / "bad.toml").write_text("not = [toml")
    assert referenced_files(tmp_path / "bad.toml") == []


def test_the_folder_holding_the_scene_is_refused(home, tmp_path_factory):
    elsewhere = tmp_path_factory.mktemp("cwd")
    before = snapshot(home)
    run = pinbore("mesh", home / "scene.toml", "--out", home, cwd=elsewhere)
    assert run.returncode == 2 and "holds the input" in run.stderr
    assert snapshot(home) == before


def test_own_output_is_replaced_whole_and_an_empty_folder_is_used(home):
    (home / "empty").mkdir()
    assert pinbore("mesh", "scene.toml", "--out", "empty", cwd=home).returncode == 0
    assert (home / "empty" / MARKER).exists() and (home / "empty" / "mesh.msh").exists()
    (home / "empty" / "stale.txt").write_text("from an older run\n")
    assert pinbore("mesh", "scene.toml", "--out", "empty", cwd=home).returncode == 0
    assert not (home / "empty" / "stale.txt").exists()          # replaced whole
    assert sorted(p.name for p in home.iterdir() if p.name.startswith(".")) == []


def test_a_second_writer_of_one_out_is_refused(home):
    with _lock(home / "out"):
        run = pinbore("mesh", "scene.toml", "--out", "out", cwd=home)
    assert run.returncode == 2 and "another pinbore run is writing it" in run.stderr
    assert not (home / "out").exists()
    assert pinbore("mesh", "scene.toml", "--out", "out", cwd=home).returncode == 0


# each command's arguments (its inputs need not exist: under another run's lock it reads nothing)
ARGUMENTS = {
    "mesh": ["scene.toml"], "fem": ["scene.toml"], "impact": ["scene.toml"], "modes": ["scene.toml"],
    "reduced": ["scene.toml"], "dynamics": ["scene.toml", "--analysis", "poincare"], "wear": ["scene.toml"],
    "calibrate": ["curve.csv"], "export": ["laws.json", "--to", "table"], "study": ["study.toml"],
    "report": ["--build", "build"],
}


def test_every_command_holds_its_out_before_its_work():
    from pinbore import stages

    assert set(ARGUMENTS) == set(stages.STAGE)


@pytest.mark.parametrize("command", list(ARGUMENTS))
def test_a_command_into_a_locked_out_is_refused_before_its_work(home, command):
    """A command holds its --out from before its work (core.output.reserved): while another
    run writes it, the command is refused at once in one line, before it reads its inputs
    (a wear run had computed for a minute and written over the first's output; a study's
    points, a calibration's fits likewise), and leaves nothing behind."""
    before = snapshot(home)
    with _lock(home / "out"):
        run = pinbore(command, *ARGUMENTS[command], "--out", "out", cwd=home)
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "another pinbore run is writing it now" in lines[0], run.stderr
    assert snapshot(home) == before


def test_bad_input_under_new_folders_leaves_no_folder(home):
    """The folders made to hold --out's lock go again when the command writes nothing."""
    (home / "bad.toml").write_text('kind = "fem"\n[geometry]\nbore_radius = -1.0\n')
    run = pinbore("fem", "bad.toml", "--out", "new/deeper/out", cwd=home)
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert not (home / "new").exists()


def test_temporaries_of_a_killed_run_are_swept(home):
    stale = home / ".out.pinbore-999999999-abc.tmp"   # no such process
    stale.mkdir()
    (stale / "fields.h5").write_bytes(b"half written")
    assert pinbore("mesh", "scene.toml", "--out", "out", cwd=home).returncode == 0
    assert not stale.exists()


@pytest.mark.parametrize("sig, code, word", [(signal.SIGTERM, 143, "terminated"),
                                             (signal.SIGINT, 130, "interrupted")])
def test_a_stopped_run_leaves_no_temporaries_and_one_line(home, sig, code, word):
    run = subprocess.Popen([sys.executable, "-m", "pinbore.cli", "fem", "scene.toml", "--out", "out"],
                           cwd=home, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(home.glob(".out.pinbore-*.tmp")) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert run.poll() is None, "the run ended before it could be stopped"
    run.send_signal(sig)
    stderr = run.communicate(timeout=60)[1]
    assert run.returncode == code
    # the last line is pinbore's (a library may have said what it was doing when stopped)
    assert stderr.strip().splitlines()[-1] == f"pinbore fem: {word}; outputs under way removed"
    assert "Traceback" not in stderr
    assert not (home / "out").exists()
    assert [p.name for p in home.iterdir() if p.name.startswith(".")] == []


def test_a_stop_the_moment_the_temporary_folder_exists_removes_it(tmp_path, monkeypatch):
    """SIGTERM delivered right as the output's temporary folder is made (the instant a user's
    kill most likely lands, when the run has just begun writing) still removes it."""
    import os
    import tempfile

    from pinbore.core import output

    made, mkdtemp = [], tempfile.mkdtemp

    def mkdtemp_then_stopped(**kw):
        made.append(mkdtemp(**kw))
        os.kill(os.getpid(), signal.SIGTERM)   # sent the moment the folder exists
        return made[-1]

    monkeypatch.setattr(output.tempfile, "mkdtemp", mkdtemp_then_stopped)
    monkeypatch.setattr(output, "_stopped", [])   # the stop this test makes is forgotten after it
    with pytest.raises(output.Terminated):
        with output.atomic_directory(tmp_path / "out") as tmp:
            (tmp / "half.txt").write_text("half written")
    assert made and not Path(made[0]).exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize("signum, group, code", [(signal.SIGTERM, False, 143), (signal.SIGINT, True, 130)],
                         ids=["SIGTERM", "Ctrl-C"])
def test_a_run_stopped_in_the_compiled_core_ends_at_once(tmp_path, signum, group, code):
    """A stop while the compiled core integrates a mechanism (40 s of the Flores
    slider-crank, about 20 s in one call of the core): the core asks Python for signals every
    20 ms of its run, so the command ends within a second, one line, nothing left (it had
    run on to the end of the call: 30 s for a flexible rod's 2 s)."""
    import tomllib

    import tomli_w
    from conftest import stopped_midrun

    data = tomllib.loads((ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml").read_text())
    data["duration"] = 40.0
    data["output"] = {"plots": False}
    (tmp_path / "scene.toml").write_text(tomli_w.dumps(data))
    done, seconds, left, temporaries = stopped_midrun(["reduced", "scene.toml", "--out", "out"], tmp_path,
                                                      tmp_path / "out", signum, 1.0, group)
    assert done.returncode == code and seconds < 1.0, (done.returncode, seconds, done.stderr)
    assert len(done.stderr.strip().splitlines()) == 1 and "Traceback" not in done.stderr
    assert left == [] and temporaries == []
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".") or p.name == "out"] == []


def test_a_stopped_commands_line_follows_its_progress_bar(tmp_path):
    """SIGTERM during a continuation (its progress bar open): the command's line is the last
    a terminal shows, on its own line (the bar, closed after it, had been redrawn over it)."""
    from conftest import stopped_midrun

    done, seconds, left, temporaries = stopped_midrun(
        ["dynamics", ROOT / "scenes" / "reduced" / "impact_oscillator.toml", "--analysis", "continuation",
         "--parameter", "frequency", "--range", "10", "30", "--points", "200", "--transient", "30",
         "--periods", "5", "--out", "out"], tmp_path, tmp_path / "out", signal.SIGTERM, 0.5,
        until="continuation:")
    shown = [line.split("\r")[-1] for line in done.stderr.rstrip("\n").split("\n")]
    assert done.returncode == 143 and shown[-1] == "pinbore dynamics: terminated; outputs under way removed", \
        done.stderr[-500:]
    assert "pinbore" not in "".join(shown[:-1]) and left == [] and temporaries == []


def test_a_run_stopped_while_gmsh_meshes_ends_at_once(tmp_path):
    """SIGTERM while Gmsh meshes a flexible body near the cell cap (seconds of meshing): the
    command ends within a second (Gmsh's mesher does not return to Python until it is done;
    it had run on for minutes), exit 143, one line, no temporary left, no crash at exit."""
    text = (ROOT / "scenes/modes/link_steel_2d.toml").read_text()
    (tmp_path / "scene.toml").write_text(text.replace("cell_size = 0.0015", "cell_size = 0.00017"))
    run = subprocess.Popen([sys.executable, "-m", "pinbore.cli", "modes", "scene.toml", "--out", "out"],
                           cwd=tmp_path, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob(".out.pinbore-*.tmp")) and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(1.0)   # into the meshing (about 7 s)
    assert run.poll() is None, "the run ended before it could be stopped"
    run.send_signal(signal.SIGTERM)
    stopped = time.monotonic()
    stderr = run.communicate(timeout=60)[1]
    assert time.monotonic() - stopped < 1.0
    assert run.returncode == 143, stderr
    assert stderr.strip().splitlines()[-1] == "pinbore modes: terminated; outputs under way removed"
    assert not (tmp_path / "out").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
