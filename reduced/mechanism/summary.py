"""summary.json of `pinbore reduced`, defined once as a validated model: the run builds a
Summary (reduced.mechanism.outputs) and writes it (`write`); the report, the tests and any other
reader read it back through `read`.

Units are SI and every key carries its unit (_N, _s, _m, _J ...); forces are those of the
whole joint (N). A file that does not validate, e.g. one written by an older version of
pinbore, is one InputError line naming the file and the key (`<file>: <key>: <rule> (written
by another version of pinbore? run pinbore reduced again)`).
"""

import json
import math
from pathlib import Path
from typing import Literal

from pinbore.core.errors import InputError
from pinbore.core.scene import Record, read_json


class JointPeaks(Record):
    """One clearance joint over the run: its peaks and impacts."""

    peak_normal_force_N: float   # refined between the steps (continuous contacts)
    time_of_peak_s: float
    impacts: int
    peak_impact_speed_m_per_s: float
    peak_impulse_N_s: float      # rigid impacts (0 for continuous contact)
    peak_penetration_m: float
    peak_friction_force_N: float
    clearance_m: float


class Stop(Record):
    """Where and why a run that did not complete stopped."""

    time_s: float
    reason: str


class EnergyBalance(Record):
    """Kinetic + potential + elastic + dissipated - work in, which a run keeps constant."""

    max_residual_J: float
    relative_to_peak_kinetic: float
    dissipated_J: float
    work_in_J: float


class Summary(Record):
    model: Literal["planar", "spatial"]   # the kind of mechanism (reduced.mechanism.kinds)
    coordinates: str            # what its state's coordinates are, per body
    status: Literal["complete", "incomplete", "suspect"]   # suspect: see `verdict`
    stop: Stop | None           # None: complete
    duration_s: float           # asked by the scene
    time_reached_s: float
    integrator: str
    clearance_joints: dict[str, JointPeaks]
    impacts: int
    steps: int                  # accepted
    rejected_steps: int
    rhs_evaluations: int
    wall_time_s: float          # of the integration
    energy_balance: EnergyBalance
    constraint_drift_max: float   # m, the largest gap of the ideal joints
    warnings: list[str]         # e.g. a calibrated law used beyond its calibrated range
    verdict: list[str] = []     # why the run is suspect (reduced.mechanism.verdict); empty: nothing
    scene_file: str

    @property
    def peak_normal_force_N(self) -> float:
        """The largest peak over the clearance joints (0 without any)."""
        return max((j.peak_normal_force_N for j in self.clearance_joints.values()), default=0.0)


def write(path: Path, summary: Summary) -> None:
    path.write_text(json.dumps(summary.model_dump(), indent=2) + "\n")


def read(path) -> Summary:
    """summary.json validated: its model, and a complete run's peaks and energy book finite
    numbers (a run that writes NaN is marked suspect or incomplete by its verdict: a
    complete one with NaN is not what pinbore wrote)."""
    summary = read_json(Summary, path, "reduced")
    if summary.status == "complete":
        numbers = [v for j in summary.clearance_joints.values() for v in j.model_dump().values()]
        numbers += list(summary.energy_balance.model_dump().values())
        if not all(math.isfinite(v) for v in numbers):
            raise InputError(f"{path}: status: complete, but a peak or the energy book is not a "
                             "finite number (not a summary pinbore wrote: run pinbore reduced again)")
    return summary
