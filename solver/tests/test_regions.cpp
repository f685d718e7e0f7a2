// Regions (issue #54 item 3; core/region.hpp): the containment test of
// every shape, bodies composed by `add` and `subtract` and filled by one
// lattice, polygon and cylinder bodies, and [[regions]] measuring the mass
// inside them (regions.csv), also following a turning tool.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "rubble/core/region.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/run.hpp"
#include "rubble/scene/initial_conditions.hpp"
#include "rubble/scene/scene_parser.hpp"
#include "conserved_column.hpp"
#include "scene_error.hpp"

using namespace rubble;
using rubble::test::csv_column;
using rubble::test::parse_error;

namespace {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("rubble_rg_" + std::to_string(getpid()) + "_" + name)) {
    std::filesystem::remove_all(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
};

const char* kWater = "[materials.water]\neos = \"murnaghan\"\nmurnaghan = { rho0 = 1000.0, K0 = 2.0e5, n = 7.0 }\n";

std::string head2() { return std::string("[simulation]\ndimension = 2\nend_time = 1.0\n") + kWater; }

template <int D>
ParticleStore<D> generated(const Scene& scene, std::vector<std::int64_t>* first = nullptr) {
  ParticleStore<D> ps;
  auto f = generate_bodies<D>(scene, smoothing_factor(scene.simulation), features_of_scene(scene), ps);
  if (first) *first = f;
  return ps;
}

bool inside2(const Region& r, double x, double y) {
  const double p[3] = {x, y, 0};
  return r.contains<2>(p);
}

}  // namespace

