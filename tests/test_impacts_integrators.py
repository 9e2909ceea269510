"""Impulse (Newton/Poisson, three-state) contact, the stiff and the fixed-step integrators, and
friction elements inside the clearance joint, against independent references: the
continuous model in the stiff limit, the Newton-Poisson equivalence of frictionless impacts,
statics, the closed-form overdamped oscillator and exact slider-crank kinematics, and the
closed-form stick-slip cycle of a mass on a belt."""

import copy
import math

import numpy as np
import pytest
from conftest import ROOT
from test_reduced import free_mechanism, solve

from pinbore.laws import dissipative
from pinbore.laws.elastic import Joint, hertz_point
from pinbore.reduced.mechanism.layout import LOG_RATE, LOG_TIME
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import PlanarScene


def rigid(data, model="newton", e=0.9):
    """The same scene with its clearance joint as a rigid impact pair."""
    data = copy.deepcopy(data)
    joint = data["clearance_joints"][0]
    for key in ("normal_law", "damping_law", "friction"):
        joint.pop(key, None)
    joint.update(impact=model, restitution=e)
    return data


def first_rebound(data):
    """The state just after the first impact ends (all bodies' velocities), and when."""
    model = build(PlanarScene.model_validate(data), "test", ROOT)
    run = simulate(model)
    cols = per_step(model, run)[0]
    force = cols["rod_slider_normal_force_N"]
    if model.scene.clearance_joints[0].impact == "continuous":
        k = np.flatnonzero(force > 0)[0]
        k += np.argmax(force[k:] == 0)     # first step after separation
    else:
        k = np.searchsorted(run.times, run.impacts[0, LOG_TIME])
    return run.states[k, model.nq:2 * model.nq], run.times[k], run


def test_impulse_and_continuous_models_agree_on_rebound_for_a_stiff_law():
    """The free slider-crank's first journal impact: a continuous Hertz + Lankarani-Nikravesh
    contact made stiffer (E x 10^2, x 10^4) approaches the Newton impulse with the law's own
    effective restitution (computed by integrating the law alone)."""
    data = free_mechanism("lankarani_nikravesh")
    data["duration"] = 4e-3
    joint = Joint(10e-3, 9.5e-3, 207e9, 0.3, 207e9, 0.3, 1.0)
    chi = dissipative.HYSTERESIS["lankarani_nikravesh"](0.8)
    e_eff = dissipative.restitution(
        lambda d, r: dissipative.hysteresis_force(hertz_point(max(d, 0), joint), r, 1.0, chi), 1.0, 1.0)
    impulse, _, run = first_rebound(rigid(data, "newton", e_eff))
    assert run.counters[3] >= 1
    errors = []
    for scale in (1.0, 1e2, 1e4):
        data["clearance_joints"][0]["E"] = 207e9 * scale
        continuous, _, _ = first_rebound(data)
        errors.append(np.max(np.abs(continuous - impulse)) / np.max(np.abs(impulse)))
    assert errors[0] > errors[1] > errors[2] and errors[2] < 2e-4, errors


def test_newton_and_poisson_coincide_without_friction_and_newton_e1_keeps_energy():
    data = rigid(free_mechanism(), "newton", 1.0)
    cols_n, e, _, counters = solve(data)
    total = e["kinetic"] + e["potential"]
    assert counters[3] >= 3
    assert np.max(np.abs(total - total[0])) < 1e-6 * e["kinetic"].max()
    cols_p, _, _, _ = solve(rigid(free_mechanism(), "poisson", 1.0))
    np.testing.assert_allclose(cols_p["slider_x_m"], cols_n["slider_x_m"], rtol=0, atol=1e-12)


def test_impacts_lose_energy_to_dissipation_and_the_balance_closes():
    _, e, _, counters = solve(rigid(free_mechanism(), "newton", 0.6))
    assert counters[3] >= 3
    assert np.all(np.diff(e["dissipated"]) >= -1e-14 * e["kinetic"].max()) and e["dissipated"][-1] > 0
    balance = e["kinetic"] + e["potential"] + e["dissipated"]
    assert np.max(np.abs(balance - balance[0])) < 1e-6 * e["kinetic"].max()


