"""The calibrated restitution: the Hunt-Crossley factor for a target e against the integrated
impact (for several elastic laws), the fit e(v0) of FE impacts, and the multibody model's
single impact with `damping_law = "calibrated"` against the FE restitution."""

import json
import math

import numpy as np
import pytest
from conftest import ROOT, pinbore
from test_impact import Impact, impact_scene

from pinbore.calibration import lawsfile, restitution
from pinbore.fem import impact_file
from pinbore.laws import dissipative
from pinbore.reduced.model import build
from pinbore.reduced.outputs import per_step, summary
from pinbore.reduced.run import simulate
from pinbore.reduced.scene import ReducedScene

# The FE impacts of the calibration: the coarse test scene (steel pin, c = 10 um), 50 steps
# over the contact (e within 1e-3 of its 200-step value at 1 m/s, test_impact), four speeds
# across the range of the Flores slider-crank's impacts: about 2 s each.
SPEEDS = (0.1, 0.3, 1.0, 3.0)


@pytest.mark.parametrize("e", [0.05, 0.3, 0.6, 0.9, 0.999])
@pytest.mark.parametrize("elastic", ["hertz", "linear", "liu-like"])
def test_hysteresis_for_restitution_rebounds_with_e(e, elastic):
    """chi(e) rebounds with e to 1e-8 in an integrated impact (DOP853) on three elastic laws
    of different shapes, at arbitrary mass and speed: the relation does not depend on F_el."""
    force = {"hertz": lambda d: 3e9 * d**1.5, "linear": lambda d: 2e8 * d,
             "liu-like": lambda d: 1e8 * d / (1 + 30 * math.sqrt(d))}[elastic]
    chi = dissipative.hysteresis_for_restitution(e)
    measured = dissipative.restitution(
        lambda d, r: dissipative.hysteresis_force(force(max(d, 0.0)), r, 0.7, chi), 0.2, 0.7)
    assert measured == pytest.approx(e, abs=1e-8)


def test_hysteresis_for_restitution_near_one_is_lankarani_nikravesh():
    """First order in 1 - e: 1 - e^2 = 4 chi / 3 ([LankaraniNikravesh1990])."""
    e = 0.999
    assert dissipative.hysteresis_for_restitution(e) == pytest.approx(
        dissipative.lankarani_nikravesh(e), rel=2e-3)


@pytest.fixture(scope="module")
def fe_impacts(tmp_path_factory):
    """impact.json of the FE impacts at SPEEDS, written through fem.impact_file."""
    folder = tmp_path_factory.mktemp("impacts")
    paths = []
    for v in SPEEDS:
        run = Impact(impact_scene(impact={"speed": v, "steps_per_contact": 50}))
        path = folder / f"v{v:g}.json"
        impact_file.write_summary(path, run.summary)
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def law(fe_impacts):
    return restitution.fit(restitution.read_impacts(fe_impacts))


def test_fit_of_the_fe_restitution(law):
    """The quadratic in ln v0 follows the four FE values within 0.01 (one degree of freedom
    left), over the impacts' speeds; e decreases with v0 (shorter contacts excite more of
    the bodies' vibrations)."""
    e = [q.restitution for q in law.impacts]
    assert law.speed_range_m_per_s == [min(SPEEDS), max(SPEEDS)]
    assert law.max_fit_error < 0.01
    assert all(a > b for a, b in zip(e, e[1:]))
    assert 0.4 < e[-1] < e[0] < 0.95


