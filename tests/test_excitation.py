"""Harmonic excitation and linear spring-dampers in planar and spatial mechanisms, against
closed forms: a block on a guide held by a spring-damper and forced by a harmonic force,
and a wheel on a pin held by a torsion spring and forced by a harmonic torque, follow the
forced linear oscillator's solution from rest (transient and steady state); the energy book
closes with the loads' work; a shaken drive turns its body by the sum of its harmonics; bad
input is one line."""

import math

import numpy as np
import pytest
from conftest import simulated

from pinbore.core.errors import InputError

MASS, STIFFNESS, DAMPING, FORCE, FREQUENCY = 2.0, 800.0, 4.0, 3.0, 2.5   # kg, N/m, N s/m, N, Hz


def forced_from_rest(t, m, k, c, f, hz):
    """x(t) of m x'' + c x' + k x = f cos(w t) from x = x' = 0 (underdamped): the steady
    response A cos(w t - phi) plus the free decay that cancels it at t = 0."""
    w, wn = 2 * math.pi * hz, math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta ** 2)
    a, phi = f / math.hypot(k - m * w * w, c * w), math.atan2(c * w, k - m * w * w)
    c1 = -a * math.cos(phi)
    c2 = (zeta * wn * c1 - a * w * math.sin(phi)) / wd
    return a * np.cos(w * t - phi) + np.exp(-zeta * wn * t) * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t))


INTEGRATOR = {"rtol": 1e-11, "atol": 1e-14, "max_step": 1e-3}


def block_on_a_guide(kind):
    """The block slides along y on an ideal guide (planar prismatic; spatial prismatic along
    y), a spring-damper from a ground point 1 m below at its free length."""
    if kind == "planar":
        return {"kind": "planar", "duration": 1.5, "integrator": INTEGRATOR,
                "bodies": [{"name": "block", "mass": MASS, "inertia": 0.01}],
                "joints": [{"type": "prismatic", "body": "block", "axis_deg": 90.0}],
                "springs": [{"body_i": "ground", "point_i": [0.0, -1.0], "body_j": "block", "point_j": [0.0, 0.0],
                             "stiffness": STIFFNESS, "damping": DAMPING, "free_length": 1.0}],
                "loads": [{"body": "block", "force": [0.0, FORCE], "frequency_hz": FREQUENCY}]}
    return {"kind": "spatial", "duration": 1.5, "integrator": INTEGRATOR,
            "bodies": [{"name": "block", "mass": MASS, "inertia": np.diag([0.01, 0.01, 0.01]).tolist()}],
            "joints": [{"type": "prismatic", "body_i": "ground", "point_i": [0.0, 0.0, 0.0], "axis_i": [0.0, 1.0, 0.0],
                        "body_j": "block", "point_j": [0.0, 0.0, 0.0], "axis_j": [0.0, 1.0, 0.0]}],
            "springs": [{"body_i": "ground", "point_i": [0.0, -1.0, 0.0], "body_j": "block",
                         "point_j": [0.0, 0.0, 0.0], "stiffness": STIFFNESS, "damping": DAMPING, "free_length": 1.0}],
            "loads": [{"body": "block", "force": [0.0, FORCE, 0.0], "frequency_hz": FREQUENCY}]}


def wheel_on_a_pin(kind):
    """The wheel turns on an ideal pin at its centre, a torsion spring-damper to the ground,
    a harmonic torque (the same numbers as the block's, in N m/rad, N m s/rad, N m, kg m^2)."""
    torsion = {"type": "spring", "body_i": "ground", "body_j": "wheel", "stiffness": STIFFNESS,
               "damping": DAMPING}
    if kind == "planar":
        return {"kind": "planar", "duration": 1.5, "integrator": INTEGRATOR,
                "bodies": [{"name": "wheel", "mass": 1.0, "inertia": MASS}],
                "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0], "body_j": "wheel",
                            "point_j": [0.0, 0.0]}],
                "torsion": [torsion],
                "loads": [{"body": "wheel", "torque": FORCE, "frequency_hz": FREQUENCY}]}
    return {"kind": "spatial", "duration": 1.5, "integrator": INTEGRATOR,
            "bodies": [{"name": "wheel", "mass": 1.0, "inertia": np.diag([1.0, 1.0, MASS]).tolist()}],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0, 0.0], "axis_i": [0.0, 0.0, 1.0],
                        "body_j": "wheel", "point_j": [0.0, 0.0, 0.0], "axis_j": [0.0, 0.0, 1.0]}],
            "torsion": [torsion | {"axis_i": [0.0, 0.0, 1.0]}],
            "loads": [{"body": "wheel", "torque": [0.0, 0.0, FORCE], "frequency_hz": FREQUENCY}]}


def coordinate(model, trajectory, which):
    """The block's y (m) or the wheel's angle about z (rad) at each step."""
    states = trajectory.states
    if which == "y":
        return states[:, 1]
    if model.kind.dimension == 2:
        return states[:, 2]
    e0, e3 = states[:, 3], states[:, 6]   # a turn about z: p = (cos a/2, 0, 0, sin a/2)
    return 2 * np.arctan2(e3, e0)


@pytest.mark.parametrize("kind", ["planar", "spatial"])
@pytest.mark.parametrize("scene, which", [(block_on_a_guide, "y"), (wheel_on_a_pin, "angle")],
                         ids=["force-spring", "torque-torsion"])
