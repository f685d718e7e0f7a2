// Collision geometry (rubble/scene/collision.hpp; issue #52 item 3).
#include "rubble/scene/collision.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "rubble/core/error.hpp"

namespace rubble {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Time from periapsis to true anomaly f (negative before periapsis) on a
// conic with eccentricity e and semi-latus rectum p.
double time_from_periapsis(double mu, double p, double e, double f) {
  if (std::fabs(e - 1) < 1e-9) {  // parabola: Barker's equation
    const double d = std::tan(0.5 * f);
    return 0.5 * std::sqrt(p * p * p / mu) * (d + d * d * d / 3);
  }
  if (e < 1) {  // ellipse: Kepler's equation
    const double a = p / (1 - e * e);
    const double E = 2 * std::atan(std::sqrt((1 - e) / (1 + e)) * std::tan(0.5 * f));
    return std::sqrt(a * a * a / mu) * (E - e * std::sin(E));
  }
  const double a = p / (e * e - 1);  // hyperbola: |a|
  const double F = 2 * std::atanh(std::sqrt((e - 1) / (e + 1)) * std::tan(0.5 * f));
  return std::sqrt(a * a * a / mu) * (e * std::sinh(F) - F);
}

// Radial infall from r0 to rc with specific energy E: t = int dr / sqrt(2 (E + mu/r)).
// With r = r0 - (r0 - rc) w^2 the integrand is finite at a turning point r0
// (where the speed is 0); midpoint rule in w.
double radial_time(double mu, double E, double rc, double r0) {
  if (r0 <= rc) return 0;
  const int n = 200000;
  const double L = r0 - rc;
  double t = 0;
  for (int k = 0; k < n; ++k) {
    const double w = (k + 0.5) / n;
    const double r = r0 - L * w * w;
    const double speed2 = 2 * (E + mu / r);
    t += 2 * L * w / std::sqrt(std::max(speed2, 1e-300));
  }
  return t / n;
}

std::array<double, 3> turned(double x, double y, double c, double s) { return {c * x - s * y, s * x + c * y, 0.0}; }

}  // namespace

CollisionOrbit collision_orbit(double mu, double r_contact, double v_contact, double angle, double r_start) {
  if (!(mu > 0 && r_contact > 0 && v_contact > 0 && r_start >= r_contact && angle >= 0 && angle < 0.5 * kPi))
    throw std::invalid_argument("collision_orbit: needs mu, r_contact, v_contact > 0, r_start >= r_contact and an angle in [0, 90) degrees");
  CollisionOrbit o;
  o.mu = mu;
  o.r_contact = r_contact;
  o.r_start = r_start;
  o.v_contact = v_contact;
  o.angle = angle;
  o.v_esc = std::sqrt(2 * mu / r_contact);
  o.energy = 0.5 * v_contact * v_contact - mu / r_contact;
  const double h = r_contact * v_contact * std::sin(angle);
  o.x_contact = {r_contact * std::cos(angle), r_contact * std::sin(angle), 0.0};
  o.v_contact_vector = {-v_contact, 0.0, 0.0};
  const double speed2_start = 2 * (o.energy + mu / r_start);
  if (!(speed2_start >= 0))
    throw std::invalid_argument("the orbit is bound and turns back closer than the starting separation (its apoapsis is " +
                                fmt_g(mu / -o.energy) + " m from the centre, the start " + fmt_g(r_start) +
                                " m): choose a smaller separation or a higher speed");

  if (h <= 1e-12 * r_contact * v_contact) {  // head-on: the radial solution along +x
    o.eccentricity = 1;
    o.x_start = {r_start, 0.0, 0.0};
    o.v_start = {-std::sqrt(speed2_start), 0.0, 0.0};
    o.time_to_contact = radial_time(mu, o.energy, r_contact, r_start);
    return o;
  }
  const double e = std::sqrt(std::max(0.0, 1 + 2 * o.energy * h * h / (mu * mu)));
  o.eccentricity = e;
  const double p = h * h / mu;
  if (e < 1e-12) {
    if (r_start > r_contact * (1 + 1e-12))
      throw std::invalid_argument("the orbit is a circle at the contact distance: it never was farther apart");
    o.x_start = o.x_contact;
    o.v_start = o.v_contact_vector;
    return o;
  }
  // true anomalies on the incoming branch (f < 0), in the periapsis frame
  auto anomaly = [&](double r) { return -std::acos(std::clamp((p / r - 1) / e, -1.0, 1.0)); };
  const double fc = anomaly(r_contact), f0 = anomaly(r_start);
  // the turn that takes the periapsis frame's contact position onto ours
  const double turn = angle - fc;  // atan2 of ours minus atan2 of (cos fc, sin fc)
  const double c = std::cos(turn), s = std::sin(turn);
  const double r0 = p / (1 + e * std::cos(f0));
  o.x_start = turned(r0 * std::cos(f0), r0 * std::sin(f0), c, s);
  o.v_start = turned(-mu / h * std::sin(f0), mu / h * (e + std::cos(f0)), c, s);
  o.time_to_contact = time_from_periapsis(mu, p, e, fc) - time_from_periapsis(mu, p, e, f0);
  return o;
}

