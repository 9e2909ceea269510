"""The study runner's cost (`pinbore study`, pinbore.core.parallel) on the shipped Monte Carlo
study of the Flores slider-crank (studies/slider_crank_monte_carlo.toml: 2 crank revolutions
a point, friction and restitution scattered), on 2 local processes:
- the runner's own cost per point: core.parallel.cached_map on 2 workers with a task that
  does no work and returns a point's real result (a summary.json of the study, ~2 kB) for a
  real point's scene (~3 kB): submitting, pickling both ways, the atomic cache file, the
  progress bar; per point of a worker's time (wall time x workers / points), against the mean
  time of a point's own run in its worker (its `seconds` in results.csv: build, integrate,
  summarise);
- studies of 50 and 250 points (fresh caches): wall time per point;
- beside it, the same point through `pinbore reduced` (a process per point, as a shell loop
  would run it: interpreter, imports, the engine's cache load, the files);
- the whole 1000-point study, and a rerun of it (all points from the cache);
- how an FE study scales: the 2D calibration study (10 points) on 1 and 2 local workers, a
  local Dask cluster of 2 workers, and 1 worker with 2 MPI ranks a point (the CPU time of a
  Dask cluster's workers is not the command's, and is not counted).
Records wall and CPU time and the load average (the machine may be shared, which a study's
wall time feels and the runner's own cost hardly does). Writes OUT/study.csv and OUT/study.png."""

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
import tomli_w

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "studies" / "slider_crank_monte_carlo.toml"
WORKERS = 2
COLUMNS = ["case", "points", "workers", "wall_time_s", "cpu_time_s", "per_point_s", "load_average"]


def _children_cpu() -> float:
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


def study(work: Path, points: int, name: str, cache: Path | None = None) -> tuple[dict, list[dict]]:
    """The shipped study with `points` points (its own base, made absolute), run fresh: its
    row and its results table."""
    data = tomllib.loads(STUDY.read_text())
    data["base"] = str((STUDY.parent / data["base"]).resolve())
    data["sampling"]["points"] = points
    if "surrogate" in data and points < 2 * math.comb(len(data["parameters"]) + data["surrogate"]["degree"],
                                                      data["surrogate"]["degree"]):
        data.pop("surrogate")   # too few points for its chaos
    path = work / f"{name}.toml"
    path.write_text(tomli_w.dumps(data))
    cache = cache or work / f"{name}-cache"
    start, cpu = time.perf_counter(), _children_cpu()
    subprocess.run([sys.executable, "-m", "pinbore.cli", "study", str(path), "--out", str(work / name),
                    "--workers", str(WORKERS), "--cache", str(cache)], cwd=work,
                   stderr=subprocess.DEVNULL)
    if not (work / name / "results.csv").exists():
        raise SystemExit(f"bench/study.py: the study {name} wrote nothing")
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu
    with open(work / name / "results.csv") as f:
        rows = list(csv.DictReader(f))
    failed = sum(r["status"] != "complete" for r in rows)
    return ({"case": name + (f" ({failed} points not complete)" if failed else ""), "points": points,
             "workers": WORKERS, "wall_time_s": wall, "cpu_time_s": cpu, "per_point_s": wall / points,
             "load_average": os.getloadavg()[0]}, rows)


CALIBRATION = ROOT / "studies" / "calibration_2d.toml"


def calibration_scaling(work: Path) -> list[dict]:
    """The 2D calibration study (10 FE points of 1-3 s each, each worker importing DOLFINx once)
    on fresh caches: 1 local worker, 2, a local Dask cluster of 2 worker processes, and 1
    worker whose points run on 2 MPI ranks each."""
    import distributed

    data = tomllib.loads(CALIBRATION.read_text())
    data["base"] = str((CALIBRATION.parent / data["base"]).resolve())
    path = work / "calibration_2d.toml"
    path.write_text(tomli_w.dumps(data))
    rows = []
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        for name, options in (("1 worker", ["--workers", "1"]), ("2 workers", ["--workers", "2"]),
                              ("a local Dask cluster of 2 workers", ["--scheduler", cluster.scheduler_address]),
                              ("1 worker, 2 MPI ranks a point", ["--workers", "1", "--ranks", "2"])):
            folder = work / f"calibration {name}"
            start, cpu = time.perf_counter(), _children_cpu()
            subprocess.run([sys.executable, "-m", "pinbore.cli", "study", str(path), "--out", str(folder),
                            "--cache", str(folder) + "-cache", *options], cwd=work,
                           stderr=subprocess.DEVNULL, check=True)
            wall = time.perf_counter() - start
            points = len(list((folder / "points").iterdir()))
            rows.append({"case": f"calibration_2d (FE): {name}", "points": points,
                         "workers": 2 if "2 workers" in name else 1, "wall_time_s": wall,
                         "cpu_time_s": _children_cpu() - cpu, "per_point_s": wall / points,
                         "load_average": os.getloadavg()[0]})
    return rows


