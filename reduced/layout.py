"""Named layouts of the compiled kernel's data: the columns of its row arrays, the codes stored
in them, and the bundles it passes around.

Rows are float arrays (one row per element) addressed by the column names below. They are
module-level integers, which numba freezes into the compiled code as constants, so a named
column costs exactly what a literal did. The bundles are namedtuples, which numba compiles
as plain structs and caches like tuples; passing one costs what passing its arrays one by
one did (numba counts the references of each array a function receives). Numba's cache does
not see edits to this module: reduced.kernel drops its compiled code when they happen.

The state vector y of the integrator holds q (x, y, phi of each body's centre of mass), q',
the energy dissipated in the joints, the work of the constraint forces, then the friction
states of the clearance joints (one for LuGre and Dahl, two for the Iwan element).
"""

from collections import namedtuple

# ---- clearance joint (Model.joints): one row per joint, JOINT_COLUMNS floats
# bearing and journal: body (-1: the ground) and centre (m, in the body's frame)
JOINT_BEARING_BODY, JOINT_BEARING_X, JOINT_BEARING_Y = 0, 1, 2
JOINT_JOURNAL_BODY, JOINT_JOURNAL_X, JOINT_JOURNAL_Y = 3, 4, 5
JOINT_CLEARANCE = 6        # c = R_b - R_j (m)
JOINT_BEARING_RADIUS = 7   # R_b (m)
JOINT_CHI = 8              # hysteresis factor chi of the damping law
JOINT_FRICTION_LAW = 9     # NO_FRICTION ... IWAN
JOINT_FRICTION = 10        # the law's parameters: FRICTION_PARAMETERS columns, named below
FRICTION_PARAMETERS = 7
JOINT_STATE = 17           # index in y of the joint's first friction state (-1: none)
JOINT_IMPACT = 18          # contact model: CONTINUOUS, NEWTON, POISSON
JOINT_RESTITUTION = 19     # e of the impulse models
JOINT_REST_SPEED = 20      # m/s: an impulse joint approaching slower is held in contact
# the calibrated damping law (damping_law = "calibrated"): chi against the impact speed v0,
# tabulated at CHI_POINTS speeds equally spaced in ln v0 from JOINT_CHI_LOG_SPEED by
# JOINT_CHI_STEP (0: no table, chi is JOINT_CHI), in JOINT_CHI_TABLE .. + CHI_POINTS - 1
JOINT_CHI_LOG_SPEED = 21
JOINT_CHI_STEP = 22
JOINT_CHI_TABLE = 23
CHI_POINTS = 33
JOINT_COLUMNS = JOINT_CHI_TABLE + CHI_POINTS

# friction laws (column JOINT_FRICTION_LAW) and their parameter columns
NO_FRICTION, COULOMB, STRIBECK, LINEAR, LUGRE, DAHL, IWAN = 0, 1, 2, 3, 4, 5, 6
COULOMB_MU = JOINT_FRICTION
STRIBECK_MU_STATIC, STRIBECK_MU_MIN, STRIBECK_V_MIN = (JOINT_FRICTION, JOINT_FRICTION + 1,
                                                      JOINT_FRICTION + 2)
LINEAR_MU_STATIC, LINEAR_ALPHA = JOINT_FRICTION, JOINT_FRICTION + 1
REGULARISATION_V0, REGULARISATION_V1 = JOINT_FRICTION + 5, JOINT_FRICTION + 6   # the static laws'
LUGRE_MU_COULOMB, LUGRE_MU_STATIC, LUGRE_STRIBECK_SPEED = (JOINT_FRICTION, JOINT_FRICTION + 1,
                                                           JOINT_FRICTION + 2)
LUGRE_SIGMA0, LUGRE_SIGMA1, LUGRE_SIGMA2 = JOINT_FRICTION + 3, JOINT_FRICTION + 4, JOINT_FRICTION + 5
DAHL_MU, DAHL_SIGMA = JOINT_FRICTION, JOINT_FRICTION + 1
IWAN_K1, IWAN_K2, IWAN_MU = JOINT_FRICTION, JOINT_FRICTION + 1, JOINT_FRICTION + 2
# the Iwan element's two states, from the joint's first: tangential travel, Jenkins stretch
STATE_TRAVEL, STATE_STRETCH = 0, 1

# contact models (column JOINT_IMPACT)
CONTINUOUS, NEWTON, POISSON = 0, 1, 2

# ---- ideal revolute joint (Model.revolute): r_i + A_i s_i = r_j + A_j s_j
REVOLUTE_BODY_I, REVOLUTE_X_I, REVOLUTE_Y_I = 0, 1, 2   # body (-1: ground, point global), s_i (m)
REVOLUTE_BODY_J, REVOLUTE_X_J, REVOLUTE_Y_J = 3, 4, 5
REVOLUTE_COLUMNS = 6

