"""The files of `pinbore impact`, defined once: history.csv (one row per time step) and
impact.json (the summary: restitution, contact duration, peak force, energy book). The impact
run writes them through `write_history` and `write_summary`; the calibration, the report,
the benchmarks and the tests read them through `read_history` and `read_summary`.

Plane strain: forces per unit length (N/m), energies per unit length (J/m), masses per unit
length (kg/m). Every history column name carries its unit. A file that does not fit (another
version's columns, a cell that is not a finite number, a summary key missing) is one
InputError line naming the file and the rule.
"""

from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.core.scene import Record, read_json, validate
from pinbore.fem.curve import Column, _float, _read, _write

COMMAND = "impact"
HISTORY = "history.csv"   # the two files of one impact's output directory
SUMMARY = "impact.json"


@dataclass(frozen=True)
class History:
    """The columns of a history.csv as arrays, one entry per time point from t = 0."""

    path: Path
    time: np.ndarray             # s
    approach: np.ndarray         # m, hub travel along the impact direction beyond first touch
    force: np.ndarray            # N/m, contact resultant along the impact direction
    hub_velocity: np.ndarray     # m/s, along the impact direction
    pin_velocity: np.ndarray     # m/s, the pin's momentum along it over its mass
    half_angle: np.ndarray       # deg, contact half-angle
    min_gap: np.ndarray          # m, smallest gap of the pin's nodes (< 0: penetration)
    kinetic: np.ndarray          # J/m
    strain: np.ndarray           # J/m, stored elastic energy
    plastic_work: np.ndarray     # J/m, dissipated by plastic flow so far
    contact_energy: np.ndarray   # J/m, stored by the penalty
    contact_work: np.ndarray     # J/m, done by the bodies on the contact so far
    friction_work: np.ndarray    # J/m, dissipated by friction so far
    residual: np.ndarray         # J/m, E_0 - kinetic - strain - plastic_work - contact_energy
                                 #      - friction_work
    newton_iterations: np.ndarray
    time_step: np.ndarray        # s


COLUMNS = {
    "time": _float("time_s", "s"), "approach": _float("approach_m", "m"),
    "force": _float("force_per_length_N_per_m", "N/m"),
    "hub_velocity": _float("hub_velocity_m_per_s", "m/s"),
    "pin_velocity": _float("pin_velocity_m_per_s", "m/s"),
    "half_angle": _float("half_angle_deg", "deg", ".6f"), "min_gap": _float("min_gap_m", "m"),
    "kinetic": _float("kinetic_energy_J_per_m", "J/m"),
    "strain": _float("strain_energy_J_per_m", "J/m"),
    "plastic_work": Column("plastic_work_J_per_m", "J/m", float, ".9e", absent=0.0),
    "contact_energy": _float("contact_energy_J_per_m", "J/m"),
    "contact_work": _float("contact_work_J_per_m", "J/m"),
    "friction_work": Column("friction_work_J_per_m", "J/m", float, ".9e", absent=0.0),
    "residual": _float("energy_residual_J_per_m", "J/m"),
    "newton_iterations": Column("newton_iterations", "1", int),
    "time_step": _float("time_step_s", "s"),
}
assert list(COLUMNS) == [f.name for f in fields(History) if f.name != "path"]


def write_history(path: Path, rows) -> None:
    """history.csv; a row maps every field of History (but path) to its value."""
    _write(path, COLUMNS, rows)


def read_history(path) -> History:
    path = Path(path)
    _, values = _read(path, {2: COLUMNS}, COMMAND)
    return History(path, **values)


class EnergyBook(Record):
    """Where the impact energy m v0^2 / 2 went, at the end of the run (J/m), and the book's
    largest residual over the run relative to the impact energy."""

    impact_J_per_m: float
    kinetic_J_per_m: float
    strain_J_per_m: float            # stored elastic energy
    plastic_J_per_m: float = 0.0     # plastic work (0: elastic bodies)
    contact_J_per_m: float           # stored by the penalty (normal and stick)
    contact_work_J_per_m: float      # done on the contact (trapezoidal rule)
    friction_J_per_m: float = 0.0    # dissipated by friction
    rebound_J_per_m: float           # |p|^2 / (2 m): the pin's flight after separation
    wave_J_per_m: float              # kinetic + strain - rebound: vibration, waves, locked stress
    residual_J_per_m: float          # impact - kinetic - strain - plastic - contact - friction
    scheme_residual_J_per_m: float   # impact - kinetic - strain - plastic - contact work
    max_relative_residual: float     # max over the run of |residual| / impact


