"""A calibrated contact law ready to use: the normal force of a revolute clearance joint against
its approach and approach rate, read from a laws file (`pinbore calibrate`), for a Python user
or another multibody code (`pinbore.laws.load`, `pinbore export`).

    laws = pinbore.laws.load("build/calibration/laws.json")   # {law name: ContactLaw}
    law = laws["liu"]
    law(2e-6)                                  # N: the elastic force at 2 um of approach
    law(2e-6, rate=-0.1, impact_speed=0.5)     # N: with the damping, separating at 0.1 m/s

The force is the multibody model's, by the same functions:
    F(d, d') = max(L P(d) (1 + chi(v0) d' / v0), 0)  for d > 0, else 0,
P(d) (N/m) the per-length law (`calibrated:<law>` of the laws file: s P_law(d) (d/d_ref)^q,
pinbore.laws.lawsfile.per_length_force), L (m) the joint's axial length, v0 (m/s) the approach
rate at the contact's onset, chi the Hunt-Crossley factor [HuntCrossley1975]: of the FE
impacts' restitution e(v0) (damping "calibrated": pinbore.laws.dissipative.
hysteresis_for_restitution, which rebounds with exactly e) or of a published hysteresis law
for a given e (pinbore.laws.dissipative.HYSTERESIS). Each law carries its validity: the FE
approaches and clearances it was fitted over, and the impact speeds of e(v0); it warns once
when used beyond them (the force is then an extrapolation).
"""

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pinbore.laws import dissipative, elastic, lawsfile

DAMPING = ("calibrated", "none", *dissipative.HYSTERESIS)


@dataclass(frozen=True)
class ContactLaw:
    """The normal force (N) of one joint against its approach (m) and approach rate (m/s)."""

    name: str                                 # "calibrated:<law>" of the laws file
    joint: elastic.Joint                      # radii (m), materials (Pa); its length (m) is L
    approach_range_m: tuple[float, float]     # the FE approaches the law was fitted over
    clearance_range_m: tuple[float, float]    # the FE clearances it was fitted over
    damping: str                              # "calibrated", "none" or a published law (DAMPING)
    restitution: float | None                 # e of a published damping law
    restitution_law: lawsfile.RestitutionLaw | None   # e(v0) of FE impacts ("calibrated")
    laws_data: lawsfile.LawsFile

    def per_length(self, d) -> np.ndarray:
        """P(d) (N/m) at the approaches d (m); 0 where d <= 0 (no contact)."""
        d = np.asarray(d, float)
        positive = np.where(d > 0, d, 1.0)
        if np.any(d > self.approach_range_m[1]):
            elastic.warn_once(self.name, "approach beyond the fitted "
                              f"{self.approach_range_m[1]:.3g} m: extrapolated")
        p = lawsfile.per_length_force(self.name, self.laws_data, positive, self.joint, "law")
        return np.where(d > 0, p, 0.0)

    def elastic(self, d) -> np.ndarray:
        """The elastic force L P(d) (N) at the approaches d (m)."""
        return self.joint.length * self.per_length(d)

    def restitution_at(self, impact_speed: float) -> float:
        """The coefficient of restitution the damping gives at the impact speed v0 (m/s)."""
        if self.damping == "none":
            return 1.0
        if self.damping != "calibrated":
            return float(self.restitution)
        low, high = self.restitution_law.speed_range_m_per_s
        if not low <= impact_speed <= high:
            elastic.warn_once(f"{self.name} restitution", "impact speed outside the FE "
                              f"impacts' {low:.3g}-{high:.3g} m/s: e held at the nearer end")
        return self.restitution_law.restitution(impact_speed)

    def chi(self, impact_speed: float) -> float:
        """The Hunt-Crossley factor chi (-) of a contact that began at v0 (m/s)."""
        if self.damping == "none":
            return 0.0
        if self.damping == "calibrated":
            return dissipative.hysteresis_for_restitution(self.restitution_at(impact_speed))
        return dissipative.HYSTERESIS[self.damping](self.restitution)

    def __call__(self, d, rate=0.0, impact_speed: float | None = None) -> np.ndarray:
        """F (N) at the approach d (m) and approach rate d' (m/s, > 0 closing) of a contact
        that began at the approach rate v0 = impact_speed (m/s): L P(d) (1 + chi d'/v0),
        never pulling; the elastic force alone without damping."""
        force = self.elastic(d)
        rate = np.asarray(rate, float)
        if self.damping == "none" or not np.any(rate):
            return force
        if impact_speed is None or not impact_speed > 0:
            raise ValueError(f"{self.name}: impact_speed (m/s, > 0) is needed with a rate: the "
                             "approach rate at the contact's onset, that the damping scales by")
        hysteresis = np.vectorize(dissipative.hysteresis_force, otypes=[float])
        return hysteresis(force, rate, impact_speed, self.chi(impact_speed))


