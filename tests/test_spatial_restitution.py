"""The calibrated restitution (damping_law = "calibrated") in the spatial model's cylindrical
clearance joint: one impact rebounds with the laws file's e(v0) at its impact speed, the same
joint written as a planar scene gives the planar model's impact, and a joint without its law
(or without a laws file, or a ball in a socket) is one line.

The law here is written by hand into laws.json (no FE impacts run): the reference is the
polynomial e(v0) itself (laws.dissipative.restitution_of_speed), which the model must
reproduce through the Hunt-Crossley factor chi(e) (laws.dissipative.hysteresis_for_restitution,
exact for one degree of freedom and any elastic law; tests/test_restitution.py checks it by
integration). An aligned journal thrown radially through its centre against a fixed bore is
one degree of freedom: every slice has the same approach and rate, so the slices' sum is
F_el (1 + chi delta'/v0) with F_el the per-length law times L."""

import math

import numpy as np
import pytest
from conftest import ROOT, pinbore

from pinbore.core.errors import InputError
from pinbore.laws import lawsfile
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step, sample, summary
from pinbore.reduced.mechanism.run import simulate

R_PIN, R_BORE, LENGTH = 9.99e-3, 10e-3, 0.02        # m: the FE study's joint, a 20 mm lug
MASS = 7850 * math.pi * R_PIN**2 * LENGTH          # kg: the steel pin over the lug
COEFFICIENTS = [0.6019, -0.0799, -0.0024]          # e(v0) of the shipped steel/steel study
SPEEDS = [0.1, 3.0]                                # m/s, the law's range


def law_file(folder, bore_E=210e9):
    """laws.json holding one restitution law, of the steel pin in a bore of modulus bore_E."""
    joint = lawsfile.ImpactJoint(pin_E_Pa=210e9, pin_nu=0.3, pin_density_kg_per_m3=7850.0,
                                 bore_E_Pa=bore_E, bore_nu=0.3, bore_density_kg_per_m3=7850.0,
                                 pin_radius_m=R_PIN, bore_radius_m=R_BORE,
                                 pin_mass_kg_per_m=7850 * math.pi * R_PIN**2)
    law = lawsfile.RestitutionLaw(model=lawsfile.RESTITUTION_MODEL, joint=joint,
                                  coefficients=COEFFICIENTS, speed_range_m_per_s=SPEEDS,
                                  max_fit_error=0.0, impacts=[])
    path = folder / "laws.json"
    lawsfile.write(path, lawsfile.LawsFile(
        units=lawsfile.UNITS, length_m=None, length_note="", curves=[], laws={}, sliced={},
        warnings=[], fit_seconds=0.0, restitution={joint.key(): law}))
    return path, law


def spatial_impact(laws_path, speed, duration, slices=4, **joint):
    """A journal (the pin's mass over the lug) thrown along -y at `speed` from the centre of a
    fixed bore along z, Liu's law per length, damping_law = "calibrated"."""
    data = {"kind": "spatial", "duration": duration, "laws_file": str(laws_path),
            "bodies": [{"name": "journal", "mass": MASS, "inertia": np.diag([1e-5] * 3).tolist(),
                        "velocity": [0.0, -speed, 0.0]}],
            "clearance_joints": [{"name": "j", "type": "cylindrical", "bearing_body": "ground",
                                  "bearing_point": [0, 0, 0], "bearing_axis": [0, 0, 1],
                                  "journal_body": "journal", "journal_point": [0, 0, 0],
                                  "journal_axis": [0, 0, 1], "bearing_radius": R_BORE,
                                  "journal_radius": R_PIN, "length": LENGTH, "slices": slices,
                                  "E": 210e9, "nu": 0.3, "normal_law": "liu",
                                  "damping_law": "calibrated", "start": "free"} | joint],
            "integrator": {"rtol": 1e-9, "atol": 1e-13, "max_step": 1e-6},
            "output": {"sample_time": duration / 50, "plots": False}}
    model = build(kinds.validate(data, "test"), "test", ROOT)
    run = simulate(model)
    assert run.status == 0, (run.status, run.t_end)
    return model, run, per_step(model, run)[0]


def duration(speed, e):
    """Across the clearance, the contact (well under 40 us at these speeds: the FE's 13-19
    us, Liu's law a little softer), and half the way back (the far side is 2 c away)."""
    c = R_BORE - R_PIN
    return c / speed + 4e-5 + c / (e * speed)


def rebound(run, cols):
    """The journal's velocity along y at the first accepted step after the first contact
    ended (free flight: constant until the far side), and the impacts before it."""
    contact = cols["j_penetration_m"] > 0
    first = int(np.argmax(contact))
    after = first + int(np.argmax(~contact[first:]))
    assert contact[first] and not contact[after]
    return cols["journal_vy_m_per_s"][after], int(np.sum(run.impacts[:, 0] < cols["time_s"][after]))


@pytest.mark.parametrize("speed", [0.1, 0.7, 3.0])
def test_spatial_impact_rebounds_with_the_calibrated_e(tmp_path, speed):
    """The rebound speed over the impact speed is e(v0) of the law to 2e-4: the table of
    chi(v0) (33 points in ln v0: 1e-4 of e, reduced.mechanism.model.damping_block) and the
    integration (rtol 1e-9); the onset is located, so the impact speed is the throw's to
    round-off."""
    path, law = law_file(tmp_path)
    e = law.restitution(speed)
    _, run, cols = spatial_impact(path, speed, duration(speed, e))
    v_out, impacts = rebound(run, cols)
    assert impacts == 1
    assert run.impacts[0, 2] == pytest.approx(speed, rel=1e-9)   # LOG_RATE
    assert v_out / speed == pytest.approx(e, rel=2e-4)


