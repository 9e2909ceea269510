// Spatial rigid bodies: the body kind of a spatial mechanism (pinbore.reduced.mechanism.spatial
// states the equations). Each body has its centre of mass r and Euler parameters p
// ([Nikravesh1988] ch. 6), 7 coordinates; the dynamics are written in the body velocities
// (r', w), w global, M = diag(m I, A J' A^T); the Euler parameters follow from
// p'' = G^T (A^T w') / 2 + k p with their normalisation's Baumgarte terms.
#pragma once

#include "bodies.h"
#include "data.h"

#include <cmath>

namespace pinbore::mechanism
{

struct Spatial
{
  static constexpr int D = 3;
  using V = Vec3;
  using A = Vec3;
  // a body's row in Work::bodies (pinbore.reduced.mechanism.spatial's layout)
  static constexpr int BODY_POS = 0, BODY_ROT = 3, BODY_VEL = 12, BODY_OMEGA = 15,
                       BODY_JINV = 18, FIRST = 27, COORD = 28, NMODES = 29;
  static constexpr int BODY_COLUMNS = 796;
  static constexpr int COLUMNS = 6, COORDINATES = 7;
  static constexpr bool MASS_LEFT = false;   // the Schur sums' order (linalg)

  using Point = PointState<V>;
  using Vector = VectorState<V>;
  struct Rotation
  {
    double angle;
    A coefficient;
    double rate, centripetal;
  };

  static V row3(const Matrix<double>& s, std::ptrdiff_t b, int k)
  {
    return {s(b, k), s(b, k + 1), s(b, k + 2)};
  }
  static V block_times(const Matrix<double>& s, std::ptrdiff_t b, int k, const V& a)
  {
    return {dot(row3(s, b, k), a), dot(row3(s, b, k + 3), a), dot(row3(s, b, k + 6), a)};
  }
  /// A a: a body-frame vector of body b in global axes (the ground's: global).
  static V turned(const Matrix<double>& s, std::ptrdiff_t b, const V& a)
  {
    return b < 0 ? a : block_times(s, b, BODY_ROT, a);
  }
  /// A^T a: a global vector in body b's axes (the ground's: global).
  static V unturned(const Matrix<double>& s, std::ptrdiff_t b, const V& a)
  {
    if (b < 0)
      return a;
    return add(add(scaled(row3(s, b, BODY_ROT), a[0]), scaled(row3(s, b, BODY_ROT + 3), a[1])),
               scaled(row3(s, b, BODY_ROT + 6), a[2]));
  }
  static V matvec(const Rows& m, std::ptrdiff_t b, const V& a)
  {
    const double* r = m.row(b);
    return {r[0] * a[0] + r[1] * a[1] + r[2] * a[2], r[3] * a[0] + r[4] * a[1] + r[5] * a[2],
            r[6] * a[0] + r[7] * a[1] + r[8] * a[2]};
  }

  // ---- Euler parameters
  using P4 = Vec<4>;
  static P4 unit_parameters(std::span<const double> q, std::ptrdiff_t i)
  {
    const double n = std::sqrt(q[i] * q[i] + q[i + 1] * q[i + 1] + q[i + 2] * q[i + 2]
                               + q[i + 3] * q[i + 3]);
    return {q[i] / n, q[i + 1] / n, q[i + 2] / n, q[i + 3] / n};
  }
  static P4 four(std::span<const double> q, std::ptrdiff_t i)
  {
    return {q[i], q[i + 1], q[i + 2], q[i + 3]};
  }
  /// G(p) p'.
  static V g_times(const P4& p, const P4& pd)
  {
    const double e0 = p[0], e1 = p[1], e2 = p[2], e3 = p[3];
    return {-e1 * pd[0] + e0 * pd[1] + e3 * pd[2] - e2 * pd[3],
            -e2 * pd[0] - e3 * pd[1] + e0 * pd[2] + e1 * pd[3],
            -e3 * pd[0] + e2 * pd[1] - e1 * pd[2] + e0 * pd[3]};
  }
  /// G(p)^T w.
  static P4 gt_times(const P4& p, const V& w)
  {
    const double e0 = p[0], e1 = p[1], e2 = p[2], e3 = p[3];
    return {-e1 * w[0] - e2 * w[1] - e3 * w[2], e0 * w[0] - e3 * w[1] + e2 * w[2],
            e3 * w[0] + e0 * w[1] - e1 * w[2], -e2 * w[0] + e1 * w[1] + e0 * w[2]};
  }

