# %% [markdown]
# # A flexible body from its modes
#
# A mechanism's links bend. pinbore brings a body's elasticity into a multibody model the way
# the floating-frame formulation does: the body moves as a rigid frame plus a few of its
# elastic modes, computed once from its finite-element model and reduced. The body here is a
# steel strip 1 m long, 20 mm × 5 mm, pinned at one end and bending in the plane of its 5 mm
# side: released at rest from horizontal under gravity, it swings as a pendulum and bends as
# it swings.
#
# 1. `pinbore modes` (here `pinbore.run("modes", ...)`) meshes the strip with Gmsh, assembles
#    its stiffness and mass with DOLFINx (P2, plane stress), and reduces it by Craig–Bampton
#    with its pinned end as a rigid interface, the eigenproblems solved with SLEPc, then
#    expresses the free modes in the body's mean-axis frame. It writes the reduced body,
#    `body.npz`.
# 2. A mechanism scene names that file as a body's `modes_file`; `pinbore reduced` integrates
#    the frame and the modal coordinates together.
#
# The checks: the reduced body's frequencies against Euler–Bernoulli's free-free beam, and
# the pendulum's energy book and swing against the rigid compound pendulum's closed form.
#
# The reduction and the floating frame: [flexible bodies](../docs/theory/flexible.md).
#
# `PINBORE_DEMO_SMALL=1` swings it for a shorter time; `PINBORE_DEMO_OUT` says where the files
# go (default `build/demos`).

# %%
import math
import os
import tomllib
from pathlib import Path

import numpy as np
import scipy.special

import pinbore

SMALL = os.environ.get("PINBORE_DEMO_SMALL") == "1"
OUT = Path(os.environ.get("PINBORE_DEMO_OUT", "build/demos")) / "flexible_body"
SCENES = Path(__file__).resolve().parent.parent / "scenes"

# %% [markdown]
# ## The body and its modes
#
# The shipped modes scene `scenes/modes/pendulum_beam_2d.toml`: a bar (`shape = "bar"`) with
# its interfaces "a" and "b" at its ends, here reduced on "a", the pinned one, with six
# fixed-interface modes and six free modes kept; `full_modes` also asks for the whole FE
# model's free modes, to measure what the reduction loses.

# %%
modes_file = SCENES / "modes" / "pendulum_beam_2d.toml"
print(modes_file.read_text())
body = pinbore.run("modes", modes_file, out=OUT / "modes")
print(f"mass {body.mass:.4f} kg, {body.modes} modes, {body.nodes.shape[0]} nodes")

# %% [markdown]
# ## Check: the frequencies against Euler–Bernoulli
#
# A free-free beam bends at ω_n = (β_n L)² √(EI / (ρA L⁴)), β_n L the roots of
# cos βL cosh βL = 1 (4.7300, 7.8532, 10.9956, 14.1372, 17.2788, 20.4204 [Blevins1979]); here
# I = t w³ / 12 for the in-plane width w = 5 mm and the thickness t = 20 mm, A = t w. A strip
# 200 times as long as it is wide is a slender beam: shear and rotary inertia (Timoshenko)
# lower its first frequencies by less than 1e-3 and the mesh's error is smaller still; the
# reduction, which keeps six fixed-interface modes, raises them by less than 1e-3 on the
# first four. Its sixth free mode, its last, carries its truncation: at 1154 Hz it is not the
# beam's sixth bending mode (495 Hz, which the whole FE model has).

# %%
scene = tomllib.loads(modes_file.read_text())
b, m = scene["body"], scene["material"]
EI = m["E"] * b["thickness"] * b["width"] ** 3 / 12
rho_A = m["density"] * b["thickness"] * b["width"]
beta_L = np.array([4.73004074, 7.85320462, 10.9956078, 14.1371655, 17.2787597, 20.4203522])
euler_bernoulli = beta_L ** 2 * math.sqrt(EI / (rho_A * b["length"] ** 4))
print(" mode   reduced (Hz)   whole FE (Hz)   Euler-Bernoulli (Hz)   reduced / EB - 1")
for n, (reduced, whole, exact) in enumerate(zip(body.omega[:5], body.full_omega, euler_bernoulli), 1):
    print(f"{n:5d} {reduced / (2 * math.pi):14.2f} {whole / (2 * math.pi):15.2f} "
          f"{exact / (2 * math.pi):22.2f} {reduced / exact - 1:+18.1e}")
assert np.all(np.abs(body.omega[:4] / euler_bernoulli[:4] - 1) < 1e-3)
assert abs(body.mass / (rho_A * b["length"]) - 1) < 1e-9

# %% [markdown]
# ## The pendulum
#
# The shipped scene `scenes/reduced/flexible_pendulum.toml`: the strip's frame centred at
# x = 0.5 m, its end "a" pinned to the ground at the origin by an ideal revolute joint,
# gravity 9.81 m/s², no damping; a point "tip" at the free end whose elastic displacement in
# the frame is written out. The scene names the modes file that `make modes` builds; here it
# takes the one just written.

# %%
pendulum = tomllib.loads((SCENES / "reduced" / "flexible_pendulum.toml").read_text())
pendulum["bodies"][0]["modes_file"] = str(OUT / "modes" / "body.npz")
if SMALL:
    pendulum["duration"] = 0.3   # s, a quarter swing
summary = pinbore.run("reduced", pendulum, out=OUT / "pendulum")
series = np.genfromtxt(OUT / "pendulum" / "timeseries.csv", delimiter=",", names=True)
print(f"{summary.status}: {summary.steps} steps in {summary.wall_time_s:.2f} s; the tip bends "
      f"by up to {np.abs(series['beam_tip_uy_m']).max() * 1e3:.2f} mm from the frame's axis")

# %% [markdown]
# ## Check: the energy book
#
# Nothing dissipates and nothing drives: kinetic energy (of the frame and of the modes),
# gravity's potential and the strain energy of the modes add up to a constant.

# %%
book = summary.energy_balance
print(f"largest change of the total energy: {book.max_residual_J:.1e} J, "
      f"{book.relative_to_peak_kinetic:.1e} of the peak kinetic energy")
assert book.relative_to_peak_kinetic < 1e-9

# %% [markdown]
# ## Check: the swing against the rigid pendulum
#
# The strip is stiff: its first frequency, 27 Hz, is far above the pendulum's, about 0.6 Hz,
# so its frame swings as the rigid compound pendulum of the same mass m and inertia J about
# its centre, pinned at d = 0.5 m from it. Released at rest from horizontal, that pendulum's
# angle from the downward vertical φ follows Jacobi's elliptic sine exactly, at any amplitude:
#
#     sin(φ / 2) = k sn(K(k) − ω₀ t, k),    k = sin 45°,    ω₀² = m g d / (J + m d²).
#
# The frame's angle stays within 2 mrad of it: what the bending moves.

# %%
g, arm = 9.81, 0.5
J = body.second_moments[0, 0] + body.second_moments[1, 1]   # kg m^2, about the centre of mass
w0 = math.sqrt(body.mass * g * arm / (J + body.mass * arm ** 2))
k2 = 0.5
sn = scipy.special.ellipj(scipy.special.ellipk(k2) - w0 * series["time_s"], k2)[0]
rigid = 2 * np.arcsin(math.sqrt(k2) * sn) - math.pi / 2      # the angle from +x, as the frame's
difference = np.abs(series["beam_angle_rad"] - rigid)
print(f"the pendulum turns by {np.ptp(series['beam_angle_rad']):.2f} rad; its frame stays within "
      f"{difference.max() * 1e3:.2f} mrad of the rigid pendulum")
assert difference.max() < 2e-3
