"""The spatial multibody model against independent references: the planar model (a planar
mechanism written as a spatial one), Euler's equations of a free body (momenta, torque-free
spin, the intermediate-axis flip with its elliptic-integral period), the sliced law's slice
sum; bad spatial scenes."""

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT, pinbore
from scipy.special import ellipk

from pinbore.laws import sliced
from pinbore.laws.tables import tabulate
from pinbore.core.cpp import mechanism as core
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.layout import (
    CONTACT_BEARING_AXIS, CONTACT_BEARING_BODY, CONTACT_CLEARANCE, CONTACT_COLUMNS,
    CONTACT_COMPLIANCE, CONTACT_END_LENGTH, CONTACT_JOURNAL_AXIS, CONTACT_JOURNAL_BODY,
    CONTACT_KIND, CONTACT_LENGTH, CONTACT_RADIUS, CONTACT_SCALE, CONTACT_SLICES, CONTACT_STATE,
    SLICED, row)
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import rotation_matrix
from pinbore.reduced.mechanism.spatial import BODY_COLUMNS, BODY_JINV, BODY_POS, BODY_ROT

SCENES = ROOT / "scenes" / "reduced"
PLANAR = tomllib.loads((SCENES / "slider_crank_flores2004.toml").read_text())
SPATIAL = tomllib.loads((SCENES / "spatial_slider_crank_flores.toml").read_text())


def run(data):
    """Build a scene of either kind (its `kind` key) and integrate it."""
    model = build(kinds.validate(data, "test"), "test", ROOT)
    trajectory = simulate(model)
    assert trajectory.status == 0, (trajectory.status, trajectory.t_end)
    return model, trajectory


def first_impact(data):
    """Time and speed of the first onset, and the largest force before the contact opens."""
    model, trajectory = run(data)
    cols = per_step(model, trajectory)[0]
    force = cols["rod_slider_normal_force_N"]
    first = np.flatnonzero(force > 0)[0]
    end = first + np.argmax(force[first:] == 0)
    return trajectory.impacts[0], float(force[first:end].max()), cols, first


def test_planar_scene_as_spatial_reproduces_the_planar_model():
    """The Flores slider-crank in the x-y plane: free flight, the first onset (located by both
    to the same tolerance) and the first impact's peak. Before the impact the motion is the
    ideal kinematics integrated at rtol 1e-10 by both (same equations, different coordinates):
    the slider's position agrees to 1e-8 of the crank length. The first impact's peak force is
    read at the accepted steps, at most 20 ns apart: for a contact of about 50 us (a half sine
    of frequency w = pi / 50 us) the sampled maximum is within (w h)^2 / 8 = 2e-7 of the true
    one, so the two peaks agree to 1e-6 when the dynamics do."""
    planar, spatial = copy.deepcopy(PLANAR), copy.deepcopy(SPATIAL)
    for data in (planar, spatial):
        data["duration"] = 4e-4   # past the first impact (its peak at 0.25 ms)
        data["integrator"] = {"rtol": 1e-10, "atol": 1e-13, "max_step": 2e-8}
    (p_log, p_peak, p_cols, p_first) = first_impact(planar)
    (s_log, s_peak, s_cols, s_first) = first_impact(spatial)
    assert s_log[0] == pytest.approx(p_log[0], rel=1e-8)    # onset time
    assert s_log[2] == pytest.approx(p_log[2], rel=1e-6)    # impact speed
    t = np.linspace(0, p_log[0], 50)
    x_planar = np.interp(t, p_cols["time_s"], p_cols["slider_x_m"])
    x_spatial = np.interp(t, s_cols["time_s"], s_cols["slider_x_m"])
    assert np.max(np.abs(x_spatial - x_planar)) < 1e-8 * 0.05
    assert s_peak == pytest.approx(p_peak, rel=1e-6)


def free_body(omega, inertia=((1.0, 0, 0), (0, 2.0, 0), (0, 0, 3.0)), duration=1.0, rtol=1e-10):
    return {"kind": "spatial", "duration": duration, "bodies": [{
        "name": "body", "mass": 2.0, "inertia": [list(r) for r in inertia],
        "velocity": [0.3, -0.2, 0.1], "omega": list(omega)}],
        "integrator": {"rtol": rtol, "atol": 1e-13, "max_step": 1e-2},
        "output": {"sample_time": 1e-3, "plots": False}}


def angular_momentum(cols, model):
    """Global angular momentum about the centre of mass, A J' A^T w, per step."""
    out = []
    for k in range(cols["time_s"].size):
        p = [cols[f"body_e{i}_1"][k] for i in range(4)]
        a = np.empty((3, 3))
        a[:] = rotation_matrix(np.array(p))
        w = np.array([cols[f"body_w{c}_rad_per_s"][k] for c in "xyz"])
        out.append(a @ model.base.inertia[0] @ a.T @ w)
    return np.array(out)


