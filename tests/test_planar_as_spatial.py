"""A planar mechanism written as a spatial one reproduces the planar model (the other
formulation of the same physics), beyond the frictionless first impact of tests/test_spatial.py:
with every friction law of a continuous contact, and with impulse contacts (Newton's and
Poisson's restitution, the rest speed, the held contact and its release: the three-state
model).

The twins are the shipped Flores slider-crank scenes: the planar one
(scenes/reduced/slider_crank_flores2004.toml) and its spatial writing
(scenes/reduced/spatial_slider_crank_flores.toml: the x-y plane, every revolute joint along z,
the rod-slider joint a cylindrical journal 20 mm long with the Hertz point law spread evenly
over its length, so that an aligned journal carries exactly the planar law). Both are built by
reduced.mechanism.model.build, the kind chosen by the scene's `kind` key, and integrated by
DOPRI5 at rtol 1e-10, atol 1e-13 (adaptive steps, contact onsets located to the onset
tolerance, 1e-3 c sqrt(rtol) = 5e-12 m).

What is compared, at common instants: every body's position (x, y) and angle about z, and
the clearance joint's normal and friction forces. The steps of the two models fall at
different times, so each model's state at an instant is the cubic Hermite interpolant of its
state and rate at the ends of the step holding it (the interpolation of
reduced.mechanism.outputs.refined_peak; fourth order: on the steps of a few hundred
nanoseconds through an impact of about 50 us it is 1e-10 of the state's own scale or better),
and the forces are each engine's at that state (kernel.observe). A step whose end state was
changed by an impulse or a contact's release is not interpolated across (its end state is
not the integral of its rates); the samples falling in such a step are left out.

Tolerances (the two models integrate the same equations in different coordinates, each to
rtol 1e-10; they differ by their integration errors and rounding):
- positions 1e-8 of the crank length (5e-10 m), the bound tests/test_spatial.py argues for
  the ideal motion at this rtol; angles 1e-8 rad (5e-10 m over the rod's half-length, 0.06 m,
  is 8e-9 rad);
- the contact forces 1e-6 of their peak: tests/test_spatial.py holds the first impact's peak
  to 1e-6 (the same dynamics; its argument is the error of reading a peak at the steps, which
  the interpolation here does not have); a friction force to 1e-6 of its own peak (a law's
  force is the normal force times a coefficient of the slip, or a state driven by the slip);
- impacts (onset time 1e-8, approach speed 1e-6: the bounds of tests/test_spatial.py; impulse
  1e-6, the impulse being (1 + e) times the approach speed times the same effective mass).
"""

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT

from pinbore.reduced.mechanism import kernel, kinds
from pinbore.reduced.mechanism.layout import LOG_IMPULSE, LOG_RATE, LOG_TIME
from pinbore.reduced.mechanism.model import build
from pinbore.reduced.mechanism.outputs import hermite_basis, roles
from pinbore.reduced.mechanism.run import simulate

SCENES = ROOT / "scenes" / "reduced"
PLANAR = tomllib.loads((SCENES / "slider_crank_flores2004.toml").read_text())
SPATIAL = tomllib.loads((SCENES / "spatial_slider_crank_flores.toml").read_text())
BODIES = ("crank", "rod", "slider")
CRANK = 0.05                 # m, the crank's length
POSITION_TOL = 1e-8 * CRANK  # m
ANGLE_TOL = 1e-8             # rad
FORCE_TOL = 1e-6             # of the peak

