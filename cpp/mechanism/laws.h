// The contact laws, one function each, the very functions the multibody engine evaluates in
// its right-hand side and pinbore.laws, the calibration and pinbore export call (bound as
// pinbore.core.cpp.laws): friction, the hysteresis damping, the tabulated elastic law, the
// bore's edge relief and the sliced joint law. v is the slip velocity (m/s); a friction law
// gives F along the slip (the sliding body feels -F) or the coefficient mu that Ambrosio's
// regularised Coulomb force turns into F; a state law gives its state's rate.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

namespace pinbore::laws
{

/// sgn v = 1 for v > 0, -1 otherwise (at v = 0 the regularised laws vanish).
inline double sgn(double v) { return v > 0 ? 1.0 : -1.0; }

/// Coulomb [DenHartog1931] ([Cao2013] eq. 12): F = mu F_N sgn v.
inline double coulomb(double v, double normal, double mu) { return mu * normal * sgn(v); }

/// Ambrosio's regularisation [Ambrosio2003]: c_d = 0 for |v| <= v0, (|v| - v0)/(v1 - v0) up
/// to v1, 1 above.
inline double ambrosio_factor(double v, double v0, double v1)
{
  const double speed = std::abs(v);
  return speed <= v0 ? 0.0 : (speed <= v1 ? (speed - v0) / (v1 - v0) : 1.0);
}

/// Ambrosio's regularised Coulomb force [Ambrosio2003]: F = mu c_d(|v|) F_N sgn v, continuous
/// at v = 0 (mu may depend on the slip: stribeck_polynomial, linear_velocity).
inline double ambrosio(double v, double normal, double mu, double v0, double v1)
{
  return coulomb(v, normal, mu * ambrosio_factor(v, v0, v1));
}

/// Stribeck polynomial [ThomsenFidlin2003] ([Cao2013] eq. 14): mu(|v|) = mu_s - k1 |v| +
/// k3 |v|^3, k1 = 1.5 (mu_s - mu_m)/v_m, k3 = 0.5 (mu_s - mu_m)/v_m^3: mu_s at v -> 0, its
/// minimum mu_m at |v| = v_m with zero slope; held at mu_m for |v| >= v_m (the polynomial
/// rises again beyond, which is no friction law), C1 there.
inline double stribeck_polynomial(double v, double mu_s, double mu_m, double v_m)
{
  const double speed = std::abs(v);
  if (speed >= v_m)
    return mu_m;
  const double k = mu_s - mu_m;
  return mu_s - 1.5 * k / v_m * speed + 0.5 * k / (v_m * (v_m * v_m)) * (speed * (speed * speed));
}

/// [Cao2013] eq. 15: mu = mu_s + alpha |v|.
inline double linear_velocity(double v, double mu_s, double alpha) { return mu_s + alpha * std::abs(v); }

/// Dahl [Dahl1976] ([Cao2013] eq. 16): dF/dt = sigma |b|^alpha sgn(b) v, b = 1 - (F / F_c)
/// sgn v (Dahl's symmetric form where |F| > F_c); divided by the normal force it is the rate
/// of m = F / F_N.
inline double dahl_rate(double force, double v, double sigma, double f_c, double alpha = 1.0)
{
  const double base = 1.0 - force / f_c * sgn(v);
  return sigma * std::pow(std::abs(base), alpha) * std::copysign(1.0, base) * v;
}

/// LuGre [CanudasDeWit1995] ([Cao2013] eq. 18): g(v) = F_c + (F_s - F_c) exp(-(v / v_s)^2),
/// force units (normalised by the normal force, F_c and F_s are coefficients).
inline double lugre_g(double v, double f_c, double f_s, double v_s)
{
  const double r = v / v_s;
  return f_c + (f_s - f_c) * std::exp(-(r * r));
}

/// LuGre bristle state ([Cao2013] eq. 17): dz/dt = v - sigma0 |v| z / g(v).
inline double lugre_rate(double z, double v, double sigma0, double g)
{
  return v - sigma0 * std::abs(v) * z / g;
}

/// LuGre friction force [CanudasDeWit1995]: F = sigma0 z + sigma1 dz/dt + sigma2 v (steady
/// sliding: g(v) sgn v + sigma2 v).
inline double lugre_force(double z, double z_rate, double v, double sigma0, double sigma1,
                          double sigma2)
{
  return sigma0 * z + sigma1 * z_rate + sigma2 * v;
}

/// Bilinear Iwan element [Iwan1966] ([Cao2013] eq. 13): a Jenkins element (spring k1 in series
/// with a Coulomb slider of strength F_cr) beside a spring k2; states the travel x and the
/// Jenkins spring's stretch z: F = k1 z + k2 x, x' = v, z' = v while the slider sticks and 0
/// while it slides (|k1 z| = F_cr, z v > 0). (F, x', z').
struct Iwan
{
  double force, travel_rate, stretch_rate;
};

inline Iwan iwan_bilinear(double travel, double stretch, double v, double k1, double k2,
                          double f_cr)
{
  const double limit = f_cr / k1;
  const double z = std::min(std::max(stretch, -limit), limit);
  const bool sliding = std::abs(stretch) >= limit and stretch * v > 0;
  return {k1 * z + k2 * travel, v, sliding ? 0.0 : v};
}

/// The Iwan slider after a step: a stretch beyond |k1 z| = F_cr is the slider moving, so z
/// returns to the limit (return mapping).
inline double iwan_return_map(double stretch, double k1, double f_cr)
{
  const double limit = f_cr / k1;
  return std::abs(stretch) > limit ? std::copysign(limit, stretch) : stretch;
}

/// F = max(F_el (1 + chi d' / v0), 0): the Hunt-Crossley family [HuntCrossley1975] (N, or
/// N/m with F_el per length), never pulling (the bracket turns negative when the bodies
/// separate faster than v0 / chi).
inline double hysteresis_force(double elastic, double rate, double impact_speed, double chi)
{
  return std::max(elastic * (1.0 + chi * rate / impact_speed), 0.0);
}


/// (f, df/d delta) of a law tabulated as ln f on the grid ln delta_j = log0 + j step at
/// delta > 0: log-log interpolation, the first segment's power law below the grid, NaN above
/// it or where the table is NaN; on a segment f = f_i (delta/delta_i)^s, s = (table_i+1 -
/// table_i) / step, so df/d delta = s f / delta.
struct ForceSlope
{
  double force, slope;
};

inline ForceSlope table_force_slope(double delta, double log0, double step, const double* table,
                                    std::size_t size)
{
  const double x = (std::log(delta) - log0) / step;
  if (std::isnan(x))
    return {std::nan(""), std::nan("")};
  const long n = static_cast<long>(size);
  const double below = std::max(x, -1.0);   // every x <= -1 takes the first segment (no cast of -inf)
  const long probe = std::min(std::max(static_cast<long>(std::min(below, static_cast<double>(n))) + 1, 0L), n - 1);
  if (x > static_cast<double>(n - 1) or not std::isfinite(table[probe]))
    return {std::nan(""), std::nan("")};
  const long i = std::min(std::max(static_cast<long>(std::floor(below)), 0L), n - 2);
  const double f = std::exp(table[i] + (x - static_cast<double>(i)) * (table[i + 1] - table[i]));
  return {f, (table[i + 1] - table[i]) / step * f / delta};
}

/// f(delta) of a law tabulated as ln f on the grid ln delta_j = log0 + j step (log-log
/// interpolation; the first segment's power law below the grid; NaN above it or where the
/// table is NaN): table_force_slope's force.
inline double table_force(double delta, double log0, double step, const double* table,
                          std::size_t size)
{
  return table_force_slope(delta, log0, step, table, size).force;
}

// ---- the edge relief of a bore (pinbore.laws.relief states the geometry): over `length`
// from each end the radius grows along a circular arc tangent to the cylinder, to `depth` at
// the end face, r(x) = R - sqrt(R^2 - x^2), R = (l^2 + d^2) / (2 d)
struct Relief
{
  double radius, slope, curvature;
};

/// Extra radius (m), its slope (-) and curvature (1/m) at z of a bore over [z_low, z_high].
inline Relief relief_at(double z, double z_low, double z_high, double length, double depth)
{
  const double r = (length * length + depth * depth) / (2 * depth);
  const double into = std::min(std::max(length - std::min(z - z_low, z_high - z), 0.0), length);
  const double side = z - z_low < z_high - z ? -1.0 : 1.0;
  const double root = std::sqrt(r * r - into * into);
  return {r - root, side * into / root, into > 0 ? r * r / (root * (root * root)) : 0.0};
}

// ---- the sliced cylindrical-joint law (pinbore.laws.sliced states it: slices of a bore,
// the section in 2D, the bore's uniform displacement under its bulk compliance)
struct SliceGeometry
{
  double offset, width, weight;
};

/// Slice i of `slices` over a bore of `length`: its offset from the mid-plane, its width
/// L/n and its weight L/n + end_length at each end slice (m).
inline SliceGeometry slice_geometry(long i, double length, long slices, double end_length)
{
  const double width = length / static_cast<double>(slices);
  const double offset = (static_cast<double>(i) + 0.5 - 0.5 * static_cast<double>(slices)) * width;
  return {offset, width,
          width + end_length * static_cast<double>(static_cast<int>(i == 0) + static_cast<int>(i == slices - 1))};
}

/// A bore's section and its law's table: the journal's axis at P_i = a + z'_i b against the
/// bore moved by d (m), the clearance, planar (the in-plane case), the slicing and the table.
struct Section
{
  double ax, ay, bx, by, clearance;
  bool planar;
  double length;
  long slices;
  double log0, step;
  const double* table;
  std::size_t size;
  double relief_length = 0.0, relief_depth = 0.0;
};

struct SliceContact
{
  double offset, approach, nx, ny, curvature, force, slope;
};

/// Slice i at the bore displacement (dx, dy): its offset, approach, normal, the curvature
/// 1/|P_i - d| across it, the local per-length force and its slope (0 when open).
inline SliceContact slice_contact(long i, double dx, double dy, const Section& s)
{
  const double offset = slice_geometry(i, s.length, s.slices, 0.0).offset;
  const double px = s.ax + s.bx * offset - dx, py = s.ay + s.by * offset - dy;
  double rho, nx, ny, curvature;
  if (s.planar)
    rho = px, nx = 1.0, ny = 0.0, curvature = 0.0;
  else
  {
    rho = std::sqrt(px * px + py * py);
    if (rho > 0.0)
      nx = px / rho, ny = py / rho, curvature = 1.0 / rho;
    else
      nx = 1.0, ny = 0.0, curvature = 0.0;
  }
  double approach = rho - s.clearance;
  if (s.relief_length > 0.0 and s.relief_depth > 0.0)
    approach -= relief_at(0.5 * s.length + offset, 0.0, s.length, s.relief_length, s.relief_depth).radius;
  if (approach <= 0.0)
    return {offset, approach, nx, ny, curvature, 0.0, 0.0};
  const ForceSlope fs = table_force_slope(approach, s.log0, s.step, s.table, s.size);
  return {offset, approach, nx, ny, curvature, fs.force, fs.slope};
}

struct SectionSums
{
  double fx, fy, mx, my, kxx, kxy, kyy, contact;
};

/// The slices' resultants and stiffness -dF/dd at the bore displacement (dx, dy).
inline SectionSums section_sums(double dx, double dy, const Section& s, double end_length,
                                double scale)
{
  SectionSums r{0, 0, 0, 0, 0, 0, 0, 0};
  for (long i = 0; i < s.slices; ++i)
  {
    const SliceContact c = slice_contact(i, dx, dy, s);
    if (c.approach <= 0.0)
      continue;
    const SliceGeometry g = slice_geometry(i, s.length, s.slices, end_length);
    const double weight = g.weight * scale;
    const double f = c.force;
    r.fx += f * weight * c.nx;
    r.fy += f * weight * c.ny;
    r.mx += f * c.offset * weight * c.nx;
    r.my += f * c.offset * weight * c.ny;
    const double across = f * c.curvature;
    r.kxx += weight * (c.slope * c.nx * c.nx + across * (1.0 - c.nx * c.nx));
    r.kxy += weight * (c.slope - across) * c.nx * c.ny;
    r.kyy += weight * (c.slope * c.ny * c.ny + across * (1.0 - c.ny * c.ny));
    r.contact += g.width;
  }
  return r;
}

/// The bore's uniform displacement d under its bulk compliance (m^2/N): the root of
/// d - compliance F(d) / L by Newton's method, an overshooting step cut back by regula falsi
/// (Illinois) on g(d + t s) . s; NaN when F is NaN.
inline std::pair<double, double> bore_displacement(const Section& s, double end_length,
                                                   double scale, double compliance)
{
  const double nan = std::nan("");
  if (compliance == 0.0)
    return {0.0, 0.0};
  const double c = compliance / s.length;
  const double size = std::sqrt(s.ax * s.ax + s.ay * s.ay)
                      + 0.5 * s.length * std::sqrt(s.bx * s.bx + s.by * s.by);
  double dx = 0.0, dy = 0.0;
  SectionSums r = section_sums(dx, dy, s, end_length, scale);
  if (not(std::isfinite(r.fx) and std::isfinite(r.fy)))
    return {nan, nan};
  if (r.fx == 0.0 and r.fy == 0.0)
    return {0.0, 0.0};
  const double tolerance = 1e-12 * (size + c * std::sqrt(r.fx * r.fx + r.fy * r.fy));
  double gx = -c * r.fx, gy = -c * r.fy;
  for (int iteration = 0; iteration < 100; ++iteration)
  {
    const double jxx = 1.0 + c * r.kxx, jxy = c * r.kxy, jyy = 1.0 + c * r.kyy;
    const double det = jxx * jyy - jxy * jxy;
    const double sx = -(jyy * gx - jxy * gy) / det, sy = -(jxx * gy - jxy * gx) / det;
    if (std::sqrt(sx * sx + sy * sy) <= tolerance)
      return {dx + sx, dy + sy};
    double low = 0.0, slope_low = gx * sx + gy * sy;
    double high = 1.0, slope_high = 0.0;
    double t = 1.0;
    int side = 0;
    for (int search = 0; search < 60; ++search)
    {
      r = section_sums(dx + t * sx, dy + t * sy, s, end_length, scale);
      if (not(std::isfinite(r.fx) and std::isfinite(r.fy)))
        return {nan, nan};
      gx = dx + t * sx - c * r.fx;
      gy = dy + t * sy - c * r.fy;
      const double slope = gx * sx + gy * sy;
      if (slope <= 0.0 and search == 0)
        break;
      if (slope > 0.0)
      {
        high = t, slope_high = slope;
        if (side > 0)
          slope_low *= 0.5;
        side = 1;
      }
      else
      {
        low = t, slope_low = slope;
        if (side < 0)
          slope_high *= 0.5;
        side = -1;
      }
      if ((high - low) * std::sqrt(sx * sx + sy * sy) <= tolerance or slope == 0.0 or search == 59)
        break;
      t = (low * slope_high - high * slope_low) / (slope_high - slope_low);
    }
    dx = dx + t * sx;
    dy = dy + t * sy;
  }
  return {dx, dy};
}


/// The approach delta - compliance F / L the slices share once the bore has moved by its
/// bulk compliance (the in-plane case of bore_displacement); NaN when F is NaN.
inline double shared_approach(double delta, double theta, const Section& plane, double end_length,
                              double scale, double compliance)
{
  Section s = plane;
  s.ax = delta, s.ay = 0.0, s.bx = theta, s.by = 0.0, s.clearance = 0.0, s.planar = true;
  return delta - bore_displacement(s, end_length, scale, compliance).first;
}

struct Sliced
{
  double force, moment, resultant, contact;
};

/// (F (N), M (N m), z_F (m), contact length (m)) of a pin approached by delta and tilted by
/// theta in its bore, the slices of the local law with the bulk compliance (pinbore.laws.sliced).
inline Sliced sliced(double delta, double theta, const Section& plane, double end_length,
                     double scale, double compliance)
{
  Section s = plane;
  s.ax = delta, s.ay = 0.0, s.bx = theta, s.by = 0.0, s.clearance = 0.0, s.planar = true;
  const double shift = bore_displacement(s, end_length, scale, compliance).first;
  if (not std::isfinite(shift))
    return {std::nan(""), std::nan(""), std::nan(""), std::nan("")};
  const SectionSums r = section_sums(shift, 0.0, s, end_length, scale);
  const double resultant = r.fx != 0.0 ? 0.5 * s.length + r.mx / r.fx : std::nan("");
  return {r.fx, r.mx, resultant, r.contact};
}

} // namespace pinbore::laws
