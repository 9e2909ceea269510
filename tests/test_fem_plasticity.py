"""Elasto-plastic contact and load-unload programmes in the FE model, against independent
references: Johnson's first-yield load of a Hertzian line contact, the energy balance of a
loading-unloading loop, elastic unloading, and the purely elastic limit."""

import math

import numpy as np
import pytest
from conftest import STEEL, Solved, scene_dict, with_clearance

from pinbore.fem import curve as fe_curve
from pinbore.fem.plasticity import von_mises

COARSE = {"contact_size": 1.75e-4, "grading": 0.5}   # 3k dofs: the bench's coarse level


def plastic(yield_stress, hardening_modulus=2e9):
    return {**STEEL, "yield_stress": yield_stress, "hardening_modulus": hardening_modulus}


class Cycle:
    """A frictionless load-unload-reload-unload programme on the coarse mesh, bore plastic."""

    def __init__(self, bore, steps=12, **load):
        self.solved = Solved(scene_dict(materials={"pin": dict(STEEL), "bore": bore},
                                        load={"steps": steps, "unload": True, "cycles": 2, **load},
                                        mesh=COARSE))
        steps = self.solved.run.steps
        self.stage = np.array([s.stage for s in steps])
        self.approach = np.array([s.approach for s in steps])
        self.force = np.array([s.force[0] for s in steps])
        self.plastic_work = np.array([s.plastic_work for s in steps])
        self.residual = np.array([s.residual_approach for s in steps])
        self.first = np.flatnonzero(self.stage == "reload")[0]   # the first cycle ends before it

    def loop_work(self, end):
        """The hub's work (J/m) from first touch to step `end` (exclusive): the trapezoidal
        area under the force-approach curve, loading positive, unloading negative."""
        d = np.concatenate([[0.0], self.approach[:end]])
        f = np.concatenate([[0.0], self.force[:end]])
        return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(d)))


@pytest.fixture(scope="module")
def cycle():
    return Cycle(plastic(30e6))


def test_loop_area_is_plastic_work_plus_locked_elastic_energy(cycle):
    """Energy balance over the first cycle (first touch -> zero force): the area of the
    force-approach loop equals the plastic work plus the elastic energy locked in the
    residual stresses (the contact is open at both ends). The FE pieces close exactly
    (fem.plasticity: trapezoidal plastic work); what is left is the trapezoidal rule on the
    contact forces, which are not linear in the step: O(step^2), measured 8e-3 of the
    plastic work with 6 steps and 1.2e-3 with 12 (default mesh, the same loop), so 12 steps
    are held to 4e-3. The second cycle reloads to the same approach elastically (isotropic
    hardening): shakedown, plastic work < 1e-3 of the first cycle's."""
    end = cycle.first
    material = cycle.solved.stepper.material
    work = cycle.plastic_work[:end].sum()
    assert work > 0.1 * cycle.loop_work(end)   # a loop that is mostly plastic, not a rounding
    # the elastic energy now equals that after the first cycle (the second adds none)
    balance = cycle.loop_work(end) - work - material.elastic_energy()
    print(f"loop {cycle.loop_work(end):.6e} J/m, plastic {work:.6e}, locked elastic "
          f"{material.elastic_energy():.6e}, residual {balance / work:.2e}")
    assert abs(balance) <= 4e-3 * work
    assert cycle.plastic_work[end:].sum() < 1e-3 * work


