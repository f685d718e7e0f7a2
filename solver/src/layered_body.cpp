// A layered body in hydrostatic equilibrium as particles on nested shells
// (rubble/scene/layered_body.hpp).
#include "rubble/scene/layered_body.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "rubble/drivers/run_physics.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<HydrostaticLayer> layers_with_radii(const LayeredSpec& spec, const std::vector<double>& radii) {
  std::vector<HydrostaticLayer> layers;
  for (std::size_t k = 0; k < spec.eos.size(); ++k) layers.push_back({spec.eos[k], radii[k]});
  return layers;
}

// Outer radii of shells of the given volumes, from the centre out.
std::vector<double> radii_of_volumes(const std::vector<double>& volume) {
  std::vector<double> r;
  double v = 0;
  for (double dv : volume) {
    v += dv;
    r.push_back(std::cbrt(3 * v / (4 * kPi)));
  }
  return r;
}

// A uniformly random rotation (Shoemake 1992, Graphics Gems III: a unit
// quaternion from three uniform numbers) applied to x.
struct Rotation {
  double q[4];  // w, x, y, z
  explicit Rotation(std::mt19937_64& rng) {
    auto uniform = [&] { return double(rng() >> 11) * 0x1.0p-53; };
    const double u1 = uniform(), u2 = uniform(), u3 = uniform();
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    q[0] = b * std::cos(2 * kPi * u3);
    q[1] = a * std::sin(2 * kPi * u2);
    q[2] = a * std::cos(2 * kPi * u2);
    q[3] = b * std::sin(2 * kPi * u3);
  }
  std::array<double, 3> operator()(const std::array<double, 3>& v) const {
    // v' = v + 2 w (u x v) + 2 u x (u x v), u the quaternion's vector part
    const double w = q[0], u[3] = {q[1], q[2], q[3]};
    const double t[3] = {2 * (u[1] * v[2] - u[2] * v[1]), 2 * (u[2] * v[0] - u[0] * v[2]),
                         2 * (u[0] * v[1] - u[1] * v[0])};
    return {v[0] + w * t[0] + (u[1] * t[2] - u[2] * t[1]), v[1] + w * t[1] + (u[2] * t[0] - u[0] * t[2]),
            v[2] + w * t[2] + (u[0] * t[1] - u[1] * t[0])};
  }
};

// n points on the unit sphere on the Fibonacci spiral: equal steps in z
// (equal areas) and the golden angle in longitude.
std::vector<std::array<double, 3>> fibonacci_sphere(std::int64_t n) {
  std::vector<std::array<double, 3>> p;
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (std::int64_t j = 0; j < n; ++j) {
    const double z = 1 - (2 * double(j) + 1) / double(n);
    const double s = std::sqrt(std::max(0.0, 1 - z * z));
    const double phi = golden * double(j);
    p.push_back({s * std::cos(phi), s * std::sin(phi), z});
  }
  return p;
}

// The mass enclosed within radius r (the profile's m(r), linear between samples).
double mass_within(const HydrostaticProfile& pr, double r) {
  const std::size_t n = pr.r.size();
  if (r >= pr.r.front()) return pr.m.front();
  for (std::size_t i = 1; i < n; ++i) {
    if (pr.r[i] > r || pr.r[i] == pr.r[i - 1]) continue;
    const double w = (pr.r[i - 1] - r) / (pr.r[i - 1] - pr.r[i]);
    return pr.m[i - 1] + w * (pr.m[i] - pr.m[i - 1]);
  }
  // inside the innermost sample: the central density's ball
  return 4.0 / 3.0 * kPi * r * r * r * pr.rho.back();
}

}  // namespace

LayeredSpec layered_spec(const std::vector<MaterialConfig>& materials, const BodyConfig& b) {
  LayeredSpec spec;
  for (const LayerConfig& layer : b.layers) {
    spec.eos.push_back(eos_params_from_material(materials.at(std::size_t(layer.material_id))));
    if (layer.mass_fraction > 0) spec.mass_fraction.push_back(layer.mass_fraction);
    else spec.outer_radius.push_back(layer.radius);
  }
  if (!spec.mass_fraction.empty()) spec.total_mass = b.mass;
  return spec;
}

