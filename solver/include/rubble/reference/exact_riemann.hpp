#pragma once
// Exact solution of the Riemann problem for the 1-D Euler equations with an
// ideal gas, p = (gamma - 1) rho u (Toro, "Riemann Solvers and Numerical
// Methods for Fluid Dynamics", 3rd ed., ch. 4), with one gamma or two: a
// gas of gamma_L left of the contact and one of gamma_R right of it (two
// materials meeting at an interface; each wave relation is its own side's,
// Toro's f_K with gamma_K, and p, v are continuous across the contact).
//
//   * p* is the root of f(p) = f_L(p) + f_R(p) + (v_R - v_L), found by a
//     Newton iteration (Toro §4.3.1) started from Toro's adaptive guess
//     (PVRS, two-rarefaction or two-shock approximation, §9.5.1) and kept
//     inside a bracket [p_lo, p_hi] with bisection as a fall-back, so it
//     cannot wander to negative pressure or diverge;
//   * v* = (v_L + v_R)/2 + (f_R(p*) - f_L(p*))/2 (eq. 4.9);
//   * the star densities follow from the shock adiabat (eq. 4.50/4.57) or
//     the isentrope (eq. 4.53/4.60);
//   * sample(xi) evaluates the self-similar solution at xi = (x - x0)/t
//     (§4.5, including the state inside rarefaction fans, eq. 4.56/4.63).
//
// Reference code: used by verification rungs (Sod shock tube) and unit
// tests, on the host only, in double precision whatever rubble::Real is.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rubble {

// A primitive gas state: density, velocity, pressure.
struct GasState {
  double rho, v, p;
};

// The star region between the left and right waves, and the wave speeds.
// For a shock head == tail == shock speed. For a rarefaction the head is the
// edge facing the undisturbed gas (v_L - a_L on the left, v_R + a_R on the
// right), the tail the edge facing the contact. The contact moves with v.
struct RiemannStar {
  double p, v, rho_left, rho_right;
  double left_head, left_tail, right_head, right_tail;
  bool left_is_shock, right_is_shock;
};

class ExactRiemann {
 public:
  ExactRiemann(GasState left, GasState right, double gamma) : ExactRiemann(left, right, gamma, gamma) {}
  ExactRiemann(GasState left, GasState right, double gamma_left, double gamma_right)
      : L_(left), R_(right), gL_(gamma_left), gR_(gamma_right) {
    check_state(left, "left");
    check_state(right, "right");
    for (double g : {gamma_left, gamma_right})
      if (!std::isfinite(g) || !(g > 1.0))
        throw std::invalid_argument("ExactRiemann: gamma must be > 1, got " + std::to_string(g));
    aL_ = std::sqrt(gL_ * L_.p / L_.rho);
    aR_ = std::sqrt(gR_ * R_.p / R_.rho);
    // Pressure positivity condition (Toro eq. 4.40, each side with its
    // gamma): otherwise the two rarefactions leave a vacuum between them.
    const double dv_crit = 2.0 * aL_ / (gL_ - 1.0) + 2.0 * aR_ / (gR_ - 1.0);
    if (!(dv_crit > R_.v - L_.v))
      throw std::invalid_argument("ExactRiemann: the initial data generate a vacuum (v_R - v_L = " +
                                  std::to_string(R_.v - L_.v) + " >= " + std::to_string(dv_crit) + ")");
    solve();
  }

  const RiemannStar& star() const { return s_; }
  double gamma() const { return gL_; }  // one-gamma problems (gamma_left == gamma_right)
  double gamma_left() const { return gL_; }
  double gamma_right() const { return gR_; }
  // The gamma of the gas at xi = (x - x0)/t: left or right of the contact.
  double gamma_at(double xi) const { return xi <= s_.v ? gL_ : gR_; }
  const GasState& left() const { return L_; }
  const GasState& right() const { return R_; }

