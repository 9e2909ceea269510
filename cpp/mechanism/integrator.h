// The integrators of the mechanism: Dormand-Prince 5(4) [DormandPrince1980] with a PI
// step-size controller (on q, q' and the friction states; the energy integrals are outputs)
// and event location (a step ends at its first contact onset, held contact's release or
// latch), at a fixed step, or Rosenbrock 2(3) [ShampineReichelt1997]; and the mechanism's
// hooks: the contact state at
// the start, the fraction of a trial step that ends it at its first event, the updates of an
// accepted step (onsets with their impact speeds, impacts, held contacts, Iwan sliders,
// latches, the projection onto the constraints).
#pragma once

#include "engine.h"

#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <vector>

namespace pinbore::mechanism
{

/// A Work with its own buffers, sized for every constraint row (ideal, drive, a held row a
/// contact).
template <class K>
struct Workspace
{
  std::vector<double> bodies, velocities, jac, phi, phi_t, rhs_c, schur, force, normal, friction,
      mjac;
  std::vector<std::int64_t> row_bodies, first;
  Work work;

  explicit Workspace(const Args& args)
  {
    const std::ptrdiff_t nb = args.bodies(), nc = args.ncontacts();
    const std::ptrdiff_t columns = args.offsets[nb];
    const std::ptrdiff_t m = Engine<K>::constraint_count(args.primitives) + nc;
    bodies.assign(nb * K::BODY_COLUMNS, 0.0);
    velocities.assign(columns, 0.0);
    jac.assign(m * columns, 0.0);
    mjac.assign(m * columns, 0.0);
    phi.assign(m, 0.0);
    phi_t.assign(m, 0.0);
    rhs_c.assign(m, 0.0);
    schur.assign(m * m, 0.0);
    force.assign(columns, 0.0);
    normal.assign(std::max<std::ptrdiff_t>(nc, 1), 0.0);
    friction.assign(std::max<std::ptrdiff_t>(nc, 1), 0.0);
    row_bodies.assign(2 * m, -1);
    first.assign(m, 0);
    work = Work{{bodies.data(), nb, K::BODY_COLUMNS}, velocities, {jac.data(), m, columns},
                phi, phi_t, rhs_c, {schur.data(), m, m}, force, normal, friction,
                {mjac.data(), m, columns}, {row_bodies.data(), m, 2}, first};
    Engine<K>::constraint_pattern(args.primitives, work.row_bodies, work.first);
  }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;
};

/// What the integrator tracks of the contacts between accepted steps.
struct Tracked
{
  std::vector<double> depth, held_force, held_peak;
  std::vector<char> in_contact;
  bool impulse_contacts = false, iwan = false, latches = false;
};

template <class K>
struct Hooks
{
  using E = Engine<K>;
  static constexpr int D = K::D;

  static bool engage_latches(const Args& args, const Matrix<double>& s)
  {
    bool changed = false;
    for (std::ptrdiff_t r = 0; r < args.torsion.rows; ++r)
      if (args.latched[r] == 0.0 and static_cast<int>(args.torsion(r, TORSION_KIND)) == LATCH
          and E::torsion_angle(s, args.torsion, r).first > -LATCH_TOL)
      {
        args.latched[r] = 1.0;
        changed = true;
      }
    return changed;
  }

  /// The contact state at t = 0 (latches given as engaged engage) and what needs checking.
  static Tracked start(std::span<const double> y, const Args& args, double onset_tol)
  {
    Tracked tracked;
    const Rows& contacts = args.contacts;
    const std::ptrdiff_t nc = contacts.rows;
    for (std::ptrdiff_t k = 0; k < nc; ++k)
    {
      tracked.impulse_contacts |= static_cast<int>(contacts(k, CONTACT_IMPACT)) != CONTINUOUS;
      tracked.iwan |= static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) == IWAN;
    }
    for (std::ptrdiff_t r = 0; r < args.torsion.rows; ++r)
      tracked.latches |= static_cast<int>(args.torsion(r, TORSION_KIND)) == LATCH;
    Workspace<K> space(args);
    E::refresh(args, y, space.work);
    engage_latches(args, space.work.bodies);
    tracked.depth.assign(nc, 0.0);
    tracked.held_force.assign(nc, 0.0);
    tracked.held_peak.assign(nc, 0.0);
    tracked.in_contact.assign(nc, 0);
    for (std::ptrdiff_t k = 0; k < nc; ++k)
    {
      tracked.depth[k] = E::contact_depth(args, space.work.bodies, k).delta;
      tracked.in_contact[k] = tracked.depth[k] > -onset_tol
                              and static_cast<int>(contacts(k, CONTACT_IMPACT)) == CONTINUOUS;
    }
    return tracked;
  }

