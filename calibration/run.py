"""`pinbore calibrate CURVE.csv [...] --out DIR`: fit and rank the contact laws.

Writes DIR/laws.json (every law: published-form errors per curve, fitted parameters with
95 % confidence intervals and their errors, validity range, the curves used), DIR/ranking.csv
(the best laws per curve and load range) and the figures DIR/curves.png, DIR/errors.png.
"""

import math
import time
import warnings

import numpy as np

from pinbore.calibration import restitution
from pinbore.calibration.curves import Curve
from pinbore.calibration.curves import read_all
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.laws import elastic, lawsfile
from pinbore.laws.lawsfile import LAWS, law_force


def evaluate(curves):
    """Published and fitted errors of every law on every curve: {law: {...}}."""
    from pinbore.calibration.fit import NotFitted, errors, fit   # noqa: PLC0415 (SciPy: after the checks)

    table = {}
    for name in LAWS:
        try:
            fitted, reason = fit(name, curves), None
        except NotFitted as err:
            fitted, reason = None, str(err)
        table[name] = {
            "published": None if name == "linear" else
            {c.name: errors(law_force(name, c.approach, c.joint), c.force) for c in curves},
            "fit": fitted,
            "not_fitted": reason,
            "fitted": None if fitted is None else
            {c.name: errors(fitted.force(name, c.approach, c.joint), c.force) for c in curves},
        }
    return table


def ranking(curves, table):
    """Best published and best fitted law per curve and load range (lighter / heavier half)."""
    from pinbore.calibration.fit import errors   # noqa: PLC0415

    rows = []
    for c in curves:
        half = c.approach.size // 2
        for label, part in (("light", slice(0, half)), ("heavy", slice(half, None))):
            d, p = c.approach[part], c.force[part]

            def rms(name, fitted):
                """RMS error over the range; a law without a solution at every point is out."""
                force = (table[name]["fit"].force(name, d, c.joint) if fitted
                         else law_force(name, d, c.joint))
                e = errors(force, p)
                return e.rms_rel if e.points == d.size else math.inf

            published = sorted((rms(n, False), n) for n in LAWS if n != "linear")
            best_fit = min((rms(n, True), n) for n in LAWS if table[n]["fit"] is not None)
            rows.append({"curve": c.name, "clearance_ratio": c.joint.clearance / c.joint.r_bore,
                         "materials": "similar" if c.similar_materials else "dissimilar",
                         "load_range": label,
                         "force_min_N_per_m": float(p.min()), "force_max_N_per_m": float(p.max()),
                         "best_published": published[0][1], "best_published_rms": published[0][0],
                         "second_published": published[1][1], "second_published_rms": published[1][0],
                         "best_fitted": best_fit[1], "best_fitted_rms": best_fit[0]})
    return rows


def laws_json(curves, table, length, caught, seconds) -> lawsfile.LawsFile:
    """The contents of laws.json (laws/lawsfile.py)."""
    clearance = [c.joint.clearance for c in curves]
    validity = lawsfile.Validity(
        clearance_m=[min(clearance), max(clearance)],
        clearance_ratio=[min(c.joint.clearance / c.joint.r_bore for c in curves),
                         max(c.joint.clearance / c.joint.r_bore for c in curves)],
        approach_m=[float(min(c.approach.min() for c in curves)),
                    float(max(c.approach.max() for c in curves))],
        housing_ratio=[min(c.housing_ratio for c in curves), max(c.housing_ratio for c in curves)])
    laws = {}
    for name in LAWS:
        entry = table[name]
        doc = (law_force.__doc__ if name == "linear" else elastic.PUBLISHED[name].__doc__)
        laws[name] = lawsfile.Law(formula=" ".join(doc.split()), published_errors=entry["published"],
                                  fitted=entry["fit"], not_fitted=entry["not_fitted"],
                                  fitted_errors=entry["fitted"], validity=validity,
                                  fitted_to=[c.name for c in curves])
    return lawsfile.LawsFile(
        units=lawsfile.UNITS,
        length_m=length,
        length_note="axial length given to the laws that need one (hertz: F/L; "
                    "dubowsky_freudenstein); null: each curve's bore diameter",
        curves=[lawsfile.CurveEntry(name=c.name, points=int(c.approach.size),
                                    clearance_m=c.joint.clearance, bore_radius_m=c.joint.r_bore,
                                    effective_modulus_Pa=c.joint.e_star,
                                    housing_ratio=c.housing_ratio,
                                    similar_materials=c.similar_materials,
                                    approach_m=[float(c.approach.min()), float(c.approach.max())],
                                    persson_half_angle_error_deg=persson_error(c),
                                    joint=lawsfile.JointRecord.of(c.joint))
                for c in curves],
        laws=laws,
        sliced={},
        warnings=sorted({str(w.message) for w in caught}),
        fit_seconds=seconds)


