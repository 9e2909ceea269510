"""pinbore from Python (pinbore.api): the tour of the documentation run in process, mesh to
FE to calibration to the multibody model, each result read back typed; a scene as a dict."""

import math
from pathlib import Path

import pytest
from conftest import ROOT, pinbore, scene_dict

import pinbore as pb   # `pinbore` is conftest's command
from pinbore.core.errors import InputError


def test_the_tour_in_process(tmp_path):
    """FE curve -> laws -> the calibrated law: the law that calibrate ranks on the curve gives
    the curve's forces within the error laws.json states for it (each stage's result as the
    next stage reads it)."""
    curve = pb.run("fem", scene_dict(load={"steps": 4}), tmp_path / "fem")
    assert curve.dim == 2 and len(curve.approach) == 4
    laws = pb.calibrate([tmp_path / "fem" / "curve.csv"], tmp_path / "cal")
    law = pb.laws.load(tmp_path / "cal" / "laws.json")["liu"]
    stated = max(e.max_rel for e in laws.laws["liu"].fitted_errors.values())
    for d, p in zip(curve.approach, curve.force):
        if d > 0:
            assert law.per_length(d) == pytest.approx(p, rel=stated + 1e-9)


def test_a_mechanism_from_a_dict(tmp_path):
    """The Flores slider-crank as a dict (a tenth of a crank turn), run as `pinbore reduced`
    runs it: its summary read back; the crank's constant speed gives the duration's angle."""
    import tomllib
    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    data["duration"] = 0.0012
    summary = pb.run("reduced", data, tmp_path / "run")
    assert summary.status == "complete"
    assert summary.time_reached_s == pytest.approx(0.0012)
    assert type(pb.scene(data)).__name__ == "PlanarScene"
    assert math.isfinite(summary.clearance_joints["rod_slider"].peak_normal_force_N)


def test_a_bad_scene_dict_is_one_input_error(tmp_path):
    with pytest.raises(InputError, match="kind: 'gearbox' is unknown"):
        pb.scene({"kind": "gearbox"})
    with pytest.raises(InputError, match="mass"):
        pb.scene({"kind": "planar", "duration": 1.0, "bodies": [{"name": "a", "mass": -1.0}]})
    with pytest.raises(ValueError, match="stage: 'mesh' is unknown"):
        pb.run("mesh", scene_dict(), tmp_path / "x")


IMPACT_OSCILLATOR = ROOT / "scenes" / "reduced" / "impact_oscillator.toml"


def oscillator() -> dict:
    import tomllib

    return tomllib.loads(IMPACT_OSCILLATOR.read_text())

# the API checks its arguments as the CLI does, and names them (a library's TypeError, or an
# error naming a deleted temporary file, had come out of these)
BAD_CALLS = [
    (lambda t: pb.run("reduced", None, t / "o"), "scene: None must be a path"),
    (lambda t: pb.run("reduced", 5, t / "o"), "scene: 5 must be a path"),
    (lambda t: pb.run("reduced", ["a.toml"], t / "o"), "scene: ['a.toml'] must be a path"),
    (lambda t: pb.run("reduced", IMPACT_OSCILLATOR, None), "out: None must be a path"),
    (lambda t: pb.run("reduced", IMPACT_OSCILLATOR, 3), "out: 3 must be a path"),
    (lambda t: pb.run("reduced", oscillator() | {1: 2}, t / "o"), "the key 1 must be a string"),
    (lambda t: pb.run("reduced", oscillator() | {"duration": None}, t / "o"),
     "scene: duration: None is no TOML value"),
    (lambda t: pb.run("reduced", oscillator() | {"duration": -1.0}, t / "o"),
     "scene: duration:"),
    (lambda t: pb.calibrate([ROOT / "nowhere.csv"], t / "c", length=-1.0), "length: -1.0 must be a finite length"),
    (lambda t: pb.calibrate(ROOT / "nowhere.csv", t / "c"), "lists of paths"),
    (lambda t: pb.calibrate([None], t / "c"), "curves.0: None must be a path"),
    (lambda t: locked(t / "o", lambda: pb.run("reduced", IMPACT_OSCILLATOR, t / "o")),
     "another pinbore run is writing it now"),
    (lambda t: locked(t / "c", lambda: pb.calibrate([ROOT / "nowhere.csv"], t / "c")),
     "another pinbore run is writing it now"),
]


