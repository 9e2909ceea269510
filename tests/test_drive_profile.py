"""A drive that follows a prescribed angle: the smooth spin-up [SimoVuQuoc1986] and a table of
angles. A bar pinned at one end and driven about the pin, no gravity: its angle is the
profile's theta(t), and the drive's work is the bar's kinetic energy J_O theta'^2 / 2 at every
instant (J_O = J_c + m d^2 about the pin), planar and spatial."""

import math

import numpy as np
import pytest
from conftest import simulated

from pinbore.core.errors import InputError
from pinbore.reduced.mechanism import layout
from pinbore.reduced.mechanism.scene import PlanarScene

MASS, LENGTH = 2.0, 1.0                  # kg, m: a bar pinned at one end
J_C = MASS * LENGTH ** 2 / 12            # kg m^2 about its centre
J_O = J_C + MASS * (LENGTH / 2) ** 2     # about the pin
OMEGA_S, T_S = 6.0, 1.5                  # rad/s, s


def spin_up_exact(t):
    """theta, theta', theta'' of the spin-up, written out here from its definition."""
    t = np.asarray(t, float)
    w = 2 * np.pi / T_S
    during = t < T_S
    theta = np.where(during, OMEGA_S / T_S * (t ** 2 / 2 + (np.cos(w * t) - 1) / w ** 2),
                     OMEGA_S * (t - T_S / 2))
    rate = np.where(during, OMEGA_S / T_S * (t - np.sin(w * t) / w), OMEGA_S)
    return theta, rate


def test_the_spin_up_is_smooth_and_reaches_its_speed():
    """The compiled profile against its definition, and its rate and acceleration against
    central differences of it; the acceleration is zero at both ends of the spin-up (the
    profile's point: no jerk at the start, none when the speed is reached)."""
    from pinbore.core.cpp.mechanism import spin_up

    t = np.linspace(0.0, 2 * T_S, 601)
    values = np.array([spin_up(x, OMEGA_S, T_S) for x in t])
    theta, rate = spin_up_exact(t)
    assert np.allclose(values[:, 0], theta, atol=1e-14) and np.allclose(values[:, 1], rate, atol=1e-14)
    h = 1e-5
    for x in (0.1, 0.7, T_S - 0.01, T_S + 0.3):
        plus, minus = spin_up(x + h, OMEGA_S, T_S), spin_up(x - h, OMEGA_S, T_S)
        assert (plus[0] - minus[0]) / (2 * h) == pytest.approx(spin_up(x, OMEGA_S, T_S)[1], abs=1e-8)
        assert (plus[1] - minus[1]) / (2 * h) == pytest.approx(spin_up(x, OMEGA_S, T_S)[2], abs=1e-8)
    assert spin_up(0.0, OMEGA_S, T_S)[2] == 0.0 and spin_up(T_S, OMEGA_S, T_S) == (
        pytest.approx(OMEGA_S * T_S / 2), OMEGA_S, 0.0)


def planar_bar(drive, duration=2 * T_S):
    return {"kind": "planar", "duration": duration, "gravity": [0.0, 0.0],
            "bodies": [{"name": "bar", "mass": MASS, "inertia": J_C, "position": [LENGTH / 2, 0.0]}],
            "joints": [{"type": "revolute", "body_i": "ground", "point_i": [0.0, 0.0],
                        "body_j": "bar", "point_j": [-LENGTH / 2, 0.0]}],
            "drive": {"body": "bar"} | drive,
            "integrator": {"rtol": 1e-10, "atol": 1e-12}, "output": {"plots": False}}


def spatial_bar(drive, duration=2 * T_S):
    return {"kind": "spatial", "duration": duration, "gravity": [0.0, 0.0, 0.0],
            "bodies": [{"name": "bar", "mass": MASS, "position": [LENGTH / 2, 0.0, 0.0],
                        "inertia": np.diag([1e-3, J_C, J_C]).tolist()}],
            "joints": [{"name": "pin", "type": "revolute", "body_i": "ground", "point_i": [0, 0, 0],
                        "axis_i": [0, 0, 1], "body_j": "bar", "point_j": [-LENGTH / 2, 0, 0],
                        "axis_j": [0, 0, 1]}],
            "drive": {"joint": "pin"} | drive,
            "integrator": {"rtol": 1e-10, "atol": 1e-12}, "output": {"plots": False}}


