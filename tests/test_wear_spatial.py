"""The worn journal of a spatial cylindrical clearance joint (`wear_file`): each slice takes
the worn overlap of its own section (cpp/mechanism/engine.h: worn_slice), the profiles the
planar joint's, extruded along the axis. Against independent references:

- a round (zero) profile reproduces the unworn spatial joint: tests/test_wear.py
  (test_a_round_profile_keeps_the_joints_impact, planar and spatial);
- an aligned worn journal is the planar worn joint written in space: the planar worn Flores
  slider-crank and its spatial twin with the same wear.csv move alike (another formulation
  of the same physics, tests/test_planar_as_spatial.py's twins and tolerances);
- a tilted journal in a worn bore, elastic and frictionless, keeps the energy book (in the
  slider-crank, and in a spinning bush);
- a wear_file where it cannot act (a rigid-impact joint, a spherical joint, a sliced law
  with a bulk compliance) is one line.
"""

import copy
import tomllib

import numpy as np
import pytest
import tomli_w
from conftest import ROOT, pinbore
from test_planar_as_spatial import (ANGLE_TOL, FORCE_TOL, LAWS, POSITION_TOL, differences, integrate,
                                    observed, sample_times, twins)

from pinbore.laws import wearfile
from pinbore.reduced.mechanism.layout import LOG_RATE, LOG_TIME


def profiles(folder, bore, pin) -> str:
    """A wear.csv of 720 angles with the bore's and the pin's depth functions of the angle
    (rad) written into folder: its path."""
    theta = np.radians(wearfile.angles(720))
    path = folder / "wear.csv"
    wearfile.write(path, wearfile.Profiles(np.degrees(theta), bore(theta), pin(theta)))
    return str(path)


def smooth_wear(folder) -> str:
    """The smooth worn profiles of tests/test_wear.py: bore 30 um (1 + cos 2 theta), pin
    20 um (1 + sin theta) (the bore worn deepest along the slider's stroke, the pin on one
    side, so the rod's turn matters)."""
    return profiles(folder, lambda t: 30e-6 * (1 + np.cos(2 * t)), lambda t: 20e-6 * (1 + np.sin(t)))


@pytest.mark.parametrize("law", [None, "coulomb_ambrosio"])
def test_an_aligned_worn_journal_is_the_planar_worn_joint(tmp_path, law):
    """The planar worn Flores slider-crank and its spatial twin (the rod's journal along z, 4
    slices) on the same wear.csv (smooth_wear) over the first impact, 4e-4 s at rtol 1e-10:
    the same onset, and at 600 instants the same positions, angles, normal and friction
    forces. The two are one physics in two formulations: the planar RADIAL contact takes the
    section's worn overlap at the frames' angles in the plane, each spatial slice at its
    section in the bore's frame with the pin's angle about the axis (the same numbers, to
    rounding, for an aligned journal: the x axes are the reference directions), a quarter
    of the force each. So tests/test_planar_as_spatial.py's bounds hold (its docstring:
    5e-10 m, 1e-8 rad, 1e-6 of the peaks; onset 1e-8, impact speed 1e-6). The worn
    profiles act: the first impact comes later than the round joint's (the bore is worn
    60 um deep along the stroke) by more than 1 us. The onsets differ as the two models'
    positions do, within POSITION_TOL over the impact speed (1e-10 s; measured 0 to 2.7e-12 s,
    the most with the Iwan element, whose states dilute the error norm's mean). The Iwan element's sliders are returned at the steps' ends, which the two models
    take at different times: its friction within tests/test_planar_as_spatial.py's 1e-2
    (LAWS); its normal force must be the worn joint's (the law's times its reach, as its
    friction's), in the planar return map as in the spatial slices'."""
    friction, mu, friction_tol, *_ = LAWS[law] if law else (None, None, None)
    joint = {"wear_file": smooth_wear(tmp_path)} | ({"friction": friction} if friction else {})
    planar, spatial = (integrate(data) for data in twins(4e-4, joint))
    (_, p_run), (_, s_run) = planar, spatial
    assert p_run.impacts.shape[0] == s_run.impacts.shape[0] == 1
    assert abs(s_run.impacts[0, LOG_TIME] - p_run.impacts[0, LOG_TIME]) <= POSITION_TOL / p_run.impacts[0, LOG_RATE]
    assert s_run.impacts[0, LOG_RATE] == pytest.approx(p_run.impacts[0, LOG_RATE], rel=1e-6)
    round_onset = integrate(twins(4e-4, {})[0])[1].impacts[0, LOG_TIME]
    assert p_run.impacts[0, LOG_TIME] - round_onset > 1e-6
    times = sample_times(p_run, p_run.impacts[0, LOG_TIME])
    positions, angles, normal, tangential, p, _ = differences(planar, spatial, times)
    assert positions < POSITION_TOL, positions
    assert angles < ANGLE_TOL, angles
    assert normal < FORCE_TOL * p[:, -2].max(), normal / p[:, -2].max()
    if friction:   # it slid somewhere: |F_t| at its law's mu times the worn joint's normal force
        in_contact = p[:, -2] > 0
        assert np.any(p[in_contact, -1] >= 0.999 * mu * p[in_contact, -2])
        assert tangential < friction_tol * p[:, -1].max(), tangential / p[:, -1].max()


