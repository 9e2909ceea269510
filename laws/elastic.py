"""Elastic normal laws for a pin (journal, radius R_j) inside a bore (bearing, radius R_i).

Notation: clearance c = R_i - R_j > 0, approach (penetration) d >= 0, composite modulus
1/E* = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j, R* = R_i R_j / c. P is a force per unit length
(N/m), F = P L a force (N) on a joint of axial length L. Every function takes arrays of d.

Sources are named in each docstring; "unverified" marks a form read from a secondary source
(Pereira et al. 2011's comparison [Pereira2011]) and not checked against the paper. Keys in
brackets are entries of REFERENCES.md.
"""

import math
import warnings
from dataclasses import dataclass

import numpy as np

_warned: set[str] = set()


def warn_once(law: str, message: str) -> None:
    """A validity warning, once per law and message in a process."""
    if (law, message) not in _warned:
        _warned.add((law, message))
        warnings.warn(f"{law}: {message}", stacklevel=3)


@dataclass(frozen=True)
class Joint:
    """Geometry (m) and materials (Pa) of a revolute clearance joint."""

    r_bore: float
    r_pin: float
    E_bore: float
    nu_bore: float
    E_pin: float
    nu_pin: float
    length: float  # m, axial length (used by the laws that need one)

    @property
    def clearance(self) -> float:
        return self.r_bore - self.r_pin

    @property
    def e_star(self) -> float:
        return 1.0 / (self.compliance_bore + self.compliance_pin)

    @property
    def compliance_bore(self) -> float:
        """sigma_i = (1 - nu_i^2) / E_i (1/Pa)."""
        return (1 - self.nu_bore**2) / self.E_bore

    @property
    def compliance_pin(self) -> float:
        return (1 - self.nu_pin**2) / self.E_pin

    @property
    def r_star(self) -> float:
        """R* = R_i R_j / (R_i - R_j) (m), the effective radius of internal contact."""
        return self.r_bore * self.r_pin / self.clearance


def hertz_point(d, joint: Joint):
    """Hertz point-contact form used for revolute joints, F = K d^1.5 (N).

    K = (4/3) E* sqrt(R*)  [LankaraniNikravesh1990], [FloresAmbrosio2004]. Written with
    h_k = (1 - nu_k^2)/(pi E_k) it reads K = 4/(3 pi (h_i + h_j)) sqrt(R*) ([Cao2013] eq. 3).
    A sphere law: it has no length; per unit length it is F / L.
    """
    return 4.0 / 3.0 * joint.e_star * math.sqrt(joint.r_star) * np.asarray(d, float) ** 1.5


def hertz_flat(d, radius: float, e_star: float):
    """Hertz, a sphere of radius R on a flat ([Johnson1985] sec. 4.2), F = (4/3) E* sqrt(R)
    d^1.5 (N): the point law of hertz_point with the bearing's radius infinite (R* = R). A
    slider's rounded corner on its guide's face (reduced.mechanism.joints.translational.corner_force)."""
    return 4.0 / 3.0 * e_star * math.sqrt(radius) * np.asarray(d, float) ** 1.5


def liu(d, joint: Joint):
    """Liu, Zhang & Yang 2007 [Liu2007], improved elastic foundation:

    P = (pi/2) E* d sqrt(d / (2 (c + d)))   (N/m).
    Limits: d << c gives P = (sqrt(2) pi / 4) E* c^-1/2 d^1.5; d >> c gives P = pi E* d / (2 sqrt 2).
    """
    d = np.asarray(d, float)
    return 0.5 * math.pi * joint.e_star * d * np.sqrt(d / (2 * (joint.clearance + d)))


def liu_stiffness(d, joint: Joint):
    """K = (pi/8) E* sqrt(2 d (3c + 2d)^2 / (c + d)^3)  (Pa): [Cao2013] eq. 10 (Bai & Zhao after
    Liu et al.). It is exactly dP/dd of `liu`, a tangent stiffness per unit length."""
    d = np.asarray(d, float)
    c = joint.clearance
    return math.pi / 8 * joint.e_star * np.sqrt(2 * d * (3 * c + 2 * d) ** 2 / (c + d) ** 3)


