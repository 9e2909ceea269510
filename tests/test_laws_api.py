"""The calibrated laws for a Python user (pinbore.laws.load) and for another multibody code
(pinbore export): against the synthetic truth the laws were calibrated on, an impact
integrated here (scipy) that must rebound with the FE impacts' e(v0), and the multibody
model's own table."""

import csv
import json
import math
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from conftest import ROOT, pinbore
from scipy.integrate import solve_ivp
from test_calibration import (APPROACH, JOINT, calibrated_scene, joint_table, synthetic,
                              synthetic_laws_file)

import pinbore.laws as pinbore_laws   # pinbore.laws.load; `pinbore` is the command (conftest)
from pinbore.calibration.run import evaluate, laws_json
from pinbore.laws import lawsfile
from pinbore.laws.elastic import Joint
from pinbore.laws.lawsfile import law_force
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.scene import PlanarScene

REFERENCE = float(np.exp(np.mean(np.log(APPROACH))))   # d_ref of the synthetic fit
E0, E1 = 0.85, -0.04   # e(v0) = E0 + E1 ln(v0 / 1 m/s), the restitution law below
SPEEDS = (0.1, 5.0)    # m/s, its range


def truth(d):
    """The synthetic curves' law, F = L 1.37 P_liu(d) (d/d_ref)^-0.12 (N)."""
    return JOINT.length * 1.37 * law_force("liu", d, JOINT) * (d / REFERENCE) ** -0.12


def with_restitution(folder):
    """The synthetic laws file with a restitution law of JOINT: e(v0) = E0 + E1 ln v0."""
    path = synthetic_laws_file(folder)
    data = json.loads(path.read_text())
    joint = lawsfile.ImpactJoint(pin_E_Pa=JOINT.E_pin, pin_nu=JOINT.nu_pin, pin_density_kg_per_m3=7800,
                                 bore_E_Pa=JOINT.E_bore, bore_nu=JOINT.nu_bore,
                                 bore_density_kg_per_m3=7800, pin_radius_m=JOINT.r_pin,
                                 bore_radius_m=JOINT.r_bore, pin_mass_kg_per_m=2.4)
    points = [lawsfile.ImpactPoint(name=f"v{v}", speed_m_per_s=v, restitution=E0 + E1 * math.log(v),
                                   fitted=E0 + E1 * math.log(v), contact_duration_s=1e-5,
                                   peak_force_N_per_m=1e5, max_approach_m=1e-6,
                                   pin_mass_kg_per_m=2.4, clearance_m=JOINT.clearance,
                                   effective_modulus_Pa=JOINT.e_star, plastic=False)
              for v in SPEEDS]
    law = lawsfile.RestitutionLaw(model=lawsfile.RESTITUTION_MODEL, joint=joint,
                                  coefficients=[E0, E1], speed_range_m_per_s=list(SPEEDS),
                                  max_fit_error=0.0, impacts=points)
    data["restitution"] = {joint.key(): law.model_dump()}
    path.write_text(json.dumps(data))
    return path


def rebound(law, mass, speed):
    """e of one impact of a mass (kg) at `speed` (m/s) on the law, integrated here:
    m d'' = -F(d, d'), from d = 0 to the return to d = 0."""
    def f(t, y):
        return [y[1], -float(law(max(y[0], 1e-15), y[1], speed)) / mass]

    def out(t, y):
        return y[0]
    out.terminal, out.direction = True, -1
    period = math.pi * math.sqrt(mass * 1e-6 / float(law(1e-6)))   # half a period, roughly
    run = solve_ivp(f, (0, 50 * period), [0.0, speed], events=out, rtol=1e-11, atol=1e-16,
                    method="DOP853", first_step=period * 1e-4)
    return -run.y_events[0][0][1] / speed


def test_a_loaded_law_is_the_law_the_curves_were_made_of(tmp_path):
    """The file's one joint is the curve's, its length 0.02 m; F = L P_calibrated(d), zero
    without contact, a warning beyond the fitted approaches."""
    laws = pinbore_laws.load(synthetic_laws_file(tmp_path))
    law = laws["liu"]
    assert law.joint == JOINT and law.damping == "none"
    d = np.geomspace(APPROACH[0], APPROACH[-1], 7)
    np.testing.assert_allclose(law(d), truth(d), rtol=1e-12)
    assert law(-1e-6) == 0 and law(0.0) == 0
    assert law.approach_range_m == (APPROACH[0], APPROACH[-1])
    with pytest.warns(UserWarning, match="extrapolated"):
        law(3 * APPROACH[-1])


