// The multibody engine's data: the columns of its row arrays and the codes stored in them
// (the same numbers as pinbore.reduced.mechanism.layout, which a test holds equal), small
// vectors of the plane and of space, views of the arrays, and the two bundles the engine
// passes around: the mechanism (Args) and the right-hand side's buffers (Work).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

namespace pinbore::mechanism
{

// ---- contacts (Args::contacts): one row per contact of a clearance joint
inline constexpr int CONTACT_CHI = 0, CONTACT_FRICTION_LAW = 1, CONTACT_FRICTION = 2,
                     CONTACT_STATE = 9, CONTACT_IMPACT = 10, CONTACT_RESTITUTION = 11,
                     CONTACT_REST_SPEED = 12, CONTACT_CHI_LOG_SPEED = 13, CONTACT_CHI_STEP = 14,
                     CONTACT_CHI_TABLE = 15, CHI_POINTS = 33;
inline constexpr int CONTACT_KIND = CONTACT_CHI_TABLE + CHI_POINTS;
inline constexpr int CONTACT_JOINT = CONTACT_KIND + 1, CONTACT_TABLE = CONTACT_KIND + 2,
                     CONTACT_BEARING_BODY = CONTACT_KIND + 3, CONTACT_JOURNAL_BODY = CONTACT_KIND + 4,
                     CONTACT_BEARING_POINT = CONTACT_KIND + 5, CONTACT_BEARING_AXIS = CONTACT_KIND + 8,
                     CONTACT_JOURNAL_POINT = CONTACT_KIND + 11, CONTACT_JOURNAL_AXIS = CONTACT_KIND + 14,
                     CONTACT_CLEARANCE = CONTACT_KIND + 17, CONTACT_RADIUS = CONTACT_KIND + 18,
                     CONTACT_SIDE = CONTACT_KIND + 19, CONTACT_AT_CONTACT = CONTACT_KIND + 20,
                     CONTACT_STIFFNESS = CONTACT_KIND + 21, CONTACT_FRICTION_ON = CONTACT_KIND + 22,
                     CONTACT_LENGTH = CONTACT_KIND + 23, CONTACT_SLICES = CONTACT_KIND + 24,
                     CONTACT_END_LENGTH = CONTACT_KIND + 25, CONTACT_SCALE = CONTACT_KIND + 26,
                     CONTACT_COMPLIANCE = CONTACT_KIND + 27, CONTACT_BORE_WEAR = CONTACT_KIND + 28,
                     CONTACT_PIN_WEAR = CONTACT_KIND + 29, CONTACT_BEARING_REFERENCE = CONTACT_KIND + 30,
                     CONTACT_JOURNAL_REFERENCE = CONTACT_KIND + 33, CONTACT_COLUMNS = CONTACT_KIND + 36;
inline constexpr int RADIAL = 0, SLICED = 1, PLANE = 2, AXIS_RADIAL = 3;
inline constexpr int NO_FRICTION = 0, COULOMB = 1, STRIBECK = 2, LINEAR = 3, LUGRE = 4, DAHL = 5,
                     IWAN = 6;
inline constexpr int COULOMB_MU = CONTACT_FRICTION, STRIBECK_MU_STATIC = CONTACT_FRICTION,
                     STRIBECK_MU_MIN = CONTACT_FRICTION + 1, STRIBECK_V_MIN = CONTACT_FRICTION + 2,
                     LINEAR_MU_STATIC = CONTACT_FRICTION, LINEAR_ALPHA = CONTACT_FRICTION + 1,
                     REGULARISATION_V0 = CONTACT_FRICTION + 5,
                     REGULARISATION_V1 = CONTACT_FRICTION + 6,
                     LUGRE_MU_COULOMB = CONTACT_FRICTION, LUGRE_MU_STATIC = CONTACT_FRICTION + 1,
                     LUGRE_STRIBECK_SPEED = CONTACT_FRICTION + 2, LUGRE_SIGMA0 = CONTACT_FRICTION + 3,
                     LUGRE_SIGMA1 = CONTACT_FRICTION + 4, LUGRE_SIGMA2 = CONTACT_FRICTION + 5,
                     DAHL_MU = CONTACT_FRICTION, DAHL_SIGMA = CONTACT_FRICTION + 1,
                     IWAN_K1 = CONTACT_FRICTION, IWAN_K2 = CONTACT_FRICTION + 1,
                     IWAN_MU = CONTACT_FRICTION + 2;
inline constexpr int STATE_TRAVEL = 0, STATE_STRETCH = 1;
inline constexpr int CONTINUOUS = 0, NEWTON = 1, POISSON = 2;

// ---- primitive constraints (Args::primitives)
inline constexpr int POINT = 0, DOT1 = 1, DOT2 = 2, ANGLE = 3;
inline constexpr int PRIM_KIND = 0, PRIM_BODY_I = 1, PRIM_BODY_J = 2, PRIM_S_I = 3, PRIM_S_J = 6,
                     PRIM_A_I = 9, PRIM_B_J = 12, PRIM_C_I = 15, PRIM_SPEED = 18, PRIM_ANGLE0 = 19,
                     PRIM_PROFILE = 20, PRIM_PROFILE_TIME = 21, PRIM_PROFILE_ROWS = 22,
                     PRIMITIVE_COLUMNS = 23;
inline constexpr int CONSTANT_SPEED = 0, SPIN_UP = 1, TABLE = 2, HARMONIC = 3;
inline constexpr int SEG_TIME = 0, SEG_C0 = 1, SEG_C1 = 2, SEG_C2 = 3, SEG_C3 = 4,
                     PROFILE_COLUMNS = 5;
inline constexpr int HARM_AMPLITUDE = 0, HARM_OMEGA = 1, HARM_PHASE = 2;

// ---- torsion elements, spring-dampers, harmonic loads
inline constexpr int TORSION_BODY_I = 0, TORSION_BODY_J = 1, TORSION_STIFFNESS = 2,
                     TORSION_DAMPING = 3, TORSION_FREE_ANGLE = 4, TORSION_KIND = 5,
                     TORSION_A_I = 6, TORSION_B_J = 9, TORSION_C_I = 12, TORSION_S_I = 15,
                     TORSION_S_J = 18, TORSION_COLUMNS = 21;
inline constexpr int SPRING = 0, STOP = 1, LATCH = 2;
inline constexpr int SPRING_BODY_I = 0, SPRING_BODY_J = 1, SPRING_S_I = 2, SPRING_S_J = 5,
                     SPRING_STIFFNESS = 8, SPRING_DAMPING = 9, SPRING_LENGTH = 10,
                     SPRING_COLUMNS = 11;
inline constexpr int LOAD_BODY = 0, LOAD_POINT = 1, LOAD_FORCE = 4, LOAD_TORQUE = 7,
                     LOAD_OMEGA = 10, LOAD_PHASE = 11, LOAD_COLUMNS = 12;

// ---- the state after q and q', the impact log, the integrator's codes
inline constexpr int DISSIPATED = 0, WORK_IN = 1, ENERGY_STATES = 2;
inline constexpr int LOG_TIME = 0, LOG_JOINT = 1, LOG_RATE = 2, LOG_IMPULSE = 3, LOG_COLUMNS = 4;
inline constexpr int OK = 0, BLOWN_UP = 1, TOO_MANY_STEPS = 2, STEP_TOO_SMALL = 3,
                     STOPPED = 4;   // the caller's stop() said so (a signal: the binding raises it)
inline constexpr int DOPRI5 = 0, DOPRI5_FIXED = 1, ROSENBROCK23 = 2;

// ---- small vectors: D = 2 (the plane) or 3 (space); an angular quantity is a float in the
// plane (about its normal) and a vector in space
template <int D>
struct Vec
{
  double v[D];
  double operator[](int i) const { return v[i]; }
  double& operator[](int i) { return v[i]; }
};
using Vec2 = Vec<2>;
using Vec3 = Vec<3>;
template <int D>
using Angular = std::conditional_t<D == 2, double, Vec<3>>;

template <int D>
Vec<D> add(const Vec<D>& a, const Vec<D>& b)
{
  Vec<D> out;
  for (int i = 0; i < D; ++i)
    out[i] = a[i] + b[i];
  return out;
}
template <int D>
Vec<D> sub(const Vec<D>& a, const Vec<D>& b)
{
  Vec<D> out;
  for (int i = 0; i < D; ++i)
    out[i] = a[i] - b[i];
  return out;
}
template <int D>
Vec<D> scaled(const Vec<D>& a, double k)
{
  Vec<D> out;
  for (int i = 0; i < D; ++i)
    out[i] = k * a[i];
  return out;
}
inline double scaled(double a, double k) { return k * a; }
template <int D>
Vec<D> negated(const Vec<D>& a)
{
  Vec<D> out;
  for (int i = 0; i < D; ++i)
    out[i] = -a[i];
  return out;
}
inline double negated(double a) { return -a; }
template <int D>
double dot(const Vec<D>& a, const Vec<D>& b)
{
  double out = a[0] * b[0];
  for (int i = 1; i < D; ++i)
    out += a[i] * b[i];
  return out;
}
inline double dot(double a, double b) { return a * b; }
/// a x b in the plane: two vectors give the normal component; an angular float w and a
/// vector b give w x b, a vector a and a float w give a x w.
inline double cross(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }
inline Vec2 cross(double a, const Vec2& b) { return {-a * b[1], a * b[0]}; }
inline Vec2 cross(const Vec2& a, double b) { return {a[1] * b, -a[0] * b}; }
inline Vec3 cross(const Vec3& a, const Vec3& b)
{
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
/// |a|: hypot in the plane, the root of a . a in space.
inline double norm(const Vec2& a) { return std::hypot(a[0], a[1]); }
inline double norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }
/// a / |a| given size = |a| > 0: divided in the plane, scaled by 1 / |a| in space.
inline Vec2 direction(const Vec2& a, double size) { return {a[0] / size, a[1] / size}; }
inline Vec3 direction(const Vec3& a, double size) { return scaled(a, 1.0 / size); }
/// The unit tangent (-n_y, n_x) of a unit normal in the plane.
inline Vec2 tangent(const Vec2& n) { return {-n[1], n[0]}; }
template <int D>
Vec<D> zero()
{
  return Vec<D>{};
}
template <int D>
Vec<D> axis(int c)
{
  Vec<D> out{};
  out[c] = 1.0;
  return out;
}

// ---- views of the arrays (row-major)
template <typename T>
struct Matrix
{
  T* data = nullptr;
  std::ptrdiff_t rows = 0, cols = 0;
  T& operator()(std::ptrdiff_t i, std::ptrdiff_t j) const { return data[i * cols + j]; }
  T* row(std::ptrdiff_t i) const { return data + i * cols; }
  template <int D>
  Vec<D> cell(std::ptrdiff_t r, int c) const
  {
    Vec<D> out;
    for (int k = 0; k < D; ++k)
      out[k] = static_cast<double>(data[r * cols + c + k]);
    return out;
  }
};
using Rows = Matrix<const double>;

/// The order p of a worn joint's overlap mean (worn.h; pinbore.reduced.mechanism.layout.WORN_ORDER).
inline constexpr int WORN_ORDER = 4;

/// A worn profile's bound (worn.h): a depth its spline never falls below.
struct WornBound
{
  double lowest = 0.0;
};

/// The mechanism (pinbore.reduced.mechanism.layout.Args): constants, but for the impact
/// speeds, latch flags and contact modes, which the integrator updates in place.
struct Args
{
  int nq = 0;
  bool project_first = false;
  std::span<const double> masses, minv;
  Rows inertia, inertia_inv;   // per body 3 x 3 (rows: body x 9)
  std::span<const double> gravity;
  std::span<const std::int64_t> offsets;
  Rows primitives;
  double baumgarte = 0.0;
  Rows contacts;
  std::span<double> speeds;
  double grid_log0 = 0.0, grid_step = 0.0;
  Rows tables;
  Rows torsion;
  std::span<double> latched;
  std::span<std::int64_t> mode;
  Rows profile, flex, springs, loads;
  Rows wear;   // worn profiles: a row per surface, its depth at angles evenly from -pi
  std::vector<WornBound> wear_bounds;   // per profile (worn.h: worn_bounds)
  std::ptrdiff_t bodies() const { return static_cast<std::ptrdiff_t>(masses.size()); }
  std::ptrdiff_t ncontacts() const { return contacts.rows; }
};

/// The right-hand side's buffers (pinbore.reduced.mechanism.layout.Work).
struct Work
{
  Matrix<double> bodies;
  std::span<double> velocities;
  Matrix<double> jac;
  std::span<double> phi, phi_t, rhs_c;
  Matrix<double> schur;
  std::span<double> force, normal, friction;
  Matrix<double> mjac;
  Matrix<std::int64_t> row_bodies;
  std::span<std::int64_t> first;
};

} // namespace pinbore::mechanism
