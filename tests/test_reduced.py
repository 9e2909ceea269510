"""The reduced multibody model against independent references: the exact slider-crank
kinematics, clearance -> 0 with stiff contact, energy conservation and balance, the
restitution of a single journal impact; bad scenes."""

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT, pinbore

from pinbore.laws import dissipative
from pinbore.laws import friction as friction_laws
from pinbore.laws.elastic import Joint, hertz_point
from pinbore.reduced.mechanism import layout
from pinbore.reduced.mechanism import summary as reduced_summary
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import PlanarScene

FLORES = tomllib.loads((ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml").read_text())


def solve(data, ideal=False):
    """Integrate a planar scene dict (ideal: its ideal twin, every clearance joint closed)."""
    model = build(PlanarScene.model_validate(data), "test", ROOT, ideal=ideal)
    run = simulate(model)
    assert run.status == 0, (run.status, run.t_end)
    cols, energy, drift = per_step(model, run)
    return cols, energy, drift, run.counters


def exact_slider(theta, omega, r=0.05, l=0.12):
    """Slider position, velocity and acceleration of the ideal slider-crank, exactly (no
    long-rod approximation): x = r cos t + sqrt(l^2 - r^2 sin^2 t), crank at constant omega."""
    s, c = np.sin(theta), np.cos(theta)
    d = np.sqrt(l**2 - r**2 * s**2)
    x = r * c + d
    dx = -r * s - r**2 * s * c / d
    ddx = -r * c - r**2 * (c**2 - s**2) / d - r**4 * s**2 * c**2 / d**3
    return x, omega * dx, omega**2 * ddx


OMEGA = 5000 * 2 * math.pi / 60


def test_ideal_slider_crank_matches_exact_kinematics():
    cols, _, drift, _ = solve(FLORES, ideal=True)
    x, v, a = exact_slider(cols["crank_angle_rad"], OMEGA)
    np.testing.assert_allclose(cols["slider_x_m"], x, atol=1e-9)
    np.testing.assert_allclose(cols["slider_vx_m_per_s"], v, atol=1e-6 * OMEGA * 0.05)
    np.testing.assert_allclose(cols["slider_ax_m_per_s2"], a, atol=1e-5 * OMEGA**2 * 0.05)
    assert drift.max() < 1e-10


def test_clearance_to_zero_with_stiff_contact_converges_to_the_ideal_joint():
    """Clearance / 10 and contact stiffness x 100 per level: the slider's position and
    velocity approach the exact ideal-joint kinematics."""
    data = copy.deepcopy(FLORES)
    data["duration"] = 0.012
    gaps = []
    for level in range(3):
        joint = data["clearance_joints"][0]
        joint["journal_radius"] = 10e-3 - 5e-4 / 10**level
        joint["E"] = 207e9 * 100**level
        cols, _, _, _ = solve(data)
        x, v, _ = exact_slider(cols["crank_angle_rad"], OMEGA)
        gaps.append([np.max(np.abs(cols["slider_x_m"] - x)), np.max(np.abs(cols["slider_vx_m_per_s"] - v))])
    gaps = np.array(gaps)
    assert np.all(np.diff(gaps, axis=0) < 0), gaps
    assert gaps[-1, 0] < 1e-5 and gaps[-1, 1] < 0.5 * gaps[0, 1]


def free_mechanism(damping="none", friction=0.0):
    """The slider-crank without drive, thrown into motion (crank at 300 rad/s), gravity on."""
    data = copy.deepcopy(FLORES)
    del data["drive"]
    data["duration"] = 0.02
    data["bodies"][0]["omega"] = 300.0
    joint = data["clearance_joints"][0]
    joint["damping_law"], joint["restitution"] = damping, 0.8
    if friction:
        joint["friction"] = {"law": "coulomb_ambrosio", "mu": friction}
    data["integrator"] = {"rtol": 1e-9, "atol": 1e-12}
    return data


def test_energy_is_conserved_without_dissipation():
    _, e, _, counters = solve(free_mechanism())
    total = e["kinetic"] + e["potential"] + e["elastic"]
    assert counters[3] >= 3  # impacts happened
    assert np.max(np.abs(total - total[0])) < 1e-6 * e["kinetic"].max()
    assert np.all(e["dissipated"] == 0) and np.all(e["work_in"] == 0)


def test_dissipation_never_adds_energy_and_the_balance_closes():
    _, e, _, counters = solve(free_mechanism("hunt_crossley", friction=0.1))
    mechanical = e["kinetic"] + e["potential"] + e["elastic"]
    assert counters[3] >= 3
    assert np.all(np.diff(e["dissipated"]) >= -1e-12)
    assert e["dissipated"][-1] > 0.01 * e["kinetic"][0]
    balance = mechanical + e["dissipated"]
    assert np.max(np.abs(balance - balance[0])) < 1e-6 * e["kinetic"].max()


@pytest.mark.parametrize("law, e", [("lankarani_nikravesh", 0.9), ("flores", 0.5)])
def test_single_impact_restitution_equals_the_laws(law, e):
    """A journal thrown at 1 m/s against a fixed bearing rebounds with the effective
    restitution of its law, as measured by integrating the same impact alone."""
    mass, speed = 0.14, 1.0
    data = {"kind": "planar", "duration": 1.2e-3,
            "bodies": [{"name": "journal", "mass": mass, "inertia": 1e-5, "velocity": [0.0, -speed]}],
            "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 9.5e-3, "E": 207e9,
                                  "nu": 0.3, "normal_law": "hertz_point", "damping_law": law,
                                  "restitution": e, "start": "free"}],
            "integrator": {"rtol": 1e-10, "atol": 1e-13}}
    cols, _, _, counters = solve(data)
    assert counters[3] == 1
    rebound = cols["journal_vy_m_per_s"][-1]
    joint = Joint(10e-3, 9.5e-3, 207e9, 0.3, 207e9, 0.3, 1.0)
    chi = dissipative.HYSTERESIS[law](e)
    reference = dissipative.restitution(
        lambda d, r: dissipative.hysteresis_force(hertz_point(max(d, 0), joint), r, speed, chi),
        mass, speed)
    assert rebound / speed == pytest.approx(reference, rel=1e-4)