  // State at xi = (x - x0)/t. Exactly at the contact (xi == v*) the left
  // star state is returned; the solution is discontinuous there anyway.
  GasState sample(double xi) const {
    if (xi <= s_.v) {  // left of the contact
      if (s_.left_is_shock) return xi < s_.left_head ? L_ : GasState{s_.rho_left, s_.v, s_.p};
      if (xi <= s_.left_head) return L_;
      if (xi >= s_.left_tail) return GasState{s_.rho_left, s_.v, s_.p};
      // inside the left fan (Toro eq. 4.56)
      const double c = 2.0 / (gL_ + 1.0) + (gL_ - 1.0) / ((gL_ + 1.0) * aL_) * (L_.v - xi);
      return GasState{L_.rho * std::pow(c, 2.0 / (gL_ - 1.0)),
                      2.0 / (gL_ + 1.0) * (aL_ + 0.5 * (gL_ - 1.0) * L_.v + xi),
                      L_.p * std::pow(c, 2.0 * gL_ / (gL_ - 1.0))};
    }
    // right of the contact
    if (s_.right_is_shock) return xi > s_.right_head ? R_ : GasState{s_.rho_right, s_.v, s_.p};
    if (xi >= s_.right_head) return R_;
    if (xi <= s_.right_tail) return GasState{s_.rho_right, s_.v, s_.p};
    // inside the right fan (Toro eq. 4.63)
    const double c = 2.0 / (gR_ + 1.0) - (gR_ - 1.0) / ((gR_ + 1.0) * aR_) * (R_.v - xi);
    return GasState{R_.rho * std::pow(c, 2.0 / (gR_ - 1.0)),
                    2.0 / (gR_ + 1.0) * (-aR_ + 0.5 * (gR_ - 1.0) * R_.v + xi),
                    R_.p * std::pow(c, 2.0 * gR_ / (gR_ - 1.0))};
  }

  // Specific internal energy u = p / ((gamma - 1) rho) and sound speed
  // a = sqrt(gamma p / rho) of a state of a one-gamma problem...
  double internal_energy(const GasState& s) const { return s.p / ((gL_ - 1.0) * s.rho); }
  double sound_speed(const GasState& s) const { return std::sqrt(gL_ * s.p / s.rho); }
  // ... and of the solution at xi, with the gamma of its side.
  double internal_energy_at(double xi) const {
    const GasState s = sample(xi);
    return s.p / ((gamma_at(xi) - 1.0) * s.rho);
  }

  // Newton iterations the pressure solve took (diagnostics, tests).
  int iterations() const { return iterations_; }

 private:
  static void check_state(const GasState& s, const char* side) {
    if (!std::isfinite(s.rho) || !std::isfinite(s.v) || !std::isfinite(s.p))
      throw std::invalid_argument(std::string("ExactRiemann: ") + side + " state is not finite");
    if (!(s.rho > 0.0) || !(s.p > 0.0))
      throw std::invalid_argument(std::string("ExactRiemann: ") + side +
                                  " state needs rho > 0 and p > 0 (rho = " + std::to_string(s.rho) +
                                  ", p = " + std::to_string(s.p) + ")");
  }

  // f_K(p) and its derivative (Toro eqs. 4.6, 4.7, 4.37).
  static void fK(double p, const GasState& K, double aK, double g, double& f, double& df) {
    if (p > K.p) {  // shock
      const double A = 2.0 / ((g + 1.0) * K.rho);
      const double B = (g - 1.0) / (g + 1.0) * K.p;
      const double q = std::sqrt(A / (p + B));
      f = (p - K.p) * q;
      df = q * (1.0 - 0.5 * (p - K.p) / (B + p));
    } else {  // rarefaction
      const double r = std::pow(p / K.p, (g - 1.0) / (2.0 * g));
      f = 2.0 * aK / (g - 1.0) * (r - 1.0);
      df = r / (K.rho * aK) * (K.p / p);  // = (p/pK)^(-(g+1)/(2g)) / (rho_K a_K)
    }
  }

  double f(double p, double& df) const {
    double fl, dfl, fr, dfr;
    fK(p, L_, aL_, gL_, fl, dfl);
    fK(p, R_, aR_, gR_, fr, dfr);
    df = dfl + dfr;
    return fl + fr + (R_.v - L_.v);
  }

