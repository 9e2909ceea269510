// The contact laws' Python bindings (pinbore.core.cpp.laws): the very functions the multibody
// engine evaluates (cpp/mechanism/laws.h), for pinbore.laws, the calibration, pinbore export
// and the tests. Scalars in, scalars or tuples out; a tabulated law takes its table as a NumPy
// array.
#include "laws_bindings.h"
#include "arrays.h"
#include "mechanism/laws.h"

#include <nanobind/ndarray.h>

#include <stdexcept>
#include <vector>

namespace nb = nanobind;
using pinbore::owned;

namespace pinbore::laws
{
namespace
{
using Table = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

/// A law's table: two points or more.
const double* tabulated(const Table& table)
{
  if (table.shape(0) < 2)
    throw std::invalid_argument("a tabulated law needs a table of two points or more");
  return table.data();
}

Section section(double ax, double ay, double bx, double by, double clearance, bool planar,
                double length, long slices, double log0, double step, const Table& table,
                double relief_length, double relief_depth)
{
  if (not(length > 0.0) or slices < 1 or not(step != 0.0))
    throw std::invalid_argument("sliced law: a positive length and at least one slice");
  return {ax, ay, bx, by, clearance, planar, length, slices, log0, step, tabulated(table),
          table.shape(0), relief_length, relief_depth};
}

Section plane(double length, long slices, double log0, double step, const Table& table,
              double relief_length, double relief_depth)
{
  return section(0.0, 0.0, 0.0, 0.0, 0.0, true, length, slices, log0, step, table,
                 relief_length, relief_depth);
}

} // namespace

void bind_laws(nb::module_& parent)
{
  nb::module_ m = parent.def_submodule(
      "laws", "The contact laws the multibody engine evaluates: friction, hysteresis damping, "
              "tabulated elastic laws, the bore's edge relief and the sliced joint law");
  using nb::arg;

  // ---- friction (cpp/mechanism/laws.h gives each law's formula and source)
  m.def("sgn", &sgn, arg("v"), "sgn v = 1 for v > 0, -1 otherwise.");
  m.def("coulomb", &coulomb, arg("v"), arg("normal"), arg("mu"),
        "Den Hartog 1931 [DenHartog1931] ([Cao2013] eq. 12): F = mu F_N sgn v.");
  m.def("ambrosio_factor", &ambrosio_factor, arg("v"), arg("v0"), arg("v1"),
        "Ambrosio 2003 [Ambrosio2003]: c_d = 0 for |v| <= v0, (|v| - v0)/(v1 - v0) up to v1, 1 "
        "above.");
  m.def("ambrosio", &ambrosio, arg("v"), arg("normal"), arg("mu"), arg("v0"), arg("v1"),
        "Ambrosio 2003 [Ambrosio2003], regularised Coulomb: F = mu c_d(|v|) F_N sgn v.");
  m.def("stribeck_polynomial", &stribeck_polynomial, arg("v"), arg("mu_s"), arg("mu_m"), arg("v_m"),
        "Thomsen & Fidlin 2003 [ThomsenFidlin2003] ([Cao2013] eq. 14): mu(|v|) = mu_s - k1 |v| + "
        "k3 |v|^3, k1 = 1.5 (mu_s - mu_m)/v_m, k3 = 0.5 (mu_s - mu_m)/v_m^3, held at mu_m for "
        "|v| >= v_m.");
  m.def("linear_velocity", &linear_velocity, arg("v"), arg("mu_s"), arg("alpha"),
        "[Cao2013] eq. 15: mu = mu_s + alpha |v| (alpha in s/m).");
  m.def("dahl_rate", &dahl_rate, arg("force"), arg("v"), arg("sigma"), arg("f_c"),
        arg("alpha") = 1.0,
        "Dahl 1976 [Dahl1976] ([Cao2013] eq. 16): dF/dt = sigma |b|^alpha sgn(b) v, "
        "b = 1 - (F / F_c) sgn v.");
  m.def("lugre_g", &lugre_g, arg("v"), arg("f_c"), arg("f_s"), arg("v_s"),
        "LuGre [CanudasDeWit1995] ([Cao2013] eq. 18): g(v) = F_c + (F_s - F_c) exp(-(v/v_s)^2).");
  m.def("lugre_rate", &lugre_rate, arg("z"), arg("v"), arg("sigma0"), arg("g"),
        "LuGre bristle state ([Cao2013] eq. 17): dz/dt = v - sigma0 |v| z / g(v).");
  m.def("lugre_force", &lugre_force, arg("z"), arg("z_rate"), arg("v"), arg("sigma0"),
        arg("sigma1"), arg("sigma2"), "LuGre friction force F = sigma0 z + sigma1 dz/dt + sigma2 v.");
  m.def(
      "iwan_bilinear",
      [](double travel, double stretch, double v, double k1, double k2, double f_cr)
      {
        const Iwan r = iwan_bilinear(travel, stretch, v, k1, k2, f_cr);
        return nb::make_tuple(r.force, r.travel_rate, r.stretch_rate);
      },
      arg("travel"), arg("stretch"), arg("v"), arg("k1"), arg("k2"), arg("f_cr"),
      "Bilinear Iwan element [Iwan1966] ([Cao2013] eq. 13): a Jenkins element (k1 with a "
      "slider of strength F_cr) beside a spring k2; (F = k1 z + k2 x, x' = v, z' = v while the "
      "slider sticks, 0 while it slides).");
  m.def("iwan_return_map", &iwan_return_map, arg("stretch"), arg("k1"), arg("f_cr"),
        "The Iwan slider after a step: a stretch beyond |k1 z| = F_cr returns to the limit.");

  // ---- damping and tabulated laws
  m.def("hysteresis_force", &hysteresis_force, arg("elastic"), arg("rate"), arg("impact_speed"),
        arg("chi"),
        "F = max(F_el (1 + chi d' / v0), 0): the Hunt-Crossley family, never pulling.");
  m.def(
      "table_force",
      [](double delta, double log0, double step, Table table)
      { return table_force(delta, log0, step, tabulated(table), table.shape(0)); },
      arg("delta"), arg("grid_log0"), arg("grid_step"), arg("table"),
      "f(delta) of a law tabulated as ln f on the grid ln delta_j = grid_log0 + j grid_step "
      "(log-log interpolation; the first segment's power law below; NaN above or where NaN).");
  m.def(
      "table_force_slope",
      [](double delta, double log0, double step, Table table)
      {
        const ForceSlope r = table_force_slope(delta, log0, step, tabulated(table), table.shape(0));
        return nb::make_tuple(r.force, r.slope);
      },
      arg("delta"), arg("grid_log0"), arg("grid_step"), arg("table"),
      "(f, df/d delta) of a tabulated law at delta > 0 (table_force).");

  // ---- the bore's edge relief
  m.def(
      "relief_at",
      [](double z, double z_low, double z_high, double length, double depth)
      {
        const Relief r = relief_at(z, z_low, z_high, length, depth);
        return nb::make_tuple(r.radius, r.slope, r.curvature);
      },
      arg("z"), arg("z_low"), arg("z_high"), arg("length"), arg("depth"),
      "Extra radius r (m), slope dr/dz and curvature (1/m) of the edge relief at z: the arc's "
      "sagitta r = R - sqrt(R^2 - x^2), R = (l^2 + d^2) / (2 d).");
  m.def(
      "relief_profile",
      [](nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu> z, double z_low,
         double z_high, double length, double depth)
      {
        const std::size_t n = z.shape(0);
        std::vector<double> out(3 * n);
        for (std::size_t k = 0; k < n; ++k)
        {
          const Relief r = relief_at(z.data()[k], z_low, z_high, length, depth);
          out[k] = r.radius, out[n + k] = r.slope, out[2 * n + k] = r.curvature;
        }
        return owned(std::move(out), {3, n});
      },
      arg("z"), arg("z_low"), arg("z_high"), arg("length"), arg("depth"),
      "relief_at at every point of z: a (3, n) array (m, -, 1/m).");

  // ---- the sliced cylindrical-joint law (pinbore.laws.sliced states it)
  m.def(
      "slice_geometry",
      [](long i, double length, long slices, double end_length)
      {
        const SliceGeometry g = slice_geometry(i, length, slices, end_length);
        return nb::make_tuple(g.offset, g.width, g.weight);
      },
      arg("i"), arg("length"), arg("slices"), arg("end_length"),
      "Slice i: its offset from the mid-plane, its width L/n and its weight (m).");
  m.def(
      "slice_contact",
      [](long i, double dx, double dy, double ax, double ay, double bx, double by,
         double clearance, bool planar, double length, long slices, double log0, double step,
         Table table, double relief_length, double relief_depth)
      {
        const SliceContact c = slice_contact(
            i, dx, dy, section(ax, ay, bx, by, clearance, planar, length, slices, log0, step,
                               table, relief_length, relief_depth));
        return nb::make_tuple(c.offset, c.approach, c.nx, c.ny, c.curvature, c.force, c.slope);
      },
      arg("i"), arg("dx"), arg("dy"), arg("ax"), arg("ay"), arg("bx"), arg("by"),
      arg("clearance"), arg("planar"), arg("length"), arg("slices"), arg("grid_log0"),
      arg("grid_step"), arg("table"), arg("relief_length"), arg("relief_depth"),
      "Slice i in the bore's section: (offset, approach, n_x, n_y, curvature, f, df/d delta).");
  m.def(
      "section_sums",
      [](double dx, double dy, double ax, double ay, double bx, double by, double clearance,
         bool planar, double length, long slices, double log0, double step, Table table,
         double relief_length, double relief_depth, double end_length, double scale)
      {
        const SectionSums r = section_sums(
            dx, dy, section(ax, ay, bx, by, clearance, planar, length, slices, log0, step, table,
                            relief_length, relief_depth),
            end_length, scale);
        return nb::make_tuple(r.fx, r.fy, r.mx, r.my, r.kxx, r.kxy, r.kyy, r.contact);
      },
      arg("dx"), arg("dy"), arg("ax"), arg("ay"), arg("bx"), arg("by"), arg("clearance"),
      arg("planar"), arg("length"), arg("slices"), arg("grid_log0"), arg("grid_step"),
      arg("table"), arg("relief_length"), arg("relief_depth"), arg("end_length"), arg("scale"),
      "The slices' resultants (F_x, F_y, M_x, M_y), stiffness (K_xx, K_xy, K_yy) and contact "
      "length at the bore displacement (dx, dy).");
  m.def(
      "bore_displacement",
      [](double ax, double ay, double bx, double by, double clearance, bool planar, double length,
         long slices, double log0, double step, Table table, double relief_length,
         double relief_depth, double end_length, double scale, double compliance)
      {
        const auto [dx, dy] = bore_displacement(
            section(ax, ay, bx, by, clearance, planar, length, slices, log0, step, table,
                    relief_length, relief_depth),
            end_length, scale, compliance);
        return nb::make_tuple(dx, dy);
      },
      arg("ax"), arg("ay"), arg("bx"), arg("by"), arg("clearance"), arg("planar"), arg("length"),
      arg("slices"), arg("grid_log0"), arg("grid_step"), arg("table"), arg("relief_length"),
      arg("relief_depth"), arg("end_length"), arg("scale"), arg("compliance"),
      "The bore's uniform displacement (d_x, d_y) under its bulk compliance (m^2/N).");
  m.def(
      "shared_approach",
      [](double delta, double theta, double length, long slices, double log0, double step,
         Table table, double relief_length, double relief_depth, double end_length, double scale,
         double compliance)
      {
        return shared_approach(delta, theta,
                               plane(length, slices, log0, step, table, relief_length, relief_depth),
                               end_length, scale, compliance);
      },
      arg("delta"), arg("theta"), arg("length"), arg("slices"), arg("grid_log0"),
      arg("grid_step"), arg("table"), arg("relief_length"), arg("relief_depth"),
      arg("end_length"), arg("scale"), arg("compliance"),
      "The approach delta - compliance F / L the slices share (m).");
  m.def(
      "sliced",
      [](double delta, double theta, double length, long slices, double log0, double step,
         Table table, double relief_length, double relief_depth, double end_length, double scale,
         double compliance)
      {
        const Sliced r = sliced(delta, theta,
                                plane(length, slices, log0, step, table, relief_length, relief_depth),
                                end_length, scale, compliance);
        return nb::make_tuple(r.force, r.moment, r.resultant, r.contact);
      },
      arg("delta"), arg("theta"), arg("length"), arg("slices"), arg("grid_log0"),
      arg("grid_step"), arg("table"), arg("relief_length"), arg("relief_depth"),
      arg("end_length"), arg("scale"), arg("compliance"),
      "(F (N), M (N m), z_F (m), contact length (m)) of a pin approached by delta and tilted "
      "by theta in its bore cut into slices.");
  m.def(
      "sliced_profile",
      [](double delta, double theta, double length, long slices, double log0, double step,
         Table table, double relief_length, double relief_depth, double end_length, double scale,
         double compliance)
      {
        Section s = plane(length, slices, log0, step, table, relief_length, relief_depth);
        s.ax = delta, s.bx = theta;
        const double shift = bore_displacement(s, end_length, scale, compliance).first;
        const auto n = static_cast<std::size_t>(slices);
        std::vector<double> z(n), approach(n), force(n);
        for (long i = 0; i < slices; ++i)
        {
          const SliceContact c = slice_contact(i, shift, 0.0, s);
          approach[i] = c.approach;
          force[i] = scale * c.force;
          z[i] = 0.5 * length + c.offset;
        }
        return nb::make_tuple(owned(std::move(z), {n}), owned(std::move(approach), {n}),
                              owned(std::move(force), {n}));
      },
      arg("delta"), arg("theta"), arg("length"), arg("slices"), arg("grid_log0"),
      arg("grid_step"), arg("table"), arg("relief_length"), arg("relief_depth"),
      arg("end_length"), arg("scale"), arg("compliance"),
      "The slices of `sliced`: their midpoints z_i (m), approaches (m) and per-length forces "
      "a f_loc (N/m).");
}

} // namespace pinbore::laws
