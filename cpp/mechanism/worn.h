// A worn journal in its bore (the plane): the profiles' interpolation, their bounds, and the
// search for the angle where the worn surfaces interfere most (engine.h: worn_radial).
//
// A profile is a row of Args::wear: the worn depth h (m) at n angles of its body's frame
// evenly from -pi, periodic, interpolated by the uniform Catmull-Rom spline through its
// points (C1; piecewise cubic, so h'' is linear on each piece and |h''| <= its largest end
// value). The contact's interference
//
//     f(phi) = e . u(phi) - h_bore(phi - phi_b) - h_pin(phi - phi_j)
//
// has |f''| <= |e| + max|h_bore''| + max|h_pin''| = M everywhere, so on an interval [a, b]
// f stays below its chord plus M (x - a)(b - x) / 2; and f <= |e| cos(phi - phi_e) - h_low
// with h_low the least the two depths can sum to. The search (worn_maximum) is a branch and
// bound on those two bounds: the global maximum to a set tolerance, whatever the profiles'
// roughness, found where it moves continuously with the bodies.
#pragma once

#include "data.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace pinbore::mechanism
{

/// A profile (row r of wear) at the angle a: its depth, slope and curvature.
inline std::array<double, 3> worn_depth(const Rows& wear, std::ptrdiff_t r, double a)
{
  const std::ptrdiff_t n = wear.cols;
  const double step = 2.0 * std::numbers::pi / static_cast<double>(n);
  double x = (a + std::numbers::pi) / step;
  x -= static_cast<double>(n) * std::floor(x / static_cast<double>(n));
  auto i = static_cast<std::ptrdiff_t>(x);
  if (i >= n)
    i = n - 1;
  const double t = x - static_cast<double>(i);
  auto at = [&](std::ptrdiff_t j) { return wear(r, ((j % n) + n) % n); };
  const double p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
  const double c1 = -p0 + p2, c2 = 2 * p0 - 5 * p1 + 4 * p2 - p3, c3 = -p0 + 3 * p1 - 3 * p2 + p3;
  return {0.5 * (2 * p1 + t * (c1 + t * (c2 + t * c3))),
          0.5 * (c1 + t * (2 * c2 + 3 * t * c3)) / step,
          0.5 * (2 * c2 + 6 * t * c3) / (step * step)};
}

/// Per profile (WornBound): the largest |h''| of its spline, and a depth it never falls
/// below (its least point less the most a piece can sag between its points, M step^2 / 8).
inline std::vector<WornBound> worn_bounds(const Rows& wear)
{
  std::vector<WornBound> out(static_cast<std::size_t>(wear.rows));
  const std::ptrdiff_t n = wear.cols;
  if (n < 3)
    return out;
  const double step = 2.0 * std::numbers::pi / static_cast<double>(n);
  for (std::ptrdiff_t r = 0; r < wear.rows; ++r)
  {
    auto at = [&](std::ptrdiff_t j) { return wear(r, ((j % n) + n) % n); };
    double curvature = 0.0, lowest = std::numeric_limits<double>::infinity();
    for (std::ptrdiff_t i = 0; i < n; ++i)
    {
      const double p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
      const double c2 = 2 * p0 - 5 * p1 + 4 * p2 - p3, c3 = -p0 + 3 * p1 - 3 * p2 + p3;
      curvature = std::max({curvature, std::abs(c2), std::abs(c2 + 3 * c3)});
      lowest = std::min(lowest, p1);
    }
    curvature /= step * step;
    out[static_cast<std::size_t>(r)] = {curvature, lowest - curvature * step * step / 8.0};
  }
  return out;
}

/// The most a function can reach on [a, b] (width w) given its ends' values fa, fb and
/// |f''| <= m: the maximum of its chord plus m (x - a)(b - x) / 2.
inline double chord_bound(double fa, double fb, double w, double m)
{
  const double sag = m * w * w;
  if (sag <= 0.0)
    return std::max(fa, fb);
  const double t = std::clamp(0.5 + (fb - fa) / sag, 0.0, 1.0);
  return fa + (fb - fa) * t + 0.5 * sag * t * (1.0 - t);
}

/// The maximum over the circle of f (f(phi, slope, curvature) returns f and sets f', f''),
/// given |f''| <= m,
/// f <= size cos(phi - centre) - lowest, to within tol: samples at spacing step outward
/// from centre while the cosine bound can beat the best, then each interval between them
/// bisected while its chord bound exceeds the best by more than tol; the best point
/// polished by Newton's method safeguarded by bisection where f' brackets a maximum in the
/// last interval about it (to 1e-14 rad: f' = 0 there, which the contact's torques need).
template <class F>
double worn_maximum(F& f, double centre, double size, double lowest, double m, double step,
                    double tol)
{
  struct Point
  {
    double x, value;
  };
  thread_local std::vector<Point> samples;
  thread_local std::vector<std::array<Point, 2>> pending;
  samples.clear();
  pending.clear();
  if (not (std::isfinite(size) and std::isfinite(m)))
    return centre;   // a state not finite (an integrator's trial): its value is NaN
  double slope, curvature;
  Point top{centre, f(centre, slope, curvature)};   // the best point so far
  samples.push_back(top);
  const auto half = static_cast<std::ptrdiff_t>(std::ceil(std::numbers::pi / step));
  // one side then the other; the last sample of each side bounds the rest below the best
  std::ptrdiff_t right = 0;
  for (int side : {1, -1})
  {
    for (std::ptrdiff_t i = 1; i <= half; ++i)
    {
      const double da = static_cast<double>(i) * step;
      const double x = centre + side * da;
      samples.push_back({x, f(x, slope, curvature)});
      if (samples.back().value > top.value)
        top = samples.back();
      if (size * std::cos(std::min(da, std::numbers::pi)) - lowest < top.value)
        break;
    }
    if (side > 0)
      right = static_cast<std::ptrdiff_t>(samples.size());
  }
  // the intervals, each between two neighbouring samples (the right side then the left)
  auto between = [&](std::ptrdiff_t from, std::ptrdiff_t to)
  {
    for (std::ptrdiff_t i = from; i + 1 < to; ++i)
      pending.push_back({samples[i], samples[i + 1]});
  };
  between(0, right);
  if (static_cast<std::ptrdiff_t>(samples.size()) > right)
  {
    pending.push_back({samples[right], samples[0]});
    between(right, static_cast<std::ptrdiff_t>(samples.size()));
  }
  double width = step;   // the spacing about the best point when it became the best
  while (not pending.empty())
  {
    auto [a, b] = pending.back();
    pending.pop_back();
    const double w = std::abs(b.x - a.x);
    if (chord_bound(a.value, b.value, w, m) <= top.value + tol or w < 1e-13)
      continue;
    const double x = 0.5 * (a.x + b.x);
    const Point mid{x, f(x, slope, curvature)};
    if (mid.value > top.value)
      top = mid, width = 0.5 * w;
    pending.push_back({a, mid});
    pending.push_back({mid, b});
  }
  // polish: f' = 0 where it changes sign from + to - about the best point
  double lo = top.x - width, hi = top.x + width;
  f(lo, slope, curvature);
  const bool rises = slope > 0.0;
  f(hi, slope, curvature);
  if (not (rises and slope < 0.0))
    return top.x;
  double x = top.x, moved = hi - lo;
  for (int it = 0; it < 60 and hi - lo > 1e-14; ++it)
  {
    f(x, slope, curvature);
    if (slope == 0.0)
      break;
    (slope > 0.0 ? lo : hi) = x;
    const double newton = curvature < 0.0 ? x - slope / curvature : std::numeric_limits<double>::quiet_NaN();
    const double next = (newton > lo and newton < hi and std::abs(newton - x) < 0.5 * moved)
                            ? newton
                            : 0.5 * (lo + hi);
    moved = std::abs(next - x);
    x = next;
    if (moved < 1e-15)
      break;
  }
  return f(x, slope, curvature) >= top.value - tol ? x : top.x;
}

} // namespace pinbore::mechanism
