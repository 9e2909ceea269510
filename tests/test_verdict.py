"""No garbage reported as complete: a reduced run that breaks a rule of physics (energy balance,
dissipation >= 0, penetration within the clearance, friction within its law, closed joints)
is `suspect`, says why in one line and exits 1; the shipped scenes are clean."""

import copy
import json
import tomllib

import pytest
from conftest import ROOT, pinbore

from pinbore.core.scene import referenced_files
from pinbore.reduced.mechanism import kinds, verdict
from pinbore.reduced.mechanism.scene import PlanarScene
from pinbore.reduced.mechanism.summary import Summary

FLORES = tomllib.loads((ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml").read_text())


def flores(edit=None):
    data = copy.deepcopy(FLORES)
    if edit:
        edit(data)
    return data


# runs that end normally with numbers that are not physical (the cases a tester found)
SUSPECT = [
    (lambda d: d["integrator"].update(rtol=1e-3), "energy residual", "tighten integrator.rtol"),
    (lambda d: d["integrator"].update(method="dopri5_fixed", fixed_step=1e-4), "energy residual",
     "shorten integrator.fixed_step"),
    (lambda d: d["clearance_joints"][0].update(E=1e9), "penetration", "times the clearance"),
]


@pytest.mark.parametrize("edit, rule, words", SUSPECT, ids=[s[1] + "-" + s[2][:12] for s in SUSPECT])
def test_an_unphysical_run_is_suspect(write_scene, tmp_path, edit, rule, words):
    out = tmp_path / "out"
    done = pinbore("reduced", write_scene(flores(edit)), "--out", out)
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "suspect:" in lines[0] and rule in lines[0] and words in lines[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "suspect" and any(rule in r for r in summary["verdict"])


def shipped_scenes():
    """The shipped mechanism scenes; those with flexible bodies (seconds to a minute each, and
    their modes made by `make modes`) marked slow."""
    for path in sorted((ROOT / "scenes" / "reduced").glob("*.toml")):
        flexible = "modes_file" in path.read_text()
        yield pytest.param(path.stem, marks=[pytest.mark.slow] if flexible else [])


@pytest.mark.parametrize("name", list(shipped_scenes()))
def test_shipped_scenes_are_clean(name, tmp_path):
    """At their own tolerances every shipped scene passes every rule (a scene whose files,
    the laws file or a modes file, `make` builds is checked when they are there: make runs
    every shipped scene and stops on a suspect one)."""
    scene = ROOT / "scenes" / "reduced" / f"{name}.toml"
    missing = [str(f) for f in referenced_files(scene) if not f.exists()]
    if missing:
        pytest.skip(f"needs {', '.join(missing)} (made by make)")
    done = pinbore("reduced", scene, "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["status"] == "complete" and summary["verdict"] == []


def test_default_fixed_step_is_clean(write_scene, tmp_path):
    """dopri5_fixed without a step takes 1/300 of the contact period 2 pi sqrt(m/k) (47.5 us
    here): clean verdict, and the first impact's peak force within 1 % of a tightly
    tolerated adaptive run's (the fixed step lands anywhere against the onset; its error
    scatters with that phase, 0.2 % at most over five steps near T/300)."""
    peaks = []
    for integrator in ({"method": "dopri5_fixed"}, {"rtol": 1e-8, "atol": 1e-11}):
        out = tmp_path / integrator.get("method", "adaptive")
        done = pinbore("reduced", write_scene(flores(lambda d: d.update(
            duration=0.001, integrator=integrator, output={"plots": False}))), "--out", out)
        assert done.returncode == 0, done.stderr
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "complete" and summary["verdict"] == []
        peaks.append(summary["clearance_joints"]["rod_slider"]["peak_normal_force_N"])
    assert abs(peaks[0] / peaks[1] - 1) < 0.01, peaks


def summary_with(**changes) -> Summary:
    """A clean summary of the Flores scene, with `changes` applied (dotted keys)."""
    data = {"model": "planar", "coordinates": kinds.KINDS["planar"].coordinates,
            "status": "complete", "stop": None, "duration_s": 0.048, "time_reached_s": 0.048,
            "integrator": "dopri5", "impacts": 10, "steps": 100, "rejected_steps": 1,
            "rhs_evaluations": 700, "wall_time_s": 0.1, "warnings": [], "scene_file": "x.toml",
            "clearance_joints": {"rod_slider": {
                "peak_normal_force_N": 4e4, "time_of_peak_s": 2.5e-4, "impacts": 10,
                "peak_impact_speed_m_per_s": 4.0, "peak_impulse_N_s": 0.0,
                "peak_penetration_m": 8e-5, "peak_friction_force_N": 0.0, "clearance_m": 5e-4}},
            "energy_balance": {"max_residual_J": 1e-2, "relative_to_peak_kinetic": 1e-4,
                               "dissipated_J": 2.0, "work_in_J": 3.0},
            "constraint_drift_max": 1e-9}
    for key, value in changes.items():
        *path, last = key.split(".")
        target = data
        for part in path:
            target = target[part]
        target[last] = value
    return Summary.model_validate(data)


def scene_with_friction(friction):
    data = flores()
    if friction:
        data["clearance_joints"][0]["friction"] = friction
    return PlanarScene.model_validate(data)


COULOMB = {"law": "coulomb_ambrosio", "mu": 0.1}
STRIBECK = {"law": "stribeck", "mu_static": 0.15, "mu_min": 0.10, "v_min": 0.05}
LINEAR = {"law": "linear", "mu_static": 0.1, "alpha": 1.0}

RULES = [   # (summary changes, friction table, the phrase of the broken rule, or None: clean)
    ({}, None, None),
    ({"energy_balance.relative_to_peak_kinetic": 0.02}, None, "energy residual"),
    ({"energy_balance.relative_to_peak_kinetic": float("nan")}, None, "energy residual"),
    ({"energy_balance.dissipated_J": -122.0}, None, "negative dissipated energy"),
    ({"energy_balance.dissipated_J": -1e-3}, None, None),   # within the residual: round-off
    ({"clearance_joints.rod_slider.peak_penetration_m": 9.3e-4}, None, "penetration 1.86 times"),
    ({"clearance_joints.rod_slider.peak_friction_force_N": 4e3}, COULOMB, None),   # mu = 0.1 exactly
    ({"clearance_joints.rod_slider.peak_friction_force_N": 6e3}, COULOMB, "above the law's largest coefficient 0.1"),
    ({"clearance_joints.rod_slider.peak_friction_force_N": 1.708e7}, STRIBECK, "friction force 427 times"),
    ({"clearance_joints.rod_slider.peak_friction_force_N": 1e5}, LINEAR, None),   # no bound
    ({"constraint_drift_max": 1e-2}, None, "constraint drift"),
]


@pytest.mark.parametrize("changes, friction, phrase", RULES, ids=range(len(RULES)))
def test_each_rule(changes, friction, phrase):
    found = verdict.reasons(summary_with(**changes), scene_with_friction(friction))
    if phrase is None:
        assert found == []
    else:
        assert len(found) == 1 and phrase in found[0]


def test_a_complete_summary_with_a_number_that_is_not_finite_does_not_read(tmp_path):
    """A summary.json edited to a NaN peak while it says complete (a run that writes NaN is
    judged suspect or incomplete) is refused on read, naming the file: the report and the
    studies never show it as a result."""
    from pinbore.core.errors import InputError
    from pinbore.reduced.mechanism import summary as summary_file

    path = tmp_path / "summary.json"
    summary_file.write(path, summary_with())
    assert summary_file.read(path).status == "complete"
    summary_file.write(path, summary_with(**{"clearance_joints.rod_slider.peak_normal_force_N": float("nan")}))
    with pytest.raises(InputError, match="not a finite number"):
        summary_file.read(path)
