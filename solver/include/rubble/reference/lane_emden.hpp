#pragma once
// Polytropes: the Lane-Emden equation and the hydrostatic structure it gives
// (Chandrasekhar 1939, An Introduction to the Study of Stellar Structure,
// ch. IV). Used by the "polytrope" body generator and the polytrope rung.
//
//   (1/xi^2) d/dxi (xi^2 dtheta/dxi) = -theta^n,  theta(0) = 1, theta'(0) = 0
//
// A polytrope p = K rho^(1 + 1/n) of mass M and radius R has
//   rho = rho_c theta^n(r/alpha),  alpha = R / xi_1,
//   rho_c = M / (4 pi alpha^3 omega),  omega = -xi_1^2 theta'(xi_1),
//   K = 4 pi G alpha^2 rho_c^(1 - 1/n) / (n + 1),
//   m(<r) / M = xi^2 (-theta'(xi)) / omega,
//   gravitational energy W = -3/(5 - n) G M^2 / R.
// n = 1 has theta = sin(xi)/xi, xi_1 = pi (the unit test checks the numerical
// solution against it). The equation is integrated once with classical RK4
// from a series start (theta = 1 - xi^2/6 + n xi^4/120 - n(8n-5) xi^6/15120
// at xi = 0.01) and tabulated;
// values between nodes use cubic Hermite interpolation (error ~ step^4).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rubble {

class LaneEmden {
 public:
  explicit LaneEmden(double n, double step = 2e-4) : n_(n) {
    if (!(n > 0 && n < 5)) throw std::invalid_argument("LaneEmden: the polytropic index must be in (0, 5)");
    // series start (error ~ xi^8), then steps of min(step, xi/50): the
    // 2 theta'/xi term varies on the scale xi near the centre
    double xi = 1e-2;
    const double c6 = n * (8 * n - 5) / 15120;
    double th = 1 - xi * xi / 6 + n * std::pow(xi, 4) / 120 - c6 * std::pow(xi, 6);
    double dth = -xi / 3 + n * std::pow(xi, 3) / 30 - 6 * c6 * std::pow(xi, 5);
    // node 0 at xi = 0
    xi_.push_back(0);
    th_.push_back(1);
    dth_.push_back(0);
    auto f = [this](double x, double t, double d) { return -power(t) - 2 * d / x; };
    for (;;) {
      xi_.push_back(xi);
      th_.push_back(th);
      dth_.push_back(dth);
      if (th <= 0) break;
      const double h = std::min(step, xi / 50);
      const double k1t = dth, k1d = f(xi, th, dth);
      const double k2t = dth + 0.5 * h * k1d, k2d = f(xi + 0.5 * h, th + 0.5 * h * k1t, dth + 0.5 * h * k1d);
      const double k3t = dth + 0.5 * h * k2d, k3d = f(xi + 0.5 * h, th + 0.5 * h * k2t, dth + 0.5 * h * k2d);
      const double k4t = dth + h * k3d, k4d = f(xi + h, th + h * k3t, dth + h * k3d);
      th += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      dth += h / 6 * (k1d + 2 * k2d + 2 * k3d + k4d);
      xi += h;
      if (xi > 100) throw std::runtime_error("LaneEmden: no surface found");
    }
    // The surface: Newton on the Hermite interpolant of the last interval.
    const std::size_t k = xi_.size() - 2;
    double x = xi_[k] - th_[k] / dth_[k];
    for (int it = 0; it < 50; ++it) {
      const double t = hermite(k, x, false), d = hermite(k, x, true);
      const double dx = -t / d;
      x += dx;
      if (std::fabs(dx) < 1e-15 * x) break;
    }
    xi1_ = x;
    omega_ = -xi1_ * xi1_ * hermite(k, xi1_, true);
  }

  double n() const { return n_; }
  double xi1() const { return xi1_; }
  double omega() const { return omega_; }

