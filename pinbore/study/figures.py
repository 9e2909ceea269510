"""A study's figures: histograms and exceedance curves of its quantities, Sobol indices (with
sobol.csv) and the tolerance band."""

import math
from pathlib import Path

import numpy as np

from pinbore.core import uq
from pinbore.study.plan import Plan
from pinbore.study.stats import complete, sampled


def figures_of(folder: Path, plan: Plan, rows: list[dict], stats: dict) -> None:
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    names = [c.name for c in plan.study.collect]
    conf = plan.study.confidence
    rows = sampled(plan, rows)
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.5), squeeze=False)
    for ax, name in zip(axes[0], names):
        y = complete(rows, name)
        if len(y):
            ax.hist(y, bins=max(5, min(50, int(math.sqrt(len(y))))), color="tab:blue", alpha=0.8)
            ax.axvline(stats["quantities"][name]["mean"], color="k", label="mean")
        ax.set_xlabel(name)
        ax.set_ylabel("points")
    save_png(fig, folder / "histograms.png", layout=True)
    fig, axes = plt.subplots(1, len(names), figsize=(4.5 * len(names), 3.5), squeeze=False)
    for ax, name in zip(axes[0], names):
        y = complete(rows, name)
        if len(y):
            curve = uq.exceedance_curve(y, conf)
            ax.step(curve[:, 0], curve[:, 1], where="post", label="P(Y > y)")
            ax.fill_between(curve[:, 0], curve[:, 2], curve[:, 3], step="post", alpha=0.3,
                            label=f"{conf:.0%} Clopper-Pearson")
            ax.set_yscale("log")
        lim = plan.study.limit
        if lim is not None and lim.quantity == name:
            ax.axvline(lim.threshold, color="r", ls="--")
            ax.axhline(lim.target, color="r", ls=":")
        ax.set_xlabel(name)
        ax.set_ylabel("exceedance probability")
        ax.legend(fontsize=7)
    save_png(fig, folder / "exceedance.png", layout=True)
    if stats.get("sobol"):
        sobol_outputs(folder, plan, stats["sobol"], plt, save_png)


def sobol_outputs(folder, plan, sobol, plt, save_png) -> None:
    from pinbore.reduced.dynamics.plots import write_table   # noqa: PLC0415

    write_table(folder / "sobol.csv", ["quantity", "parameter", "first", "first_low", "first_high",
                                       "total", "total_low", "total_high"],
                [[q, p, s["first"], *s["first_interval"], s["total"], *s["total_interval"]]
                 for q, by in sobol.items() for p, s in by.items()])
    fig, axes = plt.subplots(1, len(sobol), figsize=(5 * len(sobol), 3.5), squeeze=False)
    x = np.arange(len(plan.names))
    for ax, (q, by) in zip(axes[0], sobol.items()):
        for shift, order in ((-0.2, "first"), (0.2, "total")):
            v = np.array([by[p][order] for p in plan.names])
            ci = np.array([by[p][f"{order}_interval"] for p in plan.names])
            ax.bar(x + shift, v, 0.4, yerr=[v - ci[:, 0], ci[:, 1] - v], capsize=3, label=order)
        ax.set_xticks(x, plan.names, rotation=20, fontsize=7)
        ax.set_title(q)
        ax.legend()
    save_png(fig, folder / "sobol.png", layout=True)


def tolerance_figure(path: Path, answer: dict) -> None:
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415

    fig, ax = plt.subplots(figsize=(5, 3.5))
    if answer["curve"]:
        c = np.array(answer["curve"], dtype=float)
        ax.plot(c[:, 0], c[:, 3], label="upper bound on P(exceed)")
    ax.axhline(answer["target"], color="r", ls=":", label="target")
    if answer["half_width"] is not None:
        ax.axvline(answer["half_width"], color="k", ls="--", label="largest band")
    ax.set_xlabel(f"half-width of {answer['parameter']}")
    ax.set_yscale("log")
    ax.legend(fontsize=7)
    save_png(fig, path, layout=True)
