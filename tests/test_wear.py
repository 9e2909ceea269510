"""Wear of a clearance joint (reduced.wear) against Archard's law integrated in closed form
[Archard1953], and `pinbore wear` on the Flores slider-crank's joint.

- A load whose direction stands still in the bore while the pin turns at a constant speed:
  the bore wears the pressure profile times k v t, exactly; the pin, its contact going round
  it, uniformly (k v t times the mean pressure round it).
- A load turning uniformly round the bore: the bore wears uniformly.
- The worn volume per unit length is k s times the integral of p R over the surface; with a
  narrow contact arc that is Archard's V = k W s within the arc's cos(alpha) (W = F' L).
- The FE pressure carries its step's load: the integral of p cos(alpha) R is the step's F'
  within 0.5 % (the table is the run's).
- The command: the volumes of both surfaces are k times the integral of the load and the
  sliding speed over the cycle, times the cycles; bad input is one line.
"""

import math

import numpy as np
import pytest
import tomli_w
from conftest import ROOT, pinbore, with_clearance

from pinbore.reduced.wear import pressure, profile
from pinbore.reduced.wear.pressure import PressureTable

R = 10e-3          # m, the bore (and, near enough, the pin)
HALF = 0.1         # rad, the contact arc's half-angle
K = 1e-14          # m^2/N
F = 2e5            # N/m


def elliptic_table() -> PressureTable:
    """A Hertz-like profile p0 sqrt(1 - (alpha / HALF)^2) carrying F per unit length."""
    grid = np.linspace(-math.pi, math.pi, 14401)
    shape = np.sqrt(np.clip(1 - (grid / HALF) ** 2, 0, None))
    p0 = F / (np.trapezoid(shape * np.cos(grid), grid) * R)
    return PressureTable(np.array([0.0, F]), grid, np.array([0 * grid, p0 * shape]), R, R)


def test_a_load_standing_in_the_bore_wears_its_pressure_profile():
    table = elliptic_table()
    omega, turns, theta0 = 50.0, 3, 0.7
    t = np.linspace(0, turns * 2 * math.pi / omega, 12001)
    v = omega * R
    at = profile.angles(720)
    bore = profile.worn_depth(table, t, np.full(t.size, F), np.full(t.size, theta0), np.full(t.size, v), K, at, R)
    expected = K * v * t[-1] * np.interp(np.mod(at - theta0 + math.pi, 2 * math.pi) - math.pi,
                                         table.angles, table.pressure[1])
    np.testing.assert_allclose(bore, expected, rtol=1e-12, atol=1e-12 * expected.max())
    pin_angle = np.mod(theta0 - omega * t + math.pi, 2 * math.pi) - math.pi
    pin = profile.worn_depth(table, t, np.full(t.size, F), pin_angle, np.full(t.size, v), K, at, R)
    mean = K * v * t[-1] * np.trapezoid(table.pressure[1], table.angles) / (2 * math.pi)
    assert np.abs(pin / mean - 1).max() < 1e-3   # the steps sample the arc 120 times


def test_a_load_turning_round_the_bore_wears_it_uniformly_and_archards_volume():
    table = elliptic_table()
    omega = 40.0
    t = np.linspace(0, 2 * 2 * math.pi / omega, 4001)
    v = 0.3
    at = profile.angles(720)
    turning = np.mod(omega * t + math.pi, 2 * math.pi) - math.pi
    bore = profile.worn_depth(table, t, np.full(t.size, F), turning, np.full(t.size, v), K, at, R)
    assert bore.max() / bore.min() - 1 < 2e-3
    slid = v * t[-1]
    area = profile.volume_per_length(bore, R)
    assert area == pytest.approx(K * slid * np.trapezoid(table.pressure[1], table.angles) * R, rel=1e-3)
    # Archard: V / L = k F' s, within the arc's cos(alpha) (1 - HALF^2 / 8 on average)
    assert area == pytest.approx(K * F * slid, rel=2e-3)


def test_a_contact_turning_between_sparse_steps_wears_no_ripples():
    """The load turns 3 degrees between recorded steps (the Flores joint's contact slides
    2.8 degrees a step, median) over a profile read every half degree and a contact arc of
    +-5.7 degrees: each step's pressure swept over the turn to its neighbours lays the uniform
    depth of a load turning at a constant rate, to round-off, and Archard's volume; the
    pressure taken at the steps alone lays ripples of the steps' spacing (measured 10 %)."""
    table = elliptic_table()
    omega, v = 40.0, 0.3
    t = np.linspace(0, 2 * math.pi / omega, 121)   # one turn in 120 steps of 3 degrees
    at = profile.angles(720)
    turning = np.mod(omega * t + math.pi, 2 * math.pi) - math.pi
    bore = profile.worn_depth(table, t, np.full(t.size, F), turning, np.full(t.size, v), K, at, R)
    mean = K * v * t[-1] * np.trapezoid(table.pressure[1], table.angles) / (2 * math.pi)
    assert np.abs(bore / mean - 1).max() < 1e-9
    assert profile.volume_per_length(bore, R) == pytest.approx(K * F * v * t[-1], rel=2e-3)


@pytest.fixture(scope="module")
def flores_fe(tmp_path_factory):
    """The FE run of the Flores joint (pin 9.5 mm in a bore of 10 mm, plane strain), pushed
    to 2e-5 m (past 9e5 N/m, the slider-crank's load per unit length over 20 mm after its
    first impacts), coarse."""
    folder = tmp_path_factory.mktemp("fe")
    data = with_clearance(0.5e-3, 10e-3, load={"max_approach": 2e-5, "steps": 6},
                          output={"compliance": True})
    (folder / "fe.toml").write_text(tomli_w.dumps(data))
    done = pinbore("fem", folder / "fe.toml", "--out", folder / "run")
    assert done.returncode == 0, done.stderr
    return folder / "run"


