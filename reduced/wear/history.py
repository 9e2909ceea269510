"""What a revolute clearance joint of a planar mechanism does over a cycle, as wear needs it:
per recorded step its contact force, the contact's direction in the bore's frame and in the
pin's, and the sliding speed at the contact."""

import math
from dataclasses import dataclass

import numpy as np

from pinbore.reduced.mechanism import kernel
from pinbore.reduced.mechanism.layout import CONTACT_BORE_WEAR, CONTACT_PIN_WEAR, CONTACT_WEAR_REACH


@dataclass(frozen=True)
class JointHistory:
    """Per recorded step: time (s), the contact's normal force (N), the direction of the
    contact from the bore's centre in the bore's frame and in the pin's (rad), and the
    tangential speed of the pin's surface over the bore's there (m/s)."""

    time: np.ndarray
    force: np.ndarray
    bore_angle: np.ndarray
    pin_angle: np.ndarray
    sliding_speed: np.ndarray


def of_run(model, trajectory, j: int, window: tuple[float, float]) -> JointHistory:
    """The history of planar clearance joint j (a journal in a bore) over the recorded steps
    of `trajectory` within `window` (s). The direction is the contact's (contact_angle: the
    journal centre's offset e from the bore's on a round joint); the slip v_s = t . (v_pin -
    v_bore) + (w_pin - w_bore) R_pin at the contact, t its tangent, the material velocities
    taken at the journal's centre."""
    from pinbore.reduced.mechanism.outputs import observed_steps   # noqa: PLC0415

    c = model.joints[j]
    index = {name: i for i, name in enumerate(model.names)}
    bearing, journal = index.get(c.bearing_body, -1), index.get(c.journal_body, -1)
    keep = (trajectory.times >= window[0]) & (trajectory.times <= window[1])
    seen = observed_steps(model, trajectory)
    rows = list(model.contact_rows[j])
    force = seen["normals"][:, rows].sum(axis=1)[keep]
    args, work = seen["args"], seen["work"]
    states = trajectory.states[keep]
    offsets = np.empty((states.shape[0], 4))
    for i, y in enumerate(states):
        offsets[i] = kernel.relative_motion(y, args, work, bearing, list(c.bearing_point), journal,
                                            list(c.journal_point), [1.0, 0.0], [0.0, 1.0])
    phi_b, w_b = _rotation(model, states, bearing)
    phi_j, w_j = _rotation(model, states, journal)
    bore_angle = np.arctan2(offsets[:, 1], offsets[:, 0])
    touching = force > 0   # wear needs the contact's direction where it carries a force
    bore_angle[touching] = contact_angle(model, rows[0], offsets[touching, 0], offsets[touching, 1],
                                         (phi_b - phi_j)[touching])
    slip = (-np.sin(bore_angle) * offsets[:, 2] + np.cos(bore_angle) * offsets[:, 3]
            + (w_j - w_b) * c.journal_radius)
    return JointHistory(trajectory.times[keep], force, bore_angle,
                        np.mod(bore_angle + phi_b - phi_j + math.pi, 2 * math.pi) - math.pi, slip)


def contact_angle(model, k: int, ex, ey, turn) -> np.ndarray:
    """The direction of contact k in the bore's frame at each step (rad), e = (ex, ey) the
    journal centre's offset there and `turn` the bore's frame angle less the pin's: e's
    direction on a round joint; on a worn one (its profiles in Args.wear) where the worn
    surfaces interfere most, max over phi of e . u(phi) - h_bore(phi) - h_pin(phi + turn), as
    the core finds it (searched here at a quarter of the profiles' spacing within the reach of
    their depths, the best sample's parabola's vertex)."""
    direction = np.arctan2(ey, ex)
    row = model.base.contacts[k]
    bore, pin = int(row[CONTACT_BORE_WEAR]) - 1, int(row[CONTACT_PIN_WEAR]) - 1
    if bore < 0 and pin < 0:
        return direction
    wear = model.base.wear
    points = wear.shape[1]
    grid = -math.pi + 2 * math.pi * np.arange(points + 1) / points

    def depth(r, a):
        if r < 0:
            return 0.0
        return np.interp(np.mod(a + math.pi, 2 * math.pi) - math.pi, grid, np.append(wear[r], wear[r][0]))

    size = np.hypot(ex, ey)
    spread = np.arccos(np.clip(1 - row[CONTACT_WEAR_REACH] / np.maximum(size, 1e-300), -1.0, 1.0))
    samples = np.linspace(-1.0, 1.0, 4 * points + 1)
    out = np.empty(direction.size)
    for start in range(0, direction.size, 128):   # a block of steps at a time
        block = slice(start, start + 128)
        phi = direction[block, None] + spread[block, None] * samples[None, :]
        f = (ex[block, None] * np.cos(phi) + ey[block, None] * np.sin(phi) - depth(bore, phi)
             - depth(pin, phi + turn[block, None]))
        i = np.clip(np.argmax(f, axis=1), 1, samples.size - 2)
        rows = np.arange(phi.shape[0])
        left, mid, right = f[rows, i - 1], f[rows, i], f[rows, i + 1]
        curvature = left - 2 * mid + right
        shift = np.where(curvature < 0, 0.5 * (left - right) / np.where(curvature < 0, curvature, 1.0), 0.0)
        step = phi[rows, 1] - phi[rows, 0]
        out[block] = phi[rows, i] + np.clip(shift, -0.5, 0.5) * step   # the parabola's vertex
    return out


def _rotation(model, states, body: int) -> tuple[np.ndarray, np.ndarray]:
    """A body's angle and angular velocity in each state (the ground's: 0)."""
    if body < 0:
        return np.zeros(states.shape[0]), np.zeros(states.shape[0])
    column = int(model.base.offsets[body]) + 2   # a planar body's coordinates x, y, phi
    return states[:, column], states[:, model.nq + column]
