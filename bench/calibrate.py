"""Benchmark of the calibration: time to fit and rank every law on the study curves.

Reads the FE curves of the 2D calibration study (build/study/calibration_2d/points/*/curve.csv,
made by `make calibration`), times
the fit and ranking (median of 5 runs; reading files excluded) and writes OUT/calibration.csv.
"""

import argparse
import statistics
import time
from pathlib import Path

from pinbore.calibration.curves import read_curve
from pinbore.calibration.run import evaluate, ranking
from pinbore.laws.lawsfile import LAWS

ROOT = Path(__file__).resolve().parent.parent


def main(out: Path) -> None:
    paths = sorted((ROOT / "build" / "study" / "calibration_2d" / "points").glob("*/curve.csv"))
    if not paths:
        raise SystemExit("bench/calibrate.py: no study curves under build/study/calibration_2d: "
                         "run `make calibration` first")
    curves = [read_curve(p, None) for p in paths]
    times = []
    for _ in range(5):
        start = time.perf_counter()
        ranking(curves, evaluate(curves))
        times.append(time.perf_counter() - start)
    points = sum(c.approach.size for c in curves)
    out.mkdir(parents=True, exist_ok=True)
    (out / "calibration.csv").write_text(
        "curves,points,laws,fit_and_rank_s_median,fit_and_rank_s_max\n"
        f"{len(curves)},{points},{len(LAWS)},{statistics.median(times):.3f},{max(times):.3f}\n")
    print((out / "calibration.csv").read_text())


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    main(parser.parse_args().out)