def test_bouncing_journal_comes_to_rest_in_held_contact_carrying_its_weight():
    """Three-state model: a journal dropped inside a fixed bearing bounces (e = 0.5), the
    rebounds shrink below the rest speed, the contact is held, and then carries m g."""
    mass, g = 0.5, 9.81
    data = {"kind": "planar", "duration": 0.2, "gravity": [0.0, -g],
            "bodies": [{"name": "journal", "mass": mass, "inertia": 1e-5}],
            "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 9.0e-3, "E": 207e9,
                                  "nu": 0.3, "impact": "newton", "restitution": 0.5,
                                  "start": "free"}],
            "integrator": {"rtol": 1e-9, "atol": 1e-12}}
    model = build(PlanarScene.model_validate(data), "test", ROOT)
    run = simulate(model)
    assert run.status == 0
    cols = per_step(model, run)[0]
    rates = run.impacts[:, LOG_RATE]
    assert len(rates) >= 3 and np.all(rates[1:] < rates[:-1])   # each bounce slower
    assert np.allclose(rates[1:-1] / rates[:-2], 0.5, rtol=1e-4)  # v_(k+1) = e v_k (drop height)
    assert run.modes[-1, 0] == 1   # the journal's one contact is held
    assert cols["j_normal_force_N"][-1] == pytest.approx(mass * g, rel=1e-8)
    assert cols["j_ecc_y_m"][-1] == pytest.approx(-1e-3, abs=1e-12)


def torsional_oscillator(method, damping):
    return {"kind": "planar", "duration": 0.05,
            "bodies": [{"name": "disc", "mass": 1.0, "inertia": 1e-4, "omega": 1.0}],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0],
                        "body_j": "disc", "point_j": [0.0, 0.0]}],
            "torsion": [{"type": "spring", "body_i": "ground", "body_j": "disc", "stiffness": 10.0,
                         "damping": damping}],
            "integrator": {"method": method, "rtol": 1e-6, "atol": 1e-10, "max_step": 1.0}}


def test_rosenbrock_integrates_a_stiff_overdamped_oscillator_in_few_steps():
    """J phi'' + c phi' + k phi = 0 with c / J = 10^6 /s (eigenvalues -10^6 and -k/c): the
    closed form is matched by both methods, the implicit one in a small fraction of the steps
    the explicit one needs for stability."""
    inertia, k, c = 1e-4, 10.0, 100.0
    r1, r2 = np.roots([inertia, c, k])
    steps = {}
    for method in ("rosenbrock23", "dopri5"):
        cols, _, _, counters = solve(torsional_oscillator(method, c))
        t = cols["time_s"]
        a, b = np.linalg.solve([[1, 1], [r1, r2]], [0.0, 1.0])   # phi(0) = 0, phi'(0) = 1
        exact = a * np.exp(r1 * t) + b * np.exp(r2 * t)
        late = t > 1e-4
        assert np.max(np.abs(cols["disc_angle_rad"][late] - exact[late])) < 1e-3 * np.max(np.abs(exact))
        steps[method] = counters[0]
    assert steps["rosenbrock23"] < steps["dopri5"] / 20, steps


def test_fixed_step_dopri5_converges_with_fifth_order():
    """A pinned disc on a torsion spring (J phi'' + k phi = 0, phi'(0) = 1): the fixed-step
    error against phi = sin(W t) / W falls 32-fold per halved step."""
    inertia, k = 1e-4, 10.0
    w = math.sqrt(k / inertia)
    errors = []
    for step in (2e-4, 1e-4):
        data = torsional_oscillator("dopri5_fixed", 0.0)
        data["integrator"]["fixed_step"] = step
        cols, _, _, _ = solve(data)
        exact = np.sin(w * cols["time_s"]) / w
        errors.append(np.max(np.abs(cols["disc_angle_rad"] - exact)))
    assert math.log2(errors[0] / errors[1]) > 4.5, errors


