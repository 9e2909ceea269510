"""Shared helpers: scenes as dicts, in-process FE solves, the CLI (in process or in its own)."""

import copy
import functools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
STEEL = {"E": 210e9, "nu": 0.3}

BASE_SCENE = {
    "kind": "fem",
    "geometry": {"dim": 2, "pin_radius": 9.99e-3, "bore_radius": 10.0e-3,
                 "housing_radius": 0.2, "hub_radius": 2.0e-3},
    "materials": {"pin": dict(STEEL), "bore": dict(STEEL)},
    "contact": {"method": "augmented-lagrangian", "friction": 0.0},
    "load": {"max_approach": 1.0e-5, "steps": 4, "direction_deg": -90.0},
    "output": {"picture": False},
}


def scene_dict(**tables) -> dict:
    """BASE_SCENE with tables updated key by key, e.g. scene_dict(load={"steps": 2})."""
    scene = copy.deepcopy(BASE_SCENE)
    for table, values in tables.items():
        if isinstance(values, dict) and isinstance(scene.get(table), dict):
            scene[table].update(values)
        else:
            scene[table] = values
    return scene


def with_clearance(clearance: float, radius: float = 10.0e-3, **tables) -> dict:
    scene = scene_dict(**tables)
    scene["geometry"]["bore_radius"] = radius
    scene["geometry"]["pin_radius"] = radius - clearance
    return scene


def effective_modulus(scene: dict) -> float:
    pin, bore = scene["materials"]["pin"], scene["materials"]["bore"]
    return 1 / ((1 - pin["nu"] ** 2) / pin["E"] + (1 - bore["nu"] ** 2) / bore["E"])


class Solved:
    """An in-process FE solve of a scene dict: the run and the objects behind it."""

    def __init__(self, data: dict, approaches=None, on_step=None, hook=None):
        """hook: a dict that receives the stepper before the run (for on_step to read)."""
        from pinbore.fem import model
        from pinbore.fem.scene import FemScene, worn_joint
        from pinbore.core.scene import validate

        self.scene = validate(FemScene, data, "test scene")
        self.worn = worn_joint(self.scene, Path.cwd(), "test scene")   # a wear_file, if any
        self.stepper, self.el, self.contact, self.sizing, self.mesh_data = model.build(
            self.scene, worn=self.worn)
        if hook is not None:
            hook["stepper"] = self.stepper
        programme = self.scene.load.programme if approaches is None else [(a, 0, 0, 0) for a in approaches]
        self.run = self.stepper.run(programme, on_step=on_step)
        assert self.run.stop is None, self.run.stop

    @property
    def forces(self):
        return [s.force[0] for s in self.run.steps]

    def work_balance(self, states):
        """Per step of the turn (the hub turning), the external work less the gain of elastic
        energy (trapezoidal in the hub's forces, from the states on_step kept) and the
        friction law's dissipated work: (balance, law), J/m."""
        work, hub = states[0].duplicate(), self.el.dofs["hub"]

        def forces_and_energy(x):
            self.el.K.mult(x, work)
            return work.getArray().reshape(-1, 2)[hub].copy(), 0.5 * x.dot(work)

        balance, law = [], []
        for i in [i for i, s in enumerate(self.run.steps) if s.point[1] > 0]:
            (f0, e0), (f1, e1) = forces_and_energy(states[i - 1]), forces_and_energy(states[i])
            u0, u1 = (states[k].getArray().reshape(-1, 2)[hub] for k in (i - 1, i))
            balance.append(np.sum(0.5 * (f0 + f1) * (u1 - u0)) - (e1 - e0))
            law.append(self.run.steps[i].dissipated)
        return balance, law

    def half_angles_deg(self):
        from pinbore.fem.post import angle_from, half_angle

        d = self.scene.load.direction_deg
        return [math.degrees(half_angle(angle_from(d, s.contact.angle), s.contact.pressure))
                for s in self.run.steps]


