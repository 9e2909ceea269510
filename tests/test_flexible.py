"""Flexible bodies in the mechanism: the floating frame of the FE modes (reduced.mechanism.
planar, .flexible) against independent references.

- The rigid limit: a pendulum whose modulus is 1e4 times steel's swings as the rigid compound
  pendulum, whose angle is Jacobi's elliptic function (exact, any amplitude).
  So do the shipped mechanisms: the flexible slider-crank's first impact (its peak force and
  approach speed) and the flexible deployment's bus attitude, each against its rigid twin of
  the same mass and inertia.
- Conservation: without damping, the pendulum's energy book (kinetic + gravity + strain)
  holds; a free, spinning flexible body keeps its angular momentum J(eta) phi' + g . eta'
  (computed here from the file's invariants) while its spin loads its modes.
- Static: a beam clamped horizontally under gravity, its modes damped, settles to the tip
  deflection of the DOLFINx static solution on the same mesh (and Euler-Bernoulli's
  rho A g L^4 / 8 EI), within the truncation of the retained modes.
- The spin-up beam [SimoVuQuoc1986]: early in the spin-up (slow spin), the tip's deflection
  in the hub frame is the quasi-static one of a cantilever under the Euler load rho A alpha x,
  11 q0 L^4 / (120 EI) with q0 = rho A alpha L; with the geometric stiffening the deflection
  stays bounded, and at omega_s = 6 rad/s the beam vibrates at the rotating cantilever's
  first lead-lag frequency [HodgesRutkowski1981]; without it the linear model departs
  (it softens: its frequency falls below the still beam's).
"""

import dataclasses
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT, compound_pendulum, kinematic_duality, pinbore, simulated

from pinbore.fem.modes import file as modes_file
from pinbore.reduced.mechanism import layout
from pinbore.reduced.mechanism.flexible import rigid_twin

G = 9.81
SMALL = 1e-2   # of gravity: a static load whose deflection is linear
# the spin-up beam's data [SimoVuQuoc1986]
L_BEAM, EI, RHO_A = 10.0, 1.4e4, 1.2
OMEGA_S, T_S = 6.0, 15.0


@pytest.fixture(scope="module")
def bodies(tmp_path_factory):
    """The reduced bodies of the shipped modes scenes of the pendulum and the spin-up beam."""
    out = tmp_path_factory.mktemp("modes")
    paths = {}
    for name in ("pendulum_beam_2d", "spinup_beam_2d", "link_steel_2d", "panel_strip_2d"):
        result = pinbore("modes", str(ROOT / "scenes" / "modes" / f"{name}.toml"), "--out", str(out / name))
        assert result.returncode == 0, result.stderr
        paths[name] = out / name / "body.npz"
    return paths


def pendulum(path, duration=1.0, **body):
    return {"kind": "planar", "duration": duration, "gravity": [0.0, -G],
            "bodies": [{"name": "beam", "modes_file": str(path), "position": [0.5, 0.0]} | body],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0],
                        "body_j": "beam", "point_j": [-0.5, 0.0]}],
            "integrator": {"rtol": 1e-9, "atol": 1e-12, "max_step": 2e-4},
            "output": {"plots": False, "sample_time": 1e-3,
                       "points": [{"name": "tip", "body": "beam", "position": [0.5, 0.0]}]}}


def stiffer(path, out, factor):
    """The body of `path` with its modulus times factor: its frequencies times sqrt(factor),
    its M-normalised modes, inertia and stiffening (a stress of body forces, independent of
    E) the same: the exact scaling of linear elasticity."""
    body = modes_file.read(path)
    modes_file.write(out, dataclasses.replace(body, omega=body.omega * math.sqrt(factor)))
    return out