def echo(item):
    """A task that does no work: the result of a real point."""
    return item[1]


def runner_overhead(work: Path, points: int = 2000) -> dict:
    """cached_map's cost per point of a worker's time, on a task that does no work (see the
    module), on a fresh cache; the start of its 2 workers included (an upper bound)."""
    from pinbore.core.parallel import cached_map

    scene = json.loads(json.dumps(tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())))
    record = {"status": "complete", "reason": "", "seconds": 0.3,
              "result": json.loads((work / "n250" / "summary.json").read_text())
              | {"pad": "x" * 1500}}
    items = [(dict(scene, point=k), record) for k in range(points)]
    start = time.perf_counter()
    cached_map(echo, items, [f"p{k}" for k in range(points)], work / "overhead", WORKERS, None)
    wall = time.perf_counter() - start
    return {"wall_time_s": wall, "per_point_s": wall * WORKERS / points}


def reduced_cli(work: Path, repeats: int = 3) -> dict:
    """One point of the study (its base with [set] and the distributions' centres) through
    `pinbore reduced`, a process each time."""
    data = tomllib.loads((STUDY.parent / tomllib.loads(STUDY.read_text())["base"]).read_text())
    data["duration"] = 0.024
    data["integrator"]["rtol"] = 1e-6
    data["clearance_joints"][0]["friction"] = {"law": "coulomb_ambrosio", "mu": 0.05}
    data.setdefault("output", {})["plots"] = False
    scene = work / "point.toml"
    scene.write_text(tomli_w.dumps(data))
    start, cpu = time.perf_counter(), _children_cpu()
    for k in range(repeats):
        subprocess.run([sys.executable, "-m", "pinbore.cli", "reduced", str(scene), "--out",
                        str(work / f"point{k}")], check=True, cwd=work)
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu
    return {"case": "pinbore reduced, a process per point (no plots)", "points": repeats, "workers": 1,
            "wall_time_s": wall, "cpu_time_s": cpu, "per_point_s": wall / repeats,
            "load_average": os.getloadavg()[0]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "bench")
    p.add_argument("--skip-1000", action="store_true", help="only the overhead")
    args = p.parse_args()
    with tempfile.TemporaryDirectory(prefix="pinbore-bench-study-") as folder:
        work = Path(folder)
        small, _ = study(work, 50, "n50")
        large, rows = study(work, 250, "n250")
        seconds = np.array([float(r["seconds"]) for r in rows])
        slope = (large["wall_time_s"] - small["wall_time_s"]) / (large["points"] - small["points"])
        start = small["wall_time_s"] - slope * small["points"]
        overhead = runner_overhead(work)
        table = [small, large, reduced_cli(work), {
            "case": "runner's own cost per point (a task that does no work, 2000 points)",
            "points": 2000, "workers": WORKERS, "wall_time_s": overhead["wall_time_s"], "cpu_time_s": "",
            "per_point_s": f"{overhead['per_point_s']:.2e} = {overhead['per_point_s'] / seconds.mean():.2%} "
                           f"of a point's mean run ({seconds.mean():.3f} s)",
            "load_average": os.getloadavg()[0]}]
        table += calibration_scaling(work)
        whole = None
        if not args.skip_1000:
            whole, whole_rows = study(work, 1000, "n1000")
            again, _ = study(work, 1000, "n1000", cache=work / "n1000-cache")
            again["case"] = "n1000 rerun (every point cached)"
            table += [whole, again]
            summary = json.loads((work / "n1000" / "summary.json").read_text())
            tolerance = json.loads((work / "n1000" / "tolerance.json").read_text())
            print(json.dumps({"summary": summary, "tolerance_half_width": tolerance["half_width"],
                              "upper_bound": tolerance["upper_bound"]}, indent=2))
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "study.csv", "w", newline="") as f:
        out = csv.DictWriter(f, COLUMNS)
        out.writeheader()
        for row in table:
            out.writerow({k: f"{v:.4g}" if isinstance(v, float) else v for k, v in row.items()})
    figure(args.out / "study.png", small, large, whole, slope, start, seconds)


def figure(path, small, large, whole, slope, start, seconds) -> None:
    from pinbore.core.figures import plt, save_png

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    runs = [r for r in (small, large, whole) if r is not None]
    n = np.array([r["points"] for r in runs])
    a.plot(n, [r["wall_time_s"] for r in runs], "o", label="study, 2 workers")
    grid = np.linspace(0, n.max(), 50)
    a.plot(grid, start + slope * grid, "--", label=f"{start:.1f} s + {slope * 1e3:.0f} ms/point")
    a.set_xlabel("points")
    a.set_ylabel("wall time (s)")
    a.legend()
    b.hist(seconds * 1e3, bins=30)
    b.set_xlabel("a point's run in its worker (ms)")
    b.set_ylabel("points (N = 250)")
    save_png(fig, path, layout=True)


if __name__ == "__main__":
    main()