def test_free_body_conserves_momenta_and_energy():
    """Torque-free tumbling: linear momentum exactly (no force), angular momentum fixed in
    space and kinetic energy constant (Euler's equations), to 1e-8 of their size at rtol 1e-10
    (the error of a few thousand steps at that tolerance)."""
    model, trajectory = run(free_body([0.5, 2.0, 0.3]))
    cols, energy, _ = per_step(model, trajectory)
    momentum = angular_momentum(cols, model)
    assert np.max(np.abs(momentum - momentum[0])) < 1e-8 * np.linalg.norm(momentum[0])
    assert np.ptp(energy["kinetic"]) < 1e-8 * energy["kinetic"][0]
    np.testing.assert_allclose(cols["body_vx_m_per_s"], 0.3, rtol=1e-12)
    np.testing.assert_allclose(cols["body_x_m"], 0.3 * cols["time_s"], atol=1e-12)


def test_spin_about_a_principal_axis_keeps_angular_momentum_fixed_in_space():
    """A body spinning about its major axis with a small wobble: H stays fixed to 1e-9."""
    model, trajectory = run(free_body([1e-3, 2e-3, 5.0]))
    momentum = angular_momentum(per_step(model, trajectory)[0], model)
    assert np.max(np.abs(momentum - momentum[0])) < 1e-9 * np.linalg.norm(momentum[0])


def test_intermediate_axis_flip_has_the_closed_form_period():
    """Tennis-racket theorem: spin about the intermediate axis (J2) with a small perturbation
    w1(0): the body flips periodically. Near the separatrix Euler's equations give the period
    T = 4 K(k) / sqrt((J2 - J1)(J3 - J2) ... ) in Jacobi elliptic functions; for w1(0) = eps,
    w3(0) = 0, the exact solution is w2 = w0 dn-type with period (Landau-Lifshitz sec. 37)
        T = 4 K(m) / p,  p = sqrt((J3 - J2)(J2 - J1) / (J1 J3)) w0-scaled, m from the energy.
    The period of w2 (two flips) from the zero crossings of w2 agrees to 1e-5."""
    j1, j2, j3 = 1.0, 2.0, 3.0
    w0, eps = 2.0, 1e-3
    h2 = (j2 * w0) ** 2 + (j1 * eps) ** 2          # |H|^2
    e2 = j2 * w0**2 + j1 * eps**2                   # 2 T
    # Landau-Lifshitz sec. 37 (J3 > J2 > J1, M^2 < 2 E J2 here: m < 1 with their ordering)
    if h2 > e2 * j2:
        raise AssertionError("case not covered")
    tau_scale = math.sqrt((j3 - j2) * (e2 * j1 - h2) * 0 + (j2 - j1) * (j3 * e2 - h2) / (j1 * j2 * j3))
    m = (j3 - j2) * (h2 - e2 * j1) / ((j2 - j1) * (j3 * e2 - h2))
    period_w2 = 4 * ellipk(m) / tau_scale
    model, trajectory = run(free_body([eps, w0, 0.0], ((j1, 0, 0), (0, j2, 0), (0, 0, j3)),
                                      duration=1.2 * period_w2, rtol=1e-11))
    cols = per_step(model, trajectory)[0]
    t, w = cols["time_s"], cols["body_wy_rad_per_s"]
    body_w2 = []
    for k in range(t.size):   # the body-frame component about the intermediate axis
        a = np.empty((3, 3))
        a[:] = rotation_matrix(np.array([cols[f"body_e{i}_1"][k] for i in range(4)]))
        body_w2.append((a.T @ np.array([cols[f"body_w{c}_rad_per_s"][k] for c in "xyz"]))[1])
    body_w2 = np.array(body_w2)
    crossings = t[:-1][np.diff(np.sign(body_w2)) != 0]
    assert crossings.size >= 2, crossings
    assert crossings[1] - crossings[0] == pytest.approx(period_w2 / 2, rel=1e-5)
    assert w.size > 0


def cylinder(length=0.02, slices=16, end_length=0.0, scale=1.0, compliance=0.0):
    """The contact row (reduced.mechanism.layout.CONTACT_*) of a journal along its bore
    (SLICED): the bore on the ground along z through the origin, the journal body 0 with its
    axis along its z through its centre, table 0, no friction, no damping."""
    return np.array([row(CONTACT_COLUMNS, {
        CONTACT_KIND: SLICED, CONTACT_BEARING_BODY: -1, CONTACT_JOURNAL_BODY: 0,
        CONTACT_BEARING_AXIS: (0.0, 0.0, 1.0), CONTACT_JOURNAL_AXIS: (0.0, 0.0, 1.0),
        CONTACT_LENGTH: length, CONTACT_SLICES: slices, CONTACT_END_LENGTH: end_length,
        CONTACT_SCALE: scale, CONTACT_COMPLIANCE: compliance, CONTACT_STATE: -1,
        CONTACT_CLEARANCE: 1e-4, CONTACT_RADIUS: 0.01})])