TEST(Region, EveryShapeContainsWhatItShould) {
  Region box;
  box.min[0] = 0, box.min[1] = 0, box.max[0] = 1, box.max[1] = 2;
  EXPECT_TRUE(inside2(box, 0.5, 1.9));
  EXPECT_TRUE(inside2(box, 0.0, 0.0));   // min is inside
  EXPECT_FALSE(inside2(box, 1.0, 0.5));  // max is not
  Region ring;
  ring.shape = RegionShape::Ring;
  ring.center[0] = 1, ring.radius = 1, ring.inner_radius = 0.5;
  EXPECT_TRUE(inside2(ring, 1.7, 0.0));
  EXPECT_FALSE(inside2(ring, 1.2, 0.0));
  EXPECT_FALSE(inside2(ring, 2.1, 0.0));
  // an L-shaped (concave) polygon: the notch is outside
  Region L;
  L.shape = RegionShape::Polygon;
  const double v[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  L.vertex_count = 6;
  for (int i = 0; i < 6; ++i) L.vertices[i][0] = v[i][0], L.vertices[i][1] = v[i][1];
  EXPECT_TRUE(inside2(L, 0.5, 1.5));
  EXPECT_TRUE(inside2(L, 1.5, 0.5));
  EXPECT_FALSE(inside2(L, 1.5, 1.5));
  EXPECT_FALSE(inside2(L, -0.1, 0.5));
  region_bounds<2>(L);
  EXPECT_EQ(L.max[0], 2.0);
  EXPECT_EQ(L.max[1], 2.0);
  // a cylinder along (1, 1, 0)/sqrt 2 through the origin, radius 0.5, length 2
  Region c;
  c.shape = RegionShape::Cylinder;
  c.radius = 0.5, c.length = 2;
  c.axis[0] = c.axis[1] = 1 / std::sqrt(2.0), c.axis[2] = 0;
  const double on_axis[3] = {0.6, 0.6, 0.0}, off_end[3] = {0.8, 0.8, 0.0}, off_side[3] = {0.4, -0.4, 0.0},
               near_side[3] = {0.0, 0.0, 0.45};
  EXPECT_TRUE(c.contains<3>(on_axis));     // t = 0.85 < 1
  EXPECT_FALSE(c.contains<3>(off_end));    // t = 1.13 > 1
  EXPECT_FALSE(c.contains<3>(off_side));   // 0.57 from the axis
  EXPECT_TRUE(c.contains<3>(near_side));   // 0.45 from the axis
}

// A bed with a tool's place cut out (subtract), a wall added to it (add):
// one lattice, no point in the cut, the added points on the same lattice.
TEST(Region, BodiesComposeByAddAndSubtractOnOneLattice) {
  const std::string text = head2() +
                           "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [1.0, 0.5]\n"
                           "spacing = 0.05\ndensity = 1000.0\npressure = 0.0\n"
                           "subtract = [{ shape = \"box\", min = [0.4, 0.3], max = [0.6, 0.5] }]\n"
                           "add = [{ shape = \"box\", min = [-0.15, 0.0], max = [0.0, 0.8] }]\n";
  const ParticleStore<2> ps = generated<2>(parse_scene(text, "bed.toml"));
  // 20 x 10 cells, less the 4 x 4 cut, plus the 3 x 16 wall
  EXPECT_EQ(ps.n, std::size_t(20 * 10 - 4 * 4 + 3 * 16));
  for (std::size_t i = 0; i < ps.n; ++i) {
    const double x = ps.x[i][0], y = ps.x[i][1];
    EXPECT_FALSE(x > 0.4 && x < 0.6 && y > 0.3) << x << ", " << y;
    // every point on the lattice of cell centres (i + 1/2) 0.05
    EXPECT_NEAR(std::fmod(x / 0.05 + 100.5, 1.0), 0.0, 1e-9);
    EXPECT_NEAR(std::fmod(y / 0.05 + 100.5, 1.0), 0.0, 1e-9);
  }
}

// A polygon body holds the lattice points inside it: a right triangle of
// legs 1 m on a 0.02 m lattice, 1250 cells of area, within its perimeter's
// cells (3.4 m / 0.02 m = 171 cells).
TEST(Region, APolygonBodyFillsItsArea) {
  const std::string text = head2() +
                           "[[bodies]]\nshape = \"polygon\"\nmaterial = \"water\"\nvertices = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]\n"
                           "spacing = 0.02\ndensity = 1000.0\npressure = 0.0\n";
  const ParticleStore<2> ps = generated<2>(parse_scene(text, "tri.toml"));
  EXPECT_NEAR(double(ps.n), 0.5 / (0.02 * 0.02), 171.0);
  // (a point on the edge may fall either way: the lattice has some on it)
  for (std::size_t i = 0; i < ps.n; ++i) EXPECT_LE(ps.x[i][0] + ps.x[i][1], 1.0 + 1e-12);
}

TEST(Region, ACylinderBodyFillsItsVolume) {
  const std::string text = std::string("[simulation]\ndimension = 3\nend_time = 1.0\n") + kWater +
                           "[[bodies]]\nshape = \"cylinder\"\nmaterial = \"water\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.2\n"
                           "length = 0.6\naxis = [1.0, 0.0, 0.0]\nspacing = 0.02\ndensity = 1000.0\npressure = 0.0\n";
  const ParticleStore<3> ps = generated<3>(parse_scene(text, "cyl.toml"));
  const double cells = M_PI * 0.2 * 0.2 * 0.6 / (0.02 * 0.02 * 0.02);  // 3770
  // within one layer of cells over its surface (2 pi r L + 2 pi r^2) / dx^2 = 2200
  EXPECT_NEAR(double(ps.n), cells, 0.5 * 2200);
  for (std::size_t i = 0; i < ps.n; ++i) {
    EXPECT_LT(std::fabs(ps.x[i][0]), 0.3);
    EXPECT_LT(ps.x[i][1] * ps.x[i][1] + ps.x[i][2] * ps.x[i][2], 0.04);
  }
}

// [[regions]]: the water in a box region, and a region that follows a tool
// turning a quarter turn: given at t = 0 where the water will be in the
// tool's turned frame, it holds the water at the end; given where the
// water is, it holds nothing then.
TEST(Region, MeasuringRegionsCountMassAndFollowTools) {
  TempDir dir("measure");
  const std::string text =
      head2() +
      "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [2.0, 0.0]\nmax = [2.2, 0.2]\nspacing = 0.05\n"
      "density = 1000.0\npressure = 0.0\n"
      "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [-0.1, -0.1]\nmax = [0.1, 0.1]\nspacing = 0.05\n"
      "density = 1000.0\npressure = 0.0\nboundary = \"moving\"\nangular_velocity = 1.5707963267948966\n"
      "rotation_center = [0.0, 0.0]\n"
      "[[regions]]\nname = \"fixed\"\nshape = \"box\"\nmin = [1.9, -0.1]\nmax = [2.3, 0.3]\n"
      "[[regions]]\nname = \"there_at_start\"\nshape = \"box\"\nmin = [1.9, -0.1]\nmax = [2.3, 0.3]\nfollow = 1\n"
      "[[regions]]\nname = \"there_at_end\"\nshape = \"box\"\nmin = [-0.1, -2.3]\nmax = [0.3, -1.9]\nfollow = 1\n"
      "[output]\nsnapshots = false\n";
  RunOptions opt;
  opt.out_dir = dir.path.string();
  opt.quiet = true;
  run_scene(parse_scene(text, "measure.toml"), opt);
  const auto csv = dir.path / "regions.csv";
  const std::vector<double> mass = csv_column(csv, "mass"), water = csv_column(csv, "mass_water");
  const std::vector<double> count = csv_column(csv, "count");
  ASSERT_GE(mass.size(), 6u);
  const double block = 16 * 1000.0 * 0.05 * 0.05;  // 4 x 4 particles of 2.5 kg/m
  // rows: three per logged time, in the order of [[regions]]
  EXPECT_DOUBLE_EQ(mass[0], block);
  EXPECT_DOUBLE_EQ(water[0], block);
  EXPECT_EQ(count[0], 16);
  EXPECT_DOUBLE_EQ(mass[1], block);  // the tool has not turned yet
  EXPECT_EQ(mass[2], 0.0);
  const std::size_t end = mass.size() - 3;
  EXPECT_DOUBLE_EQ(mass[end], block);
  EXPECT_EQ(mass[end + 1], 0.0);
  EXPECT_DOUBLE_EQ(mass[end + 2], block);
}

TEST(Region, SceneErrorsNameTheKey) {
  auto has = [](const std::string& msg, const std::string& part) { return msg.find(part) != std::string::npos; };
  const std::string body = "[[bodies]]\nshape = \"box\"\nmaterial = \"water\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n"
                           "spacing = 0.1\ndensity = 1000.0\npressure = 0.0\n";
  std::string e = parse_error(head2() + "[[bodies]]\nshape = \"polygon\"\nmaterial = \"water\"\nvertices = [[0.0, 0.0], "
                                        "[1.0, 0.0]]\nspacing = 0.1\ndensity = 1000.0\npressure = 0.0\n");
  EXPECT_TRUE(has(e, "bodies[0].vertices")) << e;
  e = parse_error(head2() + "[[bodies]]\nshape = \"polygon\"\nmaterial = \"water\"\nvertices = [[0.0, 0.0], "
                            "[1.0, 1.0], [2.0, 2.0]]\nspacing = 0.1\ndensity = 1000.0\npressure = 0.0\n");
  EXPECT_TRUE(has(e, "no area")) << e;
  e = parse_error(head2() + "[[bodies]]\nshape = \"cylinder\"\nmaterial = \"water\"\ncenter = [0.0, 0.0]\nradius = 1.0\n"
                            "length = 1.0\nspacing = 0.1\ndensity = 1000.0\npressure = 0.0\n");
  EXPECT_TRUE(has(e, "bodies[0].shape") && has(e, "3-D")) << e;
  e = parse_error(head2() + body + "subtract = [{ shape = \"box\", min = [0.0, 0.0], maximum = [1.0, 1.0] }]\n");
  EXPECT_TRUE(has(e, "bodies[0].subtract[0]")) << e;
  e = parse_error(head2() + body + "[[regions]]\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n");
  EXPECT_TRUE(has(e, "regions[0].name")) << e;
  e = parse_error(head2() + body + "[[regions]]\nname = \"a\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n" +
                  "[[regions]]\nname = \"a\"\nshape = \"sphere\"\ncenter = [0.0, 0.0]\nradius = 1.0\n");
  EXPECT_TRUE(has(e, "regions[1].name")) << e;
  e = parse_error(head2() + body + "[[regions]]\nname = \"a\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n"
                                   "follow = 0\n");
  EXPECT_TRUE(has(e, "regions[0].follow") && has(e, "rigid tool")) << e;
}