def test_a_point_of_a_flexible_body_moves_as_the_material_at_its_place(bodies):
    """The link bent at random (modal coordinates about 1e-3 m sqrt(kg), every rate about 1):
    the velocity of a point of its eye from the material point (point_state) and back from
    its deformed place (material_velocity) agree to 1e-12, and the generalised force of a
    force there does its power (virtual work) to 1e-12. (The place is turned back by the
    inverse of I + theta k x, (I - theta k x) / (1 + theta^2); the states' interfaces turn
    by 0.2-1.3 rad, so that without the factor the velocities differed by 0.1-14 %.)"""
    data = {"kind": "planar", "duration": 0.1,
            "bodies": [{"name": "link", "modes_file": str(bodies["link_steel_2d"])}],
            "output": {"plots": False}}
    for seed in range(3):
        velocity, material, power, generalised = kinematic_duality(data, (0.064, 0.003), seed=seed)
        assert np.abs(material - velocity).max() <= 1e-12 * np.abs(velocity).max()
        assert abs(generalised - power) <= 1e-12 * max(abs(power), 1.0)


def test_a_stiff_pendulum_swings_as_the_rigid_one(bodies, tmp_path):
    """E x 1e4 (two modes, 1.7e4 and 4.6e4 rad/s): the floating frame's angle follows the
    rigid compound pendulum (same mass and inertia, from the file) to 1e-6 rad over a whole
    swing; the tip's elastic displacement is 1e4 times smaller than steel's."""
    stiff = stiffer(bodies["pendulum_beam_2d"], tmp_path / "stiff.npz", 1e4)
    body = modes_file.read(stiff)
    model, trajectory = simulated(pendulum(stiff, modes=2))
    inertia = body.second_moments[0, 0] + body.second_moments[1, 1]
    exact = compound_pendulum(trajectory.times, body.mass, inertia, 0.5)
    assert np.abs(trajectory.states[:, 2] - exact).max() < 1e-6


def shipped(name: str, flexible: str, path, **changes) -> dict:
    data = tomllib.loads((ROOT / "scenes" / "reduced" / f"{name}.toml").read_text())
    for b in data["bodies"]:
        if b["name"] == flexible:
            b["modes_file"] = str(path)
    return data | changes


def test_the_stiff_flexible_slider_crank_impacts_as_the_rigid_one(bodies, tmp_path):
    """The Flores slider-crank with its flexible rod (6 modes, 47-282 krad/s in steel) to just
    past its first impact's peak: the peak contact force and the impact speed against the
    rigid rod of the same mass and inertia. The rod's compliance in series with the contact's
    softens the impact (steel: the peak 45 % lower); the stiffer the rod the closer the rigid
    one: with E x 1e2 the peak differs by about 5e-3, with E x 1e4 it is the rigid one's within
    1e-4 (the onset is located to the integrator's tolerance, rtol 1e-5: the impact speed
    within 1e-3)."""
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.run import summarised

    def first_impact(data):
        _, trajectory, _, summary = summarised(kinds.validate(data, "test"), "test", ROOT)
        joint = summary.clearance_joints["rod_slider"]
        return joint.peak_normal_force_N, trajectory.impacts[0, layout.LOG_RATE]

    flexible = shipped("slider_crank_flores2004_flexible", "rod", bodies["link_steel_2d"], duration=5e-4)
    rigid_peak, rigid_speed = first_impact(rigid_twin(flexible))
    errors = {}
    for factor in (1e2, 1e4):
        stiff = stiffer(bodies["link_steel_2d"], tmp_path / f"link_{factor:g}.npz", factor)
        peak, speed = first_impact(flexible | {"bodies": shipped(
            "slider_crank_flores2004_flexible", "rod", stiff)["bodies"]})
        errors[factor] = (abs(peak / rigid_peak - 1), abs(speed / rigid_speed - 1))
    print(f"first impact against the rigid rod (peak, speed): {errors}")
    assert errors[1e4][0] < 1e-4 and errors[1e4][1] < 1e-3
    assert errors[1e2][0] > 10 * errors[1e4][0]