  // ---- points and vectors
  static Point point_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    if (b < 0)
      return {p, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    const V w = row3(s, b, BODY_OMEGA);
    const V arm = turned(s, b, p);
    const V ws = cross(w, arm);
    return {add(row3(s, b, BODY_POS), arm), add(row3(s, b, BODY_VEL), ws), cross(w, ws), arm};
  }

  static Vector vector_state(const Matrix<double>& s, std::ptrdiff_t b, const V&, const V& v)
  {
    if (b < 0)
      return {v, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    const V w = row3(s, b, BODY_OMEGA);
    const V a = turned(s, b, v);
    const V wa = cross(w, a);
    return {a, wa, cross(w, wa)};
  }

  static V material_velocity(const Matrix<double>& s, std::ptrdiff_t b, const V& x)
  {
    if (b < 0)
      return {0.0, 0.0, 0.0};
    return add(row3(s, b, BODY_VEL), cross(row3(s, b, BODY_OMEGA), sub(x, row3(s, b, BODY_POS))));
  }

  static void put(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>&,
                  std::ptrdiff_t b, const V&, const V& linear, const A& angular, double sign,
                  std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const std::ptrdiff_t col = offsets[b];
    for (int k = 0; k < 3; ++k)
    {
      jac(row, col + k) += sign * linear[k];
      jac(row, col + 3 + k) += sign * angular[k];
    }
  }

  static void push(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                   const V& f, const V& x, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const V torque = cross(sub(x, row3(s, b, BODY_POS)), f);
    const std::ptrdiff_t col = offsets[b];
    for (int c = 0; c < 3; ++c)
    {
      force[col + c] += f[c];
      force[col + 3 + c] += torque[c];
    }
  }

  static void push_torque(std::span<double> force, const Matrix<double>&, std::ptrdiff_t b,
                          const V&, const A& torque, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    for (int c = 0; c < 3; ++c)
      force[offsets[b] + 3 + c] += torque[c];
  }

  static double centripetal_gap(const Matrix<double>&, const V& a, std::ptrdiff_t, const V&,
                                const V& c_i, std::ptrdiff_t, const V&, const V& c_j)
  {
    return dot(a, sub(c_j, c_i));
  }

  /// atan2(c_i . b_j, a_i . b_j) less offset and drift, modulo 2 pi.
  static Rotation relative_rotation(const Matrix<double>& s, std::ptrdiff_t bi,
                                    std::ptrdiff_t bj, const V& s_i, const V& s_j, const V& a_i,
                                    const V& b_j, const V& c_i, double offset, double drift)
  {
    const auto c = dot1<Spatial>(s, bi, s_i, a_i, bj, s_j, b_j);
    const auto sn = dot1<Spatial>(s, bi, s_i, c_i, bj, s_j, b_j);
    const double rho2 = sn.value * sn.value + c.value * c.value;
    const V coefficient = scaled(sub(scaled(sn.coefficient, c.value), scaled(c.coefficient, sn.value)),
                                 1.0 / rho2);
    const double rate = (c.value * sn.rate - sn.value * c.rate) / rho2;
    const double gap = std::atan2(sn.value, c.value) - offset - drift;
    const double angle = gap - 2 * M_PI * std::floor(gap / (2 * M_PI) + 0.5);
    return {angle, coefficient, rate,
            -(c.value * sn.centripetal - sn.value * c.centripetal) / rho2
                + 2 * rate * (sn.value * sn.rate + c.value * c.rate) / rho2};
  }

  static A rotation_axis(const Matrix<double>& s, std::ptrdiff_t bi, const V& s_i, const V& a_i,
                         const V& c_i)
  {
    return cross(vector_state(s, bi, s_i, a_i).value, vector_state(s, bi, s_i, c_i).value);
  }

  /// rate plus body b's part of constraint row i's rate.
  static double row_rate(double rate, const Matrix<double>& jac, std::ptrdiff_t i,
                         std::ptrdiff_t b, const Matrix<double>& s, std::span<const double>,
                         std::span<const std::int64_t> offsets)
  {
    const std::ptrdiff_t col = offsets[b];
    for (int c = 0; c < 3; ++c)
      rate += (jac(i, col + c) * s(b, BODY_VEL + c) + jac(i, col + 3 + c) * s(b, BODY_OMEGA + c));
    return rate;
  }

  // ---- the whole body
  static void body_states(const Args& args, std::span<const double> y, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const std::ptrdiff_t c = args.offsets[b], q = c + b;
      const P4 p = unit_parameters(y, q + 3);
      const double e0 = p[0], e1 = p[1], e2 = p[2], e3 = p[3];
      const double a[3][3] = {{e0 * e0 + e1 * e1 - 0.5, e1 * e2 - e0 * e3, e1 * e3 + e0 * e2},
                              {e1 * e2 + e0 * e3, e0 * e0 + e2 * e2 - 0.5, e2 * e3 - e0 * e1},
                              {e1 * e3 - e0 * e2, e2 * e3 + e0 * e1, e0 * e0 + e3 * e3 - 0.5}};
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
          s(b, BODY_ROT + 3 * r + k) = 2.0 * a[r][k];
      const V w = turned(s, b, scaled(g_times(p, four(y, nq + q + 3)), 2.0));
      for (int k = 0; k < 3; ++k)
      {
        s(b, BODY_POS + k) = y[q + k];
        s(b, BODY_VEL + k) = y[nq + q + k];
        s(b, BODY_OMEGA + k) = w[k];
        work.velocities[c + k] = y[nq + q + k];
        work.velocities[c + 3 + k] = w[k];
      }
      s(b, FIRST) = static_cast<double>(c);
      s(b, COORD) = static_cast<double>(q);
      s(b, NMODES) = static_cast<double>(args.offsets[b + 1] - c - COLUMNS);
      const double* inv = args.inertia_inv.row(b);
      for (int r = 0; r < 3; ++r)
      {
        const V ar = row3(s, b, BODY_ROT + 3 * r);
        const double t0 = ar[0] * inv[0] + ar[1] * inv[3] + ar[2] * inv[6];
        const double t1 = ar[0] * inv[1] + ar[1] * inv[4] + ar[2] * inv[7];
        const double t2 = ar[0] * inv[2] + ar[1] * inv[5] + ar[2] * inv[8];
        for (int k = 0; k <= r; ++k)
        {
          const V ac = row3(s, b, BODY_ROT + 3 * k);
          s(b, BODY_JINV + 3 * r + k) = s(b, BODY_JINV + 3 * k + r) = t0 * ac[0] + t1 * ac[1] + t2 * ac[2];
        }
      }
    }
  }

