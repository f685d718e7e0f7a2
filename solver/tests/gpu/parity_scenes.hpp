#pragma once
// The scenes of the backend-parity test (gpu/test_backend_parity.cpp),
// shared with the CPU-only test that builds and steps each of them
// (test_parity_scenes.cpp, label unit), so that an invalid scene is caught
// by .ci/run rather than on a rare GPU host (issue #15 item 1).
//
// 3-D hydro with summation density on a periodic box (the Sod tube, also
// with the viscosity switch), 2-D
// solids with artificial stress, XSPH and a clamp of evolving boundary
// particles (the oscillating plate, with either stress update), and 3-D self-gravity by direct
// summation and by the octree, with damping (a small polytrope), and the 2-D
// granular column collapse with no-slip and with Coulomb walls, and two
// layered embryos held, relaxed and launched - between them every driver. Each runs `steps` steps of exactly dt: dt is below the
// Courant limit and the output interval (which bounds every step) is dt.
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "rubble/run.hpp"
#include "rubble/scene/scene.hpp"

namespace rubble::parity {

inline std::string src(const std::string& rel) { return std::string(RUBBLE_SOURCE_DIR) + "/" + rel; }

inline std::vector<std::string> steps_of(double dt, int steps) {
  return {"simulation.end_time=" + std::to_string(dt * steps), "output.interval=" + std::to_string(dt)};
}

// At the scene's own spacings (0.03125 / 0.0625, about 9000 particles):
// coarser ones (0.0625 / 0.125, the first version of this test) leave the
// periodic y and z lengths (0.43, 0.41) shorter than 2.5 h, which the run
// refuses.
inline Scene sod3d(int steps) {
  return load_scene_file(src("verification/sod_shock_tube/sod_3d.toml"), steps_of(1e-3, steps));
}

// The Sod tube with the viscosity switch (physics/viscosity_switch.hpp):
// per-particle alpha, its rate and its end-of-step bounds on both backends.
inline Scene sod3d_switch(int steps) {
  auto sets = steps_of(1e-3, steps);
  sets.push_back("materials.gas.viscosity={alpha=1.0,beta=2.0,switch=\"morris_monaghan\"}");
  return load_scene_file(src("verification/sod_shock_tube/sod_3d.toml"), sets);
}

inline Scene plate(int steps) {
  auto sets = steps_of(2e-6, steps);
  sets.insert(sets.end(), {"simulation.xsph=0.5", "bodies.0.velocity=[0.0, 1.0]"});
  return load_scene_file(src("validation/oscillating_plate/oscillating_plate.toml"), sets);
}

// The plate with the staggered stress update (leapfrog.hpp): the update
// between the two solid passes on both backends.
inline Scene plate_staggered(int steps) {
  auto sets = steps_of(2e-6, steps);
  sets.insert(sets.end(), {"simulation.xsph=0.5", "bodies.0.velocity=[0.0, 1.0]",
                           "simulation.stress_update=\"staggered\""});
  return load_scene_file(src("validation/oscillating_plate/oscillating_plate.toml"), sets);
}

// The polytrope scene damps until t = 3; the short parity runs end first, so
// the damping ends with them (damping_end must not exceed end_time).
inline std::vector<std::string> polytrope_sets(int steps) {
  auto sets = steps_of(1e-3, steps);
  sets.insert(sets.end(), {"bodies.0.particles=2000", "simulation.damping_end=" + std::to_string(1e-3 * steps)});
  return sets;
}

inline Scene polytrope(int steps) {
  auto sets = polytrope_sets(steps);
  sets.push_back("gravity.mode=\"direct\"");
  return load_scene_file(src("verification/polytrope/polytrope_n1.toml"), sets);
}

// Barnes-Hut: the GPU walks the tree once per particle, so the CPU does too
// (group_size = 1); both build the same tree (test_octree_build.cpp).
inline Scene polytrope_bh(int steps) {
  auto sets = polytrope_sets(steps);
  sets.push_back("gravity.group_size=1");
  return load_scene_file(src("verification/polytrope/polytrope_n1.toml"), sets);
}

// The granular column collapse (Drucker-Prager plasticity, the body force,
// extrapolated walls, particle shifting) at its scene's n = 25, a few
// hundred steps into the collapse; dt = 2e-5 s is a quarter of the
// Courant limit (0.3 hM / c = 8e-5 s with c = 16 m/s).
inline Scene granular_column(int steps) {
  return load_scene_file(src("validation/granular_column_collapse/granular_column_collapse.toml"), steps_of(2e-5, steps));
}

// ... with Coulomb walls (physics/wall_friction.hpp): the sliding walls'
// push, the stick-slip friction and its end-of-step anchors on both backends.
inline Scene granular_column_coulomb(int steps) {
  auto sets = steps_of(2e-5, steps);
  sets.insert(sets.end(), {"bodies.1.wall_slip=\"coulomb\"", "bodies.1.wall_normal=[0.0, 1.0]",
                           "bodies.1.wall_friction=0.36", "bodies.2.wall_slip=\"coulomb\"",
                           "bodies.2.wall_normal=[1.0, 0.0]", "bodies.2.wall_friction=0.36"});
  return load_scene_file(src("validation/granular_column_collapse/granular_column_collapse.toml"), sets);
}

// Two layered embryos (examples/embryo_collision/): Tillotson layers on
// shells, the geometric pressure force, Barnes-Hut (one walk per particle,
// as above), the damping of each body in its own frame while the collision
// holds them, and their launch at damping_end (half-way through the run).
// dt = 2 s is below the example's first steps (~5 s).
inline Scene embryo_collision(int steps) {
  auto sets = steps_of(2.0, steps);
  sets.insert(sets.end(), {"gravity.group_size=1", "simulation.damping_end=" + std::to_string(2.0 * std::max(1, steps / 2)),
                           "bodies.0.particles=900", "bodies.1.particles=100"});
  return load_scene_file(src("examples/embryo_collision/embryo_collision.toml"), sets);
}

// A driven rigid tool (physics/rigid_body.hpp) pressed into clay by a load
// while it turns freely (verification/soil_forces/bearing_capacity.toml at
// 8 particles per footing width): its placement at every stage, its
// reaction from the wall forces and its rates on both backends. dt = 1e-4 s
// is a third of the Courant limit there.
inline Scene soil_tool(int steps) {
  auto sets = steps_of(1e-4, steps);
  sets.insert(sets.end(), {"bodies.0.spacing=0.0125", "bodies.1.spacing=0.0125", "bodies.2.spacing=0.0125",
                           "bodies.2.boundary=\"driven\"", "bodies.2.applied_force=[0.0, -400.0]",
                           "bodies.2.angular_velocity=1.0"});
  return load_scene_file(src("verification/soil_forces/bearing_capacity.toml"), sets);
}

struct ParityScene {
  const char* name;  // a test-name-safe identifier
  Scene (*make)(int steps);
};

inline const std::vector<ParityScene>& scenes() {
  static const std::vector<ParityScene> s = {
      {"Sod3D", sod3d},
      {"Sod3DViscositySwitch", sod3d_switch},
      {"Plate", plate},
      {"PlateStaggered", plate_staggered},
      {"PolytropeDirect", polytrope},
      {"PolytropeBarnesHut", polytrope_bh},
      {"GranularColumn", granular_column},
      {"GranularColumnCoulomb", granular_column_coulomb},
      {"EmbryoCollision", embryo_collision},
      {"SoilTool", soil_tool}};
  return s;
}

inline FinalState run_on(const Scene& scene, Backend b) {
  RunOptions opt;
  opt.write_output = false;
  opt.quiet = true;
  opt.backend = b;
  return run_scene(scene, opt);
}

}  // namespace rubble::parity
