"""The reliability audit as a script: every bad-input, extreme and interrupted case of its
findings, against modes, export, the Python API, study,
continuation, the report and make docs, and a SIGTERM and a Ctrl-C (SIGINT to the process
group) sent to each long command mid-run (export is not one: it ends within seconds).

Each case runs as one process (`python -m pinbore.cli ...`, a Python snippet for the API,
`make docs` in a skeleton of the repository) in a temporary folder of its own, with its own
TMPDIR, in a session of its own, with a wall-clock limit; a few at a time. Its row: the
command, the exit code, stderr's line count (progress bars not counted, nor make's own
`make: ***` line), CPU time (the process and the children it waited for, os.wait4), wall
time, and the outcome:

  clean             exit 2 with one line (the report: exit 1 with one line, the section
                    that could not be trusted left out and marked on the page); a signal:
                    exit 130/143 with one line (or 1 with one line; or killed by the signal
                    sent, as a shell shows 130/143 too) within STOP_LIMIT s of the signal,
                    with no temporary folder, lock or process left behind
  accepted          exit 0 and the result passes its own physical checks (below)
  destroyed         a file that was there before the run (the inputs, a foreign folder's)
                    changed or went, or a file appeared in a folder that is not the run's
  garbage complete  exit 0 with a result that fails its physical checks (NaN, a negative
                    mass or ratio, an empty table, a corrupt value shown as a result)
  hang              the wall-clock limit passed (the process group is killed)
  traceback         exit 3, or 'Traceback' in stderr
  signal crash      killed by a signal it was not sent, a negative exit code, 134 or 139
  other             anything else (the note says what: several lines, a slow stop, a
                    leftover temporary folder or process)

The results' physical checks are the audit's own, on the files: modes.json's frequencies
finite and positive, its mass positive; an export table's forces finite, non-negative and
more than its header; a study's results.csv with a row per point, every point complete and
every quantity finite; the API's returned forces finite and non-negative; a report page
that marks the corrupt result ('Not built', 'not finite') instead of drawing it.

The inputs the cases need (an FE curve, its laws.json, a flexible link's body.npz, a short
mechanism run, a small study, the Flores joint's FE run for the wear) are built first into
the audit's scratch folder with the pinbore commands (the wear's FE run is taken from
build/fem/flores_wear when there). Writes OUT/audit.csv and prints the table by stage; exits
0 whatever the cases do (it is a measurement), 1 if a fixture could not be built.

    .venv/bin/python bench/audit.py --out bench            # about 3 minutes on 2 cores
    .venv/bin/python bench/audit.py --only study,export    # some stages (no csv written)
"""

import argparse
import copy
import csv
import hashlib
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import tomli_w

ROOT = Path(__file__).resolve().parent.parent
PY = sys.executable
PINBORE = [PY, "-m", "pinbore.cli"]
SCENES = ROOT / "scenes"
FLORES = SCENES / "reduced" / "slider_crank_flores2004.toml"
FLORES_FLEXIBLE = SCENES / "reduced" / "slider_crank_flores2004_flexible.toml"
CLEAN_LIMIT = 60.0     # s: a bad-input case's wall-clock limit
RUN_LIMIT = 300.0      # s: a case that runs
STOP_LIMIT = 5.0       # s from the signal to the exit
WORKERS = 3            # cases at a time (signal cases: 2)
OUTCOMES = ["clean", "accepted", "destroyed", "garbage complete", "hang", "traceback",
            "signal crash", "other"]
PROGRESS = re.compile(r"\d+%\|.*\||\d+(\.\d+)?[kM]?(it|step|point|period|value|guess)s? \[\d")


# ---------------------------------------------------------------- a case and its run

@dataclass
class Run:
    """What a case runs, in its folder `cwd`."""
    argv: list
    cwd: Path
    check: Callable | None = None      # (cwd, stdout) -> None if the exit-0 result holds, else why
    clean_exit: int = 2                # a refusal's exit code (the report: 1)
    mark: Callable | None = None       # (cwd) -> True if the refusal left its mark (the report's page)
    protect: list | None = None        # files and folders that must not change (default: cwd's)
    seal: list = field(default_factory=list)        # folders where no file may appear
    unprotect: list = field(default_factory=list)   # folders the run may change (a cache)
    timeout: float = CLEAN_LIMIT
    signal: tuple | None = None        # (signum, trigger, delay): see fired()
    out: Path | None = None            # the run's --out (its temporary folders and lock)
    companion: list | None = None      # argv of a run started first (two studies, one --out)
    shown: str | None = None           # the command as the table shows it (default: argv)


@dataclass
class Case:
    stage: str
    name: str
    setup: Callable                    # (folder, fixtures) -> Run


def write_toml(path: Path, data: dict) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(tomli_w.dumps(data))
    return path


def read_toml(path: Path) -> dict:
    return tomllib.loads(Path(path).read_text())


def hashes(paths, skip=(), own=None) -> dict:
    """SHA-256 of every file under `paths` (files or folders), but those under `skip` and the
    lock and temporary folders of the output `own`."""
    found = {}
    skip = [Path(s).resolve() for s in skip]
    for top in paths:
        top = Path(top)
        files = [top] if top.is_file() else [p for p in top.rglob("*") if p.is_file()]
        for f in files:
            r = f.resolve()
            if any(r == s or s in r.parents for s in skip):
                continue
            if own is not None and any(part.startswith(f".{own.name}.pinbore-") for part in f.parts):
                continue
            found[str(f)] = hashlib.sha256(f.read_bytes()).hexdigest()
    return found


def stderr_lines(text: str) -> list[str]:
    """stderr's lines as a terminal leaves them: a line's last carriage-return part, progress
    bars and make's own error line dropped."""
    lines = []
    for raw in text.split("\n"):
        line = raw.split("\r")[-1].strip()
        if line and not PROGRESS.search(line) and not line.startswith(("make: ***", "make[")):
            lines.append(line)
    return lines