def bar_motion(model, trajectory):
    """The bar's angle (from its position: the far end's direction) and the drive's work."""
    nq = model.nq
    y = trajectory.states
    x, yy = y[:, 0], y[:, 1]   # its centre (both kinds: the first body's first coordinates)
    angle = np.unwrap(np.arctan2(yy, x))
    return angle, y[:, 2 * nq + layout.WORK_IN]


@pytest.mark.parametrize("bar", [planar_bar, spatial_bar])
def test_a_spun_up_bar_follows_the_profile_and_takes_its_inertias_work(bar):
    """The bar turns through theta(t) (1e-7 rad) and the drive has done J_O theta'^2 / 2 of
    work (1e-7 of the final energy), through the spin-up and at constant speed after it."""
    model, trajectory = simulated(bar({"speed_rpm": OMEGA_S * 60 / (2 * math.pi), "spin_up_s": T_S}))
    angle, work = bar_motion(model, trajectory)
    theta, rate = spin_up_exact(trajectory.times)
    final = 0.5 * J_O * OMEGA_S ** 2
    assert np.abs(angle - theta).max() < 1e-7
    assert np.abs(work - 0.5 * J_O * rate ** 2).max() < 1e-7 * final


@pytest.mark.parametrize("bar", [planar_bar, spatial_bar])
def test_a_table_follows_a_cubic_motion_exactly(bar):
    """A table sampled from theta = a t^3 + b t (deg) at six times: the spline (not-a-knot)
    is that cubic, so the bar's angle and the drive's work are the cubic's to the
    integrator's tolerance (the bar starts at the table's rate: the initial state is made
    consistent with the drive); after the table the bar runs on at its last rate."""
    a, b = 20.0, 30.0   # deg/s^3, deg/s
    times = np.linspace(0.0, 1.0, 6)
    table = [[float(t), float(a * t ** 3 + b * t)] for t in times]
    model, trajectory = simulated(bar({"angle_table": table}, duration=1.5))
    angle, work = bar_motion(model, trajectory)
    t = trajectory.times
    during = t <= 1.0
    theta = np.radians(np.where(during, a * t ** 3 + b * t, a + b + (3 * a + b) * (t - 1.0)))
    rate = np.radians(np.where(during, 3 * a * t ** 2 + b, 3 * a + b))
    assert np.abs(angle - theta).max() < 1e-7
    # the bar starts at the table's rate b (the initial state is made consistent with the
    # drive, no work done): the drive's work is the energy gained since
    gained = 0.5 * J_O * (rate ** 2 - rate[0] ** 2)
    assert rate[0] == pytest.approx(math.radians(b))
    assert np.abs(work - gained).max() < 1e-7 * 0.5 * J_O * rate.max() ** 2


@pytest.mark.parametrize("drive, message", [
    ({"speed_rpm": 10.0, "angle_table": [[0.0, 0.0], [1.0, 5.0]]}, "give speed_rpm"),
    ({}, "give speed_rpm"),
    ({"spin_up_s": 2.0, "angle_table": [[0.0, 0.0], [1.0, 5.0]]}, "spin_up_s: the spin-up reaches speed_rpm"),
    ({"angle_table": [[0.5, 0.0], [1.0, 5.0]]}, "the first (0, 0)"),
    ({"angle_table": [[0.0, 90.0], [1.0, 180.0]]}, "the first (0, 0)"),
    ({"angle_table": [[0.0, 0.0], [1.0, 5.0], [1.0, 6.0]]}, "the times must increase strictly"),
    ({"speed_rpm": 10.0, "spin_up_s": 0.0}, "spin_up_s: Input should be greater than 0"),
])
def test_a_drive_profile_that_does_not_fit_is_one_line(drive, message):
    from pinbore.core import scene as scenes

    with pytest.raises(InputError) as err:
        scenes.validate(PlanarScene, planar_bar(drive), "test")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_nonlinear_dynamics_needs_a_drive_at_constant_speed():
    """The Poincare section is taken once per forcing period: a spin-up has no period."""
    from pinbore.reduced.dynamics import studies

    scene = PlanarScene.model_validate(planar_bar({"speed_rpm": 60.0, "spin_up_s": 1.0}))
    with pytest.raises(InputError, match="drive at constant speed"):
        studies.require_forcing(scene, "test")