def locked(out, call):
    """call() while another run holds out's lock: refused before its work."""
    from pinbore.core.output import _lock

    with _lock(out):
        call()


@pytest.mark.parametrize("call, message", BAD_CALLS, ids=range(len(BAD_CALLS)))
def test_a_bad_argument_is_an_input_error_naming_it(tmp_path, call, message):
    with pytest.raises(InputError) as caught:
        call(tmp_path)
    assert message in str(caught.value) and "pinbore-scene-" not in str(caught.value)
    assert not (tmp_path / "o").exists() and not (tmp_path / "c").exists()


def laws_home(tmp_path):
    """A folder holding cal/laws.json (a synthetic calibration) and a calibrated Flores
    slider-crank naming it relatively, cal/laws.json, run for a tenth of a crank turn."""
    from test_calibration import calibrated_scene, synthetic_laws_file

    (tmp_path / "cal").mkdir()
    synthetic_laws_file(tmp_path / "cal")
    return calibrated_scene("cal/laws.json") | {"duration": 0.0012, "output": {"plots": False}}


def test_a_dicts_relative_files_are_taken_from_base_or_the_working_folder(tmp_path, monkeypatch):
    """A dict's relative `*_file` names are taken from `base`, else from the working folder
    (core.scene.scene_file writes them absolute in its temporary scene file); the same run
    either way, and from elsewhere without base, one line naming the dict's key."""
    data = laws_home(tmp_path)
    from_base = pb.run("reduced", data, tmp_path / "a", base=tmp_path)
    monkeypatch.chdir(tmp_path)
    from_here = pb.run("reduced", data, "b")
    assert from_base.status == from_here.status == "complete"
    assert from_base.clearance_joints == from_here.clearance_joints
    monkeypatch.chdir(tmp_path / "cal")
    with pytest.raises(InputError, match="laws_file") as caught:
        pb.run("reduced", data, tmp_path / "c")
    assert "pinbore-scene-" not in str(caught.value) and not (tmp_path / "c").exists()


def test_a_study_points_relative_files_are_taken_from_its_base_scene(tmp_path, monkeypatch):
    """A study's points name files relative to the base scene's folder, wherever the study
    and its workers run: in process (a mechanism's points) and through a scene file
    (Point.in_folder, as an FE, impact, modes or wear point runs; core.scene.scene_file, as
    pinbore.run writes a dict); both give the run pinbore.run gives."""
    import csv
    import json

    import tomli_w

    from pinbore import study as runner

    data = laws_home(tmp_path)
    for folder in ("scenes", "studies", "elsewhere"):
        (tmp_path / folder).mkdir()
    (tmp_path / "scenes" / "calibrated.toml").write_text(tomli_w.dumps(data | {"laws_file": "../cal/laws.json"}))
    (tmp_path / "studies" / "s.toml").write_text(
        'base = "../scenes/calibrated.toml"\n[parameters."clearance_joints.0.restitution"]\n'
        'values = [0.9]\n[sampling]\nmethod = "grid"\n'
        '[[collect]]\nname = "peak_N"\npath = "clearance_joints.rod_slider.peak_normal_force_N"\n')
    joint = data["clearance_joints"][0] | {"restitution": 0.9}
    peak = pb.run("reduced", data | {"clearance_joints": [joint]}, tmp_path / "ref",
                  base=tmp_path).clearance_joints["rod_slider"].peak_normal_force_N
    monkeypatch.chdir(tmp_path / "elsewhere")
    done = pinbore("study", "../studies/s.toml", "--out", "out", "--workers", "1")
    assert done.returncode == 0, done.stderr
    (row,) = csv.DictReader((tmp_path / "elsewhere/out/results.csv").open())
    assert float(row["peak_N"]) == pytest.approx(peak, rel=1e-12)
    path = Path("../studies/s.toml")   # a relative base scene's folder, made absolute by Point
    plan = runner.Plan(path, runner.load(path))
    point = runner.Point("reduced", plan.base_path.parent, str(plan.base_path))
    monkeypatch.chdir(tmp_path / "cal")   # a worker that runs elsewhere
    status, _, result = point.in_folder(plan.scenes[0], lambda out: json.loads((out / "summary.json").read_text()))
    assert status == "complete"
    assert result["clearance_joints"]["rod_slider"]["peak_normal_force_N"] == pytest.approx(peak, rel=1e-12)
