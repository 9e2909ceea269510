"""The spatial model's cylindrical clearance joint against independent references: the bore's
shared bulk compliance (closed forms of a linear law; the root of the section's equations
found by scipy on a numpy model of the slices; the planar model's sliced law), a journal that
settles under a steady moment at the tilt laws.sliced.sliced gives, one pushed axially that
settles on its shoulder, and the two adaptive integrators on one spatial scene."""

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT
from scipy.optimize import fsolve, root

from pinbore.laws import elastic, sliced, tables
from pinbore.core.cpp import mechanism as core
from pinbore.reduced.mechanism import kernel, kinds
from pinbore.reduced.mechanism.layout import (
    CONTACT_BEARING_AXIS, CONTACT_BEARING_BODY, CONTACT_CLEARANCE, CONTACT_COLUMNS,
    CONTACT_COMPLIANCE, CONTACT_JOURNAL_AXIS, CONTACT_JOURNAL_BODY, CONTACT_KIND, CONTACT_LENGTH,
    CONTACT_RADIUS, CONTACT_SCALE, CONTACT_SLICES, CONTACT_STATE, SLICED, row)
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import rotation_matrix
from pinbore.reduced.mechanism.spatial import BODY_COLUMNS, BODY_JINV, BODY_POS, BODY_ROT

K = 4e10            # N/m^2, the linear per-length law f = K delta
L = 0.02            # m, bore length
CLEARANCE = 1e-4    # m


def cylinder(slices, compliance):
    """A journal along its bore (a SLICED contact row, reduced.mechanism.layout.CONTACT_*):
    the bore on the ground along z through the origin, the journal body 0 with its axis along
    its z through its centre, table 0, no friction, no damping."""
    return np.array([row(CONTACT_COLUMNS, {
        CONTACT_KIND: SLICED, CONTACT_BEARING_BODY: -1, CONTACT_JOURNAL_BODY: 0,
        CONTACT_BEARING_AXIS: (0.0, 0.0, 1.0), CONTACT_JOURNAL_AXIS: (0.0, 0.0, 1.0),
        CONTACT_LENGTH: L, CONTACT_SLICES: slices, CONTACT_SCALE: 1.0,
        CONTACT_COMPLIANCE: compliance, CONTACT_STATE: -1, CONTACT_CLEARANCE: CLEARANCE,
        CONTACT_RADIUS: 0.01})])


def journal_forces(contacts, table, centre, axis_angle, axis_direction):
    """Force and torque about its centre (6) on a journal at rest with its centre at `centre`
    and its axis turned by `axis_angle` from z towards `axis_direction` (a unit vector normal
    to z): the engine's slice sum (the core's Engine::sliced_forces)."""
    turn = np.cross([0, 0, 1], axis_direction)
    parameters = [math.cos(axis_angle / 2), *(math.sin(axis_angle / 2) * turn)]
    bodies = np.zeros((1, BODY_COLUMNS))
    rot = np.empty((3, 3))
    rot[:] = rotation_matrix(np.array(parameters))
    bodies[0, BODY_POS:BODY_POS + 3] = centre
    bodies[0, BODY_ROT:BODY_ROT + 9] = rot.ravel()
    bodies[0, BODY_JINV:BODY_JINV + 9] = np.eye(3).ravel()
    return core.sliced_forces(bodies, contacts, np.array([0, 6]), np.ones(1), table[2][None, :],
                              table[0], table[1], 0)[0]


@pytest.mark.parametrize("slices", [1, 8, 64])
def test_linear_law_with_bulk_compliance_gives_the_closed_forms(slices):
    """Linear law f = K delta, bulk compliance c = 0.5 / K, journal in full contact off centre
    along a direction 30 deg from x and tilted in the plane of that direction and the axis.
    The slices carry K_loc = K / (1 - c K); the uniform part of the approach carries
    F = K delta L (the section law's: the long-pin limit), the tilt acts on the local springs
    alone: M = K_loc t L^3/12 (1 - 1/n^2) (midpoint sums of z^2), 1/(1 - c K) times what
    independent slices of the section law give. t = sin(tilt) (the lean per metre across the
    bore), the moment about the journal's centre has the arm z_i cos(tilt) (laws along the
    journal's axis). Reference: these closed forms; tolerance the bore displacement's Newton
    tolerance (1e-12) and the round-off of the split table (1e-9)."""
    c = 0.5 / K
    local = tables.split_compliance(*tables.tabulate(lambda d: K * d, 1e-12, 1e-3, 200), c)
    delta, tilt = 4e-6, 2e-4                     # delta > t L/2 = 2e-6: full contact
    direction = np.array([math.cos(math.pi / 6), math.sin(math.pi / 6), 0.0])
    force = journal_forces(cylinder(slices, c), local, (CLEARANCE + delta) * direction, tilt,
                           direction)
    k_loc = K / (1 - c * K)
    t = math.sin(tilt)
    np.testing.assert_allclose(-force[:3], K * delta * L * direction, rtol=1e-9, atol=1e-9)
    across = np.cross([0, 0, 1], direction)      # the tilt's moment is about this axis
    moment = -(force[3:] @ across) / math.cos(tilt)
    expected = k_loc * t * L**3 / 12 * (1 - 1 / slices**2)
    assert moment == pytest.approx(expected, rel=1e-9, abs=1e-12)
    plain = journal_forces(cylinder(slices, 0.0), tables.tabulate(lambda d: K * d, 1e-12, 1e-3, 200),
                           (CLEARANCE + delta) * direction, tilt, direction)
    assert moment == pytest.approx(-(plain[3:] @ across) / math.cos(tilt) / (1 - c * K),
                                   rel=1e-9, abs=1e-12)