# the columns that hold a vector: three each (a planar mechanism reads two of them)
VECTORS = {"CONTACT_": ("CONTACT_BEARING_POINT", "CONTACT_BEARING_AXIS", "CONTACT_JOURNAL_POINT",
                        "CONTACT_JOURNAL_AXIS", "CONTACT_BEARING_REFERENCE", "CONTACT_JOURNAL_REFERENCE"),
           "PRIM_": ("PRIM_S_I", "PRIM_S_J", "PRIM_A_I", "PRIM_B_J", "PRIM_C_I"),
           "TORSION_": ("TORSION_A_I", "TORSION_B_J", "TORSION_C_I", "TORSION_S_I", "TORSION_S_J"), "LOG_": ()}


@pytest.mark.parametrize("prefix, columns", [
    ("CONTACT_", layout.CONTACT_COLUMNS), ("PRIM_", layout.PRIMITIVE_COLUMNS),
    ("TORSION_", layout.TORSION_COLUMNS), ("LOG_", layout.LOG_COLUMNS)])
def test_a_row_layout_names_every_column_once(prefix, columns):
    """The named columns of a row are 0 .. columns - 1, each once (the friction law's
    parameters take the block CONTACT_FRICTION .. + FRICTION_PARAMETERS, the calibrated
    damping's chi table CONTACT_CHI_TABLE .. + CHI_POINTS, a vector three columns)."""
    named = [v for k, v in vars(layout).items() if k.startswith(prefix) and k != f"{prefix}COLUMNS"]
    for vector in VECTORS[prefix]:
        named += range(getattr(layout, vector) + 1, getattr(layout, vector) + 3)
    if prefix == "CONTACT_":
        named += range(layout.CONTACT_FRICTION + 1, layout.CONTACT_FRICTION + layout.FRICTION_PARAMETERS)
        named += range(layout.CONTACT_CHI_TABLE + 1, layout.CONTACT_CHI_TABLE + layout.CHI_POINTS)
    assert sorted(named) == list(range(columns))


@pytest.mark.parametrize("law", ["COULOMB", "STRIBECK", "LINEAR", "LUGRE", "DAHL", "IWAN"])
def test_a_friction_law_keeps_its_parameters_in_the_friction_block(law):
    params = [v for k, v in vars(layout).items() if k.startswith(f"{law}_")]
    if law in ("COULOMB", "STRIBECK", "LINEAR"):
        params += [layout.REGULARISATION_V0, layout.REGULARISATION_V1]
    block = range(layout.CONTACT_FRICTION, layout.CONTACT_FRICTION + layout.FRICTION_PARAMETERS)
    assert params and len(set(params)) == len(params) and set(params) <= set(block)


def _scene_with(edit):
    data = copy.deepcopy(FLORES)
    edit(data)
    return data


