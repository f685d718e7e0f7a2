// Hydrostatic structure of a layered sphere (rubble/scene/hydrostatic.hpp).
#include "rubble/scene/hydrostatic.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rubble {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

double layer_reference_density(const EosParams& e) {
  switch (e.kind) {
    case EosKind::Murnaghan: return e.murnaghan.rho0;
    case EosKind::Tillotson: return e.tillotson.rho0;
    case EosKind::IdealGas: break;
  }
  throw std::invalid_argument(
      "hydrostatic_profile: an ideal-gas layer has no density at zero pressure (use Murnaghan or Tillotson)");
}

namespace {

// The density at which the EOS gives pressure p with u = 0 (bisection).
double density_at_pressure(const EosParams& e, double p) {
  const double rho0 = layer_reference_density(e);
  double lo = 0.5 * rho0, hi = rho0;
  while (double(eos_evaluate(e, Real(lo), 0).p) > p) lo *= 0.5;
  while (double(eos_evaluate(e, Real(hi), 0).p) < p) {
    lo = hi;
    hi *= 2;
    if (hi > 1e6 * rho0) throw std::runtime_error("hydrostatic_profile: no density reaches p = " + std::to_string(p));
  }
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    (double(eos_evaluate(e, Real(mid), 0).p) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

struct State {
  double m, p, rho, u;
};

// d/dr of (m, p, rho, u) at radius r in a layer of EOS e.
State rates(const EosParams& e, double G, double r, const State& s) {
  const EosState q = eos_evaluate(e, Real(s.rho), Real(s.u));
  const double c2 = std::max(double(q.c2), 1e-300);
  State d;
  d.m = 4 * kPi * r * r * s.rho;
  d.p = -G * s.m * s.rho / (r * r);
  d.rho = d.p / c2;
  d.u = s.p / (s.rho * s.rho) * d.rho;
  return d;
}

State step(const EosParams& e, double G, double r, double h, const State& s) {  // RK4 from r to r + h
  auto add = [](const State& a, const State& b, double w) {
    return State{a.m + w * b.m, a.p + w * b.p, a.rho + w * b.rho, a.u + w * b.u};
  };
  const State k1 = rates(e, G, r, s);
  const State k2 = rates(e, G, r + 0.5 * h, add(s, k1, 0.5 * h));
  const State k3 = rates(e, G, r + 0.5 * h, add(s, k2, 0.5 * h));
  const State k4 = rates(e, G, r + h, add(s, k3, h));
  return State{s.m + h / 6 * (k1.m + 2 * k2.m + 2 * k3.m + k4.m), s.p + h / 6 * (k1.p + 2 * k2.p + 2 * k3.p + k4.p),
               s.rho + h / 6 * (k1.rho + 2 * k2.rho + 2 * k3.rho + k4.rho),
               s.u + h / 6 * (k1.u + 2 * k2.u + 2 * k3.u + k4.u)};
}

// Integrates inwards from the surface with total mass M; fills `out` when
// given. Returns m at the innermost sample minus the mass of the small
// sphere inside it (the shooting residual).
double integrate(const std::vector<HydrostaticLayer>& layers, double G, int steps, double M,
                 HydrostaticProfile* out) {
  const int nl = int(layers.size());
  State s{M, 0.0, density_at_pressure(layers[nl - 1].eos, 0.0), 0.0};
  const double r_stop = 1e-4 * layers[0].outer_radius;
  for (int k = nl - 1; k >= 0; --k) {
    const EosParams& e = layers[k].eos;
    if (k < nl - 1) {  // a new layer: its own density at the pressure above, u = 0
      s.rho = density_at_pressure(e, s.p);
      s.u = 0;
    }
    const double r_out = layers[k].outer_radius, r_in = k > 0 ? layers[k - 1].outer_radius : r_stop;
    const double h = -(r_out - r_in) / steps;
    double r = r_out;
    const double m_top = s.m;
    for (int i = 0; i <= steps; ++i) {
      if (out) {
        out->r.push_back(r);
        out->m.push_back(s.m);
        out->p.push_back(s.p);
        out->rho.push_back(s.rho);
        out->u.push_back(s.u);
        out->layer.push_back(k);
      }
      if (i == steps) break;
      const State before = s;
      s = step(e, G, r, h, s);
      const double r_before = r;
      r = r_out + (i + 1) * h;
      // too small a mass: m runs out at r0 above the centre. The residual
      // is then minus the ball that would still need filling, -4/3 pi rho
      // r0^3, which joins the residual of the masses that reach r_stop
      // continuously at r0 = r_stop (a residual that jumps, as a bare
      // failure of -M did, stalls the root finder on the jump: 1.7e-6 M
      // short in an iron-basalt-ice embryo)
      if (!out && s.m <= 0 && before.m > 0) {
        const double r0 = r_before + (r - r_before) * before.m / (before.m - s.m);
        return -4.0 / 3.0 * kPi * before.rho * r0 * r0 * r0;
      }
      // a mass far off: too large blows p up at the centre (m > 0), too
      // small drives m and then p negative until the density fails
      if (!(std::isfinite(s.p) && std::isfinite(s.rho) && s.rho > 0)) return s.m > 0 ? M : -M;
    }
    if (out) {
      out->layer_mass.insert(out->layer_mass.begin(), m_top - s.m);
      out->layer_radius.insert(out->layer_radius.begin(), r_out);
    }
  }
  if (out) out->centre_pressure = s.p;
  return s.m - 4.0 / 3.0 * kPi * r_stop * r_stop * r_stop * s.rho;
}

}  // namespace

HydrostaticProfile hydrostatic_profile(const std::vector<HydrostaticLayer>& layers, double G, int steps_per_layer) {
  if (layers.empty()) throw std::invalid_argument("hydrostatic_profile: no layers");
  if (!(G > 0)) throw std::invalid_argument("hydrostatic_profile: G must be > 0");
  if (steps_per_layer < 10) throw std::invalid_argument("hydrostatic_profile: steps_per_layer must be >= 10");
  double prev = 0, M0 = 0;
  for (const HydrostaticLayer& l : layers) {
    if (!(l.outer_radius > prev))
      throw std::invalid_argument("hydrostatic_profile: layer radii must increase from the centre out");
    M0 += 4.0 / 3.0 * kPi * (l.outer_radius * l.outer_radius * l.outer_radius - prev * prev * prev) *
          layer_reference_density(l.eos);
    prev = l.outer_radius;
  }
  // bracket the mass: at the zero-pressure mass M0 the layers are at least
  // as dense inside, so m(0) < 0 at M0/2; raise the upper end until m(0) > 0
  double lo = 0.5 * M0, hi = M0;
  double f_lo = integrate(layers, G, steps_per_layer, lo, nullptr), f_hi = integrate(layers, G, steps_per_layer, hi, nullptr);
  for (int i = 0; i < 60 && f_hi <= 0; ++i) {
    lo = hi;
    f_lo = f_hi;
    hi *= 1.5;
    f_hi = integrate(layers, G, steps_per_layer, hi, nullptr);
  }
  if (!(f_lo < 0 && f_hi > 0)) throw std::runtime_error("hydrostatic_profile: cannot bracket the total mass");
  // secant steps kept inside the bracket (bisection when they leave it)
  double M = 0.5 * (lo + hi);
  for (int it = 0; it < 200; ++it) {
    double next = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double f = integrate(layers, G, steps_per_layer, next, nullptr);
    M = next;
    if (f == 0 || (hi - lo) < 1e-15 * M) break;
    if (f < 0) {
      lo = next;
      f_lo = f;
    } else {
      hi = next;
      f_hi = f;
    }
    if (std::fabs(f) < 1e-13 * M) break;
  }
  HydrostaticProfile out;
  const double residual = integrate(layers, G, steps_per_layer, M, &out);
  out.mass = M;
  out.centre_mass_residual = residual / M;
  return out;
}

HydrostaticState hydrostatic_at(const HydrostaticProfile& pr, double r) {
  const std::size_t n = pr.r.size();
  if (n == 0) throw std::invalid_argument("hydrostatic_at: empty profile");
  if (r >= pr.r.front()) return {pr.p.front(), pr.rho.front(), pr.u.front(), pr.layer.front()};
  for (std::size_t i = 1; i < n; ++i) {
    if (pr.r[i] > r || pr.r[i] == pr.r[i - 1]) continue;  // samples run inwards; a layer seam repeats its r
    const double w = (pr.r[i - 1] - r) / (pr.r[i - 1] - pr.r[i]);
    return {pr.p[i - 1] + w * (pr.p[i] - pr.p[i - 1]), pr.rho[i - 1] + w * (pr.rho[i] - pr.rho[i - 1]),
            pr.u[i - 1] + w * (pr.u[i] - pr.u[i - 1]), pr.layer[i]};
  }
  return {pr.p.back(), pr.rho.back(), pr.u.back(), pr.layer.back()};
}

}  // namespace rubble
