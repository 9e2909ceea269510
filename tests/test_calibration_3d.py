"""The 3D calibration (the sliced law of a finite pin, calibration/sliced.py) against known
truths: curves made by the sliced law itself with a known stiffness factor, end length and
bulk compliance are fitted back exactly, and the rules for 3D curves given to `pinbore
calibrate`."""

import json
from pathlib import Path

import numpy as np
import pytest
from conftest import pinbore, scene_dict

from pinbore.calibration import sliced
from pinbore.calibration.curves import Curve3D
from pinbore.core.scene import validate
from pinbore.fem import curve
from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import Joint
from pinbore.laws.lawsfile import law_force
from pinbore.laws.tables import largest_compliance

JOINT = Joint(10e-3, 9.97e-3, 210e9, 0.3, 210e9, 0.3, 0.02)


def liu(d, joint):
    return law_force("liu", d, joint)


LIU = sliced.PerLength("liu", lambda d, curve: liu(d, curve.joint), lambda curve: None)


def synthetic(name, length, scale, end_length, bulk_fraction=0.0, runs_on=False):
    """Push to 10 um in 4 steps, then tilt to twice the tilt that lifts an end (2 delta / L),
    F and M from the sliced law with the given scale, end length and bulk compliance (this
    fraction of what Liu's law can give up)."""
    approach = np.r_[np.geomspace(2e-6, 1e-5, 4), np.full(4, 1e-5)]
    tilt = np.r_[np.zeros(4), np.linspace(0.5, 2.0, 4) * 2e-5 / length]
    bare = Curve3D(name, Path(name), approach, tilt, np.ones(8), np.zeros(8), JOINT, length, runs_on, None, "steel")
    table = sliced.per_length_table(LIU.force, bare)
    force, moment = sliced.law_at_steps(bare, table, scale, end_length,
                                        bulk_fraction * largest_compliance(*table))
    return Curve3D(name, Path(name), approach, tilt, force, moment, JOINT, length, runs_on, None, "steel")


def test_the_fit_recovers_the_stiffness_factor_the_end_length_and_the_bulk_compliance():
    """Two lengths of each kind of ends, made with known a, e and c_b: fitted back to 1e-5
    (nonlinear least squares on exact data stops at its tolerances, 1e-12 on the steps and
    the cost; 1e-5 leaves room for the table interpolation of the split law), intervals
    around the truth, errors nil; the other kind of ends is a law of its own."""
    curves = [synthetic("short", 0.01, 0.9, 1.5e-3, 0.4), synthetic("long", 0.02, 0.9, 1.5e-3, 0.4),
              synthetic("lug", 0.02, 1.1, -0.5e-3, 0.2, runs_on=True),
              synthetic("short lug", 0.01, 1.1, -0.5e-3, 0.2, runs_on=True)]
    laws = sliced.calibrate(curves, LIU)
    assert set(laws) == {"flush_steel", "lug_steel"}
    flush, lug = laws["flush_steel"], laws["lug_steel"]
    assert flush.fitted_to == ["short", "long"] and lug.fitted_to == ["lug", "short lug"]
    table = sliced.per_length_table(LIU.force, curves[0])
    assert flush.scale == pytest.approx(0.9, rel=1e-5)
    assert flush.end_length_m == pytest.approx(1.5e-3, rel=1e-5)
    assert flush.bulk_compliance_m2_per_N == pytest.approx(0.4 * largest_compliance(*table), rel=1e-5)
    assert lug.scale == pytest.approx(1.1, rel=1e-5)
    assert lug.end_length_m == pytest.approx(-0.5e-3, rel=1e-5)
    assert lug.bulk_compliance_m2_per_N == pytest.approx(0.2 * largest_compliance(*table), rel=1e-5)
    assert flush.scale_ci95[0] - 1e-9 <= 0.9 <= flush.scale_ci95[1] + 1e-9
    for law in laws.values():
        for e in law.errors.values():
            assert e.force_max_rel < 1e-5 and e.moment_max_rel < 1e-5
        assert law.validity.tilt_rad[1] == pytest.approx(4e-5 / law.validity.length_m[0])