def test_a_worn_joints_iwan_element_slides_at_mu_times_its_normal_force(tmp_path):
    """The planar worn Flores joint with the bilinear Iwan element without its parallel spring
    (a Jenkins element: k1 = 1e6 N/m, mu = 0.1) over the first impact: its slider caps the
    friction at mu times the joint's normal force, the worn joint's (the law's force times
    its reach, engine.h worn_contact), and reaches the cap where it slides: |F_t| <= mu F_n
    (1 + 1e-9) at every sample in contact, >= 0.999 mu F_n somewhere. The slider's return map
    (integrator.h) takes the same normal force as the friction law."""
    friction, mu, *_ = LAWS["iwan_bilinear"]
    joint = {"wear_file": smooth_wear(tmp_path), "friction": friction}
    planar = integrate(twins(4e-4, joint)[0])
    times = sample_times(planar[1], planar[1].impacts[0, LOG_TIME])
    p, clean = observed(*planar, times)
    f_t, f_n = p[clean, -1], p[clean, -2]
    touching = f_n > 0
    assert touching.sum() > 50
    assert np.all(f_t[touching] <= mu * f_n[touching] * (1 + 1e-9))
    assert np.any(f_t[touching] >= 0.999 * mu * f_n[touching])

def misaligned_slider_crank() -> tuple:
    """The misaligned spatial slider-crank (its bore tilted 1 deg against the journal, 16
    slices: the journal bears on the bore's edges) over one crank turn (12 ms), elastic
    (restitution 1: no damping), frictionless, rtol 1e-8: (its scene, the path its files are
    named from)."""
    path = ROOT / "scenes/reduced/spatial_slider_crank_flores_misaligned.toml"
    data = tomllib.loads(path.read_text())
    data["duration"] = 0.012
    data["integrator"] = {"rtol": 1e-8, "atol": 1e-11}
    data["clearance_joints"][0]["restitution"] = 1.0
    return data, path


def spinning_bush() -> tuple:
    """A free pin (the Flores joint's radii, 20 mm long, 8 slices) in a free bush whose bore
    is tilted 1 deg against it, no gravity, no other joint, both spinning about all three
    axes (the pin at 150 rad/s about its axis, the bush at -40 rad/s), the pin flying across
    the bore: 20 ms, some sixty impacts on the bore's edges, rtol 1e-9 (at 1e-8 the round
    joint's own book is off by 2e-5 here). Its pin turns about axes other than the bore's, as
    the slider-crank's rod does not: the torques' parts off the bore's axis (the pin's turn
    about m) do work."""
    joint = {"name": "bush", "type": "cylindrical", "bearing_body": "bush",
             "bearing_point": [0.0, 0.0, 0.0], "bearing_axis": [0.017452406437284, 0.0, 0.999847695156391],
             "journal_body": "pin", "journal_point": [0.0, 0.0, 0.0], "journal_axis": [0.0, 0.0, 1.0],
             "bearing_radius": 10e-3, "journal_radius": 9.5e-3, "length": 0.02, "slices": 8,
             "E": 207e9, "nu": 0.3, "normal_law": "hertz_point", "start": "placed"}
    bodies = [{"name": "pin", "mass": 0.2, "inertia": [[2e-5, 0, 0], [0, 3e-5, 0], [0, 0, 1e-5]],
               "position": [0.0, 0.0, 0.0], "velocity": [2.0, 0.7, 0.1], "omega": [3.0, -2.0, 150.0]},
              {"name": "bush", "mass": 0.5, "inertia": [[8e-5, 0, 0], [0, 6e-5, 0], [0, 0, 9e-5]],
               "position": [0.0, 0.0, 0.0], "velocity": [-0.8, 0.0, 0.0], "omega": [-4.0, 5.0, -40.0]}]
    return {"kind": "spatial", "duration": 0.02, "gravity": [0.0, 0.0, 0.0], "bodies": bodies,
            "clearance_joints": [joint], "integrator": {"rtol": 1e-9, "atol": 1e-12}}, ROOT / "scene.toml"