def test_the_fe_pressure_carries_its_steps_load(flores_fe):
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    assert table.forces[0] == 0 and np.all(np.diff(table.forces) > 0)
    for k in range(1, table.forces.size):
        assert table.resultant(k) == pytest.approx(table.forces[k], rel=5e-3)


def wear_scene(folder, fe, **changes) -> dict:
    return {"kind": "wear", "mechanism_file": str(ROOT / "scenes/reduced/slider_crank_flores2004.toml"),
            "joint": "rod_slider", "pressure_file": str(fe / "pressure.csv"),
            "curve_file": str(fe / "curve.csv"), "length": 0.02, "cycles": 1000.0,
            "bore": {"wear_coefficient": K}, "pin": {"wear_coefficient": 2 * K}} | changes


@pytest.fixture(scope="module")
def worn(tmp_path_factory, flores_fe):
    """`pinbore wear` of the Flores joint on its coarse FE run: its output folder."""
    folder = tmp_path_factory.mktemp("worn")
    (folder / "wear.toml").write_text(tomli_w.dumps(wear_scene(folder, flores_fe)))
    done = pinbore("wear", folder / "wear.toml", "--out", folder / "build" / "wear" / "w")
    assert done.returncode == 0, done.stderr
    return folder / "build" / "wear" / "w"


def test_the_wear_command_wears_the_flores_joint(worn):
    """Both surfaces' volumes are k (cycles) times the integral of F |v_s| over the contact
    (per revolution: the mean of the run's three after its first),
    the pin's twice the bore's (its coefficient: the two lose the same area per unit k); the
    files are written."""
    import json

    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import build
    from pinbore.reduced.mechanism.run import simulate
    from pinbore.reduced.wear import history

    result = json.loads((worn / "summary.json").read_text())
    path = ROOT / "scenes/reduced/slider_crank_flores2004.toml"
    model = build(kinds.load(path), str(path), path.parent)
    run = simulate(model)
    cycle = history.of_run(model, run, 0, (0.012, run.times[-1]))   # the 3 revolutions after the first
    work = np.trapezoid(cycle.force * np.abs(cycle.sliding_speed), cycle.time) / 3   # N m per cycle
    assert result["bore"]["volume_m3"] == pytest.approx(K * 1000 * work, rel=0.02)
    assert result["pin"]["volume_m3"] == pytest.approx(2 * result["bore"]["volume_m3"], rel=0.02)
    rows = (worn / "wear.csv").read_text().splitlines()
    assert rows[0] == "angle_deg,bore_depth_m,pin_depth_m" and len(rows) == 721
    assert (worn / "wear.png").stat().st_size > 0


def test_a_wear_run_over_more_periods_averages_them(tmp_path, flores_fe):
    """`periods = 6`: the mechanism runs six crank revolutions whatever its scene's duration,
    and the wear of a cycle is the mean of the five after the first: the bore's volume is k
    (cycles) times the integral of F |v_s| over them, from a run of the mechanism 6 periods
    long made here."""
    import copy
    import json
    import tomllib

    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import build
    from pinbore.reduced.mechanism.run import simulate
    from pinbore.reduced.wear import history

    (tmp_path / "wear.toml").write_text(tomli_w.dumps(wear_scene(tmp_path, flores_fe, periods=6)))
    done = pinbore("wear", tmp_path / "wear.toml", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert result["periods_averaged"] == 5
    path = ROOT / "scenes/reduced/slider_crank_flores2004.toml"
    data = copy.deepcopy(tomllib.loads(path.read_text())) | {"duration": 6 * 0.012}
    model = build(kinds.validate(data, str(path)), str(path), path.parent)
    run = simulate(model)
    cycle = history.of_run(model, run, 0, (0.012, run.times[-1]))
    work = np.trapezoid(cycle.force * np.abs(cycle.sliding_speed), cycle.time) / 5
    assert result["bore"]["volume_m3"] == pytest.approx(K * 1000 * work, rel=0.02)


def short_flores(folder) -> str:
    """The Flores slider-crank run over less than a crank revolution, written into folder."""
    import tomllib

    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    (folder / "short.toml").write_text(tomli_w.dumps(data | {"duration": 0.006}))
    return str(folder / "short.toml")


# each a change of the scene (or of it, given its folder): one line naming the key, before any run
BAD_WEAR = [
    ({"joint": "crank_pin"}, "joint: 'crank_pin' is not a revolute clearance joint"),
    ({"periods": 1}, "periods"),
    ({"length": -1.0}, "length"),
    ({"cycles": 0}, "cycles"),
    ({"bore": {"wear_coefficient": 1.0}}, "wear_coefficient"),
    ({"pin": {}}, "pin.wear_coefficient"),
    ({"pressure_file": "/no/such/pressure.csv"}, "pressure.csv"),
    ({"cycles": math.inf}, "cycles: Input should be a finite number"),
    ({"points": 10}, "points: Input should be greater than or equal to 36"),
    ({"colour": "red"}, "colour: unknown key"),
    ({"coupling": {"tolerance": 0.0}}, "coupling.tolerance: Input should be greater than or equal to 1e-08"),
    ({"coupling": {"tolerance": 1e-12}}, "coupling.tolerance: Input should be greater than or equal to 1e-08"),
    ({"coupling": {"tolerance": 1e-6, "first_jump": -1.0}}, "coupling.first_jump: Input should be greater than 0"),
    ({"curve_file": "/no/such/curve.csv"}, "/no/such/curve.csv: cannot read"),
    ({"mechanism_file": "/no/such/mechanism.toml"}, "/no/such/mechanism.toml: cannot read"),
    ({"mechanism_file": str(ROOT / "scenes/reduced/spatial_slider_crank_flores.toml")},
     'mechanism_file: a planar mechanism (kind = "planar") is needed'),
    ({"mechanism_file": str(ROOT / "scenes/reduced/solar_panel_deployment.toml"), "joint": "hinge"},
     "mechanism_file: a periodic analysis needs a periodic forcing"),   # a deployment
    (lambda folder, fe: {"mechanism_file": short_flores(folder)},
     "mechanism_file: duration 0.006 s is shorter than one forcing period"),
    ({"coupling": {"tolerance": 1e-6, "pressure": "old"}}, "coupling.pressure: Input should be 'new' or 'worn'"),
    ({"coupling": {"tolerance": 1e-6, "pressure": "worn"}},
     'compliance_file: coupling.pressure = "worn" needs the FE run\'s compliance.csv'),
    (lambda folder, fe: {"compliance_file": str(fe / "compliance.csv")},
     'compliance_file: read only by coupling.pressure = "worn"'),
    ({"compliance_file": "/no/such/compliance.csv", "coupling": {"tolerance": 1e-6, "pressure": "worn"}},
     "/no/such/compliance.csv: cannot read"),
    (lambda folder, fe: {"compliance_file": str(fe / "curve.csv"), "coupling": {"tolerance": 1e-6, "pressure": "worn"}},
     "curve.csv: the header must be angle_deg,compliance_m_per_Pa"),
]


@pytest.mark.parametrize("change, message", BAD_WEAR, ids=[m for _, m in BAD_WEAR])
def test_bad_wear_scenes_are_one_line(tmp_path, flores_fe, change, message):
    change = change(tmp_path, flores_fe) if callable(change) else change
    (tmp_path / "wear.toml").write_text(tomli_w.dumps(wear_scene(tmp_path, flores_fe, **change)))
    done = pinbore("wear", tmp_path / "wear.toml", "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("signum, group, code, word", [(15, False, 143, "terminated"), (2, True, 130, "interrupted")],
                         ids=["SIGTERM", "Ctrl-C"])
def test_a_wear_run_stopped_while_it_computes_leaves_nothing(tmp_path, flores_fe, signum, group, code, word):
    """SIGTERM or Ctrl-C while the mechanism runs (a coupled wear whose tolerance keeps it
    jumping, long before its output is written): one line, exit 128 + signal, within a
    second, no temporary folder (its worn profiles' pinbore-wear-*), lock or process left (the
    stop handlers had been installed only for the writing: SIGTERM killed it outright with
    its temporary folder left, and Ctrl-C went unanswered)."""
    from conftest import stopped_midrun

    data = wear_scene(tmp_path, flores_fe, cycles=1e6, coupling={"tolerance": 1e-8})
    (tmp_path / "wear.toml").write_text(tomli_w.dumps(data))
    done, seconds, left, temporaries = stopped_midrun(["wear", "wear.toml", "--out", "out"], tmp_path,
                                                      tmp_path / "out", signum, 1.0, group)
    assert done.returncode == code and seconds < 1.0, (done.returncode, seconds, done.stderr)
    assert done.stderr.strip().splitlines() == [f"pinbore wear: {word}; outputs under way removed"]
    assert left == [] and temporaries == []
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".") or p.name == "out"] == []


