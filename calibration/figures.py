"""Figures of a calibration: every law over every FE curve; error maps."""

import numpy as np

from pinbore.core.figures import plt, save_png

from pinbore.calibration.lawsfile import law_force

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
