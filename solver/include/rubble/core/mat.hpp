#pragma once
// Small D x D matrix for velocity gradients, strain and rotation rates and
// the deviatoric stress (stored full, symmetric where the physics says so).
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

template <int D>
struct Mat {
  Real m[D][D];

  RUBBLE_HD_SMALL static Mat zero() {
    Mat a;
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) a.m[i][j] = Real(0);
    return a;
  }
  RUBBLE_HD_SMALL static Mat identity() {
    Mat a = zero();
    for (int i = 0; i < D; ++i) a.m[i][i] = Real(1);
    return a;
  }
  // u (x) v: (u v^T)_ij = u_i v_j
  RUBBLE_HD_SMALL static Mat outer(const Vec<D>& u, const Vec<D>& v) {
    Mat a;
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) a.m[i][j] = u[i] * v[j];
    return a;
  }
  RUBBLE_HD_SMALL Real* operator[](int i) { return m[i]; }
  RUBBLE_HD_SMALL const Real* operator[](int i) const { return m[i]; }

  RUBBLE_HD_SMALL Mat& operator+=(const Mat& o) {
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) m[i][j] += o.m[i][j];
    return *this;
  }
  RUBBLE_HD_SMALL Mat& operator-=(const Mat& o) {
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) m[i][j] -= o.m[i][j];
    return *this;
  }
  // exact element-wise equality (snapshot round trips)
  RUBBLE_HD_SMALL bool operator==(const Mat& o) const {
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j)
        if (m[i][j] != o.m[i][j]) return false;
    return true;
  }
  RUBBLE_HD_SMALL Mat& operator*=(Real s) {
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) m[i][j] *= s;
    return *this;
  }
};

template <int D>
RUBBLE_HD_SMALL Mat<D> operator+(Mat<D> a, const Mat<D>& b) { return a += b; }
template <int D>
RUBBLE_HD_SMALL Mat<D> operator-(Mat<D> a, const Mat<D>& b) { return a -= b; }
template <int D>
RUBBLE_HD_SMALL Mat<D> operator*(Mat<D> a, Real s) { return a *= s; }
template <int D>
RUBBLE_HD_SMALL Mat<D> operator*(Real s, Mat<D> a) { return a *= s; }

template <int D>
RUBBLE_HD_SMALL Mat<D> operator*(const Mat<D>& a, const Mat<D>& b) {
  Mat<D> c = Mat<D>::zero();
  for (int i = 0; i < D; ++i)
    for (int k = 0; k < D; ++k)
      for (int j = 0; j < D; ++j) c.m[i][j] += a.m[i][k] * b.m[k][j];
  return c;
}

template <int D>
RUBBLE_HD_SMALL Vec<D> operator*(const Mat<D>& a, const Vec<D>& v) {
  Vec<D> r = Vec<D>::zero();
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) r[i] += a.m[i][j] * v[j];
  return r;
}

template <int D>
RUBBLE_HD_SMALL Mat<D> transpose(const Mat<D>& a) {
  Mat<D> t;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) t.m[i][j] = a.m[j][i];
  return t;
}

template <int D>
RUBBLE_HD_SMALL Real trace(const Mat<D>& a) {
  Real t = 0;
  for (int i = 0; i < D; ++i) t += a.m[i][i];
  return t;
}

// a : b = a_ij b_ij
template <int D>
RUBBLE_HD_SMALL Real double_dot(const Mat<D>& a, const Mat<D>& b) {
  Real s = 0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) s += a.m[i][j] * b.m[i][j];
  return s;
}

// Every entry exactly zero (a solid pair skips the artificial stress of two
// particles without any).
template <int D>
RUBBLE_HD_SMALL bool is_zero(const Mat<D>& a) {
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j)
      if (a.m[i][j] != Real(0)) return false;
  return true;
}

template <int D>
RUBBLE_HD_SMALL Real determinant(const Mat<D>& a) {
  if constexpr (D == 1) return a.m[0][0];
  else if constexpr (D == 2) return a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0];
  else
    return a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
           a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0]) +
           a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}

// Inverse by the adjugate; the caller checks the determinant first.
template <int D>
RUBBLE_HD_SMALL Mat<D> inverse(const Mat<D>& a) {
  const Real inv_det = Real(1) / determinant(a);
  Mat<D> r;
  if constexpr (D == 1) {
    r.m[0][0] = inv_det;
  } else if constexpr (D == 2) {
    r.m[0][0] = a.m[1][1] * inv_det;
    r.m[0][1] = -a.m[0][1] * inv_det;
    r.m[1][0] = -a.m[1][0] * inv_det;
    r.m[1][1] = a.m[0][0] * inv_det;
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        // cofactor of a_ji
        const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
        r.m[i][j] = (a.m[i1][j1] * a.m[i2][j2] - a.m[i1][j2] * a.m[i2][j1]) * inv_det;
      }
  }
  return r;
}

}  // namespace rubble