@pytest.mark.parametrize("change, messages", [
    ({"pin_radius": 9.9e-3}, ["pin radius", "rod_slider"]),
    ({"wear_file": "wear.csv"}, ["curve_file: the FE run of a worn joint"]),
], ids=["radius", "worn"])
def test_an_fe_run_of_another_joint_is_one_line(tmp_path, flores_fe, change, messages):
    """The FE run's radii must be the joint's (its result.json says them), and its joint new
    (the wear takes the new joint's pressure)."""
    import json
    import shutil

    other = tmp_path / "fe"
    shutil.copytree(flores_fe, other)
    data = json.loads((other / "result.json").read_text())
    data["scene"]["geometry"].update(change)
    (other / "result.json").write_text(json.dumps(data))
    (tmp_path / "wear.toml").write_text(tomli_w.dumps(wear_scene(tmp_path, other)))
    done = pinbore("wear", tmp_path / "wear.toml", "--out", tmp_path / "out")
    assert done.returncode == 2 and all(m in done.stderr for m in messages), done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_the_report_leaves_out_a_wear_summary_it_cannot_trust(tmp_path, worn):
    """A summary.json changed by hand (a volume NaN or negative) is not drawn: the section's
    reader fails in one line naming the key (the report leaves the section out with it)."""
    import json

    from pinbore.core.errors import InputError
    from pinbore.reduced.wear import report

    import shutil

    shutil.copytree(worn, tmp_path / "build" / "wear" / "w")
    assert "Wear of the clearance joints" in report.section(tmp_path / "build", tmp_path)
    path = tmp_path / "build" / "wear" / "w" / "summary.json"
    for bad in (float("nan"), -1.0):
        data = json.loads(path.read_text())
        data["bore"]["volume_m3"] = bad
        path.write_text(json.dumps(data))
        with pytest.raises(InputError, match="bore.volume_m3"):
            report.section(tmp_path / "build", tmp_path)