@pytest.mark.parametrize("speed", [0.2, 1.0, 3.0])
def test_the_calibrated_damping_rebounds_with_the_impacts_restitution(tmp_path, speed):
    """Damping "calibrated" (the file has a restitution law of the joint): an impact at v0
    rebounds with e(v0) = E0 + E1 ln v0, whatever the elastic law (the Hunt-Crossley factor
    of laws.dissipative.hysteresis_for_restitution is exact); integrated to 1e-11, the
    rebound is within 1e-6."""
    law = pinbore_laws.load(with_restitution(tmp_path))["liu"]
    assert law.damping == "calibrated"
    assert rebound(law, 0.05, speed) == pytest.approx(E0 + E1 * math.log(speed), abs=1e-6)


def test_a_published_damping_takes_its_restitution(tmp_path):
    """Lankarani-Nikravesh chi = 3 (1 - e^2) / 4; it needs e; an unknown damping is named."""
    path = synthetic_laws_file(tmp_path)
    law = pinbore_laws.load(path, damping="lankarani_nikravesh", restitution=0.9)["liu"]
    assert law.chi(2.0) == pytest.approx(0.75 * (1 - 0.81), rel=1e-12)
    d, rate, v0 = 5e-6, -0.3, 2.0   # separating: the force drops by chi d'/v0
    assert law(d, rate, v0) == pytest.approx(truth(d) * (1 + 0.1425 * rate / v0), rel=1e-12)
    with pytest.raises(ValueError, match="needs e in"):
        pinbore_laws.load(path, damping="lankarani_nikravesh")
    with pytest.raises(ValueError, match="damping: 'viscous' is unknown"):
        pinbore_laws.load(path, damping="viscous")
    with pytest.raises(ValueError, match="impact_speed"):
        law(d, rate)


def test_a_file_of_several_joints_needs_the_joint(tmp_path):
    curves = [synthetic("liu", 1.37, -0.12),
              replace(synthetic("liu", 1.37, -0.12), joint=Joint(10e-3, 9.9e-3, 210e9, 0.3, 210e9, 0.3, 0.02))]
    path = tmp_path / "laws.json"
    lawsfile.write(path, laws_json(curves, evaluate(curves), None, [], 0.0))
    with pytest.raises(ValueError, match="the curves hold 2 joints"):
        pinbore_laws.load(path)
    law = pinbore_laws.load(path, joint=JOINT)["liu"]
    assert law.joint == JOINT


def test_importing_a_law_does_not_load_the_laws_file():
    code = ("import sys, pinbore.laws.elastic; "
            "assert 'pinbore.laws.contact' not in sys.modules; "
            "import pinbore.laws; assert callable(pinbore.laws.load)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


# ---- pinbore export
def read_table(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], float)


