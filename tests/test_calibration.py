"""Calibration against known truths: synthetic curves made from a law with known parameters
(exact and with noise), the multibody model applying the calibrated law, and the rules for
bad curve and laws files."""

import csv
import json
import tomllib

import numpy as np
import pytest
from conftest import ROOT, pinbore, scene_dict

from pinbore.calibration.curves import Curve
from pinbore.calibration.fit import errors, fit
from pinbore.calibration.run import evaluate, laws_json
from pinbore.laws import lawsfile
from pinbore.laws.elastic import Joint
from pinbore.laws.lawsfile import law_force
from pinbore.reduced.mechanism.layout import CONTACT_TABLE
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.scene import PlanarScene

JOINT = Joint(10e-3, 9.95e-3, 210e9, 0.3, 210e9, 0.3, 0.02)
APPROACH = np.linspace(1e-6, 1e-5, 10)


def synthetic(name, scale, exponent, noise=0.0, seed=0):
    reference = float(np.exp(np.mean(np.log(APPROACH))))
    force = scale * law_force(name, APPROACH, JOINT) * (APPROACH / reference) ** exponent
    force *= np.exp(noise * np.random.default_rng(seed).standard_normal(APPROACH.size))
    return Curve("synthetic", APPROACH, force, None, JOINT, 20.0, True)


@pytest.mark.parametrize("name", ["hertz", "liu", "johnson", "dubowsky_freudenstein"])
def test_fit_recovers_exact_parameters(name):
    f = fit(name, [synthetic(name, 1.37, -0.12)])
    assert f.scale == pytest.approx(1.37, rel=1e-9)
    assert f.exponent_correction == pytest.approx(-0.12, abs=1e-9)
    assert errors(f.force(name, APPROACH, JOINT), synthetic(name, 1.37, -0.12).force).max_rel < 1e-9


def test_published_law_has_no_error_on_its_own_curve():
    curve = synthetic("liu", 1.0, 0.0)
    assert errors(law_force("liu", APPROACH, JOINT), curve.force).max_rel < 1e-12


def test_confidence_intervals_cover_the_truth_at_their_rate():
    """95 % intervals from 200 noisy curves (2 % log-normal noise): coverage near 95 %."""
    covered = 0
    for seed in range(200):
        f = fit("liu", [synthetic("liu", 0.8, 0.05, noise=0.02, seed=seed)])
        covered += f.scale_ci95[0] <= 0.8 <= f.scale_ci95[1]
    assert 0.90 <= covered / 200 <= 0.99


def test_linear_spring_fits_its_stiffness_alone():
    curve = Curve("line", APPROACH, 3.0e11 * APPROACH, None, JOINT, 20.0, True)
    f = fit("linear", [curve])
    assert f.exponent_correction == 0.0
    assert f.scale * JOINT.e_star == pytest.approx(3.0e11, rel=1e-9)


@pytest.fixture(scope="module")
def fe_run(tmp_path_factory):
    """One small FE run whose curve.csv and result.json the bad-input tests edit."""
    import tomli_w
    folder = tmp_path_factory.mktemp("fe")
    scene = folder / "scene.toml"
    scene.write_text(tomli_w.dumps(scene_dict(load={"steps": 4})))
    done = pinbore("fem", scene, "--out", folder / "run")
    assert done.returncode == 0, done.stderr
    return folder / "run"


