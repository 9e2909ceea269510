"""The compiled core's multibody engine (pinbore.core.cpp.mechanism, C++) against numba's
(reduced.mechanism.engine), while the core takes the engine over body kind by body kind: on
the rigid mechanisms it runs, planar and spatial, the two are the same arithmetic, operation
by operation, so the shipped scenes and each friction law (of a point contact in the plane, of
a sliced journal's slices in space) integrate to the same bits (steps, states, impacts,
counters) and are observed alike. The physics of each is checked by the tests of
its scene and law; this holds the port to the engine those tests validated."""

import tomllib

import numpy as np
import pytest
from conftest import ROOT

from pinbore.core import cpp
from pinbore.reduced.mechanism import kernel, kinds, layout
from pinbore.reduced.mechanism.model import SPEED_FLOOR, build, fixed_step
from pinbore.reduced.mechanism.run import METHODS, onset_tolerance
from pinbore.reduced.mechanism.scene import MAX_STEPS

SCENES = ["slider_crank_flores2004", "slider_crank_flores2004_ideal", "slider_crank_flores2004_impulse",
          "slider_crank_translational", "impact_oscillator", "solar_panel_deployment",
          "solar_panel_deployment_two_panels", "deployed_panel_shaken", "spatial_slider_crank_flores",
          "spatial_slider_crank_flores_misaligned", "spatial_four_bar_spherical",
          "deployed_panel_shaken_3d", "solar_panel_deployment_3d"]
FRICTION = {
    "stribeck": {"law": "stribeck", "mu_static": 0.15, "mu_min": 0.1, "v_min": 0.05},
    "linear": {"law": "linear", "mu_static": 0.1, "alpha": 0.02},
    "lugre": {"law": "lugre", "mu_coulomb": 0.1, "mu_static": 0.15, "stribeck_speed": 1e-3,
              "sigma0": 1e5, "sigma1": 316.0, "sigma2": 0.0},
    "dahl": {"law": "dahl", "mu": 0.1, "sigma": 1e5},
    "iwan_bilinear": {"law": "iwan_bilinear", "mu": 0.1, "k1": 1e6, "k2": 1e3},
}


def both(data, source, duration):
    """The model of a scene dict and its integration by each engine over `duration`."""
    from pinbore.reduced.mechanism import engine   # noqa: PLC0415 (numba: the reference)

    model = build(kinds.validate(data, source), source, ROOT / "scenes" / "reduced")
    s = model.scene.integrator
    step = fixed_step(model) if s.method == "dopri5_fixed" else s.max_step
    fixed = (METHODS[s.method], s.rtol, s.atol, step, onset_tolerance(model), SPEED_FLOOR, MAX_STEPS)
    assert kernel.compiled(model.args())
    core = layout.Integration(*cpp.mechanism.integrate(model.y0, duration, model.args(), *fixed))
    return model, core, engine.integrate(model.y0, duration, model.args(), *fixed)


def assert_same(core, reference, contacts):
    """Every field of two integrations equal (of the per-contact ones, the contacts' columns:
    a mechanism without contacts keeps one column that holds nothing)."""
    for name in ("times", "states", "speeds", "modes", "latched", "impacts", "counters"):
        a, b = getattr(core, name), getattr(reference, name)
        if name in ("speeds", "modes"):
            a, b = a[:, :contacts], b[:, :contacts]
        assert a.shape == b.shape and np.array_equal(a, b), name
    assert (core.status, core.t_end) == (reference.status, reference.t_end)


def scene(name) -> dict:
    return tomllib.loads((ROOT / "scenes" / "reduced" / f"{name}.toml").read_text())


@pytest.mark.parametrize("name", SCENES)
def test_a_shipped_planar_scene_integrates_to_the_same_bits_in_the_core(name):
    data = scene(name)
    model, core, reference = both(data, name, min(data["duration"], 0.05))
    assert core.counters[0] > 20
    assert_same(core, reference, model.contacts.shape[0])


@pytest.mark.parametrize("kind", ["slider_crank_flores2004", "spatial_slider_crank_flores_misaligned"])
@pytest.mark.parametrize("law", FRICTION)
def test_each_friction_law_integrates_to_the_same_bits_in_the_core(law, kind):
    data = scene(kind)
    data["clearance_joints"][0]["friction"] = FRICTION[law]
    model, core, reference = both(data, law, 0.02)
    assert np.any(core.states[:, 2 * model.nq + layout.ENERGY_STATES:] != 0.0) or law in (
        "stribeck", "linear")   # the state laws carry their states
    assert_same(core, reference, model.contacts.shape[0])


@pytest.mark.parametrize("name", ["slider_crank_translational", "spatial_slider_crank_flores"])
def test_the_core_observes_the_steps_as_numbas_engine_does(name):
    """observe_steps (the outputs' pass), constraint_values, and a sliced journal's slices."""
    from pinbore.reduced.mechanism import engine   # noqa: PLC0415

    model, core, _ = both(scene(name), name, 0.01)
    dimension, kept = len(model.args().like), model.kind.bodies().RIGID_COLUMNS
    seen = {}
    for name, module in (("core", cpp.mechanism), ("numba", engine)):
        args = model.args()
        work = layout.Work(*module.workspace(args))
        n, nc = core.times.size, model.contacts.shape[0]
        arrays = [np.empty((n, core.states.shape[1])), np.empty((n, len(model.names), kept)),
                  np.empty((n, nc)), np.empty((n, nc)), np.empty((n, nc)),
                  np.zeros((n, nc, dimension)), np.empty(n), np.empty(n),
                  np.empty((n, model.torsion.shape[0])), np.empty((n, args.springs.shape[0]))]
        module.observe_steps(core.times, core.states, core.speeds, core.latched, core.modes, args,
                             work, *arrays)
        seen[name] = arrays + list(module.constraint_values(0.003, core.states[-1], args))
        for k in np.flatnonzero(model.contacts[:, layout.CONTACT_KIND] == layout.SLICED):
            slices = int(model.contacts[k, layout.CONTACT_SLICES])
            approaches, weights = np.empty(slices), np.empty(slices)
            moved = module.slice_approaches(core.states[-1], args, work, k, approaches, weights)
            seen[name] += [approaches, weights, np.array(moved)]
    assert len(seen["core"]) > 12 or dimension == 2
    for a, b in zip(seen["core"], seen["numba"], strict=True):
        assert np.array_equal(a, b)