HydrostaticProfile layered_profile(const LayeredSpec& spec, double G) {
  const std::size_t nl = spec.eos.size();
  if (nl == 0) throw std::invalid_argument("layered body: no layers");
  const bool by_radius = !spec.outer_radius.empty();
  if (by_radius == !spec.mass_fraction.empty())
    throw std::invalid_argument("layered body: give either every layer's outer radius or every layer's mass fraction");
  if (by_radius) {
    if (spec.outer_radius.size() != nl) throw std::invalid_argument("layered body: one outer radius per layer");
    return hydrostatic_profile(layers_with_radii(spec, spec.outer_radius), G);
  }
  if (spec.mass_fraction.size() != nl) throw std::invalid_argument("layered body: one mass fraction per layer");
  if (!(spec.total_mass > 0)) throw std::invalid_argument("layered body: mass fractions need a total mass > 0");
  // start from the layers at their surface densities, then scale each
  // layer's volume by the ratio of its wanted mass to its profile mass
  std::vector<double> volume;
  for (std::size_t k = 0; k < nl; ++k) {
    if (!(spec.mass_fraction[k] > 0)) throw std::invalid_argument("layered body: mass fractions must be > 0");
    volume.push_back(spec.mass_fraction[k] * spec.total_mass / layer_reference_density(spec.eos[k]));
  }
  for (int it = 0; it < 200; ++it) {
    HydrostaticProfile pr = hydrostatic_profile(layers_with_radii(spec, radii_of_volumes(volume)), G);
    double worst = 0;
    for (std::size_t k = 0; k < nl; ++k) {
      const double ratio = spec.mass_fraction[k] * spec.total_mass / pr.layer_mass[k];
      worst = std::max(worst, std::fabs(ratio - 1));
      volume[k] *= ratio;
    }
    if (worst < 1e-10) return pr;
  }
  throw std::runtime_error(
      "layered body: no layer radii give the mass fractions (the iteration did not converge in 200 profiles)");
}

double radius_enclosing(const HydrostaticProfile& pr, double m) {
  const std::size_t n = pr.r.size();
  if (m >= pr.m.front()) return pr.r.front();
  for (std::size_t i = 1; i < n; ++i) {
    if (pr.m[i] > m || pr.m[i] == pr.m[i - 1]) continue;  // samples run inwards; m falls
    const double w = (pr.m[i - 1] - m) / (pr.m[i - 1] - pr.m[i]);
    return pr.r[i - 1] + w * (pr.r[i] - pr.r[i - 1]);
  }
  return std::cbrt(3 * std::max(m, 0.0) / (4 * kPi * pr.rho.back()));  // the central ball
}

HydrostaticState hydrostatic_in_layer(const HydrostaticProfile& pr, double r, int layer) {
  const std::size_t n = pr.r.size();
  std::size_t top = n, bottom = n;  // the layer's samples [top, bottom]
  for (std::size_t i = 0; i < n; ++i)
    if (pr.layer[i] == layer) {
      if (top == n) top = i;
      bottom = i;
    }
  if (top == n) throw std::invalid_argument("hydrostatic_in_layer: no such layer");
  auto at = [&](std::size_t i) { return HydrostaticState{pr.p[i], pr.rho[i], pr.u[i], layer}; };
  if (r >= pr.r[top]) return at(top);
  for (std::size_t i = top + 1; i <= bottom; ++i) {
    if (pr.r[i] > r) continue;
    const double w = (pr.r[i - 1] - r) / (pr.r[i - 1] - pr.r[i]);
    return {pr.p[i - 1] + w * (pr.p[i] - pr.p[i - 1]), pr.rho[i - 1] + w * (pr.rho[i] - pr.rho[i - 1]),
            pr.u[i - 1] + w * (pr.u[i] - pr.u[i - 1]), layer};
  }
  return at(bottom);
}