  // Toro's adaptive initial guess (§9.5.1, "AIRS" with Q_user = 2).
  double initial_guess() const {
    const double pmin = std::fmin(L_.p, R_.p), pmax = std::fmax(L_.p, R_.p);
    const double rho_bar = 0.5 * (L_.rho + R_.rho), a_bar = 0.5 * (aL_ + aR_);
    const double ppv = std::fmax(0.0, 0.5 * (L_.p + R_.p) - 0.5 * (R_.v - L_.v) * rho_bar * a_bar);
    if (pmax / pmin <= 2.0 && ppv >= pmin && ppv <= pmax) return ppv;
    if (ppv < pmin) {
      if (gL_ != gR_) return pmin;  // the closed form below is for one gamma; the bracket does the rest
      // two-rarefaction approximation (eq. 9.32)
      const double g = gL_;
      const double z = (g - 1.0) / (2.0 * g);
      const double num = aL_ + aR_ - 0.5 * (g - 1.0) * (R_.v - L_.v);
      const double den = aL_ / std::pow(L_.p, z) + aR_ / std::pow(R_.p, z);
      return std::pow(num / den, 1.0 / z);
    }
    // two-shock approximation (eq. 9.42) evaluated at the PVRS pressure
    const double gL = std::sqrt((2.0 / ((gL_ + 1.0) * L_.rho)) / ((gL_ - 1.0) / (gL_ + 1.0) * L_.p + ppv));
    const double gR = std::sqrt((2.0 / ((gR_ + 1.0) * R_.rho)) / ((gR_ - 1.0) / (gR_ + 1.0) * R_.p + ppv));
    return (gL * L_.p + gR * R_.p - (R_.v - L_.v)) / (gL + gR);
  }

  void solve() {
    // f is monotone increasing in p; f(0+) < 0 by the positivity condition.
    // Bracket the root, then Newton with bisection whenever a step leaves it.
    double df = 0.0;
    double lo = 0.0, hi = std::fmax(L_.p, R_.p);
    while (f(hi, df) < 0.0) {
      lo = hi;
      hi *= 2.0;
      if (!std::isfinite(hi)) throw std::runtime_error("ExactRiemann: cannot bracket p*");
    }
    double p = initial_guess();
    if (!(p > lo && p <= hi)) p = 0.5 * (lo + hi);
    constexpr double tol = 1e-15;
    constexpr int max_iter = 200;
    int it = 0;
    for (; it < max_iter; ++it) {
      const double fp = f(p, df);
      if (fp == 0.0) break;
      if (fp < 0.0)
        lo = p;
      else
        hi = p;
      double p_new = p - fp / df;
      if (!(p_new > lo && p_new < hi)) p_new = 0.5 * (lo + hi);  // safeguard
      const double change = 2.0 * std::fabs(p_new - p) / (p_new + p);
      p = p_new;
      if (change < tol || hi - lo <= 4.0 * std::numeric_limits<double>::epsilon() * p) break;
    }
    if (it == max_iter) throw std::runtime_error("ExactRiemann: Newton iteration for p* did not converge");
    iterations_ = it + 1;

    double fl, fr, d;
    fK(p, L_, aL_, gL_, fl, d);
    fK(p, R_, aR_, gR_, fr, d);
    s_.p = p;
    s_.v = 0.5 * (L_.v + R_.v) + 0.5 * (fr - fl);

    {  // left wave, its gas's gamma
      const double gm = (gL_ - 1.0) / (gL_ + 1.0);
      const double gs = (gL_ + 1.0) / (2.0 * gL_);  // shock-speed coefficients (eq. 4.52)
      const double gz = (gL_ - 1.0) / (2.0 * gL_);
      s_.left_is_shock = p > L_.p;
      if (s_.left_is_shock) {
        const double r = p / L_.p;
        s_.rho_left = L_.rho * (r + gm) / (gm * r + 1.0);
        s_.left_head = s_.left_tail = L_.v - aL_ * std::sqrt(gs * r + gz);
      } else {
        s_.rho_left = L_.rho * std::pow(p / L_.p, 1.0 / gL_);
        s_.left_head = L_.v - aL_;
        s_.left_tail = s_.v - aL_ * std::pow(p / L_.p, gz);
      }
    }
    {  // right wave, its gas's gamma
      const double gm = (gR_ - 1.0) / (gR_ + 1.0);
      const double gs = (gR_ + 1.0) / (2.0 * gR_);  // shock-speed coefficients (eq. 4.52)
      const double gz = (gR_ - 1.0) / (2.0 * gR_);
      s_.right_is_shock = p > R_.p;
      if (s_.right_is_shock) {
        const double r = p / R_.p;
        s_.rho_right = R_.rho * (r + gm) / (gm * r + 1.0);
        s_.right_head = s_.right_tail = R_.v + aR_ * std::sqrt(gs * r + gz);
      } else {
        s_.rho_right = R_.rho * std::pow(p / R_.p, 1.0 / gR_);
        s_.right_head = R_.v + aR_;
        s_.right_tail = s_.v + aR_ * std::pow(p / R_.p, gz);
      }
    }
  }

  GasState L_, R_;
  double gL_, gR_;
  double aL_ = 0.0, aR_ = 0.0;
  RiemannStar s_{};
  int iterations_ = 0;
};

}  // namespace rubble
