"""The calibrated restitution: the Hunt-Crossley factor for a target e against the integrated
impact (for several elastic laws), the fit e(v0) of FE impacts, and the multibody model's
single impact with `damping_law = "calibrated"` against the FE restitution."""

import json
import math

import numpy as np
import pytest
from conftest import ROOT, pinbore
from test_impact import Impact, impact_scene

from pinbore.calibration import restitution
from pinbore.fem.impact import file as impact_file
from pinbore.laws import dissipative, lawsfile
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import per_step, summary
from pinbore.reduced.mechanism.run import simulate
from pinbore.reduced.mechanism.scene import PlanarScene

# The FE impacts of the calibration: the coarse test scene (steel pin, c = 10 um), 50 steps
# over the contact (e within 1e-3 of its 200-step value at 1 m/s, test_impact), four speeds
# across the range of the Flores slider-crank's impacts: about 2 s each.
SPEEDS = (0.1, 0.3, 1.0, 3.0)
# The same steel pin in an aluminium-alloy bore, three of the speeds: another joint, fitted alone
ALUMINIUM = {"E": 70e9, "nu": 0.33, "density": 2700.0}
ALUMINIUM_SPEEDS = (0.1, 1.0, 3.0)


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


def _write_impacts(folder, speeds, bore=None) -> list:
    """impact.json and history.csv of FE impacts at `speeds` (steel bore, or the `bore`
    material), one folder each, written through fem.impact.file."""
    from pinbore.fem.impact.run import history_rows
    paths = []
    for v in speeds:
        data = impact_scene(impact={"speed": v, "steps_per_contact": 50})
        data["materials"]["bore"].update(bore or {})
        path = folder / f"{'al' if bore else 'steel'}_v{v:g}" / impact_file.SUMMARY
        path.parent.mkdir()
        run = Impact(data)
        impact_file.write_summary(path, run.summary)
        impact_file.write_history(path.parent / impact_file.HISTORY,
                                  history_rows(run.run, run.stepper.impact_energy))
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def fe_impacts(tmp_path_factory):
    """The steel/steel FE impacts at SPEEDS."""
    return _write_impacts(tmp_path_factory.mktemp("impacts"), SPEEDS)


@pytest.fixture(scope="module")
def al_impacts(tmp_path_factory):
    """The steel-in-aluminium FE impacts at ALUMINIUM_SPEEDS."""
    return _write_impacts(tmp_path_factory.mktemp("al_impacts"), ALUMINIUM_SPEEDS, ALUMINIUM)


@pytest.fixture(scope="module")
def laws(fe_impacts, al_impacts):
    """Both joints' impacts given mixed, in one list: one law per joint."""
    mixed = [p for pair in zip(fe_impacts, al_impacts) for p in pair] + fe_impacts[len(al_impacts):]
    return restitution.fit_all(mixed)


def _of(laws, bore_E):
    return next(law for law in laws.values() if law.joint.bore_E_Pa == bore_E)


@pytest.fixture(scope="module")
def law(laws):
    """The steel/steel law."""
    return _of(laws, 210e9)


def test_fit_of_the_fe_restitution(laws, law, fe_impacts, al_impacts):
    """Mixed impacts are grouped by joint and each group fitted alone: the steel law is the
    fit of the steel impacts only. The quadratic in ln v0 follows the four FE values within
    0.01 (one degree of freedom left), over the impacts' speeds; e decreases with v0 in both
    joints (shorter contacts excite more of the bodies' vibrations)."""
    assert len(laws) == 2
    alone = restitution.fit_all(fe_impacts)
    assert list(alone) == [law.joint.key()]
    assert alone[law.joint.key()].coefficients == pytest.approx(law.coefficients, rel=1e-12)
    assert law.speed_range_m_per_s == [min(SPEEDS), max(SPEEDS)]
    assert law.max_fit_error < 0.01
    aluminium = _of(laws, 70e9)
    assert [q.name for q in aluminium.impacts] == [str(p) for p in al_impacts]
    for group in laws.values():
        e = [q.restitution for q in group.impacts]
        assert all(a > b for a, b in zip(e, e[1:]))
        assert 0.4 < e[-1] < e[0] < 0.95


