"""The report's calibration section: which contact law to use where."""

import csv
import math
from pathlib import Path

import numpy as np

from pinbore.core.html import figure, png_data, table
from pinbore.laws import lawsfile


def _pct(value) -> str:
    return "–" if value is None or not np.isfinite(value) else f"{100 * value:.1f} %"


def pooled_rms(errors) -> float:
    """The RMS relative error over several curves' errors (lawsfile.Errors)."""
    return float(np.sqrt(np.mean([e.rms_rel ** 2 for e in errors])))


def _pooled(errors: dict[str, lawsfile.Errors], points: dict) -> str:
    """RMS over the curves, or where the law has no solution on some curve, which ones."""
    short = [name for name, e in errors.items() if e.points < points[name]]
    if short:
        return f"no solution at some approaches of {len(short)} curve(s)"
    return _pct(pooled_rms(errors.values()))


def answers(build_dir: Path) -> list[tuple[str, str]]:
    """The report's first screen: per materials pair, the calibrated law of least RMS error
    over its FE curves (and its largest error), and per joint of the FE impacts, the
    restitution over their speeds. Empty without a calibration."""
    path = build_dir / "calibration" / "laws.json"
    if not path.exists():
        return []
    data = lawsfile.read(path)
    out = []
    groups = {}
    for c in data.curves:
        label = (f"pin E {c.joint.E_pin / 1e9:.0f} GPa in bore E {c.joint.E_bore / 1e9:.0f} GPa"
                 if c.joint is not None else f"E* {c.effective_modulus_Pa / 1e9:.0f} GPa")
        groups.setdefault(label, []).append(c)
    for label, curves in groups.items():
        names = [c.name for c in curves]
        scored = {name: (pooled_rms(law.fitted_errors[n] for n in names),
                         max(law.fitted_errors[n].max_rel for n in names))
                  for name, law in data.laws.items()
                  if law.fitted_errors and all(n in law.fitted_errors for n in names)}
        if scored:
            best = min(scored, key=lambda n: scored[n][0])
            clear = [c.clearance_m for c in curves]
            out.append((f"Contact law, {label} (c {min(clear) * 1e6:.0f}-{max(clear) * 1e6:.0f} &micro;m)",
                        f"<code>calibrated:{best}</code>: RMS error {_pct(scored[best][0])}, "
                        f"largest {_pct(scored[best][1])} over {len(curves)} FE curves"))
    for key, law in data.restitution.items():
        low, high = law.speed_range_m_per_s
        joint = key.split(" | m=")[0] if law.joint is None else (
            f"pin E {law.joint.pin_E_Pa / 1e9:.0f} GPa in bore E {law.joint.bore_E_Pa / 1e9:.0f} GPa"
            f"{' (plastic)' if law.joint.bore_plasticity else ''}, "
            f"c {(law.joint.bore_radius_m - law.joint.pin_radius_m) * 1e6:.0f} &micro;m")
        out.append((f"Restitution, {joint}",
                    f"e = {law.restitution(low):.3f} at {low:g} m/s to {law.restitution(high):.3f} "
                    f"at {high:g} m/s (fit within {law.max_fit_error:.1e} of the FE impacts)"))
    return out


