// Planar bodies: the body kind of a planar mechanism (pinbore.reduced.mechanism.planar states
// the equations). Coordinates q = (x, y, phi) of each body's centre of mass, velocity columns
// (x', y', w), M = diag(m, m, J); a body point s (body frame) is at P = r + A(phi) s. A
// flexible body adds its modal coordinates eta in Buckens' mean-axis frame: a point moves with
// its nearest interface's frame, its mass block [[J(eta), g^T], [g, I]] inverts in closed form.
// What the joints see of a body (a point's and a vector's state, a Jacobian row, a pushed
// force) and what the equations of motion need of it (its forces, the Schur matrix, the
// rates, the projection's steps, its energy). Bodies are numbered from 0; -1 is the ground.
#pragma once

#include "bodies.h"
#include "data.h"

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace pinbore::mechanism
{

struct Planar
{
  static constexpr int D = 2;
  using V = Vec2;
  using A = double;
  // a body's row in Work::bodies (pinbore.reduced.mechanism.planar's layout)
  static constexpr int X = 0, Y = 1, PHI = 2, COS = 3, SIN = 4, VX = 5, VY = 6, W = 7,
                       FIRST = 8, NMODES = 9, NFACES = 10, INERTIA = 11, SIGMA = 12, ETA = 13;
  static constexpr int MODES = 24, INTERFACES = 4;   // at most, a flexible body
  static constexpr int ETA_RATE = ETA + MODES, GVEC = ETA + 2 * MODES, FACES = ETA + 3 * MODES;
  // an interface: its centre x_k, its frame's displacement T_k eta and turn R_k eta, their
  // rates, then the mode shapes T_k (x: MODES, y: MODES) and R_k
  static constexpr int F_CENTRE = 0, F_MOVE = 2, F_TURN = 4, F_MOVE_RATE = 5, F_TURN_RATE = 7,
                       F_T = 8, F_R = 8 + 2 * MODES, FACE = 8 + 3 * MODES;
  static constexpr int BODY_COLUMNS = FACES + INTERFACES * FACE;
  static constexpr int COLUMNS = 3;
  // a flexible body's constants in its row of Args::flex: modes, interfaces, I0, then blocks
  static constexpr int C_MODES = 0, C_FACES = 1, C_I0 = 2;

  using Point = PointState<V>;
  using Vector = VectorState<V>;
  struct Rotation
  {
    double angle, coefficient, rate, centripetal;
  };

  static V arm(const Matrix<double>& s, std::ptrdiff_t b, const V& v)
  {
    const double c = s(b, COS), sn = s(b, SIN);
    return {c * v[0] - sn * v[1], sn * v[0] + c * v[1]};
  }

  /// The first column in Args::flex of a flexible body's constant block (n its modes):
  /// 0 omega^2, 1 the modal damping 2 zeta omega, 2 s1 (n each), 3 the inertia quadratic Q,
  /// 4 the gyroscopic S^ (n x n), 5 the interface k: x_k (2), T_k (x: n, y: n), R_k (n).
  static std::ptrdiff_t flex_column(std::ptrdiff_t n, int block, std::ptrdiff_t k)
  {
    if (block < 3)
      return 3 + block * n;
    if (block < 5)
      return 3 + 3 * n + (block - 3) * n * n;
    return 3 + 3 * n + 2 * n * n + k * (2 + 3 * n);
  }

  static bool flexible(const Matrix<double>& s, std::ptrdiff_t b)
  {
    return b >= 0 and s(b, NMODES) > 0.0;
  }

  /// The column where body b's interface nearest the body point p starts.
  static std::ptrdiff_t face_of(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    double best = std::numeric_limits<double>::infinity();
    std::ptrdiff_t at = FACES;
    for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(s(b, NFACES)); ++k)
    {
      const std::ptrdiff_t f = FACES + k * FACE;
      const double d0 = p[0] - s(b, f), d1 = p[1] - s(b, f + 1);
      const double d = d0 * d0 + d1 * d1;
      if (d < best)
        best = d, at = f;
    }
    return at;
  }

  /// (p + u, u') of the body point p on the interface at column f (body frame).
  static std::pair<V, V> deformed(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t f,
                                  const V& p)
  {
    const double e0 = p[0] - s(b, f), e1 = p[1] - s(b, f + 1);
    const double turn = s(b, f + F_TURN), rate = s(b, f + F_TURN_RATE);
    return {{p[0] + s(b, f + F_MOVE) - turn * e1, p[1] + s(b, f + F_MOVE + 1) + turn * e0},
            {s(b, f + F_MOVE_RATE) - rate * e1, s(b, f + F_MOVE_RATE + 1) + rate * e0}};
  }

  /// The body point whose deformed place is p, from the interface centre, turned back
  /// unscaled, and its factor 1 / (1 + theta^2).
  static std::array<double, 3> undeformed(const Matrix<double>& s, std::ptrdiff_t b,
                                          std::ptrdiff_t f, const V& p)
  {
    const double turn = s(b, f + F_TURN);
    const double e0 = p[0] - s(b, f) - s(b, f + F_MOVE);
    const double e1 = p[1] - s(b, f + 1) - s(b, f + F_MOVE + 1);
    return {e0 + turn * e1, e1 - turn * e0, 1.0 / (1.0 + turn * turn)};
  }

  /// A^T v: a global vector in body b's floating frame.
  static V turned_back(const Matrix<double>& s, std::ptrdiff_t b, const V& v)
  {
    const double c = s(b, COS), sn = s(b, SIN);
    return {c * v[0] + sn * v[1], -sn * v[0] + c * v[1]};
  }

  /// Add sign (l . (T_k,j + R_k,j k x e) + rho R_k,j) to the modal columns of a row.
  static void modal_columns(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>& s,
                            std::ptrdiff_t b, std::ptrdiff_t f, const V& e, const V& l, double rho,
                            double sign, std::ptrdiff_t column)
  {
    const double lk = l[1] * e[0] - l[0] * e[1];
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
    {
      const double r = s(b, f + F_R + j);
      jac(row, column + j) += sign * (l[0] * s(b, f + F_T + j) + l[1] * s(b, f + F_T + MODES + j)
                                      + r * (lk + rho));
    }
  }

  static Point point_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    if (b < 0)
      return {p, {0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
    const double w = s(b, W);
    if (flexible(s, b))   // P = r + A (p + u), P' = r' + w k x A (p + u) + A u'
    {
      const auto [place, rate] = deformed(s, b, face_of(s, b, p), p);
      const V a = arm(s, b, place), v = arm(s, b, rate);
      return {{s(b, X) + a[0], s(b, Y) + a[1]},
              {s(b, VX) - w * a[1] + v[0], s(b, VY) + w * a[0] + v[1]},
              {-(a[0] * w * w) - 2 * w * v[1], -(a[1] * w * w) + 2 * w * v[0]},
              a};
    }
    const V a = arm(s, b, p);
    const double w2 = w * w;
    return {{s(b, X) + a[0], s(b, Y) + a[1]},
            {s(b, VX) - w * a[1], s(b, VY) + w * a[0]},
            {-(a[0] * w2), -(a[1] * w2)},
            a};
  }

  static Vector vector_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p, const V& v)
  {
    if (b < 0)
      return {v, {0.0, 0.0}, {0.0, 0.0}};
    double w = s(b, W);
    if (flexible(s, b))   // turned with the interface's frame by R_k eta
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      const double turn = s(b, f + F_TURN);
      w = w + s(b, f + F_TURN_RATE);
      const double c = std::cos(turn), sn = std::sin(turn);
      const V a = arm(s, b, {c * v[0] - sn * v[1], sn * v[0] + c * v[1]});
      return {a, {-w * a[1], w * a[0]}, {-(a[0] * w * w), -(a[1] * w * w)}};
    }
    const V a = arm(s, b, v);
    const double w2 = w * w;
    return {a, {-w * a[1], w * a[0]}, {-(a[0] * w2), -(a[1] * w2)}};
  }

  static V material_velocity(const Matrix<double>& s, std::ptrdiff_t b, const V& x)
  {
    if (b < 0)
      return {0.0, 0.0};
    const double w = s(b, W);
    const V v{s(b, VX) - w * (x[1] - s(b, Y)), s(b, VY) + w * (x[0] - s(b, X))};
    if (flexible(s, b))
    {
      const V p = turned_back(s, b, {x[0] - s(b, X), x[1] - s(b, Y)});
      const std::ptrdiff_t f = face_of(s, b, p);
      const auto [e0, e1, k] = undeformed(s, b, f, p);
      const double rate = s(b, f + F_TURN_RATE) * k;
      const V u = arm(s, b, {s(b, f + F_MOVE_RATE) - rate * e1, s(b, f + F_MOVE_RATE + 1) + rate * e0});
      return {v[0] + u[0], v[1] + u[1]};
    }
    return v;
  }

  static void put(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>& s,
                  std::ptrdiff_t b, const V& p, const V& linear, double angular, double sign,
                  std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const std::ptrdiff_t c = offsets[b];
    jac(row, c) += sign * linear[0];
    jac(row, c + 1) += sign * linear[1];
    jac(row, c + 2) += sign * angular;
    if (flexible(s, b))
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      const V place = deformed(s, b, f, p).first;
      const V l = turned_back(s, b, linear);
      const double rho = angular - (place[0] * l[1] - place[1] * l[0]);   // less the arm x linear
      modal_columns(jac, row, s, b, f, {p[0] - s(b, f), p[1] - s(b, f + 1)}, l, rho, sign,
                    c + COLUMNS);
    }
  }

  static void push(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                   const V& f, const V& x, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const std::ptrdiff_t c = offsets[b];
    force[c] += f[0];
    force[c + 1] += f[1];
    force[c + 2] += (x[0] - s(b, X)) * f[1] - (x[1] - s(b, Y)) * f[0];
    if (flexible(s, b))   // the modes' generalised force (A (T_k + R_k k x e))^T f
    {
      const V p = turned_back(s, b, {x[0] - s(b, X), x[1] - s(b, Y)});
      const std::ptrdiff_t face = face_of(s, b, p);
      const auto [e0, e1, k] = undeformed(s, b, face, p);
      const V l = turned_back(s, b, f);
      const double lk = (l[1] * e0 - l[0] * e1) * k;
      for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
        force[c + COLUMNS + j] += (l[0] * s(b, face + F_T + j) + l[1] * s(b, face + F_T + MODES + j)
                                   + s(b, face + F_R + j) * lk);
    }
  }

  static void push_torque(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                          const V& p, double torque, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    force[offsets[b] + 2] += torque;
    if (flexible(s, b))
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
        force[offsets[b] + COLUMNS + j] += torque * s(b, f + F_R + j);
    }
  }

  static double centripetal_term(const Matrix<double>& s, std::ptrdiff_t b, const V& arm_,
                                 const V& a, const V& c)
  {
    if (b < 0)
      return 0.0;
    if (flexible(s, b))
      return a[0] * c[0] + a[1] * c[1];
    const double w = s(b, W);
    return -((a[0] * arm_[0] + a[1] * arm_[1]) * (w * w));
  }

  /// a . (c_j - c_i) of the points with arms arm_i (body i) and arm_j (body j).
  static double centripetal_gap(const Matrix<double>& s, const V& a, std::ptrdiff_t bi,
                                const V& arm_i, const V& c_i, std::ptrdiff_t bj, const V& arm_j,
                                const V& c_j)
  {
    return centripetal_term(s, bj, arm_j, a, c_j) - centripetal_term(s, bi, arm_i, a, c_i);
  }

  /// (angle, rate) of body b's frame at the body point p (the ground's: 0).
  static std::pair<double, double> frame_angle(const Matrix<double>& s, std::ptrdiff_t b,
                                               const V& p)
  {
    if (b < 0)
      return {0.0, 0.0};
    if (flexible(s, b))
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      return {s(b, PHI) + s(b, f + F_TURN), s(b, W) + s(b, f + F_TURN_RATE)};
    }
    return {s(b, PHI), s(b, W)};
  }

  static Rotation relative_rotation(const Matrix<double>& s, std::ptrdiff_t bi,
                                    std::ptrdiff_t bj, const V& s_i, const V& s_j, const V&,
                                    const V&, const V&, double offset, double drift)
  {
    const auto [phi_i, w_i] = frame_angle(s, bi, s_i);
    const auto [phi_j, w_j] = frame_angle(s, bj, s_j);
    return {((phi_j - phi_i) - offset) - drift, -1.0, w_j - w_i, 0.0};
  }

  static double rotation_axis(const Matrix<double>&, std::ptrdiff_t, const V&, const V&,
                              const V&)
  {
    return 1.0;
  }

  /// rate plus body b's part of constraint row i's rate (its columns times their velocities).
  static double row_rate(double rate, const Matrix<double>& jac, std::ptrdiff_t i,
                         std::ptrdiff_t b, const Matrix<double>&, std::span<const double> velocities,
                         std::span<const std::int64_t> offsets)
  {
    for (std::ptrdiff_t c = offsets[b]; c < offsets[b + 1]; ++c)
      rate += jac(i, c) * velocities[c];
    return rate;
  }

  // ---- the whole body
  static void body_states(const Args& args, std::span<const double> y, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const std::ptrdiff_t c = args.offsets[b];
      const double phi = y[c + 2];
      s(b, X) = y[c];
      s(b, Y) = y[c + 1];
      s(b, PHI) = phi;
      s(b, COS) = std::cos(phi);
      s(b, SIN) = std::sin(phi);
      s(b, VX) = y[nq + c];
      s(b, VY) = y[nq + c + 1];
      s(b, W) = y[nq + c + 2];
      s(b, FIRST) = static_cast<double>(c);
      const std::ptrdiff_t n = args.offsets[b + 1] - c - COLUMNS;
      s(b, NMODES) = static_cast<double>(n);
      if (n > 0)
        flexible_state(args, y, b, c + COLUMNS, n, s);
    }
    for (std::ptrdiff_t j = 0; j < nq; ++j)
      work.velocities[j] = y[nq + j];
  }

  /// (g_k = (S^T eta)_k, eta_k (2 s1_k + (Q eta)_k)) of flexible body b (eta from y[q]).
  static std::pair<double, double> inertia_terms(const Rows& flex, std::ptrdiff_t b,
                                                 std::ptrdiff_t n, std::span<const double> y,
                                                 std::ptrdiff_t q, std::ptrdiff_t k)
  {
    const std::ptrdiff_t s1 = flex_column(n, 2, 0), quad = flex_column(n, 3, 0),
                         gyro = flex_column(n, 4, 0);
    double g = 0.0, qe = 0.0;
    for (std::ptrdiff_t j = 0; j < n; ++j)
    {
      g += y[q + j] * flex(b, gyro + j * n + k);
      qe += flex(b, quad + k * n + j) * y[q + j];
    }
    return {g, y[q + k] * (2 * flex(b, s1 + k) + qe)};
  }

  /// eta, eta', g = S^T eta, J(eta), sigma = J - g.g and the interfaces' frames into body
  /// b's row (its modal coordinates from y[q]).
  static void flexible_state(const Args& args, std::span<const double> y, std::ptrdiff_t b,
                             std::ptrdiff_t q, std::ptrdiff_t n, const Matrix<double>& s)
  {
    const Rows& flex = args.flex;
    const std::ptrdiff_t nq = args.nq;
    double inertia = flex(b, C_I0), gg = 0.0;
    for (std::ptrdiff_t j = 0; j < n; ++j)
    {
      s(b, ETA + j) = y[q + j];
      s(b, ETA_RATE + j) = y[nq + q + j];
    }
    for (std::ptrdiff_t k = 0; k < n; ++k)
    {
      const auto [g, term] = inertia_terms(flex, b, n, y, q, k);
      s(b, GVEC + k) = g;
      gg += g * g;
      inertia += term;
    }
    s(b, INERTIA) = inertia;
    s(b, SIGMA) = inertia - gg;
    const auto faces = static_cast<std::ptrdiff_t>(flex(b, C_FACES));
    s(b, NFACES) = static_cast<double>(faces);
    for (std::ptrdiff_t k = 0; k < faces; ++k)
    {
      const std::ptrdiff_t at = flex_column(n, 5, k), f = FACES + k * FACE;
      s(b, f) = flex(b, at);
      s(b, f + 1) = flex(b, at + 1);
      double move0 = 0.0, move1 = 0.0, turn = 0.0, rate0 = 0.0, rate1 = 0.0, turn_rate = 0.0;
      for (std::ptrdiff_t j = 0; j < n; ++j)
      {
        const double tx = flex(b, at + 2 + j), ty = flex(b, at + 2 + n + j),
                     r = flex(b, at + 2 + 2 * n + j);
        s(b, f + F_T + j) = tx;
        s(b, f + F_T + MODES + j) = ty;
        s(b, f + F_R + j) = r;
        const double e = y[q + j], ed = y[nq + q + j];
        move0 = move0 + tx * e, move1 = move1 + ty * e;
        rate0 = rate0 + tx * ed, rate1 = rate1 + ty * ed;
        turn += r * e;
        turn_rate += r * ed;
      }
      s(b, f + F_MOVE) = move0;
      s(b, f + F_MOVE + 1) = move1;
      s(b, f + F_TURN) = turn;
      s(b, f + F_MOVE_RATE) = rate0;
      s(b, f + F_MOVE_RATE + 1) = rate1;
      s(b, f + F_TURN_RATE) = turn_rate;
    }
  }

  static constexpr bool MASS_LEFT = true;   // the Schur sums' order (linalg)

  /// Gravity on each body; a flexible body's quadratic velocity, elastic and damping forces.
  /// Returns the power the modal damping dissipates.
  static double body_forces(const Args& args, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    const Rows& flex = args.flex;
    double power = 0.0;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto c = static_cast<std::ptrdiff_t>(s(b, FIRST));
      const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
      if (n == 0)
      {
        work.force[c] = args.gravity[0] / args.minv[c];
        work.force[c + 1] = args.gravity[1] / args.minv[c + 1];
        work.force[c + 2] = 0.0;
        continue;
      }
      work.force[c] = args.masses[b] * args.gravity[0];
      work.force[c + 1] = args.masses[b] * args.gravity[1];
      const std::ptrdiff_t omega2 = flex_column(n, 0, 0), damping = flex_column(n, 1, 0),
                           s1 = flex_column(n, 2, 0), quad = flex_column(n, 3, 0),
                           gyro = flex_column(n, 4, 0);
      const double w = s(b, W);
      double coupling = 0.0;
      for (std::ptrdiff_t k = 0; k < n; ++k)
      {
        double j1 = flex(b, s1 + k), spin = 0.0;
        for (std::ptrdiff_t j = 0; j < n; ++j)
        {
          j1 += flex(b, quad + k * n + j) * s(b, ETA + j);
          spin += flex(b, gyro + k * n + j) * s(b, ETA_RATE + j);
        }
        const double rate = s(b, ETA_RATE + k);
        coupling += j1 * rate;
        work.force[c + COLUMNS + k] = (w * w * j1 + 2 * w * spin - flex(b, omega2 + k) * s(b, ETA + k)
                                       - flex(b, damping + k) * rate);
        power += flex(b, damping + k) * rate * rate;
      }
      work.force[c + 2] = -2 * w * coupling;
    }
    return power;
  }

  /// a = (v_phi - g . v_eta) / sigma: the angular part of M^-1 v of flexible body b.
  static double rotation_part(const Matrix<double>& s, std::ptrdiff_t b, double v_phi,
                              double v_eta_dot_g)
  {
    return (v_phi - v_eta_dot_g) / s(b, SIGMA);
  }

  /// out = M^-1 in over body b's columns (indexed as the force vector): the rigid columns
  /// divided by their masses, a flexible body's block [[J, g^T], [g, I]] in closed form.
  /// in and out may be the same.
  static void inverse_mass(const Args& args, const Work& work, std::ptrdiff_t b, const double* in,
                           double* out)
  {
    for (std::ptrdiff_t c = args.offsets[b]; c < args.offsets[b + 1]; ++c)
      out[c] = in[c] * args.minv[c];
    const Matrix<double>& s = work.bodies;
    if (s(b, NMODES) > 0)
    {
      const std::ptrdiff_t c = args.offsets[b];
      const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
      double g = 0.0;
      for (std::ptrdiff_t j = 0; j < n; ++j)
        g += s(b, GVEC + j) * in[c + COLUMNS + j];
      const double a = rotation_part(s, b, in[c + 2], g);
      out[c + 2] = a;
      for (std::ptrdiff_t j = 0; j < n; ++j)
        out[c + COLUMNS + j] = in[c + COLUMNS + j] - s(b, GVEC + j) * a;
    }
  }

  static void mass_rows(const Args& args, const Work& work, std::ptrdiff_t i, std::ptrdiff_t b)
  {
    inverse_mass(args, work, b, work.jac.row(i), work.mjac.row(i));
  }

  static void state_rates(const Args& args, std::span<const double> y, std::span<double> dy,
                          const Work& work)
  {
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t j = 0; j < nq; ++j)
      dy[j] = y[nq + j];
    for (std::ptrdiff_t b = 0; b < work.bodies.rows; ++b)
      inverse_mass(args, work, b, work.force.data(), dy.data() + nq);
  }

  /// y[start:start + nq] -= scale M^-1 Phi_q^T x.
  static void mass_weighted_step(const Args& args, std::span<double> y, std::ptrdiff_t start,
                                 const Work& work, std::span<const double> x, std::ptrdiff_t m,
                                 double scale)
  {
    const Matrix<double>& s = work.bodies;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto c0 = static_cast<std::ptrdiff_t>(s(b, FIRST));
      const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
      for (std::ptrdiff_t c = c0; c < c0 + COLUMNS + n; ++c)
      {
        double v = 0.0;
        if (n > 0 and c >= c0 + 2)   // a flexible body's M^-1 Phi_q^T from mjac
        {
          for (std::ptrdiff_t i = 0; i < m; ++i)
            v += work.mjac(i, c) * x[i];
          y[start + c] -= scale * v;
          continue;
        }
        for (std::ptrdiff_t i = 0; i < m; ++i)
          v += work.jac(i, c) * x[i];
        y[start + c] -= scale * args.minv[c] * v;
      }
    }
  }

  static void position_step(const Args& args, std::span<double> y, const Work& w,
                            std::span<const double> x, std::ptrdiff_t m)
  {
    mass_weighted_step(args, y, 0, w, x, m, 1.0);
  }
  static void velocity_step(const Args& args, std::span<double> y, const Work& w,
                            std::span<const double> x, std::ptrdiff_t m, double scale)
  {
    mass_weighted_step(args, y, args.nq, w, x, m, scale);
  }

  static void normalise(const Args&, std::span<double>) {}

  static double kinetic_energy(const Args& args, std::span<const double> y)
  {
    double energy = 0.0;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t b = 0; b + 1 < static_cast<std::ptrdiff_t>(args.offsets.size()); ++b)
    {
      const std::ptrdiff_t c = args.offsets[b];
      const std::ptrdiff_t n = args.offsets[b + 1] - c - COLUMNS;
      if (n == 0)
      {
        for (std::ptrdiff_t i = c; i < c + COLUMNS; ++i)
          energy += 0.5 * (y[nq + i] * y[nq + i]) / args.minv[i];
        continue;
      }
      const std::ptrdiff_t q = c + COLUMNS;
      const double w = y[nq + c + 2];
      double inertia = args.flex(b, C_I0), coupling = 0.0, modal = 0.0;
      for (std::ptrdiff_t k = 0; k < n; ++k)
      {
        const auto [g, term] = inertia_terms(args.flex, b, n, y, q, k);
        inertia += term;
        coupling += g * y[nq + q + k];
        modal += y[nq + q + k] * y[nq + q + k];
      }
      energy += (0.5 * args.masses[b] * (y[nq + c] * y[nq + c] + y[nq + c + 1] * y[nq + c + 1])
                 + 0.5 * inertia * w * w + w * coupling + 0.5 * modal);
    }
    return energy;
  }
};

} // namespace pinbore::mechanism
