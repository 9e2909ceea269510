"""Stress matrix of numerical stability: the reduced model and the 2D FE solver driven far
from their shipped scenes, one parameter at a time.

Every point is one `pinbore reduced` or `pinbore fem` subprocess in a temporary directory,
with a wall-clock limit (a point past it is killed and recorded as `hang`), so that a hang
or crash of one point cannot take the matrix down; its row is built from the files it wrote.
Two points run at a time.

Multibody (around scenes/reduced/slider_crank_flores2004.toml, one crank revolution at
5000 rpm, 0.012 s, no plots): contact modulus, clearance (journal radius changed, bearing
radius kept), restitution and drive speed swept alone; every friction law at mu 0, 0.2, 0.8;
every damping law; every integrator at its defaults.

Spatial multibody (around scenes/reduced/spatial_slider_crank_flores.toml, one revolution):
the slider's mass from 1e-12 kg to 10 kg (the mass ratio), and scenes with two joints or two
clearance joints of one name.

Dynamic impact (around the restitution study's point study_steel_c100um_v1000mm_s, coarse: 30 steps
over the contact): the hub's added mass, the impact speed, the initial gap (up to and beyond
the diametral clearance) and the steps over the contact, swept alone.

FE (around scenes/fem/steel_c10um.toml, 2D, 4 load steps, no pictures): c/R, modulus ratio
pin/bore, Poisson's ratio, max_approach, penalty factor (penalty and augmented Lagrangian),
mu = 0.8 with a rotation after the push.

Outcome of a point: complete / suspect / incomplete (from the file it wrote), refused (exit
2, bad input), hang (wall-clock limit), crash (exit 3, another exit code or signal, or no
readable file). The criterion (column `ok`): no NaN, no hang, no crash, and no `complete`
run whose numbers break the verdict's thresholds (recomputed here from summary.json or
impact.json, not taken from its status; FE: a run marked complete must have converged every load step of
its programme and, with the augmented Lagrangian, meet its gap tolerance). The script exits 0 whatever the points do (it is
a measurement) and prints `stress: N points, M failed the criterion` and the failures.

Writes OUT/stress_reduced.csv (planar and spatial), OUT/stress_impact.csv, OUT/stress_fem.csv
and OUT/stress.png.
"""

import argparse
import copy
import csv
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

import matplotlib.lines
import matplotlib.patches
import tomli_w
from tqdm import tqdm

from pinbore.core.figures import plt, save_png
from pinbore.fem.curve import COLUMNS as CURVE_COLUMNS
from pinbore.fem.impact import file as impact_file
from pinbore.laws.dissipative import HYSTERESIS
from pinbore.reduced.mechanism import kinds, verdict
from pinbore.reduced.mechanism.scene import clearance_joints
from pinbore.study import point_scene

ROOT = Path(__file__).resolve().parent.parent
REDUCED_SCENE = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
SPATIAL_SCENE = ROOT / "scenes" / "reduced" / "spatial_slider_crank_flores.toml"
IMPACT_POINT = (ROOT / "studies" / "restitution.toml", "study_steel_c100um_v1000mm_s")
FEM_SCENE = ROOT / "scenes" / "fem" / "steel_c10um.toml"
TIMEOUT = {"reduced": 120.0, "fem": 300.0, "impact": 300.0}
WORKERS = 2
OUTCOMES = ["complete", "suspect", "incomplete", "refused", "hang", "crash"]
COLOURS = {"complete": "#4caf50", "suspect": "#ffc107", "incomplete": "#ff7f0e",
           "refused": "#9e9e9e", "hang": "#7b1fa2", "crash": "#d32f2f"}


# ---------------------------------------------------------------- the points

def friction_table(law: str, mu: float) -> dict:
    """A friction table of `law` at coefficient mu, its other parameters plausible for a
    steel journal (regularisation 0.1-1 mm/s, Stribeck speed 10 mm/s, bristle/micro-slip
    lengths about a micrometre)."""
    return {"coulomb_ambrosio": {"law": law, "mu": mu},
            "stribeck": {"law": law, "mu_static": mu, "mu_min": 0.6 * mu, "v_min": 0.01},
            "linear": {"law": law, "mu_static": mu, "alpha": 0.1},
            "lugre": {"law": law, "mu_coulomb": mu, "mu_static": 1.25 * mu,
                      "stribeck_speed": 0.01, "sigma0": 1e5, "sigma1": 0.0, "sigma2": 0.0},
            "dahl": {"law": law, "mu": mu, "sigma": 1e5},
            "iwan_bilinear": {"law": law, "mu": mu, "k1": 1e8}}[law]


