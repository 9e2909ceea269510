// The contact laws the multibody engine evaluates in its right-hand side: friction (the
// laws of pinbore.laws.friction, with their sources there), the hysteresis damping of
// pinbore.laws.dissipative and the tabulated elastic law of pinbore.laws.tables. Each is the
// formula of its Python twin, operation by operation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>

namespace pinbore::laws
{

inline double sgn(double v) { return v > 0 ? 1.0 : -1.0; }

/// Coulomb [DenHartog1931]: F = mu F_N sgn v.
inline double coulomb(double v, double normal, double mu) { return mu * normal * sgn(v); }

/// Ambrosio's regularisation [Ambrosio2003]: 0 for |v| <= v0, linear up to v1, 1 above.
inline double ambrosio_factor(double v, double v0, double v1)
{
  const double speed = std::abs(v);
  return speed <= v0 ? 0.0 : (speed <= v1 ? (speed - v0) / (v1 - v0) : 1.0);
}

inline double ambrosio(double v, double normal, double mu, double v0, double v1)
{
  return coulomb(v, normal, mu * ambrosio_factor(v, v0, v1));
}

/// Stribeck polynomial [ThomsenFidlin2003], held at mu_m beyond v_m.
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

/// Dahl [Dahl1976] with alpha = 1: dF/dt = sigma (1 - (F / F_c) sgn v) v.
inline double dahl_rate(double force, double v, double sigma, double f_c)
{
  const double base = 1.0 - force / f_c * sgn(v);
  return sigma * std::pow(std::abs(base), 1.0) * std::copysign(1.0, base) * v;
}

/// LuGre [CanudasDeWit1995]: g(v) = F_c + (F_s - F_c) exp(-(v / v_s)^2).
inline double lugre_g(double v, double f_c, double f_s, double v_s)
{
  const double r = v / v_s;
  return f_c + (f_s - f_c) * std::exp(-(r * r));
}

inline double lugre_rate(double z, double v, double sigma0, double g)
{
  return v - sigma0 * std::abs(v) * z / g;
}

inline double lugre_force(double z, double z_rate, double v, double sigma0, double sigma1,
                          double sigma2)
{
  return sigma0 * z + sigma1 * z_rate + sigma2 * v;
}

/// Bilinear Iwan element [Iwan1966]: (F, x', z').
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

inline double iwan_return_map(double stretch, double k1, double f_cr)
{
  const double limit = f_cr / k1;
  return std::abs(stretch) > limit ? std::copysign(limit, stretch) : stretch;
}

/// F = max(F_el (1 + chi d' / v0), 0): the Hunt-Crossley family, never pulling.
inline double hysteresis_force(double elastic, double rate, double impact_speed, double chi)
{
  return std::max(elastic * (1.0 + chi * rate / impact_speed), 0.0);
}

/// f(delta) of a law tabulated as ln f on the grid ln delta_j = log0 + j step (log-log
/// interpolation; the first segment's power law below the grid; NaN above it or where the
/// table is NaN).
inline double table_force(double delta, double log0, double step, const double* table,
                          std::size_t size)
{
  const double x = (std::log(delta) - log0) / step;
  const long n = static_cast<long>(size);
  const long probe = std::min(std::max(static_cast<long>(x) + 1, 0L), n - 1);
  if (x > static_cast<double>(n - 1) or not std::isfinite(table[probe]))
    return std::nan("");
  const long i = std::min(std::max(static_cast<long>(std::floor(x)), 0L), n - 2);
  return std::exp(table[i] + (x - static_cast<double>(i)) * (table[i + 1] - table[i]));
}

} // namespace pinbore::laws

namespace pinbore::laws
{

/// (f, df/d delta) of a tabulated law at delta > 0 (table_force; NaN beyond the table).
struct ForceSlope
{
  double force, slope;
};

inline ForceSlope table_force_slope(double delta, double log0, double step, const double* table,
                                    std::size_t size)
{
  const double x = (std::log(delta) - log0) / step;
  const long n = static_cast<long>(size);
  const long probe = std::min(std::max(static_cast<long>(x) + 1, 0L), n - 1);
  if (x > static_cast<double>(n - 1) or not std::isfinite(table[probe]))
    return {std::nan(""), std::nan("")};
  const long i = std::min(std::max(static_cast<long>(std::floor(x)), 0L), n - 2);
  const double f = std::exp(table[i] + (x - static_cast<double>(i)) * (table[i + 1] - table[i]));
  return {f, (table[i + 1] - table[i]) / step * f / delta};
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
  const double approach = rho - s.clearance;
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

} // namespace pinbore::laws
