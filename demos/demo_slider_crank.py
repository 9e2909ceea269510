# %% [markdown]
# # The Flores slider-crank on its calibrated contact law
#
# The slider-crank of Flores and Ambrósio [FloresAmbrosio2004]: a crank of 50 mm driven at
# 5000 rpm, a connecting rod of 120 mm and a slider of 0.14 kg, with a clearance of 0.5 mm in
# the revolute joint between the rod and the slider (a steel pin of 9.5 mm radius in a 10 mm
# bore, 20 mm long). The rod's pin rattles in its bore: each impact is a spike of contact
# force, and how tall the spikes come out depends on the contact law the multibody model
# uses. Here the law is the joint's own, calibrated on its finite-element curve, from Python
# from start to end:
#
# 1. the FE push of the joint's pin into its bore (`pinbore.run("fem", ...)`);
# 2. the laws fitted and ranked on that curve (`pinbore.calibrate`);
# 3. the mechanism run on the best law (`pinbore.run("reduced", ...)`), beside the same
#    mechanism on Hertz's law as the literature uses it.
#
# At the end, two checks against physics the run was not told: its hardest impact stores the
# slider's kinetic energy in the joint (work and energy, in closed form on the calibrated
# law), and its energy book closes.
#
# The mechanism model: [multibody](../docs/theory/multibody.md).
#
# `PINBORE_DEMO_SMALL=1` runs fewer load steps and a shorter run; `PINBORE_DEMO_OUT` says
# where the files go (default `build/demos`).

# %%
import dataclasses
import os
import tomllib
from pathlib import Path

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

import pinbore
import pinbore.laws

SMALL = os.environ.get("PINBORE_DEMO_SMALL") == "1"
OUT = Path(os.environ.get("PINBORE_DEMO_OUT", "build/demos")) / "slider_crank"
SCENES = Path(__file__).resolve().parent.parent / "scenes"
LENGTH = 0.02   # m, the joint's axial length

# %% [markdown]
# ## The joint in the finite element
#
# The joint's section in plane strain: the pin of 9.5 mm radius in the bore of 10 mm of a
# steel plate held at 20 bore radii, both E = 207 GPa, ν = 0.3 (the mechanism's values),
# pushed by up to 120 µm beyond first touch, past the deepest approach the mechanism reaches.

# %%
fem_scene = {
    "kind": "fem",
    "geometry": {"dim": 2, "pin_radius": 9.5e-3, "bore_radius": 10.0e-3,
                 "housing_radius": 0.2, "hub_radius": 2.0e-3},
    "materials": {"pin": {"E": 207e9, "nu": 0.3}, "bore": {"E": 207e9, "nu": 0.3}},
    "contact": {"method": "penalty", "friction": 0.0},
    "load": {"max_approach": 1.2e-4, "steps": 4 if SMALL else 8, "direction_deg": -90.0},
    "output": {"picture": False},
}
curve = pinbore.run("fem", fem_scene, out=OUT / "fem")
for d, p, eps in zip(curve.approach, curve.force, curve.half_angle):
    print(f"approach {d * 1e6:6.1f} um: {p / 1e6:6.2f} MN/m, contact half-angle {eps:5.1f} deg")

# %% [markdown]
# ## Its calibrated law
#
# The laws fitted on this one curve, for a joint 20 mm long; the best fitted is the one the
# mechanism takes, by name: `normal_law = "calibrated:<law>"`.

# %%
laws = pinbore.calibrate([OUT / "fem" / "curve.csv"], out=OUT / "laws", length=LENGTH)
errors = {name: law.fitted_errors["fem"].rms_rel for name, law in laws.laws.items() if law.fitted}
best = min(errors, key=errors.get)
fit = laws.laws[best].fitted
print(f"best fitted law: {best}, s = {fit.scale:.3f}, q = {fit.exponent_correction:+.3f}, "
      f"{errors[best]:.2%} rms from the FE curve")

# %% [markdown]
# ## The mechanism
#
# The shipped scene `scenes/reduced/slider_crank_flores2004_calibrated.toml` is the mechanism
# (bodies, ideal joints, the drive, the clearance joint with Lankarani–Nikravesh damping at a
# restitution of 0.9); read as a dict, it takes this demo's laws file and best law. The run
# is `pinbore reduced` in process: it writes `timeseries.csv`, `summary.json` and plots, and
# returns the summary.