  /// Gravity and the gyroscopic torque -w x (J w) of each body.
  static double body_forces(const Args& args, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto col = static_cast<std::ptrdiff_t>(s(b, FIRST));
      const V w = row3(s, b, BODY_OMEGA);
      const V gyro = cross(w, turned(s, b, matvec(args.inertia, b, unturned(s, b, w))));
      for (int c = 0; c < 3; ++c)
      {
        work.force[col + c] = args.masses[b] * args.gravity[c];
        work.force[col + 3 + c] = -gyro[c];
      }
    }
    return 0.0;
  }

  static void mass_rows(const Args& args, const Work& w, std::ptrdiff_t i, std::ptrdiff_t b)
  {
    const std::ptrdiff_t col = args.offsets[b];
    const V a = block_times(w.bodies, b, BODY_JINV, {w.jac(i, col + 3), w.jac(i, col + 4), w.jac(i, col + 5)});
    for (int c = 0; c < 3; ++c)
    {
      w.mjac(i, col + c) = w.jac(i, col + c) / args.masses[b];
      w.mjac(i, col + 3 + c) = a[c];
    }
  }

  static void state_rates(const Args& args, std::span<const double> y, std::span<double> dy,
                          const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    const std::ptrdiff_t nq = args.nq;
    const double alpha = args.baumgarte;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto i = static_cast<std::ptrdiff_t>(s(b, COORD));
      const auto col = static_cast<std::ptrdiff_t>(s(b, FIRST));
      for (int c = 0; c < 3; ++c)
      {
        dy[i + c] = y[nq + i + c];
        dy[nq + i + c] = work.force[col + c] / args.masses[b];
      }
      for (int c = 0; c < 4; ++c)
        dy[i + 3 + c] = y[nq + i + 3 + c];
      const V wd = block_times(s, b, BODY_JINV,
                               {work.force[col + 3], work.force[col + 4], work.force[col + 5]});
      const P4 p = unit_parameters(y, i + 3);
      const P4 pd = four(y, nq + i + 3);
      const P4 half = gt_times(p, scaled(unturned(s, b, wd), 0.5));
      const double pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3];
      const P4 raw = four(y, i + 3);
      const double norm2 = raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2] + raw[3] * raw[3];
      const double along = (-(pd[0] * pd[0] + pd[1] * pd[1] + pd[2] * pd[2] + pd[3] * pd[3])
                            - 2 * alpha * (raw[0] * pd[0] + raw[1] * pd[1] + raw[2] * pd[2] + raw[3] * pd[3])
                            - 0.5 * alpha * alpha * (norm2 - 1.0))
                           / pp;
      for (int c = 0; c < 4; ++c)
        dy[nq + i + 3 + c] = half[c] + along * p[c];
    }
  }

  static void normalise_at(std::span<double> y, std::ptrdiff_t nq, std::ptrdiff_t i)
  {
    const double n = std::sqrt(y[i] * y[i] + y[i + 1] * y[i + 1] + y[i + 2] * y[i + 2]
                               + y[i + 3] * y[i + 3]);
    double along = 0.0;
    for (int c = 0; c < 4; ++c)
    {
      y[i + c] /= n;
      along += y[i + c] * y[nq + i + c];
    }
    for (int c = 0; c < 4; ++c)
      y[nq + i + c] -= along * y[i + c];
  }

  static void normalise(const Args& args, std::span<double> y)
  {
    for (std::ptrdiff_t b = 0; b < args.bodies(); ++b)
      normalise_at(y, args.nq, args.offsets[b] + b + 3);
  }

  /// Turn a body by a small global rotation vector: p <- (cos(|r|/2), sin(|r|/2) r/|r|) p.
  static void turn(std::span<double> y, std::ptrdiff_t i, const V& rv)
  {
    const double angle = std::sqrt(dot(rv, rv));
    if (angle == 0.0)
      return;
    const double k = std::sin(0.5 * angle) / angle;
    const double a0 = std::cos(0.5 * angle);
    const V a = scaled(rv, k);
    const double b0 = y[i];
    const V bv{y[i + 1], y[i + 2], y[i + 3]};
    const V v = add(add(scaled(bv, a0), scaled(a, b0)), cross(a, bv));
    y[i] = a0 * b0 - dot(a, bv);
    y[i + 1] = v[0];
    y[i + 2] = v[1];
    y[i + 3] = v[2];
  }

  static double column_step(const Matrix<double>& mjac, std::span<const double> x,
                            std::ptrdiff_t m, std::ptrdiff_t column, double scale)
  {
    double step = 0.0;
    for (std::ptrdiff_t i = 0; i < m; ++i)
      step -= mjac(i, column) * x[i];
    return scale != 1.0 ? step * scale : step;
  }

  /// -scale M^-1 D^T x: level 0 moves the centres and turns the bodies, level 1 changes
  /// the velocities and the parameters' rates.
  static void mass_weighted_step(const Args& args, std::span<double> y, const Work& w,
                                 std::span<const double> x, std::ptrdiff_t m, int level,
                                 double scale)
  {
    const Matrix<double>& s = w.bodies;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto col = static_cast<std::ptrdiff_t>(s(b, FIRST));
      const auto i = static_cast<std::ptrdiff_t>(s(b, COORD));
      double step[6];
      for (int c = 0; c < 6; ++c)
        step[c] = column_step(w.mjac, x, m, col + c, scale);
      if (level == 0)
      {
        for (int c = 0; c < 3; ++c)
          y[i + c] += step[c];
        turn(y, i + 3, {step[3], step[4], step[5]});
      }
      else
      {
        for (int c = 0; c < 3; ++c)
          y[nq + i + c] += step[c];
        const V wv = add(row3(s, b, BODY_OMEGA), V{step[3], step[4], step[5]});
        const P4 pd = gt_times(unit_parameters(y, i + 3), scaled(unturned(s, b, wv), 0.5));
        for (int c = 0; c < 4; ++c)
          y[nq + i + 3 + c] = pd[c];
      }
    }
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
      normalise_at(y, nq, static_cast<std::ptrdiff_t>(s(b, COORD)) + 3);
  }

  static void position_step(const Args& args, std::span<double> y, const Work& w,
                            std::span<const double> x, std::ptrdiff_t m)
  {
    mass_weighted_step(args, y, w, x, m, 0, 1.0);
  }
  static void velocity_step(const Args& args, std::span<double> y, const Work& w,
                            std::span<const double> x, std::ptrdiff_t m, double scale)
  {
    mass_weighted_step(args, y, w, x, m, 1, scale);
  }

  /// 1/2 m v.v + 1/2 w'.J' w' of every body (w' = 2 G p' in the body frame).
  static double kinetic_energy(const Args& args, std::span<const double> y)
  {
    double energy = 0.0;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t b = 0; b < args.bodies(); ++b)
    {
      const std::ptrdiff_t i = args.offsets[b] + b;
      const V v{y[nq + i], y[nq + i + 1], y[nq + i + 2]};
      const V w = scaled(g_times(unit_parameters(y, i + 3), four(y, nq + i + 3)), 2.0);
      energy += 0.5 * args.masses[b] * dot(v, v) + 0.5 * dot(w, matvec(args.inertia, b, w));
    }
    return energy;
  }
};

} // namespace pinbore::mechanism
