// A worn journal in its bore (the plane): the profiles' interpolation, their bounds, and the
// contact spread over the arc where the worn surfaces overlap (engine.h: worn_radial).
//
// A profile is a row of Args::wear: the worn depth h (m) at n angles of its body's frame
// evenly from -pi, periodic, interpolated by the uniform Catmull-Rom spline through its
// points (C1). The overlap at the angle phi,
//
//     d(phi) = e . u(phi) - c - h_bore(phi - phi_b) - h_pin(phi - phi_j),
//
// measures the joint's penetration by its mean of order 4 over the arc where the surfaces
// overlap, on the scale of a round joint: delta_p = Phi_round^-1(int d_+^4 dphi), the round
// joint's own penetration on a round profile, smooth in the bodies' motion and in the
// profiles however many nearly equal maxima d has (worn_overlap, moment_penetration).
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

/// Per profile (WornBound): a depth its spline never falls below (its least point less the
/// most a piece can sag between its points, max|h''| step^2 / 8).
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
    out[static_cast<std::size_t>(r)] = {lowest - curvature * step * step / 8.0};
  }
  return out;
}

/// The points of the arc's grid a profile's interval holds: the grid no coarser than 1/4
/// degree, and at least 2 a profile's interval.
inline int arc_fineness(std::ptrdiff_t points)
{
  return static_cast<int>(std::max<std::ptrdiff_t>(2, (1440 + points - 1) / points));
}

/// The overlap's moment over a linear piece from a to b, int_0^1 (a + (b - a) t)_+^4 dt,
/// and its derivatives in a and b (WORN_ORDER = 4: polynomials, no division where both
/// overlap).
struct Piece
{
  double value, at_a, at_b;
};

inline Piece moment_piece(double a, double b)
{
  static_assert(WORN_ORDER == 4);
  if (a <= 0.0 and b <= 0.0)
    return {0.0, 0.0, 0.0};
  if (a >= 0.0 and b >= 0.0)
  {
    const double a2 = a * a, b2 = b * b;
    return {(a2 * a2 + a2 * a * b + a2 * b2 + a * b2 * b + b2 * b2) / 5.0,
            (4 * a2 * a + 3 * a2 * b + 2 * a * b2 + b2 * b) / 5.0,
            (a2 * a + 2 * a2 * b + 3 * a * b2 + 4 * b2 * b) / 5.0};
  }
  // one end overlaps: (b^5 / (b - a)) / 5 with b the overlapping end
  const bool b_in = b > 0.0;
  const double x = b_in ? b : a, y = b_in ? a : b, w = x - y, x4 = x * x * x * x;
  const double value = x4 * x / (5.0 * w);
  const double at_x = x4 / w - value / w, at_y = value / w;
  return b_in ? Piece{value, at_y, at_x} : Piece{value, at_x, at_y};
}

/// The overlap of a worn journal and its bore: its moment Phi = int d_+^4 dpsi and the
/// gradient of Phi in the journal centre's offset e and in the two frames' angles; the
/// deepest overlap of the grid's points and its direction (worn_overlap).
struct Overlap
{
  double moment = 0.0;                          // Phi (m^4 rad)
  std::array<double, 2> gradient{0.0, 0.0};     // dPhi/de
  double turn_bearing = 0.0, turn_journal = 0.0;   // dPhi/dphi_b, dPhi/dphi_j
  double deepest = -std::numeric_limits<double>::infinity();   // the largest overlap (m)
  // where the grid was visited: the deepest point's dd/de = u(phi_b + psi_k) and dd/dphi_b,
  // dd/dphi_j (its surfaces' approach where they first touch)
  bool located = false;
  std::array<double, 2> deepest_direction{0.0, 0.0};
  double deepest_turn_bearing = 0.0, deepest_turn_journal = 0.0;
};

