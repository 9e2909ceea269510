// pinbore.core.cpp: the compiled core's Python module (nanobind). Each binding takes NumPy
// arrays (converted to C-contiguous doubles and int64 where they are not), checks their
// shapes, releases the GIL and calls the core; what it returns it allocates.
#include "laws_bindings.h"
#include "mechanism/bindings.h"
#include "plasticity.h"

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>

namespace nb = nanobind;

namespace
{
template <typename T, int D>
using In = nb::ndarray<const T, nb::ndim<D>, nb::c_contig, nb::device::cpu>;
using Out = nb::ndarray<nb::numpy, double>;

/// The elements of an input array, in order.
template <typename Array>
auto view(const Array& a)
{
  return std::span(a.data(), a.size());
}

/// A new C-contiguous array of doubles of this shape, owned by the returned object.
Out empty(std::initializer_list<std::size_t> shape)
{
  std::size_t size = 1;
  for (std::size_t s : shape)
    size *= s;
  double* data = new double[size];
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<double*>(p); });
  return Out(data, shape, owner);
}

std::span<double> span(Out& a) { return {a.data(), a.size()}; }

void expect(bool rule, const std::string& what)
{
  if (!rule)
    throw std::invalid_argument(what);
}
} // namespace

NB_MODULE(cpp, m)
{
  m.doc() = "pinbore's compiled core";
  pinbore::mechanism::bind_mechanism(m);
  pinbore::laws::bind_laws(m);

  m.def(
      "radial_return",
      [](In<double, 2> strain, In<double, 2> plastic_strain, In<double, 1> equivalent,
         In<double, 1> shear_modulus, In<double, 1> bulk_modulus, In<std::int64_t, 1> curve,
         In<double, 2> table_strains, In<double, 2> table_stresses,
         In<std::int64_t, 1> table_counts, In<double, 1> table_tails)
      {
        const std::size_t n = equivalent.shape(0);
        expect(strain.shape(0) == n and strain.shape(1) == 6 and plastic_strain.shape(0) == n
                   and plastic_strain.shape(1) == 6,
               "radial_return: strain and plastic_strain must be (n, 6), n the points");
        expect(shear_modulus.shape(0) == n and bulk_modulus.shape(0) == n and curve.shape(0) == n,
               "radial_return: shear_modulus, bulk_modulus and curve must have a value a point");
        const std::size_t m = table_counts.shape(0), width = table_strains.shape(1);
        expect(table_strains.shape(0) == m and table_stresses.shape(0) == m
                   and table_stresses.shape(1) == width and table_tails.shape(0) == m,
               "radial_return: the hardening tables must be (m, k), their counts and tails (m,)");
        for (std::size_t i = 0; i < n; ++i)
          expect(curve(i) >= -1 and curve(i) < static_cast<std::int64_t>(m),
                 "radial_return: curve names a table it was not given (-1: never yields)");
        for (std::size_t j = 0; j < m; ++j)
        {
          const std::int64_t count = table_counts(j);
          expect(count >= 1 and count <= static_cast<std::int64_t>(width),
                 "radial_return: a table's count must lie in [1, its width]");
          expect(table_strains(j, 0) == 0.0 and std::isfinite(table_tails(j)),
                 "radial_return: a table starts at plastic strain 0, its tail finite");
          for (std::int64_t k = 0; k < count; ++k)
            expect(std::isfinite(table_stresses(j, k))
                       and (k == 0 or table_strains(j, k) > table_strains(j, k - 1)),
                   "radial_return: a table's strains increase, its stresses are finite");
        }
        Out stress = empty({n, 6}), eps_p = empty({n, 6}), p = empty({n}), tangent = empty({n, 6, 6});
        {
          nb::gil_scoped_release release;
          pinbore::plasticity::radial_return(
              {view(strain), view(plastic_strain), view(equivalent), view(shear_modulus),
               view(bulk_modulus), view(curve)},
              {view(table_strains), view(table_stresses), width, view(table_counts),
               view(table_tails)},
              span(stress), span(eps_p), span(p), span(tangent));
        }
        return nb::make_tuple(stress, eps_p, p, tangent);
      },
      nb::arg("strain"), nb::arg("plastic_strain"), nb::arg("equivalent"),
      nb::arg("shear_modulus"), nb::arg("bulk_modulus"), nb::arg("curve"),
      nb::arg("table_strains"), nb::arg("table_stresses"), nb::arg("table_counts"),
      nb::arg("table_tails"),
      "Von Mises radial return with isotropic hardening at n points: (stress, plastic "
      "strain, equivalent plastic strain, consistent tangent).");

  m.def(
      "elastic_energy",
      [](In<double, 2> stress, In<double, 1> shear_modulus, In<double, 1> bulk_modulus)
      {
        const std::size_t n = stress.shape(0);
        expect(stress.shape(1) == 6 and shear_modulus.shape(0) == n and bulk_modulus.shape(0) == n,
               "elastic_energy: stress must be (n, 6), the moduli (n,)");
        Out out = empty({n});
        {
          nb::gil_scoped_release release;
          pinbore::plasticity::elastic_energy(view(stress), view(shear_modulus),
                                              view(bulk_modulus), span(out));
        }
        return out;
      },
      nb::arg("stress"), nb::arg("shear_modulus"), nb::arg("bulk_modulus"),
      "sigma : C^-1 : sigma / 2 (J/m^3) of stresses (n, 6) (Mandel).");
}