def test_the_stiff_flexible_deployment_turns_the_bus_as_the_rigid_one(bodies, tmp_path):
    """The planar solar-panel deployment with its flexible panel (six modes, 13 Hz first in
    the free strip), through the deployment and the latch (to 4.5 s: the latch catches the
    panel at 4.1 s): the bus's attitude against the rigid panel's twin. The panel's bending
    under the latch's torque turns the bus; with E x 1e2 the attitude differs by about 7e-5
    rad after the latch, with E x 1e4 by 1e-6 rad and less (the hinge rattles in its clearance
    after the latch: the timing of its small impacts differs, which the attitude smooths)."""
    rigid = simulated(rigid_twin(shipped("solar_panel_deployment_flexible", "panel",
                                         bodies["panel_strip_2d"], duration=4.5)))
    grid = np.linspace(0.0, 4.5, 9001)

    def attitude(model, trajectory):
        return np.interp(grid, trajectory.times, trajectory.states[:, model.geometry.coordinate(0) + 2])

    errors = {}
    for factor in (1e2, 1e4):
        stiff = stiffer(bodies["panel_strip_2d"], tmp_path / f"strip_{factor:g}.npz", factor)
        flexible = simulated(shipped("solar_panel_deployment_flexible", "panel", stiff, duration=4.5))
        errors[factor] = np.abs(attitude(*flexible) - attitude(*rigid)).max()
    print(f"bus attitude against the rigid twin (rad): {errors}")
    assert errors[1e4] < 2e-6 and errors[1e2] > 10 * errors[1e4]


def test_the_pendulum_keeps_its_energy_and_bends(bodies):
    """Steel, six modes, no damping: kinetic + gravity + strain energy is constant to 1e-9 of
    the energy it gains; the beam bends (its tip leaves the floating frame's axis by a tenth of
    a millimetre and more) while its frame swings within 2 mrad of the rigid pendulum's."""
    from pinbore.reduced.mechanism.outputs import per_step

    model, trajectory = simulated(pendulum(bodies["pendulum_beam_2d"]))
    cols, energy, _ = per_step(model, trajectory)
    total = energy["kinetic"] + energy["potential"]
    gained = energy["kinetic"].max()
    assert np.abs(total - total[0]).max() < 1e-9 * gained
    assert np.abs(cols["beam_tip_uy_m"]).max() > 1e-4
    body = modes_file.read(bodies["pendulum_beam_2d"])
    inertia = body.second_moments[0, 0] + body.second_moments[1, 1]
    exact = compound_pendulum(trajectory.times, body.mass, inertia, 0.5)
    assert np.abs(trajectory.states[:, 2] - exact).max() < 2e-3


def test_a_free_mechanism_with_a_flexible_body_keeps_its_momenta(bodies):
    """A rigid hub (50 kg) and the spin-up beam pinned to it, free in space, spinning at
    0.5 rad/s, a preloaded torsion spring between them (20 deg, 100 N m/rad) that bends the
    beam through its root: the linear momentum and the angular momentum about the origin,
    sum of m r x v + J w of the hub and m r x v + J(eta) phi' + g . eta' of the beam (J =
    I0 + 2 s1 . eta + eta^T (S_xx + S_yy - K_G) eta, g = (S_xy - S_yx)^T eta, computed here from
    the file), stay constant to 1e-9, and so does the energy book (1e-8 of the energy that
    moves)."""
    from pinbore.reduced.mechanism.outputs import per_step

    path = bodies["spinup_beam_2d"]
    data = {"kind": "planar", "duration": 3.0,
            "bodies": [{"name": "hub", "mass": 50.0, "inertia": 5.0, "omega": 0.5},
                       {"name": "beam", "modes_file": str(path), "position": [5.5, 0.0], "omega": 0.5}],
            "joints": [{"type": "revolute", "body_i": "hub", "point_i": [0.5, 0.0],
                        "body_j": "beam", "point_j": [-5.0, 0.0]}],
            "torsion": [{"type": "spring", "body_i": "hub", "body_j": "beam", "stiffness": 100.0,
                         "free_angle_deg": 20.0}],
            "integrator": {"rtol": 1e-10, "atol": 1e-12, "max_step": 1e-3},
            "output": {"plots": False}}
    model, trajectory = simulated(data)
    b = modes_file.read(path)
    n = b.modes
    y, nq = trajectory.states, model.nq
    hub, beam = y[:, :3], y[:, 3:6]
    hub_v, beam_v = y[:, nq:nq + 3], y[:, nq + 3:nq + 6]
    eta, rate = y[:, 6:6 + n], y[:, nq + 6:nq + 6 + n]
    quad = b.S[0, 0] + b.S[1, 1] - b.stiffening[2, 2]
    inertia = (b.second_moments[0, 0] + b.second_moments[1, 1] + 2 * eta @ (b.s[0, 0] + b.s[1, 1])
               + np.einsum("ti,ij,tj->t", eta, quad, eta))
    g = eta @ (b.S[0, 1] - b.S[1, 0])

    def moment(mass, r, v):
        return mass * (r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0])

    momentum = (moment(50.0, hub, hub_v) + 5.0 * hub_v[:, 2] + moment(b.mass, beam, beam_v)
                + inertia * beam_v[:, 2] + np.einsum("ti,ti->t", g, rate))
    linear = 50.0 * hub_v[:, :2] + b.mass * beam_v[:, :2]
    assert np.abs(eta).max() > 1e-3                     # the spring did bend the beam
    assert np.abs(momentum / momentum[0] - 1).max() < 1e-9
    assert np.abs(linear - linear[0]).max() < 1e-9 * np.abs(momentum[0]) / L_BEAM
    _, energy, _ = per_step(model, trajectory)
    total = energy["kinetic"] + energy["potential"]
    assert np.abs(total - total[0]).max() < 1e-8 * np.ptp(energy["kinetic"])


