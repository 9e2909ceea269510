#include "plasticity.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace pinbore::plasticity
{

YieldPoint yield_stress(double p, const Curve& curve)
{
  std::int64_t k = curve.count - 1;
  while (k > 0 and p < curve.strains[k])
    --k;
  if (k == curve.count - 1)
    return {curve.stresses[k] + curve.tail * (p - curve.strains[k]), curve.tail,
            std::numeric_limits<double>::infinity()};
  const double slope = (curve.stresses[k + 1] - curve.stresses[k])
                       / (curve.strains[k + 1] - curve.strains[k]);
  return {curve.stresses[k] + slope * (p - curve.strains[k]), slope, curve.strains[k + 1]};
}

Curve Tables::curve(std::int64_t j) const
{
  return {strains.subspan(j * width, width), stresses.subspan(j * width, width), counts[j],
          tails[j]};
}

void radial_return(const Points& points, const Tables& tables, std::span<double> stress,
                   std::span<double> eps_p, std::span<double> p_new, std::span<double> tangent)
{
  const std::size_t n = points.equivalent.size();
  double s[6];
  for (std::size_t i = 0; i < n; ++i)
  {
    const double mu = points.shear_modulus[i], kappa = points.bulk_modulus[i];
    const double* strain = &points.strain[6 * i];
    const double* plastic = &points.plastic_strain[6 * i];
    double trace = 0.0;
    for (int a = 0; a < 3; ++a)
      trace += strain[a] - plastic[a];
    double norm2 = 0.0;
    for (int a = 0; a < 6; ++a)
    {
      s[a] = 2.0 * mu * (strain[a] - plastic[a] - (a < 3 ? trace / 3.0 : 0.0));
      norm2 += s[a] * s[a];
    }
    const double norm = std::sqrt(norm2);
    const double q = std::sqrt(1.5) * norm;
    double theta = 1.0, beta = 0.0; // the elastic branch: C = kappa I (x) I + 2 mu I_dev
    for (int a = 0; a < 6; ++a)
      eps_p[6 * i + a] = plastic[a];
    p_new[i] = points.equivalent[i];
    if (const std::int64_t j = points.curve[i]; j >= 0)
    {
      const Curve curve = tables.curve(j);
      double p = points.equivalent[i];
      YieldPoint y = yield_stress(p, curve);
      if (q > y.stress)
      {
        // segment by segment: q - 3 mu (p - p_n) = sigma_y(p); a segment at most once each
        // (the tables' strains increase), and the last one runs on without end
        bool returned = false;
        for (std::int64_t pass = 0; pass <= curve.count and not returned; ++pass)
        {
          const double step
              = (q - 3.0 * mu * (p - points.equivalent[i]) - y.stress) / (3.0 * mu + y.slope);
          if (p + step <= y.end)
          {
            p += step;
            returned = true;
          }
          else
          {
            p = y.end;
            y = yield_stress(p, curve);
          }
        }
        if (not returned)
          throw std::runtime_error("radial_return: the return did not end on a segment of its table");
        const double dp = p - points.equivalent[i];
        theta = 1.0 - 3.0 * mu * dp / q;
        beta = 3.0 * mu / (3.0 * mu + y.slope) - 1.0 + theta;
        for (int a = 0; a < 6; ++a)
          eps_p[6 * i + a] += 1.5 * dp * s[a] / q;
        p_new[i] = p;
      }
    }
#pragma GCC unroll 6
    for (int a = 0; a < 6; ++a)
    {
      stress[6 * i + a] = theta * s[a] + (a < 3 ? kappa * trace : 0.0);
#pragma GCC unroll 6
      for (int b = 0; b < 6; ++b)
      {
        double value
            = 2.0 * mu * theta * ((a == b ? 1.0 : 0.0) - (a < 3 and b < 3 ? 1.0 / 3.0 : 0.0));
        if (beta != 0.0)
          value -= 2.0 * mu * beta * s[a] * s[b] / norm2;
        if (a < 3 and b < 3)
          value += kappa;
        tangent[36 * i + 6 * a + b] = value;
      }
    }
  }
}

void elastic_energy(std::span<const double> stress, std::span<const double> shear_modulus,
                    std::span<const double> bulk_modulus, std::span<double> out)
{
  for (std::size_t i = 0; i < out.size(); ++i)
  {
    const double* sigma = &stress[6 * i];
    const double mean = (sigma[0] + sigma[1] + sigma[2]) / 3.0;
    double ss = 0.0;
    for (int a = 0; a < 6; ++a)
    {
      const double d = sigma[a] - (a < 3 ? mean : 0.0);
      ss += d * d;
    }
    out[i] = 0.5 * mean * mean / bulk_modulus[i] + ss / (4.0 * shear_modulus[i]);
  }
}

} // namespace pinbore::plasticity