def test_bore_displacement_across_the_section_is_the_root_of_its_equations():
    """The journal's centre off the bore's axis along (c + delta, 30 um) and its axis leaning
    along y (tilt about x): the slices' normals turn along the pin, so the bore's displacement
    leaves the line of the mid-plane eccentricity. Reference: a numpy model of the slices
    (delta_i = |P_i - d| - c, f_i = K_loc delta_i, F = sum f_i w n_i) whose equation
    d = c_b F(d) / L scipy's root (hybr) solves from d = 0; the kernel's force on the journal
    is -F at that d. Tolerance: root's tolerance 1e-13 on d (the force changes by K L |d|
    1e-13)."""
    c_b, slices = 0.3 / K, 16
    local = tables.split_compliance(*tables.tabulate(lambda d: K * d, 1e-12, 1e-3, 200), c_b)
    k_loc = K / (1 - c_b * K)
    delta, tilt, side = 3e-6, 8e-4, 3e-5       # the lean 8e-4 x 1e-2 m = 8 um at each end
    centre = np.array([CLEARANCE + delta, side, 0.0])
    force = journal_forces(cylinder(slices, c_b), local, centre, tilt, np.array([0.0, 1.0, 0.0]))
    z = (np.arange(slices) + 0.5) * L / slices - L / 2
    points = np.stack([np.full(slices, centre[0]), side + z * math.sin(tilt)], axis=1)

    def resultant(d):
        across = points - d
        size = np.linalg.norm(across, axis=1)
        f = k_loc * np.maximum(size - CLEARANCE, 0.0) * L / slices
        return (f[:, None] * across / size[:, None]).sum(axis=0)

    solution = root(lambda d: d - c_b * resultant(d) / L, np.zeros(2), tol=1e-13)
    assert solution.success
    moved = solution.x
    off_line = abs(moved[0] * centre[1] - moved[1] * centre[0]) / np.linalg.norm(centre[:2])
    assert off_line > 1e-3 * np.linalg.norm(moved)      # not along the mid-plane eccentricity
    expected = resultant(moved)
    np.testing.assert_allclose(-force[:2], expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())


# ---- dynamic settling: a journal in a fixed bore under steady loads
def settling_scene(gravity, offset, inertia_xy, slices=16, shoulders=False, duration=0.4):
    """One journal (1 kg) in a bore on the ground (axis z, 20 mm, clearance 20 um, Liu's law
    for steel, Hunt-Crossley damping of Flores et al. with e = 0.3), its centre of mass
    `offset` metres along its axis from the point that sits at the bore's centre, under
    `gravity`; optional shoulders 50 um from the bore's faces, 1e7 N/m."""
    joint = {"name": "pin", "type": "cylindrical", "bearing_body": "ground",
             "bearing_point": [0.0, 0.0, 0.0], "bearing_axis": [0.0, 0.0, 1.0],
             "journal_body": "journal", "journal_point": [0.0, 0.0, -offset],
             "journal_axis": [0.0, 0.0, 1.0], "bearing_radius": 10e-3,
             "journal_radius": 10e-3 - 20e-6, "length": L, "slices": slices, "E": 207e9,
             "nu": 0.3, "normal_law": "liu", "damping_law": "flores", "restitution": 0.3,
             "start": "free"}
    if shoulders:
        joint |= {"axial_clearance": 5e-5, "axial_stiffness": 1e7}
    return {"kind": "spatial", "duration": duration, "gravity": list(gravity),
            "bodies": [{"name": "journal", "mass": 1.0,
                        "inertia": [[inertia_xy, 0, 0], [0, inertia_xy, 0], [0, 0, 5e-5]],
                        "position": [0.0, 0.0, offset]}],
            "clearance_joints": [joint],
            "integrator": {"rtol": 1e-6, "atol": 1e-12},
            "output": {"plots": False}}


