"""Sweep rate of the nonlinear-dynamics analyses, a bifurcation diagram against the clearance
on 2 local processes at rtol 1e-4 (the shipped scenes use 1e-5), plus 2 x 10 revolutions for
the Lyapunov sign where a point is not periodic:
- planar: the Flores slider-crank, 200 points over 0.1-0.5 mm, 25 transient and 50 sampled
  crank revolutions per point;
- spatial: its misaligned spatial variant (bore tilted 1 deg, 16 slices), 100 points over
  0.2-0.5 mm (below 0.175 mm the tilted journal does not fit its bore), 10 transient and 20
  sampled revolutions per point.
Records the wall time and the CPU time of all the sweep's processes (the machine may be
shared). Writes OUT/sweep.csv (a row per sweep; a sweep run alone replaces its own row) and
OUT/sweep.png, OUT/sweep_spatial.png (the diagrams)."""

import argparse
import csv
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import tomli_w

ROOT = Path(__file__).resolve().parent.parent
WORKERS = 2
# name: (scene, clearance range m, points, transient, sampled revolutions, picture)
SWEEPS = {"planar": ("slider_crank_flores2004.toml", (1e-4, 5e-4), 200, 25, 50, "sweep.png"),
          "spatial": ("spatial_slider_crank_flores_misaligned.toml", (2e-4, 5e-4), 100, 10, 20,
                      "sweep_spatial.png")}
COLUMNS = ["scene", "points", "transient_periods", "sampled_periods", "workers", "wall_time_s",
           "points_per_s", "cpu_time_s", "cpu_seconds_per_point", "classes"]


def run(name: str, work: Path) -> dict:
    """One sweep through `pinbore dynamics` (a subprocess, as a user runs it): its row."""
    file, (low, high), points, transient, periods, picture = SWEEPS[name]
    data = tomllib.loads((ROOT / "scenes" / "reduced" / file).read_text())
    data["integrator"] = {"rtol": 1e-4, "atol": 1e-8}
    scene = work / file
    scene.write_text(tomli_w.dumps(data))
    start, cpu = time.perf_counter(), _children_cpu()
    subprocess.run([sys.executable, "-m", "pinbore.cli", "dynamics", str(scene), "--analysis",
                    "bifurcation", "--parameter", "clearance", "--range", str(low), str(high),
                    "--points", str(points), "--transient", str(transient), "--periods",
                    str(periods), "--workers", str(WORKERS), "--out", str(work / name)],
                   check=True, cwd=ROOT)
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu
    counts = json.loads((work / name / "summary.json").read_text())["counts"]
    shutil.copy(work / name / "bifurcation.png", work / picture)
    return {"scene": file.removesuffix(".toml"), "points": points, "transient_periods": transient,
            "sampled_periods": periods, "workers": WORKERS, "wall_time_s": f"{wall:.1f}",
            "points_per_s": f"{points / wall:.2f}", "cpu_time_s": f"{cpu:.1f}",
            "cpu_seconds_per_point": f"{cpu / points:.2f}",
            "classes": " ".join(f"{k}:{v}" for k, v in counts.items())}


def _children_cpu() -> float:
    """CPU seconds (user + system) of the finished subprocesses and theirs (the sweep's
    workers): the cost of a sweep whatever else the machine runs (the wall time on 2 free
    cores is about half of it)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main(out: Path, names: list[str]) -> None:
    work = Path(tempfile.mkdtemp())
    try:
        rows = {name: run(name, work) for name in names}
        out.mkdir(parents=True, exist_ok=True)
        table = out / "sweep.csv"
        kept = {}
        if table.exists():   # the rows of the sweeps not run now
            for row in csv.DictReader(table.open()):
                name = next((n for n, s in SWEEPS.items() if s[0] == f"{row.get('scene')}.toml"), None)
                if name and name not in rows and set(row) == set(COLUMNS):
                    kept[name] = row
        with table.open("w", newline="") as f:
            writer = csv.DictWriter(f, COLUMNS)
            writer.writeheader()
            for name in SWEEPS:
                if name in rows or name in kept:
                    writer.writerow(rows.get(name) or kept[name])
        for name in names:
            shutil.copy(work / SWEEPS[name][5], out / SWEEPS[name][5])
        print(table.read_text())
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--sweeps", nargs="+", choices=list(SWEEPS), default=list(SWEEPS))
    args = parser.parse_args()
    main(args.out, args.sweeps)
