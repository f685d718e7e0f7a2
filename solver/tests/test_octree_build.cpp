// The level-synchronous octree build (gravity/octree_build.hpp), the form a
// GPU runs, against the recursive CPU build (rubble::Octree): the same
// depth-first node array, node by node and bit for bit (both call the same
// per-node functions in the same order of operations), on uniform,
// clustered and coincident particle sets and for several leaf sizes.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "rubble/gravity/octree.hpp"
#include "rubble/gravity/octree_build.hpp"
#include "rubble/neighbors/morton.hpp"

using namespace rubble;

namespace {

struct Set {
  std::vector<Vec<3>> x;
  std::vector<Real> m, eps;
};

Set uniform_set(std::size_t n, unsigned seed) {
  Set s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<Real> u(-1, 1), w(0.5, 1.5);
  for (std::size_t i = 0; i < n; ++i) {
    s.x.push_back(Vec<3>{u(rng), u(rng), u(rng)});
    s.m.push_back(w(rng));
    s.eps.push_back(Real(0.01) * w(rng));
  }
  return s;
}

void expect_same_tree(const Set& s, const OctreeOptions& opt) {
  Octree tree(opt);
  tree.build(s.x.data(), s.m.data(), s.eps.data(), s.x.size());
  const std::size_t n = s.x.size();
  std::vector<std::uint64_t> keys(n);
  std::vector<Vec<3>> xs(n);
  std::vector<Real> ms(n), es(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = tree.order()[k];
    xs[k] = s.x[i];
    ms[k] = s.m[i];
    es[k] = s.eps[i];
    keys[k] = morton_key<3>(xs[k], tree.key_box());
  }
  const std::vector<OctreeNode> levels =
      octree_build_by_levels(keys.data(), xs.data(), ms.data(), es.data(), std::uint32_t(n), tree.key_box(), opt.theta,
                             opt.leaf_size);
  const std::vector<OctreeNode>& ref = tree.nodes();
  ASSERT_EQ(levels.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const OctreeNode &a = levels[i], &b = ref[i];
    ASSERT_EQ(a.begin, b.begin) << "node " << i;
    ASSERT_EQ(a.end, b.end) << "node " << i;
    ASSERT_EQ(a.level, b.level) << "node " << i;
    ASSERT_EQ(a.leaf, b.leaf) << "node " << i;
    ASSERT_EQ(a.skip, b.skip) << "node " << i;
    EXPECT_EQ(a.mass, b.mass) << "node " << i;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.com[k], b.com[k]) << "node " << i;
    for (int k = 0; k < 6; ++k) EXPECT_EQ(a.quad[k], b.quad[k]) << "node " << i;
    EXPECT_EQ(a.b_max, b.b_max) << "node " << i;
    EXPECT_EQ(a.eps_max, b.eps_max) << "node " << i;
    EXPECT_EQ(a.open_radius, b.open_radius) << "node " << i;
  }
}

}  // namespace

TEST(OctreeBuildByLevels, UniformSetMatchesTheRecursiveBuild) {
  const Set s = uniform_set(5000, 1);
  for (const std::uint32_t leaf : {1u, 8u, 32u}) {
    OctreeOptions opt;
    opt.leaf_size = leaf;
    opt.theta = Real(0.5);
    expect_same_tree(s, opt);
  }
}

TEST(OctreeBuildByLevels, ClusteredAndCoincidentParticles) {
  Set s = uniform_set(1000, 2);
  for (auto& p : s.x) p = Real(1e-4) * p;  // a tight clump ...
  Set far = uniform_set(300, 3);
  for (std::size_t i = 0; i < far.x.size(); ++i) {  // ... a distant one ...
    s.x.push_back(far.x[i] + Vec<3>{50, -20, 7});
    s.m.push_back(far.m[i]);
    s.eps.push_back(far.eps[i]);
  }
  for (int i = 0; i < 40; ++i) {  // ... and 40 particles at one point (finest-level leaf)
    s.x.push_back(Vec<3>{3, 3, 3});
    s.m.push_back(1);
    s.eps.push_back(0);
  }
  OctreeOptions opt;
  opt.leaf_size = 4;
  opt.theta = Real(0.7);
  expect_same_tree(s, opt);
}

TEST(OctreeBuildByLevels, ThetaZeroAndTinySets) {
  OctreeOptions opt;
  opt.theta = 0;  // infinite opening radii
  expect_same_tree(uniform_set(200, 4), opt);
  expect_same_tree(uniform_set(1, 5), opt);
  expect_same_tree(uniform_set(2, 6), opt);
}