def test_forced_oscillator_from_rest_in_closed_form(kind, scene, which):
    """The forced response from rest, transient and steady state, to 1e-7 of the steady
    amplitude (rtol 1e-11 over 1.5 s, 4 forcing periods and 7 natural ones: the error of the
    adaptive integration, far below); the energy book (kinetic + spring - the loads' work +
    the damper's dissipation) closes to 1e-9 of the peak kinetic energy."""
    from pinbore.reduced.mechanism import outputs

    model, trajectory = simulated(scene(kind))
    exact = forced_from_rest(trajectory.times, MASS, STIFFNESS, DAMPING, FORCE, FREQUENCY)
    steady = FORCE / math.hypot(STIFFNESS - MASS * (2 * math.pi * FREQUENCY) ** 2,
                                DAMPING * 2 * math.pi * FREQUENCY)
    assert np.max(np.abs(coordinate(model, trajectory, which) - exact)) < 1e-7 * steady
    _, energy, _ = outputs.per_step(model, trajectory)
    book = energy["kinetic"] + energy["potential"] + energy["elastic"] + energy["dissipated"] - energy["work_in"]
    assert np.max(np.abs(book - book[0])) < 1e-9 * np.max(energy["kinetic"])
    assert energy["work_in"][-1] > 0 and energy["dissipated"][-1] > 0


@pytest.mark.parametrize("kind", ["planar", "spatial"])
def test_a_shaken_drive_turns_its_body_by_its_harmonics(kind):
    """theta(t) = sum A (sin(2 pi f t + phase) - sin(phase)) of two harmonics, followed to the
    constraint's drift (Baumgarte-stabilised, 1e-8 rad)."""
    harmonics = [{"amplitude_deg": 5.0, "frequency_hz": 2.0, "phase_deg": 30.0},
                 {"amplitude_deg": 1.5, "frequency_hz": 6.0, "phase_deg": -60.0}]
    data = wheel_on_a_pin(kind)
    data.pop("loads")
    if kind == "planar":
        data["drive"] = {"body": "wheel", "harmonics": harmonics}
    else:
        data["joints"][0]["name"] = "pin"
        data["drive"] = {"joint": "pin", "harmonics": harmonics}
    model, trajectory = simulated(data)
    t = trajectory.times
    exact = sum(math.radians(h["amplitude_deg"]) * (np.sin(2 * math.pi * h["frequency_hz"] * t
                                                           + math.radians(h["phase_deg"]))
                                                    - math.sin(math.radians(h["phase_deg"])))
                for h in harmonics)
    assert np.max(np.abs(coordinate(model, trajectory, "angle") - exact)) < 1e-8


@pytest.mark.parametrize("edit, rule", [
    (lambda d: d["loads"][0].update(force=[0.0, 0.0]), "a load needs a nonzero force or torque"),
    (lambda d: d["loads"][0].update(body="ground"), "loads.body: must be a moving body"),
    (lambda d: d["loads"][0].update(frequency_hz=-1.0), "frequency_hz"),
    (lambda d: d["loads"][0].update(frequency_hz=math.inf), "frequency_hz"),
    (lambda d: d["loads"][0].update(body="nobody"), "loads.body: unknown body 'nobody'"),
    (lambda d: d["springs"][0].update(free_length=0.0), "free_length"),
    (lambda d: d["springs"][0].update(stiffness=-1.0), "stiffness"),
    (lambda d: d["springs"][0].update(body_j="nobody"), "springs.body_j: unknown body"),
    (lambda d: d.update(drive={"body": "block", "speed_rpm": 10.0,
                               "harmonics": [{"amplitude_deg": 1.0, "frequency_hz": 1.0}]}), "one of them"),
    (lambda d: d.update(drive={"body": "block", "harmonics": [{"amplitude_deg": 0.0, "frequency_hz": 1.0}]}),
     "amplitude_deg"),
])
def test_bad_excitation_is_one_line(edit, rule):
    from pinbore.reduced.mechanism import kinds

    data = block_on_a_guide("planar")
    edit(data)
    with pytest.raises(InputError) as err:
        kinds.validate(data, "test")
    assert rule in str(err.value) and "\n" not in str(err.value)


def test_the_shaken_panel_on_a_vertical_hinge_rests_its_weight_on_a_shoulder_and_its_moment_on_the_end_slices():
    """scenes/reduced/deployed_panel_shaken_3d.toml, statics of the panel on its hinge: the
    hinge axis vertical, gravity along it. The lower shoulder carries the weight m g =
    29.43 N; the bore carries the weight's moment about the lug's middle, m g l (l = 0.5 m
    from the journal point to the panel's centre), as a couple on the pin's two end slices
    (the pin tilts in its clearance until they touch), whose centres lie L/2 - L/16 = 17.5 mm
    either side of the middle: their forces sum to 2 m g l / 0.035 m = 840.9 N. Over the
    second second (the start's impacts decayed), the means within 1e-3 and 2e-3: the shaking
    (0.05 deg at 3 Hz) adds in-plane loads of a few newtons that swing the end slices' forces
    by about +-0.3 N, and friction on the slices could take part of the weight."""
    import tomllib

    from conftest import ROOT

    from pinbore.reduced.mechanism import outputs

    data = tomllib.loads((ROOT / "scenes/reduced/deployed_panel_shaken_3d.toml").read_text())
    data["duration"] = 2.0
    model, trajectory = simulated(data)
    cols = outputs.per_step(model, trajectory)[0]
    late = cols["time_s"] > 1.0
    mass, g, arm, span = 3.0, 9.81, 0.5, 0.035
    assert np.mean(cols["hinge_axial_force_N"][late]) == pytest.approx(mass * g, rel=1e-3)
    assert np.mean(cols["hinge_normal_force_N"][late]) == pytest.approx(2 * mass * g * arm / span, rel=2e-3)