def session_processes(sid: int) -> list[int]:
    """Processes still running in the session `sid` (the case's, started as its leader)."""
    alive = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z":
            alive.append(int(stat.parent.name))
    return alive


def leftovers(run: Run, tmpdir: Path) -> list[str]:
    """Temporary folders and locks of the run's --out, and pinbore's temporary files."""
    left = []
    if run.out is not None and run.out.parent.is_dir():
        left += [p.name for p in run.out.parent.iterdir() if p.name.startswith(f".{run.out.name}.pinbore-")]
    left += [p.name for p in tmpdir.iterdir()] if tmpdir.is_dir() else []
    return left


def execute(case: Case, folder: Path, fixtures: dict) -> dict:
    """Run one case in `folder`: its row."""
    folder.mkdir(parents=True)
    try:
        run = case.setup(folder, fixtures)
    except Exception as err:   # noqa: BLE001 (the audit's own fault: a row saying so)
        return row(case, "-", None, [], 0.0, 0.0, None, "other", f"setup failed: {type(err).__name__}: {err}")
    tmpdir = folder / "tmp"
    tmpdir.mkdir()
    env = dict(os.environ, TMPDIR=str(tmpdir), PYTHONUNBUFFERED="1")
    protected = run.protect if run.protect is not None else [folder]
    before = hashes(protected, skip=[tmpdir, *run.unprotect], own=run.out)
    sealed = hashes(run.seal)
    companion = None
    if run.companion:
        companion = subprocess.Popen([str(a) for a in run.companion], cwd=run.cwd, env=env, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.PIPE, text=True, start_new_session=True)
        lock = run.out.parent / f".{run.out.name}.pinbore-lock"
        limit = time.monotonic() + 60
        while not lock.exists() and companion.poll() is None and time.monotonic() < limit:
            time.sleep(0.05)
        before = hashes(protected, skip=[tmpdir, *run.unprotect, run.out], own=run.out)
    proc = subprocess.Popen([str(a) for a in run.argv], cwd=run.cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    chunks = {"out": [], "err": []}

    def drain(stream, key):
        while data := os.read(stream.fileno(), 65536):
            chunks[key].append(data.decode(errors="replace"))

    readers = [threading.Thread(target=drain, args=(s, k), daemon=True)
               for s, k in ((proc.stdout, "out"), (proc.stderr, "err"))]
    for r in readers:
        r.start()
    start = time.monotonic()
    sent, said, status, usage, hung = None, 0, None, None, False
    trigger = run.signal[1] if run.signal else None
    triggered = None
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        now = time.monotonic()
        if run.signal and sent is None:
            if triggered is None and fired(trigger, run, "".join(chunks["err"]), now - start):
                triggered = now
            if triggered is not None and now - triggered >= run.signal[2]:
                signum = run.signal[0]
                (os.killpg if signum == signal.SIGINT else os.kill)(proc.pid, signum)   # Ctrl-C: the group
                sent, said = now, len("".join(chunks["err"]))
        limit = (sent + 30.0) if sent is not None else start + run.timeout
        if now > limit:
            os.killpg(proc.pid, signal.SIGKILL)
            _, status, usage = os.wait4(proc.pid, 0)
            hung = True
            break
        time.sleep(0.02)
    wall = time.monotonic() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    for r in readers:
        r.join(timeout=5)
    cpu = usage.ru_utime + usage.ru_stime
    stderr, stdout = "".join(chunks["err"]), "".join(chunks["out"])
    (folder / "stderr.txt").write_text(stderr)
    notes = []
    if companion is not None:
        try:
            companion.wait(timeout=RUN_LIMIT)
            notes.append(f"the first run: exit {companion.returncode}")
        except subprocess.TimeoutExpired:
            os.killpg(companion.pid, signal.SIGKILL)
            companion.wait()
            notes.append("the first run hung")
    left = session_processes(proc.pid)
    deadline = time.monotonic() + 3
    while left and time.monotonic() < deadline:
        time.sleep(0.1)
        left = session_processes(proc.pid)
    if left:
        notes.append(f"{len(left)} process(es) left running")
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
    after = hashes(protected, skip=[tmpdir, *run.unprotect, *([run.out] if companion else [])], own=run.out)
    changed = [Path(p).name for p in before if after.get(p) != before[p]]
    appeared = [Path(p).name for p in hashes(run.seal) if p not in sealed]
    stop = None if sent is None else (time.monotonic() - sent if hung else wall - (sent - start))
    said = stderr.rfind("\n", 0, said) + 1   # from the line under way at the signal
    lines = stderr_lines(stderr[said:])
    outcome, note = classify(run, proc.returncode, lines, stderr, stdout, hung, sent, stop,
                             changed, appeared, leftovers(run, tmpdir), bool(left))
    notes = [note, *notes] if note else notes
    command = run.shown or " ".join(map(str, run.argv if run.argv[:3] != PINBORE else ["pinbore", *run.argv[3:]]))
    if run.signal:
        command = f"{signal.Signals(run.signal[0]).name} to: {command}"
    def portable(text):   # the case's folder and the repository's, named
        return text.replace(str(folder), "$CASE").replace(f"{ROOT}/", "").replace(PY, "python")

    return row(case, portable(command), proc.returncode if not hung else None, lines,
               cpu, wall, stop, outcome, portable("; ".join(notes)), stderr)


def fired(trigger, run: Run, stderr: str, elapsed: float) -> bool:
    """Whether a signal case's moment has come: its output's lock or temporary folder exists
    ("out"), `elapsed` s have passed (("after", s)), or its stderr has shown `text` `count`
    times."""
    if trigger == "out":
        return run.out.parent.is_dir() and any(p.name.startswith(f".{run.out.name}.pinbore-")
                                               for p in run.out.parent.iterdir())
    if trigger[0] == "after":
        return elapsed >= trigger[1]
    text, count = trigger
    return stderr.count(text) >= count


def classify(run, code, lines, stderr, stdout, hung, sent, stop, changed, appeared, left, running):
    """(outcome, note) of a finished run (`lines`: stderr's, from the signal's on if one was sent)."""
    if changed or appeared:
        return "destroyed", f"changed or removed: {', '.join(changed[:4])}" if changed else \
            f"written among files not its own: {', '.join(appeared[:4])}"
    if hung:
        return "hang", "killed at the wall-clock limit" + (" after the signal" if sent else "")
    if code < 0 and not (sent and code == -run.signal[0]) or code in (134, 139):
        return "signal crash", f"exit {code}"
    if "Traceback" in stderr or code == 3:
        return "traceback", lines[-1][:160] if lines else ""
    first = lines[0][:200] if lines else ""
    if run.signal:
        if sent is None:
            return "other", f"finished (exit {code}) before the signal's moment came"
        problems = []
        if code not in (128 + run.signal[0], -run.signal[0], 1) or (code == 1 and len(lines) != 1) \
                or (code > 0 and len(lines) != 1):
            problems.append(f"exit {code}, {len(lines)} lines")
        if stop is not None and stop > STOP_LIMIT:
            problems.append(f"stopped {stop:.1f} s after the signal")
        return ("other", "; ".join(problems)) if problems else left_behind(left, running) or ("clean", first)
    if code == 0:
        why = run.check(run.cwd, stdout) if run.check else None
        if isinstance(why, tuple):   # (outcome, note): a run that should not have run
            return why
        return ("garbage complete", why) if why else left_behind(left, running) or ("accepted", "")
    if code == run.clean_exit and len(lines) == 1 and (run.mark is None or run.mark(run.cwd)):
        return left_behind(left, running) or ("clean", first)
    return "other", f"exit {code}, {len(lines)} lines: {first}"


def left_behind(left, running):
    """("other", what) if the run left a temporary folder, lock or process behind, else None."""
    if left or running:
        return "other", "; ".join(([f"left {', '.join(left[:3])}"] if left else [])
                                  + (["left processes running"] if running else []))
    return None


def row(case, command, code, lines, cpu, wall, stop, outcome, note, stderr=""):
    return {"stage": case.stage, "case": case.name, "command": command,
            "exit": "" if code is None else code, "stderr_lines": len(lines),
            "cpu_s": round(cpu, 2), "wall_s": round(wall, 2),
            "stop_s": "" if stop is None else round(stop, 2), "outcome": outcome,
            "note": note, "_stderr": stderr}


# ---------------------------------------------------------------- result checks

def finite(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x)


def modes_result(out: Path):
    try:
        data = json.loads((out / "modes.json").read_text())
    except (OSError, ValueError) as err:
        return f"modes.json does not read: {err}"
    f = data.get("frequencies_Hz") or []
    if not f or not all(finite(x) and x > 0 for x in f):
        return f"frequencies not positive and finite: {f[:3]}"
    if not finite(data.get("mass_kg")) or data["mass_kg"] <= 0:
        return f"mass {data.get('mass_kg')}"
    return None


def export_result(out: Path):
    tables = [p for p in out.glob("*.csv") if p.name != "damping.csv"]
    if not tables:
        return "no law table"
    for t in tables:
        rows = list(csv.reader(t.read_text().splitlines()))[1:]
        if not rows:
            return f"{t.name} is its header alone"
        force = [float(r[1]) for r in rows]
        if not all(math.isfinite(x) and x >= 0 for x in force):
            return f"{t.name}: a force not finite or negative"
    return None


def study_result(out: Path, points: int):
    try:
        rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    except OSError as err:
        return f"results.csv: {err}"
    if len(rows) != points:
        return f"{len(rows)} rows for {points} points"
    for r in rows:
        if r["status"] != "complete":
            return f"point {r['point']}: {r['status']}"
    quantities = [k for k in rows[0] if k not in ("point", "name", "status", "reason", "ran", "seconds", "key")]
    for r in rows:
        for q in quantities:
            try:
                if not math.isfinite(float(r[q])):
                    return f"point {r['point']}: {q} = {r[q]}"
            except ValueError:
                pass
    return None


def page_marks(cwd: Path) -> bool:
    """The report's page marks what it could not trust."""
    try:
        page = (cwd / "report" / "index.html").read_text()
    except OSError:
        return False
    return "Not built:" in page or "not finite" in page.lower()


# ---------------------------------------------------------------- fixtures

def fixtures(f: Path, jobs: int) -> dict:
    """The inputs the cases copy, built in the folder f: {name: path}. Raises RuntimeError
    naming what failed. A folder that holds them already (--fixtures) is taken as it is."""
    made = f / "made.json"
    if made.is_file():
        return {k: Path(v) for k, v in json.loads(made.read_text()).items()}
    f.mkdir(parents=True, exist_ok=True)
    fem_scene = read_toml(SCENES / "fem" / "steel_c100um.toml")
    fem_scene["output"] = {"picture": False}
    flores = read_toml(FLORES)
    flores["duration"] = 0.006
    study = {"base": str(FLORES), "set": {"duration": 0.003},
             "parameters": {"clearance_joints.0.restitution": {"distribution": {"kind": "uniform", "low": 0.8, "high": 0.95}}},
             "sampling": {"method": "monte_carlo", "points": 4, "seed": 1},
             "collect": [{"name": "peak_force_N", "path": "clearance_joints.rod_slider.peak_normal_force_N"}]}
    steps = {
        "fem": [PINBORE + ["fem", write_toml(f / "fem.toml", fem_scene), "--out", f / "fem"],
                PINBORE + ["calibrate", f / "fem" / "curve.csv", "--out", f / "cal"]],
        "modes": [PINBORE + ["modes", SCENES / "modes" / "link_steel_2d.toml", "--out", f / "modes"]],
        "reduced": [PINBORE + ["reduced", write_toml(f / "flores.toml", flores), "--out", f / "reduced"]],
        "study": [PINBORE + ["study", write_toml(f / "study.toml", study), "--out", f / "study",
                             "--cache", f / "cache", "--workers", "2"]],
    }
    wear_fe = ROOT / "build" / "fem" / "flores_wear"
    if not (wear_fe / "curve.csv").is_file():
        steps["wear_fe"] = [PINBORE + ["fem", SCENES / "fem" / "flores_wear.toml", "--out", f / "flores_wear"]]
        wear_fe = f / "flores_wear"

    def build(commands):
        for argv in commands:
            done = subprocess.run([str(a) for a in argv], capture_output=True, text=True, cwd=f)
            if done.returncode != 0:
                raise RuntimeError(f"{' '.join(map(str, argv[2:4]))}: exit {done.returncode}: "
                                   f"{done.stderr.strip()[-300:]}")

    with ThreadPoolExecutor(jobs) as pool:
        for future in [pool.submit(build, c) for c in steps.values()]:
            future.result()
    found = {"fem": f / "fem", "cal": f / "cal", "laws": f / "cal" / "laws.json", "modes": f / "modes",
             "reduced": f / "reduced", "study": f / "study", "study_toml": f / "study.toml",
             "cache": f / "cache", "wear_fe": wear_fe}
    made.write_text(json.dumps({k: str(v) for k, v in found.items()}))
    return found


def copy_of(src: Path, dst: Path) -> Path:
    if src.is_dir():
        shutil.copytree(src, dst)
    else:
        dst.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(src, dst)
    return dst


def pinbore(*args) -> list:
    return PINBORE + [str(a) for a in args]


# ---------------------------------------------------------------- the cases: modes

SMALL_PANEL = {"body": {"shape": "panel", "dim": 3, "length": 0.2, "width": 0.1, "thickness": 2e-3,
                        "cell_size": 0.02},
               "material": {"E": 7.0e10, "nu": 0.33, "density": 2700.0},
               "reduction": {"interfaces": ["edge"], "fixed_interface_modes": 4, "modes": 2}}


def modes_case(name, edit, timeout=CLEAN_LIMIT, base=SCENES / "modes" / "panel_aluminium_3d.toml"):
    def setup(d, fx):
        data = copy.deepcopy(SMALL_PANEL) if base is None else read_toml(base)
        edit(data)
        return Run(pinbore("modes", write_toml(d / "scene.toml", data), "--out", d / "out"), d,
                   check=lambda cwd, _: modes_result(cwd / "out"), timeout=timeout, out=d / "out")
    return Case("modes", name, setup)


LINK = SCENES / "modes" / "link_steel_2d.toml"
STRIP = SCENES / "modes" / "panel_strip_2d.toml"
MODES_CASES = [
    modes_case("cell_size = 2e-5 (a mesh of billions of cells)", lambda s: s["body"].update(cell_size=2e-5)),
    modes_case("length = 120 m", lambda s: s["body"].update(length=120.0)),
    modes_case("a 10 um-thick panel", lambda s: s["body"].update(thickness=1e-5), RUN_LIMIT, base=None),
    modes_case("more modes than the mesh gives (200 of a 10 cm strip, degree 1)",
               lambda s: (s["body"].update(length=0.1), s["reduction"].update(
                   fixed_interface_modes=200, modes=200, degree=1, full_modes=0)), RUN_LIMIT, base=STRIP),
    modes_case("E = 1e-300 Pa", lambda s: s["material"].update(E=1e-300)),
    modes_case("density = 1e300", lambda s: s["material"].update(density=1e300)),
    modes_case("E = 1e300 Pa", lambda s: s["material"].update(E=1e300)),
    modes_case("an eye of 1e-7 m", lambda s: s["body"].update(eye_radius=1e-7), RUN_LIMIT, base=LINK),
    modes_case("a width of 1e-9 m", lambda s: s["body"].update(width=1e-9), RUN_LIMIT, base=STRIP),
    modes_case("a valid panel (baseline)", lambda s: None, RUN_LIMIT, base=None),
]


# ---------------------------------------------------------------- export

def laws_case(name, edit, scene=None, law=None, out=None):
    """export of the fixture laws.json edited by edit(data)."""
    def setup(d, fx):
        data = json.loads(fx["laws"].read_text())
        edit(data)
        laws = d / "cal" / "laws.json"
        laws.parent.mkdir()
        laws.write_text(json.dumps(data))
        extra = []
        if scene is not None:
            extra = ["--scene", scene(d, fx)]
        if law is not None:
            extra += ["--law", law]
        target = out(d, fx) if out else d / "out"
        return Run(pinbore("export", laws, "--to", "table", "--out", target, *extra), d,
                   check=lambda cwd, _: export_result(target), out=target)
    return Case("export", name, setup)


def fitted(law="liu", **values):
    return lambda data: data["laws"][law]["fitted"].update(values)


def joint(**values):
    return lambda data: [c["joint"].update(values) for c in data["curves"]]


def flores_copy(d, fx):
    return copy_of(FLORES, d / "flores.toml")


def modes_folder(d, fx):
    return copy_of(fx["modes"], d / "modes")


EXPORT_CASES = [
    laws_case("scale NaN", fitted(scale=math.nan)),
    laws_case("scale 0", fitted(scale=0.0)),
    laws_case("scale negative", fitted(scale=-1.0)),
    laws_case("exponent correction 50", fitted(exponent_correction=50.0)),
    laws_case("reference approach negative", fitted(reference_approach_m=-1e-6)),
    laws_case("--scene the shipped Flores scene --law liu (no length)", lambda d: None, flores_copy, "liu"),
    laws_case('"laws": {}', lambda d: d.update(laws={})),
    laws_case("joint record: a negative modulus", joint(E_bore=-7e10)),
    laws_case("joint record: zero length", joint(length=0.0)),
    laws_case("joint record: a pin larger than its bore", joint(r_pin=0.0101)),
    laws_case("--out a modes output folder", lambda d: None, out=modes_folder),
    laws_case("a valid laws file (baseline)", lambda d: None),
]


# ---------------------------------------------------------------- the Python API

API_HEAD = """\
import json, math, sys
from pathlib import Path
import pinbore as pb
from pinbore.core.errors import InputError
T = Path(sys.argv[1])
FLORES = sys.argv[2]
def scene_dict():
    import tomllib
    return tomllib.loads(Path(FLORES).read_text())
try:
    result = {call}
except InputError as err:
    print(f"pinbore api: {{err}}", file=sys.stderr)
    sys.exit(2)
{after}
"""


def api_case(name, call, after="", check=None, laws_edit=None):
    """A call of the Python API in a fresh interpreter: InputError -> one line, exit 2."""
    def setup(d, fx):
        copy_of(fx["fem"], d / "fem")
        if laws_edit is not None:
            data = json.loads(fx["laws"].read_text())
            laws_edit(data)
            (d / "laws.json").write_text(json.dumps(data))
        script = d / "call.py"
        script.write_text(API_HEAD.format(call=call, after=after))
        return Run([PY, script, d, FLORES], d, check=check, out=d / "o", shown=f"python: {call}")
    return Case("Python API", name, setup)


def forces_hold(cwd, stdout):
    try:
        values = json.loads(stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return f"no forces printed: {stdout[-200:]!r}"
    return None if all(finite(v) and v >= 0 for v in values) else f"forces {values}"


LOAD_FORCES = "print(json.dumps([result['liu'](d) for d in (1e-7, 1e-6, 1e-5)]))"
CAL_LAWS = ("import pinbore.laws.lawsfile as lf; f = lf.read(T / 'c' / 'laws.json'); "
            "print(json.dumps([f.laws['liu'].fitted.scale]))")
API_CASES = [
    api_case("calibrate(length=-1)", "pb.calibrate([T / 'fem' / 'curve.csv'], T / 'c', length=-1.0)",
             CAL_LAWS, forces_hold),
    api_case("pinbore.laws.load on a corrupt file (scale -1)", "pb.laws.load(T / 'laws.json')",
             LOAD_FORCES, forces_hold, fitted(scale=-1.0)),
    api_case("pinbore.laws.load with a pin larger than its bore", "pb.laws.load(T / 'laws.json')",
             LOAD_FORCES, forces_hold, joint(r_pin=0.0101)),
    api_case("run(scene=None)", "pb.run('reduced', None, T / 'o')"),
    api_case("run(scene=5)", "pb.run('reduced', 5, T / 'o')"),
    api_case("run(scene=[a list])", "pb.run('reduced', ['a.toml'], T / 'o')"),
    api_case("run(out=None)", "pb.run('reduced', FLORES, None)"),
    api_case("run(out=3)", "pb.run('reduced', FLORES, 3)"),
    api_case("run(out=[a list])", "pb.run('reduced', FLORES, ['o'])"),
    api_case("a dict scene with a non-string key", "pb.run('reduced', scene_dict() | {1: 2}, T / 'o')"),
    api_case("a dict scene with a None value", "pb.run('reduced', scene_dict() | {'duration': None}, T / 'o')"),
    api_case("a refused dict scene (names its temporary file?)",
             "pb.run('reduced', scene_dict() | {'duration': -1.0}, T / 'o')"),
    api_case("scene(a dict with a None value)", "pb.scene({'kind': 'reduced', 'duration': None})"),
    api_case("calibrate(curves=one path)", "pb.calibrate(T / 'fem' / 'curve.csv', T / 'c')"),
    api_case("calibrate(curves=[None])", "pb.calibrate([None], T / 'c')"),
]


# ---------------------------------------------------------------- study

def study_file(d: Path, data: dict) -> Path:
    return write_toml(d / "study.toml", data)


def flores_study(points=2, duration=0.003, **extra):
    data = {"base": str(FLORES), "set": {"duration": duration},
            "parameters": {"clearance_joints.0.restitution": {"values": [0.8 + 0.1 * k / max(points - 1, 1)
                                                                          for k in range(points)]}},
            "sampling": {"method": "grid"},
            "collect": [{"name": "peak_force_N", "path": "clearance_joints.rod_slider.peak_normal_force_N"}]}
    return data | extra


def study_case(name, make, timeout=CLEAN_LIMIT, points=2, **run):
    """make(d, fx) -> (study dict, extra argv); --out d/out unless the extra names one."""
    def setup(d, fx):
        data, extra, *more = make(d, fx)
        options = dict(run, **(more[0] if more else {}))
        path = study_file(d, data)
        out = Path(extra[extra.index("--out") + 1]) if "--out" in extra else d / "out"
        if "--out" not in extra:
            extra = [*extra, "--out", out]
        if "--workers" not in extra and "--scheduler" not in extra:
            extra = [*extra, "--workers", "2"]
        return Run(pinbore("study", path, *extra), d, out=out, timeout=timeout,
                   check=lambda cwd, _: study_result(out, points), **options)
    return Case("study", name, setup)


def laws_folder_study(d, fx):
    copy_of(fx["cal"], d / "cal")
    data = flores_study()
    data["set"] |= {"laws_file": str(d / "cal" / "laws.json"),
                    "clearance_joints.0.normal_law": "calibrated:liu", "clearance_joints.0.length": 0.02}
    return data, ["--out", d / "cal"]


def modes_case_study(d, fx):
    copy_of(fx["modes"], d / "modes")
    copy_of(fx["modes"], d / "other")
    base = read_toml(FLORES_FLEXIBLE)
    base["bodies"][1]["modes_file"] = str(d / "other" / "body.npz")
    base["duration"] = 0.003
    write_toml(d / "flexible.toml", base)
    data = flores_study() | {"base": str(d / "flexible.toml"), "set": {},
                             "cases": {"rod": [{"label": "linked", "bodies.1.modes_file": str(d / "modes" / "body.npz")}]}}
    return data, ["--out", d / "modes"]


def cache_edit(edit):
    """The fixture study rerun on a copy of its cache with one entry edited."""
    def make(d, fx):
        cache = copy_of(fx["cache"], d / "cache")
        entry = sorted(cache.glob("*.json"))[0]
        edit(entry)
        return read_toml(fx["study_toml"]), ["--cache", cache]
    return make


def halve_peak(entry: Path):
    data = json.loads(entry.read_text())
    joint = data["result"]["result"]["clearance_joints"]["rod_slider"]
    joint["peak_normal_force_N"] /= 2
    entry.write_text(json.dumps(data))


def cache_check(cwd, stdout, fx):
    """The rerun's table is the fixture study's: an edited entry computed again."""
    mine = list(csv.DictReader((cwd / "out" / "results.csv").read_text().splitlines()))
    theirs = list(csv.DictReader((fx["study"] / "results.csv").read_text().splitlines()))
    for a, b in zip(mine, theirs):
        if abs(float(a["peak_force_N"]) - float(b["peak_force_N"])) > 1e-6 * abs(float(b["peak_force_N"])):
            return f"point {a['point']}: peak {a['peak_force_N']} served, computed {b['peak_force_N']}"
    return study_result(cwd / "out", 4)


def cache_case(name, edit):
    case = study_case(name, cache_edit(edit), RUN_LIMIT, points=4)
    inner = case.setup

    def setup(d, fx):
        run = inner(d, fx)
        run.unprotect = [d / "cache"]
        run.check = lambda cwd, out: cache_check(cwd, out, fx)
        return run
    return Case(case.stage, case.name, setup)


def integer_study(d, fx):
    copy_of(fx["modes"], d / "modes")
    base = read_toml(FLORES_FLEXIBLE)
    base["bodies"][1]["modes_file"] = str(d / "modes" / "body.npz")
    write_toml(d / "flexible.toml", base)
    data = flores_study() | {"base": str(d / "flexible.toml"),
                             "parameters": {"bodies.1.modes": {"values": [2, 4]}}}
    data["set"]["bodies.1.modes"] = 6   # the base scene keeps all its modes: a number to vary
    return data, []


def scenes_cache(d, fx):
    copy_of(SCENES / "reduced", d / "scenes" / "reduced")
    return flores_study(), ["--cache", d / "scenes" / "reduced"], {"seal": [d / "scenes"]}


def cache_in_file(d, fx):
    (d / "afile").write_text("a file\n")
    return flores_study(), ["--cache", d / "afile" / "cache"]


def two_wears(name):
    """Two wear runs into one --out: the second refused at once (the lock taken before the
    work), the first completes."""
    def setup(d, fx):
        argv, out = long_wear(d, fx)
        return Run(argv, d, out=out, companion=argv, timeout=RUN_LIMIT,
                   check=lambda cwd, _: ("other", "the second run computed too"))
    return Case("wear", name, setup)


def two_studies(name):
    def setup(d, fx):
        path = study_file(d, flores_study(points=16, duration=0.012))
        first = pinbore("study", path, "--out", d / "out", "--workers", "1")
        return Run(pinbore("study", path, "--out", d / "out", "--workers", "1"), d, out=d / "out",
                   companion=first, timeout=RUN_LIMIT, check=lambda cwd, _: ("other", "the second study computed too"))
    return Case("study", name, setup)


STUDY_CASES = [
    study_case("[set] names a laws_file, --out its folder", laws_folder_study),
    study_case("a case names a modes_file, --out its folder", modes_case_study),
    study_case("1e7 points", lambda d, fx: (flores_study() | {
        "parameters": {"clearance_joints.0.restitution": {"distribution": {"kind": "uniform", "low": 0.8, "high": 0.9}}},
        "sampling": {"method": "monte_carlo", "points": 10_000_000, "seed": 1}}, [])),
    study_case("1e9 points", lambda d, fx: (flores_study() | {
        "parameters": {"clearance_joints.0.restitution": {"distribution": {"kind": "uniform", "low": 0.8, "high": 0.9}}},
        "sampling": {"method": "monte_carlo", "points": 1_000_000_000, "seed": 1}}, [])),
    study_case("a 1e5 x 1e5 grid", lambda d, fx: (flores_study() | {"parameters": {
        "clearance_joints.0.restitution": {"grid": {"start": 0.8, "stop": 0.9, "num": 100_000}},
        "clearance_joints.0.journal_radius": {"grid": {"start": 9.4e-3, "stop": 9.6e-3, "num": 100_000}}}}, [])),
    study_case("seed -1", lambda d, fx: (flores_study() | {
        "parameters": {"clearance_joints.0.restitution": {"distribution": {"kind": "uniform", "low": 0.8, "high": 0.9}}},
        "sampling": {"method": "monte_carlo", "points": 2, "seed": -1}}, [])),
    study_case("a collect window outside the run", lambda d, fx: (flores_study() | {"collect": [
        {"name": "v", "column": "slider_vx_m_per_s", "statistic": "rms", "window_s": [1.0, 2.0]}]}, [])),
    study_case("--scheduler 'not an address'", lambda d, fx: (flores_study(), ["--scheduler", "not an address"])),
    study_case("--cache inside a file", cache_in_file),
    study_case("--workers 10000", lambda d, fx: (flores_study(), ["--workers", "10000"])),
    study_case("--cache a copy of scenes/reduced", scenes_cache),
    two_studies("two studies into one --out (the second)"),
    study_case("a study varying an integer key (bodies.1.modes)", integer_study, RUN_LIMIT),
]


def cache_cases():
    return [cache_case("a cache entry edited by hand (a peak halved)", halve_peak),
            cache_case("a cache entry {}", lambda e: e.write_text("{}")),
            cache_case("a cache entry null", lambda e: e.write_text("null"))]


# ---------------------------------------------------------------- the report

def report_case(name, corrupt):
    def setup(d, fx):
        build = d / "build"
        copy_of(fx["modes"], build / "modes" / "link")
        copy_of(fx["reduced"], build / "reduced" / "flores")
        copy_of(fx["cal"], build / "calibration")
        copy_of(fx["study"], build / "study" / "mc")
        corrupt(build)
        return Run(pinbore("report", "--build", build, "--out", d / "report"), d, clean_exit=1,
                   mark=page_marks, out=d / "report", timeout=RUN_LIMIT,
                   check=lambda cwd, _: None if page_marks(cwd) else "the corrupt result is drawn, unmarked")
    return Case("report", name, setup)


def edit_json(path: Path, edit):
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))


