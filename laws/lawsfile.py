"""laws.json, the file `pinbore calibrate` writes for the multibody model, defined once as a
validated model: the calibration builds a LawsFile and writes it (`write`); the multibody
model, its summary and the report read it back through `read`.

Units are SI; forces are per unit length (N/m, plane strain): a multibody joint of axial
length L takes F = P L. Every law is kept as published (errors only) and, where the curves
fix its parameters, calibrated: P = s P_law(d) (d / d_ref)^q (`Fit.force`, the one
implementation of that law, `pinbore.laws.elastic.calibrated`).

The 3D laws (`sliced`, one per kind of ends and materials pair) are the sliced law of a
finite pin (pinbore.laws.sliced) on a per-length law of this file or a published one, with
forces in N and moments in N m (calibration/sliced.py).

A file that does not validate, e.g. one written by an older version of pinbore, is one
InputError line naming the file and the key, e.g.
`<file>: laws.liu.fitted: required key is missing (written by another version of pinbore?
run pinbore calibrate again)`. The file holds no version number: the model is the version.
"""

import json
import math
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import pydantic

from pinbore.core.errors import InputError
from pinbore.core.scene import Positive, Record, read_json
from pinbore.laws import elastic

Range = Annotated[list[float], pydantic.Field(min_length=2, max_length=2)]   # [low, high]
# the physical values of the file, range-checked on read as a scene's are (a Record's numbers
# may otherwise be inf or nan: an error that a law without a solution records honestly)
NonNegative = Annotated[float, pydantic.Field(ge=0, allow_inf_nan=False)]
Poisson = Annotated[float, pydantic.Field(gt=-1, lt=0.5, allow_inf_nan=False)]
EXPONENT_CORRECTION = 3.0   # |q| of a calibrated law beyond which it is no longer a contact's


def pin_in_bore(pin: float, bore: float, names: tuple[str, str]) -> None:
    """ValueError unless the pin's radius is smaller than the bore's (m)."""
    if pin >= bore:
        raise ValueError(f"{names[0]} {pin:g} m must be smaller than {names[1]} {bore:g} m")


def _ordered(span: list[float]) -> list[float]:
    if span[0] > span[1]:
        raise ValueError(f"the range [{span[0]:g}, {span[1]:g}] runs backwards")
    return span


Span = Annotated[list[Annotated[float, pydantic.Field(allow_inf_nan=False)]],
                 pydantic.Field(min_length=2, max_length=2),
                 pydantic.AfterValidator(_ordered)]   # [low, high] of a range covered, low <= high
MODEL = "P = scale * P_law(d) * (d / reference_approach_m)^exponent_correction"
LAWS = list(elastic.PUBLISHED) + ["linear"]   # the laws a laws file holds, by name


def law_force(name: str, d, joint):
    """The published force per length of law `name` (the linear spring: E* d)."""
    if name == "linear":
        return elastic.linear(d, joint.e_star)
    return elastic.PUBLISHED[name](d, joint)


class Errors(Record):
    """How far a law's force is from the FE force over one curve's approaches."""

    max_rel: float   # largest |P_law / P_FE - 1|
    rms_rel: float   # root mean square of P_law / P_FE - 1
    points: int      # approaches where the law has a solution


class Fit(Record):
    """A law calibrated on FE curves: its stiffness factor s and exponent correction q about
    the reference approach d_ref, with 95 % confidence intervals."""

    model: Literal[MODEL]
    scale: Positive
    scale_ci95: Range
    exponent_correction: float = pydantic.Field(ge=-EXPONENT_CORRECTION, le=EXPONENT_CORRECTION,
                                                allow_inf_nan=False)
    exponent_correction_ci95: Range
    reference_approach_m: Positive
    points: int = pydantic.Field(ge=1)   # approaches the fit used

    def force(self, name: str, d, joint) -> np.ndarray:
        """P(d) (N/m) of law `name` calibrated, at the approaches d (m), for `joint`."""
        d = np.asarray(d, float)
        return elastic.calibrated(d, law_force(name, d, joint), self.scale,
                                  self.exponent_correction, self.reference_approach_m)


class Validity(Record):
    """The ranges the curves covered: a calibrated law is used beyond them by extrapolation."""

    clearance_m: Span
    clearance_ratio: Span
    approach_m: Span
    housing_ratio: Span


