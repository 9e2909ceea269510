"""pinbore's calibrated law in another multibody code: the Flores slider-crank built in Exudyn
[Gerstmayr2023] (its own bodies, joints, drive and implicit integrator) with the rod-slider
clearance joint of `pinbore export --to exudyn` (its tables and pinbore_exudyn.py) gives the
first impact of pinbore's own run of the same scene: peak within 1 %, onset speed within
0.1 %. Exudyn is an optional extra (requirements.lock installs it); skipped without it."""

import math
import sys

import numpy as np
import pytest
import tomli_w
from conftest import pinbore
from test_calibration import JOINT, calibrated_scene, synthetic_laws_file

from pinbore.reduced.mechanism import kinds, outputs
from pinbore.reduced.mechanism.layout import LOG_RATE
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.run import simulate

exu = pytest.importorskip("exudyn")
STEP = 5e-7   # s, Exudyn's fixed step: the first peak changes by < 1e-3 when it is halved


def exudyn_slider_crank(scene, law_folder):
    """The slider-crank of `scene` (crank, rod, slider on the x axis, the crank driven at its
    constant speed from angle 0, the rod-slider journal centred, velocities of the ideal
    joint) in Exudyn; its clearance joint from the exported law. (system container, contact)."""
    from exudyn.itemInterface import (CoordinateConstraint, LoadMassProportional, MarkerBodyMass,
                                      MarkerBodyPosition, MarkerNodeCoordinate, NodePointGround,
                                      NodeRigidBody2D, ObjectGround, ObjectJointRevolute2D,
                                      ObjectRigidBody2D)
    sys.path.insert(0, str(law_folder))
    from pinbore_exudyn import ExportedLaw, accept, add_revolute_clearance

    bodies = {b.name: b for b in scene.bodies}
    r = 2 * bodies["crank"].position[0]          # crank length: its centre halfway
    l = 2 * (bodies["rod"].position[0] - r)      # rod length
    w = scene.drive.speed_rpm * 2 * math.pi / 60
    w_rod = -w * r / l                           # the rod's end on the slider does not move in y
    start = {"crank": ([r / 2, 0, 0], [0, w * r / 2, w]),
             "rod": ([r + l / 2, 0, 0], [0, w * r + w_rod * l / 2, w_rod]),
             "slider": ([r + l, 0, 0], [0, 0, 0])}
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    fixed = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    node, body = {}, {}
    for name, (position, velocity) in start.items():
        node[name] = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=position, initialVelocities=velocity))
        body[name] = mbs.AddObject(ObjectRigidBody2D(mass=bodies[name].mass, inertia=bodies[name].inertia,
                                                     nodeNumber=node[name]))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=body[name])),
                                         loadVector=[*scene.gravity, 0]))

    def point(b, x):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[x, 0, 0]))

    def coordinate(name, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node[name], coordinate=k))

    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[point(ground, 0), point(body["crank"], -r / 2)]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[point(body["crank"], r / 2), point(body["rod"], -l / 2)]))
    for k in (1, 2):   # the slider's y and angle held: the prismatic joint along x
        mbs.AddObject(CoordinateConstraint(markerNumbers=[fixed, coordinate("slider", k)]))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[fixed, coordinate("crank", 2)],
                                       offsetUserFunction=lambda mbs, t, i, offset: w * t,
                                       offsetUserFunction_t=lambda mbs, t, i, offset: w))
    contact = add_revolute_clearance(mbs, point(body["slider"], 0), point(body["rod"], l / 2),
                                     ExportedLaw(law_folder))
    mbs.Assemble()
    accept(mbs, 0.0)
    return sc, mbs, contact


def first_peak(times, force):
    """(time, N) of the first contact interval's largest force, refined by the parabola
    through it and its neighbours (Exudyn's accepted steps)."""
    on = np.flatnonzero(force > 0)
    start = on[0]
    end = start + int(np.argmin(force[start:] > 0))
    k = start + int(np.argmax(force[start:end]))
    a, b, c = force[k - 1:k + 2]
    x = 0.5 * (a - c) / (a - 2 * b + c)
    return times[k] + x * (times[k + 1] - times[k]), b - 0.25 * (a - c) * x


def test_the_exported_law_in_exudyn_gives_pinbores_first_impact(tmp_path):
    laws = synthetic_laws_file(tmp_path)
    data = calibrated_scene(laws) | {"duration": 4e-4}
    (tmp_path / "scene.toml").write_text(tomli_w.dumps(data))
    done = pinbore("export", laws, "--to", "exudyn", "--scene", tmp_path / "scene.toml",
                   "--out", tmp_path / "exudyn")
    assert done.returncode == 0, done.stderr

    scene = kinds.load(tmp_path / "scene.toml")
    model = build(scene, "scene", tmp_path)
    run = simulate(model)
    force = np.asarray(outputs.per_step(model, run)[0]["rod_slider_normal_force_N"])
    start = int(np.argmax(force > 0))
    end = start + int(np.argmin(force[start:] > 0))
    peak_force, peak_time = outputs.refined_peak(model, 0, run, start + int(np.argmax(force[start:end])))
    onset_speed = run.impacts[0, LOG_RATE]

    sc, mbs, contact = exudyn_slider_crank(scene, tmp_path / "exudyn")
    settings = exu.SimulationSettings()
    settings.timeIntegration.endTime = run.times[end] + 2e-5
    settings.timeIntegration.numberOfSteps = int(round(settings.timeIntegration.endTime / STEP))
    settings.timeIntegration.adaptiveStep = False
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.newton.useModifiedNewton = False   # the contact stiffens fast
    settings.timeIntegration.generalizedAlpha.spectralRadius = 1.0   # no numerical damping
    settings.solution.file.write = False
    mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    history = np.asarray(contact.history)
    time, peak = first_peak(history[:, 0], history[:, 4])
    assert JOINT.clearance == pytest.approx(50e-6)
    assert peak == pytest.approx(peak_force, rel=1e-2)
    assert abs(time - peak_time) < 2 * STEP
    assert history[history[:, 4] > 0][0, 3] == pytest.approx(onset_speed, rel=1e-3)