/// The overlap of a worn journal and its bore at the bore's angles psi_k = -pi + k 2 pi / M
/// (M = arc_fineness times the profile's points, the bore's frame at phi_b),
///
///     d_k = e . u(phi_b + psi_k) - h_bore(psi_k) - h_pin(psi_k + phi_b - phi_j) - c,
///
/// taken linear between the points: its moment Phi = sum of 2 pi / M times each piece's
/// (moment_piece, exact for the linear pieces), whose gradient is each point's dPhi/dd_k
/// times dd_k/de = u, dd_k/dphi_b = e . u' - h_pin', dd_k/dphi_j = h_pin'. The profiles are
/// rows `bore` and `pin` of wear (-1: round), their splines evaluated with one set of weights
/// a grid point of a profile's interval (the pin's shifted by phi_b - phi_j). Only the window where
/// e . u can exceed c plus the least depths (`lowest`) is visited; where nothing overlaps,
/// `deepest` is the largest d_k or, outside the window, the bound |e| - c - lowest; within
/// it, the largest d_k's derivatives too (`located`).
inline Overlap worn_overlap(const Rows& wear, std::ptrdiff_t bore, std::ptrdiff_t pin,
                            double lowest, const std::array<double, 2>& e, double phi_b,
                            double phi_j, double clearance)
{
  Overlap out;
  const double size = std::hypot(e[0], e[1]);
  const double reach = clearance + lowest;
  if (not (std::isfinite(size) and std::isfinite(phi_b) and std::isfinite(phi_j)))
  {
    out.moment = out.deepest = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  out.deepest = size - reach;   // a bound, where no point can overlap
  if (size <= reach)
    return out;
  const std::ptrdiff_t n = wear.cols;
  const int fine = arc_fineness(n);
  const std::ptrdiff_t total = n * fine;
  const double step = 2.0 * std::numbers::pi / static_cast<double>(total);
  const double half = std::acos(std::clamp(reach / size, -1.0, 1.0));
  const double centre = std::atan2(e[1], e[0]) - phi_b + std::numbers::pi;   // psi + pi, window's centre
  const auto first = static_cast<std::ptrdiff_t>(std::floor((centre - half) / step)) - 1;
  const std::ptrdiff_t last = std::min(static_cast<std::ptrdiff_t>(std::ceil((centre + half) / step)) + 1,
                                       first + total);
  auto wrap = [](std::ptrdiff_t i, std::ptrdiff_t m) { return ((i % m) + m) % m; };
  // the profiles' spline weights (value, slope) for each grid point of an interval: the
  // bore's at its own angles, the pin's shifted by phi_b - phi_j
  thread_local std::vector<std::array<double, 8>> bore_weights, pin_weights;
  thread_local std::vector<std::ptrdiff_t> shifts;
  const double interval = 2.0 * std::numbers::pi / static_cast<double>(n);
  auto weights_at = [interval](double t) -> std::array<double, 8>
  {
    return {0.5 * (-t + 2 * t * t - t * t * t), 0.5 * (2 - 5 * t * t + 3 * t * t * t),
            0.5 * (t + 4 * t * t - 3 * t * t * t), 0.5 * (-t * t + t * t * t),
            0.5 * (-1 + 4 * t - 3 * t * t) / interval, 0.5 * (-10 * t + 9 * t * t) / interval,
            0.5 * (1 + 8 * t - 9 * t * t) / interval, 0.5 * (-2 * t + 3 * t * t) / interval};
  };
  bore_weights.resize(static_cast<std::size_t>(fine)), pin_weights.resize(static_cast<std::size_t>(fine));
  shifts.resize(static_cast<std::size_t>(fine));
  double a = (phi_b - phi_j) / interval;
  a -= static_cast<double>(n) * std::floor(a / static_cast<double>(n));
  for (int r = 0; r < fine; ++r)
  {
    const double x = static_cast<double>(r) / fine + a, base = std::floor(x);
    bore_weights[static_cast<std::size_t>(r)] = weights_at(static_cast<double>(r) / fine);
    pin_weights[static_cast<std::size_t>(r)] = weights_at(x - base);
    shifts[static_cast<std::size_t>(r)] = static_cast<std::ptrdiff_t>(base);
  }
  auto spline = [&](std::ptrdiff_t row, std::ptrdiff_t j, const std::array<double, 8>& w, double& slope)
  {
    double value = 0.0;
    slope = 0.0;
    for (int m = 0; m < 4; ++m)
    {
      const double p = wear(row, wrap(j - 1 + m, n));
      value += w[static_cast<std::size_t>(m)] * p, slope += w[static_cast<std::size_t>(m + 4)] * p;
    }
    return value;
  };
  thread_local std::vector<double> d, weight, cs, sn, slope;
  const auto count = static_cast<std::size_t>(last - first + 1);
  d.resize(count), weight.assign(count, 0.0), cs.resize(count), sn.resize(count), slope.resize(count);
  const double a0 = phi_b - std::numbers::pi + static_cast<double>(first) * step;
  const double c1 = std::cos(step), s1 = std::sin(step);
  double c = std::cos(a0), sg = std::sin(a0);
  out.deepest = -std::numeric_limits<double>::infinity();
  std::size_t best = 0;
  for (std::size_t i = 0; i < count; ++i)
  {
    const std::ptrdiff_t k = wrap(first + static_cast<std::ptrdiff_t>(i), total);
    const auto r = static_cast<std::size_t>(k % fine);
    double hb = 0.0, hp = 0.0, hb1 = 0.0, hp1 = 0.0;
    if (bore >= 0)
      hb = spline(bore, k / fine, bore_weights[r], hb1);
    if (pin >= 0)
      hp = spline(pin, k / fine + shifts[r], pin_weights[r], hp1);
    cs[i] = c, sn[i] = sg, slope[i] = hp1;
    d[i] = e[0] * c + e[1] * sg - hb - hp - clearance;
    if (d[i] > out.deepest)
      out.deepest = d[i], best = i;
    const double cn = c * c1 - sg * s1;
    sg = sg * c1 + c * s1, c = cn;
  }
  if (count > 0 and std::isfinite(out.deepest))
  {
    out.located = true;
    out.deepest_direction = {cs[best], sn[best]};
    out.deepest_turn_bearing = -e[0] * sn[best] + e[1] * cs[best] - slope[best];
    out.deepest_turn_journal = slope[best];
  }
  if (out.deepest <= 0.0)
    return out;
  for (std::size_t i = 0; i + 1 < count; ++i)
  {
    const Piece p = moment_piece(d[i], d[i + 1]);
    out.moment += step * p.value;
    weight[i] += step * p.at_a, weight[i + 1] += step * p.at_b;
  }
  for (std::size_t i = 0; i < count; ++i)
  {
    const double w = weight[i];
    if (w == 0.0)
      continue;
    out.gradient[0] += w * cs[i], out.gradient[1] += w * sn[i];
    out.turn_bearing += w * (-e[0] * sn[i] + e[1] * cs[i] - slope[i]);
    out.turn_journal += w * slope[i];
  }
  return out;
}

/// The moment of a round joint's overlap at the penetration delta > 0, Phi(delta) = int
/// d_+^4 dphi with d = (c + delta) cos phi - c, and dPhi/d delta: with t = sqrt(delta - d),
///
///     Phi = 4 int_0^sqrt(delta) (delta - t^2)^4 / sqrt(2c + 2 delta - t^2) dt,
///
/// a smooth integrand, by 12-point Gauss-Legendre (exact to rounding); the derivative under
/// the integral (the integrand vanishes at the upper end).
inline std::pair<double, double> round_moment(double delta, double clearance)
{
  static_assert(WORN_ORDER == 4);
  static constexpr std::array<double, 6> x{0.1252334085114689, 0.3678314989981802, 0.5873179542866175,
                                           0.7699026741943047, 0.9041172563704748, 0.9815606342467192};
  static constexpr std::array<double, 6> w{0.2491470458134027, 0.2334925365383546, 0.20316742672306573,
                                           0.16007832854334642, 0.10693932599531907, 0.04717533638651141};
  const double root = std::sqrt(delta), big = 2.0 * clearance + 2.0 * delta;
  double value = 0.0, slope = 0.0;
  for (std::size_t i = 0; i < 12; ++i)
  {
    const double node = i < 6 ? -x[i] : x[i - 6], weight = w[i < 6 ? i : i - 6];
    const double t = 0.5 * root * (1.0 + node), u = delta - t * t, r = 1.0 / std::sqrt(big - t * t);
    const double u3 = u * u * u;
    value += weight * u3 * u * r;
    slope += weight * (4.0 * u3 * r - u3 * u * r * r * r);
  }
  return {2.0 * root * value, 2.0 * root * slope};
}

/// A worn joint's penetration delta_p = Phi_round^-1(Phi) and dPhi_round/d delta there:
/// Newton's method on ln Phi_round(delta) = ln Phi (nearly linear in ln delta) from the
/// parabolic arc's sqrt(2/c) B(5, 1/2) delta^(9/2), B(5, 1/2) = 256/315, to 1e-14.
inline std::pair<double, double> moment_penetration(double moment, double clearance)
{
  double log_delta = std::log(moment / (std::sqrt(2.0 / clearance) * 256.0 / 315.0)) / 4.5;
  std::pair<double, double> at{};
  for (int it = 0; it < 40; ++it)
  {
    const double delta = std::exp(log_delta);
    at = round_moment(delta, clearance);
    const double change = (std::log(at.first) - std::log(moment)) / (delta * at.second / at.first);
    log_delta -= change;
    if (std::abs(change) < 1e-14)
      break;
  }
  const double delta = std::exp(log_delta);
  return {delta, round_moment(delta, clearance).second};
}

/// Whether contact k runs on worn profiles (CONTACT_BORE_WEAR or CONTACT_PIN_WEAR set).
inline bool is_worn(const Rows& contacts, std::ptrdiff_t k)
{
  return contacts(k, CONTACT_BORE_WEAR) != 0.0 or contacts(k, CONTACT_PIN_WEAR) != 0.0;
}

/// The depth worn contact k's two profiles together never fall below (their worn_bounds; a
/// round surface's 0): its journal cannot overlap its bore within |e| <= c + that.
inline double worn_lowest(const Args& args, std::ptrdiff_t k)
{
  double lowest = 0.0;
  for (const int column : {CONTACT_BORE_WEAR, CONTACT_PIN_WEAR})
  {
    const auto r = static_cast<std::ptrdiff_t>(args.contacts(k, column)) - 1;
    lowest += r < 0 ? 0.0 : args.wear_bounds[static_cast<std::size_t>(r)].lowest;
  }
  return lowest;
}

/// A worn journal in its bore's section: its penetration delta_p = Phi_round^-1(Phi) on the
/// round joint's scale (worn_overlap, moment_penetration) and its derivatives
/// d delta_p / d(e, phi_b, phi_j) = dPhi / d(...) / Phi_round'(delta_p): `normal` along
/// d delta_p / de (from the bore into the journal), `reach` its length, `turn_bearing`,
/// `turn_journal` the two frames' angles'. e, phi_b, phi_j in any one frame of the section
/// (the plane's: the planar joint; the bore's own, phi_b = 0: a spatial joint's slice).
/// Where nothing overlaps (or Phi underflows, or the input is not finite) delta is the
/// deepest (negative) overlap, the normal along e, reach 1 and no turn. `approach`,
/// `approach_bearing`, `approach_journal`: the derivatives of the deepest overlap d_max in
/// e and the two angles (along e, no turn, where the grid was not visited): its rate, the
/// surfaces' approach where they first touch, is a contact's impact speed (on the grid's
/// few points that overlap at the onset, delta_p's rate is not: the discrete moment grows
/// as d_max^5 there, the round one as delta^4.5).
struct WornSection
{
  double delta;
  std::array<double, 2> normal;
  double reach = 1.0, turn_bearing = 0.0, turn_journal = 0.0;
  std::array<double, 2> approach{1.0, 0.0};
  double approach_bearing = 0.0, approach_journal = 0.0;
};

inline WornSection worn_section(const Args& args, std::ptrdiff_t k, const std::array<double, 2>& e,
                                double phi_b, double phi_j)
{
  const Rows& contacts = args.contacts;
  const auto bore = static_cast<std::ptrdiff_t>(contacts(k, CONTACT_BORE_WEAR)) - 1;
  const auto pin = static_cast<std::ptrdiff_t>(contacts(k, CONTACT_PIN_WEAR)) - 1;
  const double clearance = contacts(k, CONTACT_CLEARANCE);
  const Overlap o = worn_overlap(args.wear, bore, pin, worn_lowest(args, k), e, phi_b, phi_j, clearance);
  const double r = std::hypot(e[0], e[1]);
  const std::array<double, 2> along = r > 0.0 ? std::array<double, 2>{e[0] / r, e[1] / r}
                                              : std::array<double, 2>{1.0, 0.0};
  WornSection out{o.deepest, along};
  if (o.located)
    out.approach = o.deepest_direction, out.approach_bearing = o.deepest_turn_bearing,
    out.approach_journal = o.deepest_turn_journal;
  else
    out.approach = along;
  const double size = std::hypot(o.gradient[0], o.gradient[1]);
  if (not (o.moment >= std::numeric_limits<double>::min() and size > 0.0))
    return out;
  const auto [delta, slope] = moment_penetration(o.moment, clearance);
  out.delta = delta;
  out.normal = {o.gradient[0] / size, o.gradient[1] / size};
  out.reach = size / slope;
  out.turn_bearing = o.turn_bearing / slope;
  out.turn_journal = o.turn_journal / slope;
  return out;
}

} // namespace pinbore::mechanism