class Law(Record):
    formula: str                                 # the law's docstring, on one line
    published_errors: dict[str, Errors] | None   # per curve; None: no published form (linear)
    fitted: Fit | None                           # None: the curves cannot fix s and q
    not_fitted: str | None                       # why not
    fitted_errors: dict[str, Errors] | None      # per curve, of the calibrated law
    validity: Validity
    fitted_to: list[str]                         # the curves' names


class JointRecord(Record):
    """The joint a per-length law was evaluated for (pinbore.laws.elastic.Joint): radii (m),
    moduli (Pa), Poisson's ratios, and the axial length (m) the laws that need one take."""

    r_bore: Positive
    r_pin: Positive
    E_bore: Positive
    nu_bore: Poisson
    E_pin: Positive
    nu_pin: Poisson
    length: Positive

    @pydantic.model_validator(mode="after")
    def _pin_in_bore(self):
        pin_in_bore(self.r_pin, self.r_bore, ("r_pin", "r_bore"))
        return self

    @classmethod
    def of(cls, joint: elastic.Joint) -> "JointRecord":
        return cls(**{k: getattr(joint, k) for k in cls.model_fields})

    def joint(self, r_bore: float, r_pin: float) -> elastic.Joint:
        """This joint's materials and law length with the radii (m) of another joint."""
        return elastic.Joint(r_bore, r_pin, self.E_bore, self.nu_bore, self.E_pin, self.nu_pin,
                             self.length)


class CurveEntry(Record):
    """One FE curve the laws were calibrated on."""

    name: str
    points: int
    clearance_m: float
    bore_radius_m: float
    effective_modulus_Pa: float
    housing_ratio: float   # housing radius / bore radius
    similar_materials: bool
    approach_m: Range
    persson_half_angle_error_deg: float | None   # None: dissimilar materials
    joint: JointRecord | None = None   # radii, materials; None: a file of an older pinbore


SLICED_MODEL = ("F = scale * (sum_i f_loc(delta_i) L/n + end_length (f_0 + f_n-1)), M likewise "
                "with the arms z_i - L/2; delta_i = delta - bulk_compliance F / L + theta (z_i - "
                "L/2) - relief(z_i); f_loc: the per-length law f with the bulk compliance taken "
                "out, f(u + bulk_compliance f_loc(u)) = f_loc(u)")


class Errors3D(Record):
    """How far the sliced law is from one 3D FE curve."""

    force_max_rel: float
    moment_max_rel: float | None   # over the tilted steps; None: the curve has none
    points: int


class Validity3D(Record):
    approach_m: Span
    tilt_rad: Span
    length_m: Span


SECTION_REACH = 2.0   # the section law holds up to this multiple of the FE's last approach


class Section(Record):
    """The per-length law `section`: the 2D FE curve of the 3D curves' own plane section
    (radii, housing, hub, materials), its push steps (m, N/m)."""

    curve: str
    approach_m: list[float]
    force_N_per_m: list[float]

    def force(self, d) -> np.ndarray:
        """P(d) (N/m): log-log interpolation between the FE points, the power law of the
        first two points below them (P -> 0 with d) and of the last two above them up to
        twice the last approach (the split of the bulk compliance, laws/sliced.py, reaches
        local approaches above the FE's: u = d - c_b P(d)), NaN beyond (no further
        extrapolation of the FE)."""
        x, lx, lf = np.log(np.asarray(d, float)), np.log(self.approach_m), np.log(self.force_N_per_m)
        below = lf[0] + (lf[1] - lf[0]) / (lx[1] - lx[0]) * (x - lx[0])
        above = lf[-1] + (lf[-1] - lf[-2]) / (lx[-1] - lx[-2]) * (x - lx[-1])
        y = np.where(x < lx[0], below, np.where(x > lx[-1], above, np.interp(x, lx, lf)))
        return np.where(x > lx[-1] + math.log(SECTION_REACH), np.nan, np.exp(y))