# Friction laws of steel on steel with enough sliding in the first impact (the journal slips
# over the bore at 1.0-2.1 m/s for about 50 us, some 100 um), each with the coefficient it
# slides at (for the check that the law was exercised) and the tolerance of its force
# (of its peak): mu 0.1; a Stribeck curve whose minimum lies above the slip speeds (so that
# mu changes along the impact); a linear law rising 0.02 per m/s; LuGre with bristles of
# sigma0 = 1e5 1/m (10 um to full strength), sigma1 = sqrt(sigma0) s/m, no viscous term; Dahl
# of the same stiffness; the Iwan element with a tangential stiffness k1 = 1e6 N/m (it sticks
# while the normal force grows and slides where mu F_n falls below k1 z: at the onset and as
# the contact opens).
# The friction force's tolerance is FORCE_TOL but for LuGre: its force F_n (sigma0 z + sigma1
# z') with z' = v - sigma0 |v| z / g carries the bristle state's integration error dz times
# sigma0 (1 + sigma1 |v| / g) = 6.6e8 1/m at 2.1 m/s; the error control holds the RMS over
# the N <= 56 states of the local errors to atol + rtol |y| (atol 1e-13 m dominates the
# state's 1e-16 m), so one state's error may reach sqrt(N) 1e-13 = 7.5e-13 m: 5e-4 F_n, below
# 5e-4 of the friction force's peak (sigma1's transient at the onset lifts it above F_n). The
# other laws' states are forces per normal force (Dahl: m ~ 0.1, its error 1e-10 of it) or a
# stretch whose error k1 dz = 7.5e-7 N is 6e-9 of the Iwan element's 125 N: within FORCE_TOL.
# LuGre's motion: the bristle state is stiff (its time constant g / (sigma0 |v|) = 0.5 us at
# 2.1 m/s, against steps of 0.1-0.3 us through the impact), and its integration error, fed
# back through the friction force, moves the bodies by 2-4 times the bounds of the
# frictionless motion at rtol 1e-10 (4.2x in position, 3.5x in angle, the normal force 1.5e-6
# of its peak, measured; it depends on the floating-point code of the machine): its twins run
# at rtol 1e-11, atol 1e-14 (the last entry), where the differences fall by 14x to 0.3 of the
# bounds (1e-12: 4e-3), within every common bound. The Iwan element's force: its stick-slip switch (at the
# onset and as the contact opens, where mu F_n falls below k1 z) is a discontinuity of the
# right-hand side, which the two models' steps cross at other instants and, in space, every
# slice at its own: the slider's force there differs by k1 times the slip over that
# misplacement (measured: 4e-3 of the peak against the planar model, 1.4e-3 between one and
# four slices, at isolated instants; positions and angles within the common bounds).
LAWS = {
    "coulomb_ambrosio": ({"law": "coulomb_ambrosio", "mu": 0.1}, 0.1, FORCE_TOL),
    "stribeck": ({"law": "stribeck", "mu_static": 0.15, "mu_min": 0.1, "v_min": 2.5}, 0.1,
                 FORCE_TOL),
    "linear": ({"law": "linear", "mu_static": 0.1, "alpha": 0.02}, 0.1, FORCE_TOL),
    "lugre": ({"law": "lugre", "mu_coulomb": 0.1, "mu_static": 0.15, "stribeck_speed": 1e-3,
               "sigma0": 1e5, "sigma1": 316.0, "sigma2": 0.0}, 0.1, 5e-4, 1e-11),
    "dahl": ({"law": "dahl", "mu": 0.1, "sigma": 1e5}, 0.1, FORCE_TOL),
    "iwan_bilinear": ({"law": "iwan_bilinear", "mu": 0.1, "k1": 1e6, "k2": 0.0}, 0.1, 1e-2),
}


def twins(duration, joint, drop=(), rtol=1e-10):
    """The planar scene and its spatial writing over `duration`, the rod-slider joint's keys
    `drop` removed and `joint` added, integrated at rtol 1e-10 (atol 1e-3 rtol m)."""
    out = []
    for data in (PLANAR, SPATIAL):
        data = copy.deepcopy(data)
        data["duration"] = duration
        data["integrator"] = {"rtol": rtol, "atol": 1e-3 * rtol}
        data["output"] = {"plots": False}
        for key in drop:
            data["clearance_joints"][0].pop(key)
        data["clearance_joints"][0] |= joint
        out.append(data)
    return out


def integrate(data):
    model = build(kinds.validate(data, "test"), "test", ROOT)   # the kind from the scene
    run = simulate(model)
    assert run.status == 0, (data["kind"], run.status, run.t_end)
    return model, run


def changed_ends(run) -> np.ndarray:
    """Per step (a, a + 1): whether its end state was changed after the step (an impulse or a
    held contact taken or released at t_{a+1}, which the rates do not carry)."""
    events = np.isin(run.times[1:], run.impacts[:, LOG_TIME])
    modes = np.any(run.modes[1:] != run.modes[:-1], axis=1) if run.modes.shape[1] else False
    return events | modes