def test_unloading_is_elastic_and_retraced(cycle):
    """Unloading does not yield again (no plastic work on unloading steps; the contact
    pressure is far below the yield surface in reverse), and reloading retraces the unloading
    curve (no hysteresis without friction): the reload forces equal the unloading curve
    interpolated at their approaches, above a tenth of the top force (linear interpolation
    between unloading steps: 2 %, measured 0.8 %; at the toe, where the curve bends most
    and the steps are far apart, the chord is 5 % off)."""
    unload = np.flatnonzero(cycle.stage[:cycle.first] == "unload")
    assert np.all(cycle.plastic_work[unload] == 0.0)
    reload = np.flatnonzero(cycle.stage == "reload")
    curve = np.concatenate([[unload[0] - 1], unload])[::-1]   # from the top down
    d, f = cycle.approach[curve], cycle.force[curve]
    inside = (cycle.approach[reload] > d[0]) & (cycle.force[reload] > 0.1 * f.max())
    expected = np.interp(cycle.approach[reload][inside], d, f)
    np.testing.assert_allclose(cycle.force[reload][inside], expected, rtol=0.02)
    # the same top force after reloading (the state at the top is that of the first cycle)
    assert cycle.force[reload[-1]] == pytest.approx(cycle.force[unload[0] - 1], rel=1e-6)


def test_residual_approach_is_where_the_force_vanishes(cycle):
    """The unloading ends at zero force: the last unloading step carries less than 1e-4 of
    the top force and the residual approach (its secant zero) is positive (the bore keeps a
    dent: the pin must travel further to touch it again), the same after both cycles
    (shakedown) and below the approach of that step."""
    ends = np.flatnonzero(np.isfinite(cycle.residual))
    assert list(cycle.stage[ends]) == ["unload", "unload"]
    top = cycle.force.max()
    assert np.all(cycle.force[ends] <= 1e-4 * top)
    assert np.all(cycle.residual[ends] > 0) and np.all(cycle.residual[ends] <= cycle.approach[ends])
    assert cycle.residual[ends[1]] == pytest.approx(cycle.residual[ends[0]], rel=1e-3)


@pytest.mark.slow
def test_unloading_slope_is_that_of_the_elastic_curve():
    """Just past first yield the plastic zone is small: the first unloading slope equals the
    slope of the purely elastic curve at the same force (its secant over the same force
    interval) within 2 %, and both exceed the elasto-plastic loading slope at the top."""
    bore = plastic(60e6)
    cycle = Cycle(bore, steps=6)
    elastic = Cycle(dict(STEEL), steps=6)
    top = cycle.first - 1
    while cycle.stage[top] != "push":
        top -= 1
    assert cycle.plastic_work[top] > 0
    unload_slope = (cycle.force[top] - cycle.force[top + 1]) / (cycle.approach[top] - cycle.approach[top + 1])
    # the elastic curve's secant between the same two forces
    f_hi, f_lo = cycle.force[top], cycle.force[top + 1]
    d_hi, d_lo = (np.interp(f, elastic.force[:elastic.first][elastic.stage[:elastic.first] == "push"],
                            elastic.approach[:elastic.first][elastic.stage[:elastic.first] == "push"])
                  for f in (f_hi, f_lo))
    elastic_slope = (f_hi - f_lo) / (d_hi - d_lo)
    loading_slope = (cycle.force[top] - cycle.force[top - 1]) / (cycle.approach[top] - cycle.approach[top - 1])
    print(f"unloading {unload_slope:.4e}, elastic {elastic_slope:.4e}, loading {loading_slope:.4e} N/m^2")
    assert unload_slope == pytest.approx(elastic_slope, rel=0.02)
    assert unload_slope > loading_slope


def test_a_material_that_never_yields_is_the_elastic_model():
    """A yield stress above every stress of the run: zero plastic work, and the curve of the
    elastic model (constant stiffness) to 1e-10 (the same equations assembled another way:
    the quadrature-point stress against K u)."""
    data = scene_dict(load={"steps": 2}, mesh=COARSE)
    elastic = Solved(data)
    data["materials"]["bore"] = plastic(1e12)
    data["materials"]["pin"] = plastic(1e12)
    never = Solved(data)
    assert never.stepper.material.plastic and not elastic.stepper.material.plastic
    np.testing.assert_allclose(never.forces, elastic.forces, rtol=1e-10)
    assert all(s.plastic_work == 0.0 for s in never.run.steps)
    assert all(s.plastic_work == 0.0 for s in elastic.run.steps)