def section(build_dir: Path, bench_dir: Path) -> str:
    folder = build_dir / "calibration"
    parts = ["<h2>Contact laws calibrated on the FE curves</h2>"]
    if not (folder / "laws.json").exists():
        return "".join(parts) + ("<p class='note'>No calibration under build/calibration: run "
                                 "<code>make calibration</code>.</p>")
    data = lawsfile.read(folder / "laws.json")
    curves, laws = data.curves, data.laws
    clear = [c.clearance_m / c.bore_radius_m for c in curves]
    parts.append(
        f"<p>{len(curves)} FE curves (the points of <code>studies/calibration_2d.toml</code>): clearance ratios c/R from "
        f"{min(clear):.3g} to {max(clear):.3g}, steel pin in steel and in aluminium housings, "
        f"approaches to {max(c.approach_m[1] for c in curves) * 1e6:.0f} um. Each law is "
        "compared as published (parameters from geometry and materials only) and fitted: "
        "P = s P<sub>law</sub>(d) (d / d<sub>ref</sub>)<sup>q</sup>, one (s, q) per law for all "
        "curves, the form a multibody model uses as <code>calibrated:&lt;law&gt;</code>. "
        f"Laws that need an axial length get {'the bore diameter' if data.length_m is None else data.length_m} "
        "(Hertz: F/L).</p>"
        "<p class='note'>In plane strain the approach is only defined against reference points: "
        "the FE approach is the displacement of the rigid hub (0.2 R) relative to the clamped "
        f"housing edge ({curves[0].housing_ratio:g} R), so it includes the bulk compliance of "
        "pin and housing, which grows with the housing's size. Laws that define the approach "
        "between points about one radius deep (Johnson, ESDU) come out stiffer. The fitted "
        "parameters hold for this definition and the housing ratio in <code>laws.json</code>.</p>")
    parts.append(figure(png_data(folder / "curves.png"),
                        "Force per length against approach for every study curve (FE: black), with "
                        "every law as published (build/calibration/curves.png)."))
    parts.append(figure(png_data(folder / "errors.png"),
                        "RMS relative force error of every law on every curve, as published (left) "
                        "and fitted (right); numbers in percent (build/calibration/errors.png)."))
    points = {c.name: c.points for c in curves}
    rows = []
    for name, law in laws.items():
        published, fitted, f = law.published_errors, law.fitted_errors, law.fitted
        if f is None:
            rows.append([name, _pooled(published, points), "not fitted", law.not_fitted, "–", "–"])
            continue
        rows.append([name, _pooled(published, points) if published else "fit only",
                     f"{f.scale:.3g} [{f.scale_ci95[0]:.3g}, {f.scale_ci95[1]:.3g}]",
                     f"{f.exponent_correction:+.3f} [{f.exponent_correction_ci95[0]:+.3f}, "
                     f"{f.exponent_correction_ci95[1]:+.3f}]",
                     _pooled(fitted, points), _pct(max(e.max_rel for e in fitted.values()))])
    parts.append("<h3>Laws: errors over all curves and fitted parameters (95 % intervals)</h3>")
    parts.append(table(["law", "RMS error, published", "scale s", "exponent correction q",
                        "RMS error, fitted", "max error, fitted"], rows))
    with open(folder / "ranking.csv", newline="") as f:
        ranking = list(csv.DictReader(f))
    if not ranking:
        raise ValueError(f"{folder / 'ranking.csv'}: no curve ranked (the table is its header alone)")
    parts.append("<h3>Recommendation: the best law per clearance, material pair and load range</h3>")
    parts.append(table(
        ["curve", "c/R", "materials", "load (kN/m)", "best published (RMS)", "runner-up (RMS)",
         "best fitted (RMS)"],
        [[r["curve"], r["clearance_ratio"], r["materials"],
          f"{float(r['force_min_N_per_m']) / 1e3:.0f}-{float(r['force_max_N_per_m']) / 1e3:.0f}",
          f"{r['best_published']} ({_pct(float(r['best_published_rms']))})",
          f"{r['second_published']} ({_pct(float(r['second_published_rms']))})",
          f"{r['best_fitted']} ({_pct(float(r['best_fitted_rms']))})"] for r in ranking]))
    if data.sliced:
        parts.append(sliced_section(data, folder))
    if data.restitution:
        parts.append(restitution_section(data.restitution, folder))
    bench = bench_dir / "calibration.csv"
    if bench.exists():
        with open(bench, newline="") as f:
            rows = list(csv.reader(f))
        parts.append("<h3>Benchmark: fit and ranking time (make bench)</h3>" + table(rows[0], rows[1:]))
    if data.warnings:
        parts.append("<p class='note'>Validity warnings: " + "; ".join(data.warnings) + "</p>")
    return "".join(parts)