class SlicedLaw(Record):
    """The sliced law of a finite pin (pinbore.laws.sliced) calibrated on 3D FE curves of one
    kind of ends and one materials pair (calibration/sliced.py): the per-length law, the
    stiffness factor, the end length and the bulk compliance (m^2/N) with 95 % intervals,
    the slices that give F within 1 % at the largest tilt of the curves, the ranges
    covered."""

    model: Literal[SLICED_MODEL]
    per_length_law: str            # a published law, calibrated:<law> of this file, or section
    section: Section | None        # the 2D FE curve of per_length_law = "section"
    scale: Positive
    scale_ci95: Range
    end_length_m: float = pydantic.Field(allow_inf_nan=False)   # of either sign: an end stiffer or softer
    end_length_ci95: Range
    bulk_compliance_m2_per_N: NonNegative
    bulk_compliance_ci95: Range
    ends: Literal["flush", "running on"]
    materials: str
    slices_for_1_percent: int = pydantic.Field(ge=1)
    fit_slices: int = pydantic.Field(ge=1)   # the slicing the end length was fitted with
    joint: JointRecord             # the per-length law's joint (materials, law length)
    points: int                    # force and tilted-moment equations of the fit
    validity: Validity3D
    errors: dict[str, Errors3D]
    fitted_to: list[str]


RESTITUTION_MODEL = ("e(v0) = sum_k coefficients[k] ln(v0 / 1 m/s)^k inside speed_range_m_per_s, "
                     "held at the nearer end outside it; chi(v0): the Hunt-Crossley factor that "
                     "rebounds with e(v0)")


class ImpactPoint(Record):
    """One FE impact (impact.json of `pinbore impact`) the restitution law was fitted on."""

    name: str
    speed_m_per_s: float
    restitution: float
    fitted: float                  # e(v0) of the law at this speed
    contact_duration_s: float
    peak_force_N_per_m: float
    max_approach_m: float
    pin_mass_kg_per_m: float
    clearance_m: float
    effective_modulus_Pa: float
    plastic: bool                  # a body was elasto-plastic
    plastic_work_share: float = 0.0   # W_p / E_0: the impact energy dissipated by plastic flow


class ImpactJoint(Record):
    """The joint a restitution law holds for: what an FE impact's e depends on besides v0
    (the pin's and the bore's elastic constants and densities, the radii, the pin's mass per
    length with the hub's added mass). Impacts of one joint are fitted together."""

    pin_E_Pa: Positive
    pin_nu: Poisson
    pin_density_kg_per_m3: Positive
    bore_E_Pa: Positive
    bore_nu: Poisson
    bore_density_kg_per_m3: Positive
    pin_radius_m: Positive
    bore_radius_m: Positive
    pin_mass_kg_per_m: Positive    # rho_pin pi r_pin^2 + the hub's added mass
    # an elasto-plastic body's yield stress and hardening (plasticity_label); None: elastic
    pin_plasticity: str | None = None
    bore_plasticity: str | None = None

    @pydantic.model_validator(mode="after")
    def _pin_in_bore(self):
        pin_in_bore(self.pin_radius_m, self.bore_radius_m, ("pin_radius_m", "bore_radius_m"))
        return self

    def key(self) -> str:
        """The law's key in laws.json: materials (with the plasticity of a plastic body),
        radii, mass per length (4 digits)."""
        pin = f" {self.pin_plasticity}" if self.pin_plasticity else ""
        bore = f" {self.bore_plasticity}" if self.bore_plasticity else ""
        return (f"pin E={self.pin_E_Pa:.4g} Pa nu={self.pin_nu:.4g} "
                f"rho={self.pin_density_kg_per_m3:.4g} kg/m3{pin} | bore E={self.bore_E_Pa:.4g} Pa "
                f"nu={self.bore_nu:.4g} rho={self.bore_density_kg_per_m3:.4g} kg/m3{bore} | "
                f"r_pin={self.pin_radius_m:.6g} m r_bore={self.bore_radius_m:.6g} m | "
                f"m={self.pin_mass_kg_per_m:.4g} kg/m")

    def matches(self, r_bore, r_pin, E_pin, nu_pin, E_bore, nu_bore, rel=1e-6) -> bool:
        """Whether a multibody joint of these radii (m) and elastic constants (Pa) is this
        joint (the densities, mass per length and plasticity are not known to the multibody
        joint: two laws that differ only in those both match, which the model refuses)."""
        pairs = ((r_bore, self.bore_radius_m), (r_pin, self.pin_radius_m),
                 (E_pin, self.pin_E_Pa), (nu_pin, self.pin_nu), (E_bore, self.bore_E_Pa),
                 (nu_bore, self.bore_nu))
        return all(math.isclose(a, b, rel_tol=rel) for a, b in pairs)