FRICTION_LAWS = ["coulomb_ambrosio", "stribeck", "linear", "lugre", "dahl", "iwan_bilinear"]


def adder(command: str, base: dict, points: list, parts=lambda scene: (scene,)):
    """add(sweep, label, parameter, value, edit): a point of `command` on a copy of the scene
    `base`, edited by edit(*parts(scene)), appended to `points`."""
    def add(sweep, label, parameter, value, edit):
        scene = copy.deepcopy(base)
        edit(*parts(scene))
        points.append({"command": command, "sweep": sweep, "label": label, "parameter": parameter,
                       "value": value, "scene": scene})
    return add


def reduced_points() -> list[dict]:
    """(sweep, label, parameter, value, scene) of every multibody point."""
    base = tomllib.loads(REDUCED_SCENE.read_text())
    base["duration"] = 0.012
    base["output"] = {"plots": False}
    points = []

    add = adder("reduced", base, points, lambda s: (s, s["clearance_joints"][0]))

    for E in (1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13):
        add("contact modulus E (Pa)", f"{E:.0e}", "E", E, lambda s, j, E=E: j.update(E=E))
    for c in (1e-6, 1e-5, 1e-4, 3e-4, 1e-3):
        add("clearance (m)", f"{c:.0e}", "clearance", c,
            lambda s, j, c=c: j.update(journal_radius=j["bearing_radius"] - c))
    for e in (0.1, 0.3, 0.5, 0.7, 0.9, 1.0):
        add("restitution", f"{e:g}", "restitution", e, lambda s, j, e=e: j.update(restitution=e))
    for rpm in (100, 300, 1000, 3000, 10000):
        add("drive speed (rpm)", f"{rpm:g}", "speed_rpm", rpm,
            lambda s, j, rpm=rpm: s["drive"].update(speed_rpm=float(rpm)))
    for law in FRICTION_LAWS:
        for mu in (0.0, 0.2, 0.8):
            add(f"friction {law} (mu)", f"{mu:g}", f"friction {law} mu", mu,
                lambda s, j, law=law, mu=mu: j.update(friction=friction_table(law, mu)))
    for law in ["none"] + sorted(HYSTERESIS):
        add("damping law", law, "damping_law", law, lambda s, j, law=law: j.update(damping_law=law))
    for method in ("dopri5", "rosenbrock23", "dopri5_fixed"):
        add("integrator (defaults)", method, "integrator", method,
            lambda s, j, method=method: s.update(integrator={"method": method}))
    return points


def spatial_points() -> list[dict]:
    """The spatial slider-crank's points: the mass ratio, names given twice."""
    base = tomllib.loads(SPATIAL_SCENE.read_text())
    base["duration"] = 0.012
    base["output"] = {"plots": False}
    points = []

    add = adder("reduced", base, points)

    def slider(scene):
        return next(b for b in scene["bodies"] if b["name"] == "slider")

    for mass in (1e-12, 1e-9, 1e-6, 1e-3, 1e-1, 10.0):
        add("spatial: slider mass (kg)", f"{mass:.0e}", "slider mass", mass,
            lambda s, m=mass: slider(s).update(mass=m))
    add("spatial: a name twice", "joints", "names", "joints",
        lambda s: s["joints"][1].update(name=s["joints"][0]["name"]))
    add("spatial: a name twice", "clearance joints", "names", "clearance joints",
        lambda s: s["clearance_joints"].append(copy.deepcopy(s["clearance_joints"][0])))
    return points


def impact_points() -> list[dict]:
    """The dynamic impact's points, each parameter alone around a coarse steel impact."""
    base = point_scene(*IMPACT_POINT)
    base["impact"]["steps_per_contact"] = 30
    base["output"] = {"picture": False}
    clearance = base["geometry"]["bore_radius"] - base["geometry"]["pin_radius"]
    points = []

    add = adder("impact", base, points, lambda s: (s["impact"],))

    for mass in (0.0, 1.0, 1e2, 1e4):
        add("impact: hub mass (kg/m)", f"{mass:g}", "hub_mass", mass,
            lambda i, m=mass: i.update(hub_mass=m))
    for speed in (0.01, 0.1, 5.0, 20.0):
        add("impact: speed (m/s)", f"{speed:g}", "speed", speed,
            lambda i, v=speed: i.update(speed=v))
    for gap in (0.1, 1.0, 1.9, 2.0, 3.0):
        add("impact: initial gap (c)", f"{gap:g}", "initial_gap / c", gap,
            lambda i, g=gap: i.update(initial_gap=g * clearance))
    for steps in (10, 100):
        add("impact: steps over the contact", f"{steps}", "steps_per_contact", steps,
            lambda i, n=steps: i.update(steps_per_contact=n))
    return points


