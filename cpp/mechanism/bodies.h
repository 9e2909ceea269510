// What a body offers the joints, for every body kind K (planar.h, spatial.h): the state of a
// body point and of a body vector, and what the joints build of them. A body kind also gives
// a point's Jacobian columns (put), a force pushed at a point (push, push_torque), its
// relative rotations, its rows' rates, its body states, forces, mass-matrix solves, the
// projection's steps and its kinetic energy: the engine calls nothing else of it.
#pragma once

#include "data.h"

namespace pinbore::mechanism
{

/// A body point's position P, velocity P', the velocity part of its acceleration and its
/// arm P - r from the body's reference point (global axes).
template <class V>
struct PointState
{
  V position, velocity, centripetal, arm;
};

/// A body vector in global axes, its rate and the velocity part of its second derivative.
template <class V>
struct VectorState
{
  V value, rate, centripetal;
};

/// a_i . b_j of a vector of body i and one of body j ([Nikravesh1988] the dot-1
/// constraint): its value, the coefficient k of w_i (-k of w_j), its rate and the velocity
/// part of its second derivative.
template <class K>
struct Dot1
{
  double value;
  typename K::A coefficient;
  double rate, centripetal;
};

template <class K>
Dot1<K> dot1(const Matrix<double>& s, std::ptrdiff_t bi, const typename K::V& s_i,
             const typename K::V& a_i, std::ptrdiff_t bj, const typename K::V& s_j,
             const typename K::V& b_j)
{
  const auto a = K::vector_state(s, bi, s_i, a_i);
  const auto b = K::vector_state(s, bj, s_j, b_j);
  return {dot(a.value, b.value), cross(a.value, b.value),
          dot(a.rate, b.value) + dot(a.value, b.rate),
          dot(a.centripetal, b.value) + 2 * dot(a.rate, b.rate) + dot(a.value, b.centripetal)};
}

} // namespace pinbore::mechanism
