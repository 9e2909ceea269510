"""The multibody engine, the compiled core's (pinbore.core.cpp.mechanism, C++: cpp/mechanism/),
as the rest of pinbore sees it: every caller of the engine comes through here. Each function
takes the mechanism as layout.Args and, where the caller keeps the right-hand side's buffers,
layout.Work (the core reads their arrays in place and updates the impact speeds, latch flags
and contact modes of Args as the integrator does); what the core returns as a tuple comes
back as the layout's namedtuple. The core picks the body kind (planar, spatial) by the
dimension of Args.like; rigid and flexible bodies mix in one mechanism.
"""

import numpy as np

from pinbore.core import cpp
from pinbore.reduced.mechanism import layout

core = cpp.mechanism


def integrate(y0, t_end, args, method, rtol, atol, max_step, onset_tol, speed_floor,
              max_steps) -> layout.Integration:
    """Integrate from t = 0 with DOPRI5 (event location), fixed-step DOPRI5 or Rosenbrock
    2(3) (layout's codes): every accepted step's time, state, impact speeds, contact modes and
    latch flags, the impact log, the counters, the status and the time reached."""
    return layout.Integration(*core.integrate(np.ascontiguousarray(y0, float), t_end, args, method,
                                              rtol, atol, max_step, onset_tol, speed_floor, max_steps))


def workspace(args) -> layout.Work:
    """The right-hand side's buffers."""
    return layout.Work(*core.workspace(args))


def rhs(t, y, dy, args, work) -> None:
    """dy = f(t, y); the contacts' forces in work.normal and work.friction."""
    core.rhs(t, y, dy, args, work)


def rhs_value(t, y, args):
    """(f(t, y), normal force per contact) as new arrays."""
    y = np.ascontiguousarray(y, float)
    dy, work = np.empty_like(y), workspace(args)
    core.rhs(t, y, dy, args, work)
    return dy, work.normal[:args.contacts.shape[0]].copy()


def observe(t, y, dy, args, work, depth, offset) -> float:
    """One state as the outputs see it: f(t, y) into dy, each contact's deepest penetration
    into depth and its journal point's offset from its bearing point into offset; the ideal
    joints' largest gap |Phi|."""
    return core.observe(t, y, dy, args, work, depth, offset)


def observe_steps(times, states, speeds, latched, modes, args, work, *seen) -> None:
    """observe, the kinetic energy, the torsion angles and the springs' stretches at every
    recorded step, each with the law memory it was taken with, into the rows of `seen`."""
    core.observe_steps(times, states, speeds, latched, modes, args, work, *seen)


def relative_motion(y, args, work, bb, s_b, bj, s_j, f, g):
    """Body bj's point s_j relative to body bb's point s_b along bb's vectors f and g:
    (e.f, e.g, v.f, v.g)."""
    return core.relative_motion(y, args, work, bb, s_b, bj, s_j, f, g)


def constraint_values(t, y, args):
    """(Phi_q, Phi, Phi_t) of the ideal joints, the drive and the held contacts."""
    return core.constraint_values(t, y, args)


def project_onto_constraints(t, y, args, work, tolerance, rate_tolerance) -> bool:
    """One mass-weighted Gauss-Newton step of positions and of velocities onto the
    constraints where they drifted; whether one was taken."""
    return core.project_onto_constraints(t, y, args, work, tolerance, rate_tolerance)


def energy_of(y, args) -> float:
    """The bodies' kinetic energy (J)."""
    return core.energy_of(y, args)


def slice_approaches(y, args, work, k, approaches, weights):
    """The slices of sliced contact k: their approaches and weights into the arrays; the
    bore's displacement (global)."""
    return core.slice_approaches(y, args, work, k, approaches, weights)
