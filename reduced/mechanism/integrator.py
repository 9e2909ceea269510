r"""The integrators of the mechanism model: DOPRI5, Rosenbrock 2(3) and fixed-step DOPRI5,
with event location.

The mechanism (reduced.mechanism.engine) brings its state y = (q, q', energy integrals,
friction states; reduced.mechanism.layout) and its arguments bundle, and teaches the
integrator five things about it by overloading the functions declared here
(numba.extending.overload, inlined, chosen by the type of the arguments bundle):

- new_workspace(args): the buffers of its right-hand side;
- evaluate(t, y, dy, args, work): dy = f(t, y);
- start(y, args, onset_tol): the contact state at t = 0 (layout.Contacts), the flags of
  what the mechanism needs checked (a tuple of booleans, passed back to the two below) and a
  buffer for the events of one step (rows of the impact log, layout.LOG_*);
- event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol, event_dt): the
  fraction of a trial step that ends it at its first event (a contact onset, a latch, a
  release; 1: none), so that every impact starts on a step boundary with a known speed;
- after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor, rate_tol, events):
  the updates of an accepted step (onsets with their impact speeds, impacts, latches, the
  projection onto the constraints), returning (whether y or the laws' state changed, the
  number of impacts and onsets written into `events`), which go into the impact log.

Dormand-Prince 5(4) [DormandPrince1980] (explicit) or Rosenbrock 2(3) (linearly implicit,
for stiff problems), both with a PI step-size controller on (q, q') and the friction states,
or DOPRI5 at a fixed step for comparison. `integrate` takes a step in four phases:
- the trial step (trial_step): a stage beyond the tabulated law (NaN) has the step retried
  ten times shorter; only if the step size collapses that way has the run blown up;
- event location (event_fraction, adaptive methods only): a step that would carry a joint
  into contact deeper than `onset_tol` is shortened until it ends at the onset;
- the mechanism's updates of the accepted step (after_step);
- the record of the accepted step (recorded), in buffers that double when full.
numba counts the references of every array a compiled function receives or reads out of a
bundle; the hooks are inlined into the loop, and pass arrays to the helpers that run at
every step.
"""

import math

import numba
import numpy as np

from pinbore.core.compiled import beside, follow_compiled_in
from pinbore.laws import dissipative, friction, sliced, tables
from pinbore.reduced.mechanism import layout
from pinbore.reduced.mechanism.layout import (  # noqa: F401 (the codes are the integrator's)
    BLOWN_UP, DOPRI5, DOPRI5_FIXED, ENERGY_STATES, LOG_COLUMNS, LOG_IMPULSE, LOG_JOINT, LOG_RATE,
    LOG_TIME, OK, ROSENBROCK23, STEP_TOO_SMALL, TOO_MANY_STEPS, Integration, Record)


# ---- what a mechanism overloads (declarations: compiled code reaches the mechanism's own)
def _declared(name):
    def hook(*arguments):
        raise TypeError(f"reduced.mechanism.integrator.{name} runs only inside compiled code, "
                        "overloaded by reduced.mechanism.engine")
    hook.__name__ = hook.__qualname__ = name
    return hook


new_workspace = _declared("new_workspace")
evaluate = _declared("evaluate")
start = _declared("start")
event_fraction = _declared("event_fraction")
after_step = _declared("after_step")


@numba.njit(cache=True, _nrt=False)
def f_of(t, y, dy, args, work):
    """dy = f(t, y) as a call of its own. The mechanism's right-hand side is inlined where it
    runs most, in DOPRI5's stages (called there, it made the slider-crank's run a sixth
    slower), and called through this from the other places, which keeps the compiled code
    and its compile time small."""
    evaluate(t, y, dy, args, work)


def evaluate_once(workspace, rhs, t, y, args):
    """(f(t, y) as a new array, the workspace it was evaluated in): one right-hand side call
    of a kernel (its `workspace` and `rhs`) from Python, for post-processing."""
    dy = np.empty_like(y)
    work = workspace(args)
    rhs(t, y, dy, args, work)
    return dy, work


@numba.njit(cache=True, _nrt=False)
def onset_shortening(depth, depth_new, onset_tol):
    """Event location for a contact out of contact at the step's start (penetration `depth`)
    and at `depth_new` at its end: the fraction of the step that ends it at the onset. One that
    would end the step deeper than onset_tol is shortened by a secant on the penetration, one
    that went in and out within the step (deeper at its end than at its start) by half.
    1: no onset."""
    if depth_new > onset_tol and depth < -onset_tol:
        return 0.99 * (-depth) / (depth_new - depth)
    if depth_new > max(depth, 0.0) + onset_tol:   # back within the step: bisect
        return 0.5
    return 1.0


# Dormand-Prince 5(4) tableau
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
A = np.array([[0, 0, 0, 0, 0, 0], [1 / 5, 0, 0, 0, 0, 0], [3 / 40, 9 / 40, 0, 0, 0, 0],
              [44 / 45, -56 / 15, 32 / 9, 0, 0, 0],
              [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0],
              [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0],
              [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]])