def observed(model, run, times):
    """At each time: every body's x, y (m) and angle about z (rad), then the clearance joint's
    normal and friction forces (N) summed over its contacts across the joint (a journal's
    slices or ends; the planar friction force is signed, the spatial one a size), from the
    cubic Hermite interpolant of the state on the step holding the time, with the contact
    law's impact speeds and modes in force over that step (those recorded at its start).
    Also whether the step's end state is the integral of its rates (changed_ends)."""
    nc, nt = model.contacts.shape[0], model.torsion.shape[0]
    per_body = model.nq // len(model.names)
    main = roles(model, 0)["main"]
    changed = changed_ends(run)
    dy, depth = np.empty(run.states.shape[1]), np.empty(nc)
    offset = np.zeros((nc, model.kind.dimension))
    out, clean = np.empty((times.size, 3 * len(BODIES) + 2)), np.empty(times.size, bool)
    for i, t in enumerate(times):
        a = min(max(int(np.searchsorted(run.times, t, side="right")) - 1, 0), run.times.size - 2)
        args = model.args(run.speeds[a, :nc], run.latched[a, :nt], run.modes[a, :nc])
        h = run.times[a + 1] - run.times[a]
        f0 = kernel.rhs_value(run.times[a], run.states[a], args)[0]
        f1 = kernel.rhs_value(run.times[a + 1], run.states[a + 1], args)[0]
        basis, _ = hermite_basis(np.array([(t - run.times[a]) / h]))
        y = basis[:, 0] @ np.array([run.states[a], h * f0, run.states[a + 1], h * f1])
        work = kernel.workspace(args)
        kernel.observe(t, y, dy, args, work, depth, offset)
        for b, name in enumerate(BODIES):
            q = y[per_body * model.names.index(name):][:per_body]
            out[i, 3 * b:3 * b + 2] = q[:2]
            # planar: the angle; spatial: Euler parameters of a turn about z, (cos, 0, 0, sin)
            out[i, 3 * b + 2] = q[2] if per_body == 3 else 2 * math.atan2(q[6], q[3])
        out[i, -2] = work.normal[main].sum()
        out[i, -1] = np.abs(work.friction[main]).sum()
        clean[i] = not changed[a]
    return out, clean


def differences(planar, spatial, times):
    """(positions m, angles rad, normal force, friction force: the largest differences at the
    times, the planar model's observations, the samples compared)."""
    (p, p_clean), (s, s_clean) = observed(*planar, times), observed(*spatial, times)
    keep = p_clean & s_clean
    assert keep.sum() > 0.9 * times.size   # few samples fall in a step ending at an event
    d = np.abs(p - s)[keep]
    angles = np.abs(np.angle(np.exp(1j * (p[keep][:, 2:-2:3] - s[keep][:, 2:-2:3]))))
    positions = d[:, [3 * b + c for b in range(len(BODIES)) for c in (0, 1)]]
    return positions.max(), angles.max(), d[:, -2].max(), d[:, -1].max(), p, keep


def sample_times(run, onset, contact=6e-5):
    """400 instants over the run and 200 across the first contact (the impact of about 50 us
    after the onset)."""
    return np.sort(np.concatenate([np.linspace(0.0, run.times[-1], 400)[1:-1],
                                   np.linspace(onset, min(onset + contact, run.times[-1]), 200)]))


@pytest.mark.parametrize("law", list(LAWS))
def test_continuous_contact_with_friction_reproduces_the_planar_model(law):
    """The first impact of the Flores slider-crank with friction in the rod-slider joint
    (4e-4 s: free flight, the impact with its peak at 0.25 ms, the contact opening, free flight
    again): the same onset, and at 600 instants the same positions, angles, normal force and
    friction force (module docstring: 5e-10 m, 1e-8 rad, 1e-6 of the peaks; LuGre's friction
    force 5e-4 of its peak, its twins at rtol 1e-11; the Iwan element's force 1e-2: LAWS). The
    law was
    exercised: somewhere in contact the planar joint slides at its law's sliding coefficient
    (|F_t| >= 0.999 mu F_n)."""
    friction, mu, friction_tol, *rtol = LAWS[law]
    rtol = rtol[0] if rtol else 1e-10
    planar, spatial = (integrate(data) for data in twins(4e-4, {"friction": friction}, rtol=rtol))
    (_, p_run), (_, s_run) = planar, spatial
    assert p_run.impacts.shape[0] == s_run.impacts.shape[0] == 1
    assert s_run.impacts[0, LOG_TIME] == pytest.approx(p_run.impacts[0, LOG_TIME], rel=1e-8)
    assert s_run.impacts[0, LOG_RATE] == pytest.approx(p_run.impacts[0, LOG_RATE], rel=1e-6)
    times = sample_times(p_run, p_run.impacts[0, LOG_TIME])
    positions, angles, normal, tangential, p, _ = differences(planar, spatial, times)
    in_contact = p[:, -2] > 0
    assert np.any(p[in_contact, -1] >= 0.999 * mu * p[in_contact, -2])   # it slid
    assert positions < POSITION_TOL, positions
    assert angles < ANGLE_TOL, angles
    assert normal < FORCE_TOL * p[:, -2].max(), normal / p[:, -2].max()
    assert tangential < friction_tol * p[:, -1].max(), tangential / p[:, -1].max()


