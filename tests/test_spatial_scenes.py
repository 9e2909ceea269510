"""Spatial mechanisms against independent references: an offset (non-planar) slider-crank
against its closed-form kinematics; the energy balance of the shipped spatial scenes with and
without dissipation; one ball-in-socket impact against the restitution of its law integrated
alone; the dynamics tools on spatial scenes (the ideal mechanism's single Poincare point);
bad spatial scenes named by their key."""

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.laws import dissipative
from pinbore.laws.elastic import Joint, hertz_point
from pinbore.reduced.dynamics import flow as dynamics
from pinbore.reduced.dynamics import studies
from pinbore.reduced.dynamics.parameters import with_parameter
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import SpatialScene

SCENES = ROOT / "scenes" / "reduced"
MISALIGNED = tomllib.loads((SCENES / "spatial_slider_crank_flores_misaligned.toml").read_text())
FOUR_BAR = tomllib.loads((SCENES / "spatial_four_bar_spherical.toml").read_text())

# the offset slider-crank: crank r about z through the origin, rod l, the slider's guide
# parallel to x at y = E, z = H (out of the crank's plane)
R, L, E, H, RPM = 0.05, 0.2, 0.03, 0.04, 600.0


def run(data):
    model = build(SpatialScene.model_validate(data), "test", ROOT)
    trajectory = simulate(model)
    assert trajectory.status == 0, (trajectory.status, trajectory.t_end)
    return model, trajectory


def offset_slider_crank(revolutions=1.0, rtol=1e-10):
    """RSUP: the crank (revolute on the ground), a spherical joint at the crank pin, a
    universal joint at the slider (its arms: z on the slider, normal to z and to the rod on
    the rod, so the rod cannot spin about itself) and the prismatic guide."""
    a = np.array([R, 0.0, 0.0])
    b = np.array([R + math.sqrt(L**2 - H**2 - E**2), E, H])
    centre = (a + b) / 2
    arm = np.cross((b - a) / L, [0.0, 0.0, 1.0])
    rod = np.diag([2e-5, 7e-4, 7e-4])   # (any tensor: the kinematics do not depend on it)
    return {"kind": "spatial", "duration": revolutions * 60 / RPM, "gravity": [0.0, -9.81, 0.0],
            "bodies": [
                {"name": "crank", "mass": 0.3, "inertia": np.diag([1e-5, 1e-4, 1e-4]).tolist(),
                 "position": [R / 2, 0.0, 0.0]},
                {"name": "rod", "mass": 0.2, "inertia": rod.tolist(), "position": centre.tolist()},
                {"name": "slider", "mass": 0.15, "inertia": np.diag([1e-4] * 3).tolist(),
                 "position": b.tolist()}],
            "joints": [
                {"name": "crank_pin", "type": "revolute", "body_i": "ground", "point_i": [0, 0, 0],
                 "axis_i": [0, 0, 1], "body_j": "crank", "point_j": [-R / 2, 0, 0], "axis_j": [0, 0, 1]},
                {"type": "spherical", "body_i": "crank", "point_i": [R / 2, 0, 0], "body_j": "rod",
                 "point_j": (a - centre).tolist()},
                {"type": "universal", "body_i": "rod", "point_i": (b - centre).tolist(),
                 "axis_i": (arm / np.linalg.norm(arm)).tolist(), "body_j": "slider",
                 "point_j": [0, 0, 0], "axis_j": [0, 0, 1]},
                {"type": "prismatic", "body_i": "ground", "point_i": [0.0, E, H], "axis_i": [1, 0, 0],
                 "body_j": "slider", "point_j": [0, 0, 0], "axis_j": [1, 0, 0]}],
            "drive": {"joint": "crank_pin", "speed_rpm": RPM},
            "integrator": {"rtol": rtol, "atol": 1e-13},
            "output": {"plots": False}}