def plasticity_label(material: dict) -> str | None:
    """A scene material's yield stress and hardening as a joint's key names them
    ("Y=5.5e+07 Pa H=2.76e+08 Pa", or the hardening table's points), None for an elastic one."""
    if material.get("yield_stress") is None:
        return None
    label = f"Y={material['yield_stress']:.4g} Pa"
    if material.get("hardening") is not None:
        points = ", ".join(f"({p:.4g}, {y:.4g} Pa)" for p, y in material["hardening"])
        return f"{label} table [{points}]"
    return f"{label} H={material.get('hardening_modulus') or 0.0:.4g} Pa"


class RestitutionLaw(Record):
    """The calibrated dissipative law (`damping_law = "calibrated"` of the multibody model):
    the restitution of FE impacts fitted against the impact speed, e(v0)
    (pinbore.laws.dissipative.restitution_of_speed), valid over the impacts' speeds; the
    multibody contact takes at each onset the Hunt-Crossley factor chi that rebounds with
    e(v_impact) (pinbore.laws.dissipative.hysteresis_for_restitution, exact for any elastic
    law)."""

    model: Literal[RESTITUTION_MODEL]
    joint: ImpactJoint | None = None   # None: a file of an older pinbore (one law, matched on
    #                                    its impacts' clearance and effective modulus)
    coefficients: list[Annotated[float, pydantic.Field(allow_inf_nan=False)]] = pydantic.Field(
        min_length=1, max_length=4)   # a0, a1, ...
    speed_range_m_per_s: Annotated[list[Positive], pydantic.Field(min_length=2, max_length=2),
                                   pydantic.AfterValidator(_ordered)]
    max_fit_error: float           # largest |e_fit - e_FE|
    impacts: list[ImpactPoint]

    def restitution(self, speed: float) -> float:
        """e at the impact speed v0 (m/s)."""
        from pinbore.laws import dissipative   # noqa: PLC0415 (compiled: not to read a file)

        return float(dissipative.restitution_of_speed(speed, np.asarray(self.coefficients, float),
                                                      *self.speed_range_m_per_s))

    def matches(self, r_bore, r_pin, E_pin, nu_pin, E_bore, nu_bore, rel=1e-6) -> bool:
        """Whether this law holds for a joint of these radii (m) and elastic constants (Pa);
        a law of an older file, without its joint, by its impacts' clearance and E*."""
        if self.joint is not None:
            return self.joint.matches(r_bore, r_pin, E_pin, nu_pin, E_bore, nu_bore, rel)
        e_star = 1 / ((1 - nu_pin**2) / E_pin + (1 - nu_bore**2) / E_bore)
        return all(math.isclose(q.clearance_m, r_bore - r_pin, rel_tol=1e-4)
                   and math.isclose(q.effective_modulus_Pa, e_star, rel_tol=1e-4)
                   for q in self.impacts)


class Units(Record):
    approach: str
    force: str


UNITS = Units(approach="m", force="N/m (per unit length, plane strain)")


class LawsFile(Record):
    units: Units
    length_m: Positive | None   # axial length given to the laws that need one
    length_note: str
    curves: list[CurveEntry]
    laws: dict[str, Law]
    sliced: dict[str, SlicedLaw]   # 3D: by kind of ends and materials (empty: no 3D curves)
    # from FE impacts, one law per joint (ImpactJoint.key); empty: no impacts given
    restitution: dict[str, RestitutionLaw] = {}
    warnings: list[str]
    fit_seconds: float

    @pydantic.field_validator("restitution", mode="before")
    @classmethod
    def _one_law_of_older_files(cls, value):
        """An older file's single law (or null) is read as a file of that one law."""
        if value is None:
            return {}
        if isinstance(value, dict) and "model" in value:
            return {"unkeyed (older laws.json)": value}
        return value

    def restitution_for(self, r_bore, r_pin, E_pin, nu_pin, E_bore, nu_bore) -> dict[str, RestitutionLaw]:
        """The restitution laws (by key) that hold for a joint of these radii (m) and
        elastic constants (Pa)."""
        return {key: law for key, law in self.restitution.items()
                if law.matches(r_bore, r_pin, E_pin, nu_pin, E_bore, nu_bore)}

    def fitted(self) -> dict[str, Fit]:
        """The calibrated laws by name (those the curves could fit)."""
        return {name: law.fitted for name, law in self.laws.items() if law.fitted is not None}


