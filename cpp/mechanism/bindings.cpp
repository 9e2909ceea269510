// The multibody engine's Python bindings (pinbore.core.cpp.mechanism): each function takes
// the mechanism as pinbore.reduced.mechanism.layout.Args and, where Python keeps the
// right-hand side's buffers, layout.Work (namedtuples of NumPy arrays), reads their arrays in
// place (the impact speeds, latch flags and contact modes are updated in place, as the
// integrator does) and releases the GIL while it computes.
#include "bindings.h"
#include "../arrays.h"
#include "integrator.h"
#include "planar.h"
#include "spatial.h"
#include "worn.h"

#include <nanobind/ndarray.h>
#include <nanobind/stl/vector.h>
#include <nanobind/stl/string.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace nb = nanobind;
using pinbore::owned;

namespace pinbore::mechanism
{
namespace
{
template <typename T>
using Array = nb::ndarray<T, nb::c_contig, nb::device::cpu>;

/// The arrays a call reads, kept alive while it runs.
struct Held
{
  std::vector<nb::object> objects;
};

template <typename T>
Array<T> array(nb::handle bundle, const char* name, Held& held, int ndim)
{
  nb::object value = nb::getattr(bundle, name);
  Array<T> a;
  if (not nb::try_cast(value, a, false) or static_cast<int>(a.ndim()) != ndim)
    throw std::invalid_argument(std::string("mechanism: ") + name + " must be a C-contiguous "
                                + std::to_string(ndim) + "-D array of "
                                + (std::is_same_v<std::remove_const_t<T>, double> ? "float64" : "int64"));
  held.objects.push_back(value);
  return a;
}

template <typename T>
std::span<T> flat(nb::handle bundle, const char* name, Held& held)
{
  auto a = array<T>(bundle, name, held, 1);
  return {a.data(), a.shape(0)};
}

template <typename T>
Matrix<T> matrix(nb::handle bundle, const char* name, Held& held, int ndim = 2)
{
  auto a = array<T>(bundle, name, held, ndim);
  std::ptrdiff_t cols = 1;
  for (int d = 1; d < ndim; ++d)
    cols *= static_cast<std::ptrdiff_t>(a.shape(d));
  return {a.data(), static_cast<std::ptrdiff_t>(a.shape(0)), cols};
}

/// v as an index in [low, high), or one line naming it.
std::ptrdiff_t index_in(double v, std::ptrdiff_t low, std::ptrdiff_t high, const char* what)
{
  if (not std::isfinite(v) or v < static_cast<double>(low) or v >= static_cast<double>(high)
      or v != std::floor(v))
    throw std::invalid_argument(std::string("mechanism: ") + what + " must be an index in ["
                                + std::to_string(low) + ", " + std::to_string(high) + ")");
  return static_cast<std::ptrdiff_t>(v);
}

/// The rows' indices: bodies (-1: the ground), codes, tables, profile rows, states.
void check_rows(const Args& args)
{
  const std::ptrdiff_t nb_ = args.bodies();
  if (args.ncontacts() and args.tables.cols < 2)
    throw std::invalid_argument("mechanism: a law's table needs two points or more");
  for (std::ptrdiff_t k = 0; k < args.ncontacts(); ++k)
  {
    const Rows& c = args.contacts;
    index_in(c(k, CONTACT_KIND), 0, 4, "a contact's kind");
    index_in(c(k, CONTACT_BEARING_BODY), -1, nb_, "a contact's bearing body");
    index_in(c(k, CONTACT_JOURNAL_BODY), -1, nb_, "a contact's journal body");
    index_in(c(k, CONTACT_TABLE), 0, args.tables.rows, "a contact's table");
    index_in(c(k, CONTACT_FRICTION_LAW), 0, IWAN + 1, "a contact's friction law");
    index_in(c(k, CONTACT_IMPACT), 0, POISSON + 1, "a contact's impact model");
    index_in(c(k, CONTACT_STATE), -1, 1L << 40, "a contact's first friction state");
    if (static_cast<int>(c(k, CONTACT_KIND)) == SLICED)
      index_in(c(k, CONTACT_SLICES), 1, 1L << 20, "a sliced contact's slices");
  }
  for (std::ptrdiff_t k = 0; k < args.primitives.rows; ++k)
  {
    const Rows& p = args.primitives;
    index_in(p(k, PRIM_KIND), 0, ANGLE + 1, "a primitive's kind");
    index_in(p(k, PRIM_BODY_I), -1, nb_, "a primitive's body i");
    index_in(p(k, PRIM_BODY_J), -1, nb_, "a primitive's body j");
    if (static_cast<int>(p(k, PRIM_KIND)) != ANGLE)
      continue;
    const int profile = static_cast<int>(index_in(p(k, PRIM_PROFILE), 0, HARMONIC + 1, "a drive's profile"));
    if (profile == TABLE or profile == HARMONIC)
    {
      const std::ptrdiff_t first = index_in(p(k, PRIM_PROFILE_TIME), 0, args.profile.rows, "a drive's first profile row");
      index_in(p(k, PRIM_PROFILE_ROWS), 1, args.profile.rows - first + 1, "a drive's profile rows");
      if (args.profile.cols < (profile == TABLE ? PROFILE_COLUMNS : HARM_PHASE + 1))
        throw std::invalid_argument("mechanism: a drive's profile rows are too short");
    }
  }
  for (std::ptrdiff_t r = 0; r < args.torsion.rows; ++r)
  {
    index_in(args.torsion(r, TORSION_BODY_I), -1, nb_, "a torsion element's body i");
    index_in(args.torsion(r, TORSION_BODY_J), -1, nb_, "a torsion element's body j");
    index_in(args.torsion(r, TORSION_KIND), 0, LATCH + 1, "a torsion element's kind");
  }
  for (std::ptrdiff_t r = 0; r < args.springs.rows; ++r)
  {
    index_in(args.springs(r, SPRING_BODY_I), -1, nb_, "a spring's body i");
    index_in(args.springs(r, SPRING_BODY_J), -1, nb_, "a spring's body j");
  }
  for (std::ptrdiff_t r = 0; r < args.loads.rows; ++r)
    index_in(args.loads(r, LOAD_BODY), -1, nb_, "a load's body");
}

/// The friction states of every contact inside y (after q, q' and the energy integrals).
template <class K>
void check_states(const Args& args, std::size_t ny)
{
  const std::ptrdiff_t first = 2 * static_cast<std::ptrdiff_t>(args.nq) + ENERGY_STATES;
  for (std::ptrdiff_t k = 0; k < args.ncontacts(); ++k)
  {
    const auto index = static_cast<std::ptrdiff_t>(args.contacts(k, CONTACT_STATE));
    if (index < 0)
      continue;
    const int law = static_cast<int>(args.contacts(k, CONTACT_FRICTION_LAW));
    const std::ptrdiff_t point = (law == IWAN ? 2 : 1) * (K::D == 2 ? 1 : 3);
    const std::ptrdiff_t width
        = point * (static_cast<int>(args.contacts(k, CONTACT_KIND)) == SLICED
                       ? static_cast<std::ptrdiff_t>(args.contacts(k, CONTACT_SLICES)) : 1);
    if (index < first or index + width > static_cast<std::ptrdiff_t>(ny))
      throw std::invalid_argument("mechanism: a contact's friction states lie outside y");
  }
}

Args args_of(nb::handle a, Held& held)
{
  Args args;
  args.nq = nb::cast<int>(nb::getattr(a, "nq"));
  args.project_first = nb::cast<bool>(nb::getattr(a, "project_first"));
  args.masses = flat<const double>(a, "masses", held);
  args.minv = flat<const double>(a, "minv", held);
  args.inertia = matrix<const double>(a, "inertia", held, 3);
  args.inertia_inv = matrix<const double>(a, "inertia_inv", held, 3);
  args.gravity = flat<const double>(a, "gravity", held);
  args.offsets = flat<const std::int64_t>(a, "offsets", held);
  args.primitives = matrix<const double>(a, "primitives", held);
  args.baumgarte = nb::cast<double>(nb::getattr(a, "baumgarte"));
  args.contacts = matrix<const double>(a, "contacts", held);
  args.speeds = flat<double>(a, "speeds", held);
  args.grid_log0 = nb::cast<double>(nb::getattr(a, "grid_log0"));
  args.grid_step = nb::cast<double>(nb::getattr(a, "grid_step"));
  args.tables = matrix<const double>(a, "tables", held);
  args.torsion = matrix<const double>(a, "torsion", held);
  args.latched = flat<double>(a, "latched", held);
  args.mode = flat<std::int64_t>(a, "mode", held);
  args.profile = matrix<const double>(a, "profile", held);
  args.flex = matrix<const double>(a, "flex", held);
  args.springs = matrix<const double>(a, "springs", held);
  args.loads = matrix<const double>(a, "loads", held);
  args.wear = matrix<const double>(a, "wear", held);
  args.wear_bounds = worn_bounds(args.wear);
  const std::ptrdiff_t nb_ = args.bodies(), nc = args.ncontacts();
  if (static_cast<std::ptrdiff_t>(args.offsets.size()) != nb_ + 1 or args.offsets[0] != 0
      or args.offsets[nb_] != static_cast<std::int64_t>(args.minv.size()))
    throw std::invalid_argument("mechanism: offsets must hold each body's first velocity column "
                                "and their number");
  if (static_cast<std::ptrdiff_t>(args.speeds.size()) != nc
      or static_cast<std::ptrdiff_t>(args.mode.size()) != nc
      or static_cast<std::ptrdiff_t>(args.latched.size()) != args.torsion.rows)
    throw std::invalid_argument("mechanism: speeds and mode need a value a contact, latched "
                                "one a torsion element");
  if ((nc and args.contacts.cols != CONTACT_COLUMNS)
      or (args.primitives.rows and args.primitives.cols != PRIMITIVE_COLUMNS)
      or (args.torsion.rows and args.torsion.cols != TORSION_COLUMNS)
      or (args.springs.rows and args.springs.cols != SPRING_COLUMNS)
      or (args.loads.rows and args.loads.cols != LOAD_COLUMNS))
    throw std::invalid_argument("mechanism: a row array has the wrong number of columns");
  for (std::ptrdiff_t k = 0; k < nc; ++k)
  {
    index_in(args.contacts(k, CONTACT_TABLE), 0, args.tables.rows, "a contact's table");
    for (const int column : {CONTACT_BORE_WEAR, CONTACT_PIN_WEAR})
      if (args.contacts(k, column) != 0.0)
      {
        index_in(args.contacts(k, column), 1, args.wear.rows + 1, "a contact's worn profile");
        const int kind = static_cast<int>(args.contacts(k, CONTACT_KIND));
        if (args.wear.cols < 3 or not (kind == RADIAL or kind == SLICED))
          throw std::invalid_argument("mechanism: a worn profile is a journal's (RADIAL, SLICED), "
                                      "of 3 angles or more");
        if (kind == SLICED and args.contacts(k, CONTACT_COMPLIANCE) != 0.0)
          throw std::invalid_argument("mechanism: a worn SLICED contact takes no bulk compliance");
      }
  }
  check_rows(args);
  return args;
}

Work work_of(nb::handle w, Held& held)
{
  Work work;
  work.bodies = matrix<double>(w, "bodies", held);
  work.velocities = flat<double>(w, "velocities", held);
  work.jac = matrix<double>(w, "jac", held);
  work.phi = flat<double>(w, "phi", held);
  work.phi_t = flat<double>(w, "phi_t", held);
  work.rhs_c = flat<double>(w, "rhs_c", held);
  work.schur = matrix<double>(w, "schur", held);
  work.force = flat<double>(w, "force", held);
  work.normal = flat<double>(w, "normal", held);
  work.friction = flat<double>(w, "friction", held);
  work.mjac = matrix<double>(w, "mjac", held);
  work.row_bodies = matrix<std::int64_t>(w, "row_bodies", held);
  work.first = flat<std::int64_t>(w, "first", held);
  return work;
}

/// The dimension of a mechanism's body kind (the length of Args.like: 2 planar, 3 spatial),
/// its bodies checked to fit it, rigid or flexible (their modes within the core's bound).
std::size_t dimension_of(nb::handle a, const Args& args)
{
  const std::size_t dimension = nb::len(nb::getattr(a, "like"));
  const int columns = dimension == 2 ? Planar::COLUMNS : Spatial::COLUMNS;
  if (dimension != 2 and dimension != 3)
    throw std::invalid_argument("mechanism: like must be a vector of 2 or 3 components");
  for (std::ptrdiff_t b = 0; b < args.bodies(); ++b)
  {
    const std::ptrdiff_t modes = args.offsets[b + 1] - args.offsets[b] - columns;
    if (modes < 0 or modes > Planar::MODES)
      throw std::invalid_argument("mechanism: a body's velocity columns are its rigid ones and "
                                  "its modes (at most 24)");
    if (modes == 0)
      continue;
    const double faces = args.flex.rows == args.bodies() and args.flex.cols > 2 ? args.flex(b, 1) : -1.0;
    const std::ptrdiff_t needed = dimension == 2
                                      ? Planar::flex_column(modes, 5, static_cast<std::ptrdiff_t>(faces))
                                      : Spatial::flex_column(modes, 6, static_cast<std::ptrdiff_t>(faces));
    if (faces < 0 or faces > Planar::INTERFACES or args.flex.cols < needed)
      throw std::invalid_argument("mechanism: a flexible body's constants do not fit its modes");
  }
  // a spatial body has 7 coordinates (r, Euler parameters) for its 6 velocity columns
  const std::ptrdiff_t coordinates = args.offsets[args.bodies()] + (dimension == 3 ? args.bodies() : 0);
  if (args.nq != coordinates or args.gravity.size() != dimension or args.inertia.rows != args.bodies()
      or args.inertia.cols != 9 or args.inertia_inv.rows != args.bodies() or args.inertia_inv.cols != 9)
    throw std::invalid_argument("mechanism: nq, gravity or the inertia tensors do not fit the bodies");
  return dimension;
}

/// f<K>() called with the mechanism's body kind (dimension_of).
template <typename F>
auto with_kind(nb::handle a, const Args& args, F&& f)
{
  return dimension_of(a, args) == 2 ? f.template operator()<Planar>() : f.template operator()<Spatial>();
}

template <class K>
void check_work(const Args& args, const Work& w, std::size_t ny)
{
  const std::ptrdiff_t m = Engine<K>::constraint_count(args.primitives) + args.ncontacts();
  if (w.bodies.rows != args.bodies() or w.bodies.cols != K::BODY_COLUMNS
      or static_cast<std::ptrdiff_t>(w.velocities.size()) != args.offsets[args.bodies()]
      or w.jac.rows != m or w.jac.cols != args.offsets[args.bodies()] or w.mjac.rows != m
      or w.mjac.cols != w.jac.cols or w.schur.rows != m or w.schur.cols != m
      or static_cast<std::ptrdiff_t>(w.rhs_c.size()) != m
      or static_cast<std::ptrdiff_t>(w.first.size()) != m
      or static_cast<std::ptrdiff_t>(w.phi.size()) != m or static_cast<std::ptrdiff_t>(w.phi_t.size()) != m
      or w.row_bodies.rows != m or w.row_bodies.cols != 2
      or static_cast<std::ptrdiff_t>(w.force.size()) != args.offsets[args.bodies()]
      or static_cast<std::ptrdiff_t>(w.normal.size()) < std::max<std::ptrdiff_t>(args.ncontacts(), 1)
      or static_cast<std::ptrdiff_t>(w.friction.size()) < std::max<std::ptrdiff_t>(args.ncontacts(), 1))
    throw std::invalid_argument("mechanism: work is not this mechanism's workspace");
  for (std::ptrdiff_t i = 0; i < m; ++i)
    if (w.first[i] < 0 or w.first[i] > i or w.row_bodies(i, 0) < -1 or w.row_bodies(i, 0) >= args.bodies()
        or w.row_bodies(i, 1) < -1 or w.row_bodies(i, 1) >= args.bodies())
      throw std::invalid_argument("mechanism: work's constraint pattern is not this mechanism's");
  if (ny < static_cast<std::size_t>(2 * args.nq + ENERGY_STATES))
    throw std::invalid_argument("mechanism: y is shorter than the mechanism's state");
  check_states<K>(args, ny);
}

std::span<const double> values(const Array<const double>& a) { return {a.data(), a.size()}; }
std::span<double> values(const Array<double>& a) { return {a.data(), a.size()}; }

/// f(t, y) into dy; each contact's deepest penetration into depth, its journal point's
/// offset from its bearing point into offset and, given `direction`, the contact's direction
/// into it (rows of `width`: a worn journal's the normal of its arc's force); the ideal
/// joints' largest gap |Phi| (no held rows).
template <class K>
double observe(double t, std::span<const double> y, std::span<double> dy, const Args& args,
               const Work& work, double* depth, double* offset, std::ptrdiff_t width,
               double* direction = nullptr)
{
  using E = Engine<K>;
  E::rhs(t, y, dy, args, work);
  const Rows& contacts = args.contacts;
  for (std::ptrdiff_t k = 0; k < contacts.rows; ++k)
  {
    const auto d = E::contact_depth(args, work.bodies, k);
    depth[k] = d.delta;
    if (direction)
      for (int i = 0; i < K::D; ++i)
        direction[k * width + i] = d.normal[i];
    const auto e = sub(K::point_state(work.bodies, E::body(contacts, k, CONTACT_JOURNAL_BODY),
                                      contacts.cell<K::D>(k, CONTACT_JOURNAL_POINT)).position,
                       K::point_state(work.bodies, E::body(contacts, k, CONTACT_BEARING_BODY),
                                      contacts.cell<K::D>(k, CONTACT_BEARING_POINT)).position);
    for (int i = 0; i < K::D; ++i)
      offset[k * width + i] = e[i];
  }
  std::vector<std::int64_t> none(std::max<std::ptrdiff_t>(contacts.rows, 1), 0);
  const std::ptrdiff_t m = E::constraint_rows(t, args, work, 0.0, none);
  double gap = 0.0;
  for (std::ptrdiff_t i = 0; i < m; ++i)
    gap = std::max(gap, std::abs(work.phi[i]));
  return gap;
}

template <int D>
Vec<D> vec(const std::vector<double>& v, const char* name)
{
  if (v.size() != static_cast<std::size_t>(D))
    throw std::invalid_argument(std::string("mechanism: ") + name + " must have "
                                + std::to_string(D) + " components");
  Vec<D> out;
  for (int i = 0; i < D; ++i)
    out[i] = v[i];
  return out;
}
} // namespace

void bind_mechanism(nb::module_& parent)
{
  nb::module_ m = parent.def_submodule(
      "mechanism", "The multibody engine: rigid and flexible bodies in the plane and in space, "
                   "their joints, contacts and integrators");

  // the layout the engine reads its arrays by (pinbore.reduced.mechanism.layout names the
  // same numbers; a test holds them equal), and the most a flexible body may hold
  nb::dict layout;
#define PINBORE_LAYOUT(name) layout[#name] = name;
  PINBORE_LAYOUT(CONTACT_CHI) PINBORE_LAYOUT(CONTACT_FRICTION_LAW) PINBORE_LAYOUT(CONTACT_FRICTION)
  PINBORE_LAYOUT(CONTACT_STATE) PINBORE_LAYOUT(CONTACT_IMPACT) PINBORE_LAYOUT(CONTACT_RESTITUTION)
  PINBORE_LAYOUT(CONTACT_REST_SPEED) PINBORE_LAYOUT(CONTACT_CHI_LOG_SPEED)
  PINBORE_LAYOUT(CONTACT_CHI_STEP) PINBORE_LAYOUT(CONTACT_CHI_TABLE) PINBORE_LAYOUT(CHI_POINTS)
  PINBORE_LAYOUT(CONTACT_KIND) PINBORE_LAYOUT(CONTACT_JOINT) PINBORE_LAYOUT(CONTACT_TABLE)
  PINBORE_LAYOUT(CONTACT_BEARING_BODY) PINBORE_LAYOUT(CONTACT_JOURNAL_BODY)
  PINBORE_LAYOUT(CONTACT_BEARING_POINT) PINBORE_LAYOUT(CONTACT_BEARING_AXIS)
  PINBORE_LAYOUT(CONTACT_JOURNAL_POINT) PINBORE_LAYOUT(CONTACT_JOURNAL_AXIS)
  PINBORE_LAYOUT(CONTACT_CLEARANCE) PINBORE_LAYOUT(CONTACT_RADIUS) PINBORE_LAYOUT(CONTACT_SIDE)
  PINBORE_LAYOUT(CONTACT_AT_CONTACT) PINBORE_LAYOUT(CONTACT_STIFFNESS)
  PINBORE_LAYOUT(CONTACT_FRICTION_ON) PINBORE_LAYOUT(CONTACT_LENGTH) PINBORE_LAYOUT(CONTACT_SLICES)
  PINBORE_LAYOUT(CONTACT_END_LENGTH) PINBORE_LAYOUT(CONTACT_SCALE) PINBORE_LAYOUT(CONTACT_COMPLIANCE)
  PINBORE_LAYOUT(CONTACT_BORE_WEAR) PINBORE_LAYOUT(CONTACT_PIN_WEAR) PINBORE_LAYOUT(WORN_ORDER)
  PINBORE_LAYOUT(CONTACT_BEARING_REFERENCE) PINBORE_LAYOUT(CONTACT_JOURNAL_REFERENCE)
  PINBORE_LAYOUT(CONTACT_COLUMNS) PINBORE_LAYOUT(RADIAL) PINBORE_LAYOUT(SLICED) PINBORE_LAYOUT(PLANE)
  PINBORE_LAYOUT(AXIS_RADIAL) PINBORE_LAYOUT(NO_FRICTION) PINBORE_LAYOUT(COULOMB)
  PINBORE_LAYOUT(STRIBECK) PINBORE_LAYOUT(LINEAR) PINBORE_LAYOUT(LUGRE) PINBORE_LAYOUT(DAHL)
  PINBORE_LAYOUT(IWAN) PINBORE_LAYOUT(REGULARISATION_V0) PINBORE_LAYOUT(REGULARISATION_V1)
  PINBORE_LAYOUT(LUGRE_SIGMA0) PINBORE_LAYOUT(LUGRE_SIGMA1) PINBORE_LAYOUT(LUGRE_SIGMA2)
  PINBORE_LAYOUT(DAHL_SIGMA) PINBORE_LAYOUT(IWAN_K2) PINBORE_LAYOUT(IWAN_MU)
  PINBORE_LAYOUT(STATE_STRETCH) PINBORE_LAYOUT(CONTINUOUS) PINBORE_LAYOUT(NEWTON) PINBORE_LAYOUT(POISSON)
  PINBORE_LAYOUT(POINT) PINBORE_LAYOUT(DOT1) PINBORE_LAYOUT(DOT2) PINBORE_LAYOUT(ANGLE)
  PINBORE_LAYOUT(PRIM_KIND) PINBORE_LAYOUT(PRIM_BODY_I) PINBORE_LAYOUT(PRIM_BODY_J)
  PINBORE_LAYOUT(PRIM_S_I) PINBORE_LAYOUT(PRIM_S_J) PINBORE_LAYOUT(PRIM_A_I) PINBORE_LAYOUT(PRIM_B_J)
  PINBORE_LAYOUT(PRIM_C_I) PINBORE_LAYOUT(PRIM_SPEED) PINBORE_LAYOUT(PRIM_ANGLE0)
  PINBORE_LAYOUT(PRIM_PROFILE) PINBORE_LAYOUT(PRIM_PROFILE_TIME) PINBORE_LAYOUT(PRIM_PROFILE_ROWS)
  PINBORE_LAYOUT(PRIMITIVE_COLUMNS) PINBORE_LAYOUT(CONSTANT_SPEED) PINBORE_LAYOUT(SPIN_UP)
  PINBORE_LAYOUT(TABLE) PINBORE_LAYOUT(HARMONIC) PINBORE_LAYOUT(SEG_TIME) PINBORE_LAYOUT(SEG_C3)
  PINBORE_LAYOUT(PROFILE_COLUMNS) PINBORE_LAYOUT(HARM_AMPLITUDE) PINBORE_LAYOUT(HARM_OMEGA)
  PINBORE_LAYOUT(HARM_PHASE) PINBORE_LAYOUT(TORSION_BODY_I) PINBORE_LAYOUT(TORSION_BODY_J)
  PINBORE_LAYOUT(TORSION_STIFFNESS) PINBORE_LAYOUT(TORSION_DAMPING) PINBORE_LAYOUT(TORSION_FREE_ANGLE)
  PINBORE_LAYOUT(TORSION_KIND) PINBORE_LAYOUT(TORSION_A_I) PINBORE_LAYOUT(TORSION_B_J)
  PINBORE_LAYOUT(TORSION_C_I) PINBORE_LAYOUT(TORSION_S_I) PINBORE_LAYOUT(TORSION_S_J)
  PINBORE_LAYOUT(TORSION_COLUMNS) PINBORE_LAYOUT(SPRING) PINBORE_LAYOUT(STOP) PINBORE_LAYOUT(LATCH)
  PINBORE_LAYOUT(SPRING_BODY_I) PINBORE_LAYOUT(SPRING_BODY_J) PINBORE_LAYOUT(SPRING_S_I)
  PINBORE_LAYOUT(SPRING_S_J) PINBORE_LAYOUT(SPRING_STIFFNESS) PINBORE_LAYOUT(SPRING_DAMPING)
  PINBORE_LAYOUT(SPRING_LENGTH) PINBORE_LAYOUT(SPRING_COLUMNS) PINBORE_LAYOUT(LOAD_BODY)
  PINBORE_LAYOUT(LOAD_POINT) PINBORE_LAYOUT(LOAD_FORCE) PINBORE_LAYOUT(LOAD_TORQUE)
  PINBORE_LAYOUT(LOAD_OMEGA) PINBORE_LAYOUT(LOAD_PHASE) PINBORE_LAYOUT(LOAD_COLUMNS)
  PINBORE_LAYOUT(DISSIPATED) PINBORE_LAYOUT(WORK_IN) PINBORE_LAYOUT(ENERGY_STATES)
  PINBORE_LAYOUT(LOG_TIME) PINBORE_LAYOUT(LOG_JOINT) PINBORE_LAYOUT(LOG_RATE) PINBORE_LAYOUT(LOG_IMPULSE)
  PINBORE_LAYOUT(LOG_COLUMNS) PINBORE_LAYOUT(OK) PINBORE_LAYOUT(BLOWN_UP) PINBORE_LAYOUT(TOO_MANY_STEPS)
  PINBORE_LAYOUT(STEP_TOO_SMALL) PINBORE_LAYOUT(DOPRI5) PINBORE_LAYOUT(DOPRI5_FIXED)
  PINBORE_LAYOUT(ROSENBROCK23)
#undef PINBORE_LAYOUT
  m.attr("LAYOUT") = layout;
  m.attr("MODES") = Planar::MODES;
  m.attr("INTERFACES") = Planar::INTERFACES;
  m.attr("BODY_COLUMNS") = nb::make_tuple(Planar::BODY_COLUMNS, Spatial::BODY_COLUMNS);

  m.def(
      "workspace",
      [](nb::handle a)
      {
        Held held;
        const Args args = args_of(a, held);
        return with_kind(a, args, [&]<class K>()
        {
          Workspace<K> space(args);
          const auto nb_ = static_cast<std::size_t>(args.bodies());
          const auto cols = static_cast<std::size_t>(args.offsets[args.bodies()]);
          const std::size_t mm = space.phi.size(), nn = space.normal.size();
          return nb::make_tuple(
              owned(std::move(space.bodies), {nb_, std::size_t(K::BODY_COLUMNS)}),
              owned(std::move(space.velocities), {cols}), owned(std::move(space.jac), {mm, cols}),
              owned(std::move(space.phi), {mm}), owned(std::move(space.phi_t), {mm}),
              owned(std::move(space.rhs_c), {mm}), owned(std::move(space.schur), {mm, mm}),
              owned(std::move(space.force), {cols}), owned(std::move(space.normal), {nn}),
              owned(std::move(space.friction), {nn}), owned(std::move(space.mjac), {mm, cols}),
              owned(std::move(space.row_bodies), {mm, 2}), owned(std::move(space.first), {mm}));
        });
      },
      nb::arg("args"), "The right-hand side's buffers (the fields of layout.Work, in order).");

  m.def(
      "rhs",
      [](double t, Array<const double> y, Array<double> dy, nb::handle a, nb::handle w)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        with_kind(a, args, [&]<class K>()
        {
          check_work<K>(args, work, y.size());
          if (dy.size() != y.size())
            throw std::invalid_argument("rhs: dy must be as long as y");
          nb::gil_scoped_release release;
          Engine<K>::rhs(t, values(y), values(dy), args, work);
        });
      },
      nb::arg("t"), nb::arg("y"), nb::arg("dy"), nb::arg("args"), nb::arg("work"),
      "dy = f(t, y); the contacts' forces in work.normal and work.friction.");

