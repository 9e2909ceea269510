// Planar rigid bodies: the body kind of a planar mechanism (pinbore.reduced.mechanism.planar
// states the equations). Coordinates q = (x, y, phi) of each body's centre of mass, velocity
// columns (x', y', w), M = diag(m, m, J); a body point s (body frame) is at P = r + A(phi) s.
// What the joints see of a body (a point's and a vector's state, a Jacobian row, a pushed
// force) and what the equations of motion need of it (its forces, the Schur matrix, the
// rates, the projection's steps, its energy). Bodies are numbered from 0; -1 is the ground.
#pragma once

#include "bodies.h"
#include "data.h"

#include <cmath>

namespace pinbore::mechanism
{

struct Planar
{
  static constexpr int D = 2;
  using V = Vec2;
  using A = double;
  // a body's row in Work::bodies (pinbore.reduced.mechanism.planar's layout)
  static constexpr int X = 0, Y = 1, PHI = 2, COS = 3, SIN = 4, VX = 5, VY = 6, W = 7,
                       FIRST = 8, NMODES = 9;
  static constexpr int BODY_COLUMNS = 405;
  static constexpr int COLUMNS = 3;

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

  static Point point_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    if (b < 0)
      return {p, {0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
    const double w = s(b, W);
    const V a = arm(s, b, p);
    const double w2 = w * w;
    return {{s(b, X) + a[0], s(b, Y) + a[1]},
            {s(b, VX) - w * a[1], s(b, VY) + w * a[0]},
            {-(a[0] * w2), -(a[1] * w2)},
            a};
  }

  static Vector vector_state(const Matrix<double>& s, std::ptrdiff_t b, const V&, const V& v)
  {
    if (b < 0)
      return {v, {0.0, 0.0}, {0.0, 0.0}};
    const double w = s(b, W);
    const V a = arm(s, b, v);
    const double w2 = w * w;
    return {a, {-w * a[1], w * a[0]}, {-(a[0] * w2), -(a[1] * w2)}};
  }

  static V material_velocity(const Matrix<double>& s, std::ptrdiff_t b, const V& x)
  {
    if (b < 0)
      return {0.0, 0.0};
    const double w = s(b, W);
    return {s(b, VX) - w * (x[1] - s(b, Y)), s(b, VY) + w * (x[0] - s(b, X))};
  }

  static void put(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>&,
                  std::ptrdiff_t b, const V&, const V& linear, double angular, double sign,
                  std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const std::ptrdiff_t c = offsets[b];
    jac(row, c) += sign * linear[0];
    jac(row, c + 1) += sign * linear[1];
    jac(row, c + 2) += sign * angular;
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
  }

  static void push_torque(std::span<double> force, const Matrix<double>&, std::ptrdiff_t b,
                          const V&, double torque, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    force[offsets[b] + 2] += torque;
  }

  static double centripetal_term(const Matrix<double>& s, std::ptrdiff_t b, const V& arm_,
                                 const V& a)
  {
    if (b < 0)
      return 0.0;
    const double w = s(b, W);
    return -((a[0] * arm_[0] + a[1] * arm_[1]) * (w * w));
  }

  /// a . (c_j - c_i) of the points with arms arm_i (body i) and arm_j (body j).
  static double centripetal_gap(const Matrix<double>& s, const V& a, std::ptrdiff_t bi,
                                const V& arm_i, const V&, std::ptrdiff_t bj, const V& arm_j,
                                const V&)
  {
    return centripetal_term(s, bj, arm_j, a) - centripetal_term(s, bi, arm_i, a);
  }

  static Rotation relative_rotation(const Matrix<double>& s, std::ptrdiff_t bi,
                                    std::ptrdiff_t bj, const V&, const V&, const V&, const V&,
                                    const V&, double offset, double drift)
  {
    const double phi_i = bi < 0 ? 0.0 : s(bi, PHI), w_i = bi < 0 ? 0.0 : s(bi, W);
    const double phi_j = bj < 0 ? 0.0 : s(bj, PHI), w_j = bj < 0 ? 0.0 : s(bj, W);
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
      s(b, NMODES) = static_cast<double>(args.offsets[b + 1] - c - COLUMNS);
    }
    for (std::ptrdiff_t j = 0; j < nq; ++j)
      work.velocities[j] = y[nq + j];
  }

  static constexpr bool MASS_LEFT = true;   // the Schur sums' order (linalg)

  /// Gravity on each body; returns the power its modal damping dissipates (none: rigid).
  static double body_forces(const Args& args, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto c = static_cast<std::ptrdiff_t>(s(b, FIRST));
      work.force[c] = args.gravity[0] / args.minv[c];
      work.force[c + 1] = args.gravity[1] / args.minv[c + 1];
      work.force[c + 2] = 0.0;
    }
    return 0.0;
  }

  static void mass_rows(const Args& args, const Work& work, std::ptrdiff_t i, std::ptrdiff_t b)
  {
    for (std::ptrdiff_t c = args.offsets[b]; c < args.offsets[b + 1]; ++c)
      work.mjac(i, c) = work.jac(i, c) * args.minv[c];
  }

  static void state_rates(const Args& args, std::span<const double> y, std::span<double> dy,
                          const Work& work)
  {
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t j = 0; j < nq; ++j)
    {
      dy[j] = y[nq + j];
      dy[nq + j] = args.minv[j] * work.force[j];
    }
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
      for (std::ptrdiff_t c = c0; c < c0 + COLUMNS; ++c)
      {
        double v = 0.0;
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
      for (std::ptrdiff_t i = c; i < c + COLUMNS; ++i)
        energy += 0.5 * (y[nq + i] * y[nq + i]) / args.minv[i];
    }
    return energy;
  }
};

} // namespace pinbore::mechanism
