// The contact laws the multibody engine evaluates in its right-hand side: friction (the
// laws of pinbore.laws.friction, with their sources there), the hysteresis damping of
// pinbore.laws.dissipative and the tabulated elastic law of pinbore.laws.tables. Each is the
// formula of its Python twin, operation by operation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

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