  m.def(
      "integrate",
      [](Array<const double> y0, double t_end, nb::handle a, int method, double rtol,
         double atol, double max_step, double onset_tol, double speed_floor,
         std::int64_t max_steps)
      {
        Held held;
        const Args args = args_of(a, held);
        if (y0.size() < static_cast<std::size_t>(2 * args.nq + ENERGY_STATES))
          throw std::invalid_argument("integrate: y0 is shorter than the mechanism's state");
        if (method < DOPRI5 or method > ROSENBROCK23 or not(max_step > 0.0)
            or not std::isfinite(max_step) or not std::isfinite(t_end) or t_end < 0.0
            or not(rtol > 0.0) or not(atol > 0.0) or not std::isfinite(rtol)
            or not std::isfinite(atol) or not(onset_tol >= 0.0) or not(speed_floor > 0.0)
            or max_steps < 0)
          throw std::invalid_argument("integrate: unknown method, or a duration, step, tolerance, "
                                      "onset tolerance or speed floor that is not finite and positive");
        Integration out = with_kind(a, args, [&]<class K>()
        {
          check_states<K>(args, y0.size());
          nb::gil_scoped_release release;
          Workspace<K> space(args);
          Integrator<K> integrator(args, space.work, static_cast<std::ptrdiff_t>(y0.size()));
          // a signal's Python handler runs between steps: its exception (KeyboardInterrupt,
          // pinbore's Terminated) ends the run and is raised here, so a stop is prompt
          auto stop = []()
          {
            nb::gil_scoped_acquire acquire;
            return PyErr_CheckSignals() != 0;
          };
          return integrator.integrate(values(y0), t_end,
                                      {method, rtol, atol, max_step, onset_tol, speed_floor,
                                       max_steps, stop});
        });
        if (out.status == STOPPED)
          throw nb::python_error();
        const std::size_t n = out.count, ny = y0.size();
        const std::size_t wc = std::max<std::ptrdiff_t>(args.ncontacts(), 1),
                          wt = std::max<std::ptrdiff_t>(args.torsion.rows, 1);
        std::vector<std::int64_t> counters(out.counters.begin(), out.counters.end());
        return nb::make_tuple(owned(std::move(out.times), {n}), owned(std::move(out.states), {n, ny}),
                              owned(std::move(out.speeds), {n, wc}), owned(std::move(out.modes), {n, wc}),
                              owned(std::move(out.latched), {n, wt}),
                              owned(std::move(out.log), {out.impacts, std::size_t(LOG_COLUMNS)}),
                              owned(std::move(counters), {4}), out.status, out.t_end);
      },
      nb::arg("y0"), nb::arg("t_end"), nb::arg("args"), nb::arg("method"), nb::arg("rtol"),
      nb::arg("atol"), nb::arg("max_step"), nb::arg("onset_tol"), nb::arg("speed_floor"),
      nb::arg("max_steps"),
      "Integrate from t = 0 (the fields of layout.Integration, in order).");