def fem_points() -> list[dict]:
    """(sweep, label, parameter, value, scene) of every FE point."""
    base = tomllib.loads(FEM_SCENE.read_text())
    base["load"]["steps"] = 4
    base["output"] = {"fields": False, "picture": False}
    points = []

    add = adder("fem", base, points)

    for ratio in (1e-5, 1e-4, 1e-3, 1e-2, 5e-2, 0.2):
        add("c/R", f"{ratio:g}", "c/R", ratio, lambda s, ratio=ratio: s["geometry"].update(
            pin_radius=s["geometry"]["bore_radius"] * (1 - ratio)))
    for ratio in (1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3):
        add("E pin / E bore", f"{ratio:g}", "E_pin/E_bore", ratio, lambda s, ratio=ratio:
            s["materials"]["pin"].update(E=ratio * s["materials"]["bore"]["E"]))
    for nu in (0.0, 0.3, 0.45, 0.49):
        add("nu (both)", f"{nu:g}", "nu", nu, lambda s, nu=nu: (
            s["materials"]["pin"].update(nu=nu), s["materials"]["bore"].update(nu=nu)))
    for approach in (1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 3e-5, 1e-4):
        add("max_approach (m)", f"{approach:.0e}", "max_approach", approach,
            lambda s, a=approach: s["load"].update(max_approach=a))
    for method in ("penalty", "augmented-lagrangian"):
        short = "AL" if method == "augmented-lagrangian" else "penalty"
        for factor in (1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6):
            add(f"penalty_factor, {short}", f"{factor:.0e}", "penalty_factor", factor,
                lambda s, f=factor, m=method: s["contact"].update(method=m, penalty_factor=f))
    # small-strain rule R phi^2 / 2 <= 1 % of max_approach: 0.256 deg at 10 um on R = 9.99 mm
    for rotation in (0.01, 0.05, 0.1, 0.25):
        add("mu 0.8, rotation_deg (AL)", f"{rotation:g}", "rotation_deg", rotation,
            lambda s, r=rotation: (s["contact"].update(friction=0.8),
                                   s["load"].update(rotation_deg=r, slide_steps=4)))
    add("mu 0.8, rotation_deg (penalty)", "0.1", "rotation_deg", 0.1,
        lambda s: (s["contact"].update(method="penalty", friction=0.8),
                   s["load"].update(rotation_deg=0.1, slide_steps=4)))
    return points


# ---------------------------------------------------------------- running one point

def failures(done: dict, outcome: str, nan: str | bool, broken: list, timeout: float) -> list[str]:
    """Why a point fails the criterion: NaN, a hang, a crash, or a complete run whose numbers
    break the thresholds (`broken`); empty if it passes."""
    found = [nan] if nan else []
    if outcome == "hang":
        found.append(f"no result within {timeout:g} s")
    if outcome == "crash":
        found.append(f"exit {done['exit_code']}: {first_line(done['stderr'])}{where(done['stderr'])}")
    if broken:
        found.append("complete but " + ", ".join(broken))
    return found


def run_point(point: dict) -> dict:
    """Run one point's CLI command in a temporary directory under its wall-clock limit;
    (exit code or None on timeout, wall time, stderr, what it wrote as parsed JSON/text)."""
    pinbore_command = point["command"]   # the CLI command that runs it: reduced or fem
    with tempfile.TemporaryDirectory(prefix=f"stress-{pinbore_command}-") as tmp:
        tmp = Path(tmp)
        scene_path = tmp / "scene.toml"
        scene_path.write_text(tomli_w.dumps(point["scene"]))
        out = tmp / "out"
        command = [sys.executable, "-m", "pinbore.cli", pinbore_command, str(scene_path), "--out", str(out)]
        env = os.environ | {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
        start = time.perf_counter()
        process = subprocess.Popen(command, cwd=tmp, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True, env=env, start_new_session=True)
        try:
            _, stderr = process.communicate(timeout=TIMEOUT[pinbore_command])
            code = process.returncode
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)   # its own session: the point and its children
            _, stderr = process.communicate()
            code = None
        wall = time.perf_counter() - start
        files = {}
        for name in ("summary.json", "result.json", "curve.csv", "impact.json"):
            path = out / name
            if path.exists():
                files[name] = path.read_text()
    return point | {"exit_code": code, "wall_s": wall, "stderr": stderr, "files": files}