def final_pose(data):
    """The journal's mid-plane eccentricity beyond the clearance (m), its tilt (sin of the
    angle between the axes) and axial offset (m) at the end, and its largest speed over the
    last tenth of the run."""
    model = build(kinds.validate(data, "test"), "test", ROOT)
    run = simulate(model)
    assert run.status == 0, run.status
    y = run.states[-1]
    args = model.args()
    work = kernel.workspace(args)
    pj, _, _, a0, a1 = core.bore_section(y, args, work, model.contact_rows[0][0])
    cols = per_step(model, run)[0]
    late = cols["time_s"] > 0.9 * cols["time_s"][-1]
    speed = np.max(np.abs(np.stack([cols[f"journal_v{c}_m_per_s"][late] for c in "xyz"])))
    clearance = model.joints[0].gap()
    return np.linalg.norm(a0) - clearance, np.linalg.norm(a1), pj[2], speed, model


def test_tilted_journal_settles_at_the_tilt_of_the_sliced_law():
    """Gravity (9.81 m/s^2 across the bore) on a journal whose centre of mass sits 6 mm along
    its axis from the bore's mid-plane: the joint carries F = m g and the moment m g 6 mm
    about the mid-plane (the resultant 6 mm off centre, beyond the middle sixth: one end
    lifts, edge contact). Reference: laws.sliced.sliced with Liu's per-length law (tabulated
    anew here), 16 slices, solved by scipy's fsolve for the approach and tilt that give that
    F and M: the statics of the law, independent of the dynamic kernel. The run settles (its
    speed falls below 1e-7 m/s; measured 1e-16) at that approach and tilt within 1e-5: the
    model's table of the law (600 points over nine decades of approach) and the reference's
    (800 points) interpolate log-log, each about 1e-6 off between its points (measured:
    1e-8 in the approach, 2e-7 in the tilt)."""
    offset, g = 6e-3, 9.81
    delta, tilt, pin_z, speed, model = final_pose(settling_scene([0, -g, 0], offset, 2e-4))
    assert speed < 1e-7
    c = model.scene.clearance_joints[0]
    joint = elastic.Joint(c.bearing_radius, c.journal_radius, c.E, c.nu, c.E, c.nu, c.length)
    table = tables.tabulate(lambda d: elastic.PUBLISHED["liu"](d, joint), 1e-12, 1e-3, 800)

    def residual(x):
        force, moment, _, _ = sliced.sliced(x[0] * 1e-7, x[1] * 1e-5, L, 16, *table, 0.0, 0.0,
                                            0.0, 1.0, 0.0)
        return [force / g - 1.0, moment / (g * offset) - 1.0]

    scaled = fsolve(residual, [1.0, 1.0], xtol=1e-13)
    assert np.max(np.abs(residual(scaled))) < 1e-10
    expected_delta, expected_tilt = scaled[0] * 1e-7, scaled[1] * 1e-5
    assert expected_delta < expected_tilt * L / 2          # edge contact: an end lifts
    assert delta == pytest.approx(expected_delta, rel=1e-5)
    assert tilt == pytest.approx(expected_tilt, rel=1e-5)


def test_journal_pushed_axially_settles_on_its_shoulder():
    """Gravity along the bore's axis (-z): the journal slides until it rests on the shoulder,
    whose penalty k_a (|s| - c_a) then carries m g: s = -(c_a + m g / k_a). Radially nothing
    loads it, so it stays centred. Reference: that closed form (the penalty is linear: no
    table), to 1e-9 of the penetration (measured 6e-14)."""
    g, k_a, c_a = 9.81, 1e7, 5e-5
    delta, tilt, pin_z, speed, _ = final_pose(settling_scene([0, 0, -g], 0.0, 2e-4,
                                                             shoulders=True, duration=0.3))
    assert speed < 1e-7
    assert -pin_z - c_a == pytest.approx(g / k_a, rel=1e-9)
    assert delta < 0 and tilt < 1e-12


def first_impact(data):
    model = build(kinds.validate(data, "test"), "test", ROOT)
    run = simulate(model)
    assert run.status == 0
    force = per_step(model, run)[0]["rod_slider_normal_force_N"]
    first = np.flatnonzero(force > 0)[0]
    end = first + np.argmax(force[first:] == 0)
    return run.impacts[0][0], float(force[first:end].max()), run


