"""The translational clearance joint (a slider in its guide, four corner contacts), written
once for planar and spatial mechanisms, against independent references:

- statics: a slider resting on its guide's face under gravity, its centre of mass off the
  rectangle's centre by d, carries F = m g (a + d)/(2a) and m g (a - d)/(2a) at its two
  lower corners (the free-body diagram: vertical forces and moments about the centre of
  mass balance), with rigid impacts (the held contacts' multipliers) and with compliant
  corners (their elastic forces once the bouncing has died out), in the plane and in space;
- kinematics: as the clearance c -> 0 under a stiff corner law the slider-crank of
  [FloresLeineGlocker2010] follows its ideal twin (a slider on an ideal prismatic guide), its
  deviation shrinking with c;
- the energy balance closes: kinetic + potential + elastic + dissipated stays constant, and
  with neither damping nor friction nothing is dissipated.
"""

import copy
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT

from pinbore.core.scene import read_toml
from pinbore.reduced.mechanism import kinds, outputs
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.run import OK, simulate

G = 9.81
MASS, A, B, C, D = 0.076, 0.05, 0.025, 1e-3, 0.01   # slider: kg, half-length, half-width, gap, CoM offset
STEEL = {"normal_law": "hertz_point", "corner_radius": 1e-3, "E": 207e9, "nu": 0.3,
         "damping_law": "flores", "restitution": 0.4}
FLG = ROOT / "scenes/reduced/slider_crank_translational.toml"


def resting_slider(kind: str, law: dict) -> dict:
    """A lone slider dropped at 5 cm/s onto the lower face of a guide along x on the ground
    (face normal y, gravity -y); its rectangle's centre is d along its axis from its centre of
    mass (journal_point), so its lower corners carry unequal loads."""
    joint = {"name": "guide", "bearing_body": "ground", "bearing_point": [0.0, 0.0],
             "bearing_axis": [1.0, 0.0], "journal_body": "slider", "journal_point": [D, 0.0],
             "journal_axis": [1.0, 0.0], "half_length": A, "half_width": B, "clearance": C,
             "start": "placed"} | law
    body = {"name": "slider", "mass": MASS, "position": [-D, 0.0], "velocity": [0.0, -0.05]}
    scene = {"kind": kind, "duration": 0.5, "gravity": [0.0, -G], "bodies": [body],
             "translational_joints": [joint], "integrator": {"rtol": 1e-6},
             "output": {"plots": False, "sample_time": 1e-3}}
    if kind == "planar":
        body["inertia"] = 1e-4
        return scene
    for key in ("bearing_point", "bearing_axis", "journal_point", "journal_axis"):
        joint[key] = joint[key] + [0.0]
    joint["bearing_normal"] = joint["journal_normal"] = [0.0, 1.0, 0.0]
    body["position"], body["velocity"] = body["position"] + [0.0], body["velocity"] + [0.0]
    body["inertia"] = [[1e-5, 0, 0], [0, 1e-4, 0], [0, 0, 1e-4]]
    scene["gravity"] = [0.0, -G, 0.0]
    return scene


def run(data: dict, source: str = "scene", ideal: bool = False):
    scene = kinds.validate(data, source)
    model = build(scene, source, Path("."), ideal=ideal)
    trajectory = simulate(model)
    assert trajectory.status == OK
    return model, trajectory


@pytest.mark.parametrize("kind, law", [("planar", {"impact": "newton", "restitution": 0.5}),
                                       ("planar", STEEL), ("spatial", STEEL)],
                         ids=["planar-impulse", "planar-compliant", "spatial-compliant"])
