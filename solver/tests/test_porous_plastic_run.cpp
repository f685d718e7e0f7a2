// Porosity (issue #11), plasticity (issue #12), the body force and walls
// through the whole pipeline: scene keys and their validation (an error
// naming the file and the key), the fields a run allocates (none for a
// scene that does not use the feature), and small runs whose outcome is
// known exactly: a porous block at rest keeps alpha0, a compressed porous
// rod never lets alpha rise, a block in free fall gains v = -g t and
// conserves kinetic + internal + potential energy, a block sliding on a
// free-slip wall keeps its momentum while a no-slip wall brakes it, and a
// Coulomb wall brakes it by mu times its push.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <unistd.h>

#include "scene_error.hpp"
#include "rubble/core/error.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/io/snapshot.hpp"
#include "rubble/physics/porosity.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "conserved_column.hpp"

using namespace rubble;

namespace {

// A 1-D porous aluminium rod (J08 §5.1 parameters) on the aluminium
// Tillotson matrix; `porosity_extra` is appended inside the porosity table.
std::string porous_rod(const std::string& porosity = "", const std::string& extra_material = "",
                       const std::string& velocity = "0.0", double end_time = 1e-7) {
  std::ostringstream s;
  s << "[simulation]\ndimension = 1\nend_time = " << end_time << "\nintegrator = \"leapfrog\"\nhfact = 2.0\ndensity = \"continuity\"\n"
    << "[materials.al]\neos = \"tillotson\"\n"
    << "tillotson = { rho0 = 2700.0, A = 7.52e10, B = 6.5e10, E0 = 5.0e6, E_iv = 3.0e6, E_cv = 1.39e7, a = 0.5, "
       "b = 1.63, alpha = 5.0, beta = 5.0 }\n"
    << (porosity.empty()
            ? "porosity = { model = \"p_alpha\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8, c_e = 4110.0, c_s0 = 5350.0 }\n"
            : porosity + "\n")
    << extra_material
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"al\"\nmin = [0.0]\nmax = [0.004]\nspacing = 1e-4\n"
       "density = 2117.6470588235293\ninternal_energy = 0.0\nvelocity = ["
    << velocity << "]\n"
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"al\"\nmin = [-0.0005]\nmax = [0.0]\nspacing = 1e-4\n"
       "density = 2117.6470588235293\ninternal_energy = 0.0\nboundary = \"fixed\"\n"
    << "[output]\ninterval = " << end_time / 4 << "\n";
  return s.str();
}

// A 2-D block of dimensionless rubber (K = 1, mu = 0.22).
std::string rubber_block(const std::string& material_extra, const std::string& simulation_extra = "",
                         const std::string& bodies_extra = "", const std::string& velocity = "0.0, 0.0",
                         double end_time = 0.5) {
  std::ostringstream s;
  s << "[simulation]\ndimension = 2\nend_time = " << end_time << "\nintegrator = \"leapfrog\"\n" << simulation_extra
    << "\n[materials.rubber]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n" << material_extra
    << "\n[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.0, 0.0]\nmax = [1.0, 0.5]\n"
       "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nvelocity = ["
    << velocity << "]\n"
    << bodies_extra << "[output]\ninterval = " << end_time / 4 << "\n";
  return s.str();
}

// The InputError message of parsing `text`, or "" when it parses.
using rubble::test::parse_error;

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) : path(std::filesystem::temp_directory_path() / ("rubble_pp_" + std::to_string(getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

// Every snapshot of a run, in order.
template <int D>
std::vector<ParticleStore<D>> run_snapshots(const Scene& s, const TempDir& dir) {
  RunOptions opt;
  opt.out_dir = dir.path.string();
  opt.quiet = true;
  run_scene(s, opt);
  std::vector<ParticleStore<D>> out;
  for (int k = 0;; ++k) {
    const auto f = dir.path / snapshot_filename(s.output.name, k);
    if (!std::filesystem::exists(f)) break;
    ParticleStore<D> ps;
    SnapshotMeta meta;
    read_snapshot<D>(f.string(), ps, meta);
    out.push_back(std::move(ps));
  }
  return out;
}

bool has(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }

using rubble::test::conserved_column;

}  // namespace

// ---- scene keys --------------------------------------------------------------

TEST(PorosityScene, KeysAreReadWithDefaults) {
  const Scene s = parse_scene(porous_rod(), "t.toml");
  const PorosityParams& p = s.materials[0].porosity;
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.curve, CrushCurve::Quadratic);  // the default
  EXPECT_EQ(p.alpha_e, 1.275);
  EXPECT_EQ(p.p_e, 8e7);
  EXPECT_EQ(p.p_s, 7e8);
  EXPECT_EQ(p.n2, 2.0);  // Jutzi 2008 eq. 8 (the quadratic curve's exponent, the params' default)
  EXPECT_TRUE(p.deviatoric_rate_factor);  // Jutzi 2008's factor on dS/dt, on by default
  EXPECT_FALSE(parse_scene(porous_rod("porosity = { model = \"p_alpha\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8, "
                                      "deviatoric_rate_factor = false }"),
                           "t.toml")
                   .materials[0]
                   .porosity.deviatoric_rate_factor);
  const Scene t = parse_scene(porous_rod("porosity = { model = \"p_alpha\", crush_curve = \"steep\", alpha0 = 4.64, "
                                         "alpha_t = 1.9, p_e = 1e6, p_t = 6.8e7, p_s = 2.13e8, n1 = 12.0, n2 = 3.0, "
                                         "c_e = 1500.0, c_s0 = 3000.0 }"),
                              "t.toml");
  EXPECT_EQ(t.materials[0].porosity.curve, CrushCurve::Steep);
  EXPECT_EQ(t.materials[0].porosity.n1, 12.0);
  // the library's porous materials load and validate
  for (const char* name : {"porous_aluminium", "porous_basalt", "pumice"}) {
    const MaterialConfig m = load_material(name);
    EXPECT_TRUE(m.porosity.enabled) << name;
  }
}

// c_e and c_s0 come as a pair: without both the material has no elastic
// branch (docs/scene.md); the parsed pair is (0, 0), which the physics reads as
// "elastic branch off" (porosity_elastic_enabled).
TEST(PorosityScene, ElasticBranchIsOptionalAsAPair) {
  const Scene s =
      parse_scene(porous_rod("porosity = { model = \"p_alpha\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8 }"), "t.toml");
  const PorosityParams& p = s.materials[0].porosity;
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.c_e, 0.0);
  EXPECT_EQ(p.c_s0, 0.0);
  // the library's pumice has no elastic branch (no sound speed of J09's pumice was found: the file says so)
  const MaterialConfig pumice = load_material("pumice");
  EXPECT_EQ(pumice.porosity.c_e, 0.0);
  EXPECT_EQ(pumice.porosity.c_s0, 0.0);
  // J09's pumice curve as PHYSICS.md section 4 prints it; the matrix is Spheral's 'pumice' in SI
  EXPECT_EQ(pumice.porosity.curve, CrushCurve::Steep);
  EXPECT_EQ(pumice.porosity.alpha_e, 4.64);
  EXPECT_EQ(pumice.porosity.alpha_t, 1.90);
  EXPECT_EQ(pumice.porosity.p_e, 1e6);
  EXPECT_EQ(pumice.porosity.p_t, 6.8e7);
  EXPECT_EQ(pumice.porosity.p_s, 2.13e8);
  EXPECT_EQ(pumice.porosity.n1, 12.0);
  EXPECT_EQ(pumice.porosity.n2, 3.0);
  EXPECT_EQ(pumice.tillotson.rho0, 2327.0);
  EXPECT_EQ(pumice.tillotson.A, 2.67e10);
}