def where(stderr: str) -> str:
    """The innermost frame of the traceback file an internal error (exit 3) names."""
    marker = "traceback in "
    if marker not in stderr:
        return ""
    try:
        trace = Path(stderr.split(marker, 1)[1].split()[0]).read_text()
    except OSError:
        return ""
    frames = [line.strip() for line in trace.splitlines() if line.strip().startswith("File ")]
    return f" (at {frames[-1]})" if frames else ""


def first_line(text: str) -> str:
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1][:300] if lines else ""


def any_nan(value) -> bool:
    if isinstance(value, float):
        return math.isnan(value)
    if isinstance(value, dict):
        return any(any_nan(v) for v in value.values())
    if isinstance(value, list):
        return any(any_nan(v) for v in value)
    return False


def outcome_of(done: dict, file: str) -> tuple[str, dict | None]:
    """The outcome from the exit code and the file, and the file parsed (None if absent)."""
    code = done["exit_code"]
    if code is None:
        return "hang", None
    if code == 2:
        return "refused", None
    data = None
    if file in done["files"]:
        try:
            data = json.loads(done["files"][file])   # NaN and Infinity read as floats
        except ValueError:
            data = None
    if code not in (0, 1) or data is None or data.get("status") not in ("complete", "incomplete", "suspect"):
        return "crash", data
    return data["status"], data


# ---------------------------------------------------------------- multibody rows

def reduced_bound(friction) -> float:
    """The largest F_t / F_n the friction table (validated, or None) allows, computed here
    from its parameters (inf: the law sets no bound)."""
    if friction is None:
        return 0.0
    law = friction.law
    if law in ("coulomb_ambrosio", "dahl"):
        return friction.mu
    if law == "stribeck":
        return max(friction.mu_static, friction.mu_min)
    if law == "iwan_bilinear" and friction.k2 == 0:
        return friction.mu
    return math.inf


def scene_joints(scene: dict) -> list:
    """The clearance joints of a point's scene of any kind (validated through the registry),
    in the order of summary.json."""
    return clearance_joints(kinds.validate(scene, "stress point"))


def reduced_breaks(s: dict, scene: dict) -> list[str]:
    """The verdict's thresholds recomputed from summary.json, whatever its status says."""
    broken = []
    energy = s["energy_balance"]
    if not energy["relative_to_peak_kinetic"] <= verdict.ENERGY_RESIDUAL:
        broken.append(f"energy residual {energy['relative_to_peak_kinetic']:.3g}")
    if energy["dissipated_J"] < -max(energy["max_residual_J"], 1e-12):
        broken.append(f"dissipated {energy['dissipated_J']:.3g} J")
    clearances = []
    for joint in scene_joints(scene):
        clearances.append(joint.gap())
        peaks = s["clearance_joints"].get(joint.name)
        if peaks is None:
            continue
        if not peaks["peak_penetration_m"] <= verdict.PENETRATION * peaks["clearance_m"]:
            broken.append(f"penetration {peaks['peak_penetration_m'] / peaks['clearance_m']:.3g} c")
        bound = reduced_bound(joint.friction)
        if peaks["peak_normal_force_N"] > 0 and math.isfinite(bound):
            ratio = peaks["peak_friction_force_N"] / peaks["peak_normal_force_N"]
            if ratio > verdict.FRICTION_MARGIN * bound:
                broken.append(f"friction ratio {ratio:.3g} > bound {bound:g}")
    limit = verdict.DRIFT * (min(clearances) if clearances else 1e-3)
    if not s["constraint_drift_max"] <= limit:
        broken.append(f"drift {s['constraint_drift_max']:.3g} m")
    return broken


