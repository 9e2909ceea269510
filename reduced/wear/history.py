"""What a revolute clearance joint of a planar mechanism does over a cycle, as wear needs it:
per recorded step its contact force, the contact's direction in the bore's frame and in the
pin's, and the sliding speed at the contact."""

import math
from dataclasses import dataclass

import numpy as np

from pinbore.reduced.mechanism import kernel


@dataclass(frozen=True)
class JointHistory:
    """Per recorded step: time (s), the contact's normal force (N), the direction of the
    contact from the bore's centre in the bore's frame and in the pin's (rad), and the
    tangential speed of the pin's surface over the bore's there (m/s); and of the whole run,
    the largest force of the joint's first contact (N: its first impact)."""

    time: np.ndarray
    force: np.ndarray
    bore_angle: np.ndarray
    pin_angle: np.ndarray
    sliding_speed: np.ndarray
    first_impact: float = 0.0


def of_run(model, trajectory, j: int, window: tuple[float, float]) -> JointHistory:
    """The history of planar clearance joint j (a journal in a bore) over the recorded steps
    of `trajectory` within `window` (s). The direction is the contact's as the core finds it
    (the journal centre's offset e from the bore's on a round joint; on a worn one the normal
    of the force of the arc where its surfaces overlap); the slip v_s = t . (v_pin - v_bore) + (w_pin - w_bore) R_pin at
    the contact, t its tangent, the material velocities taken at the journal's centre."""
    from pinbore.reduced.mechanism.outputs import observed_steps   # noqa: PLC0415

    c = model.joints[j]
    index = {name: i for i, name in enumerate(model.names)}
    bearing, journal = index.get(c.bearing_body, -1), index.get(c.journal_body, -1)
    keep = (trajectory.times >= window[0]) & (trajectory.times <= window[1])
    seen = observed_steps(model, trajectory)
    rows = list(model.contact_rows[j])
    whole = seen["normals"][:, rows].sum(axis=1)
    force = whole[keep]
    args, work = seen["args"], seen["work"]
    states = trajectory.states[keep]
    offsets = np.empty((states.shape[0], 4))
    for i, y in enumerate(states):
        offsets[i] = kernel.relative_motion(y, args, work, bearing, list(c.bearing_point), journal,
                                            list(c.journal_point), [1.0, 0.0], [0.0, 1.0])
    phi_b, w_b = _rotation(model, states, bearing)
    phi_j, w_j = _rotation(model, states, journal)
    normal = seen["directions"][keep, rows[0]]   # global; the bore's frame turned by phi_b
    bore_angle = np.mod(np.arctan2(normal[:, 1], normal[:, 0]) - phi_b + math.pi, 2 * math.pi) - math.pi
    slip = (-np.sin(bore_angle) * offsets[:, 2] + np.cos(bore_angle) * offsets[:, 3]
            + (w_j - w_b) * c.journal_radius)
    return JointHistory(trajectory.times[keep], force, bore_angle,
                        np.mod(bore_angle + phi_b - phi_j + math.pi, 2 * math.pi) - math.pi, slip,
                        first_contact_peak(whole))


def first_contact_peak(force: np.ndarray) -> float:
    """The largest of a force history's first run of steps in contact (force > 0; 0 if none)."""
    touching = np.flatnonzero(force > 0)
    if touching.size == 0:
        return 0.0
    start = touching[0]
    parted = np.flatnonzero(force[start:] <= 0)
    end = start + (parted[0] if parted.size else force.size - start)
    return float(force[start:end].max())


def _rotation(model, states, body: int) -> tuple[np.ndarray, np.ndarray]:
    """A body's angle and angular velocity in each state (the ground's: 0)."""
    if body < 0:
        return np.zeros(states.shape[0]), np.zeros(states.shape[0])
    column = int(model.base.offsets[body]) + 2   # a planar body's coordinates x, y, phi
    return states[:, column], states[:, model.nq + column]
