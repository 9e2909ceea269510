// Spatial bodies: the body kind of a spatial mechanism (pinbore.reduced.mechanism.spatial
// states the equations), rigid or flexible (modal coordinates in Buckens' mean-axis frame). Each body has its centre of mass r and Euler parameters p
// ([Nikravesh1988] ch. 6), 7 coordinates; the dynamics are written in the body velocities
// (r', w), w global, M = diag(m I, A J' A^T); the Euler parameters follow from
// p'' = G^T (A^T w') / 2 + k p with their normalisation's Baumgarte terms.
#pragma once

#include "bodies.h"
#include "data.h"

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace pinbore::mechanism
{

struct Spatial
{
  static constexpr int D = 3;
  using V = Vec3;
  using A = Vec3;
  // a body's row in Work::bodies (pinbore.reduced.mechanism.spatial's layout)
  static constexpr int BODY_POS = 0, BODY_ROT = 3, BODY_VEL = 12, BODY_OMEGA = 15,
                       BODY_JINV = 18, FIRST = 27, COORD = 28, NMODES = 29, NFACES = 30,
                       JBODY = 31;
  static constexpr int MODES = 24, INTERFACES = 4;   // at most, a flexible body
  static constexpr int GMAT = JBODY + 9;             // G[a, j] at GMAT + a MODES + j
  static constexpr int ETA = GMAT + 3 * MODES, ETA_RATE = ETA + MODES, FACES = ETA_RATE + MODES;
  // an interface: its centre x_k, its frame's displacement T_k eta and small turn R_k eta,
  // their rates (body frame), the mode shapes T_k[a, j] and R_k[a, j] (a MODES + j)
  static constexpr int F_CENTRE = 0, F_MOVE = 3, F_TURN = 6, F_MOVE_RATE = 9, F_TURN_RATE = 12,
                       F_T = 15, F_R = F_T + 3 * MODES, FACE = F_R + 3 * MODES;
  static constexpr int BODY_COLUMNS = FACES + INTERFACES * FACE;
  static constexpr int C_MODES = 0, C_FACES = 1;   // a flexible body's row of Args::flex
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

  // ---- a flexible body in Buckens' mean-axis frame (pinbore.reduced.mechanism.spatial
  // states its kinetic energy and equations)
  /// The first column in Args::flex of a flexible body's constant block (n its modes):
  /// 0 omega^2, 1 the modal damping (n each), 2 the second moments I_ab (9), 3 s_ab[k],
  /// 4 S_ab[j, k], 5 the stiffening K_G,ab[j, k], 6 the interface k: x_k, T_k, R_k.
  static std::ptrdiff_t flex_column(std::ptrdiff_t n, int block, std::ptrdiff_t k)
  {
    if (block < 2)
      return 2 + block * n;
    if (block == 2)
      return 2 + 2 * n;
    if (block == 3)
      return 11 + 2 * n;
    if (block < 6)
      return 11 + 11 * n + (block - 4) * 9 * n * n;
    return 11 + 11 * n + 18 * n * n + k * (3 + 6 * n);
  }

  static bool flexible(const Matrix<double>& s, std::ptrdiff_t b)
  {
    return b >= 0 and s(b, NMODES) > 0.0;
  }

  /// I_ac(eta) of flexible body b (eta = src[at ..]).
  static double second_moment(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n,
                              std::span<const double> src, std::ptrdiff_t at, int a, int c)
  {
    const std::ptrdiff_t s_block = flex_column(n, 3, 0), big_s = flex_column(n, 4, 0);
    double v = flex(b, flex_column(n, 2, 0) + 3 * a + c);
    const int ac = 3 * a + c, ca = 3 * c + a;
    for (std::ptrdiff_t k = 0; k < n; ++k)
    {
      const double e = src[at + k];
      double quad = 0.0;
      for (std::ptrdiff_t j = 0; j < n; ++j)
        quad += flex(b, big_s + ac * n * n + k * n + j) * src[at + j];
      v += e * (flex(b, s_block + ac * n + k) + flex(b, s_block + ca * n + k) + quad);
    }
    return v;
  }

  /// eta^T K_G,ac eta.
  static double stiffening_term(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n,
                                std::span<const double> src, std::ptrdiff_t at, int a, int c)
  {
    const std::ptrdiff_t kg = flex_column(n, 5, 0) + (3 * a + c) * n * n;
    double v = 0.0;
    for (std::ptrdiff_t k = 0; k < n; ++k)
      for (std::ptrdiff_t j = 0; j < n; ++j)
        v += src[at + k] * flex(b, kg + k * n + j) * src[at + j];
    return v;
  }

  /// S^_a[j, m] = e_abc S_bc[j, m].
  static double gyroscopic(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n, int a,
                           std::ptrdiff_t j, std::ptrdiff_t m)
  {
    const std::ptrdiff_t big_s = flex_column(n, 4, 0);
    const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
    return flex(b, big_s + (3 * b1 + b2) * n * n + j * n + m)
           - flex(b, big_s + (3 * b2 + b1) * n * n + j * n + m);
  }

  /// J(eta) (row-major, body frame).
  static std::array<double, 9> inertia_of(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n,
                                          std::span<const double> src, std::ptrdiff_t at)
  {
    const double i00 = second_moment(flex, b, n, src, at, 0, 0),
                 i11 = second_moment(flex, b, n, src, at, 1, 1),
                 i22 = second_moment(flex, b, n, src, at, 2, 2);
    const double i01 = second_moment(flex, b, n, src, at, 0, 1),
                 i02 = second_moment(flex, b, n, src, at, 0, 2),
                 i12 = second_moment(flex, b, n, src, at, 1, 2);
    const double trace = i00 + i11 + i22;
    const double k00 = stiffening_term(flex, b, n, src, at, 0, 0),
                 k11 = stiffening_term(flex, b, n, src, at, 1, 1),
                 k22 = stiffening_term(flex, b, n, src, at, 2, 2);
    const double k01 = stiffening_term(flex, b, n, src, at, 0, 1),
                 k02 = stiffening_term(flex, b, n, src, at, 0, 2),
                 k12 = stiffening_term(flex, b, n, src, at, 1, 2);
    return {trace - i00 - k00, -i01 - k01, -i02 - k02, -i01 - k01, trace - i11 - k11, -i12 - k12,
            -i02 - k02, -i12 - k12, trace - i22 - k22};
  }

  /// G[a, m] = sum_j eta_j S^_a[j, m].
  static double g_row(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n,
                      std::span<const double> src, std::ptrdiff_t at, int a, std::ptrdiff_t m)
  {
    double v = 0.0;
    for (std::ptrdiff_t j = 0; j < n; ++j)
      v += src[at + j] * gyroscopic(flex, b, n, a, j, m);
    return v;
  }

  /// The inverse of a 3 x 3 matrix (row-major) by its adjugate.
  static std::array<std::array<double, 3>, 3> inverse3(const std::array<double, 9>& m)
  {
    const double c00 = m[4] * m[8] - m[5] * m[7], c01 = m[5] * m[6] - m[3] * m[8],
                 c02 = m[3] * m[7] - m[4] * m[6];
    const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
    return {{{c00 / det, (m[2] * m[7] - m[1] * m[8]) / det, (m[1] * m[5] - m[2] * m[4]) / det},
             {c01 / det, (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det},
             {c02 / det, (m[1] * m[6] - m[0] * m[7]) / det, (m[0] * m[4] - m[1] * m[3]) / det}}};
  }

  /// (G G^T)[a, c] of body b's row.
  static double g_dot(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t n, int a, int c)
  {
    double v = 0.0;
    for (std::ptrdiff_t m = 0; m < n; ++m)
      v += s(b, GMAT + a * MODES + m) * s(b, GMAT + c * MODES + m);
    return v;
  }

  /// eta, eta', J(eta), G(eta), A sigma^-1 A^T (sigma = J - G G^T) and the interfaces'
  /// frames into body b's row (its modal coordinates from y[q]).
  static void flexible_state(const Args& args, std::span<const double> y, std::ptrdiff_t b,
                             std::ptrdiff_t q, std::ptrdiff_t n, const Matrix<double>& s)
  {
    const Rows& flex = args.flex;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t j = 0; j < n; ++j)
    {
      s(b, ETA + j) = y[q + j];
      s(b, ETA_RATE + j) = y[nq + q + j];
    }
    const auto inertia = inertia_of(flex, b, n, y, q);
    for (int k = 0; k < 9; ++k)
      s(b, JBODY + k) = inertia[k];
    for (int a = 0; a < 3; ++a)
      for (std::ptrdiff_t m = 0; m < n; ++m)
        s(b, GMAT + a * MODES + m) = g_row(flex, b, n, y, q, a, m);
    const double s00 = inertia[0] - g_dot(s, b, n, 0, 0), s01 = inertia[1] - g_dot(s, b, n, 0, 1),
                 s02 = inertia[2] - g_dot(s, b, n, 0, 2), s11 = inertia[4] - g_dot(s, b, n, 1, 1),
                 s12 = inertia[5] - g_dot(s, b, n, 1, 2), s22 = inertia[8] - g_dot(s, b, n, 2, 2);
    const auto inv = inverse3({s00, s01, s02, s01, s11, s12, s02, s12, s22});
    for (int r = 0; r < 3; ++r)
    {
      const V ar = row3(s, b, BODY_ROT + 3 * r);
      const V t{ar[0] * inv[0][0] + ar[1] * inv[1][0] + ar[2] * inv[2][0],
                ar[0] * inv[0][1] + ar[1] * inv[1][1] + ar[2] * inv[2][1],
                ar[0] * inv[0][2] + ar[1] * inv[1][2] + ar[2] * inv[2][2]};
      for (int k = 0; k <= r; ++k)
        s(b, BODY_JINV + 3 * r + k) = s(b, BODY_JINV + 3 * k + r) = dot(t, row3(s, b, BODY_ROT + 3 * k));
    }
    const auto faces = static_cast<std::ptrdiff_t>(flex(b, C_FACES));
    s(b, NFACES) = static_cast<double>(faces);
    for (std::ptrdiff_t k = 0; k < faces; ++k)
    {
      const std::ptrdiff_t at = flex_column(n, 6, k), f = FACES + k * FACE;
      for (int a = 0; a < 3; ++a)
      {
        s(b, f + F_CENTRE + a) = flex(b, at + a);
        double move = 0.0, turn = 0.0, move_rate = 0.0, turn_rate = 0.0;
        for (std::ptrdiff_t j = 0; j < n; ++j)
        {
          const double t = flex(b, at + 3 + a * n + j), r = flex(b, at + 3 + 3 * n + a * n + j);
          s(b, f + F_T + a * MODES + j) = t;
          s(b, f + F_R + a * MODES + j) = r;
          move += t * y[q + j];
          turn += r * y[q + j];
          move_rate += t * y[nq + q + j];
          turn_rate += r * y[nq + q + j];
        }
        s(b, f + F_MOVE + a) = move;
        s(b, f + F_TURN + a) = turn;
        s(b, f + F_MOVE_RATE + a) = move_rate;
        s(b, f + F_TURN_RATE + a) = turn_rate;
      }
    }
  }

  /// G v (body frame) of v = src[at .. at + n - 1].
  template <typename Get>
  static V modal_g(const Matrix<double>& s, std::ptrdiff_t b, Get&& v_of)
  {
    V out{0.0, 0.0, 0.0};
    for (std::ptrdiff_t m = 0; m < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++m)
    {
      const double v = v_of(m);
      out = {out[0] + s(b, GMAT + m) * v, out[1] + s(b, GMAT + MODES + m) * v,
             out[2] + s(b, GMAT + 2 * MODES + m) * v};
    }
    return out;
  }

  // ---- a flexible body's interfaces: a point moves with the frame of its nearest interface
  static std::ptrdiff_t face_of(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    double best = std::numeric_limits<double>::infinity();
    std::ptrdiff_t at = FACES;
    for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(s(b, NFACES)); ++k)
    {
      const std::ptrdiff_t f = FACES + k * FACE;
      const double d0 = p[0] - s(b, f), d1 = p[1] - s(b, f + 1), d2 = p[2] - s(b, f + 2);
      const double d = d0 * d0 + d1 * d1 + d2 * d2;
      if (d < best)
        best = d, at = f;
    }
    return at;
  }

  /// (p + u, u') of the body point p on the interface at column f (body frame).
  static std::pair<V, V> deformed(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t f,
                                  const V& p)
  {
    const V e = sub(p, row3(s, b, f + F_CENTRE));
    return {add(add(p, row3(s, b, f + F_MOVE)), cross(row3(s, b, f + F_TURN), e)),
            add(row3(s, b, f + F_MOVE_RATE), cross(row3(s, b, f + F_TURN_RATE), e))};
  }

  /// The body point whose deformed place is p, from the interface centre.
  static V undeformed(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t f, const V& p)
  {
    const V theta = row3(s, b, f + F_TURN);
    const V e = sub(sub(p, row3(s, b, f + F_CENTRE)), row3(s, b, f + F_MOVE));
    return scaled(add(sub(e, cross(theta, e)), scaled(theta, dot(theta, e))),
                  1.0 / (1.0 + dot(theta, theta)));
  }

  static V mode_t(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t f, std::ptrdiff_t j)
  {
    return {s(b, f + F_T + j), s(b, f + F_T + MODES + j), s(b, f + F_T + 2 * MODES + j)};
  }
  static V mode_r(const Matrix<double>& s, std::ptrdiff_t b, std::ptrdiff_t f, std::ptrdiff_t j)
  {
    return {s(b, f + F_R + j), s(b, f + F_R + MODES + j), s(b, f + F_R + 2 * MODES + j)};
  }

  /// Add sign (l . (T_k,j + R_k,j x e) + rho . R_k,j) to the modal columns of a row.
  static void modal_columns(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>& s,
                            std::ptrdiff_t b, std::ptrdiff_t f, const V& e, const V& l,
                            const V& rho, double sign, std::ptrdiff_t column)
  {
    const V arm = add(cross(e, l), rho);
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
      jac(row, column + j) += sign * (dot(l, mode_t(s, b, f, j)) + dot(arm, mode_r(s, b, f, j)));
  }

  /// Add the modes' generalised force of a force l (body frame) at e from the interface
  /// centre and a torque (body frame) on its frame: T_k^T l + R_k^T (e x l + torque).
  static void modal_forces(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                           std::ptrdiff_t f, const V& e, const V& l, const V& torque,
                           std::ptrdiff_t column)
  {
    const V arm = add(cross(e, l), torque);
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
      force[column + j] += dot(l, mode_t(s, b, f, j)) + dot(arm, mode_r(s, b, f, j));
  }

  // ---- points and vectors
  static Point point_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p)
  {
    if (b < 0)
      return {p, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    const V w = row3(s, b, BODY_OMEGA);
    if (flexible(s, b))   // P = r + A (p + u), P' = r' + w x A (p + u) + A u'
    {
      const auto [place, rate] = deformed(s, b, face_of(s, b, p), p);
      const V sp = turned(s, b, place), v = turned(s, b, rate);
      const V ws = cross(w, sp);
      return {add(row3(s, b, BODY_POS), sp), add(add(row3(s, b, BODY_VEL), ws), v),
              add(cross(w, ws), scaled(cross(w, v), 2.0)), sp};
    }
    const V arm = turned(s, b, p);
    const V ws = cross(w, arm);
    return {add(row3(s, b, BODY_POS), arm), add(row3(s, b, BODY_VEL), ws), cross(w, ws), arm};
  }

  static Vector vector_state(const Matrix<double>& s, std::ptrdiff_t b, const V& p, const V& v)
  {
    if (b < 0)
      return {v, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    const V w = row3(s, b, BODY_OMEGA);
    if (flexible(s, b))   // turned with the interface's frame by its small turn R_k eta
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      const V a = turned(s, b, add(v, cross(row3(s, b, f + F_TURN), v)));
      const V turn = turned(s, b, row3(s, b, f + F_TURN_RATE));
      const V big = add(w, turn);
      const V wa = cross(big, a);
      return {a, wa, add(cross(big, wa), cross(cross(w, turn), a))};
    }
    const V a = turned(s, b, v);
    const V wa = cross(w, a);
    return {a, wa, cross(w, wa)};
  }

  static V material_velocity(const Matrix<double>& s, std::ptrdiff_t b, const V& x)
  {
    if (b < 0)
      return {0.0, 0.0, 0.0};
    const V arm = sub(x, row3(s, b, BODY_POS));
    const V v = add(row3(s, b, BODY_VEL), cross(row3(s, b, BODY_OMEGA), arm));
    if (flexible(s, b))
    {
      const V p = unturned(s, b, arm);
      const std::ptrdiff_t f = face_of(s, b, p);
      const V rate = add(row3(s, b, f + F_MOVE_RATE),
                         cross(row3(s, b, f + F_TURN_RATE), undeformed(s, b, f, p)));
      return add(v, turned(s, b, rate));
    }
    return v;
  }

  static void put(const Matrix<double>& jac, std::ptrdiff_t row, const Matrix<double>& s,
                  std::ptrdiff_t b, const V& p, const V& linear, const A& angular, double sign,
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
    if (flexible(s, b))
    {
      const std::ptrdiff_t f = face_of(s, b, p);
      const V place = deformed(s, b, f, p).first;
      const V l = unturned(s, b, linear);
      const V rho = sub(unturned(s, b, angular), cross(place, l));   // less the arm x linear
      modal_columns(jac, row, s, b, f, sub(p, row3(s, b, f + F_CENTRE)), l, rho, sign, col + COLUMNS);
    }
  }

  static void push(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                   const V& f, const V& x, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const V arm = sub(x, row3(s, b, BODY_POS));
    const V torque = cross(arm, f);
    const std::ptrdiff_t col = offsets[b];
    for (int c = 0; c < 3; ++c)
    {
      force[col + c] += f[c];
      force[col + 3 + c] += torque[c];
    }
    if (flexible(s, b))
    {
      const V p = unturned(s, b, arm);
      const std::ptrdiff_t face = face_of(s, b, p);
      modal_forces(force, s, b, face, undeformed(s, b, face, p), unturned(s, b, f), zero<3>(),
                   col + COLUMNS);
    }
  }

  static void push_torque(std::span<double> force, const Matrix<double>& s, std::ptrdiff_t b,
                          const V& p, const A& torque, std::span<const std::int64_t> offsets)
  {
    if (b < 0)
      return;
    const std::ptrdiff_t col = offsets[b];
    for (int c = 0; c < 3; ++c)
      force[col + 3 + c] += torque[c];
    if (flexible(s, b))
      modal_forces(force, s, b, face_of(s, b, p), zero<3>(), zero<3>(), unturned(s, b, torque),
                   col + COLUMNS);
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
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
      rate += jac(i, col + COLUMNS + j) * s(b, ETA_RATE + j);
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
      const std::ptrdiff_t n = args.offsets[b + 1] - c - COLUMNS;
      s(b, FIRST) = static_cast<double>(c);
      s(b, COORD) = static_cast<double>(q);
      s(b, NMODES) = static_cast<double>(n);
      for (std::ptrdiff_t j = 0; j < n; ++j)
        work.velocities[c + COLUMNS + j] = y[nq + q + COORDINATES + j];
      if (n > 0)
      {
        flexible_state(args, y, b, q + COORDINATES, n, s);
        continue;
      }
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

  /// d/dt I_ac(eta), and d/dt (eta^T K_G,ac eta).
  static std::pair<double, double> moment_rate(const Rows& flex, std::ptrdiff_t b, std::ptrdiff_t n,
                                               const Matrix<double>& s, int a, int c)
  {
    const std::ptrdiff_t s_block = flex_column(n, 3, 0), big_s = flex_column(n, 4, 0),
                         kg = flex_column(n, 5, 0);
    const int ac = 3 * a + c, ca = 3 * c + a;
    double v = 0.0, k_rate = 0.0;
    for (std::ptrdiff_t k = 0; k < n; ++k)
    {
      const double ek = s(b, ETA + k), rk = s(b, ETA_RATE + k);
      v += rk * (flex(b, s_block + ac * n + k) + flex(b, s_block + ca * n + k));
      for (std::ptrdiff_t j = 0; j < n; ++j)
      {
        const double ej = s(b, ETA + j), rj = s(b, ETA_RATE + j);
        const double sv = flex(b, big_s + ac * n * n + k * n + j);
        v += sv * (rk * ej + ek * rj);
        k_rate += 2 * rk * flex(b, kg + ac * n * n + k * n + j) * ej;
      }
    }
    return {v, k_rate};
  }

  /// A flexible body's rotation torque -w x A h' - A J' w' and its modes' forces into its
  /// columns from col; the power of the modal damping.
  static double flexible_forces(const Rows& flex, std::ptrdiff_t b, const Matrix<double>& s,
                                std::span<double> force, std::ptrdiff_t col)
  {
    const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
    const std::ptrdiff_t omega2 = flex_column(n, 0, 0), damping = flex_column(n, 1, 0);
    const std::ptrdiff_t s_block = flex_column(n, 3, 0), big_s = flex_column(n, 4, 0),
                         kg = flex_column(n, 5, 0);
    const V w = row3(s, b, BODY_OMEGA);
    const V wb = unturned(s, b, w);
    const V jw = block_times(s, b, JBODY, wb);
    const V h = add(jw, modal_g(s, b, [&](std::ptrdiff_t m) { return s(b, ETA_RATE + m); }));
    const auto [i00, k00] = moment_rate(flex, b, n, s, 0, 0);
    const auto [i11, k11] = moment_rate(flex, b, n, s, 1, 1);
    const auto [i22, k22] = moment_rate(flex, b, n, s, 2, 2);
    const auto [i01, k01] = moment_rate(flex, b, n, s, 0, 1);
    const auto [i02, k02] = moment_rate(flex, b, n, s, 0, 2);
    const auto [i12, k12] = moment_rate(flex, b, n, s, 1, 2);
    const double trace = i00 + i11 + i22;
    const V jd0{trace - i00 - k00, -i01 - k01, -i02 - k02}, jd1{-i01 - k01, trace - i11 - k11, -i12 - k12},
        jd2{-i02 - k02, -i12 - k12, trace - i22 - k22};
    const V jdw{dot(jd0, wb), dot(jd1, wb), dot(jd2, wb)};
    const V torque = add(cross(w, turned(s, b, h)), turned(s, b, jdw));
    for (int c = 0; c < 3; ++c)
      force[col + 3 + c] = -torque[c];
    const double ww = dot(wb, wb);
    double power = 0.0;
    for (std::ptrdiff_t k = 0; k < n; ++k)
    {
      double centrifugal = 0.0;   // w'^T (dJ/deta_k) w' / 2
      for (int a = 0; a < 3; ++a)
        for (int c = 0; c < 3; ++c)
        {
          const int ac = 3 * a + c;
          double d = flex(b, s_block + ac * n + k), kgk = 0.0;
          for (std::ptrdiff_t j = 0; j < n; ++j)
          {
            d += flex(b, big_s + ac * n * n + k * n + j) * s(b, ETA + j);
            kgk += flex(b, kg + ac * n * n + k * n + j) * s(b, ETA + j);
          }
          if (a == c)
            centrifugal += ww * d;
          centrifugal -= wb[a] * wb[c] * (d + kgk);
        }
      double spin = 0.0;
      for (int a = 0; a < 3; ++a)
        for (std::ptrdiff_t m = 0; m < n; ++m)
          spin += wb[a] * gyroscopic(flex, b, n, a, k, m) * s(b, ETA_RATE + m);
      const double rate = s(b, ETA_RATE + k);
      force[col + COLUMNS + k] = (centrifugal + 2 * spin - flex(b, omega2 + k) * s(b, ETA + k)
                                  - flex(b, damping + k) * rate);
      power += flex(b, damping + k) * rate * rate;
    }
    return power;
  }

  /// Gravity and the gyroscopic torque -w x (J w) of each body; a flexible body's quadratic
  /// velocity, elastic and damping forces. The power the modal damping dissipates.
  static double body_forces(const Args& args, const Work& work)
  {
    const Matrix<double>& s = work.bodies;
    double power = 0.0;
    for (std::ptrdiff_t b = 0; b < s.rows; ++b)
    {
      const auto col = static_cast<std::ptrdiff_t>(s(b, FIRST));
      if (s(b, NMODES) > 0)
      {
        for (int c = 0; c < 3; ++c)
          work.force[col + c] = args.masses[b] * args.gravity[c];
        power += flexible_forces(args.flex, b, s, work.force, col);
        continue;
      }
      const V w = row3(s, b, BODY_OMEGA);
      const V gyro = cross(w, turned(s, b, matvec(args.inertia, b, unturned(s, b, w))));
      for (int c = 0; c < 3; ++c)
      {
        work.force[col + c] = args.masses[b] * args.gravity[c];
        work.force[col + 3 + c] = -gyro[c];
      }
    }
    return power;
  }

  /// out = M^-1 in over body b's columns (indexed as the force vector): the translation
  /// divided by the mass, the rotation and the modes coupled, a = sigma^-1 (v_w - B v_eta).
  /// in and out may be the same.
  static void inverse_mass(const Args& args, const Work& w, std::ptrdiff_t b, const double* in,
                           double* out)
  {
    const Matrix<double>& s = w.bodies;
    const std::ptrdiff_t col = args.offsets[b];
    V wv{in[col + 3], in[col + 4], in[col + 5]};
    if (s(b, NMODES) > 0)
      wv = sub(wv, turned(s, b, modal_g(s, b, [&](std::ptrdiff_t m) { return in[col + COLUMNS + m]; })));
    const V a = block_times(s, b, BODY_JINV, wv);
    for (int c = 0; c < 3; ++c)
    {
      out[col + c] = in[col + c] / args.masses[b];
      out[col + 3 + c] = a[c];
    }
    const V ab = unturned(s, b, a);
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(s(b, NMODES)); ++j)
      out[col + COLUMNS + j] = in[col + COLUMNS + j]
                               - (s(b, GMAT + j) * ab[0] + s(b, GMAT + MODES + j) * ab[1]
                                  + s(b, GMAT + 2 * MODES + j) * ab[2]);
  }

  static void mass_rows(const Args& args, const Work& w, std::ptrdiff_t i, std::ptrdiff_t b)
  {
    inverse_mass(args, w, b, w.jac.row(i), w.mjac.row(i));
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
      inverse_mass(args, work, b, work.force.data(), work.force.data());   // accelerations
      for (int c = 0; c < 3; ++c)
      {
        dy[i + c] = y[nq + i + c];
        dy[nq + i + c] = work.force[col + c];
      }
      for (int c = 0; c < 4; ++c)
        dy[i + 3 + c] = y[nq + i + 3 + c];
      const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
      const V wd{work.force[col + 3], work.force[col + 4], work.force[col + 5]};   // w' (global)
      for (std::ptrdiff_t j = 0; j < n; ++j)   // eta'' = Q_eta - B^T w'
      {
        dy[i + COORDINATES + j] = y[nq + i + COORDINATES + j];
        dy[nq + i + COORDINATES + j] = work.force[col + COLUMNS + j];
      }
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
      const auto n = static_cast<std::ptrdiff_t>(s(b, NMODES));
      double step[6];
      for (int c = 0; c < 6; ++c)
        step[c] = column_step(w.mjac, x, m, col + c, scale);
      if (level == 0)
      {
        for (int c = 0; c < 3; ++c)
          y[i + c] += step[c];
        turn(y, i + 3, {step[3], step[4], step[5]});
        for (std::ptrdiff_t j = 0; j < n; ++j)
          y[i + COORDINATES + j] += column_step(w.mjac, x, m, col + COLUMNS + j, scale);
      }
      else
      {
        for (int c = 0; c < 3; ++c)
          y[nq + i + c] += step[c];
        const V wv = add(row3(s, b, BODY_OMEGA), V{step[3], step[4], step[5]});
        const P4 pd = gt_times(unit_parameters(y, i + 3), scaled(unturned(s, b, wv), 0.5));
        for (int c = 0; c < 4; ++c)
          y[nq + i + 3 + c] = pd[c];
        for (std::ptrdiff_t j = 0; j < n; ++j)
          y[nq + i + COORDINATES + j] += column_step(w.mjac, x, m, col + COLUMNS + j, scale);
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
      const std::ptrdiff_t n = args.offsets[b + 1] - args.offsets[b] - COLUMNS;
      if (n == 0)
      {
        energy += 0.5 * args.masses[b] * dot(v, v) + 0.5 * dot(w, matvec(args.inertia, b, w));
        continue;
      }
      const std::ptrdiff_t q = i + COORDINATES;
      const auto j = inertia_of(args.flex, b, n, y, q);
      const V jw{j[0] * w[0] + j[1] * w[1] + j[2] * w[2], j[3] * w[0] + j[4] * w[1] + j[5] * w[2],
                 j[6] * w[0] + j[7] * w[1] + j[8] * w[2]};
      double coupling = 0.0, modal = 0.0;
      for (int a = 0; a < 3; ++a)
        for (std::ptrdiff_t mm = 0; mm < n; ++mm)
          coupling += w[a] * g_row(args.flex, b, n, y, q, a, mm) * y[nq + q + mm];
      for (std::ptrdiff_t mm = 0; mm < n; ++mm)
        modal += y[nq + q + mm] * y[nq + q + mm];
      energy += 0.5 * args.masses[b] * dot(v, v) + 0.5 * dot(w, jw) + coupling + 0.5 * modal;
    }
    return energy;
  }
};

} // namespace pinbore::mechanism