REPORT_CASES = [
    report_case("NaN frequencies", lambda b: edit_json(b / "modes/link/modes.json",
                                                       lambda m: m.update(frequencies_Hz=[math.nan] * len(m["frequencies_Hz"])))),
    report_case("a negative mass", lambda b: edit_json(b / "modes/link/modes.json", lambda m: m.update(mass_kg=-0.21))),
    report_case("NaN peaks", lambda b: edit_json(b / "reduced/flores/summary.json",
                                                 lambda s: s["clearance_joints"]["rod_slider"].update(peak_normal_force_N=math.nan))),
    report_case("NaN means", lambda b: edit_json(b / "study/mc/statistics.json",
                                                 lambda s: [q.update(mean=math.nan) for q in s["quantities"].values()])),
    report_case("a truncated PNG", lambda b: (b / "modes/link/mode_shapes.png").write_bytes(
        (b / "modes/link/mode_shapes.png").read_bytes()[:500])),
    report_case("a text PNG", lambda b: (b / "reduced/flores/rod_slider.png").write_text("not an image")),
    report_case("an empty ranking table", lambda b: (b / "calibration/ranking.csv").write_text(
        (b / "calibration/ranking.csv").read_text().splitlines()[0] + "\n")),
]


# ---------------------------------------------------------------- make docs