def test_offset_slider_crank_follows_its_closed_form():
    """|B - A| = l with A = r (cos t, sin t, 0), B = (x, e, h) gives
    x = r cos t + sqrt(l^2 - h^2 - (e - r sin t)^2) and, differentiated,
    x' = w [-r sin t + r cos t (e - r sin t) / sqrt(...)]. The integrated slider (rtol 1e-10,
    positions projected onto the joints after every step) matches at every step: position
    to 1e-9 m (round-off of the projection, 1e-14, times the steps' count is far below), velocity
    to 1e-7 of r w; the joints' drift stays below 1e-10 m."""
    model, trajectory = run(offset_slider_crank())
    cols, _, drift = per_step(model, trajectory)
    w = RPM * 2 * math.pi / 60
    t = w * cols["time_s"]
    root = np.sqrt(L**2 - H**2 - (E - R * np.sin(t)) ** 2)
    x = R * np.cos(t) + root
    v = w * (-R * np.sin(t) + R * np.cos(t) * (E - R * np.sin(t)) / root)
    assert np.max(np.abs(cols["slider_x_m"] - x)) < 1e-9
    assert np.max(np.abs(cols["slider_vx_m_per_s"] - v)) < 1e-7 * R * w
    np.testing.assert_allclose(cols["slider_y_m"], E, atol=1e-12)
    np.testing.assert_allclose(cols["slider_z_m"], H, atol=1e-12)
    assert np.max(drift) < 1e-10
    assert t[-1] == pytest.approx(2 * math.pi)


def free_running(data, dissipative_laws):
    """The scene without its drive, the crank thrown at 40 rad/s about z, over 20 ms at
    rtol 1e-9; conservative (no damping, no friction) or with damping and friction."""
    data = copy.deepcopy(data)
    data.pop("drive")
    data["bodies"][0]["omega"] = [0.0, 0.0, 40.0]
    data["duration"] = 0.02
    data["integrator"] = {"rtol": 1e-9, "atol": 1e-13}
    data["output"] = {"plots": False}
    for joint in data["clearance_joints"]:
        joint.pop("friction", None)
        joint["damping_law"] = "none"
        if dissipative_laws:
            joint["damping_law"], joint["restitution"] = "lankarani_nikravesh", 0.8
            joint["friction"] = {"law": "coulomb_ambrosio", "mu": 0.2}
    return data


@pytest.mark.parametrize("scene", [MISALIGNED, FOUR_BAR], ids=["misaligned", "four_bar"])
@pytest.mark.parametrize("dissipation", [False, True], ids=["conservative", "dissipative"])
def test_energy_balance_closes(scene, dissipation):
    """Free motion (no drive) with impacts in the clearance joint. Without damping and
    friction the mechanical energy (kinetic + potential + elastic) is constant; with
    Lankarani-Nikravesh damping and Coulomb friction the dissipated energy, integrated with
    the motion, never decreases and closes the balance: mechanical + dissipated = initial.
    Tolerance 1e-6 of the peak kinetic energy: the integrator's (rtol 1e-9) over a few
    thousand steps, and the projection's (its changes are of the order of the onset
    tolerance)."""
    model, trajectory = run(free_running(scene, dissipation))
    _, energy, _ = per_step(model, trajectory)
    assert trajectory.counters[3] >= 1 and energy["elastic"].max() > 0   # the joint acted
    mechanical = energy["kinetic"] + energy["potential"] + energy["elastic"]
    balance = mechanical + energy["dissipated"]
    scale = energy["kinetic"].max()
    assert np.max(np.abs(balance - balance[0])) < 1e-6 * scale
    if dissipation:
        assert np.all(np.diff(energy["dissipated"]) >= -1e-12 * scale)
        assert energy["dissipated"][-1] > 1e-3 * scale
    else:
        assert np.max(np.abs(energy["dissipated"])) < 1e-12 * scale