# The largest plane-strain von Mises stress under a Hertzian line contact, over p0 (nu = 0.3):
# hertz_line_von_mises on the axis, 0.5575 at z = 0.704 a (Johnson's p0 = 1.79 Y, rounded).
VM_MAX = 0.5575


def first_yield(mesh):
    """Large clearance (c/R = 0.1), light load, pin and bore of one steel, Y = 100 MPa: the
    FE's first-yield load over Johnson's, and the FE von Mises stress along the load axis in
    the pin minus McEwen's half-space field with the Hertz a and p0 of the FE's force.

    The FE first yields when the largest von Mises stress of its quadrature points (one per
    P1 cell) reaches Y; the elastic stress grows as sqrt(P), so from the last elastic step k
    that load is P_k (Y / vm_k)^2, and the plastic model does start yielding at the next
    step. Johnson's closed form [Johnson1985] (§6.2, von Mises, nu = 0.3): p0 = Y / VM_MAX,
    so P = pi R* p0^2 / E* with the conformal 1/R* = 1/R_pin - 1/R_bore."""
    from pinbore.laws.elastic import hertz_line_von_mises
    from pinbore.meshes.model import PIN

    clearance, radius, Y = 1e-3, 10e-3, 100e6
    r_pin = radius - clearance
    steel = plastic(Y, 10e9)
    data = with_clearance(clearance, materials={"pin": steel, "bore": steel},
                          contact={"method": "penalty"}, load={"max_approach": 2.5e-6, "steps": 5},
                          mesh={"max_cells": 400000, **mesh})
    stresses = []
    holder = {}
    solved = Solved(data, on_step=lambda x, step: stresses.append(
        holder["stepper"].material.stress.copy()), hook=holder)
    steps = solved.run.steps
    elastic = [i for i, s in enumerate(steps) if s.max_plastic_strain == 0.0]
    k = elastic[-1]
    assert k + 1 < len(steps) and steps[k + 1].max_plastic_strain > 0   # yields at the next step
    vm = von_mises(stresses[k])
    force = steps[k].force[0]
    fe = force * (Y / vm.max()) ** 2
    assert force < fe <= steps[k + 1].force[0]
    r_star = radius * r_pin / clearance
    e_star = solved.scene.effective_modulus
    johnson = math.pi * r_star * (Y / VM_MAX) ** 2 / e_star
    # the cells of the pin that the load axis (x = 0, below the pin's centre) crosses
    mesh_ = solved.el.mesh
    cells = mesh_.topology.index_map(2).size_local
    X = mesh_.geometry.x[mesh_.geometry.dofmaps[0][:cells]][:, :, :2]
    tags = np.zeros(cells, int)
    tags[solved.mesh_data.cell_tags.indices] = solved.mesh_data.cell_tags.values
    centre = X.mean(axis=1)
    a = math.sqrt(4 * force * r_star / (math.pi * e_star))      # Hertz, from the FE force
    p0 = 2 * force / (math.pi * a)
    depth = r_pin - np.hypot(centre[:, 0], centre[:, 1])
    axis = ((tags == PIN) & (centre[:, 1] < 0) & (X[:, :, 0].min(axis=1) < 0)
            & (X[:, :, 0].max(axis=1) > 0) & (depth > 0.2 * a) & (depth < 2.5 * a))
    excess = (vm[axis] - hertz_line_von_mises(0.0, depth[axis], a, p0, 0.3)) / p0
    print(f"first yield: FE {fe:.4e} N/m, Johnson {johnson:.4e} N/m, ratio {fe / johnson:.4f}; "
          f"axis vm - McEwen: mean {excess.mean():.4f} p0, largest {np.abs(excess).max():.4f} p0, "
          f"a/R_pin {a / r_pin:.4f}")
    return fe / johnson, excess, a / r_pin