TEST(PorosityScene, BadValuesNameTheKey) {
  const std::string base = "porosity = { model = \"p_alpha\", ";
  const std::string tail = ", c_e = 4110.0, c_s0 = 5350.0 }";
  struct Case {
    std::string porosity, key;
  };
  const std::vector<Case> cases = {
      {base + "alpha0 = 1.0, p_e = 8e7, p_s = 7e8" + tail, "materials.al.porosity.alpha0"},
      {base + "alpha0 = 0.9, p_e = 8e7, p_s = 7e8" + tail, "materials.al.porosity.alpha0"},
      {base + "alpha0 = 1.275, p_e = 8e8, p_s = 7e8" + tail, "materials.al.porosity.p_s"},
      {base + "alpha0 = 1.275, p_e = -1.0, p_s = 7e8" + tail, "materials.al.porosity.p_e"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, c_e = 6000.0, c_s0 = 5350.0 }", "materials.al.porosity.c_e"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, c_e = 4110.0 }", "materials.al.porosity.c_s0"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, c_s0 = 5350.0 }", "materials.al.porosity.c_e"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, c_e = 0.0, c_s0 = 5350.0 }", "materials.al.porosity.c_e"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, p_t = 1e8" + tail, "materials.al.porosity.p_t"},  // quadratic
      {base + "crush_curve = \"steep\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8" + tail, "materials.al.porosity.p_t"},
      {base + "crush_curve = \"cubic\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8" + tail,
       "materials.al.porosity.crush_curve"},
      {"porosity = { model = \"sponge\", alpha0 = 1.275, p_e = 8e7, p_s = 7e8" + tail, "materials.al.porosity.model"},
      {base + "alpha0 = nan, p_e = 8e7, p_s = 7e8" + tail, "materials.al.porosity.alpha0"},
      {base + "alpha0 = 1.275, p_e = 8e7, p_s = 7e8, deviatoric_rate_factor = 1" + tail,
       "materials.al.porosity.deviatoric_rate_factor"},
  };
  for (const Case& c : cases) {
    const std::string msg = parse_error(porous_rod(c.porosity));
    EXPECT_NE(msg.find("t.toml"), std::string::npos) << c.porosity << ": " << msg;
    EXPECT_NE(msg.find(c.key), std::string::npos) << c.porosity << ": " << msg;
  }
  // a porous ideal gas has no matrix to compact
  const std::string gas =
      "[simulation]\ndimension = 1\nend_time = 1.0\n[materials.g]\neos = \"ideal_gas\"\ngamma = 1.4\n"
      "porosity = { model = \"p_alpha\", alpha0 = 1.5, p_e = 1.0, p_s = 2.0, c_e = 1.0, c_s0 = 2.0 }\n"
      "[[bodies]]\nshape = \"box\"\nmaterial = \"g\"\nmin = [0.0]\nmax = [1.0]\nspacing = 0.1\ndensity = 1.0\n"
      "pressure = 1.0\n";
  const std::string msg = parse_error(gas);
  EXPECT_NE(msg.find("materials.g.porosity"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ideal gas"), std::string::npos) << msg;
}

TEST(PlasticityScene, KeysAreReadWithDefaults) {
  const Scene s = parse_scene(rubber_block("shear_modulus = 0.22\nplasticity = { model = \"drucker_prager\", "
                                           "friction_angle = 30.0, cohesion = 0.01 }"),
                              "t.toml");
  const PlasticityConfig& p = s.materials[0].plasticity;
  EXPECT_EQ(p.model, PlasticityModel::DruckerPrager);
  EXPECT_EQ(p.dilatancy_angle, 0.0);       // default psi = 0
  EXPECT_EQ(p.cone, DpConeFit::PlaneStrain);  // default fit
  const Scene v = parse_scene(rubber_block("shear_modulus = 0.22\nplasticity = { model = \"von_mises\", yield_stress = 0.01 }"),
                              "t.toml");
  EXPECT_EQ(v.materials[0].plasticity.model, PlasticityModel::VonMises);
  EXPECT_EQ(v.materials[0].plasticity.yield_stress, 0.01);
  for (const char* name : {"aluminium_bars", "phobos_regolith"}) {
    const MaterialConfig m = load_material(name);
    EXPECT_EQ(m.plasticity.model, PlasticityModel::DruckerPrager) << name;
  }
}

// Each cone name reaches the run as its fit's constants (plasticity.hpp).
TEST(PlasticityScene, ConeNamesSelectTheirFit) {
  struct Case { const char* name; DpConeFit cone; DpConeFit fit; };
  for (const Case c : {Case{"plane_strain", DpConeFit::PlaneStrain, DpConeFit::PlaneStrain},
                       Case{"compression", DpConeFit::Compression, DpConeFit::Compression},
                       Case{"extension", DpConeFit::Extension, DpConeFit::Extension}}) {
    const Scene s = parse_scene(rubber_block(std::string("shear_modulus = 0.22\nplasticity = { model = \"drucker_prager\", "
                                                         "friction_angle = 30.0, cohesion = 0.01, cone = \"") +
                                             c.name + "\" }"),
                                "t.toml");
    EXPECT_EQ(s.materials[0].plasticity.cone, c.cone) << c.name;
    const PlasticityParams pp = plasticity_params_from_config(s.materials[0].plasticity);
    EXPECT_EQ(pp.alpha_phi, dp_cone_alpha(Real(30.0), c.fit)) << c.name;
    EXPECT_EQ(pp.k_c, dp_cone_k(Real(30.0), Real(0.01), c.fit)) << c.name;
  }
}

TEST(PlasticityScene, BadValuesNameTheKey) {
  const std::string dp = "shear_modulus = 0.22\nplasticity = { model = \"drucker_prager\", ";
  struct Case {
    std::string material, key;
  };
  const std::vector<Case> cases = {
      {dp + "friction_angle = 90.0, cohesion = 0.0 }", "materials.rubber.plasticity.friction_angle"},
      {dp + "friction_angle = -1.0, cohesion = 0.0 }", "materials.rubber.plasticity.friction_angle"},
      {dp + "friction_angle = 20.0, cohesion = -1.0 }", "materials.rubber.plasticity.cohesion"},
      {dp + "friction_angle = 20.0, cohesion = 0.0, dilatancy_angle = 25.0 }",
       "materials.rubber.plasticity.dilatancy_angle"},
      {dp + "friction_angle = 20.0, cohesion = 0.0, cone = \"round\" }", "materials.rubber.plasticity.cone"},
      {dp + "cohesion = 0.0 }", "materials.rubber.plasticity.friction_angle"},
      {dp + "friction_angle = 20.0, cohesion = 0.0, yield_stress = 1.0 }", "materials.rubber.plasticity.yield_stress"},
      {"shear_modulus = 0.22\nplasticity = { model = \"von_mises\", yield_stress = -1.0 }",
       "materials.rubber.plasticity.yield_stress"},
      {"shear_modulus = 0.22\nplasticity = { model = \"tresca\", yield_stress = 1.0 }",
       "materials.rubber.plasticity.model"},
      // plasticity on a fluid
      {"plasticity = { model = \"von_mises\", yield_stress = 1.0 }", "materials.rubber.plasticity"},
  };
  for (const Case& c : cases) {
    const std::string msg = parse_error(rubber_block(c.material));
    EXPECT_NE(msg.find("t.toml"), std::string::npos) << c.material << ": " << msg;
    EXPECT_NE(msg.find(c.key), std::string::npos) << c.material << ": " << msg;
  }
}

TEST(BodyForceAndWallScene, KeysAreValidated) {
  const Scene s = parse_scene(rubber_block("", "gravity = [0.0, -9.81]"), "t.toml");
  EXPECT_EQ(s.simulation.gravity[1], -9.81);
  EXPECT_NE(parse_error(rubber_block("", "gravity = [0.0, -9.81, 0.0]")).find("simulation.gravity"), std::string::npos);
  EXPECT_NE(parse_error(rubber_block("", "gravity = [0.0, nan]")).find("simulation.gravity"), std::string::npos);
  const std::string wall = "[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.0, -0.3]\nmax = [1.0, 0.0]\n"
                           "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nboundary = \"fixed\"\n";
  const Scene w = parse_scene(rubber_block("", "", wall + "wall_slip = \"free_slip\"\nwall_normal = [0.0, 2.0]\n"), "t.toml");
  EXPECT_EQ(w.bodies[1].wall_slip, WallSlip::FreeSlip);
  EXPECT_DOUBLE_EQ(w.bodies[1].wall_normal[1], 1.0);  // normalised
  EXPECT_NE(parse_error(rubber_block("", "", wall + "wall_slip = \"free_slip\"\n")).find("bodies[1].wall_normal"),
            std::string::npos);
  EXPECT_NE(parse_error(rubber_block("", "", wall + "wall_slip = \"free_slip\"\nwall_normal = [0.0, 0.0]\n"))
                .find("bodies[1].wall_normal"),
            std::string::npos);
  EXPECT_NE(parse_error(rubber_block("", "", wall + "wall_slip = \"sticky\"\n")).find("bodies[1].wall_slip"),
            std::string::npos);
  // a body that is no wall cannot slip
  EXPECT_NE(parse_error(rubber_block("", "", wall.substr(0, wall.find("boundary")) + "wall_slip = \"no_slip\"\n"))
                .find("bodies[1].wall_slip"),
            std::string::npos);
}

// ---- what a run allocates ------------------------------------------------------

TEST(FeatureFields, OnlyTheScenesFeaturesAreAllocated) {
  {  // elastic solid: none of the new fields
    TempDir d("fields_elastic");
    const auto snaps = run_snapshots<2>(parse_scene(rubber_block("shear_modulus = 0.22", "", "", "0.0, 0.0", 0.05), "t.toml"), d);
    const auto f = snaps.back().allocated_fields();
    for (const char* k : {"alpha", "eps_p", "eps_v"}) EXPECT_FALSE(has(f, k)) << k;
  }
  {  // von Mises: eps_p only (no volume change)
    TempDir d("fields_von_mises");
    const auto snaps = run_snapshots<2>(
        parse_scene(rubber_block("shear_modulus = 0.22\nplasticity = { model = \"von_mises\", yield_stress = 0.05 }", "",
                                 "", "0.0, 0.0", 0.05),
                    "t.toml"),
        d);
    const auto f = snaps.back().allocated_fields();
    EXPECT_TRUE(has(f, "eps_p"));
    EXPECT_FALSE(has(f, "eps_v"));
    EXPECT_FALSE(has(f, "alpha"));
  }
  {  // Drucker-Prager, psi = 0: eps_p and eps_v (the tension-cracking opening persists)
    TempDir d("fields_plastic");
    const auto snaps = run_snapshots<2>(
        parse_scene(rubber_block("shear_modulus = 0.22\nplasticity = { model = \"drucker_prager\", friction_angle = 30.0, "
                                 "cohesion = 0.01 }",
                                 "", "", "0.0, 0.0", 0.05),
                    "t.toml"),
        d);
    const auto f = snaps.back().allocated_fields();
    EXPECT_TRUE(has(f, "eps_p"));
    EXPECT_TRUE(has(f, "eps_v"));
    EXPECT_FALSE(has(f, "alpha"));
  }
  {  // porous fluid: alpha only
    TempDir d("fields_porous");
    const auto snaps = run_snapshots<1>(parse_scene(porous_rod(), "t.toml"), d);
    const auto f = snaps.back().allocated_fields();
    EXPECT_TRUE(has(f, "alpha"));
    EXPECT_FALSE(has(f, "eps_p"));
  }
}

// ---- small runs with a known outcome ---------------------------------------------

// A porous rod at rest and zero pressure is below p_e everywhere: alpha stays alpha0.
TEST(PorousRun, AtRestKeepsAlpha0) {
  TempDir d("rest");
  const auto snaps = run_snapshots<1>(parse_scene(porous_rod(), "t.toml"), d);
  ASSERT_GE(snaps.size(), 2u);
  for (std::size_t i = 0; i < snaps.back().n; ++i) EXPECT_DOUBLE_EQ(snaps.back().alpha[i], 1.275);
}

// Driven at 458 m/s into a fixed wall, the rod compacts: alpha falls near the
// wall, never rises at any particle between outputs, never drops below 1,
// and lies on or below the crush curve at the particle's pressure.
TEST(PorousRun, CompactionNeverRaisesAlpha) {
  TempDir d("compaction");
  const Scene s = parse_scene(porous_rod("", "", "-458.0", 2e-6), "t.toml");
  const auto snaps = run_snapshots<1>(s, d);
  ASSERT_EQ(snaps.size(), 5u);
  PorosityParams pp{};
  pp.enabled = true;
  pp.alpha_e = 1.275;
  pp.p_e = 8e7;
  pp.p_s = 7e8;
  pp.n2 = 2;
  double alpha_min = 2;
  for (std::size_t k = 1; k < snaps.size(); ++k) {
    // particles are re-sorted between snapshots: match them by mass-free identity (x order is kept in 1-D)
    std::vector<std::pair<double, double>> prev, cur;
    for (std::size_t i = 0; i < snaps[k].n; ++i)
      if (!snaps[k].boundary[i]) cur.push_back({snaps[k].x[i][0], snaps[k].alpha[i]});
    for (std::size_t i = 0; i < snaps[k - 1].n; ++i)
      if (!snaps[k - 1].boundary[i]) prev.push_back({snaps[k - 1].x[i][0], snaps[k - 1].alpha[i]});
    std::sort(cur.begin(), cur.end());
    std::sort(prev.begin(), prev.end());
    ASSERT_EQ(cur.size(), prev.size());
    for (std::size_t i = 0; i < cur.size(); ++i) {
      EXPECT_LE(cur[i].second, prev[i].second) << "snapshot " << k << " particle " << i;
      EXPECT_GE(cur[i].second, 1.0);
      alpha_min = std::min(alpha_min, cur[i].second);
    }
    for (std::size_t i = 0; i < snaps[k].n; ++i) {
      if (snaps[k].boundary[i] || !(snaps[k].p[i] > 0)) continue;
      EXPECT_LE(snaps[k].alpha[i], double(crush_curve_alpha(pp, Real(snaps[k].p[i]))) * (1 + 1e-9))
          << "snapshot " << k << " above the crush curve";
    }
  }
  EXPECT_LT(alpha_min, 1.01);  // the compacted zone reached (near) full compaction (p ~ 2 GPa > p_s)
}

// Free fall: the centre of mass gains exactly v = g t (internal forces cancel
// pairwise), and kinetic + internal + potential energy is conserved.
TEST(BodyForceRun, FreeFallAndEnergy) {
  TempDir d("fall");
  const Scene s = parse_scene(rubber_block("shear_modulus = 0.22", "gravity = [0.0, -0.1]"), "t.toml");
  const auto snaps = run_snapshots<2>(s, d);
  const ParticleStore<2>& last = snaps.back();
  double mv = 0, m = 0;
  for (std::size_t i = 0; i < last.n; ++i) {
    mv += last.m[i] * last.v[i][1];
    m += last.m[i];
  }
  EXPECT_NEAR(mv / m, -0.1 * 0.5, 1e-12);  // v = g t at t = 0.5, to round-off
  const auto total = conserved_column(d.path, "total");
  const auto kin = conserved_column(d.path, "kinetic");
  ASSERT_GT(total.size(), 10u);
  // the kinetic energy grows by 1/2 M (g t)^2 = 1/2 * 0.5 * 0.05^2 = 6.25e-4;
  // leapfrog keeps the total to a small fraction of that
  EXPECT_GT(kin.back(), 5e-4);
  EXPECT_LT(std::fabs(total.back() - total.front()), 1e-3 * kin.back());
}

// A block sliding at 0.05 along a wall: a free-slip wall exerts no tangential
// force (x momentum kept to round-off); a no-slip wall brakes it.
TEST(WallRun, FreeSlipKeepsTangentialMomentumNoSlipBrakes) {
  const std::string wall = "[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [-1.0, -0.3]\nmax = [2.0, 0.0]\n"
                           "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nboundary = \"fixed\"\n";
  auto px = [](const ParticleStore<2>& ps) {
    double p = 0;
    for (std::size_t i = 0; i < ps.n; ++i)
      if (!ps.boundary[i]) p += ps.m[i] * ps.v[i][0];
    return p;
  };
  TempDir d1("free_slip"), d2("no_slip");
  const auto free_slip = run_snapshots<2>(
      parse_scene(rubber_block("shear_modulus = 0.22", "", wall + "wall_slip = \"free_slip\"\nwall_normal = [0.0, 1.0]\n",
                               "0.05, 0.0"),
                  "t.toml"),
      d1);
  const auto no_slip = run_snapshots<2>(
      parse_scene(rubber_block("shear_modulus = 0.22", "", wall + "wall_slip = \"no_slip\"\n", "0.05, 0.0"), "t.toml"), d2);
  const double p0 = px(free_slip.front());
  EXPECT_NEAR(px(free_slip.back()), p0, 1e-12 * std::fabs(p0));
  EXPECT_LT(px(no_slip.back()), 0.99 * p0);
}

// ---- Coulomb walls (issue #12 item 5; physics/wall_friction.hpp) ------------

// A 1 x 0.5 elastic block (rho = 1, K = 100 so c = 10, G = 30) on a Coulomb
// floor at y = 0 (normal +y, friction mu), under the uniform acceleration
// `gravity`, starting with velocity (vx, 0). A tilted gravity
// (g sin theta, -g cos theta) is the block on an incline of angle theta.
std::string block_on_floor(double gx, double gy, double mu, double vx, double end_time) {
  std::ostringstream s;
  s.precision(17);
  s << "[simulation]\ndimension = 2\nend_time = " << end_time << "\nintegrator = \"leapfrog\"\n"
    << "gravity = [" << gx << ", " << gy << "]\n"
    << "[materials.block]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 100.0, n = 1.0 }\nshear_modulus = 30.0\n"
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"block\"\nmin = [0.0, 0.0]\nmax = [1.0, 0.5]\n"
       "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nvelocity = [" << vx << ", 0.0]\n"
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"block\"\nmin = [-1.0, -0.3]\nmax = [3.0, 0.0]\n"
       "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nboundary = \"fixed\"\n"
       "wall_slip = \"coulomb\"\nwall_normal = [0.0, 1.0]\nwall_friction = " << mu << "\n"
    << "[output]\ninterval = " << end_time / 4 << "\n";
  return s.str();
}

struct Momentum {
  double M = 0, px = 0, py = 0;
};
Momentum free_momentum(const ParticleStore<2>& ps) {
  Momentum out;
  for (std::size_t i = 0; i < ps.n; ++i) {
    if (ps.boundary[i]) continue;
    out.M += ps.m[i];
    out.px += ps.m[i] * ps.v[i][0];
    out.py += ps.m[i] * ps.v[i][1];
  }
  return out;
}

TEST(BodyForceAndWallScene, CoulombWallKeysAreValidated) {
  const std::string wall = "[[bodies]]\nshape = \"box\"\nmaterial = \"rubber\"\nmin = [0.0, -0.3]\nmax = [1.0, 0.0]\n"
                           "spacing = 0.1\ndensity = 1.0\ninternal_energy = 0.0\nboundary = \"fixed\"\n";
  const std::string coulomb = "wall_slip = \"coulomb\"\nwall_normal = [0.0, 1.0]\n";
  const Scene w = parse_scene(rubber_block("", "", wall + coulomb + "wall_friction = 0.36\n"), "t.toml");
  EXPECT_EQ(w.bodies[1].wall_slip, WallSlip::Coulomb);
  EXPECT_DOUBLE_EQ(w.bodies[1].wall_friction, 0.36);
  auto names = [&](const std::string& extra, const std::string& key) {
    const std::string e = parse_error(rubber_block("", "", extra));
    EXPECT_NE(e.find(key), std::string::npos) << e;
  };
  names(wall + coulomb, "bodies[1].wall_friction");                                  // missing
  names(wall + coulomb + "wall_friction = 0.0\n", "bodies[1].wall_friction");        // use free_slip
  names(wall + coulomb + "wall_friction = -0.2\n", "bodies[1].wall_friction");       // negative
  names(wall + coulomb + "wall_friction = nan\n", "bodies[1].wall_friction");        // NaN
  names(wall + "wall_slip = \"coulomb\"\nwall_friction = 0.3\n", "bodies[1].wall_normal");
  names(wall + "wall_slip = \"free_slip\"\nwall_normal = [0.0, 1.0]\nwall_friction = 0.3\n", "bodies[1].wall_friction");
  names(wall + "wall_friction = 0.3\n", "bodies[1].wall_friction");  // a no-slip wall has none
  names(wall.substr(0, wall.find("boundary")) + "wall_friction = 0.3\n", "bodies[1].wall_friction");  // no wall
}

// Sliding on a Coulomb floor, Coulomb's law in aggregate: while every
// contact slides, the floor's friction is mu times its push, so the
// momentum it removes along the floor is mu times the momentum its push
// adds normal to it: P_x(t) - P_x(0) = -mu (P_y(t) - P_y(0) + M g t) (the
// block's internal forces cancel pairwise), to round-off. The push
// averages the weight, so the block decelerates at mu g (Coulomb's kinetic
// friction) up to its vertical bounce, which is small for this stiff block.
TEST(WallRun, CoulombFloorBrakesASlidingBlockAtMuG) {
  const double g = 1.0, mu = 0.3, v0 = 1.0, T = 1.0;
  TempDir d("coulomb_slide");
  const auto snaps = run_snapshots<2>(parse_scene(block_on_floor(0.0, -g, mu, v0, T), "t.toml"), d);
  ASSERT_EQ(snaps.size(), 5u);
  const Momentum m0 = free_momentum(snaps.front());
  for (std::size_t k = 1; k < snaps.size(); ++k) {
    const double t = T * double(k) / 4;
    const Momentum m = free_momentum(snaps[k]);
    EXPECT_NEAR(m.px - m0.px, -mu * (m.py - m0.py + m0.M * g * t), 1e-12 * m0.M) << "t = " << t;
  }
  const Momentum mT = free_momentum(snaps.back());
  const double bounce = std::fabs(mT.py - m0.py) / (m0.M * g * T);  // the push's departure from the weight
  EXPECT_LT(bounce, 0.05);
  const double decel = (m0.px - mT.px) / (m0.M * T);
  EXPECT_NEAR(decel, mu * g, mu * g * (bounce + 1e-9));
  EXPECT_GT(mT.px / m0.M, 0.5 * v0);  // still sliding
  // the floor holds the block at every output: no particle at or below y = 0
  for (const auto& ps : snaps) {
    for (std::size_t i = 0; i < ps.n; ++i) {
      if (!ps.boundary[i]) {
        EXPECT_GT(ps.x[i][1], 0.0);
      }
    }
  }
}

// On an incline (gravity tilted by theta). Above the friction angle
// (tan theta = 0.5 > mu = 0.3), launched down the slope so that every
// contact slides from the start, the block obeys Coulomb's law in aggregate
// as above, v_x(t) = v0 + g sin(theta) t - mu (g cos(theta) t + v_y(t)), to
// round-off, so it slides with g (sin theta - mu cos theta) up to its
// bounce. Below it (tan theta = 0.2), from rest, it holds. It slips a
// little while it lands (it starts stress-free, so the floor's push, and
// with it the friction, builds up over the first ~0.1 s: measured 2.4e-3
// in the first 0.5 s); from then on it stays, where a regularised Coulomb
// law (viscous below a stick speed) let it creep on at ~1e-2.
TEST(WallRun, CoulombFloorHoldsBelowTheFrictionAngleAndSlidesAbove) {
  const double g = 1.0, mu = 0.3;
  auto cm_x = [](const ParticleStore<2>& ps) {
    double mx = 0, m = 0;
    for (std::size_t i = 0; i < ps.n; ++i)
      if (!ps.boundary[i]) mx += ps.m[i] * ps.x[i][0], m += ps.m[i];
    return mx / m;
  };
  auto run = [&](double tan_theta, double v0, double T, const std::string& name) {
    const double theta = std::atan(tan_theta);
    TempDir d(name);
    return run_snapshots<2>(
        parse_scene(block_on_floor(g * std::sin(theta), -g * std::cos(theta), mu, v0, T), "t.toml"), d);
  };
  {
    const double theta = std::atan(0.5), v0 = 0.5, T = 1.0;
    const Momentum m = free_momentum(run(0.5, v0, T, "incline_slides").back());
    const double vx = m.px / m.M, vy = m.py / m.M;
    EXPECT_NEAR(vx, v0 + g * std::sin(theta) * T - mu * (g * std::cos(theta) * T + vy), 1e-12);
    const double bounce = std::fabs(vy) / (g * std::cos(theta) * T);
    EXPECT_LT(bounce, 0.05);
    EXPECT_NEAR(vx - v0, g * (std::sin(theta) - mu * std::cos(theta)) * T,
                mu * g * std::cos(theta) * T * (bounce + 1e-9));
  }
  {
    const double theta = std::atan(0.2), T = 2.0;
    const auto snaps = run(0.2, 0.0, T, "incline_holds");  // outputs at 0, 0.5, 1, 1.5, 2
    ASSERT_EQ(snaps.size(), 5u);
    const double landed = cm_x(snaps[1]) - cm_x(snaps[0]);
    const double after = cm_x(snaps.back()) - cm_x(snaps[1]);
    const double frictionless = 0.5 * g * std::sin(theta) * (T * T - 0.25);  // from t = 0.5 to T
    std::printf("incline below the friction angle: moved %.3e while landing, %.3e after (frictionless %.3e)\n",
                landed, after, frictionless);
    // landing: the free slide of the first ~0.15 s, a small part of the frictionless 0.5 s
    EXPECT_LT(std::fabs(landed), 0.25 * 0.5 * g * std::sin(theta) * 0.25);
    EXPECT_LT(std::fabs(after), 1e-3 * frictionless);
  }
}

// Adami, Hu & Adams 2012's hydrostatic tank: a liquid column (Murnaghan,
// rho0 = K0 = 1, so c = 1) in a tank whose floor and side walls are
// extrapolated boundary particles, under g = 0.1, relaxed by damping. The
// walls carry the column: it comes to rest (no particle through a wall) with
// the hydrostatic pressure rho g (H - y), and the wall particles take the
// pressure at their own depth (the extrapolation adds the hydrostatic
// increase across the wall). The 5 % bound is the SPH discretisation's, at
// 10 particles over the depth with the free surface's kernel truncation,
// not a property of the wall formula (which is exact for a linear field:
// test_wall_extrapolation).
TEST(WallRun, ExtrapolatedTankHoldsAHydrostaticColumn) {
  const double g = 0.1, H = 0.5, dx = 0.05;
  auto wall = [&](double x0, double y0, double x1, double y1) {
    std::ostringstream s;
    s << "[[bodies]]\nshape = \"box\"\nmaterial = \"liquid\"\nmin = [" << x0 << ", " << y0 << "]\nmax = [" << x1 << ", "
      << y1 << "]\nspacing = " << dx << "\ndensity = 1.0\ninternal_energy = 0.0\nboundary = \"fixed\"\n"
      << "boundary_state = \"extrapolated\"\n";
    return s.str();
  };
  std::ostringstream s;
  s << "[simulation]\ndimension = 2\nend_time = 6.0\nintegrator = \"leapfrog\"\ndensity = \"continuity\"\n"
    << "gravity = [0.0, " << -g << "]\ndamping_time = 0.3\ndamping_end = 6.0\n"
    << "[materials.liquid]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1.0, K0 = 1.0, n = 1.0 }\n"
    << "[[bodies]]\nshape = \"box\"\nmaterial = \"liquid\"\nmin = [0.0, 0.0]\nmax = [0.5, " << H << "]\nspacing = " << dx
    << "\ndensity = 1.0\ninternal_energy = 0.0\n"
    << wall(-0.15, -0.15, 0.65, 0.0) << wall(-0.15, 0.0, 0.0, 0.7) << wall(0.5, 0.0, 0.65, 0.7)
    << "[output]\ninterval = 3.0\n";
  TempDir d("tank");
  const auto snaps = run_snapshots<2>(parse_scene(s.str(), "t.toml"), d);
  const ParticleStore<2>& last = snaps.back();
  // the free surface after the column's compression: the top of the free particles
  double top = 0, vmax = 0;
  for (std::size_t i = 0; i < last.n; ++i)
    if (!last.boundary[i]) {
      top = std::max(top, double(last.x[i][1]) + dx / 2);
      vmax = std::max(vmax, double(norm(last.v[i])));
    }
  EXPECT_LT(vmax, 1e-3);  // at rest: far below the free-fall speed sqrt(g H) = 0.22
  double err_free = 0, err_wall = 0;
  int n_free = 0, n_wall = 0;
  for (std::size_t i = 0; i < last.n; ++i) {
    const double x = last.x[i][0], y = last.x[i][1];
    if (!last.boundary[i]) {
      EXPECT_GT(y, 0.0);
      EXPECT_GT(x, 0.0);
      EXPECT_LT(x, 0.5);
      if (y < 0.25) {  // the lower half, away from the free surface's truncated kernels
        err_free = std::max(err_free, std::fabs(double(last.p[i]) - g * (top - y)) / (g * H));
        ++n_free;
      }
    } else if (y > -0.06 && x > 0.1 && x < 0.4) {  // the floor's top row under the column
      err_wall = std::max(err_wall, std::fabs(double(last.p[i]) - g * (top - y)) / (g * H));
      ++n_wall;
    }
  }
  std::printf("tank: max |v| %.3g, pressure error (of rho g H) liquid %.3g, floor %.3g\n", vmax, err_free, err_wall);
  ASSERT_GT(n_free, 20);
  ASSERT_GT(n_wall, 4);
  EXPECT_LT(err_free, 0.05);
  EXPECT_LT(err_wall, 0.05);
}

// simulation.shifting (particle shifting, physics/particle_shifting.hpp):
// default off, validated, and a body at rest is never shifted.
TEST(ShiftingScene, KeyIsValidatedAndABodyAtRestStaysPut) {
  EXPECT_EQ(parse_scene(rubber_block(""), "t.toml").simulation.shifting, 0.0);
  EXPECT_EQ(parse_scene(rubber_block("", "shifting = 1.0"), "t.toml").simulation.shifting, 1.0);
  EXPECT_NE(parse_error(rubber_block("", "shifting = -1.0")).find("simulation.shifting"), std::string::npos);
  EXPECT_NE(parse_error(rubber_block("", "shifting = 20.0")).find("simulation.shifting"), std::string::npos);
  TempDir d("shift_rest");
  const auto snaps =
      run_snapshots<2>(parse_scene(rubber_block("shear_modulus = 0.22", "shifting = 2.0"), "t.toml"), d);
  std::vector<double> first, last;
  for (const auto* ps : {&snaps.front(), &snaps.back()})
    for (std::size_t i = 0; i < ps->n; ++i) (ps == &snaps.front() ? first : last).push_back(ps->x[i][0] + 7 * ps->x[i][1]);
  std::sort(first.begin(), first.end());
  std::sort(last.begin(), last.end());
  EXPECT_EQ(first, last);
}

// Issue #50 item 5: the adaptive RK2 collapsed in a porous impact (a basalt
// disc at 4.4 km/s into porous_basalt: 2e-11 s steps from first contact,
// 1/3000 of the Courant step) because the p-alpha rate, and J08's factor
// on the deviatoric rate that follows it, switch at the loading envelope
// and made the embedded error estimate first order (rk2_adaptive.hpp). The
// same impact into non-porous basalt runs at ~1/5 of its Courant step. The
// bound here is a regression bound between those measurements, not a
// physical one: the porous run may take at most 20 times the steps of its
// non-porous twin (measured: 83 against 42 steps after the fix, 14521
// against 42 before).
TEST(PorousRun, AdaptiveStepDoesNotCollapseInAPorousImpact) {
  auto impact = [](bool porous) {
    std::ostringstream s;
    s << "[simulation]\ndimension = 2\nend_time = 3e-7\nintegrator = \"rk2_adaptive\"\ndensity = \"continuity\"\n"
      << "[materials.target]\nlibrary = \"" << (porous ? "porous_basalt" : "basalt") << "\"\n"
      << (porous ? "" : "shear_modulus = 2.27e10\n")
      << "[materials.projectile]\nlibrary = \"basalt\"\nshear_modulus = 2.27e10\n"
      << "[[bodies]]\nshape = \"box\"\nmaterial = \"target\"\nmin = [-0.02, -0.02]\nmax = [0.02, 0.0]\n"
      << "spacing = 0.001\ndensity = " << (porous ? "2160.0" : "2700.0") << "\ninternal_energy = 0.0\n"
      << "[[bodies]]\nshape = \"sphere\"\nmaterial = \"projectile\"\ncenter = [0.0, 0.0035]\nradius = 0.003\n"
      << "spacing = 0.001\ndensity = 2700.0\ninternal_energy = 0.0\nvelocity = [0.0, -4400.0]\n"
      << "[output]\ninterval = 3e-7\n";
    return s.str();
  };
  auto steps = [&](bool porous) {
    TempDir d(porous ? "porous_impact" : "solid_impact");
    RunOptions opt;
    opt.out_dir = d.path.string();
    opt.quiet = true;
    return run_scene(parse_scene(impact(porous), "t.toml"), opt).steps;
  };
  const auto solid = steps(false), porous = steps(true);
  std::printf("rk2_adaptive over 0.3 us of the impact: %lld steps into porous_basalt, %lld into basalt\n",
              static_cast<long long>(porous), static_cast<long long>(solid));
  EXPECT_LT(porous, 20 * solid) << "porous " << porous << " steps, non-porous " << solid;
}