class ImpactSummary(Record):
    scene_file: str
    scene: dict
    status: str                      # complete | incomplete | suspect (see `verdict`)
    stop: str | None
    verdict: list[str] = []          # why a finished run's numbers are not to be trusted
    speed_m_per_s: float
    pin_mass_kg_per_m: float         # the FE pin's mass (annulus + hub + added)
    hub_mass_kg_per_m: float         # the rigid hub: its own core and the added mass
    restitution: float | None        # -p . d / (m v0) after separation; None: no separation
    rebound_velocity_m_per_s: list[float]
    contact_duration_s: float | None
    peak_force_N_per_m: float
    approach_at_peak_m: float
    max_approach_m: float
    energy: EnergyBook
    max_plastic_strain: float = 0.0  # the largest equivalent plastic strain at the end
    estimate: dict                   # Liu's law before the run: duration, max approach
    time_step_s: float               # the step dt; steps in contact may be shorter
    smallest_step_s: float | None = None   # the shortest step taken (energy control, cutbacks)
    spectral_radius: float
    steps: int
    steps_in_contact: int
    cutbacks: int
    energy_rejections: int = 0       # steps repeated smaller by the energy control
    newton_iterations: int
    factorizations: int = 0          # LU factorisations of the Jacobian, redone steps included
    dofs: int
    mesh: dict
    contact: dict
    wall_time_s: dict
    platform: dict


def history_beside(summary_path) -> Path:
    """The history.csv of the run whose impact.json (or output directory) is given."""
    path = Path(summary_path)
    return (path if path.is_dir() else path.parent) / HISTORY


# a finished impact's numbers are suspect beyond these (measured on the shipped study: energy
# book <= 6e-4 of E0, contact 0.46-0.97 of Liu's estimate, wave energy <= 0.76 E0)
BOOK_LIMIT = 1e-2               # the energy book's largest residual, of E0
DURATION_RANGE = (0.1, 10.0)    # the contact duration, of the estimate on Liu's law


def verdict(summary: ImpactSummary) -> list[str]:
    """Why a finished impact (status complete) is not to be trusted, or nothing: an energy
    book that does not close, a restitution outside 0 < e <= 1 (energy from nowhere, or no
    rebound), a contact far shorter or longer than Liu's law allows, more energy left in the
    bodies' vibration than came in."""
    reasons = []
    e0 = summary.energy.impact_J_per_m
    if not summary.energy.max_relative_residual <= BOOK_LIMIT:
        reasons.append(f"the energy book's residual reached {summary.energy.max_relative_residual:.3g} "
                       f"E0 (limit {BOOK_LIMIT:g})")
    e = summary.restitution
    if e is not None and not 0 < e <= 1 + summary.energy.max_relative_residual:
        reasons.append(f"restitution e = {e:.4g} outside 0 < e <= 1")
    duration, estimate = summary.contact_duration_s, summary.estimate.get("contact_duration_s")
    if duration is not None and estimate:
        low, high = DURATION_RANGE
        if not low * estimate <= duration <= high * estimate:
            reasons.append(f"contact duration {duration:.3g} s against {estimate:.3g} s estimated "
                           f"on Liu's law (outside {low:g}-{high:g} times)")
    if not summary.energy.wave_J_per_m <= e0 * (1 + BOOK_LIMIT):
        reasons.append(f"vibration energy {summary.energy.wave_J_per_m / e0:.3g} E0 after the "
                       "impact, more than came in")
    return reasons


def write_summary(path: Path, summary: ImpactSummary) -> None:
    path.write_text(summary.model_dump_json(indent=2) + "\n")


def read_summary(path, source: str | None = None) -> ImpactSummary:
    """impact.json, checked: its keys, a positive impact speed and mass, a restitution
    (if any) in 0 < e <= 1, a scene record that reads as an impact scene."""
    from pinbore.fem.impact.scene import ImpactScene   # noqa: PLC0415 (its laws compile)

    summary = read_json(ImpactSummary, path, COMMAND, source)
    where = str(path) if source is None else source
    again = f"(run pinbore {COMMAND} again)"
    for key in ("speed_m_per_s", "pin_mass_kg_per_m"):
        value = getattr(summary, key)
        if not (value == value and 0 < value < float("inf")):
            raise InputError(f"{where}: {key}: must be a positive number, not {value} {again}")
    e = summary.restitution
    if (summary.status != "suspect" and e is not None
            and not 0 < e <= 1 + summary.energy.max_relative_residual):   # a suspect run says why
        raise InputError(f"{where}: restitution: {e} is outside 0 < e <= 1 {again}")
    validate(ImpactScene, summary.scene, f"{where}: scene")
    return summary