def journal(position, parameters):
    """The body rows (reduced.mechanism.spatial.BODY_*) of one journal at rest: its centre and
    Euler parameters (unit inverse inertia)."""
    bodies = np.zeros((1, BODY_COLUMNS))
    rot = np.empty((3, 3))
    rot[:] = rotation_matrix(np.asarray(parameters, float))
    bodies[0, BODY_POS:BODY_POS + 3] = position
    bodies[0, BODY_ROT:BODY_ROT + 9] = rot.ravel()
    bodies[0, BODY_JINV:BODY_JINV + 9] = np.eye(3).ravel()
    return bodies


def tilted_journal_forces(contacts, table, delta, theta):
    """Forces and torques (6) on a journal whose centre sits c + delta off the bore's axis
    along x and whose axis is tilted by theta about y (leaning towards +x for z > 0), with
    the radial normal force the engine's slice sum returns."""
    bodies = journal([contacts[0, CONTACT_CLEARANCE] + delta, 0, 0],
                     [math.cos(theta / 2), 0, math.sin(theta / 2), 0])
    force, f_n, _, _ = core.sliced_forces(bodies, contacts, np.array([0, 6]), np.ones(1),
                                          table[2][None, :], table[0], table[1], 0)
    return force, f_n


@pytest.mark.parametrize("end_length,scale,compliance", [
    (0.0, 1.0, 0.0), (1.5e-3, 0.8, 0.0), (-1e-3, 1.2, 0.0), (0.0, 1.0, 2e-11), (1e-3, 0.9, 1e-11)])
def test_slice_sum_equals_the_sliced_law(end_length, scale, compliance):
    """A journal tilted by theta in the plane of its eccentricity (about y, eccentricity
    along x): the kernel's slice sum of the force and of its moment about the bore's centre
    equal laws.sliced.sliced(delta, sin theta, ..., scale, compliance) to round-off (1e-12;
    with a bulk compliance both solve for the bore's displacement to 1e-12 of its scale, the
    kernel by the 2D Newton across the section, the law along the load): the same slices,
    weights and law (the core's Engine::sliced_forces)."""
    grid_log0, grid_step, table = tabulate(lambda d: 3e10 * d**1.1, 1e-12, 1e-3, 400)
    contacts = cylinder(end_length=end_length, scale=scale, compliance=compliance)
    delta, theta = 2e-6, 1.5e-4
    force, f_n = tilted_journal_forces(contacts, (grid_log0, grid_step, table), delta, theta)
    expected = sliced.sliced(delta, math.sin(theta), 0.02, 16, grid_log0, grid_step, table, 0.0,
                             0.0, end_length, scale, compliance)
    assert -force[0] == pytest.approx(expected[0], rel=1e-12)
    assert f_n == pytest.approx(expected[0], rel=1e-12)
    assert abs(force[1]) < 1e-12 * expected[0]
    # the moment on the journal about its centre: the slice forces act at X_i = z_i u_j, whose
    # arm across the force is z_i cos theta (the law's z_i measured along the tilted axis)
    assert -force[4] == pytest.approx(expected[1] * math.cos(theta), rel=1e-12)


@pytest.mark.parametrize("change,key", [
    (lambda d: d["bodies"][0].update(orientation=[1.0, 0.1, 0.0, 0.0]), "bodies.0"),
    (lambda d: d["bodies"][0].update(rotation=[[1, 0, 0], [0, 1, 0], [0, 0, -1]]), "bodies.0"),
    (lambda d: d["bodies"][0].update(inertia=[[1, 0, 0], [0, 1, 0], [0, 0, 3]]), "bodies.0"),
    (lambda d: d["bodies"][0].update(inertia=[[1, 0, 0], [0, -1, 0], [0, 0, 1]]), "bodies.0"),
    (lambda d: d["joints"][0].update(axis_i=[0, 0, 0]), "joints.0"),
    (lambda d: d["clearance_joints"][0].update(journal_radius=0.011), "clearance_joints.0"),
    (lambda d: d["drive"].update(joint="nowhere"), "(scene)"),
    (lambda d: d["joints"][1].update(body_i="nobody"), "(scene)"),
])
def test_bad_spatial_scenes_are_one_line_exit_2(write_scene, tmp_path, change, key):
    data = copy.deepcopy(SPATIAL)
    change(data)
    out = tmp_path / "out"
    result = pinbore("reduced", write_scene(data), "--out", out)
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and key in result.stderr, result.stderr
    assert not out.exists()
