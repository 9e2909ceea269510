r"""The worn joint of an FE scene (`geometry.wear_file`): a planar joint's bore and pin worn by
the depths of a wear.csv (laws.wearfile), in the scene's frame,

    bore:  r_b(theta) = R_b + h_b(theta - phi_b),      pin:  r_p(theta) = R_p - h_p(theta - phi_p),

R_b, R_p the geometry's radii, phi_b, phi_p its bore_frame_deg and pin_frame_deg, h the
profiles' Catmull-Rom splines (laws.wearfile.spline): the surfaces the mechanism's worn
joint runs on (cpp/mechanism/worn.h). Wear widens the clearance on both.

Mesh. Gmsh meshes the round joint of the base circles, the bore's least radius
R_b0 = R_b + min h_b and the pin's greatest R_p0 = R_p - min h_p, and its nodes are then
moved radially by the rest of the wear, e_b = r_b - R_b0 >= 0 and e_p = r_p - R_p0 <= 0,
tapered linearly to nothing across each body's wall (the housing's clamped edge and the
pin's hub stay where they are):

    housing:  r -> r + e_b(theta) (R_h - r) / (R_h - R_b0),
    pin:      r -> r + e_p(theta) (r - R_hub) / (R_p0 - R_hub),

a smooth one-to-one map of each annulus while the wear is shallower than the wall (its
radial stretch 1 - e / wall). Every surface node then lies exactly on its worn surface, the
curve that fem.contact.BoreSurface takes as the bore's reference, and a uniform wear is the
round joint of the wider clearance, mesh and all. Not a spline through the profile's points
in Gmsh: an OCC spline is not the profile's Catmull-Rom curve, so the nodes would lie off the
surface the contact and the mechanism take, by the two curves' difference.

Sizing. Where to refine is estimated as for a round joint (meshes.sizing), for two round
joints: that of the base circles, and the one that conforms as the worn joint does where
they first touch. A rigid pin moved along the load first meets the worn bore at the angle
alpha0 from the load, after the travel s0 (`touch`), and about there the gap of the pin moved
by s0 opens as c_loc (alpha - alpha0)^2 / 2, with

    c_loc = d^2/dalpha^2 [r_b - r_p](alpha0) + s0 cos(alpha0),

from the gap r_b - r_p - s cos(alpha) of surfaces whose clearance is small against their
radii (round surfaces: r_b - r_p = c, s0 = c, c_loc = c). The mesh takes the finer of the
two element sizes and the wider of the two arcs, widened by |alpha0|: a pin's imprint in the
bore (c_loc well below c) spreads the contact as its own clearance does, a rough profile
(c_loc far above c: bumps meet first) holds it on bumps that need the finer elements, while
the contact still spreads over the arc of the round joint. Used only to place elements.
"""

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from pinbore.core.errors import InputError
from pinbore.laws import wearfile
from pinbore.laws.elastic import Joint
from pinbore.meshes.model import Geometry, MeshOptions
from pinbore.meshes.sizing import Sizing, estimate_sizing

SAMPLES_PER_POINT = 8      # touch: the rigid pin's travel sampled this many times a profile interval
BISECTIONS = 80            # touch: halvings of each travel's bracket (to rounding)
LOCAL_FLOOR = 1e-3         # of the base clearance: the least local clearance the sizing takes
MAX_ARC = math.radians(170)   # the widest refined arc's half-angle (the circles are split at its ends)