def curves_joint(laws_data: LawsFile, source: str, remedy: str) -> elastic.Joint:
    """The one joint (radii, materials, length) of a laws file's curves; a ValueError naming
    the joints when they are several (the law then needs a joint to be evaluated for) and
    the `remedy`."""
    records = ({tuple(c.joint.model_dump().values()) for c in laws_data.curves}
               if all(c.joint is not None for c in laws_data.curves) else set())
    if len(records) != 1:
        found = (f"{len(records)} joints (clearances "
                 f"{', '.join(sorted({f'{c.clearance_m:.3g} m' for c in laws_data.curves}))})"
                 if records else "no joint record (an older laws file)")
        raise ValueError(f"{source}: the curves hold {found}: {remedy}")
    record = laws_data.curves[0].joint
    length = laws_data.length_m if laws_data.length_m is not None else record.length
    return replace(record.joint(record.r_bore, record.r_pin), length=length)


def write(path: Path, laws: LawsFile) -> None:
    path.write_text(json.dumps(laws.model_dump(), indent=2) + "\n")


def read(path, source: str | None = None) -> LawsFile:
    """laws.json validated; `source` names it in errors (default: its path)."""
    return read_json(LawsFile, path, "calibrate", source)


def per_length_force(name: str, laws_data: "LawsFile | None", deltas, joint: elastic.Joint,
                     where: str) -> np.ndarray:
    """P(d) (N/m) at the approaches `deltas` (m) of a per-length law by name: a published law
    (pinbore.laws.elastic.PUBLISHED) or `calibrated:<law>`, the law of `laws_data` fitted on
    the FE curves (Fit.force), for `joint`. An unknown name is one InputError line naming
    `where` (the key that gave it) and the valid names. The one resolution of a law's name,
    for the multibody model and for a Python user (pinbore.laws.load)."""
    if not name.startswith("calibrated:"):
        if name not in elastic.PUBLISHED:
            raise InputError(f"{where}: {name!r} is not a published law; valid: "
                             f"{', '.join(elastic.PUBLISHED)}")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the range is the caller's (a table's NaN beyond it)
            return elastic.PUBLISHED[name](deltas, joint)
    law = name.split(":", 1)[1]
    fitted = laws_data.fitted() if laws_data is not None else {}
    if law not in fitted:
        raise InputError(f"{where}: {name!r} is not a fitted law of the laws file; valid: "
                         + (f"calibrated:{', calibrated:'.join(fitted)}" if fitted else "none"))
    return fitted[law].force(law, deltas, joint)


def joint_restitution(laws_data: "LawsFile | None", joint: elastic.Joint,
                      where: str) -> RestitutionLaw:
    """The restitution law of `laws_data` fitted on FE impacts of `joint`'s radii and of its
    pin's and bore's E and nu; none, or several (joints differing only in densities or mass
    per length, which a multibody joint does not know), is one InputError line naming
    `where`."""
    if laws_data is None or not laws_data.restitution:
        raise InputError(f"{where} needs a laws_file with a restitution law "
                         "(pinbore calibrate --impacts IMPACT.json ...)")
    j = joint
    found = laws_data.restitution_for(j.r_bore, j.r_pin, j.E_pin, j.nu_pin, j.E_bore, j.nu_bore)
    if len(found) != 1:
        what = "no restitution law" if not found else f"{len(found)} restitution laws"
        raise InputError(f"{where}: {what} of the laws file fits the joint (bearing_radius "
                         f"{j.r_bore:.6g} m, journal_radius {j.r_pin:.6g} m, journal E {j.E_pin:.4g} "
                         f"Pa nu {j.nu_pin:.4g}, bearing E {j.E_bore:.4g} Pa nu {j.nu_bore:.4g}); "
                         f"the file has: {'; '.join(laws_data.restitution)}")
    return next(iter(found.values()))