# ---- ideal prismatic joint (Model.prismatic): n.(r + A s - P) = 0 and phi = phi_0
PRISMATIC_BODY, PRISMATIC_X, PRISMATIC_Y = 0, 1, 2          # body, its point s (m)
PRISMATIC_AXIS_X, PRISMATIC_AXIS_Y, PRISMATIC_AXIS_ANGLE = 3, 4, 5   # P (m), axis angle (rad)
PRISMATIC_ANGLE = 6                                          # the body's fixed angle phi_0 (rad)
PRISMATIC_COLUMNS = 7

# ---- drive (Model.drive, one row): phi = phi_0 + omega t
DRIVE_BODY, DRIVE_SPEED, DRIVE_ANGLE = 0, 1, 2   # body (-1: no drive), omega (rad/s), phi_0 (rad)
DRIVE_COLUMNS = 3

# ---- torsion spring, stop or latch (Model.torsion)
TORSION_BODY_I, TORSION_BODY_J = 0, 1
TORSION_STIFFNESS, TORSION_DAMPING = 2, 3    # N m/rad, N m s/rad
TORSION_FREE_ANGLE = 4                       # rad, relative to the bodies' initial relative angle
TORSION_KIND = 5                             # SPRING, STOP, LATCH
TORSION_COLUMNS = 6
SPRING, STOP, LATCH = 0, 1, 2

# ---- the state vector after q and q': the energy integrals, then the friction states
DISSIPATED, WORK_IN = 0, 1
ENERGY_STATES = 2

# ---- impact log of the integrator: one row per impact or contact onset
LOG_TIME, LOG_JOINT, LOG_RATE, LOG_IMPULSE = 0, 1, 2, 3   # s, joint, approach rate m/s, N s
LOG_COLUMNS = 4

# ---- bundles
# The arguments of kernel.rhs and kernel.integrate (reduced.model.Model.kernel_args). speeds
# (impact speed per clearance joint), latched (flag per torsion element) and mode (1: an
# impulse joint held in contact) are updated in place by the integrator.
KernelArgs = namedtuple("KernelArgs", [
    "nq", "minv", "gravity_x", "gravity_y", "revolute", "prismatic", "drive", "baumgarte", "joints",
    "speeds", "grid_log0", "grid_step", "tables", "torsion", "latched", "mode"])

# The buffers of the right-hand side: Phi_q, Phi, Phi_t, rhs_c (gamma - 2 a Phi' - a^2 Phi,
# then the multipliers), the Schur matrix, the applied forces, and per clearance joint its
# normal force (the law's, or the multiplier of a held contact).
Workspace = namedtuple("Workspace", ["jac", "phi", "phi_t", "rhs_c", "schur", "force", "normal"])

# A torsion element's relative angle beyond its free angle (rad) and its rate (rad/s).
RelativeAngle = namedtuple("RelativeAngle", ["angle", "rate"])

# A clearance joint's penetration delta, normal n, contact point c, approach rate delta'
# and tangential slip.
Kinematics = namedtuple("Kinematics", ["delta", "nx", "ny", "cx", "cy", "rate", "slip"])

# A continuous clearance joint's forces: penetration, normal force, friction force (along
# the slip, acting against it), elastic force, power into damping and friction, normal,
# contact point, and the rates of its first and second friction states.
JointForces = namedtuple("JointForces", [
    "delta", "f_n", "f_t", "f_el", "power", "nx", "ny", "cx", "cy", "state_rate", "second_state_rate"])

# An impulse: normal impulse on the journal (N s), energy dissipated (J), work of the
# drive's impulse (J).
Impulse = namedtuple("Impulse", ["impulse", "dissipated", "work_in"])

# What the integrator tracks of the clearance joints between accepted steps: the penetration
# at the last accepted state, whether a continuous joint is in contact (between an onset and
# the next separation), and the normal force of a held contact and its peak.
Contacts = namedtuple("Contacts", ["depth", "in_contact", "held_force", "held_peak"])

# The accepted steps recorded by the integrator: time, state, impact speeds, contact modes,
# latch flags.
Record = namedtuple("Record", ["times", "states", "speeds", "modes", "latched"])

# What kernel.integrate returns: the record cut to the accepted steps, the impact log,
# counters (accepted, rejected, rhs calls, impacts), status code, time reached.
Integration = namedtuple("Integration", [
    "times", "states", "speeds", "modes", "latched", "impacts", "counters", "status", "t_end"])


def row(columns: int, values: dict) -> list:
    """A row of `columns` floats, zero but for `values` ({column: value})."""
    out = [0.0] * columns
    for column, value in values.items():
        out[column] = value
    return out