def persson_error(curve):
    """Largest |FE half-angle - Persson| (deg) for similar materials, else None."""
    if curve.half_angle is None or not curve.similar_materials:
        return None
    closed = np.degrees(elastic.persson_half_angles(curve.force, curve.joint))
    return float(np.max(np.abs(curve.half_angle - closed)))


def per_length(name: str | None, table, curves, curves_3d) -> "pinbore.calibration.sliced.PerLength":
    """The per-length law of the sliced 3D law: `name` is a published law, calibrated:<law>,
    or section (the 2D FE curve of each 3D curve's own plane section: radii, housing, hub,
    materials). None: section when every 3D curve has its section among the 2D curves (the
    exact plane-strain law of the joint: the calibrated laws miss it by 6-42 % at c/R = 3e-3),
    else the fitted law with the smallest mean RMS error over the 2D curves."""
    from pinbore.calibration import sliced   # noqa: PLC0415

    sections = {c.section: c for c in curves}
    fitted = {n: e["fit"] for n, e in table.items() if e["fit"] is not None and n != "linear"}
    if name is None:
        if all(c.section in sections for c in curves_3d):
            name = "section"
        elif not fitted:
            raise InputError("--per-length: no law could be fitted on the 2D curves; name a "
                             f"published one: {', '.join(n for n in LAWS if n != 'linear')}")
        else:
            best = min(fitted, key=lambda n: np.mean([e.rms_rel for e in table[n]["fitted"].values()]))
            name = f"calibrated:{best}"
    if name == "section":
        missing = [c for c in curves_3d if c.section not in sections]
        if missing:
            raise InputError(f"--per-length: section: {missing[0].path}: no 2D curve of its plane "
                             "section (radii, housing and hub radii, materials) among the curves")
        records = {key: lawsfile.Section(curve=plane.name,
                                         approach_m=[float(x) for x in plane.approach],
                                         force_N_per_m=[float(x) for x in plane.force])
                   for key, plane in sections.items()}
        return sliced.PerLength(name, lambda d, c: records[c.section].force(d),
                                lambda c: records[c.section])
    if name.startswith("calibrated:"):
        law = name.split(":", 1)[1]
        if law not in fitted:
            raise InputError(f"--per-length: {name!r} is not a law the 2D curves fitted; valid: "
                             f"section, calibrated:{', calibrated:'.join(fitted)}, {', '.join(LAWS)}")
        return sliced.PerLength(name, lambda d, c: fitted[law].force(law, d, c.joint),
                                lambda c: None)
    if name not in LAWS or name == "linear":
        raise InputError(f"--per-length: {name!r} is unknown; valid: section, "
                         f"{', '.join(n for n in LAWS if n != 'linear')}, calibrated:<law>")
    return sliced.PerLength(name, lambda d, c: law_force(name, d, c.joint), lambda c: None)


def run(paths, out, length=None, per_length_name=None, impacts=()) -> int:
    if length is not None and not (isinstance(length, (int, float)) and math.isfinite(length) and length > 0):
        raise InputError(f"length: {length!r} must be a finite length above 0 m (or None: the bore "
                         "diameter)")
    read = read_all(paths, length)
    restitution_laws = restitution.fit_all(impacts) if impacts else {}
    # the inputs read and checked: now the fits' and the figures' libraries
    from pinbore.calibration import figures, sliced   # noqa: PLC0415
    curves = [c for c in read if isinstance(c, Curve)]
    curves_3d = [c for c in read if not isinstance(c, Curve)]
    if not curves:
        raise InputError("calibrate: no 2D curve given; the 2D curves calibrate the per-length "
                         "law that the 3D curves' sliced law is built on")
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = evaluate(curves)
        rows = ranking(curves, table)
        sliced_laws = {}
        if curves_3d:
            chosen = per_length(per_length_name, table, curves, curves_3d)
            sliced_laws = sliced.calibrate(curves_3d, chosen)
    seconds = time.perf_counter() - start
    with atomic_directory(out) as tmp:
        lawsfile.write(tmp / "laws.json", laws_json(curves, table, length, caught, seconds)
                       .model_copy(update={"sliced": sliced_laws, "restitution": restitution_laws}))
        header = list(rows[0])
        lines = [",".join(header)] + [",".join(_cell(r[h]) for h in header) for r in rows]
        (tmp / "ranking.csv").write_text("\n".join(lines) + "\n")
        figures.curves(tmp / "curves.png", curves, table, LAWS)
        figures.error_maps(tmp / "errors.png", curves, table, LAWS)
        if curves_3d:
            figures.sliced_curves(tmp / "sliced.png", curves_3d, sliced_laws, chosen.force)
        if restitution_laws:
            figures.restitution(tmp / "restitution.png", restitution_laws)
            histories = restitution.histories(restitution_laws)
            if histories:
                figures.force_histories(tmp / "impact_force.png", histories)
    return 0


def _cell(value):
    return f"{value:.4g}" if isinstance(value, float) and math.isfinite(value) else str(value)