template <int D>
CollisionSetup place_collision(const Scene& scene, ParticleStore<D>& ps, const std::vector<std::int64_t>& body_first) {
  CollisionSetup out;
  const CollisionConfig& cc = scene.collision;
  if (!cc.enabled) return out;
  if constexpr (D != 3) {
    throw InputError(scene.file, "collision", "needs a 3-D scene with self-gravity");
  } else {
    // mass, centre of mass and radius of a group of scene bodies
    struct Group {
      double m = 0, R = 0;
      std::array<double, 3> com{};
      std::vector<std::size_t> particles;
    };
    auto group = [&](const std::vector<int>& bodies) {
      Group g;
      for (int b : bodies)
        for (std::int64_t i = body_first[b]; i < body_first[b + 1]; ++i) g.particles.push_back(std::size_t(i));
      for (std::size_t i : g.particles) {
        g.m += ps.m[i];
        for (int k = 0; k < 3; ++k) g.com[k] += ps.m[i] * ps.x[i][k];
      }
      for (int k = 0; k < 3; ++k) g.com[k] /= g.m;
      for (int b : bodies) {
        const BodyConfig& bc = scene.bodies[b];
        double far = 0;
        for (std::int64_t i = body_first[b]; i < body_first[b + 1]; ++i) {
          double r2 = 0;
          for (int k = 0; k < 3; ++k) r2 += (ps.x[i][k] - g.com[k]) * (ps.x[i][k] - g.com[k]);
          far = std::max(far, std::sqrt(r2));
        }
        g.R = std::max(g.R, bc.shape == BodyShape::Polytrope || bc.shape == BodyShape::Layered ? bc.radius : far + 0.5 * bc.spacing);
      }
      return g;
    };
    const Group t = group(cc.target), im = group(cc.impactor);
    const double M = t.m + im.m, mu = scene.gravity.G * M, rc = t.R + im.R;
    const double v_esc = std::sqrt(2 * mu / rc);
    double v = cc.impact_speed;
    if (cc.impact_speed_vesc > 0) v = cc.impact_speed_vesc * v_esc;
    if (cc.v_infinity >= 0) v = std::sqrt(cc.v_infinity * cc.v_infinity + v_esc * v_esc);
    CollisionOrbit o;
    try {
      o = collision_orbit(mu, rc, v, cc.impact_angle * kPi / 180, cc.separation * rc);
    } catch (const std::invalid_argument& e) {
      throw InputError(scene.file, "collision", e.what());
    }
    // held in place while the run relaxes the bodies, launched after it
    const bool held = scene.simulation.damping_time > 0;
    out.held = held;
    for (int k = 0; k < 3; ++k) {
      out.velocity_target[k] = -im.m / M * o.v_start[k];
      out.velocity_impactor[k] = t.m / M * o.v_start[k];
    }
    // barycentric: the target at -(M_i/M) r, the impactor at +(M_t/M) r
    // and each spinning rigidly about its own centre of mass: v += w x (x - com)
    auto move = [&](const Group& g, double share, const std::array<double, 3>& w) {
      for (std::size_t i : g.particles) {
        const double r[3] = {ps.x[i][0] - g.com[0], ps.x[i][1] - g.com[1], ps.x[i][2] - g.com[2]};
        const double spin[3] = {w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]};
        for (int k = 0; k < 3; ++k) {
          ps.x[i][k] += Real(share * o.x_start[k] - g.com[k]);
          if (!held) ps.v[i][k] += Real(share * o.v_start[k] + spin[k]);
        }
      }
    };
    move(t, -im.m / M, cc.spin_target);
    move(im, t.m / M, cc.spin_impactor);
    out.mass_target = t.m;
    out.mass_impactor = im.m;
    out.radius_target = t.R;
    out.radius_impactor = im.R;
    out.orbit = o;
    return out;
  }
}

std::string collision_report(const CollisionSetup& c) {
  const CollisionOrbit& o = c.orbit;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "collision: target %.4g kg (R = %.4g m), impactor %.4g kg (R = %.4g m); v_esc = %.4g m/s, "
                "impact at %.4g m/s (%.4g v_esc) and %.4g deg; start %.4g m apart (%.4g touching distances), "
                "contact %.4g s after the launch%s",
                c.mass_target, c.radius_target, c.mass_impactor, c.radius_impactor, o.v_esc, o.v_contact,
                o.v_contact / o.v_esc, o.angle * 180 / kPi, o.r_start, o.r_start / o.r_contact, o.time_to_contact,
                c.held ? " (held in place and relaxed until simulation.damping_end, then launched)" : " (at t = 0)");
  return buf;
}

template CollisionSetup place_collision<1>(const Scene&, ParticleStore<1>&, const std::vector<std::int64_t>&);
template CollisionSetup place_collision<2>(const Scene&, ParticleStore<2>&, const std::vector<std::int64_t>&);
template CollisionSetup place_collision<3>(const Scene&, ParticleStore<3>&, const std::vector<std::int64_t>&);

}  // namespace rubble
