"""The discretisation error of the restitution study: studies/convergence/restitution_mesh.toml
(a steel pin in a steel bore, c = 10 um, at 1 and 5 m/s; the whole mesh refined 0, 1 and 2
times, the steps over the contact doubled each time) through `pinbore study`, and per speed the
Richardson extrapolation of e from the three meshes with the observed order
p = log2((e0 - e1) / (e1 - e2)): e_inf = e2 + (e2 - e1) / (2^p - 1). Writes
OUT/restitution_convergence.csv: per mesh and speed, e, its error against e_inf and the run
time of the point. About 9 minutes on 2 cores (the r2 points), seconds from the study's cache.
"""

import argparse
import csv
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "studies" / "convergence" / "restitution_mesh.toml"


def main(out: Path, cache: Path) -> None:
    folder = cache.parent / "restitution_mesh"
    done = subprocess.run([sys.executable, "-m", "pinbore.cli", "study", str(STUDY), "--out", str(folder),
                           "--cache", str(cache)], stderr=subprocess.DEVNULL)
    if done.returncode != 0:
        raise SystemExit(f"bench/restitution_convergence.py: the study failed (exit {done.returncode})")
    with open(folder / "results.csv") as f:
        rows = list(csv.DictReader(f))
    table = []
    for speed in sorted({float(r["impact.speed"]) for r in rows}):
        e = {r["mesh"]: (float(r["restitution"]), float(r["seconds"]))
             for r in rows if float(r["impact.speed"]) == speed}
        e0, e1, e2 = (e[m][0] for m in ("r0", "r1", "r2"))
        order = math.log2((e0 - e1) / (e1 - e2))
        converged = e2 + (e2 - e1) / (2**order - 1)
        for mesh in ("r0", "r1", "r2"):
            table.append({"speed_m_per_s": speed, "mesh": mesh, "restitution": e[mesh][0],
                          "observed_order": order, "extrapolated": converged,
                          "relative_error": e[mesh][0] / converged - 1, "seconds": e[mesh][1]})
            print(f"{speed:g} m/s {mesh}: e = {e[mesh][0]:.5f}, {table[-1]['relative_error']:+.2%} "
                  f"of {converged:.5f} (order {order:.2f}), {e[mesh][1]:.0f} s")
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "restitution_convergence.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(table[0]))
        writer.writeheader()
        writer.writerows(table)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "bench")
    parser.add_argument("--cache", type=Path, default=ROOT / "build" / "study" / "cache")
    args = parser.parse_args()
    main(args.out, args.cache)
