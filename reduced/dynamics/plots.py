"""Tables and pictures of the nonlinear-dynamics analyses (reduced.studies)."""

import csv

import numpy as np

from pinbore.core.figures import plt, save_png

KIND_COLOURS = {"periodic": "tab:blue", "quasi-periodic": "tab:green", "chaotic": "tab:red"}


def write_table(path, header, rows) -> None:
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(header)
        out.writerows(rows)


def read_table(path, header) -> list[dict]:
    """The rows of a table write_table wrote with `header`, as dicts of strings; a file that
    cannot be read or has another header is one InputError line naming it."""
    from pinbore.core.errors import InputError   # noqa: PLC0415

    again = "(written by another version of pinbore? run pinbore dynamics again)"
    try:
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError) as err:
        raise InputError(f"{path}: cannot read ({err})") from None
    if not rows or rows[0] != list(header):
        raise InputError(f"{path}: header: not {', '.join(header)} {again}")
    if any(len(row) != len(header) for row in rows[1:]):
        raise InputError(f"{path}: a row has not {len(header)} cells {again}")
    return [dict(zip(header, row)) for row in rows[1:]]


def poincare(path, samples, clearance, title, observed) -> None:
    """Poincare samples of the observed point (the journal centre in its clearance circle, when
    there is one), and x against its rate."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 5))
    if observed.startswith("journal"):
        ring = np.linspace(0, 2 * np.pi, 200)
        ax.plot(clearance * np.cos(ring) * 1e3, clearance * np.sin(ring) * 1e3, "k-", lw=0.8)
        ax.set_aspect("equal")
    ax.plot(samples[:, 0] * 1e3, samples[:, 1] * 1e3, "o", ms=3)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(observed, fontsize=9)
    bx.plot(samples[:, 0] * 1e3, samples[:, 2], "o", ms=3)
    bx.set_xlabel("x (mm)")
    bx.set_ylabel("its rate (m/s)")
    for a in (ax, bx):
        a.grid(alpha=0.3)
    fig.suptitle(f"Poincare map, once per drive revolution ({title})")
    save_png(fig, path, layout=True)


def convergence(path, running) -> None:
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(np.arange(1, len(running) + 1), running)
    ax.set_xlabel("periods")
    ax.set_ylabel("largest Lyapunov exponent estimate (1/s)")
    ax.grid(alpha=0.3)
    save_png(fig, path, layout=True)


def bifurcation(path, rows, parameter, unit) -> None:
    """Poincare samples (journal x) against the parameter, coloured by classification."""
    fig, ax = plt.subplots(figsize=(10, 5))
    for kind, colour in KIND_COLOURS.items():
        xs = [r["value"] for r in rows if r["kind"] == kind for _ in r["observed"]]
        ys = [j[0] * 1e3 for r in rows if r["kind"] == kind for j in r["observed"]]
        if xs:
            ax.plot(xs, ys, ",", color=colour, alpha=0.8)
            ax.plot([], [], "o", ms=4, color=colour, label=kind)
    ax.set_xlabel(f"{parameter} ({unit})")
    ax.set_ylabel("journal centre x at the Poincare section (mm)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save_png(fig, path, layout=True)


def design(path, rows, clearances, speeds, max_force, max_deviation) -> None:
    """Peak force and acceleration deviation over clearance x speed, with the thresholds."""
    shape = (len(speeds), len(clearances))
    force = np.array([r["peak_force_N"] for r in rows]).reshape(shape)
    deviation = np.array([r["acceleration_deviation"] for r in rows]).reshape(shape)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, values, label, limit in ((axes[0], force, "peak contact force (N)", max_force),
                                     (axes[1], deviation, "slider acceleration deviation (RMS / ideal RMS)",
                                      max_deviation)):
        image = ax.pcolormesh(np.array(clearances) * 1e3, speeds, values, shading="nearest", cmap="viridis")
        fig.colorbar(image, ax=ax, label=label)
        if len(speeds) > 1 and len(clearances) > 1:
            ax.contour(np.array(clearances) * 1e3, speeds, values, levels=[limit], colors="w")
        ax.set_xlabel("clearance (mm)")
        ax.set_ylabel("drive speed (rpm)")
        ax.set_title(f"{label}; white: threshold {limit:g}", fontsize=9)
    save_png(fig, path, layout=True)


SPECIAL_MARKERS = {"fold": ("s", "tab:orange"), "period_doubling": ("D", "tab:red"),
                   "neimark_sacker": ("^", "tab:purple"), "grazing": ("o", "tab:green")}


def response(path, rows, specials, sweeps, parameter, unit, title) -> None:
    """The continued branches' amplitude against the parameter (stable solid, unstable
    dashed; a doubled branch in its own colour), the bifurcations marked, and the direct
    up- and down-sweeps; below, the first clearance joint's largest normal force over each
    orbit and each sweep's value (where the mechanism has one)."""
    forces = any(r[7] is not None for r in rows)
    fig, axes = plt.subplots(2 if forces else 1, 1, figsize=(9, 8 if forces else 5), sharex=True, squeeze=False)
    ax = axes[0, 0]
    colours = ["tab:blue", "tab:purple", "tab:brown", "tab:pink"]
    for branch in sorted({r[0] for r in rows}):
        mine = [r for r in rows if r[0] == branch]
        values = np.array([r[2] for r in mine])
        stable = np.array([bool(r[4]) for r in mine])
        colour = colours[branch % len(colours)]
        for column, scale, bx in ((3, 1e3, ax), (7, 1.0, axes[-1, 0] if forces else None)):
            if bx is None:
                continue
            y = np.array([np.nan if r[column] is None else r[column] * scale for r in mine])
            for k in range(len(mine) - 1):
                bx.plot(values[k:k + 2], y[k:k + 2], "-" if stable[k] and stable[k + 1] else "--",
                        color=colour, lw=1.6)
        what = "continued" if branch == 0 else f"period {mine[0][1]} (switched at a doubling)"
        ax.plot([], [], "-", color=colour, label=f"{what}, stable")
        ax.plot([], [], "--", color=colour, label=f"{what}, unstable")
    if forces:
        axes[-1, 0].set_ylabel("largest normal force over the orbit (N)")
        axes[-1, 0].set_xlabel(f"{parameter} ({unit})")
        axes[-1, 0].grid(alpha=0.3)
    for direction, marker, colour in (("up", "^", "tab:orange"), ("down", "v", "tab:green")):
        kept = [r for r in sweeps if r[0] == direction]
        if kept:
            ax.plot([r[1] for r in kept], [r[2] * 1e3 for r in kept], marker, color=colour, ms=4, alpha=0.7,
                    label=f"direct {direction}-sweep")
            if forces:
                axes[-1, 0].plot([r[1] for r in kept], [np.nan if r[4] is None else r[4] for r in kept],
                                 marker, color=colour, ms=4, alpha=0.7)
    for kind, (marker, colour) in SPECIAL_MARKERS.items():
        found = [s for s in specials if s.kind == kind]
        if found:
            ax.plot([s.p for s in found], [s.point.measures["amplitude"] * 1e3 for s in found], marker,
                    color=colour, ms=8, mfc="none", mew=1.6, label=kind.replace("_", " "))
    ax.set_xlabel(f"{parameter} ({unit})")
    ax.set_ylabel("response amplitude (mm)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save_png(fig, path, layout=True)