  m.def(
      "observe",
      [](double t, Array<const double> y, Array<double> dy, nb::handle a, nb::handle w,
         Array<double> depth, Array<double> offset)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        return with_kind(a, args, [&]<class K>()
        {
          check_work<K>(args, work, y.size());
          const std::ptrdiff_t nc = args.ncontacts();
          if (dy.size() != y.size() or depth.size() < static_cast<std::size_t>(nc)
              or offset.ndim() != 2 or offset.shape(0) < static_cast<std::size_t>(nc)
              or (nc and offset.shape(1) < static_cast<std::size_t>(K::D)))
            throw std::invalid_argument("observe: dy as long as y, depth a value and offset a "
                                        "row a contact");
          nb::gil_scoped_release release;
          return observe<K>(t, values(y), values(dy), args, work, depth.data(), offset.data(),
                            nc ? static_cast<std::ptrdiff_t>(offset.shape(1)) : 0);
        });
      },
      nb::arg("t"), nb::arg("y"), nb::arg("dy"), nb::arg("args"), nb::arg("work"),
      nb::arg("depth"), nb::arg("offset"),
      "One state as the outputs see it: f(t, y) into dy, each contact's deepest penetration "
      "and journal offset; returns the ideal joints' largest gap |Phi|.");

  m.def(
      "observe_steps",
      [](Array<const double> times, Array<const double> states, Array<const double> speeds,
         Array<const double> latched, Array<const std::int64_t> modes, nb::handle a,
         nb::handle w, Array<double> rates, Array<double> bodies, Array<double> depths,
         Array<double> normals, Array<double> frictions, Array<double> offsets,
         Array<double> directions, Array<double> drift, Array<double> kinetic,
         Array<double> angles, Array<double> stretches)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        with_kind(a, args, [&]<class K>()
        {
          using E = Engine<K>;
          const std::size_t n = times.size();
          const std::size_t ny = states.ndim() == 2 ? states.shape(1) : 0;
          check_work<K>(args, work, ny);
          const auto nc = static_cast<std::size_t>(args.ncontacts());
          const auto nt = static_cast<std::size_t>(args.torsion.rows);
          const auto ns = static_cast<std::size_t>(args.springs.rows);
          if (bodies.ndim() != 3 or offsets.ndim() != 3 or speeds.ndim() != 2 or modes.ndim() != 2
              or latched.ndim() != 2 or states.ndim() != 2)
            throw std::invalid_argument("observe_steps: states, speeds, modes and latched are "
                                        "2-D, bodies and offsets 3-D");
          const std::size_t kept = bodies.shape(2);
          const std::size_t width = offsets.shape(2);
          auto rows = [n](const auto& x, std::size_t ndim, std::size_t columns)
          { return x.ndim() == ndim and x.shape(0) == n and (ndim == 1 or x.size() == n * columns); };
          auto wide = [n](const auto& x, std::size_t least)
          { return x.ndim() == 2 and x.shape(0) == n and x.shape(1) >= least; };
          if (states.shape(0) != n or not wide(speeds, nc) or not wide(modes, nc)
              or not wide(latched, nt) or not rows(rates, 2, ny) or bodies.shape(0) != n
              or bodies.shape(1) != static_cast<std::size_t>(args.bodies())
              or kept > static_cast<std::size_t>(K::BODY_COLUMNS) or not rows(depths, 2, nc)
              or not rows(normals, 2, nc) or not rows(frictions, 2, nc) or offsets.shape(0) != n
              or (nc and (width < static_cast<std::size_t>(K::D) or offsets.shape(1) != nc))
              or directions.ndim() != 3 or directions.shape(0) != n
              or (nc and (directions.shape(1) != nc or directions.shape(2) != width))
              or not rows(drift, 1, 1) or not rows(kinetic, 1, 1) or not rows(angles, 2, nt)
              or not rows(stretches, 2, ns))
            throw std::invalid_argument("observe_steps: the arrays must have a row a step of "
                                        "this mechanism's sizes");
          nb::gil_scoped_release release;
          const std::size_t sw = speeds.shape(1), mw = modes.shape(1), lw = latched.shape(1);
          std::vector<double> depth(std::max<std::size_t>(nc, 1)),
              offset(std::max<std::size_t>(nc, 1) * std::max<std::size_t>(width, 1)),
              direction(offset.size());
          for (std::size_t k = 0; k < n; ++k)
          {
            for (std::size_t i = 0; i < nc; ++i)
            {
              args.speeds[i] = speeds.data()[k * sw + i];
              args.mode[i] = modes.data()[k * mw + i];
            }
            for (std::size_t i = 0; i < nt; ++i)
              args.latched[i] = latched.data()[k * lw + i];
            std::span<const double> y(states.data() + k * ny, ny);
            std::span<double> dy(rates.data() + k * ny, ny);
            drift.data()[k] = observe<K>(times.data()[k], y, dy, args, work, depth.data(),
                                         offset.data(), static_cast<std::ptrdiff_t>(width),
                                         direction.data());
            for (std::ptrdiff_t b = 0; b < args.bodies(); ++b)
              for (std::size_t c = 0; c < kept; ++c)
                bodies.data()[(k * args.bodies() + b) * kept + c] = work.bodies(b, c);
            for (std::size_t i = 0; i < nc; ++i)
            {
              depths.data()[k * nc + i] = depth[i];
              normals.data()[k * nc + i] = work.normal[i];
              frictions.data()[k * nc + i] = work.friction[i];
              for (std::size_t c = 0; c < width; ++c)
              {
                offsets.data()[(k * nc + i) * width + c] = offset[i * width + c];
                directions.data()[(k * nc + i) * width + c] = direction[i * width + c];
              }
            }
            kinetic.data()[k] = K::kinetic_energy(args, y);
            // observe's right-hand side left y's body states in work
            for (std::size_t r = 0; r < nt; ++r)
              angles.data()[k * nt + r] = E::torsion_angle(work.bodies, args.torsion, r).first;
            for (std::size_t r = 0; r < ns; ++r)
              stretches.data()[k * ns + r] = E::spring_ends(work.bodies, args.springs, r).length
                                             - args.springs(r, SPRING_LENGTH);
          }
        });
      },
      nb::arg("times"), nb::arg("states"), nb::arg("speeds"), nb::arg("latched"),
      nb::arg("modes"), nb::arg("args"), nb::arg("work"), nb::arg("rates"), nb::arg("bodies"),
      nb::arg("depths"), nb::arg("normals"), nb::arg("frictions"), nb::arg("offsets"),
      nb::arg("directions"), nb::arg("drift"), nb::arg("kinetic"), nb::arg("angles"), nb::arg("stretches"),
      "observe (with each contact's direction), the kinetic energy, the torsion angles and the "
      "springs' stretches at every "
      "recorded step (each with the impact speeds, latches and modes it was taken with, put "
      "into args in place), into the rows of the output arrays.");

  m.def(
      "constraint_values",
      [](double t, Array<const double> y, nb::handle a)
      {
        Held held;
        const Args args = args_of(a, held);
        if (y.size() < static_cast<std::size_t>(2 * args.nq + ENERGY_STATES))
          throw std::invalid_argument("constraint_values: y is shorter than the mechanism's state");
        return with_kind(a, args, [&]<class K>()
        {
          Workspace<K> space(args);
          std::ptrdiff_t m;
          {
            nb::gil_scoped_release release;
            Engine<K>::refresh(args, values(y), space.work);
            m = Engine<K>::fill_constraints(t, args, space.work, 0.0);
          }
          const std::ptrdiff_t cols = args.offsets[args.bodies()];
          std::vector<double> jac(space.jac.begin(), space.jac.begin() + m * cols);
          std::vector<double> phi(space.phi.begin(), space.phi.begin() + m);
          std::vector<double> phi_t(space.phi_t.begin(), space.phi_t.begin() + m);
          const auto rows = static_cast<std::size_t>(m);
          return nb::make_tuple(owned(std::move(jac), {rows, static_cast<std::size_t>(cols)}),
                                owned(std::move(phi), {rows}), owned(std::move(phi_t), {rows}));
        });
      },
      nb::arg("t"), nb::arg("y"), nb::arg("args"),
      "(Phi_q, Phi, Phi_t) of the ideal joints, the drive and the held contacts.");

  m.def(
      "energy_of",
      [](Array<const double> y, nb::handle a)
      {
        Held held;
        const Args args = args_of(a, held);
        if (y.size() < static_cast<std::size_t>(2 * args.nq))
          throw std::invalid_argument("energy_of: y is shorter than the mechanism's state");
        return with_kind(a, args, [&]<class K>() { return K::kinetic_energy(args, values(y)); });
      },
      nb::arg("y"), nb::arg("args"), "The bodies' kinetic energy (J).");

  m.def(
      "project_onto_constraints",
      [](double t, Array<double> y, nb::handle a, nb::handle w, double tolerance,
         double rate_tolerance)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        return with_kind(a, args, [&]<class K>()
        {
          check_work<K>(args, work, y.size());
          nb::gil_scoped_release release;
          return Engine<K>::project_onto_constraints(t, values(y), args, work, tolerance,
                                                     rate_tolerance);
        });
      },
      nb::arg("t"), nb::arg("y"), nb::arg("args"), nb::arg("work"), nb::arg("tolerance"),
      nb::arg("rate_tolerance"),
      "One mass-weighted Gauss-Newton step of positions and of velocities onto the "
      "constraints where they drifted; whether one was taken.");

  m.def(
      "relative_motion",
      [](Array<const double> y, nb::handle a, nb::handle w, std::int64_t bb,
         std::vector<double> s_b, std::int64_t bj, std::vector<double> s_j,
         std::vector<double> f, std::vector<double> g)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        if (bb < -1 or bb >= args.bodies() or bj < -1 or bj >= args.bodies())
          throw std::invalid_argument("relative_motion: no such body");
        return with_kind(a, args, [&]<class K>()
        {
          constexpr int D = K::D;
          check_work<K>(args, work, y.size());
          Engine<K>::refresh(args, values(y), work);
          const Matrix<double>& s = work.bodies;
          const auto sb = vec<D>(s_b, "s_b");
          const auto pj = K::point_state(s, bj, vec<D>(s_j, "s_j")).position;
          const auto e = sub(pj, K::point_state(s, bb, sb).position);
          const auto v = sub(K::material_velocity(s, bj, pj), K::material_velocity(s, bb, pj));
          const auto ff = K::vector_state(s, bb, sb, vec<D>(f, "f")).value;
          const auto gg = K::vector_state(s, bb, sb, vec<D>(g, "g")).value;
          return nb::make_tuple(dot(e, ff), dot(e, gg), dot(v, ff), dot(v, gg));
        });
      },
      nb::arg("y"), nb::arg("args"), nb::arg("work"), nb::arg("bb"), nb::arg("s_b"),
      nb::arg("bj"), nb::arg("s_j"), nb::arg("f"), nb::arg("g"),
      "Body bj's point s_j relative to body bb's point s_b along bb's vectors f and g: "
      "(e.f, e.g, v.f, v.g).");

  m.def(
      "slice_approaches",
      [](Array<const double> y, nb::handle a, nb::handle w, std::int64_t k,
         Array<double> approaches, Array<double> weights)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        if (dimension_of(a, args) != 3)
          throw std::invalid_argument("slice_approaches: a sliced contact is spatial");
        check_work<Spatial>(args, work, y.size());
        using E = Engine<Spatial>;
        if (k < 0 or k >= args.ncontacts()
            or static_cast<int>(args.contacts(k, CONTACT_KIND)) != SLICED)
          throw std::invalid_argument("slice_approaches: k is not a sliced contact");
        const auto slices = static_cast<std::size_t>(args.contacts(k, CONTACT_SLICES));
        if (approaches.size() < slices or weights.size() < slices)
          throw std::invalid_argument("slice_approaches: approaches and weights need a value a slice");
        E::refresh(args, values(y), work);
        const Vec3 d = E::slice_penetrations(args, work.bodies, k, {approaches.data(), slices},
                                             {weights.data(), slices});
        return nb::make_tuple(d[0], d[1], d[2]);
      },
      nb::arg("y"), nb::arg("args"), nb::arg("work"), nb::arg("k"), nb::arg("approaches"),
      nb::arg("weights"),
      "The slices of sliced contact k with the bore moved by its bulk compliance: each "
      "slice's approach (m; a worn slice's penetration delta_p) and weight (m); returns the "
      "bore's displacement (global).");

  // ---- the engine's pieces, for the tests that check them alone
  m.def(
      "round_moment", [](double delta, double clearance)
      {
        const auto [value, slope] = round_moment(delta, clearance);
        return nb::make_tuple(value, slope);
      },
      nb::arg("delta"), nb::arg("clearance"),
      "(Phi, dPhi/d delta) of a round joint's overlap at the penetration delta > 0 (m): Phi = "
      "int d_+^4 dphi, d = (c + delta) cos phi - c (worn.h).");
  m.def(
      "moment_penetration", [](double moment, double clearance)
      {
        const auto [delta, slope] = moment_penetration(moment, clearance);
        return nb::make_tuple(delta, slope);
      },
      nb::arg("moment"), nb::arg("clearance"),
      "(delta_p, dPhi/d delta there) with round_moment(delta_p) = moment: a worn joint's "
      "penetration (worn.h).");
  m.def(
      "spin_up", [](double t, double speed, double duration)
      {
        const auto p = Engine<Planar>::spin_up(t, speed, duration);
        return nb::make_tuple(p.theta, p.rate, p.acceleration);
      },
      nb::arg("t"), nb::arg("speed"), nb::arg("duration"),
      "The drive's smooth spin-up [SimoVuQuoc1986]: (theta (rad), rate, acceleration).");

  m.def(
      "point_kinematics",
      [](Array<const double> y, nb::handle a, nb::handle w, std::int64_t b, std::vector<double> p,
         std::vector<double> f)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        if (b < 0 or b >= args.bodies())
          throw std::invalid_argument("point_kinematics: no such body");
        return with_kind(a, args, [&]<class K>()
        {
          constexpr int D = K::D;
          check_work<K>(args, work, y.size());
          Engine<K>::refresh(args, values(y), work);
          const Matrix<double>& s = work.bodies;
          const auto point = K::point_state(s, b, vec<D>(p, "p"));
          const auto material = K::material_velocity(s, b, point.position);
          std::vector<double> force(work.velocities.size(), 0.0);
          K::push(std::span<double>(force), s, b, vec<D>(f, "f"), point.position, args.offsets);
          std::vector<double> place(point.position.v, point.position.v + D),
              velocity(point.velocity.v, point.velocity.v + D), moving(material.v, material.v + D);
          return nb::make_tuple(owned(std::move(place), {std::size_t(D)}),
                                owned(std::move(velocity), {std::size_t(D)}),
                                owned(std::move(moving), {std::size_t(D)}),
                                owned(std::move(force), {work.velocities.size()}));
        });
      },
      nb::arg("y"), nb::arg("args"), nb::arg("work"), nb::arg("b"), nb::arg("p"), nb::arg("f"),
      "Body b's point p (body frame) at the state y: its place P and velocity P', the "
      "velocity of the material at P, and the generalised forces of the force f acting at P.");

  m.def(
      "sliced_forces",
      [](Array<const double> bodies, Array<const double> contacts, Array<const std::int64_t> offsets,
         Array<double> speeds, Array<const double> tables, double grid_log0, double grid_step,
         std::int64_t k)
      {
        if (bodies.ndim() != 2 or bodies.shape(1) != static_cast<std::size_t>(Spatial::BODY_COLUMNS)
            or contacts.ndim() != 2 or contacts.shape(1) != static_cast<std::size_t>(CONTACT_COLUMNS)
            or offsets.size() != bodies.shape(0) + 1 or speeds.size() != contacts.shape(0)
            or tables.ndim() != 2 or k < 0 or static_cast<std::size_t>(k) >= contacts.shape(0))
          throw std::invalid_argument("sliced_forces: spatial body rows, contact rows, offsets, a "
                                      "speed a contact and the law tables");
        Args args;
        args.contacts = {contacts.data(), static_cast<std::ptrdiff_t>(contacts.shape(0)), CONTACT_COLUMNS};
        args.offsets = {offsets.data(), offsets.size()};
        args.speeds = values(speeds);
        args.tables = {tables.data(), static_cast<std::ptrdiff_t>(tables.shape(0)),
                       static_cast<std::ptrdiff_t>(tables.shape(1))};
        args.grid_log0 = grid_log0, args.grid_step = grid_step;
        const auto nbodies = static_cast<std::ptrdiff_t>(bodies.shape(0));
        index_in(args.contacts(k, CONTACT_TABLE), 0, args.tables.rows, "the contact's table");
        index_in(args.contacts(k, CONTACT_BEARING_BODY), -1, nbodies, "the contact's bearing body");
        index_in(args.contacts(k, CONTACT_JOURNAL_BODY), -1, nbodies, "the contact's journal body");
        index_in(args.contacts(k, CONTACT_FRICTION_LAW), 0, LINEAR + 1, "the contact's (static) friction law");
        if (static_cast<int>(args.contacts(k, CONTACT_KIND)) != SLICED or args.contacts(k, CONTACT_STATE) >= 0
            or args.tables.cols < 2)
          throw std::invalid_argument("sliced_forces: k must be a sliced contact without states");
        index_in(args.contacts(k, CONTACT_SLICES), 1, 1L << 20, "the contact's slices");
        for (std::ptrdiff_t b = 0; b <= nbodies; ++b)
          if (offsets.data()[b] != Spatial::COLUMNS * b)
            throw std::invalid_argument("sliced_forces: offsets must be those of rigid bodies");
        for (std::ptrdiff_t b = 0; b < nbodies; ++b)
          if (bodies.data()[b * Spatial::BODY_COLUMNS + Spatial::NMODES] != 0.0
              or bodies.data()[b * Spatial::BODY_COLUMNS + Spatial::FIRST] != Spatial::COLUMNS * b)
            throw std::invalid_argument("sliced_forces: the body rows must be rigid bodies'");
        std::vector<double> rows(bodies.data(), bodies.data() + bodies.size());
        std::vector<double> force(offsets.data()[bodies.shape(0)], 0.0);
        Work work;
        work.bodies = {rows.data(), static_cast<std::ptrdiff_t>(bodies.shape(0)), Spatial::BODY_COLUMNS};
        work.force = force;
        const auto r = Engine<Spatial>::sliced_forces(args, work, {}, {}, k, true);
        return nb::make_tuple(owned(std::move(force), {work.force.size()}), r.normal, r.power,
                              r.tangential);
      },
      nb::arg("bodies"), nb::arg("contacts"), nb::arg("offsets"), nb::arg("speeds"),
      nb::arg("tables"), nb::arg("grid_log0"), nb::arg("grid_step"), nb::arg("k"),
      "A sliced contact's forces on the bodies of the spatial body rows given: (generalised "
      "forces, normal force N, dissipated power W, friction force N).");

  m.def(
      "elastic_force",
      [](Array<const double> contacts, std::int64_t k, double delta, double grid_log0,
         double grid_step, Array<const double> tables)
      {
        if (contacts.ndim() != 2 or contacts.shape(1) != static_cast<std::size_t>(CONTACT_COLUMNS)
            or k < 0 or static_cast<std::size_t>(k) >= contacts.shape(0) or tables.ndim() != 2)
          throw std::invalid_argument("elastic_force: contact rows, a contact and the law tables");
        Args args;
        args.contacts = {contacts.data(), static_cast<std::ptrdiff_t>(contacts.shape(0)), CONTACT_COLUMNS};
        args.tables = {tables.data(), static_cast<std::ptrdiff_t>(tables.shape(0)),
                       static_cast<std::ptrdiff_t>(tables.shape(1))};
        args.grid_log0 = grid_log0, args.grid_step = grid_step;
        const double named = args.contacts(k, CONTACT_TABLE);
        const auto table = std::isfinite(named) ? static_cast<std::ptrdiff_t>(named) : -1;
        if (not(args.contacts(k, CONTACT_STIFFNESS) > 0.0)
            and (not std::isfinite(args.contacts(k, CONTACT_TABLE)) or table < 0 or table >= args.tables.rows
                 or args.tables.cols < 2))
          throw std::invalid_argument("elastic_force: the contact names a table it was not given");
        return Engine<Planar>::elastic_force(args, k, delta);
      },
      nb::arg("contacts"), nb::arg("k"), nb::arg("delta"), nb::arg("grid_log0"),
      nb::arg("grid_step"), nb::arg("tables"),
      "F_el(delta) of contact k: its linear law, or its table (NaN beyond it).");

  m.def(
      "bore_section",
      [](Array<const double> y, nb::handle a, nb::handle w, std::int64_t k)
      {
        Held held;
        const Args args = args_of(a, held);
        const Work work = work_of(w, held);
        if (dimension_of(a, args) != 3 or k < 0 or k >= args.ncontacts()
            or static_cast<int>(args.contacts(k, CONTACT_KIND)) != SLICED)
          throw std::invalid_argument("bore_section: k must be a sliced contact of a spatial mechanism");
        check_work<Spatial>(args, work, y.size());
        Engine<Spatial>::refresh(args, values(y), work);
        const auto bore = Engine<Spatial>::bore_section(work.bodies, args.contacts, k);
        auto list = [](const Vec3& v) { return nb::make_tuple(v[0], v[1], v[2]); };
        return nb::make_tuple(list(bore.pj), list(bore.uj), list(bore.ub), list(bore.a0),
                              list(bore.a1));
      },
      nb::arg("y"), nb::arg("args"), nb::arg("work"), nb::arg("k"),
      "Sliced contact k in its bore's section at the state y: (the journal's point and axis, "
      "the bore's axis, the mid-plane eccentricity a0, the lean a1).");

  m.def(
      "cholesky_solve",
      [](Array<double> a, Array<double> b, std::int64_t m, Array<const std::int64_t> first)
      {
        if (a.ndim() != 2 or m < 0 or a.shape(0) < static_cast<std::size_t>(m)
            or a.shape(1) < static_cast<std::size_t>(m) or b.size() < static_cast<std::size_t>(m)
            or first.size() < static_cast<std::size_t>(m))
          throw std::invalid_argument("cholesky_solve: a (m x m or larger), b and first (m or longer)");
        for (std::int64_t i = 0; i < m; ++i)
          if (first.data()[i] < 0 or first.data()[i] > i)
            throw std::invalid_argument("cholesky_solve: first[i] must lie in [0, i]");
        cholesky_solve({a.data(), static_cast<std::ptrdiff_t>(a.shape(0)), static_cast<std::ptrdiff_t>(a.shape(1))},
                       values(b), m, {first.data(), first.size()});
      },
      nb::arg("a"), nb::arg("b"), nb::arg("m"), nb::arg("first"),
      "Solve a x = b in place (x in b) for the leading m x m block of a symmetric positive "
      "semi-definite a (its lower triangle, overwritten) within the envelope `first`; a "
      "dependent row's unknown is 0.");
}

} // namespace pinbore::mechanism