@pytest.mark.parametrize("scene", [misaligned_slider_crank, spinning_bush], ids=["slider_crank", "spinning_bush"])
def test_a_tilted_journal_in_a_worn_bore_keeps_the_energy_book(tmp_path, scene):
    """A journal tilted 1 deg in its bore, elastic and frictionless, on the worn profiles of
    smooth_wear: each slice's force along its normal and its torques (the pin's
    about m, the bore's about its axis and u_b - m) are the gradient of the slices' potential
    sum a w_i U(delta_p,i), so kinetic plus potential energy hold as on the round joint: the
    book's residual, its integration error, within twice the round joint's on the same run
    and within 5e-6 of the peak kinetic energy (the planar worn joint's bound,
    tests/test_wear.py)."""
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.run import summarised

    data, path = scene()
    data["output"] = {"plots": False}
    books = []
    for wear in (None, smooth_wear(tmp_path)):
        run = copy.deepcopy(data)
        if wear:
            run["clearance_joints"][0]["wear_file"] = wear
        summary = summarised(kinds.validate(run, str(path)), str(path), path.parent)[3]
        assert summary.status == "complete" and summary.energy_balance.dissipated_J == 0.0
        assert next(iter(summary.clearance_joints.values())).impacts > 10
        books.append(summary.energy_balance.relative_to_peak_kinetic)
    assert books[1] < 2 * books[0] and books[1] < 5e-6, books


BAD = [
    ("spatial_slider_crank_flores.toml",
     lambda j: j.update(impact="newton", restitution=0.5) or [j.pop(k) for k in ("normal_law", "damping_law")],
     "wear_file: a worn joint's contact is continuous"),
    ("spatial_four_bar_spherical.toml", lambda j: None,
     "wear_file: a spherical joint takes no worn profile"),
]


@pytest.mark.parametrize("scene, change, message", BAD, ids=["rigid", "spherical"])
def test_a_wear_file_where_it_cannot_act_is_one_line(tmp_path, scene, change, message):
    """`pinbore reduced` on a spatial joint with a wear_file it cannot take: exit 2, one line
    naming the key and the rule, no output."""
    data = tomllib.loads((ROOT / "scenes/reduced" / scene).read_text())
    data["duration"] = 1e-3
    joint = data["clearance_joints"][0]
    change(joint)
    joint["wear_file"] = smooth_wear(tmp_path)
    (tmp_path / "scene.toml").write_text(tomli_w.dumps(data))
    done = pinbore("reduced", tmp_path / "scene.toml", "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_worn_journal_refuses_a_bulk_compliance(tmp_path):
    """A sliced law with a bulk compliance (the law of
    tests/test_spatial_clearance.py's planar-spatial comparison) on a worn spatial journal:
    one InputError line naming the joint, wear_file and the law (the bore's displacement
    under its compliance is solved from the round slices' forces and stiffness; the worn
    slices have no such stiffness)."""
    import test_calibration
    import test_calibration_3d

    from pinbore.calibration import sliced as calibration
    from pinbore.calibration.run import evaluate, laws_json
    from pinbore.core.errors import InputError
    from pinbore.laws import lawsfile
    from pinbore.reduced.mechanism import kinds
    from pinbore.reduced.mechanism.model import build

    laws = calibration.calibrate([test_calibration_3d.synthetic("short", 0.01, 0.9, 1.5e-3, 0.4),
                                  test_calibration_3d.synthetic("long", 0.02, 0.9, 1.5e-3, 0.4)],
                                 test_calibration_3d.LIU)
    flat = [test_calibration.synthetic("liu", 1.0, 0.0)]
    lawsfile.write(tmp_path / "laws.json", laws_json(flat, evaluate(flat), None, [], 0.0)
                   .model_copy(update={"sliced": laws}))
    joint = test_calibration_3d.JOINT
    data = copy.deepcopy(twins(4e-4, {})[1])
    data["laws_file"] = str(tmp_path / "laws.json")
    data["clearance_joints"][0] |= {"bearing_radius": joint.r_bore, "journal_radius": joint.r_pin,
                                    "normal_law": "sliced:flush_steel", "wear_file": smooth_wear(tmp_path)}
    with pytest.raises(InputError, match="rod_slider: wear_file: a worn journal's bore takes no "
                                         "bulk compliance") as error:
        build(kinds.validate(data, "test"), "test", ROOT)
    assert "sliced:flush_steel" in str(error.value) and "\n" not in str(error.value)
