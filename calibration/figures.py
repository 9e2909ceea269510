"""Figures of a calibration: every law over every FE curve; error maps; the 3D curves beside
the sliced law; the restitution e(v0) of FE impacts beside the published hysteresis laws."""

import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from pinbore.core.figures import plt, save_png

from pinbore.calibration import sliced
from pinbore.fem.curve import read_pressure
from pinbore.laws import dissipative
from pinbore.laws import sliced as sliced_law
from pinbore.laws import tables
from pinbore.laws.lawsfile import law_force

COLOURS = dict(zip(["hertz", "johnson", "liu", "bai_zhao", "pereira", "radzimovsky",
                    "dubowsky_freudenstein", "esdu_78035", "linear"], plt.cm.tab10.colors))


def _label(curve):
    pair = "similar" if curve.similar_materials else "steel/Al" if curve.joint.E_bore < 1e11 else "dissimilar"
    return f"c/R = {curve.joint.clearance / curve.joint.r_bore:.3g}, {pair}"


def curves(path, curves, table, laws) -> None:
    """One panel per FE curve: the FE points and every law as published (lines)."""
    n = len(curves)
    cols = min(n, 5)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols, 3.1 * rows + 0.8), squeeze=False)
    for ax, c in zip(axes.flat, curves):
        d = np.geomspace(c.approach.min(), c.approach.max(), 60)
        for name in laws:
            if name == "linear":
                continue
            ax.loglog(d * 1e6, law_force(name, d, c.joint) / 1e3, color=COLOURS[name], lw=1,
                      ls="--" if name == "esdu_78035" else "-", label=name)
        ax.loglog(c.approach * 1e6, c.force / 1e3, "ko", ms=3, label="FE")
        ax.set_title(_label(c), fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.tick_params(labelsize=7)
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax in axes[:, 0]:
        ax.set_ylabel("force per length (kN/m)", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("approach (um)", fontsize=8)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    save_png(fig, path, dpi=100)


def error_maps(path, curves, table, laws) -> None:
    """RMS relative error of every law on every curve, as published and fitted."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 0.45 * len(laws) + 2.4), sharey=True)
    for ax, kind in zip(axes, ("published", "fitted")):
        values = np.array([[np.nan if table[n][kind] is None else table[n][kind][c.name].rms_rel
                            for c in curves] for n in laws])
        shown = ax.imshow(np.log10(np.clip(values, 1e-4, 10)), cmap="viridis_r", vmin=-3, vmax=0.5,
                          aspect="auto")
        for (i, j), v in np.ndenumerate(values):
            if np.isfinite(v):
                ax.text(j, i, f"{100 * v:.0f}" if v >= 0.01 else f"{100 * v:.1f}", ha="center",
                        va="center", fontsize=7, color="white" if v < 0.03 else "black")
        ax.set_yticks(range(len(laws)), laws, fontsize=8)
        ax.set_xticks(range(len(curves)), [_label(c).replace(", ", "\n") for c in curves],
                      fontsize=7, rotation=90)
        ax.set_title(f"RMS force error (%), {kind}" + (" (linear: fit only)" if kind == "published" else ""))
    fig.colorbar(shown, ax=axes, label="log10 RMS relative error")
    save_png(fig, path, dpi=100, bbox_inches="tight")


def sliced_curves(path, curves_3d, laws, force) -> None:
    """Per 3D curve: F against the step and M against the tilt, FE points beside the
    calibrated sliced law of its group (lines)."""
    n = len(curves_3d)
    fig, axes = plt.subplots(3, n, figsize=(3.6 * n, 9.4), squeeze=False)
    for (ax, bx, cx), c in zip(axes.T, curves_3d):
        law = laws[sliced.group_key(c)]
        line_load_panel(cx, c, law, force)
        f, m = sliced.predict(c, law, force)
        steps = np.arange(1, c.force.size + 1)
        ax.plot(steps, c.force / 1e3, "ko", ms=4, label="FE")
        ax.plot(steps, f / 1e3, "C0-", label="sliced law")
        ax.set_xlabel("load step (push, then tilt)")
        ax.set_ylabel("force F (kN)")
        ax.set_title(f"{c.name}\nL = {c.length * 1e3:g} mm, {'lug' if c.runs_on else 'flush'}",
                     fontsize=8)
        tilted = c.tilt != 0
        bx.plot(np.degrees(c.tilt[tilted]), c.moment[tilted], "ko", ms=4, label="FE")
        bx.plot(np.degrees(c.tilt[tilted]), m[tilted], "C0-", label="sliced law")
        bx.set_xlabel(f"tilt (deg) at approach {c.approach.max() * 1e6:.3g} um")
        bx.set_ylabel("tilting moment M (N m)")
        for a in (ax, bx):
            a.grid(alpha=0.3)
            a.legend(fontsize=7)
    save_png(fig, path, layout=True)


def fe_line_load(pressure_csv: Path, step: int, radius: float):
    """The FE line load along the load direction (N/m) against z (m) at one step of a 3D run:
    per level, the pressure integrated over the refined arc, p cos(alpha) R d alpha
    (trapezoids in the angle alpha from the load)."""
    p = read_pressure(pressure_csv)
    keep = p.step == step
    z, alpha, pressure = p.z[keep], np.radians(p.angle[keep]), p.pressure[keep]
    levels = np.unique(z)
    load = []
    for level in levels:
        on = z == level
        order = np.argsort(alpha[on])
        load.append(np.trapezoid(pressure[on][order] * np.cos(alpha[on][order]),
                                 alpha[on][order]) * radius)
    return levels, np.array(load)


def line_load_panel(ax, c, law, force) -> None:
    """The FE line load along the pin at the largest tilt beside the sliced law's per-length
    forces (a f_loc(delta_i); the end lengths add at the two end slices)."""
    last = int(np.argmax(np.abs(c.tilt)))
    if not (c.path.parent / "pressure.csv").exists():
        ax.text(0.5, 0.5, "no pressure.csv beside the curve", ha="center", transform=ax.transAxes)
        return
    z, load = fe_line_load(c.path.parent / "pressure.csv", last + 1, c.joint.r_pin)
    bulk = law.bulk_compliance_m2_per_N
    local = tables.split_compliance(*sliced.per_length_table(force, c), bulk)
    relief = c.relief or (0.0, 0.0)
    zs, _, f = sliced_law.sliced_profile(c.approach[last], c.tilt[last], c.length,
                                         sliced.FIT_SLICES, *local, *relief, law.end_length_m,
                                         law.scale, bulk)
    inside = (z >= 0) & (z <= c.length)
    ax.plot(z[inside] * 1e3, load[inside] / 1e6, "ko", ms=3, label="FE")
    ax.plot(zs * 1e3, f / 1e6, "C0-", label="sliced law (interior)")
    ax.set_xlabel("z (mm)")
    ax.set_ylabel("line load (MN/m)")
    ax.set_title(f"at tilt {np.degrees(c.tilt[last]):.3g} deg", fontsize=8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def restitution(path, laws) -> None:
    """e(v0) of every joint's restitution law (laws.json `restitution`, by key): left, the
    FE impacts and the fits of all joints together (held beyond their speeds, dashed); then
    one panel per joint with what each published hysteresis law rebounds with when given
    the fitted e as its target (the exact e of its chi,
    laws.dissipative.hysteresis_for_restitution inverted)."""
    fig, axes = plt.subplots(1, 1 + len(laws), figsize=(5.2 * (1 + len(laws)), 4.8), squeeze=False)
    for k, (key, law) in enumerate(laws.items()):
        low, high = law.speed_range_m_per_s
        v = np.geomspace(low / 3, high * 3, 80)
        inside = (v >= low) & (v <= high)
        e = np.array([law.restitution(x) for x in v])
        label = _joint_label(law)
        for ax, colour in ((axes[0, 0], f"C{k}"), (axes[0, 1 + k], "k")):
            ax.semilogx(v, np.where(inside, e, np.nan), "-", color=colour, lw=2,
                        label=f"fit e(v0), {label}")
            ax.semilogx(v, np.where(inside, np.nan, e), "--", color=colour, lw=1)
            ax.plot([q.speed_m_per_s for q in law.impacts], [q.restitution for q in law.impacts],
                    "o", color=colour, ms=6, label=f"FE impacts, {label}")
        ax = axes[0, 1 + k]
        for name, chi_of in dissipative.HYSTERESIS.items():
            with warnings.catch_warnings():   # the point of the figure: laws derived for e near 1
                warnings.simplefilter("ignore")   # (and their range warnings) used at the FE's e
                delivered = [brentq(lambda r, c=chi_of(t): dissipative.hysteresis_for_restitution(r) - c,
                                    1e-6, 1.0) for t in e[inside]]
            ax.semilogx(v[inside], delivered, lw=0.9, label=f"{name} (given the fit's e)")
        ax.set_title(f"{label} (fit error {law.max_fit_error:.2g})", fontsize=9)
    axes[0, 0].set_title("restitution from FE impacts (dashed: held outside the range)", fontsize=9)
    for ax in axes[0]:
        ax.set_xlabel("impact speed v0 (m/s)")
        ax.set_ylabel("coefficient of restitution e")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6, ncol=1 if ax is axes[0, 0] else 2)
    save_png(fig, path, layout=True)


def _joint_label(law) -> str:
    """A short name of a restitution law's joint: pin / bore moduli and the clearance."""
    j = law.joint
    if j is None:
        return "older laws.json"
    return (f"pin {j.pin_E_Pa / 1e9:.3g} / bore {j.bore_E_Pa / 1e9:.3g} GPa, "
            f"c = {(j.bore_radius_m - j.pin_radius_m) * 1e6:.3g} um")


def force_histories(path, histories) -> None:
    """The contact force per length against time of every impact, one row per joint
    (`histories`: {joint key: (law, [(impact point, fem.impact.file.History)])}): left, the
    force (kN/m, logarithmic) against the time from first touch (us); right, the force over
    its peak against the time over the contact duration, t / t_c, which shows how the pulse's
    shape changes with the speed (a Hertzian pulse of a rigid pin would be one curve)."""
    fig, axes = plt.subplots(len(histories), 2, figsize=(11.5, 3.9 * len(histories)),
                             squeeze=False)
    for (ax, bx), (key, (law, runs)) in zip(axes, histories.items()):
        colours = plt.cm.viridis(np.linspace(0, 0.9, len(runs)))
        for colour, (q, h) in zip(colours, runs):
            first = np.flatnonzero(h.approach >= 0)[0]   # first touch: the hub's travel beyond
            start = np.interp(0.0, h.approach[first - 1:first + 1], h.time[first - 1:first + 1])
            t = h.time - start                          # it crosses 0 (free flight before it)
            label = f"v0 = {q.speed_m_per_s:.3g} m/s, e = {q.restitution:.3f}"
            ax.semilogy(t * 1e6, np.where(h.force > 0, h.force / 1e3, np.nan), "-", color=colour,
                        lw=1.2, label=label)
            bx.plot(t / q.contact_duration_s, h.force / q.peak_force_N_per_m, "-", color=colour,
                    lw=1.2, label=label)
        ax.set_xlabel("time from first touch (us)")
        ax.set_ylabel("contact force per length (kN/m)")
        peaks = [q.peak_force_N_per_m / 1e3 for q, _ in runs]
        ax.set_ylim(0.03 * min(peaks), 2 * max(peaks))
        bx.set_xlabel("t / t_contact")
        bx.set_ylabel("force / peak force")
        bx.set_xlim(-0.05, 1.3)
        ax.set_title(_joint_label(law), fontsize=9)
        bx.set_title("normalised: shape of the pulse", fontsize=9)
        for a in (ax, bx):
            a.grid(alpha=0.3, which="both")
            a.legend(fontsize=7)
    save_png(fig, path, layout=True)