B5 = np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0])
E54 = B5 - np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])


@numba.njit(cache=True, _nrt=False)
def error_norm(err_vec, y, y_new, nq, rtol, atol):
    """RMS of the local error scaled by atol + rtol |y|; the energy integrals are outputs."""
    err = 0.0
    for i in range(y.size):
        if 2 * nq <= i < 2 * nq + ENERGY_STATES:
            continue
        scale = atol + rtol * max(abs(y[i]), abs(y_new[i]))
        err += (err_vec[i] / scale) ** 2
    return math.sqrt(err / (y.size - ENERGY_STATES))


@numba.njit(cache=True, _nrt=False)
def dopri5_step(t, y, h, k, y_new, err_vec, args, work):
    """One Dormand-Prince 5(4) step: k[0] = f(t, y) on entry, k[6] = f(t + h, y_new) on exit."""
    for s in range(1, 7):
        for i in range(y.size):
            v = y[i]
            for r in range(s):
                v += h * A[s, r] * k[r, i]
            y_new[i] = v
        evaluate(t + C[s] * h, y_new, k[s], args, work)
    for i in range(y.size):
        e = 0.0
        for r in range(7):
            e += E54[r] * k[r, i]
        err_vec[i] = h * e
    return 6


ROS_D = 1.0 / (2.0 + math.sqrt(2.0))
ROS_E32 = 6.0 + math.sqrt(2.0)


@numba.njit(cache=True)
def rosenbrock23_step(t, y, h, k, y_new, err_vec, args, work):
    """One linearly implicit Rosenbrock 2(3) step (Shampine & Reichelt 1997 [ShampineReichelt1997], MATLAB's ode23s),
    L-stable, with W = I - h d J and J, df/dt by finite differences:
        k1 = W^-1 (F0 + h d T),  F1 = f(t + h/2, y + h k1 / 2),  k2 = W^-1 (F1 - k1) + k1,
        y1 = y + h k2,  F2 = f(t + h, y1),
        k3 = W^-1 (F2 - e32 (k2 - F1) - 2 (k1 - F0) + h d T),  error = h (k1 - 2 k2 + k3) / 6.
    k[0] = F0 on entry, k[6] = F2 on exit; k[1..5] are scratch."""
    n = y.size
    f0, f1, col = k[0], k[1], k[2]
    jacobian = np.empty((n, n))
    ys = y.copy()
    for c in range(n):
        step = 1e-7 * max(abs(y[c]), 1e-6)
        ys[c] = y[c] + step
        f_of(t, ys, col, args, work)
        for r in range(n):
            jacobian[r, c] = (col[r] - f0[r]) / step
        ys[c] = y[c]
    dt = 1e-7 * max(t, h)
    f_of(t + dt, y, col, args, work)
    tdot = (col - f0) / dt
    w = -h * ROS_D * jacobian
    for i in range(n):
        w[i, i] += 1.0
    winv = np.linalg.inv(w)
    k1 = winv @ (f0 + h * ROS_D * tdot)
    f_of(t + 0.5 * h, y + 0.5 * h * k1, f1, args, work)
    k2 = winv @ (f1 - k1) + k1
    y_new[:] = y + h * k2
    f_of(t + h, y_new, k[6], args, work)
    k3 = winv @ (k[6] - ROS_E32 * (k2 - f1) - 2.0 * (k1 - f0) + h * ROS_D * tdot)
    err_vec[:] = h / 6.0 * (k1 - 2.0 * k2 + k3)
    return n + 4


@numba.njit(cache=True)
def doubled(a):
    """a in the first rows of a zeroed array of twice its rows (a buffer that is full)."""
    out = np.zeros((2 * a.shape[0],) + a.shape[1:], a.dtype)
    out[:a.shape[0]] = a
    return out


@numba.njit(cache=True)
def log_impact(log, impacts, t, j, rate, impulse):
    """The impacts-th row of the impact log (layout.LOG_*), the log doubled when full; returns
    the log."""
    if impacts > log.shape[0]:
        log = doubled(log)
    row = impacts - 1
    log[row, LOG_TIME], log[row, LOG_JOINT] = t, j
    log[row, LOG_RATE], log[row, LOG_IMPULSE] = rate, impulse
    return log


@numba.njit(cache=True)
def new_record(capacity, ny, nj, nt):
    """Buffers for `capacity` accepted steps (layout.Record; a column for absent clearance
    joints or torsion elements keeps the shapes)."""
    return Record(np.empty(capacity), np.empty((capacity, ny)), np.empty((capacity, max(nj, 1))),
                  np.zeros((capacity, max(nj, 1)), np.int64), np.zeros((capacity, max(nt, 1))))


@numba.njit(cache=True)
def recorded(record, count, t, y, speeds, mode, latched):
    """Accepted step `count` (time, state, impact speeds, contact modes, latch flags) stored
    in the record, its buffers doubled when full; returns the record."""
    if count == record.times.size:
        record = Record(doubled(record.times), doubled(record.states), doubled(record.speeds),
                        doubled(record.modes), doubled(record.latched))
    record.times[count], record.states[count] = t, y
    record.speeds[count, :speeds.size], record.modes[count, :mode.size] = speeds, mode
    record.latched[count, :latched.size] = latched
    return record


