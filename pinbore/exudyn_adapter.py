"""pinbore's calibrated revolute clearance joint in Exudyn [Gerstmayr2023], from the tables of
`pinbore export LAWS --to exudyn --out DIR` (which writes this file as DIR/pinbore_exudyn.py).
It needs numpy and exudyn only, not pinbore.

    from pinbore_exudyn import ExportedLaw, accept, add_revolute_clearance
    law = ExportedLaw("DIR")                     # DIR/export.json and its tables; law="liu"
    contact = add_revolute_clearance(mbs, bearing_marker, journal_marker, law)
    mbs.Assemble(); accept(mbs, 0.0)             # the initial state: the histories' first row
    mbs.SolveDynamic(settings)                   # a fixed step: see below
    contact.history                              # (t, delta, rate, v0, F) per accepted step

The force is pinbore's continuous contact, F(d, d') = max(F_el(d) (1 + chi(v0) d'/v0), 0) for
d = |e| - c > 0 (e: the journal's centre from the bearing's, c the clearance), along n = e/|e|,
equal and opposite on the two centres, d' = n . (v_journal - v_bearing), v0 the approach rate
at the contact's onset (at least export.json's speed floor). F_el is the exported table
interpolated log-log (the power law of the first segment below it), chi linear in ln v0 between
damping.csv's rows, held at its ends: what pinbore's engine evaluates.

The joint is an ObjectConnectorCartesianSpringDamper whose spring-force user function returns
the force vector (Exudyn applies it +f on the first marker, -f on the second: the bearing first).
Exudyn calls that function at Newton's trial states and at perturbed states of its Jacobian,
so the contact's state (on or off, v0) changes only at accepted steps, in the post-step user
function this module installs; within the step where a contact begins, v0 is the rate
interpolated linearly in d to d = 0 between the last accepted state and the trial state. Use an
implicit solver at a fixed step (generalized-alpha with spectral radius 1, or
TrapezoidalIndex2) and halve the step until the peaks you need stop changing: against pinbore's
Flores slider-crank, 0.5 us gives the first impact's peak within 1e-4.
"""

import csv
import json
import math
from pathlib import Path

import numpy as np


def _table(path: Path) -> np.ndarray:
    with path.open() as f:
        rows = list(csv.reader(f))[1:]
    return np.array(rows, float)


class ExportedLaw:
    """The exported contact law of one joint: force (N) against approach (m), approach rate
    (m/s) and the contact's onset speed v0 (m/s)."""

    def __init__(self, folder, law: str | None = None):
        folder = Path(folder)
        self.description = json.loads((folder / "export.json").read_text())
        laws = self.description["laws"]
        if law is None:
            if len(laws) != 1:
                raise ValueError(f"{folder}: several laws ({', '.join(laws)}): name one, law=...")
            law = next(iter(laws))
        self.name = law
        self.clearance = self.description["joint"]["clearance_m"]
        self.speed_floor = self.description["speed_floor_m_per_s"]
        force = _table(folder / laws[law]["table"])
        self._log_d, self._log_f = np.log(force[:, 0]), np.log(force[:, 1])
        damping = _table(folder / self.description["damping"]["table"])
        self._log_v, self._chi = np.log(damping[:, 0]), damping[:, 1]

    def elastic(self, d: float) -> float:
        """F_el (N) at the approach d > 0 (m): log-log interpolation; NaN beyond the table."""
        x = math.log(d)
        if x > self._log_d[-1]:
            return math.nan
        if x < self._log_d[0]:
            slope = (self._log_f[1] - self._log_f[0]) / (self._log_d[1] - self._log_d[0])
            return math.exp(self._log_f[0] + slope * (x - self._log_d[0]))
        return math.exp(float(np.interp(x, self._log_d, self._log_f)))

    def chi(self, impact_speed: float) -> float:
        """The Hunt-Crossley factor at v0 (m/s): linear in ln v0, held at the table's ends."""
        return float(np.interp(math.log(impact_speed), self._log_v, self._chi))

    def __call__(self, d: float, rate: float, impact_speed: float) -> float:
        """F (N) at the approach d (m) and rate d' (m/s) of a contact begun at v0 (m/s)."""
        if d <= 0.0:
            return 0.0
        return max(self.elastic(d) * (1.0 + self.chi(impact_speed) * rate / impact_speed), 0.0)