def bai_zhao(d, joint: Joint):
    """Bai & Zhao 2012 [BaiZhao2012], hybrid model, elastic part:

    P = K_L(d) d   (N/m),   K_L = [Cao2013] eq. 10 (`liu_stiffness`).
    As printed, F = K_L d^n with n = 1.5, whose units do not close (K_L is in Pa); n = 1 is
    the only exponent that does, and [Cao2013] writes the L-N framework F = K d^n with this
    K. K_L is Liu's tangent used as a secant: P exceeds Liu's force, by 50 % at d << c.
    """
    return liu_stiffness(d, joint) * np.asarray(d, float)


def _solve_increasing(approach, d, name):
    """P(d) for an implicit law d = approach(P) that rises to a largest approach and falls.

    Returns NaN (with a warning) where d exceeds the largest approach the law can give.
    """
    from scipy.optimize import brentq   # noqa: PLC0415 (scipy.optimize: a second to import)

    largest_p = brentq(lambda p: _slope(approach, p), *_slope_bracket(approach))
    largest_d = approach(largest_p)
    out = np.full(np.shape(d), np.nan)
    for i, di in np.ndenumerate(np.asarray(d, float)):
        if di <= 0:
            out[i] = 0.0
        elif di < largest_d:
            out[i] = brentq(lambda p: approach(p) - di, largest_p * 1e-18, largest_p, xtol=1e-300,
                            rtol=1e-13)
        else:
            warn_once(name, f"no force gives an approach above {largest_d:.3g} m (outside the "
                            "law's range: its log term turns negative)")
    return out


def _slope(approach, p, h=1e-7):
    return (approach(p * (1 + h)) - approach(p * (1 - h))) / (2 * h * p)


def _slope_bracket(approach):
    low = 1e-6
    high = low
    while _slope(approach, high) > 0:
        high *= 4
    return high / 4, high


def johnson(d, joint: Joint):
    """Johnson (Contact Mechanics, 1985), line contact of cylinders, solved for P (N/m):

    d = (P / pi) [sigma_i (2 ln(4 R_i / a) - 1) + sigma_j (2 ln(4 R_j / a) - 1)],
    a = sqrt(4 P R* / (pi E*)),  sigma_k = (1 - nu_k^2) / E_k.
    Equal materials: d = (P / (pi E*)) [ln(4 pi E* c / P) - 1]. d is defined between points
    far inside each body (at distances of order R), as the FE approach is.
    """
    si, sj = joint.compliance_bore, joint.compliance_pin

    def approach(p):
        a = math.sqrt(4 * p * joint.r_star / (math.pi * joint.e_star))
        return p / math.pi * (si * (2 * math.log(4 * joint.r_bore / a) - 1)
                              + sj * (2 * math.log(4 * joint.r_pin / a) - 1))

    return _solve_increasing(approach, d, "johnson")


def radzimovsky(d, joint: Joint):
    """Radzimovsky [Radzimovsky1953], as compared by [Pereira2011] (unverified), solved for P (N/m):

    d = (P / (pi E*)) [2/3 + ln(4 R_i / b) + ln(4 R_j / b)],  b = 1.6 sqrt(P R* / E*).
    """
    def approach(p):
        b = 1.6 * math.sqrt(p * joint.r_star / joint.e_star)
        return p / (math.pi * joint.e_star) * (2 / 3 + math.log(4 * joint.r_bore / b)
                                               + math.log(4 * joint.r_pin / b))

    return _solve_increasing(approach, d, "radzimovsky")


def dubowsky_freudenstein(d, joint: Joint):
    """Dubowsky & Freudenstein [DubowskyFreudenstein1971], as quoted by [Pereira2011] (unverified), for P (N/m):

    d = P (h_i + h_j) [ln(L^2 c / (P (h_i + h_j) R_i R_j)) + 1],  h_k = (1 - nu_k^2)/(pi E_k).
    Dimensionally consistent, but the approach depends on the joint length L.
    """
    h = (joint.compliance_bore + joint.compliance_pin) / math.pi

    def approach(p):
        return p * h * (math.log(joint.length**2 * joint.clearance
                                 / (p * h * joint.r_bore * joint.r_pin)) + 1)

    return _solve_increasing(approach, d, "dubowsky_freudenstein")