def row_head(done: dict, outcome: str, data: dict | None) -> dict:
    """The columns every row starts with: the point, its outcome and its run."""
    return {"sweep": done["sweep"], "parameter": done["parameter"], "value": done["value"],
            "outcome": outcome, "status": (data or {}).get("status", ""),
            "exit_code": "" if done["exit_code"] is None else done["exit_code"],
            "wall_time_s": f"{done['wall_s']:.2f}"}


def reduced_row(done: dict) -> dict:
    outcome, s = outcome_of(done, "summary.json")
    row = row_head(done, outcome, s)
    nan = s is not None and any_nan(s)
    broken = []
    if s is not None and outcome != "crash":
        name, joint = next(iter(s["clearance_joints"].items()))
        scene_joint = next(c for c in scene_joints(done["scene"]) if c.name == name)
        ratio = (joint["peak_friction_force_N"] / joint["peak_normal_force_N"]
                 if joint["peak_normal_force_N"] > 0 else 0.0)
        row |= {"energy_residual_rel": f"{s['energy_balance']['relative_to_peak_kinetic']:.3g}",
                "dissipated_J": f"{s['energy_balance']['dissipated_J']:.4g}",
                "drift_m": f"{s['constraint_drift_max']:.3g}",
                "penetration_over_clearance": f"{joint['peak_penetration_m'] / joint['clearance_m']:.3g}",
                "peak_normal_force_N": f"{joint['peak_normal_force_N']:.4g}",
                "friction_ratio": f"{ratio:.3g}",
                "friction_bound": f"{reduced_bound(scene_joint.friction):g}",
                "steps": s["steps"], "rejected_steps": s["rejected_steps"], "impacts": s["impacts"],
                "time_reached_s": f"{s['time_reached_s']:.4g}",
                "verdict": "; ".join(s.get("verdict", [])
                                     + ([f"stopped: {s['stop']['reason']}"] if s.get("stop") else []))}
        if s["status"] == "complete":
            broken = reduced_breaks(s, done["scene"])
    row["nan_in_summary"] = nan
    failure = failures(done, outcome, nan and "NaN in summary.json", broken, TIMEOUT["reduced"])
    if outcome == "refused":
        row["verdict"] = first_line(done["stderr"])
    row["ok"] = not failure
    row["failure"] = "; ".join(failure)
    return row


REDUCED_COLUMNS = ["sweep", "parameter", "value", "outcome", "status", "exit_code", "wall_time_s",
                   "energy_residual_rel", "dissipated_J", "drift_m", "nan_in_summary",
                   "penetration_over_clearance", "peak_normal_force_N", "friction_ratio",
                   "friction_bound", "steps", "rejected_steps", "impacts", "time_reached_s",
                   "verdict", "ok", "failure"]


# ---------------------------------------------------------------- impact rows

def impact_breaks(s: dict) -> list[str]:
    """The impact verdict (fem.impact.file.verdict) applied afresh to impact.json's numbers,
    whatever its status says."""
    return impact_file.verdict(impact_file.ImpactSummary.model_validate(s))


def impact_row(done: dict) -> dict:
    outcome, s = outcome_of(done, "impact.json")
    row = row_head(done, outcome, s)
    nan = s is not None and any_nan(s)
    broken = []
    if s is not None and outcome != "crash":
        energy, estimate = s["energy"], s["estimate"]["contact_duration_s"]
        duration = s.get("contact_duration_s")
        row |= {"restitution": "" if s.get("restitution") is None else f"{s['restitution']:.4f}",
                "contact_over_estimate": "" if duration is None else f"{duration / estimate:.3g}",
                "book_residual_over_E0": f"{energy['max_relative_residual']:.3g}",
                "vibration_over_E0": f"{energy['wave_J_per_m'] / energy['impact_J_per_m']:.3g}",
                "steps": s.get("steps", ""), "verdict": "; ".join(s.get("verdict", []))}
        if s["status"] == "complete":
            broken = impact_breaks(s)
    if outcome in ("refused", "crash", "incomplete") and not row.get("verdict"):
        row["verdict"] = first_line(done["stderr"])
    row["nan"] = nan
    failure = failures(done, outcome, nan and "NaN in impact.json", broken, TIMEOUT["impact"])
    row["ok"] = not failure
    row["failure"] = "; ".join(failure)
    return row


IMPACT_COLUMNS = ["sweep", "parameter", "value", "outcome", "status", "exit_code", "wall_time_s",
                  "restitution", "contact_over_estimate", "book_residual_over_E0",
                  "vibration_over_E0", "steps", "nan", "verdict", "ok", "failure"]