def pinbore(*args, cwd=None, process=False) -> subprocess.CompletedProcess:
    """Run the pinbore command: `pinbore.cli.main` in this process (its imports shared by the
    worker's tests), its stdout, stderr and warnings captured as a fresh process would print
    them; in a process of its own (as installed in this interpreter's environment) if
    `process`, for what only a process shows (signals, exit, the modules it loads)."""
    argv = [str(a) for a in args]
    if process:
        return subprocess.run([sys.executable, "-m", "pinbore.cli", *argv],
                              capture_output=True, text=True, cwd=cwd)
    import contextlib
    import io
    import os
    import warnings

    from pinbore.cli import main

    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with (contextlib.redirect_stdout(out), contextlib.redirect_stderr(err),
              warnings.catch_warnings(record=True) as caught):
            warnings.simplefilter("default")   # a fresh process's: each warning once a place
            try:
                code = main(argv)
            except SystemExit as stop:   # argparse's usage errors
                code = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
            for w in caught:
                err.write(warnings.formatwarning(w.message, w.category, w.filename, w.lineno, w.line))
    finally:
        os.chdir(here)
    return subprocess.CompletedProcess(["pinbore", *argv], code, out.getvalue(), err.getvalue())


def main_in_child(*argv) -> subprocess.CompletedProcess:
    """pinbore.cli.main(argv) in a fresh interpreter, which fails (an AssertionError) if DOLFINx
    or a mechanism's model got loaded; its stdout is the child's CPU time (s), import of the CLI included."""
    code = ("import resource, sys; from pinbore.cli import main; "
            f"code = main({[str(a) for a in argv]!r}); "
            "assert not any(m.split('.')[0] == 'dolfinx' or m == 'pinbore.reduced.mechanism.model' "
            "for m in sys.modules), 'loaded'; "
            "u = resource.getrusage(resource.RUSAGE_SELF); print(u.ru_utime + u.ru_stime); sys.exit(code)")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)


@pytest.fixture
def write_scene(tmp_path):
    """Write a scene dict (or raw text) to a TOML file and return its path."""
    import tomli_w

    def write(data, name="scene.toml"):
        path = tmp_path / name
        path.write_text(data if isinstance(data, str) else tomli_w.dumps(data))
        return path

    return write


def compound_pendulum(t, mass, inertia, arm, gravity=9.81):
    """The angle from +x (rad) of a compound pendulum released at rest from horizontal, its
    pivot at `arm` from the centre of mass (inertia about the centre): with phi from the
    downward vertical, sin(phi/2) = k sn(K(k) - w0 t, k), k = sin(45 deg), w0^2 = m g d / J_O
    (Jacobi's elliptic sine: exact at any amplitude)."""
    import scipy.special

    w0 = math.sqrt(mass * gravity * arm / (inertia + mass * arm ** 2))
    m = 0.5
    sn = scipy.special.ellipj(scipy.special.ellipk(m) - w0 * t, m)[0]
    return 2 * np.arcsin(math.sqrt(m) * sn) - math.pi / 2