def law_of(laws_data: lawsfile.LawsFile, name: str, joint: elastic.Joint,
           damping: str | None = None, restitution: float | None = None,
           source: str = "laws file") -> ContactLaw:
    """The calibrated law `name` (a fitted law of the file: "liu", ...) for `joint`.
    damping None: "calibrated" when the file has a restitution law for the joint, else
    "none"; a published damping law needs its restitution e in (0, 1]."""
    fitted = laws_data.fitted()
    if name not in fitted:
        raise ValueError(f"{source}: {name!r} is not a fitted law of the file; valid: "
                         f"{', '.join(fitted) or 'none'}")
    restitution_law = None
    if damping is None:
        found = laws_data.restitution_for(joint.r_bore, joint.r_pin, joint.E_pin, joint.nu_pin,
                                          joint.E_bore, joint.nu_bore)
        damping = "calibrated" if len(found) == 1 else "none"
    if damping not in DAMPING:
        raise ValueError(f"damping: {damping!r} is unknown; valid: {', '.join(DAMPING)}")
    if damping == "calibrated":
        restitution_law = lawsfile.joint_restitution(laws_data, joint, f"{source}: damping")
    elif damping != "none" and (restitution is None or not 0 < restitution <= 1):
        raise ValueError(f"restitution: the damping law {damping!r} needs e in (0, 1], "
                         f"got {restitution}")
    validity = laws_data.laws[name].validity
    low, high = validity.clearance_m
    if not low * (1 - 1e-9) <= joint.clearance <= high * (1 + 1e-9):
        elastic.warn_once(f"calibrated:{name}", f"clearance {joint.clearance:.3g} m outside the "
                          f"fitted {low:.3g}-{high:.3g} m: extrapolated")
    return ContactLaw(f"calibrated:{name}", joint, tuple(validity.approach_m), (low, high),
                      damping, restitution if damping not in ("none", "calibrated") else None,
                      restitution_law, laws_data)


def load(path, joint: elastic.Joint | None = None, damping: str | None = None,
         restitution: float | None = None) -> dict[str, ContactLaw]:
    """Every calibrated law of the laws file at `path`, by name, for `joint` (default: the
    one joint of the file's curves, with the file's axial length); damping and restitution
    as `law_of`. A file that does not validate is one InputError line."""
    source = str(path)
    laws_data = lawsfile.read(Path(path), source)
    if joint is None:
        joint = lawsfile.curves_joint(laws_data, source, "give the joint, pinbore.laws.elastic.Joint("
                             "r_bore, r_pin, E_bore, nu_bore, E_pin, nu_pin, length) (m, Pa)")
    if not (joint.length > 0 and math.isfinite(joint.length)):
        raise ValueError(f"{source}: the joint's length must be > 0 m (the laws are per length)")
    return {name: law_of(laws_data, name, joint, damping, restitution, source)
            for name in laws_data.fitted()}