BAD = [
    (lambda d: d["clearance_joints"][0].update(journal_radius=10.0e-3), "journal_radius must be smaller"),
    (lambda d: d["bodies"][1].update(mass=-0.21), "bodies.1.mass"),
    (lambda d: d["bodies"][2].update(inertia=0.0), "bodies.2.inertia"),
    (lambda d: d["clearance_joints"][0].update(normal_law="hertzian"), "valid: hertz_point"),
    (lambda d: d["clearance_joints"][0].update(damping_law="magic"), "valid: none, flores"),
    (lambda d: d["joints"][1].update(body_j="conrod"), "unknown body 'conrod'"),
    (lambda d: d["integrator"].update(rtol=0.0), "integrator.rtol"),
    (lambda d: d["bodies"].append({"name": "loose", "mass": 1.0, "inertia": 1.0}),
     "loose not connected to crank"),
    (lambda d: d["clearance_joints"][0].update(impact="newton"), "give no normal_law, damping_law or friction"),
    (lambda d: d["clearance_joints"][0].update(restitution=1.5), "clearance_joints.0.restitution"),
    (lambda d: d["integrator"].update(method="euler"), "integrator.method"),
]


@pytest.mark.parametrize("edit, message", BAD)
def test_bad_scenes_are_one_line_exit_2(write_scene, tmp_path, edit, message):
    done = pinbore("reduced", write_scene(_scene_with(edit)), "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_run_that_blows_up_keeps_its_time_series_and_says_so(write_scene, tmp_path):
    """A journal thrown at 2 km/s penetrates beyond a tenth of its radius."""
    def edit(d):
        d["clearance_joints"][0].update(start="free")
        d["bodies"][1].update(velocity=[0.0, -2000.0])
    done = pinbore("reduced", write_scene(_scene_with(edit)), "--out", tmp_path / "out")
    assert done.returncode == 1 and "blown up" in done.stderr
    summary = reduced_summary.read(tmp_path / "out" / "summary.json")
    assert summary.status == "incomplete" and summary.stop.time_s < FLORES["duration"]
    rows = (tmp_path / "out" / "timeseries.csv").read_text().splitlines()
    assert len(rows) > 2


def test_flores_scene_runs_and_writes_everything(tmp_path):
    out = tmp_path / "out"
    done = pinbore("reduced", ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml", "--out", out)
    assert done.returncode == 0, done.stderr
    assert {"timeseries.csv", "summary.json", "acceleration.png", "rod_slider.png"} <= {p.name for p in out.iterdir()}
    summary = reduced_summary.read(out / "summary.json")
    # at the scene's rtol = 1e-5 the balance closes to 1.7e-4 of the peak kinetic energy (the
    # strict energy tests above run at rtol = 1e-9)
    assert summary.impacts > 10 and summary.energy_balance.relative_to_peak_kinetic < 1e-3


def test_the_planar_kinds_former_name_runs_with_one_warning(write_scene, tmp_path):
    """kind = "reduced", the planar kind's former name: the same run as kind = "planar", and
    one FutureWarning that names the key and the name to write."""
    short = FLORES | {"duration": 2e-3, "output": {"plots": False}}
    done = {}
    for kind in ("planar", "reduced"):
        done[kind] = pinbore("reduced", write_scene(short | {"kind": kind}, f"{kind}.toml"),
                             "--out", tmp_path / kind)
        assert done[kind].returncode == 0, done[kind].stderr
    assert done["planar"].stderr == ""
    warned = [line for line in done["reduced"].stderr.splitlines() if "FutureWarning" in line]
    assert len(warned) == 1 and 'reduced.toml: kind: "reduced" is deprecated: write kind = "planar"' in warned[0]
    runs = [reduced_summary.read(tmp_path / kind / "summary.json") for kind in ("planar", "reduced")]
    assert runs[0].model == runs[1].model == "planar"
    assert runs[0].clearance_joints == runs[1].clearance_joints


def journal_in_fixed_bearing(friction, omega=10.0, duration=0.6):
    """A journal (1 kg) turned at omega inside a fixed bearing, under gravity."""
    return {"kind": "planar", "duration": duration, "gravity": [0.0, -9.81],
            "bodies": [{"name": "journal", "mass": 1.0, "inertia": 1e-4}],
            "drive": {"body": "journal", "speed_rpm": omega * 60 / (2 * math.pi)},
            "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 9.5e-3, "E": 207e9,
                                  "nu": 0.3, "normal_law": "hertz_point", "damping_law": "flores",
                                  "restitution": 0.3, "friction": friction}],
            "integrator": {"rtol": 1e-7, "atol": 1e-10}}


