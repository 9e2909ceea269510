"""Sweep rate of the nonlinear-dynamics analyses: a 200-point bifurcation diagram of the
Flores slider-crank against the clearance (0.1-0.5 mm), 25 transient and 50 sampled crank
revolutions per point (plus 2 x 10 for the Lyapunov sign where a point is not periodic), on
2 local processes, at rtol 1e-4 (the shipped scene uses 1e-5). Writes OUT/sweep.csv and
OUT/sweep.png (the diagram)."""

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import tomli_w

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
POINTS, TRANSIENT, PERIODS, WORKERS = 200, 25, 50, 2


def main(out: Path) -> None:
    work = Path(tempfile.mkdtemp())
    try:
        data = tomllib.loads(SCENE.read_text())
        data["integrator"] = {"rtol": 1e-4, "atol": 1e-8}
        scene = work / "slider_crank.toml"
        scene.write_text(tomli_w.dumps(data))
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "pinbore.cli", "dynamics", str(scene), "--analysis",
                        "bifurcation", "--parameter", "clearance", "--range", "1e-4", "5e-4",
                        "--points", str(POINTS), "--transient", str(TRANSIENT), "--periods",
                        str(PERIODS), "--workers", str(WORKERS), "--out", str(work / "out")],
                       check=True, cwd=ROOT)
        wall = time.perf_counter() - start
        counts = json.loads((work / "out" / "summary.json").read_text())["counts"]
        out.mkdir(parents=True, exist_ok=True)
        shutil.copy(work / "out" / "bifurcation.png", out / "sweep.png")
        (out / "sweep.csv").write_text(
            "points,transient_periods,sampled_periods,workers,wall_time_s,points_per_s,classes\n"
            f"{POINTS},{TRANSIENT},{PERIODS},{WORKERS},{wall:.1f},{POINTS / wall:.2f},"
            f"\"{' '.join(f'{k}:{v}' for k, v in counts.items())}\"\n")
        print((out / "sweep.csv").read_text())
    finally:
        shutil.rmtree(work)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