@dataclass(frozen=True)
class WornJoint:
    """The profiles' points (m, the wear file's, evenly from -pi in each body's frame), the
    frames' angles in the scene's (rad) and the round joint's radii (m)."""

    bore_depth: np.ndarray
    pin_depth: np.ndarray
    bore_frame: float
    pin_frame: float
    bore_radius: float
    pin_radius: float

    @property
    def bore_base(self) -> float:
        """R_b0, the bore's least radius at the profile's points (m): the meshed circle."""
        return self.bore_radius + float(self.bore_depth.min())

    @property
    def pin_base(self) -> float:
        """R_p0, the pin's greatest radius at the profile's points (m): the meshed circle."""
        return self.pin_radius - float(self.pin_depth.min())

    def bore_excess(self, theta):
        """e_b = r_b - R_b0 at the scene's angles theta (rad), its slope and curvature (m,
        m/rad, m/rad^2)."""
        h, slope, curvature = wearfile.spline(self.bore_depth, np.asarray(theta) - self.bore_frame)
        return h - self.bore_depth.min(), slope, curvature

    def pin_excess(self, theta):
        """e_p = r_p - R_p0 <= 0 at the scene's angles theta (rad), its slope and curvature."""
        h, slope, curvature = wearfile.spline(self.pin_depth, np.asarray(theta) - self.pin_frame)
        return self.pin_depth.min() - h, -slope, -curvature

    def bore_surface(self, theta) -> np.ndarray:
        """r_b (m) at the scene's angles theta (rad)."""
        return self.bore_base + self.bore_excess(theta)[0]

    def pin_surface(self, theta) -> np.ndarray:
        """r_p (m) at the scene's angles theta (rad)."""
        return self.pin_base + self.pin_excess(theta)[0]

    def base_geometry(self, geometry: Geometry) -> Geometry:
        """The round joint of the base circles that Gmsh meshes (no wear of its own)."""
        return geometry.model_copy(update={"bore_radius": self.bore_base, "pin_radius": self.pin_base,
                                           "wear_file": None, "bore_frame_deg": None,
                                           "pin_frame_deg": None})

    def travel(self, points: np.ndarray, direction) -> np.ndarray:
        """How far (m) each point (n, 2), inside the worn bore, moves along the unit vector
        `direction` before it meets the bore: the root of r_b(angle(x + t d)) = |x + t d|
        bracketed from t = 0 to where |x + t d| passes the bore's greatest radius, halved
        BISECTIONS times (the first root, where the bore's radius varies slowly along the
        way, as it does in front of the load)."""
        d = np.asarray(direction, dtype=float)[:2]
        x = np.asarray(points, dtype=float)[:, :2]
        spread = float(self.bore_depth.max() - self.bore_depth.min())
        outer = self.bore_base + 2 * spread + 1e-9 * self.bore_radius   # beyond the spline's overshoot
        along = x @ d
        low = np.zeros(len(x))
        high = -along + np.sqrt(np.maximum(along**2 - np.sum(x**2, axis=1) + outer**2, 0.0))
        for _ in range(BISECTIONS):
            mid = 0.5 * (low + high)
            p = x + mid[:, None] * d
            inside = self.bore_surface(np.arctan2(p[:, 1], p[:, 0])) > np.hypot(p[:, 0], p[:, 1])
            low, high = np.where(inside, mid, low), np.where(inside, high, mid)
        return high

    def touch(self, direction_deg: float) -> tuple[float, float]:
        """(s0 (m), alpha0 (rad)): the rigid pin moved along the load direction first meets the
        worn bore after the travel s0, at its surface point alpha0 from the load: the least
        travel of the pin's surface points in front of the load, sampled SAMPLES_PER_POINT
        times a profile interval symmetrically about the load and refined by the parabola
        through the least sample and its neighbours (a round joint: s0 = c, alpha0 = 0)."""
        phi = math.radians(direction_deg)
        d = np.array([math.cos(phi), math.sin(phi)])
        half = SAMPLES_PER_POINT * max(self.bore_depth.size, self.pin_depth.size) // 4
        alpha = (math.pi / 2) * np.arange(-half + 1, half) / half

        def travels(a):
            r = self.pin_surface(phi + a)
            return self.travel(np.stack([r * np.cos(phi + a), r * np.sin(phi + a)], axis=1), d)

        t = travels(alpha)
        j = int(np.clip(np.argmin(t), 1, alpha.size - 2))
        curvature = t[j - 1] - 2 * t[j] + t[j + 1]
        if curvature > 0:
            best = alpha[j] + 0.5 * (alpha[1] - alpha[0]) * (t[j - 1] - t[j + 1]) / curvature
            refined = travels(np.array([best]))[0]
            if refined < t[j]:
                return float(refined), float(best)
        return float(t[j]), float(alpha[j])

    def local_clearance(self, direction_deg: float) -> tuple[float, float]:
        """(c_loc (m), alpha0 (rad)): the clearance of the round joint that conforms as this
        one where a rigid pin moved along the load first touches (module docstring), at
        least LOCAL_FLOOR of the base clearance."""
        travel, alpha = self.touch(direction_deg)
        theta = math.radians(direction_deg) + alpha
        local = (float(self.bore_excess(theta)[2]) - float(self.pin_excess(theta)[2])
                 + travel * math.cos(alpha))
        return max(local, LOCAL_FLOOR * (self.bore_base - self.pin_base)), alpha

    def local_joint(self, joint: Joint, direction_deg: float) -> tuple[Joint, float]:
        """(the round joint that conforms as this one where they first touch, alpha0 (rad)):
        `joint` (its materials) on the base circles, its clearance taken to c_loc (module
        docstring) by the bore's radius."""
        base = dataclasses.replace(joint, r_bore=self.bore_base, r_pin=self.pin_base)
        local, alpha = self.local_clearance(direction_deg)
        return dataclasses.replace(base, r_bore=base.r_bore - (base.clearance - local)), alpha

    def sizing(self, joint: Joint, direction_deg: float, max_approach: float,
               mesh: MeshOptions) -> Sizing:
        """Where to refine the worn joint's mesh (module docstring): the finer element size
        and the wider arc of the base circles' joint and of `local_joint`, the arc widened by
        |alpha0|."""
        local, alpha = self.local_joint(joint, direction_deg)
        base = dataclasses.replace(joint, r_bore=self.bore_base, r_pin=self.pin_base)
        sizings = [estimate_sizing(j, max_approach, mesh.contact_size, mesh.grading, mesh.refine)
                   for j in (base, local)]
        return dataclasses.replace(
            sizings[0], contact_size=min(s.contact_size for s in sizings),
            arc_half_angle=min(max(s.arc_half_angle for s in sizings) + abs(alpha), MAX_ARC))


def read(geometry: Geometry, path, source: str) -> WornJoint:
    """The worn joint of a geometry from its wear file at `path` (laws.wearfile.read, errors
    one line naming `source`), checked: no wear through the housing's wall or into the pin's
    hub."""
    profiles = wearfile.read(path, source)
    for name, depth, wall, what in (
            ("bore_depth_m", profiles.bore, geometry.housing_radius - geometry.bore_radius,
             "housing_radius - bore_radius, the housing's wall"),
            ("pin_depth_m", profiles.pin, geometry.pin_radius - geometry.hub_radius,
             "pin_radius - hub_radius, the pin's wall")):
        if depth.max() >= 0.5 * wall:
            raise InputError(f"{source}: {name}: the deepest wear, {depth.max():.3g} m, must be "
                             f"below half of {what} ({wall:.3g} m)")
    return WornJoint(profiles.bore, profiles.pin, math.radians(geometry.bore_frame_deg or 0.0),
                     math.radians(geometry.pin_frame_deg or 0.0), geometry.bore_radius,
                     geometry.pin_radius)