  /// The fraction of a step from depth to depth_new that ends it at the onset (1: none).
  static double onset_shortening(double depth, double depth_new, double onset_tol)
  {
    if (depth_new > onset_tol and depth < -onset_tol)
      return 0.99 * (-depth) / (depth_new - depth);
    if (depth_new > std::max(depth, 0.0) + onset_tol)
      return 0.5;
    return 1.0;
  }

  static double event_fraction(std::span<const double> y, std::span<const double> y_new,
                               double h, const Args& args, const Work& w, const Tracked& tr,
                               double onset_tol, double rtol, double event_dt)
  {
    const Matrix<double>& s = w.bodies;
    E::refresh(args, y_new, w);
    double shorten = 1.0;
    for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
      if (not tr.in_contact[k] and args.mode[k] == 0)
      {
        const double d_new = E::contact_depth(args, s, k).delta;
        shorten = std::min(shorten, onset_shortening(tr.depth[k], d_new, onset_tol));
      }
    if (tr.impulse_contacts and h > event_dt)
    {
      double release = 1.0;
      for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
        if (args.mode[k] == 1)
        {
          const double f_new = w.normal[k];
          if (tr.held_force[k] > 0.0 and f_new < -1e-3 * std::sqrt(rtol) * tr.held_peak[k])
            release = std::min(release, 0.99 * tr.held_force[k] / (tr.held_force[k] - f_new));
        }
      shorten = std::min(shorten, release);
    }
    if (tr.latches)
      for (std::ptrdiff_t r = 0; r < args.torsion.rows; ++r)
        if (args.latched[r] == 0.0 and static_cast<int>(args.torsion(r, TORSION_KIND)) == LATCH)
        {
          const double a_new = E::torsion_angle(s, args.torsion, r).first;
          if (a_new > LATCH_TOL)
          {
            E::refresh(args, y, w);
            const double a_old = E::torsion_angle(s, args.torsion, r).first;
            E::refresh(args, y_new, w);
            shorten = std::min(shorten, 0.99 * (-a_old) / (a_new - a_old));
          }
        }
    return shorten;
  }

  static bool release_held_contacts(double t, std::span<double> y, const Args& args,
                                    const Work& w, Tracked& tr)
  {
    bool changed = false;
    for (std::ptrdiff_t k = 0; k < args.contacts.rows; ++k)
      if (args.mode[k] == 1)
      {
        tr.held_force[k] = w.normal[k];
        tr.held_peak[k] = std::max(tr.held_peak[k], tr.held_force[k]);
        if (tr.held_force[k] < 0.0)
        {
          E::refresh(args, y, w);
          if (E::contact_depth(args, w.bodies, k).rate > 0.0)
            E::impulse_energy(y, args.nq, E::apply_impulse(t, y, args, w, k, 0.0));
          args.mode[k] = 0;
          changed = true;
        }
      }
    return changed;
  }

  static int iwan_states(const Rows& contacts, std::ptrdiff_t k)
  {
    const int per_point = D == 2 ? 2 : 6;
    if (static_cast<int>(contacts(k, CONTACT_KIND)) == SLICED)
      return per_point * static_cast<int>(contacts(k, CONTACT_SLICES));
    return per_point;
  }