def sliced_section(data: lawsfile.LawsFile, folder: Path) -> str:
    """The 3D laws: the sliced law of a finite pin per kind of ends and materials."""
    first = next(iter(data.sliced.values()))
    rows = [[key, law.ends, law.per_length_law,
             f"{law.scale:.3g} [{law.scale_ci95[0]:.3g}, {law.scale_ci95[1]:.3g}]",
             f"{law.end_length_m * 1e3:.3g} [{law.end_length_ci95[0] * 1e3:.3g}, "
             f"{law.end_length_ci95[1] * 1e3:.3g}]",
             f"{law.bulk_compliance_m2_per_N:.3g} [{law.bulk_compliance_ci95[0]:.3g}, "
             f"{law.bulk_compliance_ci95[1]:.3g}]",
             f"{math.pi * law.joint.E_bore * law.bulk_compliance_m2_per_N:.3g}",
             str(law.slices_for_1_percent),
             _pct(max(e.force_max_rel for e in law.errors.values())),
             _pct(max((e.moment_max_rel for e in law.errors.values()
                       if e.moment_max_rel is not None), default=None)),
             ", ".join(law.fitted_to)] for key, law in data.sliced.items()]
    parts = ["<h3>3D: the sliced law of a finite pin (force and tilting moment)</h3>",
             f"<p>The bore length is cut into slices, each carrying the per-length law "
             f"<code>{first.per_length_law}</code> at its own approach &delta; - c<sub>b</sub> "
             "F/L + &theta; (z - L/2), less the bulk compliance c<sub>b</sub> that the housing "
             "shares over the whole length (it moves the bore as a whole under the resultant F, "
             "so the tilt acts on the contact's own compliance). A stiffness factor, an end "
             "length per end and c<sub>b</sub> are fitted on the 3D FE curves (push, then tilt "
             "as a load), one law per kind of ends and materials pair (<code>laws.json</code>: "
             "<code>sliced</code>); &pi; E<sub>bore</sub> c<sub>b</sub> is the bulk compliance "
             "in units of the housing's.</p>",
             table(["group", "ends", "per-length law", "scale [95 %]", "end length (mm) [95 %]",
                    "bulk compliance c_b (m^2/N) [95 %]", "pi E_bore c_b",
                    "slices for 1 % in F", "max error F", "max error M (tilted)", "curves"], rows)]
    if (folder / "sliced.png").exists():
        parts.append(figure(png_data(folder / "sliced.png"),
                            "3D FE force and tilting moment (points) beside the calibrated sliced "
                            "law (lines) (build/calibration/sliced.png)."))
    return "".join(parts)


def restitution_section(laws: dict[str, lawsfile.RestitutionLaw], folder: Path) -> str:
    """The restitution e(v0) of the FE impacts and its fit per joint (damping_law =
    "calibrated")."""
    parts = ["<h3>Restitution from FE impacts (damping_law = \"calibrated\")</h3>",
             "<p>One law per joint (materials, radii, mass per length); the multibody contact "
             "takes the Hunt-Crossley factor that rebounds with e(v0) at each onset, from the "
             "law of its own radii and materials.</p>"]
    for key, law in laws.items():
        low, high = law.speed_range_m_per_s
        rows = [[f"{q.speed_m_per_s:.3g}", f"{q.restitution:.4f}", f"{q.fitted:.4f}",
                 f"{q.contact_duration_s * 1e6:.1f}", f"{q.peak_force_N_per_m / 1e3:.4g}",
                 f"{q.plastic_work_share:.3f}" if q.plastic else "elastic"]
                for q in law.impacts]
        terms = "".join(f" {a:+.5f} x" + (f"<sup>{k}</sup>" if k > 1 else "")
                        for k, a in enumerate(law.coefficients) if k > 0)
        parts += [f"<p><code>{key}</code>: e(v0) = {law.coefficients[0]:.4f}{terms}, "
                  f"x = ln(v0 / 1 m/s), valid for {low:.3g}-{high:.3g} m/s (largest fit error "
                  f"{law.max_fit_error:.3g}).</p>",
                  table(["v0 (m/s)", "e (FE)", "e (fit)", "contact (us)", "peak force (kN/m)",
                         "plastic work / impact energy"], rows)]
    if (folder / "restitution.png").exists():
        parts.append(figure(png_data(folder / "restitution.png"),
                            "e(v0) of the FE impacts (points) and the fits of every joint "
                            "(left); per joint, what each published hysteresis law rebounds "
                            "with when given the fit's e (build/calibration/restitution.png)."))
    if (folder / "impact_force.png").exists():
        parts.append(figure(png_data(folder / "impact_force.png"),
                            "Contact force per length against time of the FE impacts, one row "
                            "per joint: against the time from first touch (left) and, over its "
                            "peak, against the time over the contact duration (right) "
                            "(build/calibration/impact_force.png)."))
    return "".join(parts)
