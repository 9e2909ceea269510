// The mechanism, written once for every body kind K (planar.h, spatial.h): ideal joints and
// the drive, torsion springs, stops and latches, spring-dampers and harmonic loads, clearance
// joints and their contacts, the equations of motion with their constraints, impacts, the
// projection onto the constraints and the integrator's hooks (integrator.h). A body is
// reached only through K (K::point_state, K::put, K::push, ...).
//
// Equations of motion ([Cao2013] eq. 21; stabilised after [Baumgarte1972]), in the bodies'
// velocity columns v (planar: x', y', w; spatial: r', w; a flexible body's modal rates after):
//
//     M v' + D^T lambda = Q(q, v, t),     D v' = gamma - 2 a Phi' - a^2 Phi,
//
// lambda from the Schur system (D M^-1 D^T) lambda = D M^-1 Q - gamma~ (Cholesky within its
// envelope: two rows couple only through a body they share), then v' = M^-1 (Q - D^T lambda),
// and the body kind turns v' into the coordinates' second derivatives.
//
// Ideal joints and the drive are primitive constraints ([Nikravesh1988] ch. 7): a point of
// body i on a point of body j (POINT: D rows), a vector of i normal to a vector of j (DOT1), a
// vector of i normal to the line between two points (DOT2), the relative angle about an axis
// (ANGLE: angle0 + theta(t)). Each row gives its value, its Jacobian, its explicit time rate
// and gamma, the velocity terms of its second derivative with the sign changed: for a body
// point P'' = r'' + w' x s + w x (w x s), for a body vector a'' = w' x a + w x (w x a).
//
// Clearance joints are contacts, each a distance that closes:
// - RADIAL: a journal point X (a planar journal's centre; a ball's in its socket, the dry
//   spherical joint of [FloresLankarani2010] and [Tian2009]) from a bearing point P:
//   delta = |X - P| - c, normal n = (X - P)/|X - P|, contact point C = P + R_b n;
// - AXIS_RADIAL: a journal point from the bore's axis u: delta = |(X - P) - ((X - P).u) u| - c;
// - PLANE: a journal point against a face of the bearing body, normal N, offset d:
//   delta = s N.(X - P) - d on the face's side s (a translational joint's slider corners; a
//   cylindrical joint's shoulders, two-sided);
// - SLICED: a journal along its bore in space, cut into slices ([Cao2013]'s 3D joint, the
//   sliced law with its bulk compliance): sliced_forces.
// A continuous contact carries F_n = F_el(delta) (1 + chi delta'/v0) while delta > 0, F_el
// tabulated (laws.h) or linear, chi the damping law's hysteresis factor (or, calibrated, of
// the laws file's e(v0) at v0), v0 the approach rate at this impact's onset; friction opposes
// the slip at the contact point (the laws of laws.h; in the plane along the tangent, in space
// against the slip with a state law's state a vector in the bearing body's frame). Impulse
// contacts (Newton or Poisson): rigid impacts between steps (apply_impulse), and below a rest
// speed held contact: the constraint delta = 0 joins the ideal ones until its multiplier (the
// normal force) would pull. While delta <= 0 no law is evaluated.
//
// Extra states integrate the energy dissipated in the contacts, dampers and modal damping and
// the work of the constraint forces (the drive) and of the loads, for the energy book.
#pragma once