def docs_case(name, which):
    def setup(d, fx):
        skeleton = d / "repo"
        skeleton.mkdir()
        for entry in ROOT.iterdir():
            if entry.name not in ("build", "docs", ".git"):
                (skeleton / entry.name).symlink_to(entry)
        shutil.copytree(ROOT / "docs", skeleton / "docs", symlinks=True)
        (skeleton / "build" / "docs").mkdir(parents=True)
        deps = subprocess.run([PY, "-I", ROOT / "core" / "codedeps.py", ROOT], capture_output=True,
                              text=True, check=True).stdout   # what make would include
        (skeleton / "build" / "deps.mk").write_text(deps)
        (skeleton / "build" / "docs" / which).write_text("a file\n")
        # (-o: the repository's .venv and deps.mk are not made again from the skeleton)
        return Run(["make", "-s", "--no-print-directory", "-o", ".venv/.installed", "-o", "build/deps.mk",
                    "docs"], skeleton, timeout=RUN_LIMIT,
                   protect=[skeleton / "build", skeleton / "docs"],
                   check=lambda cwd, _: None if (cwd / "build/docs/html/index.html").is_file() else "no site")
    return Case("make docs", name, setup)


DOCS_CASES = [docs_case("build/docs/doctrees a file", "doctrees"),
              docs_case("build/docs/html a file", "html")]