def static_tip_deflection(scene_path) -> float:
    """The tip deflection (m, mean over the free end's nodes) of the DOLFINx static solution
    of the modes scene's body held at its interface "a" (tied rigidly, as in the reduction)
    under gravity along -y on the same mesh: K_II u_I = (M g)_I."""
    import scipy.sparse.linalg

    from pinbore.core import scene as scenes
    from pinbore.fem.modes.reduction import FEBody, mesh_of, rigid_interfaces
    from pinbore.fem.modes.scene import ModesScene

    scene = scenes.validate(ModesScene, scenes.read_toml(scene_path), str(scene_path))
    fe = FEBody(mesh_of(scene), scene)
    interior, _ = rigid_interfaces(fe, scene)
    g = np.zeros(fe.K.shape[0])
    g[1::2] = -G
    f = fe.M @ g
    u = np.zeros_like(f)
    u[interior] = scipy.sparse.linalg.spsolve(fe.K[interior][:, interior].tocsc(), f[interior])
    tip = np.flatnonzero(np.isclose(fe.X[:, 0], fe.X[:, 0].max()))
    return float(u[2 * tip + 1].mean())


def test_a_clamped_beam_settles_to_its_static_deflection(bodies):
    """The pendulum's beam held horizontal at its root (a drive at zero speed on its interface
    "a") under gravity, its modes damped (zeta = 1 of the free-free modes: the cantilever's
    own first mode, mostly a turn of the floating frame, keeps a few percent of it), 3 s: its
    tip's mean over the last six periods of that mode (1.875^2 sqrt(EI / rho A L^4)) is the
    DOLFINx static deflection on the same mesh within 0.5 % (the truncation of six modes and the
    oscillation left) and Euler-Bernoulli's rho A g L^4 / 8 EI within 1 %. Gravity is a
    hundredth of the Earth's, so that the deflection (0.2 mm, 2e-4 of the length) is linear:
    at 1 g the beam's slope (0.03 rad) turns its floating frame enough for the second-order
    terms a linear deformation leaves out to move the tip by a few percent."""
    from pinbore.reduced.mechanism.outputs import per_step

    data = pendulum(bodies["pendulum_beam_2d"], duration=3.0, damping_ratio=1.0)
    data["drive"] = {"body": "beam", "speed_rpm": 0.0}
    data["gravity"] = [0.0, -G * SMALL]
    model, trajectory = simulated(data)
    cols, _, _ = per_step(model, trajectory)
    E, width, thickness, rho = 2.1e11, 0.005, 0.020, 7850.0
    ei, rho_a = E * thickness * width ** 3 / 12, rho * width * thickness
    period = 2 * math.pi / (1.8751 ** 2 * math.sqrt(ei / rho_a))
    t, tip = cols["time_s"], cols["beam_tip_y_m"]
    last = t > t[-1] - 6 * period
    settled = np.trapezoid(tip[last], t[last]) / np.ptp(t[last])
    fe = static_tip_deflection(ROOT / "scenes" / "modes" / "pendulum_beam_2d.toml")
    assert settled == pytest.approx(SMALL * fe, rel=5e-3)
    assert settled == pytest.approx(-SMALL * rho_a * G / (8 * ei), rel=1e-2)