def test_calibrate_writes_laws_json(fe_run, tmp_path):
    out = tmp_path / "cal"
    done = pinbore("calibrate", fe_run / "curve.csv", "--out", out)
    assert done.returncode == 0, done.stderr
    data = json.loads((out / "laws.json").read_text())
    assert set(data["laws"]) == {"hertz", "johnson", "liu", "bai_zhao", "pereira", "radzimovsky",
                                 "dubowsky_freudenstein", "esdu_78035", "linear"}
    for name, law in data["laws"].items():
        assert law["fitted_to"] == ["run"]
        assert law["validity"]["clearance_m"] == [pytest.approx(1e-5)] * 2
        if name in ("johnson", "esdu_78035"):
            # c = 10 um: their log term allows approaches up to 5.4 um only; 2 of 4 points
            assert law["fitted"] is None and "cannot fix 2 parameters" in law["not_fitted"]
            continue
        low, high = law["fitted"]["scale_ci95"]
        assert low <= law["fitted"]["scale"] <= high
    assert data["curves"][0]["persson_half_angle_error_deg"] < 1.5
    assert {"curves.png", "errors.png", "ranking.csv"} <= {p.name for p in out.iterdir()}


def _edited(fe_run, tmp_path, edit):
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "result.json").write_text((fe_run / "result.json").read_text())
    rows = list(csv.reader(open(fe_run / "curve.csv")))
    rows = edit(rows)
    with open(folder / "curve.csv", "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return folder / "curve.csv"


@pytest.mark.parametrize("edit, message", [
    (lambda r: [[c for i, c in enumerate(row) if i != r[0].index("approach_m")] for row in r],
     "approach_m: required column"),
    (lambda r: [r[0]] + [r[2], r[1]] + r[3:], "approach_m: must be positive and increase"),
    (lambda r: r[:2] + [r[2][:2] + ["nan"] + r[2][3:]] + r[3:], "row 2: nan is not finite"),
    (lambda r: r[:3], "2 points; a fit of 2 parameters needs at least 3"),
    (lambda r: r[:1], "0 points; a fit of 2 parameters needs at least 3"),
    (lambda r: [row[:-1] for row in r], "gap_violation_m: required column is missing (written "
                                        "by another version of pinbore? run pinbore fem again)"),
    (lambda r: [[h.replace("force_per_length_N_per_m", "force_N") for h in r[0]]] + r[1:],
     "force_N: units do not match"),
    (lambda r: [[h.replace("approach_m", "approach_mm") for h in r[0]]] + r[1:],
     "approach_mm: units do not match"),
])
def test_bad_curves_are_one_line_exit_2(fe_run, tmp_path, edit, message):
    path = _edited(fe_run, tmp_path, edit)
    done = pinbore("calibrate", path, "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_curve_cut_short_of_its_run_is_one_line(fe_run, tmp_path):
    """The run converged 4 steps; a curve.csv of 3 is not its curve."""
    path = _edited(fe_run, tmp_path, lambda r: r[:4])
    done = pinbore("calibrate", path, "--out", tmp_path / "out")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "3 steps, but the run converged 4 (result.json): the curve was cut short" in done.stderr


def test_a_curve_beside_another_dimensions_run_is_one_line(fe_run, tmp_path):
    """A 2D curve beside the result.json of a 3D run (a TypeError once)."""
    path = _edited(fe_run, tmp_path, lambda r: r)
    result = json.loads((path.parent / "result.json").read_text())
    result["scene"]["geometry"].update(dim=3, length=0.01)
    result["scene"].setdefault("mesh", {})["max_cells"] = 10**7   # a valid 3D scene
    (path.parent / "result.json").write_text(json.dumps(result))
    done = pinbore("calibrate", path, "--out", tmp_path / "out")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "scene: geometry.dim = 3, but curve.csv is a 2D curve" in done.stderr


@pytest.mark.parametrize("how", ["same file", "a copy"])
def test_a_curve_given_twice_is_one_line(fe_run, tmp_path, how):
    """One run given twice would weigh double in the fit."""
    other = fe_run / "curve.csv"
    if how == "a copy":
        other = _edited(fe_run, tmp_path, lambda r: r)
    done = pinbore("calibrate", fe_run / "curve.csv", other, "--out", tmp_path / "out")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert "the same curve as" in done.stderr


def test_curve_without_its_scene(fe_run, tmp_path):
    path = _edited(fe_run, tmp_path, lambda r: r)
    (path.parent / "result.json").unlink()
    done = pinbore("calibrate", path, "--out", tmp_path / "out")
    assert done.returncode == 2 and "needs the FE run's result.json" in done.stderr


def synthetic_laws_file(folder):
    """laws.json of the laws calibrated on one synthetic curve: Liu's law with s = 1.37,
    q = -0.12."""
    curves = [synthetic("liu", 1.37, -0.12)]
    path = folder / "laws.json"
    lawsfile.write(path, laws_json(curves, evaluate(curves), None, [], 0.0))
    return path


def calibrated_scene(laws_file, law="liu") -> dict:
    """The calibrated slider-crank, its joint that of JOINT, its normal law calibrated."""
    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004_calibrated.toml").read_text())
    data["laws_file"] = str(laws_file)
    data["clearance_joints"][0] |= {"bearing_radius": JOINT.r_bore, "journal_radius": JOINT.r_pin,
                                    "E": JOINT.E_pin, "nu": JOINT.nu_pin, "length": JOINT.length,
                                    "normal_law": f"calibrated:{law}"}
    return data


def test_laws_file_reads_back_what_was_written(tmp_path):
    path = synthetic_laws_file(tmp_path)
    curves = [synthetic("liu", 1.37, -0.12)]
    assert lawsfile.read(path) == laws_json(curves, evaluate(curves), None, [], 0.0)


def joint_table(model, j=0):
    """ln F of clearance joint j's normal law, as the model tabulated it (the table of its
    first contact; a planar revolute joint has one)."""
    return model.base.tables[int(model.contacts[model.contact_rows[j][0], CONTACT_TABLE])]


def test_multibody_model_applies_the_law_the_calibration_fitted(tmp_path):
    """The joint's tabulated force is F = P L, P the calibrated law: here the synthetic truth."""
    model = build(PlanarScene.model_validate(calibrated_scene(synthetic_laws_file(tmp_path))),
                  "test", tmp_path)
    table = joint_table(model)
    d = np.exp(model.base.grid_log0 + model.base.grid_step * np.arange(table.size))
    inside = np.isfinite(table)
    reference = float(np.exp(np.mean(np.log(APPROACH))))
    truth = 1.37 * law_force("liu", d, JOINT) * (d / reference) ** -0.12 * JOINT.length
    np.testing.assert_allclose(np.exp(table[inside]), truth[inside], rtol=1e-8)


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("laws"), "laws: required key is missing"),
    (lambda d: d["laws"]["liu"].pop("fitted"), "laws.liu.fitted: required key is missing"),
    (lambda d: d["laws"]["liu"]["fitted"].update(scale="1.37"), "laws.liu.fitted.scale:"),
])
def test_a_laws_file_of_another_version_is_one_line_exit_2(write_scene, tmp_path, edit, message):
    path = synthetic_laws_file(tmp_path)
    data = json.loads(path.read_text())
    edit(data)
    path.write_text(json.dumps(data))
    done = pinbore("reduced", write_scene(calibrated_scene(path)), "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert len(line.splitlines()) == 1 and f"laws_file: {path}: {message}" in line
    assert line.endswith("(written by another version of pinbore? run pinbore calibrate again)")
    assert not (tmp_path / "out").exists()


def test_a_3d_curve_without_its_section_is_one_line_for_the_section_law(fe_run, tmp_path):
    """--per-length section needs the 2D curve of each 3D curve's own plane section: a 3D
    run of another clearance than the 2D run's is refused in one line, exit 2, nothing
    written."""
    from test_calibration_3d import three_d_run

    other = three_d_run(tmp_path / "run3d", {"pin_radius": 9.98e-3})
    done = pinbore("calibrate", fe_run / "curve.csv", other, "--per-length", "section",
                   "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert len(line.splitlines()) == 1 and "--per-length: section:" in line
    assert "no 2D curve of its plane section" in line
    assert not (tmp_path / "out").exists()