def three_d_run(folder, geometry=None):
    """A 3D curve.csv (push, then tilt) with its result.json, written through the file
    modules (no FE solve: the rules under test read files)."""
    folder.mkdir()
    data = scene_dict(geometry={"dim": 3, "length": 0.01} | (geometry or {}), mesh={"contact_size": 8e-4},
                      load={"max_approach": 1e-5, "steps": 3, "tilt_deg": 0.1, "tilt_steps": 3})
    scene = validate(FemScene, data, "test")
    (folder / "result.json").write_text(json.dumps({"scene": scene.model_dump()}))
    rows = []
    for i, (d, t) in enumerate([(3e-6, 0), (6e-6, 0), (1e-5, 0), (1e-5, .03), (1e-5, .06), (1e-5, .1)]):
        rows.append({f: 0.0 for f in curve.COLUMNS[3]} | {
            "step": i + 1, "stage": "tilt" if t else "push", "approach": d, "tilt": t,
            "force": 1e9 * d * (1 + 10 * t), "tilt_moment": 1e3 * t, "newton_iterations": 3,
            "uzawa_iterations": 1})
    curve.write(folder / "curve.csv", 3, rows)
    return folder / "curve.csv"


@pytest.mark.parametrize("geometry, extra, message", [
    ({}, [], "calibrate: no 2D curve given"),
    ({"tilt_deg": 0.01}, [], "geometry.tilt_deg: the 3D calibration reads the tilt as a load"),
])
def test_bad_3d_curves_are_one_line_exit_2(tmp_path, geometry, extra, message):
    path = three_d_run(tmp_path / "run", geometry)
    done = pinbore("calibrate", path, *extra, "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_the_planar_model_takes_the_straight_pin_force_of_a_3d_law(tmp_path):
    """normal_law = "sliced:<group>": the joint's tabulated force is the sliced sum at zero
    tilt (pinbore.laws.sliced with the group's scale and end length over the joint's length,
    the per-length law at the materials and law length it was calibrated with), whose slices
    all sit at the same approach. The reference looks Liu's law up in a
    600-point log-log table over nine decades (step 0.035 in ln d): its interpolation error,
    of order step^2/8 times the change of the local exponent, is about 1e-6; asserted 1e-5."""
    from pinbore.laws import lawsfile
    from pinbore.calibration.run import evaluate, laws_json
    from pinbore.laws import sliced as sliced_law
    from pinbore.laws import tables
    from pinbore.reduced.mechanism.model import build
    from pinbore.reduced.mechanism.scene import PlanarScene
    import test_calibration

    laws = sliced.calibrate([synthetic("short", 0.01, 0.9, 1.5e-3, 0.4),
                             synthetic("long", 0.02, 0.9, 1.5e-3, 0.4)], LIU)
    flat = [test_calibration.synthetic("liu", 1.0, 0.0)]
    data = laws_json(flat, evaluate(flat), None, [], 0.0).model_copy(update={"sliced": laws})
    lawsfile.write(tmp_path / "laws.json", data)
    scene = test_calibration.calibrated_scene(tmp_path / "laws.json")
    joint = scene["clearance_joints"][0]
    joint["normal_law"] = "sliced:flush_steel"
    model = build(PlanarScene.model_validate(scene), "test", tmp_path)
    modelled = test_calibration.joint_table(model)
    d = np.exp(model.base.grid_log0 + model.base.grid_step * np.arange(modelled.size))
    pick = np.flatnonzero(np.isfinite(modelled))[::60]
    law_joint = laws["flush_steel"].joint.joint(joint["bearing_radius"], joint["journal_radius"])
    law = laws["flush_steel"]
    table = tables.tabulate(lambda x: liu(x, law_joint), 1e-12, 1e-3, 600)
    local = tables.split_compliance(*table, law.bulk_compliance_m2_per_N)
    for i in pick:
        expected = sliced_law.sliced(d[i], 0.0, joint["length"], 16, *local, 0.0, 0.0,
                                     law.end_length_m, law.scale, law.bulk_compliance_m2_per_N)[0]
        assert np.exp(modelled[i]) == pytest.approx(expected, rel=1e-5)



def test_an_unknown_3d_law_is_one_line(write_scene, tmp_path):
    """A sliced:<group> the laws file does not hold: exit 2, one line naming the key and the
    groups there are (none: the calibration had no 3D curves)."""
    import test_calibration

    path = test_calibration.synthetic_laws_file(tmp_path)
    scene = test_calibration.calibrated_scene(path)
    scene["clearance_joints"][0]["normal_law"] = "sliced:flush_steel"
    done = pinbore("reduced", write_scene(scene), "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip()
    assert len(line.splitlines()) == 1
    assert "clearance_joints.normal_law: 'sliced:flush_steel' is not a 3D law" in line
    assert "none (no 3D curves)" in line


@pytest.mark.parametrize("tilted", [False, True])
def test_curves_of_one_length_are_refused(tilted):
    """Without tilt and with one length, F = a (L + 2 e) f_loc(delta - c_b F / L): a and e only
    through their product; with tilt they separate, but the end length, what carries the law
    to another length, is then fixed by the tilt alone (a one-length fit missed the 20 mm lug
    by 13 % in F). A group of one length is refused, one InputError line."""
    from pinbore.core.errors import InputError

    curve = synthetic("one length", 0.01, 0.9, 1.5e-3)
    n = curve.approach.size if tilted else 4
    one = Curve3D(curve.name, curve.path, curve.approach[:n], curve.tilt[:n], curve.force[:n],
                  curve.moment[:n], curve.joint, curve.length, False, None, "steel")
    with pytest.raises(InputError, match="curves of one length \\(0.01 m\\)"):
        sliced.calibrate([one, one], LIU)


def test_a_law_on_its_sections_fe_curve_holds_for_that_section_only(tmp_path):
    """A sliced law whose per-length law is the FE curve of its section (here: Liu's law at
    a few points standing in for it) applies to a joint of that section's radii; the planar
    model takes it at those radii (the long pin: a = 1, e = 0 would be f L) and refuses
    other radii in one line naming the keys (a 30 um clearance curve says nothing of a
    0.5 mm one)."""
    from pinbore.laws import lawsfile
    from pinbore.calibration.run import evaluate, laws_json
    from pinbore.core.errors import InputError
    from pinbore.reduced.mechanism.model import build
    from pinbore.reduced.mechanism.scene import PlanarScene
    import test_calibration

    points = np.geomspace(1e-6, 6e-5, 12)
    section = lawsfile.Section(curve="section", approach_m=list(points),
                               force_N_per_m=list(liu(points, JOINT)))
    per_length = sliced.PerLength("section", lambda d, c: section.force(d), lambda c: section)
    laws = sliced.calibrate([synthetic("short", 0.01, 0.9, 1.5e-3, 0.4),
                             synthetic("long", 0.02, 0.9, 1.5e-3, 0.4)], per_length)
    law = laws["flush_steel"]
    # Liu's law log-log between 12 points (ratio 1.45) differs from Liu's by its curvature,
    # a few 1e-3 at most: the fit finds the made-up a = 0.9 to that
    assert law.section == section and law.scale == pytest.approx(0.9, rel=1e-2)
    flat = [test_calibration.synthetic("liu", 1.0, 0.0)]
    data = laws_json(flat, evaluate(flat), None, [], 0.0).model_copy(update={"sliced": laws})
    lawsfile.write(tmp_path / "laws.json", data)
    scene = test_calibration.calibrated_scene(tmp_path / "laws.json")
    joint = scene["clearance_joints"][0]
    joint |= {"normal_law": "sliced:flush_steel", "bearing_radius": JOINT.r_bore,
              "journal_radius": JOINT.r_pin}
    model = build(PlanarScene.model_validate(scene), "test", tmp_path)
    assert np.isfinite(test_calibration.joint_table(model)).sum() > 100
    joint["journal_radius"] = JOINT.r_pin - 1e-5
    with pytest.raises(InputError, match="clearance_joints.bearing_radius, journal_radius: "
                                         "'sliced:flush_steel' is built on the FE curve"):
        build(PlanarScene.model_validate(scene), "test", tmp_path)