# ---------------------------------------------------------------- signals

def signal_case(stage, name, signum, make, trigger="out", delay=1.0):
    """make(d, fx) -> (argv, out): the command stopped by `signum` `delay` s after its
    moment (its output's lock or temporary folder appears, a time, a text in its stderr)."""
    def setup(d, fx):
        argv, out = make(d, fx)
        return Run(argv, d, out=out, timeout=RUN_LIMIT, signal=(signum, trigger, delay))
    return Case(stage, f"{signal.Signals(signum).name}: {name}", setup)


def long_fem(d, fx):
    scene = read_toml(SCENES / "fem" / "steel_c100um.toml")
    scene["load"]["steps"] = 60
    return pinbore("fem", write_toml(d / "fem.toml", scene), "--out", d / "out"), d / "out"


def long_impact(d, fx):
    return pinbore("impact", SCENES / "impact" / "steel_c10um_v1.toml", "--out", d / "out"), d / "out"


def long_modes(d, fx):
    return pinbore("modes", SCENES / "modes" / "panel_aluminium_3d.toml", "--out", d / "out"), d / "out"


def long_reduced(d, fx):
    base = read_toml(FLORES_FLEXIBLE)
    base["bodies"][1]["modes_file"] = str(fx["modes"] / "body.npz")
    base["duration"] = 2.0
    base["output"] = {"plots": False}
    return pinbore("reduced", write_toml(d / "flexible.toml", base), "--out", d / "out"), d / "out"