def test_spatial_impact_matches_the_planar_calibrated_impact(tmp_path):
    """The same journal, law and laws file as a planar scene (the planar model's calibrated
    impact, Liu's law times L): rebound to 1e-6, peak force to 1e-5: the slices of an
    aligned journal sum to the planar law exactly, and what differs is the two integrations'
    steps at rtol 1e-9 (measured 2e-7 on the rebound) and the peak read between steps of
    about a tenth of a microsecond (the damped force is not symmetric about its peak: the
    parabola's error is of third order in the step; measured 4e-6)."""
    path, law = law_file(tmp_path)
    speed = 1.0
    t_end = duration(speed, law.restitution(speed))
    _, run, cols = spatial_impact(path, speed, t_end, slices=8)
    planar = {"kind": "planar", "duration": t_end, "laws_file": str(path),
              "bodies": [{"name": "journal", "mass": MASS, "inertia": 1e-5,
                          "velocity": [0.0, -speed]}],
              "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                    "journal_body": "journal", "journal_point": [0.0, 0.0],
                                    "bearing_radius": R_BORE, "journal_radius": R_PIN,
                                    "length": LENGTH, "E": 210e9, "nu": 0.3, "normal_law": "liu",
                                    "damping_law": "calibrated", "start": "free"}],
              "integrator": {"rtol": 1e-9, "atol": 1e-13, "max_step": 1e-6},
              "output": {"sample_time": t_end / 50, "plots": False}}
    model_p = build(kinds.validate(planar, "test"), "test", ROOT)   # the planar kind
    run_p = simulate(model_p)
    cols_p = per_step(model_p, run_p)[0]
    assert rebound(run, cols)[1] == 1
    assert rebound(run, cols)[0] == pytest.approx(rebound(run_p, cols_p)[0], rel=1e-6)
    assert vertex(cols) == pytest.approx(vertex(cols_p), rel=1e-5)


def vertex(cols):
    """The peak normal force: the vertex of the parabola through the largest accepted step's
    force and its neighbours (the steps of the two models fall at different times; near the
    peak F is quadratic in t, the parabola's error is of third order in the step, the damped force being asymmetric)."""
    k = int(np.argmax(cols["j_normal_force_N"]))
    t, f = cols["time_s"][k - 1:k + 2], cols["j_normal_force_N"][k - 1:k + 2]
    a, b, c = np.polyfit(t - t[1], f, 2)
    return c - b * b / (4 * a)


def test_an_impact_beyond_the_range_warns(tmp_path):
    """At 6 m/s (the law was fitted up to 3 m/s) e is held at its 3 m/s value, and the
    summary says so in one line naming the joint and the range."""
    path, law = law_file(tmp_path)
    model, run, cols = spatial_impact(path, 6.0, duration(6.0, law.restitution(3.0)))
    v_out, impacts = rebound(run, cols)
    assert impacts == 1
    assert v_out / 6.0 == pytest.approx(law.restitution(3.0), rel=2e-4)
    text = summary(model, sample(model, run), run, "ok", "test").warnings
    assert len(text) == 1 and text[0].startswith("j: ") and "6 m/s" in text[0] and "0.1-3 m/s" in text[0]


def test_a_joint_without_its_law_is_one_line(tmp_path):
    """A bore of another modulus than the laws file's law: one InputError line naming the
    joint and the file's keys."""
    path, law = law_file(tmp_path, bore_E=70e9)
    with pytest.raises(InputError, match="clearance_joints.j.damping_law: 'calibrated': no "
                                         "restitution law") as err:
        spatial_impact(path, 1.0, 1e-5)
    assert "\n" not in str(err.value) and law.joint.key() in str(err.value)
    _, run, _ = spatial_impact(path, 1.0, 1e-5, bearing_E=70e9)   # the bearing_E it was fitted on
    assert run.status == 0


def test_bad_calibrated_scenes_are_one_line_exit_2(tmp_path, write_scene):
    """No laws_file (a journal), and a spherical joint asking for the calibrated law: one line naming the
    key and the rule, exit 2, nothing written."""
    ball = {"name": "socket", "type": "spherical", "bearing_body": "ground",
            "bearing_point": [0, 0, 0], "journal_body": "ball", "journal_point": [0, 0, 0],
            "bearing_radius": 10e-3, "journal_radius": 9.5e-3, "E": 207e9, "nu": 0.3,
            "normal_law": "hertz_point", "damping_law": "calibrated"}
    base = {"kind": "spatial", "duration": 1e-4,
            "bodies": [{"name": "ball", "mass": 0.1, "inertia": np.diag([1e-6] * 3).tolist()}]}
    journal = ball | {"type": "cylindrical", "bearing_axis": [0, 0, 1], "journal_axis": [0, 0, 1],
                      "length": LENGTH, "normal_law": "liu"}
    cases = [(base | {"clearance_joints": [journal]}, "laws_file is required by damping_law"),
             (base | {"laws_file": str(law_file(tmp_path)[0]), "clearance_joints": [ball]},
              "damping_law 'calibrated' is for cylindrical joints")]
    for k, (data, words) in enumerate(cases):
        out = tmp_path / f"out{k}"
        done = pinbore("reduced", write_scene(data, f"s{k}.toml"), "--out", out)
        assert done.returncode == 2, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1 and words in done.stderr, done.stderr
        assert not out.exists()