@numba.njit(cache=True)
def next_step_size(h, err, err_prev, exponent):
    """PI step-size control after an accepted step: h 0.9 err^(-0.7 k) err_prev^(0.4 k), within
    0.2 h to 5 h. Returns (the next h, the error to remember)."""
    factor = 0.9 * err ** (-0.7 * exponent) * err_prev ** (0.4 * exponent) if err > 0 else 5.0
    return h * min(5.0, max(0.2, factor)), max(err, 1e-4)


@numba.njit(cache=True)
def integrate(y0, t_end, args, method, rtol, atol, max_step, onset_tol, speed_floor, max_steps):
    """Integrate from t = 0, continuing from the impact speeds, latches and contact modes in
    args (layout.Args), with DOPRI5 (adaptive), DOPRI5 at the fixed step max_step (no
    error control, no event location: for comparison) or Rosenbrock 2(3) (adaptive, for
    stiff contact). Returns the layout.Integration: times, states, impact speeds, contact
    modes and latch flags of every accepted step, the impact log (layout.LOG_*), counters
    (accepted, rejected, rhs calls, impacts), a status code and the time reached."""
    ny = y0.size
    adaptive = method != DOPRI5_FIXED
    event_dt = 1e-8 * max_step   # a release is located to within this time
    exponent = 1.0 / 3.0 if method == ROSENBROCK23 else 0.2
    t, y = 0.0, y0.copy()
    contacts, needs, events = start(y, args, onset_tol)   # before f: a latch given as engaged stays so
    k = np.empty((7, ny))
    y_new = np.empty(ny)
    err_vec = np.empty(ny)
    work = new_workspace(args)
    f_of(t, y, k[0], args, work)
    calls, accepted, rejected, impacts = 1, 0, 0, 0
    h = max_step if not adaptive else min(max_step, 1e-6)
    err_prev = 1e-4
    speeds, latched, mode = args.speeds, args.latched, args.mode
    record = recorded(new_record(4096, y.size, speeds.size, latched.size), 0, t, y, speeds, mode,
                      latched)
    count = 1
    log = np.empty((256, LOG_COLUMNS))
    status = OK
    last_nan = False
    while t < t_end:
        if accepted + rejected >= max_steps:
            status = TOO_MANY_STEPS
            break
        h = min(h, t_end - t, max_step)
        if h < 1e-15 * max(t, 1e-3):
            status = BLOWN_UP if last_nan else STEP_TOO_SMALL
            break
        if method == ROSENBROCK23:
            calls += rosenbrock23_step(t, y, h, k, y_new, err_vec, args, work)
        else:
            calls += dopri5_step(t, y, h, k, y_new, err_vec, args, work)
        err = error_norm(err_vec, y, y_new, args.nq, rtol, atol)
        last_nan = not math.isfinite(err)
        if last_nan:   # a stage went beyond the tabulated law: much smaller step
            rejected += 1
            h *= 0.1
            continue
        if adaptive and err > 1.0:
            rejected += 1
            h *= max(0.2, 0.9 * err ** -exponent)
            continue
        if adaptive:   # event location: the step ends at its first event
            shorten = event_fraction(y, y_new, h, args, work, contacts, needs, onset_tol, rtol,
                                     event_dt)
            if shorten < 1.0:
                rejected += 1
                h *= max(shorten, 1e-3)
                continue
        t += h
        y[:] = y_new
        accepted += 1
        k[0, :] = k[6]  # first same as last
        # the mechanism's updates of the accepted step (events, projection); any of them means
        # f(t, y) is evaluated again
        changed, arrived = after_step(t, y, args, work, contacts, needs, onset_tol, speed_floor,
                                      onset_tol / max_step, events)
        for i in range(arrived):
            impacts += 1
            log = log_impact(log, impacts, events[i, LOG_TIME], int(events[i, LOG_JOINT]),
                             events[i, LOG_RATE], events[i, LOG_IMPULSE])
        if changed:
            f_of(t, y, k[0], args, work)
            calls += 1
        record = recorded(record, count, t, y, speeds, mode, latched)
        count += 1
        if adaptive:
            h, err_prev = next_step_size(h, err, err_prev, exponent)
    counters = np.array([accepted, rejected, calls, impacts])
    return Integration(record.times[:count], record.states[:count], record.speeds[:count],
                       record.modes[:count], record.latched[:count], log[:impacts], counters,
                       status, t)



# ---- the compiled code follows the mechanism that overloads its hooks
# numba's cache checks only this file: the integrator compiles in the right-hand side and the
# event code of the mechanism and what they call, so an edit there alone would leave its
# cached code stale (pinbore.core.compiled drops the cache when those files change).
COMPILED_IN = (friction.__file__, dissipative.__file__, tables.__file__, sliced.__file__,
               *beside(__file__, "layout", "vectors", "bodies", "linalg", "engine", "planar", "spatial"))
follow_compiled_in(globals(), COMPILED_IN)