def belt(friction, duration=1.2):
    """A mass on a belt as a journal on a turning drum: the drum (bearing, R_b = 10 mm) turns
    at omega_b about a fixed centre; the journal turns about its own fixed centre, held at a
    penetration delta0 below the drum's (constant normal force N), against a torsion spring k.
    With r = R_j - delta0 it is a mass J/r^2 on a spring k/r^2 riding a belt of speed omega_b R_b."""
    c, delta0 = 0.5e-3, 2e-7
    return {"kind": "planar", "duration": duration,
            "bodies": [{"name": "drum", "mass": 1.0, "inertia": 1e-3},
                       {"name": "journal", "mass": 1.0, "inertia": 2e-6, "position": [0.0, -c - delta0]}],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0],
                        "body_j": "drum", "point_j": [0.0, 0.0]},
                       {"type": "revolute", "body_i": "ground", "point_i": [0.0, -c - delta0],
                        "body_j": "journal", "point_j": [0.0, 0.0]}],
            "drive": {"body": "drum", "speed_rpm": 0.05 / 10e-3 * 60 / (2 * math.pi)},   # belt 0.05 m/s
            "torsion": [{"type": "spring", "body_i": "ground", "body_j": "journal", "stiffness": 0.02}],
            "clearance_joints": [{"name": "j", "bearing_body": "drum", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 10e-3 - c, "E": 207e9,
                                  "nu": 0.3, "normal_law": "hertz_point", "friction": friction,
                                  "start": "placed"}],
            "integrator": {"method": "rosenbrock23", "rtol": 1e-6, "atol": 1e-10, "max_step": 1e-3}}


def test_mass_on_belt_stick_slip_cycle_matches_the_closed_form():
    """Coulomb friction with mu_s > mu_k (LuGre with stiff bristles and a Stribeck speed far
    below the slip speeds; integrated by the stiff method): the mass sticks to the belt until the spring reaches mu_s N, slips harmonically
    about mu_k N / k, and sticks again where its speed meets the belt's. Closed form:
    x_s = mu_s N / k, x_k = mu_k N / k, A^2 = (x_s - x_k)^2 + (v_b / w)^2, period
    2 (x_s - x_k) / v_b + (pi + 2 asin(v_b / (A w))) / w, lowest point x_k - A."""
    mu_s, mu_k = 0.4, 0.25
    data = belt({"law": "lugre", "mu_coulomb": mu_k, "mu_static": mu_s, "stribeck_speed": 1e-3,
                 "sigma0": 1e7, "sigma1": 300.0})   # bristles about critically damped
    scene = PlanarScene.model_validate(data)
    cols, _, _, _ = solve(data)
    r_b, c, delta0 = 10e-3, 0.5e-3, 2e-7
    r = r_b - c - delta0
    joint = Joint(r_b, r_b - c, 207e9, 0.3, 207e9, 0.3, 1.0)
    normal = float(hertz_point(delta0, joint))
    mass, spring = 2e-6 / r**2, 0.02 / r**2
    v_b = scene.drive.speed_rpm * 2 * math.pi / 60 * r_b
    w = math.sqrt(spring / mass)
    x_s, x_k = mu_s * normal / spring, mu_k * normal / spring
    amplitude = math.hypot(x_s - x_k, v_b / w)
    period = 2 * (x_s - x_k) / v_b + (math.pi + 2 * math.asin(v_b / (amplitude * w))) / w
    t, x = cols["time_s"], cols["journal_angle_rad"] * r
    late = t > 0.3 * t[-1]
    assert np.max(x[late]) == pytest.approx(x_s, rel=0.01)
    assert np.min(x[late]) == pytest.approx(x_k - amplitude, rel=0.01)
    slipping = np.flatnonzero(np.diff((np.gradient(x, t) < 0.5 * v_b).astype(int)) == 1)
    starts = t[slipping][t[slipping] > 0.3 * t[-1]]
    assert np.mean(np.diff(starts)) == pytest.approx(period, rel=0.01)


def test_jenkins_element_in_the_joint_slides_at_mu_n():
    """The belt with a bilinear Iwan joint without its parallel spring (a Jenkins element,
    k1 stiff, mu = 0.3): the slider caps the friction at mu N, and the mass oscillates about
    the spring's balance of the sliding friction, x = mu N / k (Coulomb, mu_s = mu_k)."""
    mu = 0.3
    data = belt({"law": "iwan_bilinear", "mu": mu, "k1": 1e6}, duration=0.6)
    cols, _, _, _ = solve(data)
    r_b, c, delta0 = 10e-3, 0.5e-3, 2e-7
    r = r_b - c - delta0
    normal = float(hertz_point(delta0, Joint(r_b, r_b - c, 207e9, 0.3, 207e9, 0.3, 1.0)))
    t, friction = cols["time_s"], np.abs(cols["j_friction_force_N"])
    assert np.max(friction) == pytest.approx(mu * normal, rel=1e-9)
    late = t > 0.2
    x = cols["journal_angle_rad"][late] * r
    mean = np.sum(0.5 * (x[1:] + x[:-1]) * np.diff(t[late])) / (t[late][-1] - t[late][0])
    assert mean == pytest.approx(mu * normal / (0.02 / r**2), rel=0.01)