# %%
SHORT = 0.006   # s, half a revolution, for PINBORE_DEMO_SMALL (the scenes run four)
calibrated = tomllib.loads((SCENES / "reduced" / "slider_crank_flores2004_calibrated.toml").read_text())
calibrated["laws_file"] = str(OUT / "laws" / "laws.json")
calibrated["clearance_joints"][0]["normal_law"] = f"calibrated:{best}"
if SMALL:
    calibrated["duration"] = SHORT
summary = pinbore.run("reduced", calibrated, out=OUT / "calibrated")
joint = summary.clearance_joints["rod_slider"]
print(f"{summary.status}: {joint.impacts} impacts, peak contact force {joint.peak_normal_force_N / 1e3:.1f} kN "
      f"at {joint.time_of_peak_s * 1e3:.3f} ms, deepest approach {joint.peak_penetration_m * 1e6:.1f} um")

# %% [markdown]
# The same mechanism on Hertz's point law as the literature uses it
# (`slider_crank_flores2004.toml`):

# %%
hertz = tomllib.loads((SCENES / "reduced" / "slider_crank_flores2004.toml").read_text())
if SMALL:
    hertz["duration"] = SHORT
hertz_summary = pinbore.run("reduced", hertz, out=OUT / "hertz")
hertz_joint = hertz_summary.clearance_joints["rod_slider"]
print(f"{hertz_summary.status}: {hertz_joint.impacts} impacts, peak contact force "
      f"{hertz_joint.peak_normal_force_N / 1e3:.1f} kN at {hertz_joint.time_of_peak_s * 1e3:.3f} ms, "
      f"deepest approach {hertz_joint.peak_penetration_m * 1e6:.1f} um")

# %% [markdown]
# The calibrated law is stiffer than Hertz's point law at these approaches, and the peak
# force of the joint's hardest impact comes out higher on it.
#
# ## Check: the hardest impact stores the slider's kinetic energy
#
# The hardest impact is the first, at a crank angle of a few degrees: the rod lies nearly
# along the slider's axis, so along the contact's normal the rod's pin moves with the crank,
# driven at constant speed, while the slider, free along its axis, runs into it at the
# approach speed v₀. Over the few tens of microseconds of contact, the slider's kinetic energy
# goes into the joint's elastic work:
#
#     ½ m v₀² = ∫₀^δ F(x) dx ,     F = L P_cal ,
#
# which gives the deepest approach δ and the peak force F(δ) in closed form on the calibrated
# law, with no multibody model at all. The model has more in it (the damping, the crank's
# motion during the contact, the rod's turning), each worth a per cent or less here.

# %%
slider = next(b for b in calibrated["bodies"] if b["name"] == "slider")
c = calibrated["clearance_joints"][0]
law = pinbore.laws.load(OUT / "laws" / "laws.json", dataclasses.replace(
    pinbore.scene(fem_scene).joint, length=c["length"]), damping="none")[best]

kinetic = 0.5 * slider["mass"] * joint.peak_impact_speed_m_per_s ** 2
depth = brentq(lambda d: quad(law, 0.0, d)[0] - kinetic, 1e-9, law.approach_range_m[1])
print(f"v0 = {joint.peak_impact_speed_m_per_s:.3f} m/s, 1/2 m v0^2 = {kinetic:.3f} J")
print(f"deepest approach: energy {depth * 1e6:.2f} um, mechanism {joint.peak_penetration_m * 1e6:.2f} um")
print(f"peak force:       energy {law(depth) / 1e3:.2f} kN, mechanism {joint.peak_normal_force_N / 1e3:.2f} kN")
assert joint.time_of_peak_s < 1e-3, "the hardest impact is the first"
assert abs(joint.peak_penetration_m / depth - 1) < 0.03
assert abs(joint.peak_normal_force_N / law(depth) - 1) < 0.03

# %% [markdown]
# ## Check: the energy book
#
# Kinetic, gravitational and elastic energy, plus what the damping dissipated, minus the work
# the drive put in, is a constant of the motion; the run reports its largest change, which
# only the integrator's tolerance (rtol 1e-5 in this scene) may leave.

# %%
for name, run in (("calibrated", summary), ("hertz", hertz_summary)):
    book = run.energy_balance
    print(f"{name:10s}: drive work {book.work_in_J:.3f} J, dissipated {book.dissipated_J:.3f} J, "
          f"largest residual {book.relative_to_peak_kinetic:.1e} of the peak kinetic energy")
    assert book.relative_to_peak_kinetic < 1e-3