  /// Per contact: the penetration; an impulse contact arriving takes its impact (or is
  /// held); a continuous one arriving records its impact speed and restarts its Iwan
  /// elements; one that left is marked free. Events into `events` (LOG_* rows).
  static std::pair<bool, int> onsets_and_impacts(double t, std::span<double> y, const Args& args,
                                                 const Work& w, Tracked& tr, double onset_tol,
                                                 double speed_floor, std::vector<double>& events)
  {
    const Rows& contacts = args.contacts;
    bool changed = false, current = false;
    int arrived = 0;
    for (std::ptrdiff_t k = 0; k < contacts.rows; ++k)
    {
      if (not current)
      {
        E::refresh(args, y, w);
        current = true;
      }
      const auto d = E::contact_depth(args, w.bodies, k);
      const double delta = d.delta, rate = d.rate;
      tr.depth[k] = delta;
      bool onset = false;
      double impulse = 0.0;
      if (static_cast<int>(contacts(k, CONTACT_IMPACT)) != CONTINUOUS)
      {
        if (args.mode[k] == 0 and delta > -onset_tol and rate > 0.0)
        {
          const double restitution = contacts(k, CONTACT_RESTITUTION);
          const double e = restitution * rate >= contacts(k, CONTACT_REST_SPEED) ? restitution : 0.0;
          impulse = E::impulse_energy(y, args.nq, E::apply_impulse(t, y, args, w, k, e));
          current = false;
          if (e == 0.0)
          {
            args.mode[k] = 1;
            tr.held_force[k] = tr.held_peak[k] = 0.0;
          }
          args.speeds[k] = rate;
          onset = true;
        }
      }
      else if (not tr.in_contact[k] and delta > -onset_tol)
      {
        tr.in_contact[k] = 1;
        args.speeds[k] = std::max(rate, speed_floor);
        if (static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) == IWAN)
        {
          const auto index = static_cast<std::ptrdiff_t>(contacts(k, CONTACT_STATE));
          for (std::ptrdiff_t i = index; i < index + iwan_states(contacts, k); ++i)
            y[i] = 0.0;
        }
        onset = true;
      }
      else if (tr.in_contact[k] and delta < -onset_tol)
        tr.in_contact[k] = 0;
      if (onset)
      {
        changed = true;
        double* e = events.data() + arrived * LOG_COLUMNS;
        e[LOG_TIME] = t;
        e[LOG_JOINT] = contacts(k, CONTACT_JOINT);
        e[LOG_RATE] = rate;
        e[LOG_IMPULSE] = impulse;
        ++arrived;
      }
    }
    return {changed, arrived};
  }

  /// The Iwan slider of every contact in contact held to |k1 z| <= mu F_n.
  static bool iwan_slider_return(std::span<double> y, const Args& args, const Work& w,
                                 const Tracked& tr)
  {
    const Rows& contacts = args.contacts;
    E::refresh(args, y, w);
    bool changed = false;
    for (std::ptrdiff_t k = 0; k < contacts.rows; ++k)
    {
      if (static_cast<int>(contacts(k, CONTACT_FRICTION_LAW)) != IWAN or not tr.in_contact[k])
        continue;
      if (static_cast<int>(contacts(k, CONTACT_KIND)) == SLICED)
      {
        if constexpr (D == 3)
          E::sliced_forces(args, w, y, y, k, false);
        continue;
      }
      double f_n = 0.0;
      typename K::V n;
      if (static_cast<int>(contacts(k, CONTACT_KIND)) == PLANE)
      {
        const auto p = E::plane_geometry(w.bodies, contacts, k);
        n = p.normal;
        if (p.delta > 0.0)
          f_n = laws::hysteresis_force(E::elastic_force(args, k, p.delta), p.rate, args.speeds[k],
                                       E::contact_chi(contacts, k, args.speeds[k]));
      }
      else
      {   // the normal force the contact's friction takes (a worn journal's: times its reach)
        const auto g = E::radial_geometry(args, w.bodies, k);
        n = g.normal;
        if (g.delta > 0.0)
          f_n = E::radial_normal(args, k, g, args.speeds[k]).force;
      }
      changed |= E::iwan_return(w.bodies, contacts, k, f_n, n, y,
                                static_cast<std::ptrdiff_t>(contacts(k, CONTACT_STATE)), 1.0);
    }
    return changed;
  }

  static std::pair<bool, int> after_step(double t, std::span<double> y, const Args& args,
                                         const Work& w, Tracked& tr, double onset_tol,
                                         double speed_floor, double rate_tol,
                                         std::vector<double>& events)
  {
    bool projected = args.project_first
                     and E::project_onto_constraints(t, y, args, w, onset_tol, rate_tol);
    const bool released = tr.impulse_contacts and release_held_contacts(t, y, args, w, tr);
    const auto [happened, arrived] = onsets_and_impacts(t, y, args, w, tr, onset_tol,
                                                        speed_floor, events);
    const bool slid = tr.iwan and iwan_slider_return(y, args, w, tr);
    bool engaged = false;
    if (tr.latches)
    {
      E::refresh(args, y, w);
      engaged = engage_latches(args, w.bodies);
    }
    if (not args.project_first)
      projected = E::project_onto_constraints(t, y, args, w, onset_tol, rate_tol);
    return {projected or released or happened or slid or engaged, arrived};
  }
};

