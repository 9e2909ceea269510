// Von Mises plasticity with isotropic hardening at the quadrature points of the FE bodies:
// the radial return with its consistent tangent, and the elastic energy density
// (pinbore.fem.plasticity states the equations; [SimoHughes1998] Box 3.2).
// Tensors are 6 Mandel components (xx, yy, zz, sqrt2 xy, sqrt2 yz, sqrt2 xz).
#pragma once

#include <cstdint>
#include <span>

namespace pinbore::plasticity
{

/// A piecewise linear hardening curve sigma_y(p): through (strains[k], stresses[k]),
/// k < count (strains[0] = 0), continued beyond its last point with slope `tail`.
struct Curve
{
  std::span<const double> strains;
  std::span<const double> stresses;
  std::int64_t count;
  double tail;
};

/// sigma_y at p (Pa), its slope H (Pa) and the plastic strain where the segment holding p
/// ends (inf on the last one).
struct YieldPoint
{
  double stress;
  double slope;
  double end;
};

YieldPoint yield_stress(double p, const Curve& curve);

/// The hardening curves of a body's materials: row j of the padded tables (width columns),
/// its count of points and its tail slope.
struct Tables
{
  std::span<const double> strains;
  std::span<const double> stresses;
  std::size_t width;
  std::span<const std::int64_t> counts;
  std::span<const double> tails;

  Curve curve(std::int64_t j) const;
};

/// The material at n points: the state returned from (total strain of the iterate, the
/// converged plastic strain, (n, 6); the converged equivalent plastic strain p, (n,)), the
/// moduli mu and kappa (Pa, (n,)) and each point's hardening curve (a row of `tables`; -1:
/// never yields).
struct Points
{
  std::span<const double> strain;
  std::span<const double> plastic_strain;
  std::span<const double> equivalent;
  std::span<const double> shear_modulus;
  std::span<const double> bulk_modulus;
  std::span<const std::int64_t> curve;
};

/// The radial return at every point into stress (n, 6) (Pa), eps_p (n, 6), p (n,) and the
/// consistent tangent d sigma / d eps (n, 6, 6) (Pa).
void radial_return(const Points& points, const Tables& tables, std::span<double> stress,
                   std::span<double> eps_p, std::span<double> p, std::span<double> tangent);

/// sigma : C^-1 : sigma / 2 (J/m^3) of stresses (n, 6) into out (n,).
void elastic_energy(std::span<const double> stress, std::span<const double> shear_modulus,
                    std::span<const double> bulk_modulus, std::span<double> out);

} // namespace pinbore::plasticity