def journal_impact(laws_path, speed, duration):
    """The multibody model's single impact: the FE pin (its mass per length times the joint
    length) thrown at `speed` against a fixed bearing of the FE joint's radii and material,
    Liu's law per length, damping_law = "calibrated"."""
    length, mass_per_length = 0.02, 7850 * math.pi * 9.99e-3**2
    data = {"kind": "reduced", "duration": duration, "laws_file": str(laws_path),
            "bodies": [{"name": "journal", "mass": mass_per_length * length, "inertia": 1e-5,
                        "velocity": [0.0, -speed]}],
            "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 9.99e-3,
                                  "length": length, "E": 210e9, "nu": 0.3,
                                  "normal_law": "liu", "damping_law": "calibrated",
                                  "start": "free"}],
            "integrator": {"rtol": 1e-9, "atol": 1e-13, "max_step": 1e-6},
            "output": {"sample_time": duration / 50}}
    model = build(ReducedScene.model_validate(data), "test", ROOT)
    run = simulate(model)
    assert run.status == 0, (run.status, run.t_end)
    cols, _, _ = per_step(model, run)
    return model, run, cols


def laws_file(tmp_path, law) -> str:
    path = tmp_path / "laws.json"
    lawsfile.write(path, lawsfile.LawsFile(
        units=lawsfile.UNITS, length_m=None, length_note="", curves=[], laws={}, sliced={},
        warnings=[], fit_seconds=0.0, restitution=law))
    return path


@pytest.mark.parametrize("index", [0, 2, 3])
def test_multibody_impact_reproduces_the_fe_restitution(tmp_path, law, index):
    """One journal impact with the calibrated law rebounds with the FE's e at its speed
    within 5 % (the fit's error, 0.01 at most, and the table of chi(v0): 1e-4)."""
    point = law.impacts[index]
    v = point.speed_m_per_s
    # the flight across the clearance c, the contact (the FE's duration, give or take a
    # tenth), and half the way back (the other side is 2 c away)
    c = 10e-6
    duration = c / v + 1.1 * point.contact_duration_s + c / (point.restitution * v)
    _, run, cols = journal_impact(laws_file(tmp_path, law), v, duration)
    assert run.counters[3] == 1
    rebound = cols["journal_vy_m_per_s"][-1] / v
    assert rebound == pytest.approx(point.restitution, rel=0.05)
    assert rebound == pytest.approx(law.restitution(v), rel=1e-3)


def test_an_impact_beyond_the_range_warns_once(tmp_path, law):
    """At 10 m/s (above the FE's 3 m/s) e is held at its 3 m/s value and the summary says
    so in one line."""
    model, run, _ = journal_impact(laws_file(tmp_path, law), 10.0, 1e-6 + 1.5e-5)
    from pinbore.reduced.outputs import sample
    text = summary(model, sample(model, run), run, "ok", "test").warnings
    assert len([w for w in text if "restitution" in w]) == 1
    assert "10 m/s" in text[0] and "0.1-3 m/s" in text[0]


def test_calibrate_writes_the_restitution(tmp_path, fe_impacts):
    """pinbore calibrate --impacts puts the law into laws.json (with a 2D curve, which the
    command needs), and its figure; a reduced scene without a restitution law in its file
    is one line, exit 2."""
    from conftest import scene_dict
    from pinbore.core.scene import validate  # noqa: F401
    import tomli_w
    scene = tmp_path / "fem.toml"
    scene.write_text(tomli_w.dumps(scene_dict()))
    assert pinbore("fem", str(scene), "--out", str(tmp_path / "fem")).returncode == 0
    out = tmp_path / "cal"
    done = pinbore("calibrate", str(tmp_path / "fem" / "curve.csv"), "--impacts",
                   *map(str, fe_impacts), "--out", str(out))
    assert done.returncode == 0, done.stderr
    written = lawsfile.read(out / "laws.json")
    assert written.restitution.coefficients == pytest.approx(
        restitution.fit(restitution.read_impacts(fe_impacts)).coefficients, rel=1e-12)
    assert (out / "restitution.png").stat().st_size > 0
    plain = pinbore("calibrate", str(tmp_path / "fem" / "curve.csv"), "--out", str(tmp_path / "c2"))
    assert plain.returncode == 0
    data = json.loads((tmp_path / "c2" / "laws.json").read_text())
    assert data["restitution"] is None
    with pytest.raises(Exception, match="restitution law"):
        journal_impact(tmp_path / "c2" / "laws.json", 1.0, 1e-4)