/// What the integrator returns: per accepted step its time, state, impact speeds, contact
/// modes and latch flags; the impact log; counters (accepted, rejected, rhs calls, impacts);
/// the status and the time reached.
struct Integration
{
  std::vector<double> times, states, speeds, latched, log;
  std::vector<std::int64_t> modes;
  std::array<std::int64_t, 4> counters{};
  int status = OK;
  double t_end = 0.0;
  std::size_t count = 0, impacts = 0;
};

struct Settings
{
  int method;
  double rtol, atol, max_step, onset_tol, speed_floor;
  std::int64_t max_steps;
  /// Asked every STOP_POLL of wall time (if given): true ends the integration, status
  /// STOPPED (the binding's asks Python whether a signal came, so that a stop is prompt
  /// however long the run).
  std::function<bool()> stop = nullptr;
};

inline constexpr auto STOP_POLL = std::chrono::milliseconds(20);

namespace tableau
{
inline constexpr double C[7] = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
inline constexpr double A[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}};
inline constexpr double B5[7] = {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784,
                                 11.0 / 84, 0};
inline constexpr double B4[7] = {5179.0 / 57600, 0, 7571.0 / 16695, 393.0 / 640,
                                 -92097.0 / 339200, 187.0 / 2100, 1.0 / 40};
} // namespace tableau

template <class K>
struct Integrator
{
  using E = Engine<K>;
  using H = Hooks<K>;

  const Args& args;
  const Work& w;
  std::ptrdiff_t n;
  double e54[7];

  Integrator(const Args& a, const Work& work, std::ptrdiff_t size) : args(a), w(work), n(size)
  {
    for (int r = 0; r < 7; ++r)
      e54[r] = tableau::B5[r] - tableau::B4[r];
  }

  void f(double t, std::span<const double> y, std::span<double> dy) const
  {
    E::rhs(t, y, dy, args, w);
  }

  /// RMS of the local error scaled by atol + rtol |y|; the energy integrals are outputs.
  double error_norm(std::span<const double> err_vec, std::span<const double> y,
                    std::span<const double> y_new, double rtol, double atol) const
  {
    double err = 0.0;
    const std::ptrdiff_t nq = args.nq;
    for (std::ptrdiff_t i = 0; i < n; ++i)
    {
      if (2 * nq <= i and i < 2 * nq + ENERGY_STATES)
        continue;
      const double scale = atol + rtol * std::max(std::abs(y[i]), std::abs(y_new[i]));
      const double r = err_vec[i] / scale;
      err += r * r;
    }
    return std::sqrt(err / static_cast<double>(n - ENERGY_STATES));
  }

  /// One Dormand-Prince 5(4) step: k[0] = f(t, y) on entry, k[6] = f(t + h, y_new) on exit.
  int dopri5_step(double t, std::span<const double> y, double h, std::vector<double>& k,
                  std::span<double> y_new, std::span<double> err_vec) const
  {
    for (int s = 1; s < 7; ++s)
    {
      for (std::ptrdiff_t i = 0; i < n; ++i)
      {
        double v = y[i];
        for (int r = 0; r < s; ++r)
          v += h * tableau::A[s][r] * k[r * n + i];
        y_new[i] = v;
      }
      f(t + tableau::C[s] * h, y_new, std::span(k.data() + s * n, n));
    }
    for (std::ptrdiff_t i = 0; i < n; ++i)
    {
      double e = 0.0;
      for (int r = 0; r < 7; ++r)
        e += e54[r] * k[r * n + i];
      err_vec[i] = h * e;
    }
    return 6;
  }

  /// The LU factorisation of the n x n matrix a in place, with partial pivoting (rows
  /// swapped as in `perm`); false if a pivot is zero.
  static bool factorise(std::vector<double>& a, std::ptrdiff_t n, std::vector<std::ptrdiff_t>& perm)
  {
    perm.resize(n);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      perm[i] = i;
    for (std::ptrdiff_t c = 0; c < n; ++c)
    {
      std::ptrdiff_t p = c;
      for (std::ptrdiff_t r = c + 1; r < n; ++r)
        if (std::abs(a[r * n + c]) > std::abs(a[p * n + c]))
          p = r;
      if (a[p * n + c] == 0.0)
        return false;
      if (p != c)
      {
        for (std::ptrdiff_t j = 0; j < n; ++j)
          std::swap(a[c * n + j], a[p * n + j]);
        std::swap(perm[c], perm[p]);
      }
      for (std::ptrdiff_t r = c + 1; r < n; ++r)
      {
        const double l = a[r * n + c] /= a[c * n + c];
        for (std::ptrdiff_t j = c + 1; j < n; ++j)
          a[r * n + j] -= l * a[c * n + j];
      }
    }
    return true;
  }