def kinematic_duality(data: dict, point, seed=0, eta=1e-3, rates=1.0):
    """A flexible body (the scene's first) at a state whose modal coordinates (about `eta`,
    m sqrt(kg)) and every rate (about `rates`) are random, and the body point `point` (body
    frame) on it: (P' of the point (the core's point_state of its body kind), the velocity of
    the material at its deformed place P (material_velocity), f . P' and G . q' with G the
    generalised force of a force f acting at P (push) and q' the bodies' velocities, for a
    random f). The first two are one velocity reached two ways (from the material point and
    back from its place), the last two the power of f by virtual work."""
    from pinbore.core import cpp
    from pinbore.reduced.mechanism import kernel, kinds
    from pinbore.reduced.mechanism.model import build

    scene = kinds.validate(data, "test")
    model = build(scene, "test", ROOT)
    args = model.args()
    rng = np.random.default_rng(seed)
    y = model.y0.copy()
    nq = model.nq
    planar = len(args.like) == 2
    first = 3 if planar else 7                   # (x, y, angle) or (r, Euler parameters)
    modes = int(args.offsets[1] - args.offsets[0]) - (3 if planar else 6)
    y[first:first + modes] = eta * rng.standard_normal(modes)
    y[nq:2 * nq] = rates * rng.standard_normal(nq)
    if not planar:   # unit Euler parameters and a rate normal to them
        p = y[3:7] / np.linalg.norm(y[3:7])
        y[3:7] = p
        y[nq + 3:nq + 7] -= p * (p @ y[nq + 3:nq + 7])
    work = kernel.workspace(args)
    f = rng.standard_normal(len(point))
    _, velocity, material, force = cpp.mechanism.point_kinematics(y, args, work, 0, list(point), list(f))
    return velocity, material, float(np.dot(f, velocity)), float(force @ work.velocities)


def simulated(data: dict):
    """(model, trajectory) of a mechanism scene dict of any kind, run whole (status 0)."""
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import build
    from pinbore.reduced.mechanism.run import simulate

    model = build(kinds.validate(data, "test"), "test", ROOT)
    trajectory = simulate(model)
    assert trajectory.status == 0
    return model, trajectory


@functools.cache
def bench_audit():
    """bench/audit.py as a module, loaded once (its session_processes: a stopped command's
    leftovers)."""
    import importlib.util   # noqa: PLC0415

    spec = importlib.util.spec_from_file_location("audit", ROOT / "bench" / "audit.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def stopped_midrun(args, cwd, out, signum, wait=1.0, group=False, until=None):
    """`pinbore ARGS` in a process of its own (its own session and TMPDIR, cwd/tmp), stopped
    by `signum` `wait` s after it takes `out`'s lock (or 10 s after it starts, if it has not
    by then: a command that takes it only to write) and, if `until`, has printed that text to
    stderr (SIGINT to its process group as Ctrl-C sends it, if `group`; else to the
    command): (the completed process, the seconds from the signal to its exit, the processes
    of its session still running (given up to 2 s to end), what it left in its TMPDIR)."""
    import os
    import signal
    import threading
    import time

    tmp = Path(cwd) / "tmp"
    tmp.mkdir(exist_ok=True)
    run = subprocess.Popen([sys.executable, "-m", "pinbore.cli", *map(str, args)], cwd=cwd,
                           stderr=subprocess.PIPE, start_new_session=True,
                           env=dict(os.environ, TMPDIR=str(tmp)))
    said = []
    reader = threading.Thread(target=lambda: said.extend(iter(lambda: os.read(run.stderr.fileno(), 65536), b"")),
                              daemon=True)
    reader.start()
    lock = Path(out).parent / f".{Path(out).name}.pinbore-lock"
    deadline = time.monotonic() + 10
    while not lock.exists() and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    deadline = time.monotonic() + 60
    while until is not None and until.encode() not in b"".join(said) and run.poll() is None \
            and time.monotonic() < deadline:
        time.sleep(0.02)
    time.sleep(wait)
    assert run.poll() is None, f"the run ended before it could be stopped: {b''.join(said).decode()}"
    (os.killpg if group else os.kill)(run.pid, signum)
    sent = time.monotonic()
    run.wait(timeout=120)
    seconds = time.monotonic() - sent
    reader.join(timeout=10)

    session = bench_audit().session_processes
    deadline = time.monotonic() + 2.0
    while (left := session(run.pid)) and time.monotonic() < deadline:
        time.sleep(0.05)
    for pid in left:   # the test's own processes, ended by id
        os.kill(pid, signal.SIGKILL)
    stderr = b"".join(said).decode(errors="replace")
    return subprocess.CompletedProcess(run.args, run.returncode, "", stderr), seconds, left, sorted(tmp.iterdir())