  // theta(xi) (0 beyond the surface) and its derivative.
  double theta(double xi) const { return xi >= xi1_ ? 0.0 : std::max(0.0, hermite(interval(xi), xi, false)); }
  double dtheta(double xi) const { return hermite(interval(std::min(xi, xi1_)), std::min(xi, xi1_), true); }

  // m(<xi) / M, from 0 at the centre to 1 at the surface.
  double mass_fraction(double xi) const {
    if (xi >= xi1_) return 1.0;
    return std::clamp(-xi * xi * dtheta(xi) / omega_, 0.0, 1.0);
  }

  // The xi enclosing mass fraction f in [0, 1] (bisection; the fraction is
  // monotonic).
  double xi_of_mass_fraction(double f) const {
    if (f <= 0) return 0;
    if (f >= 1) return xi1_;
    double lo = 0, hi = xi1_;
    for (int it = 0; it < 200 && hi - lo > 1e-15 * xi1_; ++it) {
      const double mid = 0.5 * (lo + hi);
      (mass_fraction(mid) < f ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }

 private:
  std::size_t interval(double xi) const {
    const std::size_t k = std::size_t(std::upper_bound(xi_.begin(), xi_.end(), xi) - xi_.begin());
    return std::min(k == 0 ? 0 : k - 1, xi_.size() - 2);
  }
  // Cubic Hermite on interval k (value or derivative), using theta'' from
  // the equation at the nodes.
  double second(std::size_t k) const {
    return xi_[k] > 0 ? -power(th_[k]) - 2 * dth_[k] / xi_[k] : -1.0 / 3.0;
  }
  // theta^n, continued as -|theta|^n past the surface so that the step and
  // the interpolant across it stay smooth (exact for n = 1).
  double power(double t) const { return t >= 0 ? std::pow(t, n_) : -std::pow(-t, n_); }
  double hermite(std::size_t k, double x, bool derivative) const {
    const double x0 = xi_[k], x1 = xi_[k + 1], dx = x1 - x0, t = (x - x0) / dx;
    const double y0 = th_[k], y1 = th_[k + 1], m0 = dth_[k] * dx, m1 = dth_[k + 1] * dx;
    if (!derivative) {
      const double t2 = t * t, t3 = t2 * t;
      return (2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * m1;
    }
    // the derivative from the Hermite interpolant of theta' itself (nodes
    // theta', slopes theta''), which is as accurate as the value
    const double d0 = dth_[k], d1 = dth_[k + 1], s0 = second(k) * dx, s1 = second(k + 1) * dx;
    const double t2 = t * t, t3 = t2 * t;
    return (2 * t3 - 3 * t2 + 1) * d0 + (t3 - 2 * t2 + t) * s0 + (-2 * t3 + 3 * t2) * d1 + (t3 - t2) * s1;
  }

  double n_, xi1_ = 0, omega_ = 0;
  std::vector<double> xi_, th_, dth_;
};

// The structure of a polytrope of index n, mass M and radius R under G.
struct Polytrope {
  Polytrope(double n, double mass, double radius, double G) : le(n), M(mass), R(radius) {
    constexpr double pi = std::numbers::pi;
    alpha = R / le.xi1();
    rho_c = M / (4 * pi * alpha * alpha * alpha * le.omega());
    K = 4 * pi * G * alpha * alpha * std::pow(rho_c, 1 - 1 / n) / (n + 1);
    W = -3.0 / (5.0 - n) * G * M * M / R;
  }
  double density(double r) const { return rho_c * std::pow(le.theta(r / alpha), le.n()); }
  double pressure(double r) const { return K * std::pow(density(r), 1 + 1 / le.n()); }
  double mass_fraction(double r) const { return le.mass_fraction(r / alpha); }
  double radius_of_mass_fraction(double f) const { return alpha * le.xi_of_mass_fraction(f); }

  LaneEmden le;
  double M, R;
  double alpha = 0, rho_c = 0, K = 0;
  double W = 0;  // gravitational energy
};

}  // namespace rubble