def test_a_resting_slider_carries_the_free_body_diagram_forces(kind, law):
    """After 0.5 s the bouncing (e = 0.4-0.5, about ten impacts from 5 cm/s) has died out; the
    lower corners (3: end -1, 4: end +1) carry the static loads, the upper ones nothing. Rigid
    impacts: the multipliers of the held contacts are the static forces up to the drift of
    the held constraints (1e-9 relative); compliant corners: to the residual vibration of the
    damped Hertz contacts (1e-5 relative)."""
    model, trajectory = run(resting_slider(kind, law))
    cols = outputs.per_step(model, trajectory)[0]
    left, right = MASS * G * (A + D) / (2 * A), MASS * G * (A - D) / (2 * A)
    tol = 1e-9 if law.get("impact") == "newton" else 1e-5
    assert cols["guide_corner3_normal_force_N"][-1] == pytest.approx(left, rel=tol)
    assert cols["guide_corner4_normal_force_N"][-1] == pytest.approx(right, rel=tol)
    assert cols["guide_corner1_normal_force_N"][-1] == 0.0
    assert cols["guide_corner2_normal_force_N"][-1] == 0.0
    # the slider lies on the face: its centre c below the guide's axis, untilted
    assert cols["guide_offset_m"][-1] == pytest.approx(-C, abs=1e-6 if tol > 1e-9 else 1e-12)
    assert abs(cols["guide_tilt_rad"][-1]) < 1e-5


def flg(clearance: float, duration: float, **law) -> dict:
    data = read_toml(FLG)
    data["duration"] = duration
    data["output"] = {"plots": False}
    joint = data["translational_joints"][0]
    joint["clearance"] = clearance
    joint.update(law)
    return data


def slider_deviation(clearance: float) -> float:
    """The largest distance (m) between the slider's centre of mass and its ideal twin's over
    the first 20 ms (half a crank revolution), at the same times; corners elastic (Hertz,
    steel, 1 mm radius), without damping or friction, as the ideal guide is lossless."""
    data = flg(clearance, 0.02, damping_law="none", friction=None)
    model, trajectory = run(data)
    twin, ideal = run(copy.deepcopy(data), ideal=True)
    x, y = (outputs.per_step(model, trajectory)[0][f"slider_{k}_m"] for k in "xy")
    cols = outputs.per_step(twin, ideal)[0]
    x_ideal = np.interp(trajectory.times, ideal.times, cols["slider_x_m"])
    y_ideal = np.interp(trajectory.times, ideal.times, cols["slider_y_m"])
    return float(np.max(np.hypot(x - x_ideal, y - y_ideal)))


def test_a_vanishing_clearance_gives_the_ideal_prismatic_joint():
    """The slider's deviation from its ideal twin is its free play across the guide (of the
    order of c) plus the corners' elastic deflection and vibration (micrometres under the
    Hertz law at these loads): ten times less clearance gives several times less deviation
    (measured 1.2e-4 m at c = 100 um, 1.7e-5 m at 10 um), within a few c."""
    coarse, fine = slider_deviation(1e-4), slider_deviation(1e-5)
    assert fine < 0.3 * coarse
    assert fine < 3e-5


def test_the_energy_balance_closes():
    """The shipped scene (damped corners, Coulomb friction): the book's residual stays within
    1e-6 of the peak kinetic energy (the integrator's rtol 1e-6 on the energy integrals), and
    the contacts dissipate. Without damping or friction the corners only store and return
    elastic energy: nothing is dissipated and the residual stays as small."""
    model, trajectory = run(read_toml(FLG) | {"duration": 0.05, "output": {"plots": False}})
    energy = outputs.per_step(model, trajectory)[1]
    total = energy["kinetic"] + energy["potential"] + energy["elastic"] + energy["dissipated"]
    assert np.max(np.abs(total - total[0])) < 1e-6 * np.max(energy["kinetic"])
    assert energy["dissipated"][-1] > 1e-3 * np.max(energy["kinetic"])
    model, trajectory = run(flg(C, 0.05, damping_law="none", friction=None))
    energy = outputs.per_step(model, trajectory)[1]
    total = energy["kinetic"] + energy["potential"] + energy["elastic"]
    assert np.max(np.abs(total - total[0])) < 1e-6 * np.max(energy["kinetic"])
    assert abs(energy["dissipated"][-1]) < 1e-9 * np.max(energy["kinetic"])
    assert not math.isnan(total[-1])
