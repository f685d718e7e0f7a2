#pragma once
// The oscillating cantilever plate (Gray, Monaghan & Swift 2001; issue #4
// item 6): the plate and clamp read from its scene, the Euler-Bernoulli
// first mode and the thin-plate (plane strain) period. Shared by the
// time-domain rung (oscillating_plate_rung.cpp) and the operator-level
// check (plate_operator.cpp).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "rubble/scene/scene.hpp"

namespace rubble::plate {

constexpr double kKL = 1.875;  // first root of cos(kL) cosh(kL) = -1 (1.8751)

// Euler-Bernoulli cantilever mode shape (clamped at s = 0, free at s = kL).
inline double mode_shape(double s) {
  return (std::cos(s) - std::cosh(s)) * (std::sin(kKL) + std::sinh(kKL)) -
         (std::sin(s) - std::sinh(s)) * (std::cos(kKL) + std::cosh(kKL));
}

struct Plate {
  double L = 0, H = 0;    // free length (clamp mouth to tip), thickness
  double xc = 0, y0 = 0;  // clamp mouth (x), lower face (y)
  double rho0 = 0, K = 0, mu = 0, E = 0, nu = 0, cs = 0;
  double omega = 0, period = 0;  // thin-plate theory
};

// Body 0 is the plate (a box; it may reach into the clamp), bodies 1.. are
// the clamp (fixed boundary boxes, all at x < the clamp mouth). The clamp
// mouth is the largest x of the clamp; the free length L runs from there
// to the plate's end.
inline Plate plate_of(const rubble::Scene& scene) {
  if (scene.simulation.dimension != 2 || scene.bodies.size() < 2 || scene.materials.empty())
    throw std::runtime_error("the plate scene is 2-D: body 0 the plate, bodies 1.. the clamp");
  const rubble::BodyConfig& b = scene.bodies[0];
  if (b.shape != rubble::BodyShape::Box || b.boundary != rubble::BoundaryKind::None || b.material_id != 0)
    throw std::runtime_error("body 0 must be the plate: a free box of the first material");
  Plate p;
  p.xc = -1e300;
  for (std::size_t i = 1; i < scene.bodies.size(); ++i) {
    const rubble::BodyConfig& c = scene.bodies[i];
    if (c.shape != rubble::BodyShape::Box || c.boundary != rubble::BoundaryKind::Fixed)
      throw std::runtime_error("bodies 1.. must be the clamp: fixed boundary boxes");
    p.xc = std::max(p.xc, c.max[0]);
  }
  if (!(p.xc >= b.min[0] && p.xc < b.max[0]))
    throw std::runtime_error("the clamp mouth (largest x of the clamp) must lie within the plate's x range");
  const rubble::MaterialConfig& m = scene.materials[0];
  if (m.eos != rubble::EosKind::Murnaghan || m.murnaghan.n != 1.0 || m.shear_modulus <= 0)
    throw std::runtime_error("the plate material is a linear (Murnaghan n = 1) elastic solid");
  p.L = b.max[0] - p.xc;
  p.H = b.max[1] - b.min[1];
  p.y0 = b.min[1];
  p.rho0 = m.murnaghan.rho0;
  p.K = m.murnaghan.K0;
  p.mu = m.shear_modulus;
  p.E = 9 * p.K * p.mu / (3 * p.K + p.mu);
  p.nu = (3 * p.K - 2 * p.mu) / (2 * (3 * p.K + p.mu));
  p.cs = std::sqrt(p.K / p.rho0);
  const double k = kKL / p.L;
  p.omega = std::sqrt(p.E * p.H * p.H * std::pow(k, 4) / (12 * p.rho0 * (1 - p.nu * p.nu)));
  p.period = 2 * std::numbers::pi / p.omega;
  return p;
}

// The period extrapolated to infinite resolution: least squares of
// T(n) = T_inf (1 + a/n + b/n^2) over the resolutions n (H/dx), with two
// resolutions T_inf (1 + a/n) (issue #17 item 2). Shared by both programs.
struct PeriodLimit {
  double T_inf = NAN, a = NAN;  // a: the first-order coefficient, relative to T_inf
  int terms = 0;                // 2 or 3 (NaN fields and 0 with fewer than 2 resolutions)
};

inline PeriodLimit extrapolate_period(const std::vector<double>& n, const std::vector<double>& T) {
  PeriodLimit out;
  if (n.size() != T.size() || n.size() < 2) return out;
  const int terms = n.size() >= 3 ? 3 : 2;
  // normal equations M c = r of the basis 1, 1/n, 1/n^2; Gaussian elimination
  double M[3][4] = {};
  for (std::size_t i = 0; i < n.size(); ++i) {
    const double basis[3] = {1.0, 1 / n[i], 1 / (n[i] * n[i])};
    for (int r = 0; r < terms; ++r) {
      M[r][terms] += basis[r] * T[i];
      for (int c = 0; c < terms; ++c) M[r][c] += basis[r] * basis[c];
    }
  }
  for (int k = 0; k < terms; ++k) {
    int piv = k;
    for (int r = k + 1; r < terms; ++r)
      if (std::fabs(M[r][k]) > std::fabs(M[piv][k])) piv = r;
    for (int c = 0; c <= terms; ++c) std::swap(M[k][c], M[piv][c]);
    for (int r = k + 1; r < terms; ++r) {
      const double f = M[r][k] / M[k][k];
      for (int c = k; c <= terms; ++c) M[r][c] -= f * M[k][c];
    }
  }
  double coef[3] = {};
  for (int k = terms - 1; k >= 0; --k) {
    double s = M[k][terms];
    for (int c = k + 1; c < terms; ++c) s -= M[k][c] * coef[c];
    coef[k] = s / M[k][k];
  }
  out.T_inf = coef[0];
  out.a = coef[1] / coef[0];
  out.terms = terms;
  return out;
}

}  // namespace rubble::plate