#include "bodies.h"
#include "data.h"
#include "laws.h"
#include "worn.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace pinbore::mechanism
{

inline constexpr double LATCH_TOL = 1e-8;   // rad: a latch engages within this of its angle
inline const double NaN = std::numeric_limits<double>::quiet_NaN();

// ---- the small dense linear algebra of the constraint solve (Schur matrix, Cholesky)
inline std::int64_t envelope(std::span<const std::int64_t> first, std::ptrdiff_t i)
{
  return first.empty() ? 0 : first[i];
}

/// Solve a x = b in place for the leading m x m block of a symmetric positive semi-definite
/// a (lower triangle, overwritten); a dependent row (pivot below 1e-10 of its diagonal) is
/// dropped, its unknown 0; `first` the envelope (empty: none).
inline void cholesky_solve(const Matrix<double>& a, std::span<double> b, std::ptrdiff_t m,
                           std::span<const std::int64_t> first)
{
  for (std::ptrdiff_t j = 0; j < m; ++j)
  {
    const std::ptrdiff_t fj = envelope(first, j);
    double d = a(j, j);
    const double scale = d;
    for (std::ptrdiff_t k = fj; k < j; ++k)
      d -= a(j, k) * a(j, k);
    if (d <= 1e-10 * scale)
    {
      a(j, j) = 0.0;
      for (std::ptrdiff_t i = j + 1; i < m; ++i)
        a(i, j) = 0.0;
      continue;
    }
    a(j, j) = std::sqrt(d);
    for (std::ptrdiff_t i = j + 1; i < m; ++i)
    {
      const std::ptrdiff_t fi = envelope(first, i);
      if (fi > j)
        continue;
      double v = a(i, j);
      for (std::ptrdiff_t k = std::max(fi, fj); k < j; ++k)
        v -= a(i, k) * a(j, k);
      a(i, j) = v / a(j, j);
    }
  }
  for (std::ptrdiff_t i = 0; i < m; ++i)
  {
    double v = b[i];
    for (std::ptrdiff_t k = envelope(first, i); k < i; ++k)
      v -= a(i, k) * b[k];
    b[i] = a(i, i) > 0.0 ? v / a(i, i) : 0.0;
  }
  for (std::ptrdiff_t i = m - 1; i >= 0; --i)
  {
    double v = b[i];
    for (std::ptrdiff_t k = i + 1; k < m; ++k)
      if (envelope(first, k) <= i)
        v -= a(k, i) * b[k];
    b[i] = a(i, i) > 0.0 ? v / a(i, i) : 0.0;
  }
}

inline bool shares_body(const Matrix<std::int64_t>& rb, std::ptrdiff_t i, std::ptrdiff_t k)
{
  for (int side = 0; side < 2; ++side)
  {
    const std::int64_t b = rb(i, side);
    if (b >= 0 and (b == rb(k, 0) or b == rb(k, 1)))
      return true;
  }
  return false;
}

/// first[i] for rows start..m-1: the first row k <= i that shares a body with row i.
inline void envelope_of(const Matrix<std::int64_t>& rb, std::span<std::int64_t> first,
                        std::ptrdiff_t start, std::ptrdiff_t m)
{
  for (std::ptrdiff_t i = start; i < m; ++i)
  {
    first[i] = i;
    for (std::ptrdiff_t k = 0; k < i; ++k)
      if (shares_body(rb, i, k))
      {
        first[i] = k;
        break;
      }
  }
}

template <class K>
struct Engine
{
  static constexpr int D = K::D;
  using V = typename K::V;
  using Ang = typename K::A;

  // ---- the constraint rows
  static std::ptrdiff_t constraint_count(const Rows& primitives)
  {
    std::ptrdiff_t m = 0;
    for (std::ptrdiff_t k = 0; k < primitives.rows; ++k)
      m += static_cast<int>(primitives(k, PRIM_KIND)) == POINT ? D : 1;
    return m;
  }

  static void sorted_bodies(const Matrix<std::int64_t>& rb, std::ptrdiff_t row, std::int64_t bi,
                            std::int64_t bj)
  {
    if (bj == bi)
      bj = -1;
    rb(row, 0) = std::min(bi, bj);
    rb(row, 1) = std::max(bi, bj);
  }

  /// The ideal rows' bodies and the Schur matrix's envelope (held rows after them: dense).
  static void constraint_pattern(const Rows& primitives, const Matrix<std::int64_t>& rb,
                                 std::span<std::int64_t> first)
  {
    for (std::ptrdiff_t i = 0; i < rb.rows; ++i)
      rb(i, 0) = rb(i, 1) = -1;
    std::ptrdiff_t row = 0;
    for (std::ptrdiff_t k = 0; k < primitives.rows; ++k)
    {
      const int kind = static_cast<int>(primitives(k, PRIM_KIND));
      const auto bi = static_cast<std::int64_t>(primitives(k, PRIM_BODY_I));
      const auto bj = static_cast<std::int64_t>(primitives(k, PRIM_BODY_J));
      const int n = kind == POINT ? D : 1;
      for (int c = 0; c < n; ++c)
        sorted_bodies(rb, row + c, bi, bj);
      row += n;
    }
    for (std::ptrdiff_t i = 0; i < rb.rows; ++i)
      first[i] = 0;
    envelope_of(rb, first, 0, row);
  }

  static void clear_row(const Matrix<double>& jac, std::ptrdiff_t row, std::int64_t b,
                        std::span<const std::int64_t> offsets)
  {
    if (b >= 0)
      for (std::ptrdiff_t c = offsets[b]; c < offsets[b + 1]; ++c)
        jac(row, c) = 0.0;
  }

  /// Phi' of constraint row i: D_i v + Phi_t (the row's two bodies only).
  static double constraint_rate(const Args& args, const Work& w, std::ptrdiff_t i)
  {
    double rate = w.phi_t[i];
    for (int side = 0; side < 2; ++side)
    {
      const std::int64_t b = w.row_bodies(i, side);
      if (b >= 0)
        rate = K::row_rate(rate, w.jac, i, b, w.bodies, w.velocities, args.offsets);
    }
    return rate;
  }

  struct Profile
  {
    double theta, rate, acceleration;
  };

  /// The smooth spin-up to `speed` over `duration` [SimoVuQuoc1986].
  static Profile spin_up(double t, double speed, double duration)
  {
    if (t >= duration)
      return {speed * (t - duration / 2), speed, 0.0};
    const double w = 2 * M_PI / duration;
    const double k = speed / duration;
    return {k * (t * t / 2 + (std::cos(w * t) - 1) / (w * w)), k * (t - std::sin(w * t) / w),
            k * (1 - std::cos(w * t))};
  }

  /// theta(t) of the ANGLE primitive k: constant speed, spin-up, table or harmonics.
  static Profile drive_profile(const Rows& primitives, std::ptrdiff_t k, const Rows& profile,
                               double t)
  {
    const int kind = static_cast<int>(primitives(k, PRIM_PROFILE));
    const double speed = primitives(k, PRIM_SPEED);
    if (kind == SPIN_UP)
      return spin_up(t, speed, primitives(k, PRIM_PROFILE_TIME));
    if (kind == HARMONIC)
    {
      double theta = 0.0, rate = 0.0, acceleration = 0.0;
      const auto first = static_cast<std::ptrdiff_t>(primitives(k, PRIM_PROFILE_TIME));
      const auto count = static_cast<std::ptrdiff_t>(primitives(k, PRIM_PROFILE_ROWS));
      for (std::ptrdiff_t i = first; i < first + count; ++i)
      {
        const double a = profile(i, HARM_AMPLITUDE), w = profile(i, HARM_OMEGA),
                     phase = profile(i, HARM_PHASE);
        const double sine = std::sin(w * t + phase);
        theta += a * (sine - std::sin(phase));
        rate += a * w * std::cos(w * t + phase);
        acceleration -= a * w * w * sine;
      }
      return {theta, rate, acceleration};
    }
    if (kind == TABLE)
    {
      auto i = static_cast<std::ptrdiff_t>(primitives(k, PRIM_PROFILE_TIME));
      std::ptrdiff_t last = i + static_cast<std::ptrdiff_t>(primitives(k, PRIM_PROFILE_ROWS)) - 1;
      while (i < last)
      {
        const std::ptrdiff_t middle = (i + last + 1) / 2;
        if (profile(middle, SEG_TIME) <= t)
          i = middle;
        else
          last = middle - 1;
      }
      const double tau = t - profile(i, SEG_TIME);
      const double c1 = profile(i, SEG_C1), c2 = profile(i, SEG_C2), c3 = profile(i, SEG_C3);
      return {profile(i, SEG_C0) + tau * (c1 + tau * (c2 + tau * c3)),
              c1 + tau * (2 * c2 + 3 * c3 * tau), 2 * c2 + 6 * c3 * tau};
    }
    return {speed * t, speed, 0.0};
  }

  /// The dot-2 row a_i . (P_j - P_i) into row `row`: (value, gamma).
  static std::pair<double, double> dot2_row(const Args& args, const Work& w, std::ptrdiff_t row,
                                            std::int64_t bi, const V& s_i, const V& a_i,
                                            std::int64_t bj, const V& s_j)
  {
    const Matrix<double>& s = w.bodies;
    const auto a = K::vector_state(s, bi, s_i, a_i);
    const auto pi = K::point_state(s, bi, s_i);
    const auto pj = K::point_state(s, bj, s_j);
    const V d = sub(pj.position, pi.position), dd = sub(pj.velocity, pi.velocity);
    K::put(w.jac, row, s, bi, s_i, scaled(a.value, -1.0), cross(a.value, add(d, pi.arm)), 1.0,
           args.offsets);
    K::put(w.jac, row, s, bj, s_j, a.value, cross(pj.arm, a.value), 1.0, args.offsets);
    return {dot(a.value, d),
            -(dot(a.centripetal, d) + 2 * dot(a.rate, dd)
              + K::centripetal_gap(s, a.value, bi, pi.arm, pi.centripetal, bj, pj.arm,
                                   pj.centripetal))};
  }

  // ---- contact geometry
  struct Radial
  {
    double delta;
    V normal, point;
    double rate;
    V at_journal, at_bearing;
    double along;
    V relative;
    bool worn = false;   // a worn journal: the force at the centres with the torques below
    double reach = 1.0;   // a worn journal's |d delta / d e| (its force's share along the normal)
    double turn_bearing = 0.0, turn_journal = 0.0;   // d delta / d(angle) of each body's frame
    double approach = 0.0;   // a worn journal's impact speed: its deepest overlap's rate
  };
  struct Plane
  {
    double delta;
    V normal, point;
    double rate, side;
    V relative;
  };
  /// A contact's penetration and its approach rate (its impact speed at the onset: a worn
  /// journal's the rate of its deepest overlap, worn_section) and direction.
  struct Depth
  {
    double delta, rate;
    V normal{};   // the contact's direction, from the bearing into the journal's side
  };

  static std::int64_t body(const Rows& contacts, std::ptrdiff_t k, int column)
  {
    return static_cast<std::int64_t>(contacts(k, column));
  }

  /// A worn journal in its bore (the plane): its section (worn_section) in the plane's frame
  /// at the two frames' angles; the rate d delta_p / dt = reach n . v + turn_b w_b + turn_j w_j,
  /// the approach (its deepest overlap's rate) likewise.
  static void worn_radial(const Args& args, const Matrix<double>& s, std::ptrdiff_t k, const V& e,
                          const V& v, Radial& g)
  {
    if constexpr (D == 2)
    {
      const Rows& contacts = args.contacts;
      const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                         bj = body(contacts, k, CONTACT_JOURNAL_BODY);
      const auto [phi_b, w_b] = K::frame_angle(s, bb, contacts.cell<D>(k, CONTACT_BEARING_POINT));
      const auto [phi_j, w_j] = K::frame_angle(s, bj, contacts.cell<D>(k, CONTACT_JOURNAL_POINT));
      const WornSection ws = worn_section(args, k, {e[0], e[1]}, phi_b, phi_j);
      g.worn = true;
      g.delta = ws.delta;
      g.normal = {ws.normal[0], ws.normal[1]};
      g.point = add(g.at_bearing, scaled(g.normal, contacts(k, CONTACT_RADIUS)));
      g.reach = ws.reach;
      g.turn_bearing = ws.turn_bearing;
      g.turn_journal = ws.turn_journal;
      g.rate = g.reach * dot(g.normal, v) + g.turn_bearing * w_b + g.turn_journal * w_j;
      g.approach = dot(V{ws.approach[0], ws.approach[1]}, v) + ws.approach_bearing * w_b
                   + ws.approach_journal * w_j;
    }
  }

  static Radial radial_geometry(const Args& args, const Matrix<double>& s, std::ptrdiff_t k)
  {
    const Rows& contacts = args.contacts;
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    V pb = K::point_state(s, bb, contacts.cell<D>(k, CONTACT_BEARING_POINT)).position;
    const V pj = K::point_state(s, bj, contacts.cell<D>(k, CONTACT_JOURNAL_POINT)).position;
    V e = sub(pj, pb);
    double along = 0.0;
    if (static_cast<int>(contacts(k, CONTACT_KIND)) == AXIS_RADIAL)
    {
      const V u = K::vector_state(s, bb, contacts.cell<D>(k, CONTACT_BEARING_POINT),
                                  contacts.cell<D>(k, CONTACT_BEARING_AXIS))
                      .value;
      along = dot(u, e);
      pb = add(pb, scaled(u, along));
      e = sub(e, scaled(u, along));
    }
    const double size = norm(e);
    const double delta = size - contacts(k, CONTACT_CLEARANCE);
    if (is_worn(contacts, k))
    {   // the force between the centres: its velocities there
      Radial g{delta, axis<D>(0), pb, 0.0, pj, pb, along,
               sub(K::material_velocity(s, bj, pj), K::material_velocity(s, bb, pb))};
      worn_radial(args, s, k, e, g.relative, g);
      return g;
    }
    if (size == 0.0)
      return {delta, axis<D>(0), pb, 0.0, pj, pb, along, zero<D>()};
    const V n = direction(e, size);
    const V c = add(pb, scaled(n, contacts(k, CONTACT_RADIUS)));
    const bool at = contacts(k, CONTACT_AT_CONTACT) > 0.0;
    const V xj = at ? c : pj, xb = at ? c : pb;
    const V v = sub(K::material_velocity(s, bj, xj), K::material_velocity(s, bb, xb));
    return {delta, n, c, dot(n, v), xj, xb, along, v};
  }

  static Plane plane_geometry(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k)
  {
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    const V bp = contacts.cell<D>(k, CONTACT_BEARING_POINT);
    const V p = K::point_state(s, bb, bp).position;
    const V u = K::vector_state(s, bb, bp, contacts.cell<D>(k, CONTACT_BEARING_AXIS)).value;
    const V x = K::point_state(s, bj, contacts.cell<D>(k, CONTACT_JOURNAL_POINT)).position;
    const double along = dot(sub(x, p), u);
    double side = contacts(k, CONTACT_SIDE), delta;
    if (side == 0.0)
    {
      side = along >= 0.0 ? 1.0 : -1.0;
      delta = std::abs(along) - contacts(k, CONTACT_CLEARANCE);
    }
    else
      delta = side * along - contacts(k, CONTACT_CLEARANCE);
    const V n = side > 0.0 ? u : scaled(u, -1.0);
    const V v = sub(K::material_velocity(s, bj, x), K::material_velocity(s, bb, x));
    return {delta, n, x, dot(n, v), side, v};
  }

  static Depth contact_depth(const Args& args, const Matrix<double>& s, std::ptrdiff_t k)
  {
    const Rows& contacts = args.contacts;
    const int kind = static_cast<int>(contacts(k, CONTACT_KIND));
    if (kind == PLANE)
    {
      const Plane g = plane_geometry(s, contacts, k);
      return {g.delta, g.rate, g.normal};
    }
    if (kind == SLICED)
    {
      if constexpr (D == 3)
        return sliced_depth(args, s, k);
      else
        return {-std::numeric_limits<double>::infinity(), 0.0};   // the plane has none
    }
    const Radial g = radial_geometry(args, s, k);
    return {g.delta, g.worn ? g.approach : g.rate, g.normal};
  }

  /// The held contact's row delta = 0 (its multiplier is the normal force).
  static void held_row(const Args& args, const Work& w, std::ptrdiff_t row, std::ptrdiff_t k)
  {
    const Rows& contacts = args.contacts;
    const Matrix<double>& s = w.bodies;
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    for (std::ptrdiff_t c = 0; c < w.jac.cols; ++c)
      w.jac(row, c) = w.mjac(row, c) = 0.0;
    sorted_bodies(w.row_bodies, row, bb, bj);
    w.phi_t[row] = 0.0;
    const V bp = contacts.cell<D>(k, CONTACT_BEARING_POINT);
    const V baxis = contacts.cell<D>(k, CONTACT_BEARING_AXIS);
    if (static_cast<int>(contacts(k, CONTACT_KIND)) == PLANE)
    {
      const Plane g = plane_geometry(s, contacts, k);
      const auto [value, gamma] = dot2_row(args, w, row, bb, bp, scaled(baxis, g.side), bj,
                                           contacts.cell<D>(k, CONTACT_JOURNAL_POINT));
      (void)value;
      w.phi[row] = g.delta;
      w.rhs_c[row] = gamma;
      return;
    }
    const Radial g = radial_geometry(args, s, k);
    const V s_j = contacts.cell<D>(k, CONTACT_JOURNAL_POINT);
    const auto pj = K::point_state(s, bj, s_j);
    const auto u = K::vector_state(s, bb, bp, baxis);
    const V foot = add(bp, scaled(baxis, g.along));
    const auto pb = K::point_state(s, bb, foot);
    const V n = g.normal;
    K::put(w.jac, row, s, bj, s_j, n, cross(pj.arm, n), 1.0, args.offsets);
    K::put(w.jac, row, s, bb, foot, n, cross(pb.arm, n), -1.0, args.offsets);
    const V e_dot = sub(pj.velocity, pb.velocity);
    const double along_rate = dot(u.rate, sub(pj.position, pb.position)) + dot(u.value, e_dot);
    const double size = g.delta + contacts(k, CONTACT_CLEARANCE);
    w.rhs_c[row] = -K::centripetal_gap(s, n, bb, pb.arm, pb.centripetal, bj, pj.arm,
                                       pj.centripetal);
    w.rhs_c[row] -= (dot(e_dot, e_dot) - along_rate * dot(u.value, e_dot) - g.rate * g.rate) / size;
    w.rhs_c[row] += along_rate * dot(n, u.rate);
    w.phi[row] = g.delta;
  }

  /// D, Phi, Phi_t and gamma - 2 a Phi' - a^2 Phi of the ideal rows, the drive and the held
  /// contacts (body states current; `mode` the contacts held): the number of rows.
  static std::ptrdiff_t constraint_rows(double t, const Args& args, const Work& w, double alpha,
                                        std::span<const std::int64_t> mode)
  {
    const Rows& pr = args.primitives;
    const Matrix<double>& s = w.bodies;
    std::ptrdiff_t row = 0;
    for (std::ptrdiff_t k = 0; k < pr.rows; ++k)
    {
      const int kind = static_cast<int>(pr(k, PRIM_KIND));
      const auto bi = static_cast<std::int64_t>(pr(k, PRIM_BODY_I));
      const auto bj = static_cast<std::int64_t>(pr(k, PRIM_BODY_J));
      for (int c = 0; c < (kind == POINT ? D : 1); ++c)
      {
        clear_row(w.jac, row + c, w.row_bodies(row + c, 0), args.offsets);
        clear_row(w.jac, row + c, w.row_bodies(row + c, 1), args.offsets);
      }
      const V s_i = pr.cell<D>(k, PRIM_S_I), s_j = pr.cell<D>(k, PRIM_S_J);
      if (kind == POINT)
      {
        const auto pi = K::point_state(s, bi, s_i);
        const auto pj = K::point_state(s, bj, s_j);
        for (int c = 0; c < D; ++c)
        {
          const V unit = axis<D>(c);
          K::put(w.jac, row + c, s, bi, s_i, unit, cross(pi.arm, unit), 1.0, args.offsets);
          K::put(w.jac, row + c, s, bj, s_j, unit, cross(pj.arm, unit), -1.0, args.offsets);
          w.phi[row + c] = pi.position[c] - pj.position[c];
          w.phi_t[row + c] = 0.0;
          w.rhs_c[row + c] = pj.centripetal[c] - pi.centripetal[c];
        }
        row += D;
        continue;
      }
      if (kind == DOT1)
      {
        const auto r = dot1<K>(s, bi, s_i, pr.cell<D>(k, PRIM_A_I), bj, s_j, pr.cell<D>(k, PRIM_B_J));
        K::put(w.jac, row, s, bi, s_i, zero<D>(), r.coefficient, 1.0, args.offsets);
        K::put(w.jac, row, s, bj, s_j, zero<D>(), r.coefficient, -1.0, args.offsets);
        w.phi[row] = r.value;
        w.phi_t[row] = 0.0;
        w.rhs_c[row] = -r.centripetal;
      }
      else if (kind == DOT2)
      {
        const auto [value, gamma] = dot2_row(args, w, row, bi, s_i, pr.cell<D>(k, PRIM_A_I), bj, s_j);
        w.phi[row] = value;
        w.phi_t[row] = 0.0;
        w.rhs_c[row] = gamma;
      }
      else   // ANGLE: the relative angle = angle0 + theta(t)
      {
        const Profile p = drive_profile(pr, k, args.profile, t);
        const auto r = K::relative_rotation(s, bi, bj, s_i, s_j, pr.cell<D>(k, PRIM_A_I),
                                            pr.cell<D>(k, PRIM_B_J), pr.cell<D>(k, PRIM_C_I),
                                            pr(k, PRIM_ANGLE0), p.theta);
        K::put(w.jac, row, s, bi, s_i, zero<D>(), r.coefficient, 1.0, args.offsets);
        K::put(w.jac, row, s, bj, s_j, zero<D>(), r.coefficient, -1.0, args.offsets);
        w.phi[row] = r.angle;
        w.phi_t[row] = 0.0 - p.rate;
        w.rhs_c[row] = r.centripetal + p.acceleration;
      }
      row += 1;
    }
    for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
      if (mode[k] == 1)
        held_row(args, w, row++, k);
    for (std::ptrdiff_t i = 0; i < row; ++i)
      w.rhs_c[i] -= (2 * alpha * constraint_rate(args, w, i) + alpha * alpha * w.phi[i]);
    return row;
  }

  // ---- contact laws
  /// chi for the impact speed v0: the damping law's constant or the calibrated chi(v0)
  /// tabulated in ln v0 (held at the table's ends).
  static double contact_chi(const Rows& contacts, std::ptrdiff_t k, double impact_speed)
  {
    const double step = contacts(k, CONTACT_CHI_STEP);
    if (step == 0.0)
      return contacts(k, CONTACT_CHI);
    const double x = (std::log(impact_speed) - contacts(k, CONTACT_CHI_LOG_SPEED)) / step;
    if (x <= 0.0)
      return contacts(k, CONTACT_CHI_TABLE);
    if (x >= CHI_POINTS - 1)
      return contacts(k, CONTACT_CHI_TABLE + CHI_POINTS - 1);
    const int i = static_cast<int>(x);
    const double f = x - i;
    return (1.0 - f) * contacts(k, CONTACT_CHI_TABLE + i) + f * contacts(k, CONTACT_CHI_TABLE + i + 1);
  }

  static double static_coefficient(const double* c, double slip)
  {
    const int law = static_cast<int>(c[CONTACT_FRICTION_LAW]);
    if (law == COULOMB)
      return c[COULOMB_MU];
    if (law == STRIBECK)
      return laws::stribeck_polynomial(slip, c[STRIBECK_MU_STATIC], c[STRIBECK_MU_MIN],
                                       c[STRIBECK_V_MIN]);
    return laws::linear_velocity(slip, c[LINEAR_MU_STATIC], c[LINEAR_ALPHA]);
  }

  /// (friction force along the slip, the rate of the law's state) of every law but Iwan.
  static std::pair<double, double> scalar_friction(const double* c, double f_n, double slip,
                                                   double state)
  {
    const int law = static_cast<int>(c[CONTACT_FRICTION_LAW]);
    if (law == NO_FRICTION)
      return {0.0, 0.0};
    if (law <= LINEAR)
      return {laws::ambrosio(slip, f_n, static_coefficient(c, slip), c[REGULARISATION_V0],
                             c[REGULARISATION_V1]),
              0.0};
    if (law == LUGRE)
    {
      const double g = laws::lugre_g(slip, c[LUGRE_MU_COULOMB], c[LUGRE_MU_STATIC],
                                     c[LUGRE_STRIBECK_SPEED]);
      const double rate = laws::lugre_rate(state, slip, c[LUGRE_SIGMA0], g);
      return {f_n * laws::lugre_force(state, rate, slip, c[LUGRE_SIGMA0], c[LUGRE_SIGMA1],
                                      c[LUGRE_SIGMA2]),
              rate};
    }
    return {f_n * state, laws::dahl_rate(state, slip, c[DAHL_SIGMA], c[DAHL_MU])};
  }

  struct Friction
  {
    V force;
    double power, size;
  };

  /// Friction at a contact point in the plane: the slip along t = (-n_y, n_x).
  static Friction planar_friction(const Rows& contacts, std::ptrdiff_t k, double f_n, const V& n,
                                  const V& v, std::span<const double> y, std::span<double> dy,
                                  std::ptrdiff_t index)
  {
    const V t = tangent(n);
    const double slip = dot(t, v);
    const double* c = contacts.row(k);
    double f_t;
    if (static_cast<int>(c[CONTACT_FRICTION_LAW]) == IWAN)
    {
      const laws::Iwan r = laws::iwan_bilinear(y[index + STATE_TRAVEL], y[index + STATE_STRETCH],
                                               slip, c[IWAN_K1], c[IWAN_K2], c[IWAN_MU] * f_n);
      f_t = r.force;
      dy[index] = r.travel_rate;
      dy[index + STATE_STRETCH] = r.stretch_rate;
    }
    else
    {
      const auto [force, rate] = scalar_friction(c, f_n, slip, index >= 0 ? y[index] : 0.0);
      f_t = force;
      if (index >= 0)
        dy[index] = rate;
    }
    return {scaled(t, -f_t), f_t * slip, f_t};
  }

  static double elastic_force(const Args& args, std::ptrdiff_t k, double delta)
  {
    const double stiffness = args.contacts(k, CONTACT_STIFFNESS);
    if (stiffness > 0.0)
      return stiffness * delta;
    const auto table = static_cast<std::ptrdiff_t>(args.contacts(k, CONTACT_TABLE));
    return laws::table_force(delta, args.grid_log0, args.grid_step, args.tables.row(table),
                             static_cast<std::size_t>(args.tables.cols));
  }

  struct Normal
  {
    double elastic, law, force;   // f_el, f = F(delta, delta') and the normal force f reach
  };
  /// A journal's normal force in its bore: the law's F(delta, delta') with its hysteresis,
  /// and the normal force it gives, F times a worn journal's reach (1 on a round one); the
  /// one the friction and the Iwan element's slider take (integrator.h).
  static Normal radial_normal(const Args& args, std::ptrdiff_t k, const Radial& g, double speed)
  {
    const double f_el = elastic_force(args, k, g.delta);
    const double f = laws::hysteresis_force(f_el, g.rate, speed, contact_chi(args.contacts, k, speed));
    return {f_el, f, f * (g.worn ? g.reach : 1.0)};
  }

  /// A worn journal's forces (worn_radial): the law's force F(delta_p, delta_p') of its
  /// penetration, -F d delta_p / de on the journal at its centre (its opposite on the
  /// bearing) with the torques -F d delta_p / dphi on the two frames (the force of the
  /// potential of delta_p: an elastic contact keeps the energy book); friction at the bore's
  /// surface point along the normal's tangent as on a round bore; the dissipated power (NaN
  /// beyond the law's table; 0 when open).
  static double worn_contact(const Args& args, const Work& w, std::span<const double> y,
                             std::span<double> dy, std::ptrdiff_t k, double speed, const Radial& g)
  {
    if constexpr (D == 2)
    {
      const Rows& contacts = args.contacts;
      const Matrix<double>& s = w.bodies;
      const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                         bj = body(contacts, k, CONTACT_JOURNAL_BODY);
      if (std::isnan(g.delta))
        return NaN;
      if (g.delta <= 0.0)
        return 0.0;
      const auto [f_el, f, f_n] = radial_normal(args, k, g, speed);   // f_n: between the centres
      if (not std::isfinite(f))
        return NaN;
      w.normal[k] = f_n;
      K::push(w.force, s, bj, scaled(g.normal, -f_n), g.at_journal, args.offsets);
      K::push(w.force, s, bb, scaled(g.normal, f_n), g.at_bearing, args.offsets);
      K::push_torque(w.force, s, bj, contacts.cell<D>(k, CONTACT_JOURNAL_POINT), -f * g.turn_journal,
                     args.offsets);
      K::push_torque(w.force, s, bb, contacts.cell<D>(k, CONTACT_BEARING_POINT), -f * g.turn_bearing,
                     args.offsets);
      double power = (f - f_el) * g.rate;
      if (contacts(k, CONTACT_FRICTION_ON) > 0.0
          and static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) != NO_FRICTION)
      {
        const V c = g.point;
        const V vc = sub(K::material_velocity(s, bj, c), K::material_velocity(s, bb, c));
        const Friction r = contact_friction(args, w, k, f_n, g.normal, vc, y, dy,
                                            static_cast<std::ptrdiff_t>(contacts(k, CONTACT_STATE)),
                                            g.at_journal, g.delta);
        w.friction[k] = r.size;
        K::push(w.force, s, bj, r.force, c, args.offsets);
        K::push(w.force, s, bb, negated(r.force), c, args.offsets);
        power += r.power;
      }
      return power;
    }
    else
      return 0.0;
  }

  /// A continuous RADIAL, AXIS_RADIAL or PLANE contact's forces: its dissipated power (NaN
  /// beyond its law's table; 0 when open).
  static double point_contact(const Args& args, const Work& w, std::span<const double> y,
                              std::span<double> dy, std::ptrdiff_t k, double speed)
  {
    const Rows& contacts = args.contacts;
    const Matrix<double>& s = w.bodies;
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    double delta, rate;
    V n, c, v, xj, xb;
    bool at_contact;
    if (static_cast<int>(contacts(k, CONTACT_KIND)) == PLANE)
    {
      const Plane p = plane_geometry(s, contacts, k);
      delta = p.delta, n = p.normal, rate = p.rate, c = p.point, v = p.relative;
      xj = c, xb = c, at_contact = true;
    }
    else
    {
      const Radial g = radial_geometry(args, s, k);
      delta = g.delta, n = g.normal, rate = g.rate, c = g.point, v = g.relative;
      xj = g.at_journal, xb = g.at_bearing, at_contact = contacts(k, CONTACT_AT_CONTACT) > 0.0;
      if (g.worn)
        return worn_contact(args, w, y, dy, k, speed, g);
    }
    if (delta <= 0.0)
      return 0.0;
    const double f_el = elastic_force(args, k, delta);
    const double f_n = laws::hysteresis_force(f_el, rate, speed, contact_chi(contacts, k, speed));
    if (not std::isfinite(f_n))
      return NaN;
    w.normal[k] = f_n;
    const auto index = static_cast<std::ptrdiff_t>(contacts(k, CONTACT_STATE));
    const bool rubbing = contacts(k, CONTACT_FRICTION_ON) > 0.0
                         and static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) != NO_FRICTION;
    if (at_contact)
    {
      double power = (f_n - f_el) * rate;
      V f = scaled(n, -f_n);
      if (rubbing or D == 2)
      {
        const Friction r = contact_friction(args, w, k, f_n, n, v, y, dy, index, xj, delta);
        w.friction[k] = r.size;
        f = add(f, r.force);
        power = power + r.power;
      }
      K::push(w.force, s, bj, f, c, args.offsets);
      K::push(w.force, s, bb, negated(f), c, args.offsets);
      return power;
    }
    K::push(w.force, s, bj, scaled(n, -f_n), xj, args.offsets);
    K::push(w.force, s, bb, scaled(n, f_n), xb, args.offsets);
    double power = (f_n - f_el) * rate;
    if (rubbing)
    {
      const V vc = sub(K::material_velocity(s, bj, c), K::material_velocity(s, bb, c));
      const Friction r = contact_friction(args, w, k, f_n, n, vc, y, dy, index, xj, delta);
      w.friction[k] = r.size;
      if (r.power != 0.0 or dot(r.force, r.force) > 0.0)
      {
        K::push(w.force, s, bj, r.force, c, args.offsets);
        K::push(w.force, s, bb, negated(r.force), c, args.offsets);
        power += r.power;
      }
    }
    return power;
  }

  /// Friction at a contact point: in the plane along its tangent, in space against the
  /// slip with a state law's state following the normal's turn (normal_spin).
  static Friction contact_friction(const Args& args, const Work& w, std::ptrdiff_t k, double f_n,
                                   const V& n, const V& v, std::span<const double> y,
                                   std::span<double> dy, std::ptrdiff_t index, const V& xj,
                                   double delta)
  {
    if constexpr (D == 2)
      return planar_friction(args.contacts, k, f_n, n, v, y, dy, index);
    else
      return spatial_friction(w.bodies, args.contacts, k, f_n, n, v, y, dy, index,
                              normal_spin(w.bodies, args.contacts, k, n, xj, delta), 1.0);
  }

  /// Every continuous contact's forces; per contact its normal and friction forces; the
  /// power dissipated, summed joint by joint (NaN beyond a law's table).
  static double contact_forces(const Args& args, const Work& w, std::span<const double> y,
                               std::span<double> dy)
  {
    const Rows& contacts = args.contacts;
    for (std::size_t k = 0; k < w.normal.size(); ++k)
      w.normal[k] = w.friction[k] = 0.0;
    double dissipation = 0.0, joint_power = 0.0;
    for (std::ptrdiff_t k = 0; k < contacts.rows; ++k)
    {
      if (static_cast<int>(contacts(k, CONTACT_IMPACT)) == CONTINUOUS)
      {
        double p;
        if (static_cast<int>(contacts(k, CONTACT_KIND)) == SLICED)
        {
          if constexpr (D == 3)
          {
            const Sliced r = sliced_forces(args, w, y, dy, k, true);
            w.normal[k] = r.normal;
            w.friction[k] = r.tangential;
            p = r.power;
          }
          else
            p = 0.0;
        }
        else
          p = point_contact(args, w, y, dy, k, args.speeds[k]);
        if (not std::isfinite(p))
          return NaN;
        joint_power += p;
      }
      if (k + 1 == contacts.rows or contacts(k + 1, CONTACT_JOINT) != contacts(k, CONTACT_JOINT))
      {
        dissipation += joint_power;
        joint_power = 0.0;
      }
    }
    return dissipation;
  }

  // ---- friction in space
  /// The normal's turn against the bearing body of a point contact in space (a state law
  /// needs it; zero for a face and for the static laws).
  static V normal_spin(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k, const V& n,
                       const V& x, double delta)
  {
    if (static_cast<int>(contacts(k, CONTACT_KIND)) == PLANE
        or static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) <= LINEAR)
      return zero<D>();
    const V w = sub(K::material_velocity(s, body(contacts, k, CONTACT_JOURNAL_BODY), x),
                    K::material_velocity(s, body(contacts, k, CONTACT_BEARING_BODY), x));
    return scaled(sub(w, scaled(n, dot(n, w))), 1.0 / (delta + contacts(k, CONTACT_CLEARANCE)));
  }

  static V state_vector(const Matrix<double>& s, std::int64_t bb, std::span<const double> y,
                        std::ptrdiff_t i)
  {
    return K::turned(s, bb, V{y[i], y[i + 1], y[i + 2]});
  }

  /// Friction at a contact in space: the slip v - n (v.n) and the law's force against it; a
  /// state law's state a vector in the bearing body's frame, of which the tangent part acts
  /// (its rate gains -n (spin.z), which keeps it tangent); a slice's Iwan element carries its
  /// `share` of k1, k2. (force on the journal, power, the force's size).
  static Friction spatial_friction(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k,
                                   double f_n, const V& n, const V& v, std::span<const double> y,
                                   std::span<double> dy, std::ptrdiff_t index, const V& spin,
                                   double share)
  {
    const int law = static_cast<int>(contacts(k, CONTACT_FRICTION_LAW));
    const V slip = sub(v, scaled(n, dot(v, n)));
    const double speed = std::sqrt(dot(slip, slip));
    if (law <= LINEAR)
    {
      if (speed > 0.0)
      {
        const double f_t = scalar_friction(contacts.row(k), f_n, speed, 0.0).first;
        return {scaled(slip, -f_t / speed), f_t * speed, f_t};
      }
      return {zero<D>(), 0.0, 0.0};
    }
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY);
    const std::ptrdiff_t state = law == IWAN ? index + 3 * STATE_STRETCH : index;
    V z = state_vector(s, bb, y, state);
    z = sub(z, scaled(n, dot(z, n)));
    V rate, f;
    if (law == LUGRE)
    {
      const double sigma0 = contacts(k, LUGRE_SIGMA0);
      const double g = laws::lugre_g(speed, contacts(k, LUGRE_MU_COULOMB), contacts(k, LUGRE_MU_STATIC),
                                     contacts(k, LUGRE_STRIBECK_SPEED));
      rate = sub(slip, scaled(z, sigma0 * speed / g));
      f = scaled(add(add(scaled(z, sigma0), scaled(rate, contacts(k, LUGRE_SIGMA1))),
                     scaled(slip, contacts(k, LUGRE_SIGMA2))),
                 f_n);
      rate = sub(rate, scaled(n, dot(spin, z)));
    }
    else if (law == DAHL)
    {
      const double mu = contacts(k, DAHL_MU);
      rate = sub(scaled(sub(slip, scaled(z, speed / mu)), contacts(k, DAHL_SIGMA)),
                 scaled(n, dot(spin, z)));
      f = scaled(z, f_n);
    }
    else   // IWAN: travel then stretch
    {
      const double k1 = share * contacts(k, IWAN_K1);
      const double limit = contacts(k, IWAN_MU) * f_n / k1;
      V travel = state_vector(s, bb, y, index);
      travel = sub(travel, scaled(n, dot(travel, n)));
      const double size = std::sqrt(dot(z, z));
      rate = slip;
      if (size >= limit and dot(z, slip) > 0.0)
        rate = sub(slip, scaled(z, dot(z, slip) / (size * size)));
      const V held = size > limit ? scaled(z, limit / size) : z;
      f = add(scaled(held, k1), scaled(travel, share * contacts(k, IWAN_K2)));
      rate = sub(rate, scaled(n, dot(spin, z)));
      const V moved = K::unturned(s, bb, sub(slip, scaled(n, dot(spin, travel))));
      dy[index] = moved[0], dy[index + 1] = moved[1], dy[index + 2] = moved[2];
    }
    const V moved = K::unturned(s, bb, rate);
    dy[state] = moved[0], dy[state + 1] = moved[1], dy[state + 2] = moved[2];
    return {negated(f), dot(f, slip), std::sqrt(dot(f, f))};
  }

  /// The Iwan slider of a contact point held to its strength after a step (in the plane a
  /// float, in space the size of the stretch's tangent part; a slice's k1 its `share`):
  /// whether it moved.
  static bool iwan_return(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k,
                          double f_n, const V& n, std::span<double> y, std::ptrdiff_t index,
                          double share)
  {
    if constexpr (D == 2)
    {
      const std::ptrdiff_t stretch = index + STATE_STRETCH;
      const double held = laws::iwan_return_map(y[stretch], contacts(k, IWAN_K1),
                                                contacts(k, IWAN_MU) * f_n);
      if (held != y[stretch])
      {
        y[stretch] = held;
        return true;
      }
      return false;
    }
    else
    {
      const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY);
      const std::ptrdiff_t stretch = index + 3 * STATE_STRETCH;
      const V z = state_vector(s, bb, y, stretch);
      const V tangential = sub(z, scaled(n, dot(z, n)));
      const double size = std::sqrt(dot(tangential, tangential));
      const double limit = contacts(k, IWAN_MU) * f_n / (share * contacts(k, IWAN_K1));
      if (size <= limit)
        return false;
      const V held = K::unturned(s, bb, scaled(tangential, limit / size));
      y[stretch] = held[0], y[stretch + 1] = held[1], y[stretch + 2] = held[2];
      return true;
    }
  }

  // ---- a journal along its bore (space only)
  struct Bore
  {
    V pj, uj, ub, a0, a1;
  };

  /// A SLICED contact in its bore's section: the journal's point and axis, the bore's axis,
  /// the mid-plane eccentricity a0 and the lean a1 (their parts normal to u_b).
  static Bore bore_section(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k)
  {
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    const V bp = contacts.cell<D>(k, CONTACT_BEARING_POINT), jp = contacts.cell<D>(k, CONTACT_JOURNAL_POINT);
    const V pb = K::point_state(s, bb, bp).position;
    const V ub = K::vector_state(s, bb, bp, contacts.cell<D>(k, CONTACT_BEARING_AXIS)).value;
    const V pj = K::point_state(s, bj, jp).position;
    const V uj = K::vector_state(s, bj, jp, contacts.cell<D>(k, CONTACT_JOURNAL_AXIS)).value;
    const V e = sub(pj, pb), lean = sub(uj, ub);
    return {pj, uj, ub, sub(e, scaled(ub, dot(e, ub))), sub(lean, scaled(ub, dot(lean, ub)))};
  }

  static double end_offset(const Rows& contacts, std::ptrdiff_t k)
  {
    const auto slices = static_cast<long>(contacts(k, CONTACT_SLICES));
    return laws::slice_geometry(slices - 1, contacts(k, CONTACT_LENGTH), slices, 0.0).offset;
  }

  static double slice_rate(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k,
                           const V& n, const V& x, const V& b)
  {
    return dot(n, sub(K::material_velocity(s, body(contacts, k, CONTACT_JOURNAL_BODY), x),
                      K::material_velocity(s, body(contacts, k, CONTACT_BEARING_BODY), b)));
  }

  /// A unit vector normal to the unit vector u (across the axis of u's smallest component).
  static V perpendicular(const V& u)
  {
    const double a0 = std::abs(u[0]), a1 = std::abs(u[1]), a2 = std::abs(u[2]);
    const V helper = a0 <= a1 and a0 <= a2 ? V{1.0, 0.0, 0.0}
                                           : (a1 <= a2 ? V{0.0, 1.0, 0.0} : V{0.0, 0.0, 1.0});
    const V f = cross(u, helper);
    return scaled(f, 1.0 / std::sqrt(dot(f, f)));
  }

  struct Frame
  {
    V f, g;
    double ax, ay, bx, by;
  };
  /// The bore's section in 2D: f along a0 (where the journal is off centre), g = u_b x f.
  static Frame section_frame(const V& ub, const V& a0, const V& a1)
  {
    const double size = std::sqrt(dot(a0, a0));
    const V f = size > 0.0 ? scaled(a0, 1.0 / size) : perpendicular(ub);
    const V g = cross(ub, f);
    return {f, g, dot(a0, f), dot(a0, g), dot(a1, f), dot(a1, g)};
  }

  /// A worn SLICED contact's frames ([theory/wear.md]): the bore's section frame f_b (its
  /// reference direction, CONTACT_BEARING_REFERENCE, turned with the bore), g_b = u_b x f_b;
  /// the pin's angle psi = atan2(f_j . g_b, f_j . f_b) of the journal's reference direction
  /// f_j about the axis and its rate; the axis m = (u_b - (f_j . u_b) f_j) / (1 - (f_j . u_b)^2)
  /// of the pin's turn (d psi = (dtheta_j - dtheta_b) . m of the two bodies' small turns;
  /// u_b for an aligned journal); spin = w_b . u_b = f_b' . g_b.
  struct WornFrame
  {
    V f, g, m;
    double psi, psi_rate, spin;
  };
  static WornFrame worn_frame(const Matrix<double>& s, const Rows& contacts, std::ptrdiff_t k)
  {
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    const V bp = contacts.cell<D>(k, CONTACT_BEARING_POINT), jp = contacts.cell<D>(k, CONTACT_JOURNAL_POINT);
    const auto ub = K::vector_state(s, bb, bp, contacts.cell<D>(k, CONTACT_BEARING_AXIS));
    const auto fb = K::vector_state(s, bb, bp, contacts.cell<D>(k, CONTACT_BEARING_REFERENCE));
    const auto fj = K::vector_state(s, bj, jp, contacts.cell<D>(k, CONTACT_JOURNAL_REFERENCE));
    const V g = cross(ub.value, fb.value), g_rate = add(cross(ub.rate, fb.value), cross(ub.value, fb.rate));
    const double a = dot(fj.value, g), b = dot(fj.value, fb.value);
    const double a_rate = dot(fj.rate, g) + dot(fj.value, g_rate),
                 b_rate = dot(fj.rate, fb.value) + dot(fj.value, fb.rate);
    const double lean = dot(fj.value, ub.value), across = 1.0 - lean * lean;
    return {fb.value, g, scaled(sub(ub.value, scaled(fj.value, lean)), 1.0 / across), std::atan2(a, b),
            (b * a_rate - a * b_rate) / (a * a + b * b), dot(fb.rate, g)};
  }

  /// Slice z of a worn SLICED contact: its section (worn_section) at e_i = a0 + z a1 in the
  /// bore's frame (e . f_b, e . g_b; phi_b = 0, phi_j = psi), the journal's axis point
  /// X = P_j + z u_j, its foot B = X - e_i on the bore's axis, the normal n in space and the
  /// rate d delta_p / dt = reach n . (v_J(X) - v_B(B)) + (turn_b + turn_j) w_b . u_b
  /// + turn_j psi' (the section's angles turn with the bore: e's frame at w_b . u_b, the pin
  /// at psi' against it); the deepest overlap's rate likewise.
  struct WornSlice
  {
    WornSection section;
    V normal, x, b;
    double rate, approach;   // d delta_p / dt; the deepest overlap's rate
  };
  static WornSlice worn_slice(const Args& args, const Matrix<double>& s, std::ptrdiff_t k,
                              const Bore& bore, const WornFrame& fr, double z)
  {
    const Rows& contacts = args.contacts;
    const V e = add(bore.a0, scaled(bore.a1, z));
    const WornSection ws = worn_section(args, k, {dot(e, fr.f), dot(e, fr.g)}, 0.0, fr.psi);
    const V n = add(scaled(fr.f, ws.normal[0]), scaled(fr.g, ws.normal[1]));
    const V x = add(bore.pj, scaled(bore.uj, z)), b = sub(x, e);
    const V a = add(scaled(fr.f, ws.approach[0]), scaled(fr.g, ws.approach[1]));
    return {ws, n, x, b,
            ws.reach * slice_rate(s, contacts, k, n, x, b) + (ws.turn_bearing + ws.turn_journal) * fr.spin
                + ws.turn_journal * fr.psi_rate,
            slice_rate(s, contacts, k, a, x, b) + (ws.approach_bearing + ws.approach_journal) * fr.spin
                + ws.approach_journal * fr.psi_rate};
  }

  /// The deepest slice (an end slice) with the bore unmoved, and its approach rate. A worn
  /// contact's too: each angle's overlap is linear in z along the journal, so the overlap's
  /// moment (a convex function of z) and its deepest point are largest at an end.
  static Depth sliced_depth(const Args& args, const Matrix<double>& s, std::ptrdiff_t k)
  {
    const Rows& contacts = args.contacts;
    const Bore bore = bore_section(s, contacts, k);
    double zz = end_offset(contacts, k);
    if (is_worn(contacts, k))
    {
      const WornFrame fr = worn_frame(s, contacts, k);
      const WornSlice plus = worn_slice(args, s, k, bore, fr, zz), minus = worn_slice(args, s, k, bore, fr, -zz);
      const WornSlice& deeper = minus.section.delta > plus.section.delta ? minus : plus;
      return {deeper.section.delta, deeper.approach, deeper.normal};
    }
    V plus = add(bore.a0, scaled(bore.a1, zz));
    const V minus = sub(bore.a0, scaled(bore.a1, zz));
    if (dot(minus, minus) > dot(plus, plus))
      zz = -zz, plus = minus;
    const double size = std::sqrt(dot(plus, plus));
    const V n = size > 0.0 ? scaled(plus, 1.0 / size) : axis<D>(0);
    const V x = add(bore.pj, scaled(bore.uj, zz));
    return {size - contacts(k, CONTACT_CLEARANCE), slice_rate(s, contacts, k, n, x, sub(x, plus)), n};
  }

  static laws::Section section(const Args& args, std::ptrdiff_t k, const Frame& fr)
  {
    const Rows& c = args.contacts;
    const auto table = static_cast<std::ptrdiff_t>(c(k, CONTACT_TABLE));
    return {fr.ax, fr.ay, fr.bx, fr.by, c(k, CONTACT_CLEARANCE), false, c(k, CONTACT_LENGTH),
            static_cast<long>(c(k, CONTACT_SLICES)), args.grid_log0, args.grid_step,
            args.tables.row(table), static_cast<std::size_t>(args.tables.cols)};
  }

  struct Sliced
  {
    double normal, power, tangential;
  };

  /// Each slice's approach (a worn slice's penetration delta_p,i, worn_slice) and weight
  /// a w_i (m), the potential's sum U = sum a w_i U_loc(delta_i) plus the bore's bulk
  /// compliance; returns the bore's displacement d (global).
  static V slice_penetrations(const Args& args, const Matrix<double>& s, std::ptrdiff_t k,
                              std::span<double> approaches, std::span<double> weights)
  {
    const Rows& contacts = args.contacts;
    const Bore bore = bore_section(s, contacts, k);
    const Frame fr = section_frame(bore.ub, bore.a0, bore.a1);
    const laws::Section sec = section(args, k, fr);
    const double scale = contacts(k, CONTACT_SCALE), end_length = contacts(k, CONTACT_END_LENGTH);
    const auto [dx, dy] = laws::bore_displacement(sec, end_length, scale, contacts(k, CONTACT_COMPLIANCE));
    const bool worn = is_worn(contacts, k);
    const WornFrame wf = worn ? worn_frame(s, contacts, k) : WornFrame{};
    for (long i = 0; i < sec.slices; ++i)
    {
      const auto at = static_cast<std::size_t>(i);
      approaches[at] = worn ? worn_slice(args, s, k, bore, wf, laws::slice_geometry(i, sec.length, sec.slices, 0.0).offset).section.delta
                            : laws::slice_contact(i, dx, dy, sec).approach;
      weights[at] = scale * laws::slice_geometry(i, sec.length, sec.slices, end_length).weight;
    }
    return add(scaled(fr.f, dx), scaled(fr.g, dy));
  }

  /// A journal along its bore, cut into n slices (laws::slice_geometry: offset z_i from the
  /// mid-plane, weight w_i = L/n + e at each end slice). At slice i the journal's axis point
  /// X_i = P_j + z_i u_j is off the bore's axis by e_i across it: delta_i = |e_i| - c along
  /// n_i. Each slice carries a f_el(delta_i) (1 + chi delta_i'/v0) w_i, -f n_i on the journal at
  /// X_i and +f n_i on the bore at B_i = X_i - e_i, its point on the bore's axis (the pair has
  /// no moment, delta_i' = n_i . (v_J(X_i) - v_B(B_i)) exactly); friction acts at
  /// C_i = B_i + R_b n_i. With a bulk compliance the bore's axis first moves across by d
  /// (laws::bore_displacement) and the slices see e_i - d. The deepest slice is an end slice:
  /// a journal whose end slices are free skips the slices.
  /// A worn journal's slice (worn_slice: its section in the bore's frame, the profiles
  /// extruded along the axis) carries f = a f_el(delta_p,i) (1 + chi delta_p,i'/v0) w_i, the
  /// force f reach_i along n_i as above and the torques -f turn_j m on the journal and
  /// -f (turn_b u_b + turn_j (u_b - m)) on the bore: the force of the potential of delta_p,i
  /// (an elastic contact keeps the energy book); its bore takes no bulk compliance.
  /// apply = false: the forces are not pushed, only the slices' Iwan sliders held (in dy,
  /// the state y itself).
  static Sliced sliced_forces(const Args& args, const Work& w, std::span<const double> y,
                              std::span<double> dy, std::ptrdiff_t k, bool apply)
  {
    const Rows& contacts = args.contacts;
    const Matrix<double>& s = w.bodies;
    Sliced out{0.0, 0.0, 0.0};
    const Bore bore = bore_section(s, contacts, k);
    const double zz = end_offset(contacts, k);
    const V plus = add(bore.a0, scaled(bore.a1, zz)), minus = sub(bore.a0, scaled(bore.a1, zz));
    const double clearance = contacts(k, CONTACT_CLEARANCE);
    const bool worn = is_worn(contacts, k);
    const double free = clearance + (worn ? worn_lowest(args, k) : 0.0);
    if (std::max(dot(plus, plus), dot(minus, minus)) <= free * free and free >= 0.0)
      return out;
    const Frame fr = section_frame(bore.ub, bore.a0, bore.a1);
    const laws::Section sec = section(args, k, fr);
    const double length = contacts(k, CONTACT_LENGTH), scale = contacts(k, CONTACT_SCALE),
                 end_length = contacts(k, CONTACT_END_LENGTH);
    const auto [dx, dy_] = laws::bore_displacement(sec, end_length, scale, contacts(k, CONTACT_COMPLIANCE));
    if (not std::isfinite(dx))
      return {NaN, NaN, NaN};
    const WornFrame wf = worn ? worn_frame(s, contacts, k) : WornFrame{};
    const std::int64_t bb = body(contacts, k, CONTACT_BEARING_BODY),
                       bj = body(contacts, k, CONTACT_JOURNAL_BODY);
    const double speed = args.speeds[k];
    const double chi = contact_chi(contacts, k, speed);
    const auto index = static_cast<std::ptrdiff_t>(contacts(k, CONTACT_STATE));
    const int law = static_cast<int>(contacts(k, CONTACT_FRICTION_LAW));
    const std::ptrdiff_t per_slice = index < 0 ? 0 : (law == IWAN ? 6 : 3);
    const double total = length + 2.0 * end_length;
    for (long i = 0; i < sec.slices; ++i)
    {
      const double weight = laws::slice_geometry(i, length, sec.slices, end_length).weight;
      V n, x, b;
      double f_el, rate, arm;   // arm: |X_i - B_i|
      WornSection ws{};
      if (worn)
      {
        const WornSlice slice = worn_slice(args, s, k, bore, wf, laws::slice_geometry(i, length, sec.slices, 0.0).offset);
        ws = slice.section;
        if (ws.delta <= 0.0)
          continue;
        n = slice.normal, x = slice.x, b = slice.b, rate = slice.rate, arm = norm(sub(x, b));
        f_el = scale * weight * elastic_force(args, k, ws.delta);
      }
      else
      {
        const laws::SliceContact sc = laws::slice_contact(i, dx, dy_, sec);
        if (sc.approach <= 0.0)
          continue;
        n = add(scaled(fr.f, sc.nx), scaled(fr.g, sc.ny));
        x = add(bore.pj, scaled(bore.uj, sc.offset));
        arm = sc.approach + clearance;
        b = sub(x, scaled(n, arm));
        f_el = scale * weight * sc.force;
        rate = slice_rate(s, contacts, k, n, x, b);
      }
      const double f = laws::hysteresis_force(f_el, rate, speed, chi);
      const double f_n = f * ws.reach;   // the force between X_i and B_i
      const std::ptrdiff_t state = index + i * per_slice;
      const V c = add(b, scaled(n, contacts(k, CONTACT_RADIUS)));
      if (not apply)
      {
        if (law == IWAN)
          iwan_return(s, contacts, k, f_n, n, dy, state, weight / total);
        continue;
      }
      K::push(w.force, s, bj, scaled(n, -f_n), x, args.offsets);
      K::push(w.force, s, bb, scaled(n, f_n), b, args.offsets);
      if (worn)
      {
        K::push_torque(w.force, s, bj, contacts.cell<D>(k, CONTACT_JOURNAL_POINT),
                       scaled(wf.m, -f * ws.turn_journal), args.offsets);
        K::push_torque(w.force, s, bb, contacts.cell<D>(k, CONTACT_BEARING_POINT),
                       scaled(add(scaled(bore.ub, ws.turn_bearing), scaled(sub(bore.ub, wf.m), ws.turn_journal)), -f),
                       args.offsets);
      }
      double p = (f - f_el) * rate;
      if (law != NO_FRICTION)
      {
        const V v = sub(K::material_velocity(s, bj, c), K::material_velocity(s, bb, c));
        V spin = zero<D>();
        if (law > LINEAR)
        {
          V wv = sub(K::material_velocity(s, bj, x), K::material_velocity(s, bb, x));
          wv = sub(wv, add(scaled(n, dot(n, wv)), scaled(bore.ub, dot(bore.ub, wv))));
          spin = scaled(wv, 1.0 / arm);
        }
        const Friction r = spatial_friction(s, contacts, k, f_n, n, v, y, dy, state, spin,
                                            weight / total);
        out.tangential += r.size;
        if (r.power != 0.0 or dot(r.force, r.force) > 0.0)
        {
          K::push(w.force, s, bj, r.force, c, args.offsets);
          K::push(w.force, s, bb, negated(r.force), c, args.offsets);
          p += r.power;
        }
      }
      out.normal += f_n;
      out.power += p;
    }
    return out;
  }

  // ---- torsion elements, spring-dampers, loads
  /// Torque of a torsion spring, stop or latch beyond its free angle, and its damper's power.
  static std::pair<double, double> torsion_law(double angle, double rate, const double* row,
                                               bool latched)
  {
    const int kind = static_cast<int>(row[TORSION_KIND]);
    const double stiffness = row[TORSION_STIFFNESS], damping = row[TORSION_DAMPING];
    if (kind == LATCH)
    {
      if (latched)
        return {-stiffness * angle - damping * rate, damping * rate * rate};
      return {0.0, 0.0};
    }
    if (kind == STOP and angle <= 0.0)
      return {0.0, 0.0};
    const double torque = -stiffness * angle - damping * rate;
    if (kind == STOP and torque > 0.0)
      return {0.0, -stiffness * angle * rate};
    return {torque, damping * rate * rate};
  }

  static std::pair<double, double> torsion_angle(const Matrix<double>& s, const Rows& tor,
                                                 std::ptrdiff_t r)
  {
    const auto rot = K::relative_rotation(
        s, static_cast<std::int64_t>(tor(r, TORSION_BODY_I)),
        static_cast<std::int64_t>(tor(r, TORSION_BODY_J)), tor.cell<D>(r, TORSION_S_I),
        tor.cell<D>(r, TORSION_S_J), tor.cell<D>(r, TORSION_A_I), tor.cell<D>(r, TORSION_B_J),
        tor.cell<D>(r, TORSION_C_I), tor(r, TORSION_FREE_ANGLE), 0.0);
    return {rot.angle, rot.rate};
  }

  static double torsion_forces(const Args& args, const Work& w, double dissipation)
  {
    const Rows& tor = args.torsion;
    for (std::ptrdiff_t r = 0; r < tor.rows; ++r)
    {
      const auto [angle, rate] = torsion_angle(w.bodies, tor, r);
      const auto [torque, power] = torsion_law(angle, rate, tor.row(r), args.latched[r] > 0);
      const V s_i = tor.cell<D>(r, TORSION_S_I), s_j = tor.cell<D>(r, TORSION_S_J);
      const auto bi = static_cast<std::int64_t>(tor(r, TORSION_BODY_I));
      const auto bj = static_cast<std::int64_t>(tor(r, TORSION_BODY_J));
      const Ang u = K::rotation_axis(w.bodies, bi, s_i, tor.cell<D>(r, TORSION_A_I),
                                     tor.cell<D>(r, TORSION_C_I));
      K::push_torque(w.force, w.bodies, bj, s_j, scaled(u, torque), args.offsets);
      K::push_torque(w.force, w.bodies, bi, s_i, scaled(u, -torque), args.offsets);
      dissipation += power;
    }
    return dissipation;
  }

  struct Ends
  {
    V x_i, v_i, x_j, v_j;
    double length;
  };
  static Ends spring_ends(const Matrix<double>& s, const Rows& springs, std::ptrdiff_t r)
  {
    const auto pi = K::point_state(s, static_cast<std::int64_t>(springs(r, SPRING_BODY_I)),
                                   springs.cell<D>(r, SPRING_S_I));
    const auto pj = K::point_state(s, static_cast<std::int64_t>(springs(r, SPRING_BODY_J)),
                                   springs.cell<D>(r, SPRING_S_J));
    return {pi.position, pi.velocity, pj.position, pj.velocity, norm(sub(pj.position, pi.position))};
  }

  static double spring_forces(const Args& args, const Work& w, double dissipation)
  {
    const Rows& sp = args.springs;
    for (std::ptrdiff_t r = 0; r < sp.rows; ++r)
    {
      const auto bi = static_cast<std::int64_t>(sp(r, SPRING_BODY_I));
      const auto bj = static_cast<std::int64_t>(sp(r, SPRING_BODY_J));
      const Ends e = spring_ends(w.bodies, sp, r);
      if (e.length == 0.0)
        continue;
      const V n = scaled(sub(e.x_j, e.x_i), 1.0 / e.length);
      const double rate = dot(n, sub(e.v_j, e.v_i));
      const double tension = sp(r, SPRING_STIFFNESS) * (e.length - sp(r, SPRING_LENGTH))
                             + sp(r, SPRING_DAMPING) * rate;
      K::push(w.force, w.bodies, bj, scaled(n, -tension), e.x_j, args.offsets);
      K::push(w.force, w.bodies, bi, scaled(n, tension), e.x_i, args.offsets);
      dissipation += sp(r, SPRING_DAMPING) * rate * rate;
    }
    return dissipation;
  }

  static Ang angular_cell(const Rows& a, std::ptrdiff_t r, int i, double k)
  {
    if constexpr (D == 2)
      return k * a(r, i + 2);
    else
      return Vec3{k * a(r, i), k * a(r, i + 1), k * a(r, i + 2)};
  }

  static double load_forces(double t, const Args& args, const Work& w)
  {
    double power = 0.0;
    const Rows& loads = args.loads;
    for (std::ptrdiff_t r = 0; r < loads.rows; ++r)
    {
      const auto b = static_cast<std::int64_t>(loads(r, LOAD_BODY));
      if (b < 0)
        continue;
      const double c = std::cos(loads(r, LOAD_OMEGA) * t + loads(r, LOAD_PHASE));
      const V s = loads.cell<D>(r, LOAD_POINT);
      const V x = K::point_state(w.bodies, b, s).position;
      for (std::ptrdiff_t col = args.offsets[b]; col < args.offsets[b + 1]; ++col)
        power -= w.force[col] * w.velocities[col];
      K::push(w.force, w.bodies, b, scaled(loads.cell<D>(r, LOAD_FORCE), c), x, args.offsets);
      K::push_torque(w.force, w.bodies, b, s, angular_cell(loads, r, LOAD_TORQUE, c), args.offsets);
      for (std::ptrdiff_t col = args.offsets[b]; col < args.offsets[b + 1]; ++col)
        power += w.force[col] * w.velocities[col];
    }
    return power;
  }

  // ---- the equations of motion
  /// M^-1 D^T into mjac and the lower triangle of D M^-1 D^T within the envelope.
  static void fill_schur(const Args& args, const Work& w, std::ptrdiff_t m)
  {
    for (std::ptrdiff_t i = 0; i < m; ++i)
      for (int side = 0; side < 2; ++side)
      {
        const std::int64_t b = w.row_bodies(i, side);
        if (b >= 0)
          K::mass_rows(args, w, i, b);
      }
    for (std::ptrdiff_t i = 0; i < m; ++i)
      for (std::ptrdiff_t k = w.first[i]; k <= i; ++k)
      {
        double v = 0.0;
        for (int side = 0; side < 2; ++side)
        {
          const std::int64_t b = w.row_bodies(i, side);
          if (b >= 0 and (b == w.row_bodies(k, 0) or b == w.row_bodies(k, 1)))
            for (std::ptrdiff_t c = args.offsets[b]; c < args.offsets[b + 1]; ++c)
              v += K::MASS_LEFT ? w.mjac(i, c) * w.jac(k, c) : w.jac(i, c) * w.mjac(k, c);
        }
        w.schur(i, k) = v;
      }
  }

  /// Solve the Schur system for the multipliers, take D^T lambda from the forces; returns
  /// the power of the constraint forces.
  static double constrained_forces(const Args& args, const Work& w, std::ptrdiff_t m)
  {
    for (std::ptrdiff_t i = 0; i < m; ++i)
    {
      double v = -w.rhs_c[i];
      for (int side = 0; side < 2; ++side)
      {
        const std::int64_t b = w.row_bodies(i, side);
        if (b >= 0)
          for (std::ptrdiff_t c = args.offsets[b]; c < args.offsets[b + 1]; ++c)
            v += w.mjac(i, c) * w.force[c];
      }
      w.rhs_c[i] = v;
    }
    cholesky_solve(w.schur, w.rhs_c, m, w.first);
    double work_in = 0.0;
    for (std::ptrdiff_t i = 0; i < m; ++i)
    {
      for (int side = 0; side < 2; ++side)
      {
        const std::int64_t b = w.row_bodies(i, side);
        if (b >= 0)
          for (std::ptrdiff_t c = args.offsets[b]; c < args.offsets[b + 1]; ++c)
            w.force[c] -= w.jac(i, c) * w.rhs_c[i];
      }
      work_in += w.rhs_c[i] * w.phi_t[i];
    }
    return work_in;
  }

  static void refresh(const Args& args, std::span<const double> y, const Work& w)
  {
    K::body_states(args, y, w);
  }

  /// dy = f(t, y).
  static void rhs(double t, std::span<const double> y, std::span<double> dy, const Args& args,
                  const Work& w)
  {
    const std::ptrdiff_t nq = args.nq;
    K::body_states(args, y, w);
    const double damping = K::body_forces(args, w);
    for (std::ptrdiff_t i = 2 * nq + ENERGY_STATES; i < static_cast<std::ptrdiff_t>(y.size()); ++i)
      dy[i] = 0.0;
    double dissipation = contact_forces(args, w, y, dy);
    if (not std::isfinite(dissipation))
    {
      for (double& d : dy)
        d = NaN;
      return;
    }
    dissipation = torsion_forces(args, w, dissipation);
    dissipation = spring_forces(args, w, dissipation);
    dissipation += damping;
    const double loaded = load_forces(t, args, w);
    const std::ptrdiff_t m = constraint_rows(t, args, w, args.baumgarte, args.mode);
    double work_in = 0.0;
    if (m > 0)
    {
      fill_schur(args, w, m);
      work_in = constrained_forces(args, w, m);
      std::ptrdiff_t row = m;
      for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
        row -= args.mode[k];
      for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
        if (args.mode[k] == 1)
          w.normal[k] = w.rhs_c[row++];
    }
    K::state_rates(args, y, dy, w);
    dy[2 * nq + DISSIPATED] = dissipation;
    dy[2 * nq + WORK_IN] = work_in + loaded;
  }

  // ---- impacts and the projection onto the constraints
  static std::ptrdiff_t fill_constraints(double t, const Args& args, const Work& w, double alpha)
  {
    return constraint_rows(t, args, w, alpha, args.mode);
  }

  static void solve_rows(const Args& args, const Work& w, std::ptrdiff_t m)
  {
    fill_schur(args, w, m);
    cholesky_solve(w.schur, w.rhs_c, m, w.first);
  }

  struct Impulse
  {
    double impulse, dissipated, work_in;
  };

  /// Impact of impulse contact k: the velocity jump of least kinetic-energy change that keeps
  /// the constraints and leaves the approach rate at -e v (Newton; Poisson: e times the
  /// compression impulse).
  static Impulse apply_impulse(double t, std::span<double> y, const Args& args, const Work& w,
                               std::ptrdiff_t k, double target_restitution)
  {
    refresh(args, y, w);
    const double rate = contact_depth(args, w.bodies, k).rate;
    const double before = K::kinetic_energy(args, y);
    const std::int64_t held = args.mode[k];
    args.mode[k] = 1;
    const std::ptrdiff_t m = fill_constraints(t, args, w, 0.0);
    args.mode[k] = held;
    std::ptrdiff_t row = constraint_count(args.primitives);
    for (std::ptrdiff_t j = 0; j < k; ++j)
      row += args.mode[j];
    const bool poisson = static_cast<int>(args.contacts(k, CONTACT_IMPACT)) == POISSON;
    const double e = target_restitution;
    for (std::ptrdiff_t i = 0; i < m; ++i)
      w.rhs_c[i] = 0.0;
    w.rhs_c[row] = poisson ? rate : (1.0 + e) * rate;
    solve_rows(args, w, m);
    const double scale = poisson ? (1.0 + e) : 1.0;
    K::velocity_step(args, y, w, w.rhs_c, m, scale);
    const double after = K::kinetic_energy(args, y);
    double work_in = 0.0;
    for (std::ptrdiff_t i = 0; i < m; ++i)
      work_in += scale * w.rhs_c[i] * w.phi_t[i];
    return {scale * w.rhs_c[row], before - after + work_in, work_in};
  }

  /// One mass-weighted Gauss-Newton step of positions and one of velocities onto the
  /// constraints, each where its residual exceeds its tolerance. Whether one was taken.
  static bool project_onto_constraints(double t, std::span<double> y, const Args& args,
                                       const Work& w, double tolerance, double rate_tolerance)
  {
    K::normalise(args, y);
    bool changed = false;
    std::ptrdiff_t m = 0;
    for (int level = 0; level < 2; ++level)
    {
      if (level == 0 or changed)
      {
        refresh(args, y, w);
        m = fill_constraints(t, args, w, 0.0);
      }
      double largest = 0.0;
      for (std::ptrdiff_t i = 0; i < m; ++i)
      {
        w.rhs_c[i] = level == 0 ? w.phi[i] : constraint_rate(args, w, i);
        largest = std::max(largest, std::abs(w.rhs_c[i]));
      }
      if (largest <= (level == 0 ? tolerance : rate_tolerance))
        continue;
      changed = true;
      solve_rows(args, w, m);
      if (level == 0)
        K::position_step(args, y, w, w.rhs_c, m);
      else
        K::velocity_step(args, y, w, w.rhs_c, m, 1.0);
    }
    if (changed)
      refresh(args, y, w);
    return changed;
  }

  static double impulse_energy(std::span<double> y, std::ptrdiff_t nq, const Impulse& impulse)
  {
    y[2 * nq + DISSIPATED] += impulse.dissipated;
    y[2 * nq + WORK_IN] += impulse.work_in;
    return impulse.impulse;
  }
};

} // namespace pinbore::mechanism
