#pragma once
// Small fixed-size vector used for positions, velocities and accelerations.
// Dimension is a template parameter (DESIGN.md principle 3).
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"

namespace rubble {

template <int D>
struct Vec {
  static_assert(D >= 1 && D <= 3, "rubble supports 1, 2 and 3 dimensions");
  Real c[D];

  RUBBLE_HD_SMALL static Vec zero() {
    Vec v;
    for (int i = 0; i < D; ++i) v.c[i] = Real(0);
    return v;
  }
  RUBBLE_HD_SMALL Real& operator[](int i) { return c[i]; }
  RUBBLE_HD_SMALL const Real& operator[](int i) const { return c[i]; }

  RUBBLE_HD_SMALL Vec& operator+=(const Vec& o) {
    for (int i = 0; i < D; ++i) c[i] += o.c[i];
    return *this;
  }
  RUBBLE_HD_SMALL Vec& operator-=(const Vec& o) {
    for (int i = 0; i < D; ++i) c[i] -= o.c[i];
    return *this;
  }
  RUBBLE_HD_SMALL Vec& operator*=(Real s) {
    for (int i = 0; i < D; ++i) c[i] *= s;
    return *this;
  }
};

template <int D>
RUBBLE_HD_SMALL Vec<D> operator+(Vec<D> a, const Vec<D>& b) { return a += b; }
template <int D>
RUBBLE_HD_SMALL Vec<D> operator-(Vec<D> a, const Vec<D>& b) { return a -= b; }
template <int D>
RUBBLE_HD_SMALL Vec<D> operator-(Vec<D> a) { return a *= Real(-1); }
template <int D>
RUBBLE_HD_SMALL Vec<D> operator*(Vec<D> a, Real s) { return a *= s; }
template <int D>
RUBBLE_HD_SMALL Vec<D> operator*(Real s, Vec<D> a) { return a *= s; }

template <int D>
RUBBLE_HD_SMALL Real dot(const Vec<D>& a, const Vec<D>& b) {
  Real s = 0;
  for (int i = 0; i < D; ++i) s += a.c[i] * b.c[i];
  return s;
}
template <int D>
RUBBLE_HD_SMALL Real norm2(const Vec<D>& a) { return dot(a, a); }
template <int D>
RUBBLE_HD_SMALL Real norm(const Vec<D>& a) { return std::sqrt(dot(a, a)); }

}  // namespace rubble