@pytest.mark.parametrize("law, e", [("lankarani_nikravesh", 0.9), ("flores", 0.5)])
def test_ball_impact_reproduces_the_laws_restitution(law, e):
    """A ball thrown at 1 m/s from the centre of a fixed socket (0.5 mm clearance, Hertz
    point law with damping) meets it once, along a normal through its centre (no moment,
    no friction): a one-degree-of-freedom impact of the ball's mass. Its rebound speed is the
    effective restitution of the same law integrated alone (laws.dissipative.restitution) to
    1e-4, and that is the law's target e within the 6 % the law library shows for these
    laws (tests/test_laws.py)."""
    mass, speed = 0.14, 1.0
    data = {"kind": "spatial", "duration": 1.2e-3,
            "bodies": [{"name": "ball", "mass": mass, "inertia": np.diag([2e-6] * 3).tolist(),
                        "velocity": [speed * 0.6, speed * 0.8, 0.0]}],
            "clearance_joints": [{"name": "socket", "type": "spherical", "bearing_body": "ground",
                                  "bearing_point": [0, 0, 0], "journal_body": "ball",
                                  "journal_point": [0, 0, 0], "bearing_radius": 10e-3,
                                  "journal_radius": 9.5e-3, "E": 207e9, "nu": 0.3,
                                  "normal_law": "hertz_point", "damping_law": law,
                                  "restitution": e, "start": "free"}],
            "integrator": {"rtol": 1e-10, "atol": 1e-13}, "output": {"plots": False}}
    model, trajectory = run(data)
    assert trajectory.counters[3] == 1
    cols = per_step(model, trajectory)[0]
    rebound = -np.array([cols[f"ball_v{c}_m_per_s"][-1] for c in "xy"]) @ [0.6, 0.8]
    chi = dissipative.HYSTERESIS[law](e)
    joint = Joint(10e-3, 9.5e-3, 207e9, 0.3, 207e9, 0.3, None)
    reference = dissipative.restitution(
        lambda d, r: dissipative.hysteresis_force(hertz_point(max(d, 0), joint), r, speed, chi),
        mass, speed)
    assert rebound / speed == pytest.approx(reference, rel=1e-4)
    assert reference == pytest.approx(e, rel=0.06)


def test_ideal_spatial_mechanism_has_one_poincare_point():
    """The ideal offset slider-crank is periodic with the drive: its stroboscopic samples are
    one point (the crank's Euler parameters change sign every turn; the coordinates do not),
    and a perturbation projected onto the joints vanishes (no free direction): what is left
    after a period is the two integrations' different steps (rtol 1e-10), below 1e-3 of the
    perturbation, so the exponent is below ln(1e-3) / T (measured: a separation of 1e-5 d0)."""
    flow = dynamics.MechanismFlow(build(SpatialScene.model_validate(
        offset_slider_crank()), "test", ROOT))
    coords, states = dynamics.poincare(flow, flow.start(), 1, 3)
    assert np.ptp(coords, axis=0).max() * flow.length < 1e-12
    assert dynamics.period_of(coords) == 1
    exponent, _ = dynamics.lyapunov(flow, states[-1], 2)
    assert exponent < math.log(1e-3) / flow.period


def test_bifurcation_point_of_the_misaligned_slider_crank():
    """One point of the clearance sweep on the misaligned scene (the dynamics tools take
    spatial scenes): its Poincare samples lie across the bore within the clearance plus the
    tilt's reach at the journal's mid-plane, and it is classified."""
    point = studies.BifurcationPoint(SCENES, "test", 1, 3)(with_parameter(MISALIGNED, "clearance", 3e-4, "test"))
    assert point["kind"] in ("periodic", "chaotic", "quasi-periodic"), point
    observed = np.array(point["observed"])
    assert observed.shape == (3, 4)
    assert np.all(np.hypot(observed[:, 0], observed[:, 1]) < 3e-4 + 1e-5)