def long_study(d, fx):
    path = study_file(d, flores_study(points=40, duration=0.24))
    return pinbore("study", path, "--out", d / "out", "--workers", "2"), d / "out"


def long_wear(d, fx):
    scene = read_toml(SCENES / "wear" / "slider_crank_flores2004_coupled.toml")
    scene["mechanism_file"] = str(FLORES)
    scene["pressure_file"] = str(fx["wear_fe"] / "pressure.csv")
    scene["curve_file"] = str(fx["wear_fe"] / "curve.csv")
    return pinbore("wear", write_toml(d / "wear.toml", scene), "--out", d / "out"), d / "out"


def continuation(d, fx):
    return pinbore("dynamics", SCENES / "reduced" / "impact_oscillator.toml", "--analysis", "continuation",
                   "--parameter", "frequency", "--range", "10", "30", "--points", "200", "--transient", "30",
                   "--periods", "5", "--out", d / "out"), d / "out"


GRAZING = ("locating a grazing", 1)
# the moment of a stage whose output may not exist mid-run: seconds after the start
TRIGGERS = {"wear": ("after", 10.0)}
SIGNAL_CASES = [
    case for make, stage, what, delay in (
        (long_fem, "fem", "pinbore fem, 60 load steps", 2.0),
        (long_impact, "impact", "pinbore impact (the shipped scene)", 3.0),
        (long_modes, "modes", "pinbore modes (the aluminium panel)", 4.0),
        (long_reduced, "reduced", "pinbore reduced (the flexible Flores rod, 2 s)", 2.0),
        (long_study, "study", "pinbore study (40 mechanism points)", 3.0),
        (long_wear, "wear", "pinbore wear (the coupled Flores joint)", 0.0),
        (continuation, "continuation", "pinbore dynamics --analysis continuation", 3.0))
    for case in (signal_case(stage, what, signal.SIGTERM, make, TRIGGERS.get(stage, "out"), delay),
                 signal_case(stage, what, signal.SIGINT, make, TRIGGERS.get(stage, "out"), delay))
] + [signal_case("continuation", f"while it locates a grazing point (try {k})", signal.SIGTERM, continuation,
                 trigger=GRAZING, delay=0.2 * k) for k in range(3)] + [
    signal_case("continuation", "while it locates a grazing point", signal.SIGINT, continuation,
                trigger=GRAZING, delay=0.1)]


