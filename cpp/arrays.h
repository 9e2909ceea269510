// The NumPy arrays the compiled core's bindings return: a vector's storage handed to NumPy
// and freed with the array.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <cstddef>
#include <initializer_list>
#include <utility>
#include <vector>

namespace pinbore
{
template <typename T>
nanobind::ndarray<nanobind::numpy, T> owned(std::vector<T>&& data,
                                            std::initializer_list<std::size_t> shape)
{
  auto* heap = new std::vector<T>(std::move(data));
  nanobind::capsule owner(heap, [](void* p) noexcept { delete static_cast<std::vector<T>*>(p); });
  return nanobind::ndarray<nanobind::numpy, T>(heap->data(), shape, owner);
}
} // namespace pinbore