def test_fit_degree_grows_to_a_cubic_with_the_impacts(law):
    """The fit keeps one impact more than coefficients: e(x) = a cubic in x = ln v0 sampled
    at five speeds is reproduced to round-off everywhere in the range (its own cubic), at
    four speeds by a quadratic, whose residual is the cubic term's least-squares remainder
    (nonzero); e is held at the ends beyond the range."""
    truth = np.array([0.60, -0.07, -0.006, 0.004])
    speeds = np.array([0.1, 0.3, 1.0, 3.0, 5.0])

    def points(vs):
        e = np.polynomial.polynomial.polyval(np.log(vs), truth)
        return [law.impacts[0].model_copy(update={"speed_m_per_s": float(v), "restitution": float(r)})
                for v, r in zip(vs, e)]
    cubic = restitution.fit(points(speeds), law.joint)
    assert len(cubic.coefficients) == 4 and cubic.max_fit_error < 1e-12
    for v in np.geomspace(0.1, 5.0, 17):
        assert cubic.restitution(v) == pytest.approx(np.polynomial.polynomial.polyval(np.log(v), truth), abs=1e-12)
    assert cubic.restitution(10.0) == pytest.approx(cubic.restitution(5.0), abs=1e-15)
    quadratic = restitution.fit(points(speeds[:4]), law.joint)
    assert len(quadratic.coefficients) == 3 and quadratic.max_fit_error > 1e-4


def test_a_joint_with_one_impact_is_one_line(fe_impacts, al_impacts):
    """A joint given a single impact cannot be fitted: one InputError naming the joint."""
    from pinbore.core.errors import InputError
    with pytest.raises(InputError, match="1 impact of the joint pin E=2.1e\\+11.*at least 2"):
        restitution.fit_all(al_impacts + fe_impacts[:1])


def journal_impact(laws_path, speed, duration, bearing=None):
    """The multibody model's single impact: the FE pin (its mass per length times the joint
    length) thrown at `speed` against a fixed bearing of the FE joint's radii and materials
    (steel, or `bearing`: E, nu), Liu's law per length, damping_law = "calibrated"."""
    length, mass_per_length = 0.02, 7850 * math.pi * 9.99e-3**2
    data = {"kind": "planar", "duration": duration, "laws_file": str(laws_path),
            "bodies": [{"name": "journal", "mass": mass_per_length * length, "inertia": 1e-5,
                        "velocity": [0.0, -speed]}],
            "clearance_joints": [{"name": "j", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
                                  "journal_body": "journal", "journal_point": [0.0, 0.0],
                                  "bearing_radius": 10e-3, "journal_radius": 9.99e-3,
                                  "length": length, "E": 210e9, "nu": 0.3,
                                  "normal_law": "liu", "damping_law": "calibrated",
                                  "start": "free"} | (bearing or {})],
            "integrator": {"rtol": 1e-9, "atol": 1e-13, "max_step": 1e-6},
            "output": {"sample_time": duration / 50}}
    model = build(PlanarScene.model_validate(data), "test", ROOT)
    run = simulate(model)
    assert run.status == 0, (run.status, run.t_end)
    cols, _, _ = per_step(model, run)
    return model, run, cols


def laws_file(tmp_path, laws) -> str:
    """laws.json of the restitution laws `laws` (by key) only."""
    path = tmp_path / "laws.json"
    lawsfile.write(path, lawsfile.LawsFile(
        units=lawsfile.UNITS, length_m=None, length_note="", curves=[], laws={}, sliced={},
        warnings=[], fit_seconds=0.0, restitution=laws))
    return path


