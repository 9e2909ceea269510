"""The restitution study's elasto-plastic joint (steel pin in an annealed 6061-O bore,
c = 0.5 mm) against Hertz–Johnson first yield: its slowest impact stays elastic."""

import json
import math
from pathlib import Path

import pytest
from conftest import effective_modulus, pinbore

STUDY = Path(__file__).parent.parent / "studies/restitution.toml"
POINT = "study_steel_al6061o_c500um_v0100mm_s"


def hertz_first_yield_force(scene: dict) -> float:
    """The line load (N/m) at which a Hertzian line contact first yields: p0 = 1.79 Y for von
    Mises at nu ~ 0.3 [Johnson1985] (sec. 6.2), p0 = sqrt(P E* / (pi R*)), so
    P = pi R* (1.79 Y)^2 / E*, with 1/R* = 1/R_pin - 1/R_bore (a pin in a bore)."""
    g = scene["geometry"]
    relative = 1 / (1 / g["pin_radius"] - 1 / g["bore_radius"])
    p0 = 1.79 * scene["materials"]["bore"]["yield_stress"]
    return math.pi * relative * p0**2 / effective_modulus(scene)


@pytest.mark.slow
def test_slowest_impact_stays_elastic(tmp_path):
    """At 0.1 m/s the peak force (19 kN/m measured) lies far below the Hertz first-yield
    load (100 kN/m; the FE first yields at 0.85 of it on the default mesh, see
    tests/test_fem_plasticity.py), so no point flows: no plastic work, no plastic strain.
    About 15 s."""
    from pinbore.study import point_scene

    scene = point_scene(STUDY, POINT, tmp_path / "scene.toml")
    done = pinbore("impact", tmp_path / "scene.toml", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "out" / "impact.json").read_text())
    assert result["peak_force_N_per_m"] < 0.85 * hertz_first_yield_force(scene)
    assert result["energy"]["plastic_J_per_m"] == 0.0
    assert result["max_plastic_strain"] == 0.0