def ring_limit(a_over_r):
    """The first-yield ratio the FE tends to as its mesh refines: the pin is a ring on a rigid
    hub, not a half-space, and carries a smooth stress of the order of the force over its
    radius, P / R = (pi/2) (a/R) p0, on which the Hertz field rides. Bounded by a/R p0 added
    to the largest von Mises stress VM_MAX p0, the load at first yield falls by the factor
    (VM_MAX / (VM_MAX + a/R))^2 at most (0.90 at a/R = 0.029)."""
    return (VM_MAX / (VM_MAX + a_over_r)) ** 2


def test_first_yield_matches_johnson_line_contact():
    """On the default mesh. Measured over five meshes (contact_size and grading halved
    together, every other size kept; h, the element size at the depth of the largest stress):
    h/a = 0.29, 0.165 (default), 0.088, 0.042, 0.021 give FE/Johnson 0.763, 0.847, 0.874,
    0.908, 0.922; the observed order of the last three is 1.3 and the Richardson limit 0.932,
    so the default mesh yields early by 0.085 in load ratio (the largest of the P1 cell
    stresses overshoots the smooth peak). The limit is not 1: along the load axis the FE von
    Mises stress exceeds McEwen's by a mean of 0.022, 0.019, 0.018, 0.018 p0 (mesh levels
    0-3), a smooth excess carried by a tension sigma_x = 0.0215 p0 of the ring, which alone
    lowers the yield load by (0.5575 / (0.5575 + 0.018))^2 = 0.937, the Richardson limit
    to 0.5 %. Asserted: the FE yields no later than Johnson's load and no earlier than the
    ring bound (ring_limit) less the measured default-mesh error 0.085; the axis excess lies
    between 0 and a/R (the ring's stress bound), its largest cell deviation within a/R + 0.04
    p0 (the cells scatter about the smooth excess by 0.027-0.04 p0 on this mesh, 0.009 on the
    finest)."""
    ratio, excess, a_over_r = first_yield({})
    assert ring_limit(a_over_r) - 0.085 <= ratio <= 1.0
    assert 0.0 < excess.mean() <= a_over_r
    assert np.abs(excess).max() <= a_over_r + 0.04


@pytest.mark.slow
def test_first_yield_converges_towards_the_ring_limit():
    """The mesh twice refined (contact_size / 4, grading / 4: 2.2e5 cells, about 90 s): the
    ratio rises towards the Richardson limit 0.932 and stays within the ring bound less this
    level's measured discretisation error (0.932 - 0.908 = 0.024) and 1; the axis stress
    is within a/R + 0.02 p0 of McEwen's (the cells scatter by 0.014 p0 about the smooth excess
    on this mesh)."""
    ratio, excess, a_over_r = first_yield({"contact_size": 4.2e-6 / 4, "grading": 0.25 / 4})
    assert ring_limit(a_over_r) - 0.024 <= ratio <= 1.0
    assert 0.0 < excess.mean() <= a_over_r
    assert np.abs(excess).max() <= a_over_r + 0.02


def test_old_curves_read_without_the_plastic_columns(tmp_path):
    """A curve.csv written before the plastic columns existed reads with zero plastic work,
    zero plastic strain and no residual approach."""
    path = tmp_path / "curve.csv"
    names = [c.name for f, c in fe_curve.COLUMNS[2].items()
             if f not in ("plastic_work", "max_plastic_strain", "residual_approach")]
    row = {c.name: c.cell(1 if c.kind is int else ("push" if c.kind is str else 1.0))
           for c in fe_curve.COLUMNS[2].values()}
    path.write_text(",".join(names) + "\n" + ",".join(str(row[n]) for n in names) + "\n")
    old = fe_curve.read(path)
    assert old.plastic_work[0] == 0.0 and old.max_plastic_strain[0] == 0.0
    assert math.isnan(old.residual_approach[0])