def spin_up_beam(path, stiffening=True, duration=20.0):
    return {"kind": "planar", "duration": duration,
            "bodies": [{"name": "beam", "modes_file": str(path), "position": [5.0, 0.0],
                        "stiffening": stiffening}],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0],
                        "body_j": "beam", "point_j": [-5.0, 0.0]}],
            "drive": {"body": "beam", "point": [-5.0, 0.0],
                      "speed_rpm": OMEGA_S * 30 / math.pi, "spin_up_s": T_S},
            "integrator": {"rtol": 1e-8, "atol": 1e-10, "max_step": 1e-3},
            "output": {"plots": False, "sample_time": 1e-2,
                       "points": [{"name": "tip", "body": "beam", "position": [5.0, 0.0]}]}}


def hub_deflection(model, trajectory):
    """(times, the tip's deflection across the hub's axis (m), the hub's angle theta(t))."""
    from pinbore.core.cpp.mechanism import spin_up
    from pinbore.reduced.mechanism.outputs import per_step

    cols, _, _ = per_step(model, trajectory)
    t = cols["time_s"]
    theta = np.array([spin_up(x, OMEGA_S, T_S)[0] for x in t])
    return t, -np.sin(theta) * cols["beam_tip_x_m"] + np.cos(theta) * cols["beam_tip_y_m"]


# The first flapwise frequency of a uniform cantilever turning about its root, omega /
# sqrt(EI / rho A L^4) against Omega / sqrt(EI / rho A L^4) [HodgesRutkowski1981]; in the plane
# of the turn (lead-lag) omega_lag^2 = omega_flap^2 - Omega^2.
FLAPWISE = {5.0: 6.4495, 6.0: 7.3604, 7.0: 8.2996}


def lead_lag_frequency(spin: float) -> float:
    """rad/s of the spin-up beam at a constant spin (rad/s), the table interpolated by the
    parabola through its three points."""
    scale = math.sqrt(EI / (RHO_A * L_BEAM ** 4))
    x = spin / scale
    flap = np.polyval(np.polyfit(list(FLAPWISE), list(FLAPWISE.values()), 2), x)
    return math.sqrt(flap ** 2 - x ** 2) * scale


def after_spin_up(t, deflection):
    """(mean, amplitude, frequency (rad/s) from the zero crossings) of the deflection a second
    after the spin-up."""
    after = t > T_S + 1
    tt, d = t[after], deflection[after] - deflection[after].mean()
    crossings = tt[1:][np.sign(d[1:]) != np.sign(d[:-1])]
    return deflection[after].mean(), np.ptp(d) / 2, math.pi / np.diff(crossings).mean()


def test_the_spin_up_beam_bends_quasi_statically_then_vibrates_at_the_rotating_frequency(bodies):
    """At 2 s and 3 s (spin 0.09 and 0.29 rad/s, far below the first cantilever frequency,
    3.8 rad/s) the tip lags by the quasi-static deflection of the Euler load within 3 %; the
    deflection peaks between 0.3 and 0.7 m during the spin-up and, at 6 rad/s after it, the tip
    vibrates about the hub's axis (within 1 mm) by a few millimetres at the first lead-lag
    frequency of the rotating cantilever (4.51 rad/s, 19 % above the still one) within 1 %."""
    from pinbore.core.cpp.mechanism import spin_up

    model, trajectory = simulated(spin_up_beam(bodies["spinup_beam_2d"], duration=26.0))
    t, deflection = hub_deflection(model, trajectory)
    for when in (2.0, 3.0):
        alpha = spin_up(when, OMEGA_S, T_S)[2]
        quasi_static = -11 * (RHO_A * alpha * L_BEAM) * L_BEAM ** 4 / (120 * EI)
        assert np.interp(when, t, deflection) == pytest.approx(quasi_static, rel=3e-2)
    assert 0.3 < -deflection.min() < 0.7
    mean, amplitude, frequency = after_spin_up(t, deflection)
    assert abs(mean) < 1e-3 and amplitude < 1e-2
    assert frequency == pytest.approx(lead_lag_frequency(OMEGA_S), rel=1e-2)