@pytest.mark.parametrize("law", ["lugre", "dahl", "iwan_bilinear"])
def test_aligned_journal_friction_does_not_depend_on_its_slices(law):
    """An aligned journal's slices all carry the same approach, slip and friction state: one
    slice or four give the same joint (the normal law is per length, every law is written per
    slice of its share of the length). The spatial slider-crank of the test above, with 1 and
    with 4 slices: the same positions, angles and forces to the same tolerances (the two runs
    differ by rounding, the slices' sums, and the integration errors it leaves: LAWS)."""
    friction, _, friction_tol, *_ = LAWS[law]
    spatial = twins(4e-4, {"friction": friction})[1]
    runs = []
    for slices in (1, 4):
        data = copy.deepcopy(spatial)
        data["clearance_joints"][0]["slices"] = slices
        runs.append(integrate(data))
    times = sample_times(runs[0][1], runs[0][1].impacts[0, LOG_TIME])
    positions, angles, normal, tangential, p, _ = differences(runs[0], runs[1], times)
    assert positions < POSITION_TOL, positions
    assert angles < ANGLE_TOL, angles
    assert normal < FORCE_TOL * p[:, -2].max(), normal / p[:, -2].max()
    assert tangential < friction_tol * p[:, -1].max(), tangential / p[:, -1].max()


@pytest.mark.parametrize("impact", ["newton", "poisson"])
def test_impulse_contact_reproduces_the_planar_model(impact):
    """Rigid impacts in the rod-slider joint, restitution 0.5, rest speed 1 m/s, over 4 ms:
    the first two impacts rebound (e v >= 1 m/s), the third is held (the journal rides on the
    bore, the contact a constraint whose multiplier is the normal force), the held contact
    releases where its force would pull, the journal crosses and its next impact is held
    again. The planar joint is one contact; the spatial journal two (its ends), which arrive
    together. Every impact carrying an impulse in either model is in the other, one for one:
    onset time to 1e-8, approach speed and impulse to 1e-6; an impact logged by one alone
    carries no impulse. The contact is held over the same intervals (taken at the impacts;
    released at the zero of the held force, which the models agree on to 1e-6 of its 6 kN
    peak, 6 mN, and which falls through zero at about its peak over a quarter of the crank's
    12 ms turn, 2e6 N/s: 3 ns, 1e-6 of the release's 3.4 ms). At 600 instants the same positions, angles and held
    normal force (module docstring: 5e-10 m, 1e-8 rad, 1e-6 of the peak)."""
    planar, spatial = (integrate(data) for data in twins(
        4e-3, {"impact": impact, "restitution": 0.5, "rest_speed": 1.0},
        drop=("normal_law", "damping_law")))
    (_, p_run), (_, s_run) = planar, spatial
    p_log, s_log = (run.impacts[run.impacts[:, LOG_IMPULSE] > 0] for run in (p_run, s_run))
    for run in (p_run, s_run):   # the impacts left out carry no impulse
        assert np.all(run.impacts[run.impacts[:, LOG_IMPULSE] <= 0, LOG_IMPULSE] == 0)
    assert p_log.shape[0] == s_log.shape[0] == 4
    np.testing.assert_allclose(s_log[:, LOG_TIME], p_log[:, LOG_TIME], rtol=1e-8)
    np.testing.assert_allclose(s_log[:, LOG_RATE], p_log[:, LOG_RATE], rtol=1e-6)
    np.testing.assert_allclose(s_log[:, LOG_IMPULSE], p_log[:, LOG_IMPULSE], rtol=1e-6)
    # the exercise: two rebounds, then held; released; held again at the fourth impact
    assert np.all(0.5 * p_log[:2, LOG_RATE] >= 1.0) and np.all(0.5 * p_log[2:, LOG_RATE] < 1.0)
    switches = []
    for run in (p_run, s_run):
        held = run.modes.max(axis=1) > 0
        switches.append(run.times[1:][held[1:] != held[:-1]])
    assert switches[0].size == 3, switches[0]     # held, released, held
    np.testing.assert_allclose(switches[0][[0, 2]], p_log[2:, LOG_TIME], rtol=1e-12)
    np.testing.assert_allclose(switches[1], switches[0], rtol=1e-6)
    times = np.linspace(0.0, min(p_run.times[-1], s_run.times[-1]), 600)[1:-1]
    positions, angles, normal, _, p, keep = differences(planar, spatial, times)
    held = p[keep, -2] != 0
    assert held.sum() > 300   # the held contact's force compared over most of the run
    assert positions < POSITION_TOL, positions
    assert angles < ANGLE_TOL, angles
    assert normal < FORCE_TOL * np.abs(p[:, -2]).max(), normal / np.abs(p[:, -2]).max()
