"""The calibrated restitution: e(v0) from FE impacts (`pinbore impact`, impact.json), the
dissipative law of the multibody model's `damping_law = "calibrated"`.

What the FE gives: an elastic pin rebounding from its bore leaves part of the impact
energy in the bodies' vibrations (the pin rings after separation; fem.impact.solver), a plastic
one also leaves plastic work, so e < 1 with no damping in the material. The multibody
contact F = F_el(d) (1 + chi d'/v0) [HuntCrossley1975] can carry that loss: chi is chosen at
each contact onset so that the impact rebounds with the FE's e at that onset's speed.

Fit: e(v0) = sum_k a_k x^k, x = ln(v0 / 1 m/s), least squares on the impacts' (v0, e),
degree min(3, impacts - 2) (at least one point more than coefficients, so the fit error
says something; one or two impacts give a constant). e(ln v0) of the elastic study is
S-shaped, flat at both ends of 0.1-5 m/s and steepest near 1 m/s: measured on the steel pin
(c = 10 um) at 0.1, 0.3, 1, 3, 5 m/s, the quadratic misses by 0.012, the cubic by 3e-4. The valid range is the impacts'
speeds; outside it e is held at the nearer end (laws.dissipative.restitution_of_speed) and
the multibody summary warns.

One law per joint: e depends on the materials (elastic constants and densities of pin and
bore), the radii and the pin's mass per length as much as on v0 (a steel pin rebounds
from an aluminium-alloy bore with a different e than from a steel one), so the impacts are
grouped by their joint (lawsfile.ImpactJoint, its key) and each group is fitted alone;
laws.json holds the laws by key and the multibody joint takes the one of its materials and
radii.
"""

import math

import numpy as np

from pinbore.core.errors import InputError
from pinbore.fem.impact import file as impact_file
from pinbore.laws import lawsfile


MIN_IMPACTS = 2   # per joint: one more than the coefficients of the lowest degree (a constant)
MAX_DEGREE = 3    # a cubic in ln v0 from five impacts on


def read_impacts(paths) -> dict[str, tuple[lawsfile.ImpactJoint, list[lawsfile.ImpactPoint]]]:
    """The impacts of impact.json files (or their folders) grouped by joint (key: joint and
    its impacts sorted by speed); an impact that did not rebound (incomplete, no
    restitution), or a joint with fewer than MIN_IMPACTS impacts, is one InputError line."""
    groups = {}
    for p in paths:
        summary = impact_file.read_summary(p)
        if summary.status != "complete" or summary.restitution is None:
            raise InputError(f"{p}: status: the impact must be complete with a rebound to "
                             f"calibrate a restitution (status {summary.status!r}, "
                             + (f"verdict: {'; '.join(summary.verdict)})" if summary.verdict
                                else f"stop {summary.stop!r})"))
        scene = summary.scene   # checked on read as an impact scene (hub_mass defaults)
        g, m = scene["geometry"], scene["materials"]
        e_star = 1 / ((1 - m["pin"]["nu"] ** 2) / m["pin"]["E"]
                      + (1 - m["bore"]["nu"] ** 2) / m["bore"]["E"])
        plastic = any(m[b].get("yield_stress") is not None for b in ("pin", "bore"))
        joint = lawsfile.ImpactJoint(
            pin_E_Pa=m["pin"]["E"], pin_nu=m["pin"]["nu"], pin_density_kg_per_m3=m["pin"]["density"],
            bore_E_Pa=m["bore"]["E"], bore_nu=m["bore"]["nu"],
            bore_density_kg_per_m3=m["bore"]["density"], pin_radius_m=g["pin_radius"],
            bore_radius_m=g["bore_radius"],   # the nominal mass (the FE mesh's is within 0.4 %)
            pin_mass_kg_per_m=m["pin"]["density"] * math.pi * g["pin_radius"] ** 2
            + scene["impact"].get("hub_mass", 0.0),
            pin_plasticity=lawsfile.plasticity_label(m["pin"]),
            bore_plasticity=lawsfile.plasticity_label(m["bore"]))
        groups.setdefault(joint.key(), (joint, []))[1].append(lawsfile.ImpactPoint(
            name=str(p), speed_m_per_s=summary.speed_m_per_s, restitution=summary.restitution,
            fitted=float("nan"), contact_duration_s=summary.contact_duration_s,
            peak_force_N_per_m=summary.peak_force_N_per_m,
            max_approach_m=summary.max_approach_m, pin_mass_kg_per_m=summary.pin_mass_kg_per_m,
            clearance_m=g["bore_radius"] - g["pin_radius"], effective_modulus_Pa=e_star,
            plastic=plastic,
            plastic_work_share=summary.energy.plastic_J_per_m / summary.energy.impact_J_per_m))
    for key, (_, points) in groups.items():
        if len(points) < MIN_IMPACTS:
            raise InputError(f"--impacts: {len(points)} impact of the joint {key} ({points[0].name}); "
                             f"a restitution law needs at least {MIN_IMPACTS} impacts per joint "
                             "(materials, radii, mass per length), at different speeds")
        points.sort(key=lambda q: q.speed_m_per_s)
    return groups


def fit_all(paths) -> dict[str, lawsfile.RestitutionLaw]:
    """The restitution law of every joint among the impacts (impact.json files), by key."""
    return {key: fit(points, joint) for key, (joint, points) in read_impacts(paths).items()}


def fit(points: list[lawsfile.ImpactPoint], joint: lawsfile.ImpactJoint) -> lawsfile.RestitutionLaw:
    """The restitution law of the impacts of one joint (module docstring)."""
    speeds = np.array([q.speed_m_per_s for q in points])
    if np.unique(speeds).size != speeds.size:
        raise InputError(f"--impacts: two impacts at the same speed for the joint {joint.key()}; "
                         "give one impact per speed")
    e = np.array([q.restitution for q in points])
    x = np.log(speeds)
    degree = max(0, min(MAX_DEGREE, len(points) - 2))
    coefficients = np.polynomial.polynomial.polyfit(x, e, degree)
    law = lawsfile.RestitutionLaw(
        model=lawsfile.RESTITUTION_MODEL, joint=joint, coefficients=[float(a) for a in coefficients],
        speed_range_m_per_s=[float(speeds.min()), float(speeds.max())],
        max_fit_error=0.0, impacts=points)
    fitted = [law.restitution(v) for v in speeds]
    return law.model_copy(update={
        "max_fit_error": float(np.max(np.abs(np.asarray(fitted) - e))),
        "impacts": [q.model_copy(update={"fitted": f}) for q, f in zip(points, fitted)]})


def histories(laws: dict[str, lawsfile.RestitutionLaw]):
    """The force histories of each law's impacts, {key: (law, [(impact, History)])}, from
    the history.csv beside each impact.json (fem.impact.file); impacts without one (a summary
    copied alone) are left out, and so is a joint with none."""
    found = {}
    for key, law in laws.items():
        runs = [(q, impact_file.read_history(impact_file.history_beside(q.name)))
                for q in law.impacts if impact_file.history_beside(q.name).is_file()]
        if runs:
            found[key] = (law, runs)
    return found