def test_without_stiffening_the_spin_up_beam_departs(bodies):
    """The same spin-up without the geometric stiffening: the linear model softens where the
    spinning beam stiffens (after the spin-up it vibrates below the still cantilever's 3.8
    rad/s, 25 % and more off the rotating beam's frequency) and bends 15 % and more further
    during the spin-up."""
    model, trajectory = simulated(spin_up_beam(bodies["spinup_beam_2d"], stiffening=False, duration=26.0))
    t, deflection = hub_deflection(model, trajectory)
    _, _, frequency = after_spin_up(t, deflection)
    still = 1.8751 ** 2 * math.sqrt(EI / (RHO_A * L_BEAM ** 4))
    assert frequency < still and frequency < 0.75 * lead_lag_frequency(OMEGA_S)
    assert -deflection.min() > 1.15 * 0.57


@pytest.mark.parametrize("body, message", [
    ({"modes": 7}, "bodies.beam.modes: 7 modes asked"),
    ({"damping_ratio": -0.1}, "damping_ratio"),
    ({"damping_ratio": [0.1, 0.2]}, "one ratio or one a mode"),
    ({"mass": 1.0}, "mass: a flexible body's mass comes from its modes_file"),
    ({"modes_file": None}, "mass: a rigid body needs its mass"),
    ({"modes_file": "nowhere.npz"}, "is not a file"),
])
def test_bad_flexible_bodies_are_one_line(bodies, write_scene, tmp_path, body, message):
    data = pendulum(bodies["pendulum_beam_2d"], **body)
    data["bodies"][0] = {k: v for k, v in data["bodies"][0].items() if v is not None}
    result = pinbore("reduced", write_scene(data), "--out", tmp_path / "out")
    assert result.returncode == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("change, message", [
    (lambda d: d["joints"][0].update(point_j=[0.0, 0.0]), "from its nearest interface 'a'"),
    (lambda d: d["output"]["points"][0].update(position=[0.6, 0.0]), "is not on flexible body 'beam'"),
    (lambda d: d["bodies"][0].update(modes_file="other.npz"), "format"),
])
def test_bad_flexible_attachments_are_one_line(bodies, write_scene, tmp_path, change, message):
    data = pendulum(bodies["pendulum_beam_2d"])
    change(data)
    np.savez(tmp_path / "other.npz", format="something-else", version=1)
    result = pinbore("reduced", write_scene(data), "--out", tmp_path / "out")
    assert result.returncode == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_the_layout_of_a_flexible_row_fits_its_modes():
    """The core's row of a flexible body holds the most modes and interfaces a scene may ask
    for (the scene's bound is the core's), and the layout the core reads its arrays by is
    pinbore.reduced.mechanism.layout's, name by name."""
    from pinbore.core.cpp import mechanism as core
    from pinbore.reduced.mechanism import planar, scene, spatial

    assert scene.FLEXIBLE_MODES == planar.MODES == spatial.MODES == core.MODES
    assert planar.INTERFACES == spatial.INTERFACES == core.INTERFACES
    assert spatial.BODY_COLUMNS == core.BODY_COLUMNS[1]
    assert len(core.LAYOUT) > 100
    assert {name: getattr(layout, name) for name in core.LAYOUT} == core.LAYOUT
    assert layout.TORSION_S_J + 3 == layout.TORSION_COLUMNS