class ClearanceContact:
    """One clearance joint's contact state: on or off, the onset speed v0, the last accepted
    (d, d'), and the history of the accepted steps."""

    def __init__(self, law, clearance: float, speed_floor: float):
        self.law, self.c, self.floor = law, clearance, speed_floor
        self.in_contact = False
        self.v0 = speed_floor
        self.last = (-clearance, 0.0)
        self.history = []   # (t, delta, rate, v0, force)

    def kinematics(self, e, v):
        """(d = |e| - c, n = e/|e|, d' = n . v) of the eccentricity e and its rate v (2D)."""
        size = math.hypot(e[0], e[1])
        if size == 0.0:
            return -self.c, (1.0, 0.0), 0.0
        n = (e[0] / size, e[1] / size)
        return size - self.c, n, n[0] * v[0] + n[1] * v[1]

    def onset_speed(self, delta: float, rate: float) -> float:
        """v0 of a contact begun between the last accepted state (d <= 0) and this one (d > 0):
        the rate interpolated linearly in d to d = 0, at least the speed floor."""
        d0, r0 = self.last
        s = -d0 / (delta - d0) if delta != d0 else 1.0
        return max(r0 + s * (rate - r0), self.floor)

    def force(self, delta: float, rate: float) -> float:
        """F (N) at a (trial) state; the contact's state is not changed."""
        if delta <= 0.0:
            return 0.0
        v0 = self.v0 if self.in_contact else self.onset_speed(delta, rate)
        return float(self.law(delta, rate, v0))

    def accept(self, t: float, delta: float, rate: float) -> None:
        """An accepted step: the contact begins or ends, the history records it."""
        if delta > 0.0 and not self.in_contact:
            self.v0, self.in_contact = self.onset_speed(delta, rate), True
        elif delta <= 0.0 and self.in_contact:
            self.in_contact = False
        self.history.append((t, delta, rate, self.v0 if self.in_contact else 0.0,
                             self.force(delta, rate)))
        self.last = (delta, rate)


_CONTACTS = {}   # id(mbs) -> [(contact, bearing marker, journal marker)]: one post-step hook


def accept(mbs, t: float) -> bool:
    """Every clearance joint of `mbs` at an accepted state (Exudyn's post-step user function;
    call it once after mbs.Assemble() to record the initial state)."""
    import exudyn as exu   # noqa: PLC0415

    position, velocity = exu.OutputVariableType.Position, exu.OutputVariableType.Velocity
    for contact, bearing, journal in _CONTACTS.get(id(mbs), []):
        e = mbs.GetMarkerOutput(journal, position) - mbs.GetMarkerOutput(bearing, position)
        v = mbs.GetMarkerOutput(journal, velocity) - mbs.GetMarkerOutput(bearing, velocity)
        delta, _, rate = contact.kinematics(e, v)
        contact.accept(t, delta, rate)
    return True


def add_revolute_clearance(mbs, bearing_marker: int, journal_marker: int,
                           law: ExportedLaw) -> ClearanceContact:
    """Add a planar revolute clearance joint between two position markers (the bearing's
    centre, the journal's centre) of the Exudyn system `mbs`; its ClearanceContact. Installs
    `accept` as the system's post-step user function."""
    from exudyn.itemInterface import ObjectConnectorCartesianSpringDamper   # noqa: PLC0415

    contact = ClearanceContact(law, law.clearance, law.speed_floor)

    def contact_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        delta, n, rate = contact.kinematics(displacement, velocity)
        f = contact.force(delta, rate)
        return [f * n[0], f * n[1], 0.0]

    mbs.AddObject(ObjectConnectorCartesianSpringDamper(
        markerNumbers=[bearing_marker, journal_marker], springForceUserFunction=contact_force))
    _CONTACTS.setdefault(id(mbs), []).append((contact, bearing_marker, journal_marker))
    mbs.SetPostStepUserFunction(accept)
    return contact