def test_dopri5_and_rosenbrock_agree_on_the_spatial_slider_crank():
    """The spatial Flores slider-crank to past its first impact, by DOPRI5 at rtol 1e-10 with
    steps of at most 50 ns and by the linearly implicit Rosenbrock 2(3) (the shared
    integrators, through the spatial kernel's hooks) at rtol 1e-6 with steps of at most
    0.2 us: the onset time agrees to 1e-6 (both locate it to the onset tolerance) and the peak
    force, read at the accepted steps, to 1e-4: for a contact of about 50 us (a half sine of
    w = pi / 50 us) a sample h from the peak is (w h)^2 / 8 below it, 2e-5 at 0.2 us, with
    Rosenbrock's error at rtol 1e-6 besides (measured: 4e-7 in onset, 1e-5 in peak)."""
    data = tomllib.loads((ROOT / "scenes" / "reduced" / "spatial_slider_crank_flores.toml").read_text())
    data["duration"] = 3.5e-4
    explicit, implicit = copy.deepcopy(data), copy.deepcopy(data)
    explicit["integrator"] = {"method": "dopri5", "rtol": 1e-10, "atol": 1e-13, "max_step": 5e-8}
    implicit["integrator"] = {"method": "rosenbrock23", "rtol": 1e-6, "atol": 1e-9, "max_step": 2e-7}
    t_explicit, peak_explicit, _ = first_impact(explicit)
    t_implicit, peak_implicit, _ = first_impact(implicit)
    assert t_implicit == pytest.approx(t_explicit, rel=1e-6)
    assert peak_implicit == pytest.approx(peak_explicit, rel=1e-4)


def test_planar_and_spatial_models_agree_on_a_sliced_law_with_bulk_compliance(tmp_path):
    """A 3D law with a bulk compliance (fitted on synthetic curves made with c_b = 0.4 of what
    Liu's law can give up, as tests/test_calibration_3d.py does) in the Flores slider-crank,
    planar (`sliced:<group>`: the straight-pin force tabulated from laws.sliced.sliced) and
    spatial (the slices and the bore's displacement solved in the kernel at every
    evaluation): an aligned journal gives both the same force, so free flight, the first
    onset and the first impact agree. Onset to 1e-8 as the planar-spatial test of
    tests/test_spatial.py; peak to 1e-5: the two tables of the law differ by their log-log
    interpolation (the planar one tabulates F, the spatial one the local law f_loc resampled
    on the model's grid), about 1e-6 each."""
    import test_calibration
    import test_calibration_3d
    from pinbore.laws import lawsfile
    from pinbore.calibration import sliced as calibration
    from pinbore.calibration.run import evaluate, laws_json

    laws = calibration.calibrate([test_calibration_3d.synthetic("short", 0.01, 0.9, 1.5e-3, 0.4),
                                  test_calibration_3d.synthetic("long", 0.02, 0.9, 1.5e-3, 0.4)],
                                 test_calibration_3d.LIU)
    assert laws["flush_steel"].bulk_compliance_m2_per_N > 0
    flat = [test_calibration.synthetic("liu", 1.0, 0.0)]
    lawsfile.write(tmp_path / "laws.json", laws_json(flat, evaluate(flat), None, [], 0.0)
                   .model_copy(update={"sliced": laws}))
    joint = test_calibration_3d.JOINT
    common = {"bearing_radius": joint.r_bore, "journal_radius": joint.r_pin, "length": 0.02,
              "normal_law": "sliced:flush_steel"}
    results = []
    for name in ("slider_crank_flores2004", "spatial_slider_crank_flores"):
        data = tomllib.loads((ROOT / "scenes" / "reduced" / f"{name}.toml").read_text())
        data["laws_file"] = str(tmp_path / "laws.json")
        data["clearance_joints"][0] |= common
        data["duration"] = 4e-4
        data["integrator"] = {"rtol": 1e-10, "atol": 1e-13, "max_step": 2e-8}
        model = build(kinds.validate(data, "test"), "test", ROOT)   # kind from the scene
        run = simulate(model)
        assert run.status == 0
        force = per_step(model, run)[0]["rod_slider_normal_force_N"]
        first = np.flatnonzero(force > 0)[0]
        end = first + np.argmax(force[first:] == 0)
        results.append((run.impacts[0][0], float(force[first:end].max())))
    (t_planar, peak_planar), (t_spatial, peak_spatial) = results
    assert t_spatial == pytest.approx(t_planar, rel=1e-8)
    assert peak_spatial == pytest.approx(peak_planar, rel=1e-5)
