"""The report's section on the studies under build/study (make study): each study's
statistics, figures and answers."""

import csv
import json
import math
from pathlib import Path

CHAOS_HOLDS = 0.05   # a chaos whose leave-one-out error is above this share of the variance misses
                    # more than a twentieth of it: its indices are not shown as an answer


def _studies(build_dir: Path) -> list[Path]:
    return sorted(p.parent for p in (Path(build_dir) / "study").glob("*/summary.json"))


def answers(build_dir: Path) -> list[tuple[str, str]]:
    """The report's first screen: each study's [limit] (the exceedance probability with its
    interval, against its target) and [tolerance] (the widest band) answers."""
    out = []
    for folder in _studies(build_dir):
        stats = json.loads((folder / "statistics.json").read_text())
        limit = stats.get("limit")
        if limit:
            low, high = limit["interval"]
            out.append((f"P({limit['quantity']} &gt; {limit['threshold']:.4g}), {folder.name}",
                        f"{limit['probability']:.3f} [{low:.3f}, {high:.3f}] against a target of "
                        f"{limit['target']:g}: {'met' if limit['meets_target'] else 'not shown to be met'} "
                        f"({limit['points']} points, {stats['confidence']:.0%} confidence)"))
        for quantity, indices in stats.get("sobol", {}).items():
            name, top = max(indices.items(), key=lambda item: item[1]["total"])
            low, high = top["total_interval"]
            out.append((f"What drives {quantity}, {folder.name}",
                        f"{name}: total-order Sobol index {top['total']:.2f} [{low:.2f}, {high:.2f}] "
                        f"(first order {top['first']:.2f}; of {len(indices)} inputs)"))
        for quantity, c in stats.get("surrogate", {}).items():
            if "total" not in c:
                continue
            name = max(c["total"], key=c["total"].get)
            held = c["loo_error"] <= CHAOS_HOLDS
            out.append((f"What drives {quantity}, {folder.name} (polynomial chaos)",
                        f"{name}: total-order Sobol index {c['total'][name]:.2f} (first order "
                        f"{c['first'][name]:.2f}); the chaos's leave-one-out error "
                        f"{c['loo_error']:.1g} of the variance"
                        + ("" if held else ": the chaos does not hold, nor its indices")))
        if (folder / "tolerance.json").exists():
            t = json.loads((folder / "tolerance.json").read_text())
            band = (f"&plusmn;{t['half_width']:.3g} about {t['centre']:.4g}" if t["half_width"]
                    else "no band of the sample")
            out.append((f"Tolerance of {t['parameter']}, {folder.name}",
                        f"{band} keeps P({t['quantity']} &gt; {t['threshold']:.4g}) &le; "
                        f"{t['target']:g} with {t['confidence']:.0%} confidence "
                        f"({t['exceeding_in_band']} of {t['points_in_band']} points in it above)"))
    return out


def section(build_dir: Path, bench_dir: Path) -> str:
    """Each study's statistics (mean, spread and quantiles with their intervals), its
    figures and its answers."""
    import html as markup   # noqa: PLC0415

    from pinbore.core.html import figure, note, png_data, table   # noqa: PLC0415

    parts = ["<h2>Studies: uncertainty and tolerance</h2>",
             "<p>A scene run over a sample of its inputs (<code>pinbore study</code>): the "
             "statistics of each collected quantity with their confidence intervals, the "
             "exceedance of a limit, Sobol indices and the tolerance band (docs/study.md).</p>"]
    studies = _studies(build_dir)
    if not studies:
        return "".join(parts) + note("No studies under build/study: run <code>make study</code>.")
    for folder in studies:
        s = json.loads((folder / "summary.json").read_text())
        stats = json.loads((folder / "statistics.json").read_text())
        parts.append(f"<h3>{markup.escape(folder.name)}</h3><p>{s['complete']} of {s['points']} "
                     f"points complete ({stats['method']}), base scene "
                     f"<code>{markup.escape(str(s['base']))}</code>.</p>")
        if stats["method"] == "grid":   # chosen points: their table, not a distribution
            results = list(csv.DictReader((folder / "results.csv").read_text().splitlines()))
            quantities = list(stats["quantities"])
            parts.append(table(["point", *quantities, "status"],
                               [[r["name"], *(f"{float(r[q]):.5g}" for q in quantities), r["status"]]
                                for r in results]))
            continue
        untrusted = set()

        def shown(name, value, spec):   # a statistic as the page shows it
            if isinstance(value, (int, float)) and math.isfinite(value):
                return format(value, spec)
            untrusted.add(name)
            return "not finite"

        rows = [[name, f"{shown(name, q['mean'], '.4g')} [{shown(name, q['mean_interval'][0], '.4g')}, "
                 f"{shown(name, q['mean_interval'][1], '.4g')}]",
                 shown(name, q["std"], ".3g"), shown(name, q["q05"], ".4g"), shown(name, q["q50"], ".4g"),
                 f"{shown(name, q['q95'], '.4g')} [{shown(name, q['q95_interval'][0], '.4g')}, "
                 f"{shown(name, q['q95_interval'][1], '.4g')}]"]
                for name, q in stats["quantities"].items()]
        parts.append(table(["quantity", f"mean [{stats['confidence']:.0%}]", "std", "5 %",
                            "median", f"95 % quantile [{stats['confidence']:.0%}]"], rows))
        if untrusted:
            parts.append(note(f"Not finite in statistics.json, so not shown as results: "
                              f"{markup.escape(', '.join(sorted(untrusted)))} (an interval of "
                              "too few points is not finite; otherwise the file was changed "
                              "or a point's value is not a number)."))
        if "statistics_of" in stats:
            parts.append(f"<p>Statistics of {stats['statistics_of']}.</p>")
        sobol = [[quantity, name, f"{i['first']:.2f} [{i['first_interval'][0]:.2f}, {i['first_interval'][1]:.2f}]",
                  f"{i['total']:.2f} [{i['total_interval'][0]:.2f}, {i['total_interval'][1]:.2f}]"]
                 for quantity, indices in stats.get("sobol", {}).items() for name, i in indices.items()]
        if sobol:
            parts.append(table(["quantity", "input", f"first order [{stats['confidence']:.0%}]",
                                f"total order [{stats['confidence']:.0%}]"], sobol))
        chaos = [[quantity, f"{c['degree']} ({c['terms']} terms)", f"{c['loo_error']:.2g}",
                  f"{c['mean']:.4g} ± {c['std']:.3g}",
                  ", ".join(f"{markup.escape(n)} {c['first'][n]:.2f} / {c['total'][n]:.2f}" for n in c["first"])]
                 for quantity, c in stats.get("surrogate", {}).items() if "degree" in c]
        if chaos:
            parts.append(table(["quantity", "chaos degree", "leave-one-out error / variance",
                                "mean ± std", "Sobol indices, first / total order"], chaos))
        for png, caption in (("histograms.png", "histograms of the collected quantities"),
                             ("exceedance.png", "exceedance curve: P(quantity > x)"),
                             ("sobol.png", "Sobol indices, first and total order"),
                             ("tolerance.png", "the exceedance's upper bound against the band")):
            if (folder / png).exists():
                parts.append(figure(png_data(folder / png), f"{markup.escape(folder.name)}: {caption}."))
    return "".join(parts)
