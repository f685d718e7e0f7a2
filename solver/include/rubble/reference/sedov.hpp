#pragma once
// Exact Sedov–Taylor point-blast solution: energy E released at t = 0 at a
// point of an ideal gas (gamma) of uniform density rho0 and zero pressure
// (Sedov 1959, "Similarity and Dimensional Methods in Mechanics", ch. IV;
// Taylor 1950, Proc. R. Soc. A 201:159; Kamm & Timmes 2007, LA-UR-07-2849).
// Geometry j = 1 (planar), 2 (cylindrical), 3 (spherical).
//
// The shock sits at R(t) = xi0 (E t^2 / rho0)^(1/(j+2)) and moves at
// Rdot = delta R / t, delta = 2/(j+2). Behind it, with lambda = r/R,
//     v = Rdot phi(lambda),  rho = rho0 psi(lambda),  p = rho0 Rdot^2 pi(lambda).
// Substituting into the Euler equations (continuity, momentum, and entropy
// p rho^-gamma constant along a particle path) gives, with w = phi - lambda,
//     w psi' + psi phi'          = -(j-1) psi phi / lambda
//     w phi' + pi'/psi           = (1 - delta)/delta phi
//     w (pi'/pi - gamma psi'/psi) = 2 (1 - delta)/delta
// (derived here; the same system as Sedov's eqs. IV.(4.x) in other
// variables). The strong-shock jump conditions at lambda = 1 are
//     phi = 2/(gamma+1), psi = (gamma+1)/(gamma-1), pi = 2/(gamma+1).
// We integrate inwards from lambda = 1 with classical RK4 in s = ln(lambda)
// (uniform steps) down to lambda_c = 1e-2, for phi, ln psi and ln pi: psi falls like lambda^(j/(gamma-1)) towards the
// centre, through twenty decades, and its logarithm keeps full relative
// precision there (psi itself would be lost to cancellation and go
// negative). In these variables, with theta = psi/pi (-> 0 at the centre),
//     phi'  = (a phi w theta - (2a - gamma (j-1) phi/lambda)) / (w^2 theta - gamma),  a = (1-delta)/delta
//     (ln psi)' = (-(j-1) phi/lambda - phi') / w
//     (ln pi)'  = 2a/w + gamma (ln psi)'
// (the second form of the first line has no overflow as theta -> 0). The
// table is read by cubic Hermite interpolation with the stored derivatives
// (error ~ ds^4). The centre is a singular point that the inward
// integration approaches along an unstable direction (rounding errors grow
// like a power of 1/lambda: at lambda = 1e-3 phi is off by 1 % for
// gamma = 1.4, j = 3), so below lambda_c the solution continues with its
// exact core asymptote, which the equations give for phi -> lambda/gamma:
//     phi ~ lambda,  psi ~ lambda^(j/(gamma-1)),  pi = const,
// matched to the integrated values at lambda_c (their mismatch from the
// asymptote there is < 2e-5 relative). The energy integral
//     E = rho0 Rdot^2 R^j sigma_j I,  I = int_0^1 (psi phi^2/2 + pi/(gamma-1)) lambda^(j-1) dlambda,
// sigma_j = 2, 2 pi, 4 pi, then fixes xi0 = (delta^2 sigma_j I)^(-1/(j+2)).
//
// Reference code for the Sedov–Taylor rung and its tests: host only, double
// precision whatever rubble::Real is.
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rubble {

struct SedovState {
  double rho, v, p;  // v is the radial velocity
};

class SedovSolution {
 public:
  // gamma > 1; j in {1, 2, 3}; `steps` (even) RK4 steps over ln(lambda) in [ln 1e-2, 0].
  SedovSolution(double gamma, int j, int steps = 20000) : gamma_(gamma), j_(j) {
    if (!(gamma > 1) || j < 1 || j > 3 || steps < 100 || steps % 2)
      throw std::invalid_argument("SedovSolution: need gamma > 1, j in {1,2,3}, an even steps >= 100");
    delta_ = 2.0 / (j + 2);
    const double s_min = std::log(kLambdaCore);
    ds_ = -s_min / steps;
    s_min_ = s_min;
    // table index k <-> s = s_min + k ds (k = steps is the shock)
    y_.assign(steps + 1, Y{});
    dy_.assign(steps + 1, Y{});
    Y y{{2 / (gamma + 1), std::log((gamma + 1) / (gamma - 1)), std::log(2 / (gamma + 1))}};
    y_[steps] = y;
    dy_[steps] = rhs(0.0, y);
    for (int k = steps; k > 0; --k) {
      const double s = s_min_ + k * ds_, h = -ds_;
      const Y k1 = rhs(s, y);
      const Y k2 = rhs(s + h / 2, add(y, k1, h / 2));
      const Y k3 = rhs(s + h / 2, add(y, k2, h / 2));
      const Y k4 = rhs(s + h, add(y, k3, h));
      for (int q = 0; q < 3; ++q) y.c[q] += h / 6 * (k1.c[q] + 2 * k2.c[q] + 2 * k3.c[q] + k4.c[q]);
      y_[k - 1] = y;
      dy_[k - 1] = rhs(s + h, y);
    }
    // energy integral: Simpson's rule in s (integrand times lambda^j ds)
    // over the table, plus the core below lambda_c in closed form from the
    // asymptote (psi phi^2 lambda^(j-1) ~ lambda^(n+j+1), n = j/(gamma-1))
    const double phi_c = y_[0].c[0], psi_c = std::exp(y_[0].c[1]), pi_c = std::exp(y_[0].c[2]);
    const double n_core = j / (gamma - 1);
    double I = std::pow(kLambdaCore, j) * (psi_c * phi_c * phi_c / 2 / (n_core + j + 2) + pi_c / (gamma - 1) / j);
    for (int k = 0; k <= steps; ++k) {
      const double lam = std::exp(s_min_ + k * ds_);
      const double phi = y_[k].c[0], psi = std::exp(y_[k].c[1]), pi = std::exp(y_[k].c[2]);
      const double f = (psi * phi * phi / 2 + pi / (gamma - 1)) * std::pow(lam, j);
      I += (k == 0 || k == steps ? 1.0 : k % 2 ? 4.0 : 2.0) * f * ds_ / 3;
    }
    energy_integral_ = I;
    const double pi = std::numbers::pi;
    const double sigma = j == 1 ? 2.0 : j == 2 ? 2 * pi : 4 * pi;
    xi0_ = std::pow(delta_ * delta_ * sigma * I, -1.0 / (j + 2));
  }

  double gamma() const { return gamma_; }
  int geometry() const { return j_; }
  // xi0 of R = xi0 (E t^2 / rho0)^(1/(j+2)).
  double xi0() const { return xi0_; }
  // The dimensionless energy integral I (E = rho0 Rdot^2 R^j sigma_j I).
  double energy_integral() const { return energy_integral_; }
  double shock_radius(double E, double rho0, double t) const {
    return xi0_ * std::pow(E * t * t / rho0, 1.0 / (j_ + 2));
  }
  double shock_speed(double E, double rho0, double t) const { return delta_ * shock_radius(E, rho0, t) / t; }

  // The dimensionless profiles at lambda in (0, 1], as {psi, phi, pi} in
  // the fields {rho, v, p}. Below lambda_c the core asymptote.
  SedovState profile(double lambda) const {
    if (!(lambda > 0) || lambda > 1) throw std::invalid_argument("SedovSolution::profile: lambda outside (0, 1]");
    const double s = std::log(lambda);
    if (s <= s_min_) {
      const double x = lambda / kLambdaCore;
      return {std::exp(y_[0].c[1]) * std::pow(x, j_ / (gamma_ - 1)), y_[0].c[0] * x, std::exp(y_[0].c[2])};
    }
    const double f = (s - s_min_) / ds_;
    const std::size_t k = std::min<std::size_t>(static_cast<std::size_t>(f), y_.size() - 2);
    const double t = f - double(k);
    // cubic Hermite basis on [k, k+1] in units of ds
    const double h00 = (1 + 2 * t) * (1 - t) * (1 - t), h10 = t * (1 - t) * (1 - t);
    const double h01 = t * t * (3 - 2 * t), h11 = t * t * (t - 1);
    double v[3];
    for (int q = 0; q < 3; ++q)
      v[q] = h00 * y_[k].c[q] + h10 * ds_ * dy_[k].c[q] + h01 * y_[k + 1].c[q] + h11 * ds_ * dy_[k + 1].c[q];
    return {std::exp(v[1]), v[0], std::exp(v[2])};
  }

  // rho, radial v, p at distance r from the blast centre at time t > 0;
  // outside the shock the undisturbed gas (rho0, 0, p0).
  SedovState sample(double r, double t, double E, double rho0, double p0 = 0) const {
    const double R = shock_radius(E, rho0, t);
    if (r > R) return {rho0, 0, p0};
    const double Rdot = delta_ * R / t;
    const SedovState d = profile(std::max(r / R, 1e-300));  // {psi, phi, pi}
    return {rho0 * d.rho, Rdot * d.v, rho0 * Rdot * Rdot * d.p};
  }

 private:
  static constexpr double kLambdaCore = 1e-2;  // lambda_c
  struct Y {
    double c[3];  // phi, ln psi, ln pi
  };
  static Y add(const Y& y, const Y& k, double h) {
    return {{y.c[0] + h * k.c[0], y.c[1] + h * k.c[1], y.c[2] + h * k.c[2]}};
  }
  // d(phi, ln psi, ln pi)/ds = lambda d/dlambda, from the equations above.
  Y rhs(double s, const Y& y) const {
    const double lam = std::exp(s);
    const double phi = y.c[0];
    const double theta = std::exp(y.c[1] - y.c[2]);  // psi / pi
    const double w = phi - lam, a = (1 - delta_) / delta_;
    const double dphi = (a * phi * w * theta - (2 * a - gamma_ * (j_ - 1) * phi / lam)) / (w * w * theta - gamma_);
    const double dlnpsi = (-(j_ - 1) * phi / lam - dphi) / w;
    const double dlnpi = 2 * a / w + gamma_ * dlnpsi;
    return {{lam * dphi, lam * dlnpsi, lam * dlnpi}};
  }

  double gamma_;
  int j_;
  double delta_ = 0, ds_ = 0, s_min_ = 0, xi0_ = 0, energy_integral_ = 0;
  std::vector<Y> y_, dy_;  // (phi, ln psi, ln pi) and their s-derivatives
};

}  // namespace rubble