def test_the_exported_table_is_the_multibody_models(tmp_path):
    """For a mechanism scene's joint, the exported force is the engine's table, row for row,
    and the damping its Lankarani-Nikravesh chi; between rows, log-log interpolation of the
    table gives the law within h^2/8 max|dn/d ln d| (h the rows' step in ln d, n the law's
    local exponent, which changes by less than 0.2 per unit of ln d for Liu's law here)."""
    laws_path = synthetic_laws_file(tmp_path)
    scene = tmp_path / "scene.toml"
    import tomli_w
    scene.write_text(tomli_w.dumps(calibrated_scene(laws_path)))
    done = pinbore("export", laws_path, "--to", "table", "--scene", scene, "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    header, table = read_table(tmp_path / "out" / "liu.csv")
    assert header == ["approach_m", "force_N"]
    model = build(PlanarScene.model_validate(calibrated_scene(laws_path)), "test", tmp_path)
    engine = np.exp(joint_table(model))
    np.testing.assert_allclose(table[:, 1], engine[:table.shape[0]], rtol=1e-12)
    np.testing.assert_allclose(table[:, 1], truth(table[:, 0]), rtol=1e-10)
    middle = np.sqrt(table[1:, 0] * table[:-1, 0])
    between = np.sqrt(table[1:, 1] * table[:-1, 1])   # log-log interpolation at the middles
    inside = (middle > APPROACH[0]) & (middle < 0.1 * JOINT.r_pin)
    h = math.log(table[1, 0] / table[0, 0])
    assert np.max(np.abs(between[inside] / truth(middle[inside]) - 1)) < h**2 / 8 * 0.2
    _, damping = read_table(tmp_path / "out" / "damping.csv")
    assert damping[:, 1] == pytest.approx(0.75 * (1 - 0.9**2), rel=1e-12)
    described = json.loads((tmp_path / "out" / "export.json").read_text())
    assert described["joint"]["length_m"] == JOINT.length
    assert described["laws"]["liu"]["fitted_approach_m"] == [APPROACH[0], APPROACH[-1]]


def test_export_without_a_scene_writes_every_law_of_the_files_joint(tmp_path):
    done = pinbore("export", with_restitution(tmp_path), "--to", "exudyn", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    names = set(pinbore_laws.load(with_restitution(tmp_path)))
    assert {p.stem for p in (tmp_path / "out").glob("*.csv")} == names | {"damping"}
    assert (tmp_path / "out" / "pinbore_exudyn.py").exists()
    _, damping = read_table(tmp_path / "out" / "damping.csv")
    speeds = damping[:, 0]
    assert speeds[0] == pytest.approx(SPEEDS[0]) and speeds[-1] == pytest.approx(SPEEDS[1])
    np.testing.assert_allclose(damping[:, 2], E0 + E1 * np.log(speeds), rtol=1e-12)


@pytest.mark.parametrize("extra, message", [
    (["--law", "foo"], "--law: 'foo' is not a fitted law"),
    (["--joint", "rod"], "--joint: names a clearance joint of --scene"),
    (["--scene", ROOT / "scenes/reduced/slider_crank_flores2004.toml"],
     "normal_law: 'hertz_point' is not a fitted law"),
    (["--scene", ROOT / "scenes/reduced/slider_crank_flores2004.toml", "--joint", "crank"],
     "--joint: 'crank' is not a revolute clearance joint of the scene; valid: rod_slider"),
    (["--scene", ROOT / "scenes/reduced/spatial_slider_crank_flores.toml"],
     "--scene: a planar mechanism"),
    (["--scene", ROOT / "scenes/reduced/slider_crank_flores2004.toml", "--law", "liu"],
     "clearance_joints.rod_slider.length: the joint needs its axial length"),
])
def test_bad_export_is_one_line_exit_2(tmp_path, extra, message):
    done = pinbore("export", synthetic_laws_file(tmp_path), "--to", "table", "--out",
                   tmp_path / "out", *extra)
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()


# a laws file's records are checked on read with ranges the laws can take (a table that was
# its header alone, NaN forces, or a traceback came out of these)
CORRUPT = [("laws", {}, "no fitted law to export"),
           ("laws.liu.fitted.scale", float("nan"), "laws.liu.fitted.scale"),
           ("laws.liu.fitted.scale", 0.0, "laws.liu.fitted.scale"),
           ("laws.liu.fitted.scale", -1.0, "laws.liu.fitted.scale"),
           ("laws.liu.fitted.exponent_correction", 50.0, "laws.liu.fitted.exponent_correction"),
           ("laws.liu.fitted.reference_approach_m", -1e-6, "laws.liu.fitted.reference_approach_m"),
           ("curves.0.joint.E_bore", -2e11, "curves.0.joint.E_bore"),
           ("curves.0.joint.length", 0.0, "curves.0.joint.length"),
           ("curves.0.joint.r_pin", 1.0, "r_pin 1 m must be smaller than r_bore")]


@pytest.mark.parametrize("key, value, message", CORRUPT, ids=[c[0] + "=" + str(c[1]) for c in CORRUPT])
def test_a_laws_file_out_of_range_is_one_line_exit_2(tmp_path, key, value, message):
    path = synthetic_laws_file(tmp_path)
    data = json.loads(path.read_text())
    *parents, last = key.split(".")
    place = data
    for part in parents:
        place = place[int(part)] if part.isdigit() else place[part]
    place[last] = value
    path.write_text(json.dumps(data))
    done = pinbore("export", path, "--to", "table", "--out", tmp_path / "out")
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and not (tmp_path / "out").exists()
    if key != "laws":   # the Python API refuses the file alike
        from pinbore.core.errors import InputError

        with pytest.raises(InputError, match=message.split(" ")[0]):
            pinbore_laws.load(path)


def test_an_output_of_another_command_is_not_replaced(tmp_path):
    """A folder `pinbore modes` wrote (its marker names the command) is not replaced by
    `pinbore export` (it had replaced the reduced body): one line, exit 2, the body kept;
    the command that wrote it may write it again."""
    folder = tmp_path / "modes"
    folder.mkdir()
    (folder / ".pinbore-output").write_text("Written by pinbore.\ncommand: modes\n")
    (folder / "body.npz").write_bytes(b"body")
    done = pinbore("export", synthetic_laws_file(tmp_path), "--to", "table", "--out", folder)
    assert done.returncode == 2 and "holds the output of pinbore modes" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and (folder / "body.npz").read_bytes() == b"body"
    out = tmp_path / "table"
    for _ in range(2):   # its own output, twice
        assert pinbore("export", synthetic_laws_file(tmp_path), "--to", "table", "--out", out).returncode == 0
    assert "command: export" in (out / ".pinbore-output").read_text()