# ---------------------------------------------------------------- FE rows

# the curve.csv columns whose NaN means "undefined here", not a lost value (e.g. the residual
# approach on a step that ends no unloading): the curve reader accepts them
UNDEFINED_OK = {c.name for columns in CURVE_COLUMNS.values() for c in columns.values() if c.undefined_ok}


def curve_nan(text: str) -> bool:
    """Any cell of curve.csv that reads as NaN (read raw: the curve reader refuses them), but
    in the columns where NaN means undefined (UNDEFINED_OK)."""
    rows = list(csv.reader(text.splitlines()))
    header = rows[0] if rows else []
    for row in rows[1:]:
        for name, cell in zip(header, row):
            if name in UNDEFINED_OK:
                continue
            try:
                if math.isnan(float(cell)):
                    return True
            except ValueError:
                if cell.strip().lower() in ("nan", "-nan"):
                    return True
    return False


def fem_row(done: dict) -> dict:
    outcome, r = outcome_of(done, "result.json")
    scene = done["scene"]
    row = row_head(done, outcome, r) | {"method": scene["contact"]["method"]}
    nan = (r is not None and any_nan(r)) or ("curve.csv" in done["files"] and curve_nan(done["files"]["curve.csv"]))
    broken = []
    if r is not None and outcome != "crash":
        newton = r.get("newton_iterations", [])
        expected = scene["load"]["steps"] + (scene["load"].get("slide_steps", 10)
                                             if scene["load"].get("rotation_deg") else 0)
        tolerance = r["contact"].get("gap_tolerance_m")
        row |= {"newton_median": statistics.median(newton) if newton else "",
                "newton_max": max(newton) if newton else "",
                "cutbacks": r.get("cutbacks", ""), "steps_converged": r.get("steps_converged", ""),
                "steps_expected": expected, "dofs": r.get("dofs", ""),
                "max_gap_violation_m": f"{r.get('max_gap_violation_m', float('nan')):.3g}",
                "gap_tolerance_m": "" if tolerance is None else f"{tolerance:.3g}",
                "message": (r.get("stop") or {}).get("reason", "") if isinstance(r.get("stop"), dict)
                           else str(r.get("stop") or "")}
        if r["status"] == "complete":
            # a cutback splits a step: complete runs converge at least the programme's steps
            if not r.get("steps_converged", 0) >= expected:
                broken.append(f"{r.get('steps_converged')} of {expected} steps")
            if (scene["contact"]["method"] == "augmented-lagrangian" and tolerance is not None
                    and not r["max_gap_violation_m"] <= 1.01 * tolerance):
                broken.append(f"gap violation {r['max_gap_violation_m']:.3g} m > tolerance {tolerance:.3g} m")
    if outcome in ("refused", "crash") or (outcome == "incomplete" and not row.get("message")):
        row["message"] = first_line(done["stderr"])
    row["nan"] = nan
    failure = failures(done, outcome, nan and "NaN in result.json or curve.csv", broken,
                       TIMEOUT["fem"])
    row["ok"] = not failure
    row["failure"] = "; ".join(failure)
    return row


FEM_COLUMNS = ["sweep", "parameter", "value", "method", "outcome", "status", "exit_code",
               "wall_time_s", "newton_median", "newton_max", "cutbacks", "steps_converged",
               "steps_expected", "dofs", "nan", "max_gap_violation_m", "gap_tolerance_m",
               "message", "ok", "failure"]


# ---------------------------------------------------------------- outputs

def write_csv(path: Path, columns, rows) -> None:
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({c: row.get(c, "") for c in columns})


def sweeps_of(rows) -> dict[str, list[dict]]:
    sweeps = {}
    for row in rows:
        sweeps.setdefault(row["sweep"], []).append(row)
    return sweeps