def all_cases() -> list[Case]:
    return (MODES_CASES + EXPORT_CASES + API_CASES + STUDY_CASES + cache_cases() + REPORT_CASES
            + DOCS_CASES + [two_wears("two wear runs into one --out (the second)")])


# ---------------------------------------------------------------- main

COLUMNS = ["stage", "case", "command", "exit", "stderr_lines", "cpu_s", "wall_s", "stop_s",
           "outcome", "note"]


def summary_table(rows: list[dict]) -> str:
    stages = list(dict.fromkeys(r["stage"] for r in rows))
    head = "| stage | cases | " + " | ".join(OUTCOMES) + " |"
    lines = [head, "|" + "---|" * (len(OUTCOMES) + 2)]
    for stage in stages + ["**total**"]:
        mine = rows if stage == "**total**" else [r for r in rows if r["stage"] == stage]
        counts = [sum(r["outcome"] == o for r in mine) for o in OUTCOMES]
        lines.append(f"| {stage} | {len(mine)} | " + " | ".join(map(str, counts)) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=None, help="write OUT/audit.csv")
    p.add_argument("--only", default=None, help="comma-separated stages (no csv written)")
    p.add_argument("--jobs", type=int, default=WORKERS)
    p.add_argument("--case", default=None, help="only the cases whose name holds this text (no csv written)")
    p.add_argument("--keep", action="store_true", help="keep the scratch folder")
    p.add_argument("--fixtures", type=Path, default=None,
                   help="build the fixtures in this folder, or take them from it (kept)")
    args = p.parse_args(argv)
    scratch = Path(tempfile.mkdtemp(prefix="pinbore-audit-"))
    start = time.monotonic()
    try:
        try:
            fx = fixtures(args.fixtures.resolve() if args.fixtures else scratch / "fixtures", args.jobs)
        except RuntimeError as err:
            print(f"audit: a fixture failed: {err}", file=sys.stderr)
            return 1
        print(f"audit: fixtures in {time.monotonic() - start:.0f} s", file=sys.stderr)
        cases = all_cases()
        signals = SIGNAL_CASES
        if args.only:
            wanted = set(args.only.split(","))
            cases = [c for c in cases if c.stage in wanted]
            signals = [c for c in signals if c.stage in wanted]
        if args.case:
            cases = [c for c in cases if args.case in c.name]
            signals = [c for c in signals if args.case in c.name]
        rows = []
        for batch, jobs in ((cases, args.jobs), (signals, 2)):
            with ThreadPoolExecutor(jobs) as pool:
                futures = [pool.submit(execute, c, scratch / "cases" / f"{len(rows) + i:03d}", fx)
                           for i, c in enumerate(batch)]
                for c, f in zip(batch, futures):
                    r = f.result()
                    rows.append(r)
                    print(f"audit: {r['stage']}: {r['case']}: {r['outcome']} (exit {r['exit']}, "
                          f"{r['stderr_lines']} lines, {r['cpu_s']} s CPU) {r['note'][:120]}", file=sys.stderr)
        if args.out is not None and not args.only and not args.case:
            args.out.mkdir(parents=True, exist_ok=True)
            with open(args.out / "audit.csv", "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
                w.writeheader()
                w.writerows(rows)
        print(summary_table(rows))
        bad = [r for r in rows if r["outcome"] not in ("clean", "accepted")]
        print(f"audit: {len(rows)} cases in {time.monotonic() - start:.0f} s, {len(bad)} neither clean nor accepted")
        for r in bad:
            print(f"  {r['stage']}: {r['case']}: {r['outcome']}: {r['note']}")
            if r["_stderr"].strip():
                print("    " + "\n    ".join(stderr_lines(r["_stderr"])[-3:])[:600])
        return 0
    finally:
        if not args.keep:
            shutil.rmtree(scratch, ignore_errors=True)
        else:
            print(f"audit: scratch kept in {scratch}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