def bad(change):
    data = copy.deepcopy(MISALIGNED)
    change(data)
    return data


@pytest.mark.parametrize("change, words", [
    (lambda d: d["bodies"][0].update(rotation=[[2, 0, 0], [0, 1, 0], [0, 0, 1]]),
     ["bodies.0", "rotation matrix"]),
    (lambda d: d["bodies"][0].update(inertia=[[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]),
     ["bodies.0", "symmetric"]),
    (lambda d: d["clearance_joints"][0].update(bearing_axis=[0, 0, 0]),
     ["clearance_joints.0", "bearing_axis", "nonzero length"]),
    (lambda d: d.update(torsion=[{"type": "spring", "body_i": "ground", "body_j": "crank",
                                  "axis_i": [0, 0, 0], "stiffness": 1.0}]),
     ["torsion.0", "axis_i", "nonzero length"]),
    (lambda d: d["bodies"][1].update(colour="red"), ["bodies.1.colour", "unknown key"]),
    (lambda d: d["clearance_joints"][0].update(normal_law="stiff"), ["clearance_joints.0", "'stiff'"]),
    (lambda d: d["clearance_joints"][0].update(bearing_axis=[0.2, 0.0, 0.98]),
     ["clearance_joints.0 (rod_slider)", "does not fit"]),
    (lambda d: d["joints"][0].update(axis_j=[1, 0, 0]), ["joints.axis_j", "parallel"]),
    (lambda d: d["joints"][1].update(type="universal"), ["joints.axis_j", "normal to each other"]),
])
def test_bad_spatial_scene_is_one_line_naming_key_and_rule(change, words):
    """Rules checked when the scene is read or built (the CLI turns the InputError into one
    line and exit code 2 before anything is written: tests/test_spatial.py runs it)."""
    with pytest.raises(InputError) as err:
        build(scenes.validate(SpatialScene, bad(change), "scene.toml"), "scene.toml", ROOT)
    line = str(err.value)
    assert "\n" not in line
    for word in words:
        assert word in line, line


def test_the_3d_deployment_has_the_planar_ones_shortest_period():
    """The torsion springs of the 3D deployment about their hinge axes: its shortest period
    (what sizes a fixed step and bounds the steps a run can need) equals the planar
    deployment's, the same panels and springs in the plane (a spatial torsion element crashed
    this sum once)."""
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import shortest_period

    periods = []
    for name in ("solar_panel_deployment", "solar_panel_deployment_3d"):
        path = ROOT / "scenes" / "reduced" / f"{name}.toml"
        periods.append(shortest_period(build(kinds.load(path), str(path), path.parent)))
    assert periods[1] == pytest.approx(periods[0], rel=1e-9)


@pytest.mark.parametrize("name", ["slider_crank_flores2004", "spatial_slider_crank_flores"])
def test_a_mass_ratio_that_cannot_be_resolved_is_refused_at_once(tmp_path, name):
    """A slider of 1e-12 kg on the Flores joint: a contact period of 1.6e-10 s, 6e8 steps at
    two a period, beyond the integrator's 5e6 (the run worked on for minutes): one line,
    before any work; 1e-6 kg (7.6e5 steps) builds."""
    import tomli_w
    from conftest import pinbore

    data = tomllib.loads((ROOT / "scenes" / "reduced" / f"{name}.toml").read_text())
    slider = next(b for b in data["bodies"] if b["name"] == "slider")
    slider["mass"] = 1e-12
    path = tmp_path / "light.toml"
    path.write_text(tomli_w.dumps(data))
    done = pinbore("reduced", path, "--out", tmp_path / "out")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "bodies: the shortest contact or torsion period" in done.stderr
    assert "the mass ratio cannot be resolved" in done.stderr
    slider["mass"] = 1e-6
    from pinbore.reduced.mechanism import kinds
    path.write_text(tomli_w.dumps(data))
    build(kinds.load(path), str(path), path.parent)