ShellParticles place_on_shells(const HydrostaticProfile& pr, std::int64_t particles, std::uint64_t seed) {
  if (particles < 1) throw std::invalid_argument("place_on_shells: particles must be >= 1");
  const std::size_t nl = pr.layer_mass.size();
  const double m0 = pr.mass / double(particles);
  std::mt19937_64 rng(seed);
  ShellParticles out;
  double m_below = 0;  // the mass inside the current layer
  for (std::size_t k = 0; k < nl; ++k) {
    const double r_in = k > 0 ? pr.layer_radius[k - 1] : 0.0, r_out = pr.layer_radius[k];
    const double M_k = pr.layer_mass[k];
    const std::int64_t N_k = std::max<std::int64_t>(1, std::llround(M_k / m0));
    const double m_k = M_k / double(N_k);
    // the layer's thickness in local spacings d = (m_k / rho)^(1/3), on a
    // fine grid (midpoint rule), and the radius at each fraction of it
    constexpr int kGrid = 4000;
    std::vector<double> cum(kGrid + 1, 0.0);
    const double dr = (r_out - r_in) / kGrid;
    for (int j = 0; j < kGrid; ++j) {
      const double r = r_in + (j + 0.5) * dr;
      cum[j + 1] = cum[j] + dr * std::cbrt(hydrostatic_in_layer(pr, r, int(k)).rho / m_k);
    }
    // The innermost layer starts with one particle at the centre (its ball
    // of mass m_k is c0 spacings thick), the shells about one spacing thick
    // around it: the closest shells then sit near one spacing from it, as
    // in a close packing. (Shells from r = 0 leave a hole of about a
    // spacing at the centre: summation densities there came out 9-15 % low.)
    double c0 = 0;
    std::vector<std::int64_t> below{0};
    if (k == 0 && N_k > 1) {
      const double r1 = radius_enclosing(pr, m_k);
      c0 = cum[std::size_t(std::min(kGrid, int(r1 / dr)))];
      below.push_back(1);
    }
    const std::int64_t n_shells = std::clamp<std::int64_t>(std::llround(cum[kGrid] - c0), 1, N_k);
    // each boundary's particle count below it, from the ideal boundaries
    for (std::int64_t s = 1; s < n_shells; ++s) {
      const double target = c0 + (cum[kGrid] - c0) * double(s) / double(n_shells);
      const auto it = std::lower_bound(cum.begin(), cum.end(), target);
      const std::size_t j = std::size_t(std::max<std::ptrdiff_t>(1, it - cum.begin()));
      const double w = (target - cum[j - 1]) / (cum[j] - cum[j - 1]);
      const double r = r_in + (double(j - 1) + w) * dr;
      const std::int64_t c = std::llround((mass_within(pr, r) - m_below) / m_k);
      if (c > below.back() && c < N_k) below.push_back(c);  // a shell holds at least one particle
    }
    below.push_back(N_k);
    for (std::size_t s = 0; s + 1 < below.size(); ++s) {
      const std::int64_t count = below[s + 1] - below[s];
      // the shell's mass-median radius: half its particles' mass below it
      const double r_mid = radius_enclosing(pr, m_below + m_k * 0.5 * double(below[s] + below[s + 1]));
      const Rotation turn(rng);
      const bool centre = k == 0 && s == 0 && count == 1;  // the central particle
      for (const auto& p : fibonacci_sphere(count)) {
        const auto q = turn(p);
        out.x.push_back(centre ? std::array<double, 3>{0, 0, 0}
                               : std::array<double, 3>{r_mid * q[0], r_mid * q[1], r_mid * q[2]});
        out.m.push_back(m_k);
        out.layer.push_back(int(k));
        out.shell.push_back(out.shells);
      }
      ++out.shells;
    }
    m_below += M_k;
  }
  return out;
}

}  // namespace rubble
