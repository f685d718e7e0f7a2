#pragma once
// What the Sedov-Taylor rung measures on a set of particles, kept apart
// from the running so that the side-by-side benchmark
// (benchmarks/peers/sedov_vs_phantom.py) measures another code's snapshot
// with exactly the same definitions (`sedov_rung --measure FILE`).
//
// All distances from the blast centre at the origin (the periodic cube is
// [-0.5, 0.5]^3, and every quantity below is taken inside its inscribed
// sphere r < 0.5, where the blast has not met its periodic images).
//
//   * Shock radius: the particles' densities are averaged (mass-weighted)
//     in spherical shells of width `bin` out to r = 0.5. The exact density
//     is largest right at the shock (4 rho0 for gamma = 5/3), so the shock
//     radius is the radius of the profile's maximum, refined by the parabola
//     through the largest shell and its two neighbours. Smoothing puts the
//     measured peak a fraction of a smoothing length inside the true shock,
//     an error that falls with h.
//     Also reported, not judged: the half-height radius, where the profile,
//     going outwards from the peak, first falls to (rho_peak + rho0)/2 (the
//     middle of the smeared jump; it lies a fraction of h outside the shock
//     because the smeared exact profile is a sawtooth, not a step).
//   * L1 errors: the mean over the particles with r < 0.5 of
//     |rho - rho_exact(r)|, |v_r - v_exact(r)| and |p - p_exact(r)|, the
//     exact solution at each particle's radius (rubble/reference/sedov.hpp).
//   * Energy: sum of m (u + |v|^2/2) over all particles.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "rubble/reference/sedov.hpp"

namespace rubble::verification {

struct SedovParticles {
  std::vector<double> x, v;  // N x 3, row-major
  std::vector<double> m, rho, u;
  double time = 0;
  std::size_t size() const { return m.size(); }
};

struct SedovMeasures {
  double shock_radius = 0, half_height_radius = 0, peak_density = 0, exact_radius = 0;
  double shock_radius_error = 0;        // |R - R_exact| / R_exact (R: the peak)
  double half_height_radius_error = 0;  // the same for the half-height radius
  double l1_rho = 0, l1_v = 0, l1_p = 0;
  double energy = 0;
  std::size_t counted = 0;  // particles with r < 0.5
  // the binned profile (shell centres, mass-weighted mean density)
  std::vector<double> bin_r, bin_rho;
};

inline SedovMeasures measure_sedov(const SedovParticles& s, const SedovSolution& exact, double E, double rho0,
                                   double bin) {
  const double gamma = exact.gamma(), r_max = 0.5;
  SedovMeasures out;
  out.exact_radius = exact.shock_radius(E, rho0, s.time);
  const std::size_t bins = static_cast<std::size_t>(std::ceil(r_max / bin));
  std::vector<double> mass(bins, 0.0), mass_rho(bins, 0.0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double* x = &s.x[3 * i];
    const double* v = &s.v[3 * i];
    out.energy += s.m[i] * (s.u[i] + 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    const double r = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    if (r >= r_max) continue;
    const double vr = r > 0 ? (x[0] * v[0] + x[1] * v[1] + x[2] * v[2]) / r : 0.0;
    const double p = (gamma - 1) * s.rho[i] * s.u[i];
    const SedovState e = exact.sample(r, s.time, E, rho0);
    out.l1_rho += std::fabs(s.rho[i] - e.rho);
    out.l1_v += std::fabs(vr - e.v);
    out.l1_p += std::fabs(p - e.p);
    ++out.counted;
    const std::size_t b = std::min(bins - 1, static_cast<std::size_t>(r / bin));
    mass[b] += s.m[i];
    mass_rho[b] += s.m[i] * s.rho[i];
  }
  if (out.counted > 0) {
    out.l1_rho /= double(out.counted);
    out.l1_v /= double(out.counted);
    out.l1_p /= double(out.counted);
  }
  for (std::size_t b = 0; b < bins; ++b)
    if (mass[b] > 0) {
      out.bin_r.push_back((double(b) + 0.5) * bin);
      out.bin_rho.push_back(mass_rho[b] / mass[b]);
    }
  if (out.bin_rho.empty()) return out;
  const std::size_t k = std::size_t(std::max_element(out.bin_rho.begin(), out.bin_rho.end()) - out.bin_rho.begin());
  out.peak_density = out.bin_rho[k];
  out.shock_radius = out.bin_r[k];
  if (k > 0 && k + 1 < out.bin_rho.size()) {
    // vertex of the parabola through (r_{k-1}, r_k, r_{k+1}) (equal spacing when no shell is empty)
    const double f0 = out.bin_rho[k - 1], f1 = out.bin_rho[k], f2 = out.bin_rho[k + 1];
    const double h = 0.5 * (out.bin_r[k + 1] - out.bin_r[k - 1]), curvature = f0 - 2 * f1 + f2;
    if (curvature < 0) out.shock_radius = out.bin_r[k] + 0.5 * h * (f0 - f2) / curvature;
  }
  const double half = 0.5 * (out.peak_density + rho0);
  out.half_height_radius = out.bin_r.back();
  for (std::size_t b = k + 1; b < out.bin_rho.size(); ++b)
    if (out.bin_rho[b] <= half) {
      const double r0 = out.bin_r[b - 1], r1 = out.bin_r[b], f0 = out.bin_rho[b - 1], f1 = out.bin_rho[b];
      out.half_height_radius = r0 + (r1 - r0) * (f0 - half) / (f0 - f1);
      break;
    }
  out.shock_radius_error = std::fabs(out.shock_radius - out.exact_radius) / out.exact_radius;
  out.half_height_radius_error = std::fabs(out.half_height_radius - out.exact_radius) / out.exact_radius;
  return out;
}

}  // namespace rubble::verification