SLIP = 10.0 * 9.5e-3  # m/s, the journal's surface speed


@pytest.mark.parametrize("friction, mu", [
    ({"law": "coulomb_ambrosio", "mu": 0.2}, 0.2),
    # slip speeds stay beyond v_min, where the law holds its kinetic coefficient mu_min
    ({"law": "stribeck", "mu_static": 0.3, "mu_min": 0.2, "v_min": 0.01},
     float(friction_laws.stribeck_polynomial(SLIP, 0.3, 0.2, 0.01))),
    ({"law": "linear", "mu_static": 0.1, "alpha": 3.0}, 0.1 + 3.0 * SLIP),
    ({"law": "lugre", "mu_coulomb": 0.1, "mu_static": 0.15, "stribeck_speed": 0.05,
      "sigma0": 1e5, "sigma1": 3.0, "sigma2": 2.0},
     float(friction_laws.lugre_g(SLIP, 0.1, 0.15, 0.05)) + 2.0 * SLIP),
    ({"law": "dahl", "mu": 0.2, "sigma": 1e4}, 0.2),
])
def test_friction_circle(friction, mu):
    """A turning journal climbs the bearing wall until normal and friction forces balance
    gravity: the contact angle psi from the bottom has tan psi = mu(v) at the slip speed
    (the friction circle). With mu rising in v the swing along the wall dies out; with
    Coulomb or Dahl it does not, and its mean angle is the equilibrium."""
    cols, _, _, _ = solve(journal_in_fixed_bearing(friction))
    t = cols["time_s"]
    late = t > 0.5 * t[-1]
    psi = np.arctan2(cols["j_ecc_x_m"], -cols["j_ecc_y_m"])[late]
    mean = np.sum(psi[1:] * np.diff(t[late])) / (t[late][-1] - t[late][0])
    assert abs(math.tan(mean)) == pytest.approx(mu, rel=0.01)


@pytest.mark.parametrize("scene", ["solar_panel_deployment", "solar_panel_deployment_two_panels"])
def test_free_floating_deployment_conserves_momentum_and_energy(scene):
    """No external force: from rest, total linear and angular momentum stay zero through the
    spring-driven deployment, the latches and the hinge impacts; the energy balance closes."""
    data = tomllib.loads((ROOT / "scenes" / "reduced" / f"{scene}.toml").read_text())
    data["duration"] = 4.6   # past the latch (about 4.1 s)
    data["integrator"] = {"rtol": 1e-9, "atol": 1e-12, "max_step": 1e-3}
    cols, e, _, counters = solve(data)
    assert counters[3] > 10
    linear = np.zeros((cols["time_s"].size, 2))
    angular = np.zeros(cols["time_s"].size)
    for body in data["bodies"]:
        n, m, inertia = body["name"], body["mass"], body["inertia"]
        x, y = cols[f"{n}_x_m"], cols[f"{n}_y_m"]
        vx, vy = cols[f"{n}_vx_m_per_s"], cols[f"{n}_vy_m_per_s"]
        linear += m * np.stack([vx, vy], 1)
        angular += m * (x * vy - y * vx) + inertia * cols[f"{n}_omega_rad_per_s"]
    panel_scale = (0.25 + 3.0 * 0.5**2) * np.max(np.abs(cols["panel_omega_rad_per_s"]))
    assert np.max(np.abs(angular)) < 1e-7 * panel_scale
    assert np.max(np.abs(linear)) < 1e-7 * 3.0 * np.max(np.abs(cols["panel_vx_m_per_s"]))
    total = e["kinetic"] + e["potential"] + e["elastic"] + e["dissipated"]
    assert np.max(np.abs(total - total[0])) < 1e-6 * e["kinetic"].max()


def test_a_run_that_draws_nothing_loads_no_plotting_library():
    """A mechanism integrated and summarised without plots (what a study point does) never
    imports matplotlib: its import is 0.5 s of every point's start."""
    import subprocess   # noqa: PLC0415
    import sys   # noqa: PLC0415

    code = ("import sys; from pathlib import Path; from pinbore.reduced.mechanism import kinds, run; "
            f"p = Path({str(ROOT / 'scenes/reduced/slider_crank_flores2004.toml')!r}); "
            "s = kinds.load(p).model_copy(update={'duration': 0.002}); "
            "r = run.summarised(s, str(p), p.parent)[3]; "
            "print(r.status, 'matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["complete", "False"], out.stdout + out.stderr
