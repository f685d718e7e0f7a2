#pragma once
// Collision geometry from the quantities the field uses (issue #52 item 3):
// two bodies (each one or more scene bodies) that are to meet at a given
// speed and angle. The two-body orbit of their centres of mass is traced
// back analytically from contact to the starting separation, and the bodies
// are placed in the barycentric frame with their discretised masses.
//
// Conventions (as Asphaug 2010, Chem. Erde 70:199, and the SPH collision
// studies after it):
//   contact      the centres R_t + R_i apart (the bodies' radii);
//   v_esc        the mutual escape speed at contact, sqrt(2 G M / (R_t + R_i)),
//                M = M_t + M_i;
//   impact angle theta between the line of centres and the relative
//                velocity at contact: 0 head-on, 90 grazing (impact parameter
//                b = (R_t + R_i) sin theta); 45 degrees is the most probable
//                (Shoemaker 1962);
//   v_infinity   the relative speed at infinity: v_contact^2 = v_inf^2 + v_esc^2.
// The orbit lies in the x-y plane; at contact the impactor moves along -x
// and sits at (R_t + R_i)(cos theta, sin theta, 0) from the target.
//
// Orbit (Kepler problem with mu = G M): specific energy E = v^2/2 - mu/r,
// angular momentum h = r_c v_c sin theta, eccentricity
// e = sqrt(1 + 2 E h^2 / mu^2), semi-latus rectum p = h^2/mu; on the incoming
// branch r(f) = p / (1 + e cos f) with true anomaly f < 0, position
// r (cos f, sin f), velocity (mu/h)(-sin f, e + cos f) in the frame of the
// periapsis, turned so that the contact state is the one above. A head-on
// orbit (theta = 0) is the radial solution. The time from the start to
// contact comes from Kepler's equation (ellipse, hyperbola) or Barker's
// (parabola); the radial one by quadrature. Implemented in
// solver/src/collision.cpp; tested against a direct integration of the
// two-body problem (test_collision.cpp).
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rubble/particles/particle_store.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble {

struct CollisionOrbit {
  double mu = 0;           // G (M_t + M_i) [m^3/s^2]
  double r_contact = 0;    // R_t + R_i [m]
  double r_start = 0;      // the centres' distance at the start [m]
  double v_esc = 0;        // mutual escape speed at contact [m/s]
  double v_contact = 0;    // relative speed at contact [m/s]
  double angle = 0;        // impact angle [rad]
  double energy = 0;       // specific orbital energy [J/kg]
  double eccentricity = 0;
  double time_to_contact = 0;  // [s]
  // the impactor relative to the target (x_i - x_t, v_i - v_t)
  std::array<double, 3> x_start{}, v_start{}, x_contact{}, v_contact_vector{};
};

// The orbit that reaches contact at distance r_contact with speed
// v_contact and impact angle `angle` [rad], traced back to r_start >=
// r_contact. Throws std::invalid_argument when there is none (a bound orbit
// whose apoapsis is closer than r_start; a circular orbit at contact).
CollisionOrbit collision_orbit(double mu, double r_contact, double v_contact, double angle, double r_start);

// What place_collision did, for the run's report.
struct CollisionSetup {
  double mass_target = 0, mass_impactor = 0;      // discretised [kg]
  double radius_target = 0, radius_impactor = 0;  // [m]
  CollisionOrbit orbit;
  // Held for a relaxation (simulation.damping_time with [collision]): the
  // bodies were moved to the start but left at rest; launch_collision gives
  // them these velocities (and the scene's spins) at damping_end.
  bool held = false;
  std::array<double, 3> velocity_target{}, velocity_impactor{};
};

// Moves and launches the [collision]'s bodies in the generated store: the
// target's and the impactor's centres of mass to the start of the orbit in
// the barycentric frame of the two, their particles' velocities to the
// orbit's (the bodies start at rest). A body's radius is the largest
// distance of its particles from its centre of mass plus half its spacing
// (the polytrope's and the layered body's own radius). No-op without a
// [collision] table. With a relaxation (simulation.damping_time) the bodies
// are moved but not launched: held = true, velocities in the setup.
template <int D>
CollisionSetup place_collision(const Scene& scene, ParticleStore<D>& ps, const std::vector<std::int64_t>& body_first);

// One line for the run's start: masses, radii, v_esc, v_contact, angle,
// separation, time to contact.
std::string collision_report(const CollisionSetup& c);

}  // namespace rubble