def heat_map(path: Path, panels) -> None:
    """One strip per sweep, a cell per point coloured by outcome and labelled by its value
    (a cell that failed the criterion is crossed); `panels`: (title, rows) with rows."""
    panels = [(title, sweeps_of(rows)) for title, rows in panels if rows]
    width = max(len(cells) for _, sweeps in panels for cells in sweeps.values())
    heights = [len(sweeps) for _, sweeps in panels]
    fig, axes = plt.subplots(len(panels), 1, figsize=(2.6 + 1.05 * width, 0.42 * sum(heights) + 2.2),
                             gridspec_kw={"height_ratios": heights}, squeeze=False)
    axes = axes[:, 0]
    for ax, (title, sweeps) in zip(axes, panels):
        for i, (sweep, cells) in enumerate(sweeps.items()):
            for j, row in enumerate(cells):
                ax.add_patch(matplotlib.patches.Rectangle((j, -i - 1), 0.96, 0.9,
                                                          color=COLOURS[row["outcome"]]))
                label = str(row["value"])
                if isinstance(row["value"], float):
                    label = f"{row['value']:g}"
                ax.text(j + 0.48, -i - 0.55, label.replace("_", " "), ha="center", va="center",
                        fontsize=6.5 if len(label) < 12 else 5.5)
                if not row["ok"]:
                    ax.plot([j + 0.05, j + 0.91], [-i - 0.95, -i - 0.15], color="k", lw=1.2)
        ax.set_yticks([-i - 0.55 for i in range(len(sweeps))], list(sweeps))
        ax.tick_params(axis="y", labelsize=7, length=0)
        ax.set_xticks([])
        ax.set_xlim(0, width)
        ax.set_ylim(-len(sweeps) - 0.1, 0)
        for side in ax.spines.values():
            side.set_visible(False)
        ax.set_title(title, fontsize=9)
    handles = [matplotlib.patches.Patch(color=COLOURS[o], label=o) for o in OUTCOMES]
    handles.append(matplotlib.lines.Line2D([], [], color="k", lw=1.2, label="failed the criterion"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False)
    save_png(fig, path, layout=True, bbox_inches="tight")


def main(out: Path, only: str | None, sweep: str | None, limit: int | None) -> int:
    points = []
    if only in (None, "reduced"):
        points += reduced_points() + spatial_points()
    if only in (None, "impact"):
        points += impact_points()
    if only in (None, "fem"):
        points += fem_points()
    if sweep:
        points = [p for p in points if sweep in p["sweep"]]
    if limit:
        points = points[:limit]
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    done = [None] * len(points)
    with ThreadPoolExecutor(WORKERS) as pool:
        futures = {pool.submit(run_point, p): k for k, p in enumerate(points)}
        for future in tqdm(as_completed(futures), total=len(points), desc="stress", unit="point"):
            done[futures[future]] = future.result()
    reduced_rows = [reduced_row(d) for d in done if d["command"] == "reduced"]
    impact_rows = [impact_row(d) for d in done if d["command"] == "impact"]
    fem_rows = [fem_row(d) for d in done if d["command"] == "fem"]
    if reduced_rows:
        write_csv(out / "stress_reduced.csv", REDUCED_COLUMNS, reduced_rows)
    if impact_rows:
        write_csv(out / "stress_impact.csv", IMPACT_COLUMNS, impact_rows)
    if fem_rows:
        write_csv(out / "stress_fem.csv", FEM_COLUMNS, fem_rows)
    if only is None:
        heat_map(out / "stress.png", [
            ("multibody (slider-crank, 1 revolution; spatial: its spatial twin)", reduced_rows),
            ("dynamic impact (steel, c = 100 um, 1 m/s, coarse)", impact_rows),
            ("FE 2D (steel_c10um, 4 steps)", fem_rows)])
    rows = reduced_rows + impact_rows + fem_rows
    for name, part in (("multibody", reduced_rows), ("impact", impact_rows), ("FE", fem_rows)):
        if part:
            counts = {o: sum(r["outcome"] == o for r in part) for o in OUTCOMES}
            print(f"{name}: " + ", ".join(f"{n} {o}" for o, n in counts.items() if n))
    failed = [r for r in rows if not r["ok"]]
    print(f"wall time of the matrix: {time.perf_counter() - start:.0f} s")
    print(f"stress: {len(rows)} points, {len(failed)} failed the criterion")
    for r in failed:
        print(f"  {r['sweep']} = {r['value']}: {r['outcome']}: {r['failure']}")
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--only", choices=["reduced", "impact", "fem"], help="run one of the matrices")
    parser.add_argument("--sweep", help="run the sweeps whose name holds this text only (trials)")
    parser.add_argument("--limit", type=int, help="run the first N points only (trials)")
    args = parser.parse_args()
    sys.exit(main(args.out, args.only, args.sweep, args.limit))