BEARINGS = {"steel": None, "aluminium": {"bearing_E": ALUMINIUM["E"], "bearing_nu": ALUMINIUM["nu"]}}


@pytest.mark.parametrize("bearing,index", [("steel", 0), ("steel", 2), ("steel", 3),
                                           ("aluminium", 0), ("aluminium", 2)])
def test_multibody_impact_reproduces_the_fe_restitution(tmp_path, laws, bearing, index):
    """One journal impact with the calibrated law, the laws file holding both joints' laws,
    rebounds with its own joint's FE e at its speed within 5 % (the fit's error, 0.01 at
    most, and the table of chi(v0): 1e-4)."""
    law = _of(laws, 210e9 if bearing == "steel" else ALUMINIUM["E"])
    point = law.impacts[index]
    v = point.speed_m_per_s
    # the flight across the clearance c, the contact (the FE's duration, give or take a
    # tenth), and half the way back (the other side is 2 c away)
    c = 10e-6
    duration = c / v + 1.1 * point.contact_duration_s + c / (point.restitution * v)
    _, run, cols = journal_impact(laws_file(tmp_path, laws), v, duration, BEARINGS[bearing])
    assert run.counters[3] == 1
    rebound = cols["journal_vy_m_per_s"][-1] / v
    assert rebound == pytest.approx(point.restitution, rel=0.05)
    assert rebound == pytest.approx(law.restitution(v), rel=1e-3)


def test_an_impact_beyond_the_range_warns_once(tmp_path, law):
    """At 10 m/s (above the FE's 3 m/s) e is held at its 3 m/s value and the summary says
    so in one line."""
    model, run, _ = journal_impact(laws_file(tmp_path, {law.joint.key(): law}), 10.0, 1e-6 + 1.5e-5)
    from pinbore.reduced.mechanism.outputs import sample
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
    (key, law), = restitution.fit_all(fe_impacts).items()
    assert written.restitution[key].coefficients == pytest.approx(law.coefficients, rel=1e-12)
    assert (out / "restitution.png").stat().st_size > 0
    assert (out / "impact_force.png").stat().st_size > 0   # the force histories beside them
    plain = pinbore("calibrate", str(tmp_path / "fem" / "curve.csv"), "--out", str(tmp_path / "c2"))
    assert plain.returncode == 0
    data = json.loads((tmp_path / "c2" / "laws.json").read_text())
    assert data["restitution"] == {}
    with pytest.raises(Exception, match="restitution law"):
        journal_impact(tmp_path / "c2" / "laws.json", 1.0, 1e-4)


def test_a_joint_without_its_law_is_one_line(tmp_path, law):
    """A bearing of another material than the laws file's impacts: refused in one line
    that names the joint and the laws the file has."""
    from pinbore.core.errors import InputError
    with pytest.raises(InputError, match="no restitution law of the laws file fits the joint") as err:
        journal_impact(laws_file(tmp_path, {law.joint.key(): law}), 1.0, 1e-4,
                       BEARINGS["aluminium"])
    assert "\n" not in str(err.value) and law.joint.key() in str(err.value)


def test_an_older_laws_file_with_one_law_is_read(tmp_path, law):
    """A laws.json of an older pinbore (one law, no joint) is read as that one law and
    taken by the joint of its impacts' clearance and E*."""
    older = law.model_dump()
    older.pop("joint")
    path = laws_file(tmp_path, {})
    data = json.loads(path.read_text()) | {"restitution": older}
    path.write_text(json.dumps(data))
    read = lawsfile.read(path)
    assert len(read.restitution) == 1 and next(iter(read.restitution.values())).joint is None
    _, run, cols = journal_impact(path, 1.0, 1e-5 + 1.1 * law.impacts[2].contact_duration_s + 2e-5)
    assert run.counters[3] == 1
    assert cols["journal_vy_m_per_s"][-1] == pytest.approx(law.restitution(1.0), rel=1e-3)
