#pragma once
// The thermodynamic definition of the squared sound speed, evaluated by
// central finite differences of the pressure (PHYSICS.md §3):
//   c² = ∂p/∂ρ|_u + (p/ρ²) ∂p/∂u|_ρ
// The reference every EOS's closed-form c² is checked against, in the unit
// tests (solver/tests/test_eos.cpp) and the Tillotson rung
// (verification/tillotson_continuity/). Host only; double precision.
#include <cmath>

namespace rubble {

// Fourth-order central difference f'(x) with step h (stencil x ± h, x ± 2h):
// truncation error h⁴ f⁽⁵⁾/30, round-off about 1.5 ε |f| / h.
template <class F>
double central_difference4(const F& f, double x, double h) {
  return (-f(x + 2 * h) + 8 * f(x + h) - 8 * f(x - h) + f(x - 2 * h)) / (12 * h);
}

// Fourth-order one-sided difference: side > 0 uses x, x + h, ..., x + 4h;
// side < 0 the mirror image. Truncation error h⁴ f⁽⁵⁾/5, round-off about
// 10 ε |f| / h: for states next to a kink, where a central stencil would
// have to shrink.
template <class F>
double one_sided_difference4(const F& f, double x, double h, int side) {
  const double s = side > 0 ? h : -h;
  return (-25 * f(x) + 48 * f(x + s) - 36 * f(x + 2 * s) + 16 * f(x + 3 * s) - 3 * f(x + 4 * s)) / (12 * s);
}

struct SoundSpeedFd {
  double p;       // p(ρ, u)
  double dpdrho;  // ∂p/∂ρ at constant u
  double dpdu;    // ∂p/∂u at constant ρ
  double c2;      // ∂p/∂ρ + (p/ρ²) ∂p/∂u
};

// `pressure(rho, u)` returns p. The stencils must stay on one side of every
// regime boundary (p has kinks there): central (side 0) within ±2h, or
// one-sided (side ±1) within 4h in that direction.
template <class P>
SoundSpeedFd sound_speed2_fd(const P& pressure, double rho, double u, double h_rho, double h_u, int side_rho = 0,
                             int side_u = 0) {
  SoundSpeedFd r{};
  auto along_rho = [&](double x) { return pressure(x, u); };
  auto along_u = [&](double x) { return pressure(rho, x); };
  r.p = pressure(rho, u);
  r.dpdrho = side_rho == 0 ? central_difference4(along_rho, rho, h_rho) : one_sided_difference4(along_rho, rho, h_rho, side_rho);
  r.dpdu = side_u == 0 ? central_difference4(along_u, u, h_u) : one_sided_difference4(along_u, u, h_u, side_u);
  r.c2 = r.dpdrho + r.p / (rho * rho) * r.dpdu;
  return r;
}

}  // namespace rubble