def esdu_78035(d, joint: Joint):
    """ESDU-78035 [ESDU78035], as quoted by [Pereira2011] (unverified), solved for P (N/m):

    d = P (h_i + h_j) [ln(4 c / (P (h_i + h_j))) - 1],  h_k = (1 - nu_k^2)/(pi E_k),
    i.e. Johnson's equal-material form with E* for any pair of materials.
    """
    h = (joint.compliance_bore + joint.compliance_pin) / math.pi

    def approach(p):
        return p * h * (math.log(4 * joint.clearance / (p * h)) - 1)

    return _solve_increasing(approach, d, "esdu_78035")


def pereira(d, joint: Joint):
    """Pereira, Ramalho & Ambrosio 2011 [Pereira2011], fitted to FE, internal
    contact (unverified): in mm, MPa and N,

    F = ((a c + b) / c) L E* d^n,  a = 0.965, b = 0.0965,  n = Y c^-0.005,
    Y = 1.51 [ln(1000 c)]^-0.151 for 0.005 <= c < 0.34954 mm,
    Y = 0.0151 c + 1.151        for 0.34954 <= c <= 10 mm.
    Returned per unit length in SI: P = F / L (N/m). Consistent form: with n != 1 the units
    close only through the length in which the fit was made, P = ((a c + b)/c) E* d^n l0^(1-n)
    with l0 = 1 mm; so unlike the other laws it does not scale with the joint's size.
    """
    c_mm = joint.clearance * 1e3
    if not 0.005 <= c_mm <= 10:
        warn_once("pereira", f"clearance {c_mm:g} mm outside the fitted range 0.005-10 mm")
        c_fit = min(max(c_mm, 0.005), 10.0)
    else:
        c_fit = c_mm
    y = 1.51 * math.log(1000 * c_fit) ** -0.151 if c_fit < 0.34954 else 0.0151 * c_fit + 1.151
    n = y * c_fit**-0.005
    force_per_mm = (0.965 * c_mm + 0.0965) / c_mm * (joint.e_star * 1e-6) * (np.asarray(d, float) * 1e3) ** n
    return force_per_mm * 1e3  # N per mm of length -> N/m


def linear(d, stiffness):
    """Linear spring (the elastic part of Kelvin-Voigt): P = k d, k (Pa) a free parameter."""
    return stiffness * np.asarray(d, float)


def persson_load(b):
    """Persson 1964 / Ciavarella & Decuzzi 2001 [Persson1964], [CiavarellaDecuzzi2001]: conformal
    contact of elastically similar pin and infinite plate, plane strain,

    P / (E* c) = 2 pi b^2 (1 + b^2) / (2 - ln(1 + b^2) - 2 b^4),  b = tan(eps / 2),
    eps the contact half-angle; the load is unbounded as eps -> 84.83 deg (b = 0.913572).
    Small eps: P = pi E* c eps^2 / 4 (Hertz line contact).
    """
    b2 = np.asarray(b, float) ** 2
    return 2 * np.pi * b2 * (1 + b2) / (2 - np.log1p(b2) - 2 * b2 * b2)


PERSSON_LIMIT_B = 0.913572


def persson_force(eps, joint: Joint):
    """Force per length (N/m) that opens a contact of half-angle eps (rad): `persson_load`."""
    return persson_load(np.tan(np.asarray(eps, float) / 2)) * joint.e_star * joint.clearance


def persson_half_angle(load: float) -> float:
    """Contact half-angle eps (rad) for the dimensionless load P / (E* c) >= 0."""
    from scipy.optimize import brentq   # noqa: PLC0415 (scipy.optimize: a second to import)

    if load <= 0:
        return 0.0
    b = brentq(lambda b: persson_load(b) - load, 0.0, PERSSON_LIMIT_B * (1 - 1e-12))
    return 2 * math.atan(b)