def test_a_study_of_the_wear_coefficient(tmp_path, flores_fe):
    """`pinbore study` runs wear scenes (the base's files named relative to it): the bore's
    worn volume is proportional to its coefficient (Archard: the same history), the pin's
    unchanged."""
    import csv

    (tmp_path / "wear.toml").write_text(tomli_w.dumps(wear_scene(tmp_path, flores_fe)))
    (tmp_path / "study.toml").write_text(
        'base = "wear.toml"\n[parameters."bore.wear_coefficient"]\nvalues = [1e-14, 3e-14]\n'
        '[sampling]\nmethod = "grid"\n'
        '[[collect]]\nname = "bore"\npath = "bore.volume_m3"\n'
        '[[collect]]\nname = "pin"\npath = "pin.volume_m3"\n')
    done = pinbore("study", tmp_path / "study.toml", "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    rows = list(csv.DictReader((tmp_path / "out" / "results.csv").read_text().splitlines()))
    assert [r["status"] for r in rows] == ["complete", "complete"]
    assert float(rows[1]["bore"]) == pytest.approx(3 * float(rows[0]["bore"]), rel=1e-12)
    assert float(rows[1]["pin"]) == pytest.approx(float(rows[0]["pin"]), rel=1e-12)


# ---- the worn joint: a journal meeting its bore over the arc where the worn surfaces overlap

def worn_flores(tmp_path, rtol=None, restitution=None, rough=0.0) -> tuple:
    """The Flores slider-crank on a smooth worn bore (30 um (1 + cos 2 theta)) and pin
    (20 um (1 + sin theta)), each roughened by uniform noise of `rough` m at its points if
    asked (several extrema between two points: the profiles a coupled run grows), and those
    profiles."""
    import copy
    import tomllib

    from pinbore.laws import wearfile

    theta = np.radians(wearfile.angles(720))
    bore, pin = 30e-6 * (1 + np.cos(2 * theta)), 20e-6 * (1 + np.sin(theta))
    noise = np.random.default_rng(3).uniform(0.0, rough, (2, theta.size))
    bore, pin = bore + noise[0], pin + noise[1]
    wearfile.write(tmp_path / "wear.csv", wearfile.Profiles(np.degrees(theta), bore, pin))
    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    data = copy.deepcopy(data)
    data["clearance_joints"][0]["wear_file"] = str(tmp_path / "wear.csv")
    if rtol:
        data["integrator"]["rtol"] = rtol
    if restitution:
        data["clearance_joints"][0]["restitution"] = restitution
    return data, theta, bore, pin


def catmull_rom(profile: np.ndarray, a: np.ndarray) -> np.ndarray:
    """A periodic profile (its points evenly from -pi) at the angles a, by the uniform
    Catmull-Rom spline through its points in Python (laws.wearfile.spline, which the FE of a
    worn joint meshes and contacts): the test below checks it against the core's."""
    from pinbore.laws.wearfile import spline

    return spline(profile, a)[0]


def worn_model(data):
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import build

    path = ROOT / "scenes/reduced/slider_crank_flores2004.toml"
    return build(kinds.validate(data, str(path)), str(path), path.parent)


def test_the_round_overlap_moment_and_its_inverse():
    """Phi(delta) = int d_+^4 dphi of a round journal offset by c + delta (the core's
    round_moment, the worn joint's scale of penetration) is the adaptive quadrature of the
    overlap (c + delta) cos phi - c within 1e-10 from 1 nm to 0.5 mm, its slope the central
    difference's within 1e-7, and the parabolic arc's closed form sqrt(2/c) B(5, 1/2)
    delta^(9/2) where delta << c (to delta / c); moment_penetration inverts it to 1e-13."""
    from scipy.integrate import quad
    from scipy.special import beta

    from pinbore.core.cpp.mechanism import moment_penetration, round_moment

    c = 0.5e-3
    for delta in (1e-9, 1e-6, 1e-5, 1e-4, 5e-4):
        e, half = c + delta, math.acos(c / (c + delta))
        exact = 2 * quad(lambda p: (e * math.cos(p) - c) ** 4, 0, half, epsabs=0, epsrel=1e-13, limit=200)[0]
        value, slope = round_moment(delta, c)
        assert value == pytest.approx(exact, rel=1e-10)
        h = 1e-5 * delta
        assert slope == pytest.approx((round_moment(delta + h, c)[0] - round_moment(delta - h, c)[0]) / (2 * h), rel=1e-7)
        assert moment_penetration(value, c)[0] == pytest.approx(delta, rel=1e-13)
    for delta in (1e-12, 1e-10):
        assert round_moment(delta, c)[0] == pytest.approx(math.sqrt(2 / c) * beta(5, 0.5) * delta**4.5, rel=1e-6)


def test_a_round_profile_keeps_the_joints_law(tmp_path):
    """A wear file of zero depths: the journal pushed into its bore by c + delta along any
    direction feels its law's force f(delta), the round joint's own (the bodies at rest: no
    damping). On the engine's arc grid of 1/4 degree (720 points a profile) within 2 % at
    0.1 um and 0.2 % from 1 um; the error is of second order in the grid (1/16 degree, 2880
    points: 16 times smaller), the overlap's chord between grid points."""
    from pinbore.laws import wearfile
    from pinbore.laws.tables import table_force
    from pinbore.reduced.mechanism import kernel, layout

    data, *_ = worn_flores(tmp_path)
    errors = {}
    for points in (720, 2880):
        theta = wearfile.angles(points)
        wearfile.write(tmp_path / "wear.csv", wearfile.Profiles(theta, 0 * theta, 0 * theta))
        model = worn_model(data)
        args, c = model.args(), model.joints[0]
        column = model.geometry.coordinate(model.names.index(c.bearing_body))
        table = model.base.tables[int(model.contacts[0, layout.CONTACT_TABLE])]
        for delta in (1e-7, 1e-6, 1e-5, 5e-5):
            for direction in (0.3, 2.0, -2.5):
                y = model.y0.copy()
                y[column:column + 2] -= (c.gap() + delta) * np.array([math.cos(direction), math.sin(direction)])
                y[model.nq:2 * model.nq] = 0.0   # at rest
                force = kernel.rhs_value(0.0, y, args)[1][0]
                law = table_force(delta, model.base.grid_log0, model.base.grid_step, table)
                errors[points, delta, direction] = abs(force / law - 1)
    assert max(errors[720, 1e-7, a] for a in (0.3, 2.0, -2.5)) < 2e-2
    assert max(v for (p, d, _), v in errors.items() if p == 720 and d >= 1e-6) < 2e-3
    for delta in (1e-7, 1e-6):
        assert errors[2880, delta, 0.3] < errors[720, delta, 0.3] / 10


@pytest.mark.parametrize("kind", ["planar", "spatial"])
def test_a_round_profile_keeps_the_joints_impact(tmp_path, kind):
    """The Flores slider-crank's first impact (damped: Lankarani-Nikravesh, e = 0.9; 4e-4 s,
    rtol 1e-10; tests/test_planar_as_spatial.py's twins, `kind` the one: in space every slice
    of the journal worn) with a wear.csv of zero depths against the same joint without one. The zero profile's penetration is the
    round one measured on the arc grid's chords: a round joint whose clearance is larger by
    the chord's sag s = c (2 pi / M)^2 / 8 (M = 1440 points a turn: 1.2e-9 m). So the bodies
    agree within a few sags (3 s; the rod's angle 3 s over its half-length, 0.06 m), and the
    force, F(delta) against F(delta - s), within F'(delta) s <= 1.5 s / delta_peak of the
    peak on the Hertz law F ~ delta^1.5 (delta_peak where the law carries the peak force),
    doubled for the onset the sag delays. The impact speed, the damping's v0, is the deepest
    overlap's rate (on the few grid points that overlap at the onset the penetration's rate
    is not the approach: it had been half of it): within pi / M of the round joint's, the
    deepest grid point's direction lying within half a grid step of the centres' line and
    the journal's slip there (1.0-2.1 m/s) below its 4.4 m/s approach."""
    from test_planar_as_spatial import differences, integrate, sample_times, twins

    from pinbore.laws import elastic, wearfile
    from pinbore.reduced.mechanism.layout import LOG_RATE, LOG_TIME

    theta = wearfile.angles(720)
    wearfile.write(tmp_path / "wear.csv", wearfile.Profiles(theta, 0 * theta, 0 * theta))
    which = ["planar", "spatial"].index(kind)
    round_, worn = (integrate(twins(4e-4, joint)[which]) for joint in ({}, {"wear_file": str(tmp_path / "wear.csv")}))
    c = round_[0].joints[0]
    sag = c.gap() * (2 * math.pi / 1440) ** 2 / 8
    times = sample_times(round_[1], round_[1].impacts[0, LOG_TIME])
    positions, angles, normal, _, p, _ = differences(round_, worn, times)
    deltas = np.geomspace(1e-8, 1e-3, 4001)
    delta_peak = np.interp(p[:, -2].max(), elastic.hertz_point(deltas, c.elastic_joint()), deltas)
    assert positions < 3 * sag, positions / sag
    assert angles < 3 * sag / 0.06, angles
    assert normal < 2 * 1.5 * sag / delta_peak * p[:, -2].max(), normal / p[:, -2].max()
    assert worn[1].impacts[0, LOG_RATE] == pytest.approx(round_[1].impacts[0, LOG_RATE], rel=math.pi / 1440)


@pytest.mark.parametrize("rough", [0.0, 2e-6], ids=["smooth", "rough"])
def test_a_worn_journal_meets_its_bore_over_the_arc_where_they_overlap(tmp_path, rough):
    """At 40 recorded steps of the worn slider-crank (elastic: the normal force is the
    elastic one), the core's penetration and force against brute force on 400,001 angles:
    the overlap d(phi) = e . u(phi) - c - h_bore(phi - phi_bore) - h_pin(phi - phi_pin) of the
    profiles by the Catmull-Rom spline in Python (laws.wearfile.spline, the core's curve),
    its moment Phi = int d_+^4 dphi, the penetration delta_p where the round joint's moment
    equals it (moment_penetration, checked above; within 0.5 % or the chord's sag between
    the core's grid points),
    and the force f(delta_p) grad Phi / Phi_round'(delta_p) (magnitude within 0.5 %,
    direction within 0.1 degree, where it exceeds 1 % of the run's largest; the rough
    profiles' bumps, two grid points wide, within 2 %). The rough profiles' extrema lie
    closer than the profile's points: the run completes all the same."""
    from pinbore.core.cpp.mechanism import moment_penetration, round_moment
    from pinbore.laws.tables import table_force
    from pinbore.reduced.mechanism import layout
    from pinbore.reduced.mechanism.outputs import observed_steps
    from pinbore.reduced.mechanism.run import OK, STATUS, simulate

    data, theta, bore, pin = worn_flores(tmp_path, restitution=1.0, rough=rough)
    model = worn_model(data)
    run = simulate(model)
    assert run.status == OK, STATUS[run.status]
    seen = observed_steps(model, run)
    c = model.joints[0]
    law = model.base.tables[int(model.contacts[0, layout.CONTACT_TABLE])]
    grid = model.base.grid_log0, model.base.grid_step
    column = {name: int(model.base.offsets[i]) + 2 for i, name in enumerate(model.names)}
    fine = np.linspace(-math.pi, math.pi, 400001)[:-1]
    step = fine[1] - fine[0]
    largest = seen["normals"][:, 0].max()
    tol = 2e-2 if rough else 5e-3   # the rough splines' bumps are two grid points wide
    # the chord's sag between the core's grid points (1/4 degree): |d''| dphi^2 / 8, d'' the
    # clearance's and the rough profiles' spline curvature (noise over the profile's 1/2 degree)
    sag = (c.gap() + 4 * rough / math.radians(0.5) ** 2) * math.radians(0.25) ** 2 / 8 + 1e-9
    checked = 0
    for k in np.linspace(0, run.times.size - 1, 40).astype(int):
        e = seen["offsets"][k, 0]
        d = (e[0] * np.cos(fine) + e[1] * np.sin(fine) - c.gap()
             - catmull_rom(bore, fine - run.states[k, column[c.bearing_body]])
             - catmull_rom(pin, fine - run.states[k, column[c.journal_body]]))
        if seen["depths"][k, 0] <= 0:   # open on the core's grid: within its chord's sag
            assert d.max() < sag
            continue
        over = np.maximum(d, 0.0)
        moment = step * np.sum(over**4)
        delta, slope = moment_penetration(moment, c.gap())
        assert seen["depths"][k, 0] == pytest.approx(delta, rel=tol, abs=sag)
        if seen["normals"][k, 0] < 0.01 * largest:
            continue
        gradient = step * 4 * np.array([over**3 @ np.cos(fine), over**3 @ np.sin(fine)])
        force = table_force(delta, *grid, law) * gradient / slope
        assert seen["normals"][k, 0] == pytest.approx(np.hypot(*force), rel=tol)
        n = seen["directions"][k, 0]
        assert abs(math.atan2(force[0] * n[1] - force[1] * n[0], force @ n)) < math.radians(0.1)
        checked += 1
    assert checked >= 5


def test_a_worn_joint_keeps_the_energy_book(tmp_path):
    """Elastic (restitution 1), frictionless, rtol 1e-8: the worn joint's force along the
    normal at phi* and its torques -F dh/dphi on the two frames do the work of its potential,
    so the energy book holds as on the round joint (measured 8e-7 against 5e-7 of the peak
    kinetic energy)."""
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.run import summarised

    data, *_ = worn_flores(tmp_path, rtol=1e-8, restitution=1.0)
    path = ROOT / "scenes/reduced/slider_crank_flores2004.toml"
    summary = summarised(kinds.validate(data, str(path)), str(path), path.parent)[3]
    assert summary.status == "complete" and summary.energy_balance.dissipated_J == 0.0
    assert summary.energy_balance.relative_to_peak_kinetic < 5e-6


@pytest.mark.parametrize("text, message", [
    ("angle,bore,pin\n0,0,0\n", "not a wear.csv"),
    ("angle_deg,bore_depth_m,pin_depth_m\n-180,0,0\n0,0,0\n90,0,0\n", "evenly spaced"),
    ("angle_deg,bore_depth_m,pin_depth_m\n-180,0,0\n-60,-1e-6,0\n60,0,0\n", "from 0 to"),
])
def test_a_bad_wear_file_is_one_line(tmp_path, text, message):
    import tomllib

    (tmp_path / "wear.csv").write_text(text)
    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    data["clearance_joints"][0]["wear_file"] = str(tmp_path / "wear.csv")
    data["duration"] = 0.001
    (tmp_path / "scene.toml").write_text(tomli_w.dumps(data))
    done = pinbore("reduced", tmp_path / "scene.toml", "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr and "wear_file" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


# ---- cycle jumping

def test_cycle_jumping_follows_an_accelerating_wear_in_closed_form():
    """dh/dN = a + b h (a wear that grows with the depth) from h = 0: h(N) = a (e^{bN} - 1) / b.
    The jumps' error estimates stay within the tolerance, and the result is within it of
    the closed form after 1e5 cycles (b N = 2); a tolerance 4 times smaller is about 4
    times closer (the trapezoidal rule: second order), with more jumps."""
    from pinbore.reduced.wear import jumping

    a = np.array([1e-9, 2e-9, 0.5e-9])   # m per cycle at three angles
    b, cycles = 2e-5, 1e5
    exact = a * np.expm1(b * cycles) / b
    errors, counts = [], []
    for tolerance in (1e-6, 0.25e-6):
        h, jumps = jumping.jump(lambda h: (a + b * h, None), np.zeros(3), cycles, tolerance, 1000.0)
        assert max(jumps.errors) <= tolerance and jumps.cycles[-1] == pytest.approx(cycles)
        errors.append(np.abs(h - exact).max())
        counts.append(len(jumps.cycles))
        assert errors[-1] < 0.01 * exact.max()
    assert errors[1] < errors[0] / 3 and counts[1] > counts[0]


def test_the_coupled_wear_runs_the_mechanism_on_its_worn_joint(tmp_path, flores_fe):
    """[coupling]: the jumps cover the cycles, each within the tolerance, one run of the worn
    mechanism each (the rate at the predictor stands for the next jump's start) besides the
    first; the last jump's record is the written profile's deepest wear and volume, the first's
    first impact the new joint's."""
    import json

    data = wear_scene(tmp_path, flores_fe, cycles=200.0,
                      coupling={"tolerance": 1e-3, "first_jump": 100.0})
    (tmp_path / "wear.toml").write_text(tomli_w.dumps(data))
    done = pinbore("wear", tmp_path / "wear.toml", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "out" / "summary.json").read_text())
    jumps = result["jumps"]
    assert result["coupled"] and [j["cycles"] for j in jumps] == [0.0, 100.0, 200.0]
    assert result["mechanism_runs"] == 3 and result["refused_jumps"] == 0
    assert all(j["error_m"] <= 1e-3 for j in jumps)
    assert jumps[-1]["bore_max_depth_m"] == pytest.approx(result["bore"]["max_depth_m"], rel=1e-12)
    assert jumps[-1]["volume_m3"] == pytest.approx(result["bore"]["volume_m3"], rel=1e-12)
    assert jumps[0]["volume_m3"] == 0.0 and jumps[1]["volume_m3"] > 0
    # the new joint's first impact is the Flores mechanism's largest force (0.25 ms): its peak
    # as the mechanism's own summary finds it (refined between steps), within 2 %
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.run import summarised

    path = ROOT / "scenes/reduced/slider_crank_flores2004.toml"
    new = summarised(kinds.load(path), str(path), path.parent)[3].clearance_joints["rod_slider"]
    assert jumps[0]["first_impact_force_N"] == pytest.approx(new.peak_normal_force_N, rel=2e-2)


def test_the_worn_joints_own_pressure_wears_archards_volume(tmp_path, flores_fe):
    """[coupling] pressure = "worn": the pressure of the joint as it wears, its contact solved
    on the FE run's surface compliance (fem.compliance.Conformal; tests/test_worn_fe.py checks
    it against the worn FE run). Archard's volume is k times the load times the distance slid
    whatever the pressure's shape: on one run of the mechanism (the Flores slider-crank at
    150 rpm with friction, its joint loaded throughout: bench/wear.py's periodic one) the
    cycle's volumes are the FE table's within the share of the pressure's arc off the load
    (1 - cos alpha over the contact's half-angle, under 1 %), the pin's twice the bore's; the
    bore's deepest wear lies where the table's does, within 2 degrees. The scene runs through
    `pinbore wear`."""
    import json

    from pinbore.core import scene as scenes
    from pinbore.fem import compliance
    from pinbore.reduced.wear import run as wear_run
    from pinbore.reduced.wear.scene import WearScene

    data = wear_scene(tmp_path, flores_fe, cycles=200.0, compliance_file=str(flores_fe / "compliance.csv"),
                      coupling={"tolerance": 1e-3, "first_jump": 100.0, "pressure": "worn"},
                      mechanism_file=str(ROOT / "bench/slider_crank_flores2004_loaded.toml"), periods=2)
    (tmp_path / "wear.toml").write_text(tomli_w.dumps(data))
    scene = scenes.load(WearScene, tmp_path / "wear.toml")
    mechanism, path, _, period = wear_run.mechanism_of(scene, tmp_path, "test")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    at = profile.angles(scene.points)
    new = np.zeros(at.size)
    rates = {}
    for name, kernel in (("table", None), ("worn", compliance.read(flores_fe / "compliance.csv"))):
        cycle = wear_run.Cycle(scene, mechanism, path, table, period, at, tmp_path, kernel)
        rates[name] = cycle({"bore": new, "pin": new})[0]
    volume = {name: profile.volume_per_length(r["bore"], table.bore_radius) for name, r in rates.items()}
    assert volume["worn"] == pytest.approx(volume["table"], rel=1e-2)
    pin = profile.volume_per_length(rates["worn"]["pin"], table.pin_radius)
    assert pin == pytest.approx(2 * volume["worn"], rel=1e-9)
    deepest = [math.degrees(at[np.argmax(r["bore"])]) for r in rates.values()]
    assert abs(deepest[0] - deepest[1]) <= 2.0
    done = pinbore("wear", tmp_path / "wear.toml", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert result["coupled"] and result["jumps"][-1]["cycles"] == 200.0 and result["pressure"] == "worn"
    assert result["worn_contacts_solved"] > 0   # the run says so of the contacts it did not resolve
    assert (result["worn_contacts_unresolved"] > 0) == ("are not resolved" in done.stderr)


def test_the_worn_joints_contact_meets_its_load_and_its_conditions(flores_fe):
    """fem.compliance.Conformal loaded on the FE run's compliance, a bore worn 30 um along a
    diameter and in an off-centre pocket, a pin worn on one side and turned 0.4 rad: at every
    load (1e3 to 1e6 N/m) and direction the solution, checked here from its own definition,
    has p >= 0, the gap g + C p >= 0 where p = 0 and = 0 where p > 0 (to 1e-12 m), and the
    resultant R_b Delta sum p_j n_j = F u within 1e-6 F. A round joint's pressure turns with
    its load and its pin (by whole steps of the kernel's angles)."""
    from pinbore.fem import compliance

    kernel = compliance.read(flores_fe / "compliance.csv")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    r_p, r_b = table.pin_radius, table.bore_radius
    theta = profile.angles(720)
    bore = 15e-6 * (1 + np.cos(2 * theta)) + 10e-6 * np.exp(-((theta - 2.2) / 0.3) ** 2)
    pin = 10e-6 * (1 + np.sin(theta))
    joint = compliance.Conformal(kernel, r_p, r_b, bore, pin)
    for force in (1e3, 1e5, 1e6):
        for direction in (0.3, 2.0, -2.5):
            for turn in (0.0, 0.4):
                p, _, e, _, push = joint.loaded(force, direction, turn)
                points = joint.facing(push, turn)
                g, normal, _ = joint.gap(e, turn, points)
                opened = g + joint.matrix(points) @ p
                assert np.all(p >= 0)
                assert np.all(opened >= -1e-12) and np.all(np.abs(opened[p > 0]) <= 1e-12)
                resultant = r_b * joint.spacing * (p @ normal)
                u = np.array([math.cos(direction), math.sin(direction)])
                assert np.hypot(*(resultant - force * u)) <= 1e-6 * force
    round_joint = compliance.Conformal(kernel, r_p, r_b, np.zeros(720), np.zeros(720))
    one, other = round_joint.loaded(5e5, 0.0, 0.0)[0], round_joint.loaded(5e5, math.pi / 2, math.radians(30))[0]
    assert np.max(np.abs(np.sort(one) - np.sort(other))) <= 1e-6 * np.max(one)


def test_the_worn_joints_pressure_moves_continuously_with_the_history(flores_fe):
    """The worn pressure a step wears by (wear.pressure.worn_tables) is a continuous function
    of the joint's history, as the cycle jumping's error estimate, a difference of two runs'
    rates, needs: a step whose load's direction in the bore's or in the pin's frame crosses a
    node of the grid (where the tables change) has the same pressure on either side (to the
    crossing's 1e-9 rad); a step's pressure does not depend on the other steps' loads (the
    tables' loads are fixed, each solved alone); each step's pressure moves with the worn
    depth in proportion (a change of 1e-6 and of 1e-4 of the depth: ratio 100 within 1 %)."""
    from pinbore.fem import compliance

    kernel = compliance.read(flores_fe / "compliance.csv")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    theta = profile.angles(720)
    bore = 12e-6 * (1 + np.cos(theta - 0.4)) + 6e-6 * np.exp(-((theta - 1.2) / 0.3) ** 2)
    pin = 8e-6 * (1 + np.sin(theta))

    def rows(history, bore=bore):
        joint = compliance.Conformal(kernel, table.pin_radius, table.bore_radius, bore, pin)
        force, direction, pin_direction = (np.array(x, float) for x in history)
        tables = pressure.worn_tables(joint, table, force, direction, pin_direction)
        return np.array([[t.at(f) for t, f in zip(getattr(tables, name), force)] for name in ("bore", "pin")])

    edge, load = -math.pi + 24 * pressure.NODE, 4e5   # a node of the grid
    for crossing in (rows([[load, load], [edge - 1e-9, edge + 1e-9], [edge - 0.2, edge - 0.2]]),
                     rows([[load, load], [edge + 0.02, edge + 0.02], [edge - 1e-9, edge + 1e-9]])):
        assert np.abs(crossing[:, 0] - crossing[:, 1]).max() <= 1e-6 * crossing.max()
    alone = rows([[load], [edge + 0.03], [edge - 0.17]])[:, 0]
    beside = rows([[load, 50 * load, load / 50], [edge + 0.03, edge + 0.05, edge + 0.07],
                   [edge - 0.17, edge - 0.16, edge - 0.15]])[:, 0]
    assert np.abs(alone - beside).max() <= 1e-9 * alone.max()
    history = [[2e4, 3e5, 8e5], [0.5, 0.52, 0.61], [0.4, 0.40, 0.43]]
    base = rows(history)
    small, large = (np.abs(rows(history, bore * (1 + eps)) - base).max() for eps in (1e-6, 1e-4))
    assert large / small == pytest.approx(100.0, rel=1e-2)


def test_the_worn_pin_wears_where_it_touches(flores_fe):
    """A pin with a notch 20 um deep and 6 degrees wide at the load (deeper than the contact's
    elastic approach) rests on the notch's shoulders: the pin's pressure (wear.pressure.
    worn_tables, a step on a node of the grid) is nil in the notch, lies on both shoulders
    alike (its two halves' forces within 1 %) and carries the load (the pin's pressure's
    resultant, over its arc, within 1 % of F). Turned 10 degrees in the bore (the same bore
    direction), the pin is touched elsewhere on its own surface: its pressure lies where the
    joint, solved there directly, touches it (within the grid's 0.5 degree)."""
    from pinbore.fem import compliance

    kernel = compliance.read(flores_fe / "compliance.csv")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    r_p, r_b = table.pin_radius, table.bore_radius
    theta = profile.angles(720)
    notch = 20e-6 * np.clip(1 - np.abs(theta) / math.radians(3), 0, 1) ** 0.5
    joint = compliance.Conformal(kernel, r_p, r_b, np.zeros(720), notch)
    load, node = 2e5, 0.0   # the load along the bore's 0 and the pin's 0: a node
    tables = pressure.worn_tables(joint, table, np.array([load]), np.array([node]), np.array([node]))
    on_pin = tables.pin[0].at(load)
    beta = tables.pin[0].angles * r_b / r_p   # the pin's angle from the load
    assert np.all(on_pin[np.abs(beta) < math.radians(2)] == 0)
    halves = [np.trapezoid(np.where(side, on_pin, 0.0), beta) for side in (beta < 0, beta > 0)]
    assert halves[0] == pytest.approx(halves[1], rel=1e-2)
    resultant = np.trapezoid(on_pin * np.cos(beta), beta) * r_p
    assert resultant == pytest.approx(load, rel=1e-2)
    turned = math.radians(10)
    tables = pressure.worn_tables(joint, table, np.array([load]), np.array([node]), np.array([node - turned]))
    on_pin = tables.pin[0].at(load)
    p, _, _, _, push = joint.loaded(load, node, turned)
    touched = joint.beta[joint.facing(push, turned)][p > 0]   # the pin's own angles in contact
    pressed = beta[on_pin > 0] + node - turned
    assert abs(np.mean(pressed) - np.mean(touched)) <= math.radians(0.5)


def test_the_worn_pressure_spares_the_pockets_on_their_own_sides(flores_fe):
    """Each surface's worn pressure lies in its own frame on the right side of its load: under
    1e6 N/m (the round joint's contact +-8 degrees) along 20 degrees in the bore's frame, the
    pin turned 10 degrees, a pocket 20 um deep in the bore 5 degrees before the load and a notch
    in the pin 4 degrees after it (in the pin's frame) carry no pressure, the arcs mirrored
    across the load do (wear.pressure.worn_tables, a step on a node of the grid): the geometry
    alone says where, whatever the code's conventions."""
    from pinbore.fem import compliance

    kernel = compliance.read(flores_fe / "compliance.csv")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    r_p, r_b = table.pin_radius, table.bore_radius
    theta = profile.angles(720)
    bore_direction, pin_direction, load = math.radians(20), math.radians(10), 1e6

    def pocket(at):
        return 20e-6 * np.clip(1 - np.abs(np.mod(theta - at + math.pi, 2 * math.pi) - math.pi) / math.radians(1.5), 0, 1)

    joint = compliance.Conformal(kernel, r_p, r_b, pocket(bore_direction - math.radians(5)),
                                 pocket(pin_direction + math.radians(4)))
    tables = pressure.worn_tables(joint, table, np.array([load]), np.array([bore_direction]),
                                  np.array([pin_direction]))
    for name, feature, scale in (("bore", -5.0, 1.0), ("pin", 4.0, r_p / r_b)):
        row, alpha = getattr(tables, name)[0].at(load), getattr(tables, name)[0].angles
        spared, mirrored = (np.abs(alpha - scale * math.radians(centre)) <= scale * math.radians(0.5)
                            for centre in (feature, -feature))
        assert np.all(row[spared] == 0), name
        assert row[mirrored].max() > 0.1 * row.max(), name


def test_a_contact_narrower_than_the_compliances_grid_is_counted(flores_fe):
    """The worn pressure counts the contacts the compliance's grid does not resolve (the run
    says how many, summary.json and one line): a round joint under the FE run's top load
    presses an arc of many of its points (the grid's 0.5 degree apart), none counted; a pin
    recessed 20 um all round but for one point of the grid, under 1/64 of that load (its
    approach a fraction of a micrometre), rests on that point alone: counted."""
    from pinbore.fem import compliance

    kernel = compliance.read(flores_fe / "compliance.csv")
    table = pressure.read(flores_fe / "pressure.csv", flores_fe / "curve.csv", "test")
    top = table.forces[-1]
    crest = np.full(720, 20e-6)
    crest[360] = 0.0   # the pin's point at 0 degrees
    for pin, load, unresolved in ((np.zeros(720), top, 0), (crest, top / 64, 1)):
        joint = compliance.Conformal(kernel, table.pin_radius, table.bore_radius, np.zeros(720), pin)
        worn = pressure.worn_tables(joint, table, np.array([load]), np.array([0.0]), np.array([0.0]))
        assert (worn.solves, worn.narrow) == (1, unresolved)
