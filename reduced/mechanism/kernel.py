"""The engine that runs a mechanism, chosen by its arguments: the compiled core
(pinbore.core.cpp.mechanism, C++) for the bodies it implements, rigid ones in the plane and in
space, and numba's (reduced.mechanism.engine, loaded only then) for a mechanism with a
flexible body, until the core covers them. Both take layout.Args and layout.Work and give the
same numbers (the core's arithmetic is the numba engine's, operation by operation: the
shipped rigid scenes integrate to the same bits). Every caller of the engine comes through
here.
"""

import numpy as np

from pinbore.core import cpp
from pinbore.reduced.mechanism import layout

RIGID_COLUMNS = {2: 3, 3: 6}   # a rigid body's velocity columns: x', y', w; r', w


def compiled(args) -> bool:
    """Whether the compiled core runs this mechanism: every body rigid."""
    return bool(np.all(np.diff(args.offsets) == RIGID_COLUMNS[len(args.like)]))


def _numba():
    from pinbore.reduced.mechanism import engine   # noqa: PLC0415 (numba, loaded on use)
    return engine


def integrate(y0, t_end, args, method, rtol, atol, max_step, onset_tol, speed_floor,
              max_steps) -> layout.Integration:
    """Integrate from t = 0 (reduced.mechanism.integrator.integrate)."""
    settings = (method, rtol, atol, max_step, onset_tol, speed_floor, max_steps)
    if compiled(args):
        return layout.Integration(*cpp.mechanism.integrate(np.ascontiguousarray(y0, float), t_end,
                                                           args, *settings))
    return _numba().integrate(y0, t_end, args, *settings)


def workspace(args) -> layout.Work:
    """The right-hand side's buffers."""
    if compiled(args):
        return layout.Work(*cpp.mechanism.workspace(args))
    return _numba().workspace(args)


def rhs(t, y, dy, args, work) -> None:
    """dy = f(t, y); the contacts' forces in work.normal and work.friction."""
    (cpp.mechanism if compiled(args) else _numba()).rhs(t, y, dy, args, work)


def rhs_value(t, y, args):
    """(f(t, y), normal force per contact) as new arrays."""
    y = np.ascontiguousarray(y, float)
    dy, work = np.empty_like(y), workspace(args)
    rhs(t, y, dy, args, work)
    return dy, work.normal[:args.contacts.shape[0]].copy()


def observe(t, y, dy, args, work, depth, offset) -> float:
    """One state as the outputs see it (reduced.mechanism.engine.observe)."""
    return (cpp.mechanism if compiled(args) else _numba()).observe(t, y, dy, args, work, depth, offset)


def observe_steps(times, states, speeds, latched, modes, args, work, *seen) -> None:
    """observe at every recorded step into the rows of `seen` (engine.observe_steps)."""
    (cpp.mechanism if compiled(args) else _numba()).observe_steps(
        times, states, speeds, latched, modes, args, work, *seen)


def relative_motion(y, args, work, bb, s_b, bj, s_j, f, g):
    """Body bj's point s_j relative to body bb's point s_b along bb's vectors f and g."""
    if compiled(args):
        return cpp.mechanism.relative_motion(y, args, work, bb, s_b, bj, s_j, f, g)
    return _numba().relative_motion(y, args, work, bb, s_b, bj, s_j, f, g)


def constraint_values(t, y, args):
    """(Phi_q, Phi, Phi_t) of the ideal joints, the drive and the held contacts."""
    return (cpp.mechanism if compiled(args) else _numba()).constraint_values(t, y, args)


def project_onto_constraints(t, y, args, work, tolerance, rate_tolerance) -> bool:
    """One Gauss-Newton step of positions and of velocities onto the constraints."""
    return (cpp.mechanism if compiled(args) else _numba()).project_onto_constraints(
        t, y, args, work, tolerance, rate_tolerance)


def energy_of(y, args) -> float:
    """The bodies' kinetic energy (J)."""
    return (cpp.mechanism if compiled(args) else _numba()).energy_of(y, args)


def slice_approaches(y, args, work, k, approaches, weights):
    """The slices of sliced contact k: their approaches and weights into the arrays; the
    bore's displacement (engine.slice_approaches)."""
    if compiled(args):
        return cpp.mechanism.slice_approaches(y, args, work, k, approaches, weights)
    return _numba().slice_approaches(y, args, work, k, approaches, weights)
