"""Benchmark of the first-yield load of a Hertzian line contact against the mesh.

Pin and bore of one steel, c/R = 0.1, an elastic push to 2 um (a/R_pin = 0.029, the load at
which a Y = 100 MPa steel first yields). The first-yield load of the FE, P (Y / max vm)^2 from
the largest von Mises stress of its P1 cells, over Johnson's pi R* (Y / 0.5575)^2 / E*
(laws.elastic.hertz_line_von_mises: the peak of McEwen's field, 0.5575 p0 at z = 0.70 a,
nu = 0.3), at contact-zone sizes (contact_size and grading) halved level after level, every
other size kept. Writes OUT/first_yield.csv and OUT/first_yield.png: wall time (build and
solve), cells, h/a (the element size at the depth of the peak over the contact half-width),
the ratio, and the mean and largest excess of the FE von Mises stress over McEwen's along the
load axis (0.2 a < z < 2.5 a, in p0). The ratio's Richardson limit from the last two levels at the
order of P1 stresses (1) is printed and drawn, beside the ratio that the ring's smooth excess
alone gives, (0.5575 / (0.5575 + excess))^2. About 75 s.
"""

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.core.scene import validate
from pinbore.fem import model
from pinbore.fem.plasticity import von_mises
from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import hertz_line_von_mises
from pinbore.meshes.model import PIN

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fem2d import write_table  # noqa: E402  (the benchmarks' one table writer)

VM_MAX = 0.5575      # the peak of hertz_line_von_mises over p0, nu = 0.3
R_PIN, R_BORE = 9e-3, 10e-3
R_STAR = R_PIN * R_BORE / (R_BORE - R_PIN)
LEVELS = [0.5**k for k in (-1, 0, 1, 2)]     # times the default contact_size and grading
DEFAULT_SIZE = 4.2011e-6                    # the contact_size pinbore chooses for this scene


def scene(scale: float) -> dict:
    steel = {"E": 210e9, "nu": 0.3, "yield_stress": 1e12}   # never yields: the stresses kept
    return {"kind": "fem",
            "geometry": {"dim": 2, "pin_radius": R_PIN, "bore_radius": R_BORE,
                         "housing_radius": 0.2, "hub_radius": 2e-3},
            "materials": {"pin": steel, "bore": dict(steel)},
            "contact": {"method": "penalty", "friction": 0.0},
            "load": {"max_approach": 2e-6, "steps": 2, "direction_deg": -90.0},
            "mesh": {"contact_size": DEFAULT_SIZE * scale, "grading": 0.25 * scale,
                     "max_cells": 10**6},
            "output": {"picture": False}}


def level(scale: float):
    start = time.perf_counter()
    sc = validate(FemScene, scene(scale), "first-yield scene")
    stepper, el, _, _, data = model.build(sc)
    run = stepper.run(sc.load.programme)
    wall = time.perf_counter() - start
    vm = von_mises(stepper.material.stress)
    force, e_star = run.steps[-1].force[0], sc.effective_modulus
    ratio = force * e_star / (math.pi * R_STAR * (vm.max() / VM_MAX) ** 2)
    a = math.sqrt(4 * force * R_STAR / (math.pi * e_star))
    p0 = 2 * force / (math.pi * a)
    mesh = el.mesh
    cells = mesh.topology.index_map(2).size_local
    X = mesh.geometry.x[mesh.geometry.dofmaps[0][:cells]][:, :, :2].copy()
    tags = np.zeros(cells, int)
    tags[data.cell_tags.indices] = data.cell_tags.values
    centre = X.mean(axis=1)
    depth = R_PIN - np.hypot(centre[:, 0], centre[:, 1])
    area = 0.5 * np.abs((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1])
                        - (X[:, 2, 0] - X[:, 0, 0]) * (X[:, 1, 1] - X[:, 0, 1]))
    axis = ((tags == PIN) & (centre[:, 1] < 0) & (X[:, :, 0].min(axis=1) < 0)
            & (X[:, :, 0].max(axis=1) > 0))
    near = axis & (np.abs(depth - 0.7 * a) < 0.15 * a)
    h = float(np.median(np.sqrt(2 * area[near])))
    band = axis & (depth > 0.2 * a) & (depth < 2.5 * a)
    excess = (vm[band] - hertz_line_von_mises(0.0, depth[band], a, p0, 0.3)) / p0
    profile = (depth[axis & (depth < 3 * a)] / a, vm[axis & (depth < 3 * a)] / p0)
    return [f"{scale:g}", f"{DEFAULT_SIZE * scale:.3e}", f"{0.25 * scale:g}", cells,
            f"{h / a:.3f}", f"{wall:.1f}", f"{ratio:.4f}", f"{excess.mean():.4f}",
            f"{np.abs(excess).max():.4f}", f"{a / R_PIN:.4f}"], profile


def richardson(h, r, order=1.0):
    """Limit of the last two ratios (sizes halving) at the order of P1 stresses, 1, and the
    order observed on the last three (erratic on these levels: the largest cell value
    jumps between cells; with a fifth level, 860k cells and 13 minutes, it was 1.3 and the
    limit 0.932)."""
    observed = math.log2(abs((r[-2] - r[-3]) / (r[-1] - r[-2])))
    return r[-1] + (r[-1] - r[-2]) / (2**order - 1), observed


def main(out: Path) -> None:
    header = ["scale", "contact_size_m", "grading", "cells", "h_over_a", "wall_s",
              "fe_over_johnson", "axis_excess_mean_p0", "axis_excess_max_p0", "a_over_r"]
    rows, profiles = [], []
    for scale in LEVELS:
        row, profile = level(scale)
        rows.append(row)
        profiles.append(profile)

    def plot(path, header, rows):
        h = np.array([float(r[4]) for r in rows])
        ratio = np.array([float(r[6]) for r in rows])
        limit, order = richardson(h, ratio)
        ring = (VM_MAX / (VM_MAX + np.mean([float(r[7]) for r in rows[-2:]]))) ** 2
        print(f"Richardson limit (order 1) {limit:.4f}, observed order {order:.2f}, "
              f"ring excess alone {ring:.4f}")
        fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.8))
        left.plot(h, ratio, "o-", label="FE / Johnson")
        left.axhline(limit, ls="--", c="k", label=f"Richardson limit {limit:.3f} (order 1)")
        left.axhline(ring, ls=":", c="r", label=f"ring excess alone {ring:.3f}")
        left.axhline(1.0, c="grey", lw=0.8)
        left.set_xscale("log")
        left.set_xlabel("h / a at the depth of the peak")
        left.set_ylabel("first-yield load, FE / Johnson")
        left.legend()
        z = np.linspace(0, 3, 300)
        right.plot(z, hertz_line_von_mises(0.0, z, 1.0, 1.0, 0.3), "k-", label="McEwen (half-space)")
        for (zz, v), r in zip(profiles, rows):
            order_ = np.argsort(zz)
            right.plot(zz[order_], v[order_], ".-", ms=3, lw=0.7, label=f"FE, h/a = {r[4]}")
        right.set_xlabel("depth below the contact centre z / a")
        right.set_ylabel("von Mises / p0 on the load axis (pin)")
        right.legend()
        save_png(fig, path, layout=True)

    write_table(out, "first_yield", header, rows, plot)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("bench"))
    main(parser.parse_args().out)
