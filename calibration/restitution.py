"""The calibrated restitution: e(v0) from FE impacts (`pinbore impact`, impact.json), the
dissipative law of the multibody model's `damping_law = "calibrated"`.

What the FE gives: an elastic pin rebounding from its bore leaves part of the impact
energy in the bodies' vibrations (the pin rings after separation; fem.dynamics), a plastic
one also leaves plastic work, so e < 1 with no damping in the material. The multibody
contact F = F_el(d) (1 + chi d'/v0) [HuntCrossley1975] can carry that loss: chi is chosen at
each contact onset so that the impact rebounds with the FE's e at that onset's speed.

Fit: e(v0) = sum_k a_k x^k, x = ln(v0 / 1 m/s), least squares on the impacts' (v0, e),
degree min(2, impacts - 2) (at least one point more than coefficients, so the fit error
says something; one or two impacts give a constant). The valid range is the impacts'
speeds; outside it e is held at the nearer end (laws.dissipative.restitution_of_speed) and
the multibody summary warns.
"""

import numpy as np

from pinbore.calibration import lawsfile
from pinbore.core.errors import InputError
from pinbore.fem import impact_file


def read_impacts(paths) -> list[lawsfile.ImpactPoint]:
    """The impacts of impact.json files (or their folders), sorted by speed; an impact that
    did not rebound (incomplete, no restitution) is one InputError line."""
    points = []
    for p in paths:
        summary = impact_file.read_summary(p)
        if summary.status != "complete" or summary.restitution is None:
            raise InputError(f"{p}: status: the impact must be complete with a rebound to "
                             f"calibrate a restitution (status {summary.status!r}, stop "
                             f"{summary.stop!r})")
        scene = summary.scene
        g, m = scene["geometry"], scene["materials"]
        e_star = 1 / ((1 - m["pin"]["nu"] ** 2) / m["pin"]["E"]
                      + (1 - m["bore"]["nu"] ** 2) / m["bore"]["E"])
        plastic = any(m[b].get("yield_stress") is not None for b in ("pin", "bore"))
        points.append(lawsfile.ImpactPoint(
            name=str(p), speed_m_per_s=summary.speed_m_per_s, restitution=summary.restitution,
            fitted=float("nan"), contact_duration_s=summary.contact_duration_s,
            peak_force_N_per_m=summary.peak_force_N_per_m,
            max_approach_m=summary.max_approach_m, pin_mass_kg_per_m=summary.pin_mass_kg_per_m,
            clearance_m=g["bore_radius"] - g["pin_radius"], effective_modulus_Pa=e_star,
            plastic=plastic))
    return sorted(points, key=lambda q: q.speed_m_per_s)


def fit(points: list[lawsfile.ImpactPoint]) -> lawsfile.RestitutionLaw:
    """The restitution law of the impacts (module docstring)."""
    speeds = np.array([q.speed_m_per_s for q in points])
    if np.unique(speeds).size != speeds.size:
        raise InputError("--impacts: two impacts at the same speed; give one impact per speed")
    e = np.array([q.restitution for q in points])
    x = np.log(speeds)
    degree = max(0, min(2, len(points) - 2))
    coefficients = np.zeros(3)
    coefficients[:degree + 1] = np.polynomial.polynomial.polyfit(x, e, degree)
    law = lawsfile.RestitutionLaw(
        model=lawsfile.RESTITUTION_MODEL, coefficients=[float(a) for a in coefficients],
        speed_range_m_per_s=[float(speeds.min()), float(speeds.max())],
        max_fit_error=0.0, impacts=points)
    fitted = [law.restitution(v) for v in speeds]
    return law.model_copy(update={
        "max_fit_error": float(np.max(np.abs(np.asarray(fitted) - e))),
        "impacts": [q.model_copy(update={"fitted": f}) for q, f in zip(points, fitted)]})
