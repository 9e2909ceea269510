"""The discretisation error of the shipped studies, measured by refining the whole mesh (and
the steps, where the result depends on them): the studies of studies/convergence/ through
`pinbore study`.

Each convergence study crosses a group of cases `mesh` with the cases of its other groups
(joints, speeds, lugs). Its cases r0, r1, r2 are a family of meshes, each refined from the
one before by halving every element size (mesh.refine: on the contact arc, along the
surfaces, through the pin's wall and the housing; in 3D the layers along the length double
too) and doubling the steps over an impact; `study`, where given, is the shipped study's own
mesh when it is not r0. Per case of the other groups and per collected quantity q:

- with r0, r1, r2: the observed order p = log2((q0 - q1) / (q1 - q2)) and Richardson's
  extrapolation to the converged mesh, q_inf = q2 + (q2 - q1) / (2^p - 1);
- with r0 and r1 only (a case whose r2 would take too long): the same with the smallest order
  observed in any three-level case (the most cautious: a smaller order extrapolates
  further), marked `order assumed`;

and each mesh's relative error q / q_inf - 1 with the run time of its point. Writes
OUT/discretisation.csv and OUT/discretisation.png (the error against the run time, per case).
The r2 points take minutes each (about 40 minutes on 2 cores from scratch); a rerun reads the
study cache.
"""

import argparse
import csv
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
STUDIES = sorted((ROOT / "studies" / "convergence").glob("*.toml"))
FAMILY = ("r0", "r1", "r2")
COLUMNS = ["study", "case", "quantity", "mesh", "value", "observed_order", "extrapolated",
           "relative_error", "seconds"]


def run(study: Path, cache: Path) -> list[dict]:
    """The study's results table (the cache makes a rerun cheap)."""
    folder = cache.parent / "convergence" / study.stem
    done = subprocess.run([sys.executable, "-m", "pinbore.cli", "study", str(study), "--out", str(folder),
                           "--cache", str(cache)], stderr=subprocess.DEVNULL)
    if done.returncode != 0:
        raise SystemExit(f"bench/discretisation.py: {study.name} failed (exit {done.returncode})")
    with open(folder / "results.csv") as f:
        return list(csv.DictReader(f))


def extrapolated(coarse: float, fine: float, order: float) -> float:
    """The limit of values on a mesh and on its halving, converging at `order`."""
    return fine + (fine - coarse) / (2**order - 1)


def richardson(q0: float, q1: float, q2: float) -> tuple[float, float]:
    """(observed order, extrapolated value) of three values on meshes halved in turn."""
    order = math.log2((q0 - q1) / (q1 - q2))
    return order, extrapolated(q1, q2, order)


def cases_of(study: Path, rows: list[dict]) -> list[tuple[str, str, dict]]:
    """(case, quantity, {mesh: (value, seconds)}) of every case of the study's other groups
    and every collected quantity."""
    data = tomllib.loads(study.read_text())
    groups = [g for g in data.get("cases", {}) if g != "mesh"] + list(data.get("parameters", {}))
    out = []
    for quantity in (c["name"] for c in data["collect"]):
        cases = {}
        for r in rows:
            case = " ".join(r[g] for g in groups)
            cases.setdefault(case, {})[r["mesh"]] = (float(r[quantity]), float(r["seconds"]))
        out += [(case, quantity, meshes) for case, meshes in cases.items()]
    return out


def tables(studies: dict[str, list]) -> list[dict]:
    """The rows of OUT/discretisation.csv: every mesh of every case against the extrapolated
    value (three-level cases with their observed order, two-level ones with the smallest order
    observed of all three-level cases)."""
    fitted = {(study, case, quantity): richardson(*(meshes[m][0] for m in FAMILY))
              for study, cases in studies.items() for case, quantity, meshes in cases
              if all(m in meshes for m in FAMILY)}
    cautious = min(p for p, _ in fitted.values())
    out = []
    for study, cases in studies.items():
        for case, quantity, meshes in cases:
            if (study, case, quantity) in fitted:
                order, converged = fitted[study, case, quantity]
                note = ""
            else:
                (q0, _), (q1, _) = meshes["r0"], meshes["r1"]
                order, converged = cautious, extrapolated(q0, q1, cautious)
                note = " (order assumed)"
            for mesh, (value, seconds) in meshes.items():
                out.append({"study": study, "case": case, "quantity": quantity, "mesh": mesh,
                            "value": value, "observed_order": f"{order:.3g}{note}",
                            "extrapolated": converged, "relative_error": value / converged - 1,
                            "seconds": seconds})
                print(f"{study} {case} {quantity} {mesh}: {value:.6g}, {value / converged - 1:+.2%} "
                      f"of {converged:.6g} (order {order:.2f}{note}), {seconds:.0f} s")
    return out


def figure(path: Path, table: list[dict]) -> None:
    studies = sorted({r["study"] for r in table})
    fig, axes = plt.subplots(1, len(studies), figsize=(4.2 * len(studies), 3.6), squeeze=False)
    for ax, study in zip(axes[0], studies):
        mine = [r for r in table if r["study"] == study]
        for case, quantity in sorted({(r["case"], r["quantity"]) for r in mine}):
            line = sorted((r for r in mine if r["case"] == case and r["quantity"] == quantity
                           and r["mesh"] in FAMILY), key=lambda r: r["mesh"])
            label = case if len({r["quantity"] for r in mine}) == 1 else f"{case}, {quantity}"
            drawn = ax.loglog([r["seconds"] for r in line], [abs(r["relative_error"]) for r in line],
                              "o-", ms=4, label=label)
            for r in mine:
                if r["case"] == case and r["quantity"] == quantity and r["mesh"] == "study":
                    ax.loglog(r["seconds"], abs(r["relative_error"]), "*", ms=11,
                              color=drawn[0].get_color())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(study, fontsize=9)
        ax.set_xlabel("run time of a point (s)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    axes[0][0].set_ylabel("|relative error| against the extrapolated value\n(r0, r1, r2; star: the study's mesh)")
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main(out: Path, cache: Path) -> None:
    table = tables({study.stem: cases_of(study, run(study, cache)) for study in STUDIES})
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "discretisation.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(table)
    figure(out / "discretisation.png", table)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--cache", type=Path, default=ROOT / "build" / "study" / "cache")
    args = parser.parse_args()
    main(args.out, args.cache)