def persson_half_angles(forces, joint: Joint) -> np.ndarray:
    """Persson contact half-angles (rad) at the forces per length `forces` (N/m)."""
    scale = joint.e_star * joint.clearance
    return np.array([persson_half_angle(p / scale) for p in np.atleast_1d(forces)])


def hertz_per_length(d, joint: Joint):
    """The Hertz point form spread over the joint's length: P = K d^1.5 / L (N/m)."""
    return hertz_point(d, joint) / joint.length


def calibrated(d, published, scale, exponent_correction, reference_approach):
    """A law calibrated on FE curves (`pinbore calibrate`, calibration/fit.py), P (N/m):

    P(d) = s P_law(d) (d / d_ref)^q,
    P_law(d) = `published`, the law's force per length at the same approaches d (N/m);
    s = `scale` and q = `exponent_correction` fitted by least squares on ln(P_FE / P_law)
    about d_ref = `reference_approach` (m), the geometric mean of the fitted approaches.
    For a power law K d^n this refits K and n; q = 0 keeps the law's own shape.
    """
    d = np.asarray(d, float)
    return scale * published * (d / reference_approach) ** exponent_correction


# The laws that predict a force per unit length from geometry and materials alone.
PUBLISHED = {"hertz": hertz_per_length, "johnson": johnson, "liu": liu, "bai_zhao": bai_zhao,
             "pereira": pereira, "radzimovsky": radzimovsky,
             "dubowsky_freudenstein": dubowsky_freudenstein, "esdu_78035": esdu_78035}


def hertz_line_subsurface(x, z, a, p0):
    r"""Stresses (Pa) under a Hertzian line contact of half-width a (m) and peak pressure p0
    (Pa) in an elastic half-space, at the lateral position x and the depth z >= 0 (m)
    ([Johnson1985] §4.2, eqs 4.49-4.50, after McEwen):

        sigma_x = -(p0/a) [m (1 + (z^2 + n^2)/(m^2 + n^2)) - 2 z],
        sigma_z = -(p0/a) m (1 - (z^2 + n^2)/(m^2 + n^2)),
        tau_xz  =  (p0/a) n (m^2 - z^2)/(m^2 + n^2),

    m^2, n^2 = ([(a^2 - x^2 + z^2)^2 + 4 x^2 z^2]^(1/2) +- (a^2 - x^2 + z^2)) / 2, m >= 0, n
    with the sign of x. On the axis x = 0: sigma_x = -p0 [(1 + 2 z^2/a^2)/sqrt(1 + z^2/a^2)
    - 2 z/a], sigma_z = -p0 / sqrt(1 + z^2/a^2). Returns (sigma_x, sigma_z, tau_xz).
    The axis forms and the surface z = 0 (sigma_z = -p(x), tau_xz = 0) are checked
    (tests/test_laws.py); the off-axis field was written from the general form, not checked
    against the printed page: off the axis, unverified."""
    x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
    A = a * a - x * x + z * z
    S = np.sqrt(A * A + 4 * x * x * z * z)
    m = np.sqrt(0.5 * (S + A))
    n = np.sign(x) * np.sqrt(np.maximum(0.5 * (S - A), 0.0))
    q = (z * z + n * n) / (m * m + n * n)
    return (-(p0 / a) * (m * (1 + q) - 2 * z), -(p0 / a) * m * (1 - q),
            (p0 / a) * n * (m * m - z * z) / (m * m + n * n))


def hertz_line_von_mises(x, z, a, p0, nu):
    """Von Mises stress (Pa) of hertz_line_subsurface in plane strain, sigma_y = nu (sigma_x +
    sigma_z). Its largest value is on the axis, 0.5575 p0 at z = 0.704 a for nu = 0.3, that
    is first yield at p0 = 1.794 Y ([Johnson1985] §6.2 rounds it to 1.79 Y = 3.1 k)."""
    sx, sz, t = hertz_line_subsurface(x, z, a, p0)
    sy = nu * (sx + sz)
    return np.sqrt(0.5 * ((sx - sy) ** 2 + (sy - sz) ** 2 + (sz - sx) ** 2) + 3 * t * t)