  /// x = A^-1 b from factorise's LU of A.
  static void solve(const std::vector<double>& lu, const std::vector<std::ptrdiff_t>& perm,
                    std::ptrdiff_t n, const std::vector<double>& b, std::vector<double>& x)
  {
    for (std::ptrdiff_t i = 0; i < n; ++i)
    {
      double v = b[perm[i]];
      for (std::ptrdiff_t r = 0; r < i; ++r)
        v -= lu[i * n + r] * x[r];
      x[i] = v;
    }
    for (std::ptrdiff_t i = n - 1; i >= 0; --i)
    {
      double v = x[i];
      for (std::ptrdiff_t r = i + 1; r < n; ++r)
        v -= lu[i * n + r] * x[r];
      x[i] = v / lu[i * n + i];
    }
  }

  /// One linearly implicit Rosenbrock 2(3) step (Shampine & Reichelt 1997), W = I - h d J
  /// (factorised once, solved three times), J and df/dt by finite differences.
  /// k[0] = F0 on entry, k[6] = F2 on exit.
  int rosenbrock23_step(double t, std::span<const double> y, double h, std::vector<double>& k,
                        std::span<double> y_new, std::span<double> err_vec) const
  {
    const double d = 1.0 / (2.0 + std::sqrt(2.0)), e32 = 6.0 + std::sqrt(2.0);
    std::span<double> f0(k.data(), n), f1(k.data() + n, n), col(k.data() + 2 * n, n);
    std::vector<double> jacobian(n * n), ys(y.begin(), y.end()), tdot(n);
    std::vector<std::ptrdiff_t> perm;
    for (std::ptrdiff_t c = 0; c < n; ++c)
    {
      const double step = 1e-7 * std::max(std::abs(y[c]), 1e-6);
      ys[c] = y[c] + step;
      f(t, ys, col);
      for (std::ptrdiff_t r = 0; r < n; ++r)
        jacobian[r * n + c] = (col[r] - f0[r]) / step;
      ys[c] = y[c];
    }
    const double dt = 1e-7 * std::max(t, h);
    f(t + dt, y, col);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      tdot[i] = (col[i] - f0[i]) / dt;
    for (std::ptrdiff_t i = 0; i < n * n; ++i)
      jacobian[i] = -h * d * jacobian[i];
    for (std::ptrdiff_t i = 0; i < n; ++i)
      jacobian[i * n + i] += 1.0;
    if (not factorise(jacobian, n, perm))
    {
      for (std::ptrdiff_t i = 0; i < n; ++i)
        err_vec[i] = NaN;
      return n + 1;
    }
    auto apply = [&](const std::vector<double>& v, std::vector<double>& out)
    { solve(jacobian, perm, n, v, out); };
    std::vector<double> v(n), k1(n), k2(n), k3(n), mid(n);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      v[i] = f0[i] + h * d * tdot[i];
    apply(v, k1);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      mid[i] = y[i] + 0.5 * h * k1[i];
    f(t + 0.5 * h, mid, f1);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      v[i] = f1[i] - k1[i];
    apply(v, k2);
    for (std::ptrdiff_t i = 0; i < n; ++i)
    {
      k2[i] += k1[i];
      y_new[i] = y[i] + h * k2[i];
    }
    std::span<double> f2(k.data() + 6 * n, n);
    f(t + h, y_new, f2);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      v[i] = f2[i] - e32 * (k2[i] - f1[i]) - 2.0 * (k1[i] - f0[i]) + h * d * tdot[i];
    apply(v, k3);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      err_vec[i] = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]);
    return static_cast<int>(n) + 4;
  }

  /// Integrate from t = 0 to t_end (layout's DOPRI5, DOPRI5_FIXED or ROSENBROCK23).
  Integration integrate(std::span<const double> y0, double t_end, const Settings& set) const
  {
    Integration out;
    const bool adaptive = set.method != DOPRI5_FIXED;
    const double event_dt = 1e-8 * set.max_step;
    const double exponent = set.method == ROSENBROCK23 ? 1.0 / 3.0 : 0.2;
    double t = 0.0;
    std::vector<double> y(y0.begin(), y0.end());
    Tracked tracked = H::start(y, args, set.onset_tol);
    const std::ptrdiff_t nc = args.contacts.rows, nt = args.torsion.rows;
    const std::ptrdiff_t wc = std::max<std::ptrdiff_t>(nc, 1), wt = std::max<std::ptrdiff_t>(nt, 1);
    std::vector<double> events(std::max<std::ptrdiff_t>(nc, 1) * LOG_COLUMNS);
    std::vector<double> k(7 * n), y_new(n), err_vec(n);
    f(t, y, std::span(k.data(), n));
    std::int64_t calls = 1, accepted = 0, rejected = 0;
    double h = adaptive ? std::min(set.max_step, 1e-6) : set.max_step;
    double err_prev = 1e-4;
    auto record = [&]()
    {
      out.times.push_back(t);
      out.states.insert(out.states.end(), y.begin(), y.end());
      const std::size_t at = out.speeds.size();
      out.speeds.resize(at + wc, 0.0);
      out.modes.resize(at + wc, 0);
      out.latched.resize(out.latched.size() + wt, 0.0);
      for (std::ptrdiff_t i = 0; i < nc; ++i)
      {
        out.speeds[at + i] = args.speeds[i];
        out.modes[at + i] = args.mode[i];
      }
      for (std::ptrdiff_t i = 0; i < nt; ++i)
        out.latched[out.latched.size() - wt + i] = args.latched[i];
      ++out.count;
    };
    record();
    int status = OK;
    bool last_nan = false;
    auto polled = std::chrono::steady_clock::now();
    while (t < t_end)
    {
      if (set.stop and (accepted + rejected) % 16 == 0
          and std::chrono::steady_clock::now() - polled >= STOP_POLL)
      {
        polled = std::chrono::steady_clock::now();
        if (set.stop())
        {
          status = STOPPED;
          break;
        }
      }
      if (accepted + rejected >= set.max_steps)
      {
        status = TOO_MANY_STEPS;
        break;
      }
      h = std::min(std::min(h, t_end - t), set.max_step);
      if (h < 1e-15 * std::max(t, 1e-3))
      {
        status = last_nan ? BLOWN_UP : STEP_TOO_SMALL;
        break;
      }
      if (set.method == ROSENBROCK23)
        calls += rosenbrock23_step(t, y, h, k, y_new, err_vec);
      else
        calls += dopri5_step(t, y, h, k, y_new, err_vec);
      const double err = error_norm(err_vec, y, y_new, set.rtol, set.atol);
      last_nan = not std::isfinite(err);
      if (last_nan)
      {
        ++rejected;
        h *= 0.1;
        continue;
      }
      if (adaptive and err > 1.0)
      {
        ++rejected;
        h *= std::max(0.2, 0.9 * std::pow(err, -exponent));
        continue;
      }
      if (adaptive)
      {
        const double shorten = H::event_fraction(y, y_new, h, args, w, tracked, set.onset_tol,
                                                 set.rtol, event_dt);
        if (shorten < 1.0)
        {
          ++rejected;
          h *= std::max(shorten, 1e-3);
          continue;
        }
      }
      t += h;
      std::copy(y_new.begin(), y_new.end(), y.begin());
      ++accepted;
      std::copy(k.begin() + 6 * n, k.begin() + 7 * n, k.begin());
      const auto [changed, arrived] = H::after_step(t, y, args, w, tracked, set.onset_tol,
                                                    set.speed_floor,
                                                    set.onset_tol / set.max_step, events);
      for (int i = 0; i < arrived; ++i)
      {
        out.log.insert(out.log.end(), events.begin() + i * LOG_COLUMNS,
                       events.begin() + (i + 1) * LOG_COLUMNS);
        ++out.impacts;
      }
      if (changed)
      {
        f(t, y, std::span(k.data(), n));
        ++calls;
      }
      record();
      if (adaptive)
      {
        const double factor = err > 0 ? 0.9 * std::pow(err, -0.7 * exponent)
                                             * std::pow(err_prev, 0.4 * exponent)
                                       : 5.0;
        h = h * std::min(5.0, std::max(0.2, factor));
        err_prev = std::max(err, 1e-4);
      }
    }
    out.counters = {accepted, rejected, calls, static_cast<std::int64_t>(out.impacts)};
    out.status = status;
    out.t_end = t;
    return out;
  }
};

} // namespace pinbore::mechanism
