// Unit tests of the neighbour search (rubble/neighbors/): Morton keys, the
// spatial order, and CellList against an O(n^2) brute force.
//
// The brute force applies the criterion of cell_list.hpp literally,
//   b in N(a)  iff  a != b and |separation(x_a, x_b)|^2 < max(H_a, H_b)^2,
// with the same Box::separation and the same arithmetic, so the neighbour
// sets must be IDENTICAL, not merely close. Sets are chosen to stress what
// a cell search gets wrong: H varying 10x between particles, strong
// clustering, periodic wrap in all or some axes, periodic boxes only ~2 H
// across (where a particle could be found through two images), duplicate
// positions, unsorted input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "rubble/neighbors/cell_list.hpp"
#include "rubble/neighbors/morton.hpp"
#include "rubble/neighbors/spatial_order.hpp"

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace {

using namespace rubble;
using Rng = std::mt19937_64;

// ---- helpers ------------------------------------------------------------------

// Bit k of `periodic_axes` makes axis k periodic.
template <int D>
Box<D> make_box(Real lo, Real hi, unsigned periodic_axes) {
  Box<D> b;
  for (int k = 0; k < D; ++k) {
    b.lo[k] = lo;
    b.hi[k] = hi;
    b.periodic[k] = (periodic_axes >> k) & 1u;
  }
  return b;
}

template <int D>
struct ParticleSet {
  std::vector<Vec<D>> x;
  std::vector<Real> H;
  Box<D> box;
};

// Uniform in [lo, hi) per axis (a draw rounded up to hi goes back to lo).
template <int D>
Vec<D> uniform_point(const Box<D>& box, Rng& rng) {
  Vec<D> p;
  for (int k = 0; k < D; ++k) {
    std::uniform_real_distribution<Real> u(box.lo[k], box.hi[k]);
    p[k] = u(rng);
    if (p[k] >= box.hi[k]) p[k] = box.lo[k];
  }
  return p;
}

// Map into [lo, hi) on periodic axes, exactly as a driver would.
template <int D>
Vec<D> wrap_strict(const Box<D>& box, Vec<D> p) {
  p = box.wrap(p);
  for (int k = 0; k < D; ++k)
    if (box.periodic[k] && p[k] >= box.hi[k]) p[k] = box.lo[k];
  return p;
}

// H = base * 10^u, u uniform in [0, 1): a factor 10 between particles.
Real varied_h(Real base, Rng& rng) {
  std::uniform_real_distribution<Real> u(0, 1);
  return base * std::pow(Real(10), u(rng));
}

// Mean spacing of n particles spread over the box.
template <int D>
Real spacing(const Box<D>& box, std::size_t n) {
  Real volume = 1;
  for (int k = 0; k < D; ++k) volume *= box.length(k);
  return std::pow(volume / Real(n), Real(1) / Real(D));
}

// H / mean spacing for the uniform sets: some tens of neighbours in each D.
template <int D>
constexpr Real kHOverSpacing = D == 1 ? 1.5 : (D == 2 ? 0.7 : 0.4);

template <int D>
ParticleSet<D> uniform_set(std::size_t n, const Box<D>& box, Real h_over_spacing, std::uint64_t seed) {
  Rng rng(seed);
  ParticleSet<D> s{{}, {}, box};
  const Real h0 = h_over_spacing * spacing(box, n);
  for (std::size_t i = 0; i < n; ++i) {
    s.x.push_back(uniform_point(box, rng));
    s.H.push_back(varied_h(h0, rng));
  }
  return s;
}

// 90% of the particles in a Gaussian blob of width 1e-3 of the box, 10% in
// a uniform background; H follows the local spacing (as SPH would set it)
// times a random factor up to 10. On periodic axes the blob sits on the
// boundary, so it is cut in two by the wrap.
template <int D>
ParticleSet<D> clustered_set(std::size_t n, const Box<D>& box, std::uint64_t seed) {
  Rng rng(seed);
  ParticleSet<D> s{{}, {}, box};
  const std::size_t n_blob = n * 9 / 10, n_bg = n - n_blob;
  const Real sigma = Real(1e-3) * box.length(0);
  const Real h_blob = (D == 3 ? Real(0.8) : Real(2)) * sigma * std::pow(Real(1) / Real(n_blob), Real(1) / Real(D));
  const Real h_bg = Real(0.5) * spacing(box, n_bg);
  Real h_cap = 1e30;  // H <= L/2 on periodic axes
  for (int k = 0; k < D; ++k)
    if (box.periodic[k]) h_cap = std::min(h_cap, Real(0.49) * box.length(k));
  std::normal_distribution<Real> gauss(0, sigma);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 10 == 9) {  // background particles interleaved with the blob
      s.x.push_back(uniform_point(box, rng));
      s.H.push_back(std::min(varied_h(h_bg, rng), h_cap));
    } else {
      Vec<D> p;
      for (int k = 0; k < D; ++k) {
        const Real centre = box.periodic[k] ? box.lo[k] + Real(0.3) * sigma
                                            : box.lo[k] + Real(0.5) * box.length(k);
        p[k] = centre + gauss(rng);
      }
      s.x.push_back(wrap_strict(box, p));
      s.H.push_back(varied_h(h_blob, rng));
    }
  }
  return s;
}

// m^D points x = lo + i dx (a lattice that tiles a periodic box), with
// H = h_over_dx * dx, or alternating between two values.
template <int D>
ParticleSet<D> lattice_set(int m, const Box<D>& box, Real h_over_dx, Real h2_over_dx) {
  ParticleSet<D> s{{}, {}, box};
  std::size_t total = 1;
  for (int k = 0; k < D; ++k) total *= std::size_t(m);
  for (std::size_t i = 0; i < total; ++i) {
    Vec<D> p;
    std::size_t rest = i, parity = 0;
    for (int k = 0; k < D; ++k) {
      const std::size_t ik = rest % std::size_t(m);
      rest /= std::size_t(m);
      parity += ik;
      p[k] = box.lo[k] + Real(ik) * (box.length(k) / Real(m));
    }
    s.x.push_back(p);
    s.H.push_back((parity % 2 ? h2_over_dx : h_over_dx) * box.length(0) / Real(m));
  }
  return s;
}

// The reference: every ordered pair, the criterion written out.
template <int D>
std::vector<std::vector<std::uint32_t>> brute_force(const ParticleSet<D>& s) {
  const std::size_t n = s.x.size();
  std::vector<std::vector<std::uint32_t>> nb(n);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = 0; b < n; ++b) {
      if (a == b) continue;
      const Real r = std::max(s.H[a], s.H[b]);
      if (norm2(s.box.separation(s.x[a], s.x[b])) < r * r) nb[a].push_back(std::uint32_t(b));
    }
  return nb;
}

template <int D>
NeighborLists cell_list_neighbors(const ParticleSet<D>& s, std::uint32_t max_cell_size = 32,
                                  std::uint32_t max_group_size = 64) {
  CellList<D> cells(max_cell_size, max_group_size);
  cells.build(s.x.data(), s.H.data(), s.x.size(), s.box);
  NeighborLists nl;
  cells.find_neighbors(nl);
  return nl;
}

std::vector<std::uint32_t> list_of(const NeighborLists& nl, std::size_t i) { return nl.copy(i); }

// Every list, for comparing two searches.
std::vector<std::vector<std::uint32_t>> all_lists(const NeighborLists& nl) {
  std::vector<std::vector<std::uint32_t>> out;
  for (std::size_t i = 0; i < nl.size(); ++i) out.push_back(nl.copy(i));
  return out;
}

// One list per particle, lists strictly ascending (so no duplicates), no
// self, and the relation symmetric.
void expect_well_formed(const NeighborLists& nl, std::size_t n) {
  ASSERT_EQ(nl.size(), n);
  std::size_t bad = 0, total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto li = list_of(nl, i);
    total += li.size();
    EXPECT_EQ(nl.count(i), li.size());
    for (std::size_t j = 0; j < li.size(); ++j) {
      if (j > 0 && !(li[j - 1] < li[j])) ++bad;
      if (li[j] == i || li[j] >= n) { ++bad; continue; }
      const auto lj = list_of(nl, li[j]);
      if (!std::binary_search(lj.begin(), lj.end(), std::uint32_t(i))) ++bad;
    }
  }
  EXPECT_EQ(bad, 0u) << "unsorted, duplicate, self or one-sided entries";
  EXPECT_EQ(nl.total(), total);
}

// The central check: identical sets to the brute force. Returns the mean
// number of neighbours so callers can make sure the case is not trivial.
template <int D>
double expect_matches_brute_force(const ParticleSet<D>& s, std::uint32_t max_cell_size = 32,
                                  std::uint32_t max_group_size = 64) {
  const std::size_t n = s.x.size();
  const NeighborLists nl = cell_list_neighbors(s, max_cell_size, max_group_size);
  expect_well_formed(nl, n);
  const auto ref = brute_force(s);
  std::size_t mismatches = 0, ref_total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ref_total += ref[i].size();
    if (list_of(nl, i) == ref[i]) continue;
    if (++mismatches <= 3)
      ADD_FAILURE() << "particle " << i << ": cell list has " << nl.count(i) << " neighbours, brute force "
                    << ref[i].size();
  }
  EXPECT_EQ(mismatches, 0u) << "of " << n << " particles";
  const double mean = n ? double(ref_total) / double(n) : 0.0;
  if (std::getenv("RUBBLE_TEST_VERBOSE")) std::printf("  n = %zu, mean neighbours %.1f\n", n, mean);
  return mean;
}

// ---- Morton keys --------------------------------------------------------------

TEST(Morton, Encode1DIsTheCoordinate) {
  const std::uint32_t c[1] = {0xDEADBEEFu};
  EXPECT_EQ(morton_encode<1>(c), 0xDEADBEEFull);
}

TEST(Morton, Encode2DInterleavesXInTheLowBit) {
  auto enc = [](std::uint32_t x, std::uint32_t y) {
    const std::uint32_t c[2] = {x, y};
    return morton_encode<2>(c);
  };
  EXPECT_EQ(enc(0, 0), 0u);
  EXPECT_EQ(enc(1, 0), 1u);
  EXPECT_EQ(enc(0, 1), 2u);
  EXPECT_EQ(enc(1, 1), 3u);
  EXPECT_EQ(enc(2, 0), 4u);
  // x = 011, y = 101 -> y2 x2 y1 x1 y0 x0 = 1 0 0 1 1 1
  EXPECT_EQ(enc(3, 5), 0b100111u);
  EXPECT_EQ(enc(0xFFFFFFFFu, 0), 0x5555555555555555ull);
  EXPECT_EQ(enc(0, 0xFFFFFFFFu), 0xAAAAAAAAAAAAAAAAull);
  EXPECT_EQ(enc(0xFFFFFFFFu, 0xFFFFFFFFu), ~0ull);
  EXPECT_EQ(enc(1u << 31, 0), 1ull << 62);
}

TEST(Morton, Encode3DInterleavesXYZ) {
  auto enc = [](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    const std::uint32_t c[3] = {x, y, z};
    return morton_encode<3>(c);
  };
  EXPECT_EQ(enc(1, 0, 0), 1u);
  EXPECT_EQ(enc(0, 1, 0), 2u);
  EXPECT_EQ(enc(0, 0, 1), 4u);
  EXPECT_EQ(enc(7, 0, 0), 0b001001001u);
  // x = 101, y = 011, z = 110: groups (z y x) per bit = 101 | 110 | 011
  EXPECT_EQ(enc(5, 3, 6), 0b101110011u);
  const std::uint32_t all21 = (1u << 21) - 1;
  EXPECT_EQ(enc(all21, all21, all21), (1ull << 63) - 1);
  EXPECT_EQ(enc(1u << 20, 0, 0), 1ull << 60);
  EXPECT_EQ(enc(0, 0, 1u << 20), 1ull << 62);
  EXPECT_EQ(enc(1u << 21, 0, 0), 0u) << "bits above the 21st are ignored";
}

TEST(Morton, KeyQuantisesAtFullResolution) {
  const Box<1> b1 = make_box<1>(0, 1, 0);
  EXPECT_EQ(morton_key<1>(Vec<1>{{0}}, b1), 0u);
  EXPECT_EQ(morton_key<1>(Vec<1>{{0.5}}, b1), 1ull << 62);
  EXPECT_EQ(morton_key<1>(Vec<1>{{0.25}}, b1), 1ull << 61);
  EXPECT_EQ(morton_key<1>(Vec<1>{{1}}, b1), (1ull << 63) - 1);

  const Box<2> b2 = make_box<2>(-1, 1, 0);
  EXPECT_EQ(morton_key<2>(Vec<2>{{0, -1}}, b2), 1ull << 62);
  EXPECT_EQ(morton_key<2>(Vec<2>{{-1, 0}}, b2), 1ull << 63);
  EXPECT_EQ(morton_key<2>(Vec<2>{{0, 0}}, b2), 3ull << 62);

  const Box<3> b3 = make_box<3>(0, 8, 0);
  EXPECT_EQ(morton_key<3>(Vec<3>{{4, 0, 0}}, b3), 1ull << 60);
  EXPECT_EQ(morton_key<3>(Vec<3>{{0, 4, 0}}, b3), 1ull << 61);
  EXPECT_EQ(morton_key<3>(Vec<3>{{0, 0, 4}}, b3), 1ull << 62);
  EXPECT_EQ(morton_key<3>(Vec<3>{{2, 2, 2}}, b3), 7ull << 57);
}

TEST(Morton, KeyClampsOpenAxesAndWrapsPeriodicOnes) {
  const Box<3> open = make_box<3>(0, 1, 0);
  EXPECT_EQ(morton_key<3>(Vec<3>{{-5, -5, -5}}, open), 0u);
  EXPECT_EQ(morton_key<3>(Vec<3>{{9, 9, 9}}, open), (1ull << 63) - 1);
  const Box<3> periodic = make_box<3>(0, 1, 0b111);
  EXPECT_EQ(morton_key<3>(Vec<3>{{1.25, -0.75, 0.5}}, periodic),
            morton_key<3>(Vec<3>{{0.25, 0.25, 0.5}}, periodic));
}

// A Morton key never decreases when one coordinate grows.
TEST(Morton, KeyIsMonotoneAlongEachAxis) {
  Rng rng(7);
  const Box<3> box = make_box<3>(0, 1, 0);
  std::uniform_real_distribution<Real> u(0, 1);
  for (int trial = 0; trial < 10000; ++trial) {
    Vec<3> a{{u(rng), u(rng), u(rng)}};
    Vec<3> b = a;
    const int k = trial % 3;
    b[k] = std::max(a[k], u(rng));
    EXPECT_LE(morton_key<3>(a, box), morton_key<3>(b, box));
  }
}

// ---- spatial order ------------------------------------------------------------

template <typename T>
class SpatialOrderTest : public ::testing::Test {};
template <typename T>
class NeighborsTest : public ::testing::Test {};
using Dims = ::testing::Types<std::integral_constant<int, 1>, std::integral_constant<int, 2>,
                              std::integral_constant<int, 3>>;
struct DimName {
  template <typename T>
  static std::string GetName(int) {
    return std::to_string(T::value) + "D";
  }
};
TYPED_TEST_SUITE(SpatialOrderTest, Dims, DimName);
TYPED_TEST_SUITE(NeighborsTest, Dims, DimName);

TYPED_TEST(SpatialOrderTest, BoundingBoxEnclosesOpenAxesAndIsTheDomainOnPeriodicOnes) {
  constexpr int D = TypeParam::value;
  const Box<D> domain = make_box<D>(-3, 5, 0b001);  // x periodic, the rest open
  auto s = uniform_set<D>(500, make_box<D>(-2, 1, 0b001), 0.5, 11);
  for (auto& p : s.x) p[0] = p[0] * Real(2) + Real(1);  // x spread over [-3, 3)
  const Box<D> bb = bounding_box(s.x.data(), s.x.size(), domain);
  EXPECT_EQ(bb.lo[0], domain.lo[0]);
  EXPECT_EQ(bb.hi[0], domain.hi[0]);
  EXPECT_TRUE(bb.periodic[0]);
  for (int k = 1; k < D; ++k) {
    Real mn = s.x[0][k], mx = s.x[0][k];
    for (const auto& p : s.x) mn = std::min(mn, p[k]), mx = std::max(mx, p[k]);
    EXPECT_LT(bb.lo[k], mn);
    EXPECT_GT(bb.hi[k], mx);
    EXPECT_LT(mx - mn, bb.length(k));
    EXPECT_GT(Real(1.001) * (mx - mn), bb.length(k)) << "padding must stay small";
  }
  // All particles at one point: still a box of positive size.
  const std::vector<Vec<D>> same(10, s.x[0]);
  const Box<D> tiny = bounding_box(same.data(), same.size(), make_box<D>(0, 1, 0));
  for (int k = 0; k < D; ++k) EXPECT_GT(tiny.hi[k], tiny.lo[k]);
}

TYPED_TEST(SpatialOrderTest, SortIsAStablePermutationWithNonDecreasingKeys) {
  constexpr int D = TypeParam::value;
  auto s = uniform_set<D>(3000, make_box<D>(0, 1, 0), 0.5, 12);
  // Some exact duplicates, so equal keys occur and stability matters.
  for (std::size_t i = 0; i < 300; ++i) s.x[2000 + i] = s.x[i];
  const Box<D> bb = bounding_box(s.x.data(), s.x.size(), s.box);
  const auto perm = spatial_sort_permutation(s.x.data(), s.x.size(), bb);
  ASSERT_EQ(perm.size(), s.x.size());
  std::vector<std::uint32_t> sorted = perm;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i) << "not a permutation";
  for (std::size_t i = 1; i < perm.size(); ++i) {
    const auto k0 = morton_key<D>(s.x[perm[i - 1]], bb), k1 = morton_key<D>(s.x[perm[i]], bb);
    ASSERT_LE(k0, k1) << "keys decrease at sorted position " << i;
    if (k0 == k1) {
      ASSERT_LT(perm[i - 1], perm[i]) << "equal keys out of input order";
    }
  }
  // Sorting sorted input gives the identity.
  std::vector<Vec<D>> xs(s.x.size());
  for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = s.x[perm[i]];
  const auto again = spatial_sort_permutation(xs.data(), xs.size(), bb);
  for (std::size_t i = 0; i < again.size(); ++i) ASSERT_EQ(again[i], i);
}

// ---- neighbour search against brute force -----------------------------------

TYPED_TEST(NeighborsTest, UniformRandomOpen) {
  constexpr int D = TypeParam::value;
  const auto s = uniform_set<D>(3000, make_box<D>(-0.3, 1.7, 0), kHOverSpacing<D>, 21);
  EXPECT_GT(expect_matches_brute_force(s), 3.0);
}

TYPED_TEST(NeighborsTest, UniformRandomPeriodicAllAxes) {
  constexpr int D = TypeParam::value;
  const auto s = uniform_set<D>(3000, make_box<D>(-0.3, 1.7, (1u << D) - 1), kHOverSpacing<D>, 22);
  EXPECT_GT(expect_matches_brute_force(s), 3.0);
}

TYPED_TEST(NeighborsTest, UniformRandomPeriodicXOnly) {
  constexpr int D = TypeParam::value;
  const auto s = uniform_set<D>(3000, make_box<D>(2, 3, 0b001), kHOverSpacing<D>, 23);
  EXPECT_GT(expect_matches_brute_force(s), 3.0);
}

TYPED_TEST(NeighborsTest, UniformRandomPeriodicAllButX) {
  constexpr int D = TypeParam::value;
  if (D == 1) GTEST_SKIP() << "no axis besides x";
  const auto s = uniform_set<D>(3000, make_box<D>(0, 1, ((1u << D) - 1) & ~1u), kHOverSpacing<D>, 24);
  EXPECT_GT(expect_matches_brute_force(s), 3.0);
}

// Whatever the cell and group sizes, the answer is the same (exercises deep
// and shallow trees, one particle per cell, groups smaller than cells, one
// cell holding everything).
TYPED_TEST(NeighborsTest, AnyCellSizeGivesTheSameAnswer) {
  constexpr int D = TypeParam::value;
  const auto s = uniform_set<D>(1500, make_box<D>(0, 1, 0b001), 0.4, 25);
  for (const auto& [cell, group] : {std::pair{1u, 1u}, std::pair{3u, 8u}, std::pair{64u, 16u}, std::pair{5000u, 64u}}) {
    SCOPED_TRACE("max_cell_size " + std::to_string(cell) + ", max_group_size " + std::to_string(group));
    expect_matches_brute_force(s, cell, group);
  }
}

TYPED_TEST(NeighborsTest, RegularLattice) {
  constexpr int D = TypeParam::value;
  const int m = D == 1 ? 2000 : (D == 2 ? 50 : 14);
  for (unsigned periodic : {0u, (1u << D) - 1, 1u}) {
    SCOPED_TRACE("periodic axes mask " + std::to_string(periodic));
    // H = 1.7 dx everywhere, then alternating 1.3 dx / 2.9 dx.
    const auto uniform_h = lattice_set<D>(m, make_box<D>(0, 1, periodic), 1.7, 1.7);
    EXPECT_GT(expect_matches_brute_force(uniform_h), 1.9);
    const auto mixed_h = lattice_set<D>(m, make_box<D>(0, 1, periodic), 1.3, 2.9);
    EXPECT_GT(expect_matches_brute_force(mixed_h), 1.9);
  }
}

TYPED_TEST(NeighborsTest, StronglyClusteredWithTenfoldH) {
  constexpr int D = TypeParam::value;
  for (unsigned periodic : {0u, (1u << D) - 1, 1u}) {
    SCOPED_TRACE("periodic axes mask " + std::to_string(periodic));
    const auto s = clustered_set<D>(3000, make_box<D>(-1, 1, periodic), 31 + periodic);
    EXPECT_GT(expect_matches_brute_force(s), 3.0);
  }
}

// Periodic boxes only ~2H across: fewer than three H-sized cells per axis,
// where searching the cells "left" and "right" would find the same particle
// twice. H up to exactly L/2 is allowed.
TYPED_TEST(NeighborsTest, SmallPeriodicBox) {
  constexpr int D = TypeParam::value;
  Rng rng(41);
  ParticleSet<D> s{{}, {}, make_box<D>(0, 1, (1u << D) - 1)};
  std::uniform_real_distribution<Real> u(0.2, 0.5);
  for (int i = 0; i < 400; ++i) {
    s.x.push_back(uniform_point(s.box, rng));
    s.H.push_back(u(rng));
  }
  s.H[17] = 0.5;
  EXPECT_GT(expect_matches_brute_force(s), 10.0);

  // A 3^D lattice with H = 0.45 L: the x-neighbours on either side are
  // different particles, each found once.
  EXPECT_GT(expect_matches_brute_force(lattice_set<D>(3, s.box, 1.35, 1.35)), 1.0);

  // Two particles, 0.45 L apart one way round and 0.55 L the other: exactly
  // one neighbour each, not two.
  ParticleSet<D> two{{Vec<D>::zero(), Vec<D>::zero()}, {0.5, 0.5}, s.box};
  for (int k = 0; k < D; ++k) two.x[0][k] = 0.1, two.x[1][k] = k == 0 ? 0.55 : 0.1;
  const NeighborLists nl = cell_list_neighbors(two);
  EXPECT_EQ(all_lists(nl), (std::vector<std::vector<std::uint32_t>>{{1}, {0}}));
}

// Small periodic in x, large and open in the other axes.
TYPED_TEST(NeighborsTest, SmallPeriodicXLargeOpenRest) {
  constexpr int D = TypeParam::value;
  if (D == 1) GTEST_SKIP() << "no axis besides x (see SmallPeriodicBox)";
  Rng rng(42);
  Box<D> box = make_box<D>(0, 4, 0b001);
  box.hi[0] = 1;
  ParticleSet<D> s{{}, {}, box};
  std::uniform_real_distribution<Real> u(0.05, 0.5);
  for (int i = 0; i < 2000; ++i) {
    s.x.push_back(uniform_point(box, rng));
    s.H.push_back(u(rng));
  }
  EXPECT_GT(expect_matches_brute_force(s), 1.0);
}

// Positions given as other periodic images (here shifted by whole periods,
// exactly representable, and one at -1e-30 that wraps to lo) give the same
// neighbours as the wrapped positions.
TYPED_TEST(NeighborsTest, PositionsOutsideThePeriodicBoxAreWrapped) {
  constexpr int D = TypeParam::value;
  const auto inside = lattice_set<D>(D == 1 ? 64 : (D == 2 ? 16 : 8), make_box<D>(0, 1, (1u << D) - 1), 1.7, 2.3);
  auto outside = inside;
  for (std::size_t i = 0; i < outside.x.size(); ++i)
    for (int k = 0; k < D; ++k) outside.x[i][k] += Real(int((i + std::size_t(k)) % 5) - 2);  // -2 .. +2 periods
  outside.x[0][0] = Real(-1e-30);  // inside.x[0][0] is 0
  const NeighborLists a = cell_list_neighbors(inside), b = cell_list_neighbors(outside);
  EXPECT_EQ(all_lists(a), all_lists(b));
  EXPECT_GT(a.total(), inside.x.size());
}

// Many particles at one point (more than a cell holds, with equal keys).
TYPED_TEST(NeighborsTest, DuplicatePositions) {
  constexpr int D = TypeParam::value;
  auto s = uniform_set<D>(1000, make_box<D>(0, 1, 0b001), 0.4, 51);
  for (std::size_t i = 0; i < 200; ++i) s.x[500 + i] = s.x[3];
  EXPECT_GT(expect_matches_brute_force(s), 3.0);
}

// One cell far larger than max_cell_size: 5000 particles at one point
// (equal keys cannot be split). All but one have H = 0, so each has that one
// as its only neighbour and the output stays small.
TYPED_TEST(NeighborsTest, HugeCellOfDuplicates) {
  constexpr int D = TypeParam::value;
  auto s = uniform_set<D>(500, make_box<D>(0, 1, 0b000), 0.2, 52);
  const Vec<D> point = s.x[0];
  for (int i = 0; i < 5000; ++i) {
    s.x.push_back(point);
    s.H.push_back(i == 0 ? Real(1e-6) : Real(0));
  }
  expect_matches_brute_force(s);
}

// Input already in spatial order: the same neighbours, renumbered.
TYPED_TEST(NeighborsTest, PresortedInputGivesTheSameRelation) {
  constexpr int D = TypeParam::value;
  const auto s = clustered_set<D>(2000, make_box<D>(0, 1, 0b001), 61);
  const auto perm = spatial_sort_permutation(s.x.data(), s.x.size(), bounding_box(s.x.data(), s.x.size(), s.box));
  ParticleSet<D> t{{}, {}, s.box};
  for (const auto i : perm) {
    t.x.push_back(s.x[i]);
    t.H.push_back(s.H[i]);
  }
  const NeighborLists a = cell_list_neighbors(s), b = cell_list_neighbors(t);
  ASSERT_EQ(a.total(), b.total());
  for (std::size_t j = 0; j < perm.size(); ++j) {
    auto lb = list_of(b, j);
    for (auto& v : lb) v = perm[v];
    std::sort(lb.begin(), lb.end());
    ASSERT_EQ(lb, list_of(a, perm[j])) << "sorted particle " << j;
  }
}

TYPED_TEST(NeighborsTest, EmptyAndSingleParticle) {
  constexpr int D = TypeParam::value;
  ParticleSet<D> s{{}, {}, make_box<D>(0, 1, (1u << D) - 1)};
  NeighborLists nl = cell_list_neighbors(s);
  EXPECT_EQ(nl.size(), 0u);
  EXPECT_EQ(nl.total(), 0u);
  s.x.push_back(Vec<D>::zero());
  s.H.push_back(0.5);
  nl = cell_list_neighbors(s);
  EXPECT_EQ(nl.size(), 1u);
  EXPECT_EQ(nl.count(0), 0u);
}

// The result must not depend on the number of threads.
TYPED_TEST(NeighborsTest, DeterministicAcrossThreadCounts) {
  constexpr int D = TypeParam::value;
  const auto s = clustered_set<D>(3000, make_box<D>(0, 1, 0b001), 71);
#if defined(_OPENMP)
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const NeighborLists one = cell_list_neighbors(s);
  omp_set_num_threads(4);
  const NeighborLists four = cell_list_neighbors(s);
  omp_set_num_threads(saved);
  EXPECT_EQ(all_lists(one), all_lists(four));
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// The lists' memory (issue #14): searching again reuses the blocks (no new
// one), the result is the same; particles in spatial order (as the run keeps
// them) need few escapes, so the lists take about two bytes per entry; and
// what is held stays within an eighth of the units (the growth of a thread's
// blocks), each thread's first 8192-unit block, the end of each block that
// could not take a whole list, and the 12 bytes of index per particle (no
// second copy of the lists).
TYPED_TEST(NeighborsTest, RepeatedSearchesReuseTheBuffers) {
  constexpr int D = TypeParam::value;
  // uniform random positions, one H (about 12 / 28 / 58 neighbours in 1-D / 2-D / 3-D)
  Rng rng(91);
  ParticleSet<D> s{{}, {}, make_box<D>(0, 1, (1u << D) - 1)};
  const Real H = Real(D == 1 ? 6.0 : D == 2 ? 3.0 : 2.4) * spacing(s.box, 20000);
  for (int i = 0; i < 20000; ++i) {
    s.x.push_back(uniform_point(s.box, rng));
    s.H.push_back(H);
  }
  const auto perm = spatial_sort_permutation<D>(s.x.data(), s.x.size(), s.box);
  std::vector<Vec<D>> sorted(s.x.size());
  for (std::size_t i = 0; i < perm.size(); ++i) sorted[i] = s.x[perm[i]];
  s.x = sorted;
  CellList<D> cells;
  cells.build(s.x.data(), s.H.data(), s.x.size(), s.box);
  NeighborLists nl;
  cells.find_neighbors(nl);
  const auto first = all_lists(nl);
  const std::size_t blocks = nl.block_count();
  for (int repeat = 0; repeat < 3; ++repeat) cells.find_neighbors(nl);
  EXPECT_EQ(all_lists(nl), first);
  EXPECT_EQ(nl.block_count(), blocks);
#if defined(_OPENMP)
  const double threads = double(omp_get_max_threads());
#else
  const double threads = 1;
#endif
  const double entries = double(nl.total()), units = double(nl.units());
  EXPECT_GT(entries, 10.0 * double(s.x.size()));
  // escapes (3 units) for at most 5 % of the entries in spatial order
  EXPECT_LE(units, 1.10 * entries);
  std::size_t longest = 0;
  for (std::size_t i = 0; i < nl.size(); ++i) longest = std::max(longest, nl.count(i));
  EXPECT_LE(double(nl.bytes()), 2 * (1.125 * units + threads * 8192 + double(blocks) * (3.0 * double(longest))) +
                                    12.0 * double(s.x.size()));
}

// The 16-bit difference encoding round-trips any list of indices: lists
// below and above their owner, differences at the edges of the 16-bit
// range, jumps that need escapes, indices near 2^32, unordered lists,
// duplicates, the owner itself, empty lists.
TEST(NeighborListsEncoding, AnyListRoundTrips) {
  const std::uint32_t big = 0xFFFFFFF0u;
  std::vector<std::vector<std::uint32_t>> lists = {
      {},                                          // particle 0: empty
      {0, 2, 3, 65538, 65539, 131075, big},        // 1: step 65535 (direct) and 65536 (escape)
      {2, 3},                                      // 2: the owner itself (escape), then +1 from it
      {},                                          // 3
      {7, 5, 6, 6, 4},                             // 4: unordered and duplicates
  };
  lists.push_back({0, 1});  // 5: first entry below the owner (zigzag 9)
  std::vector<std::uint32_t> far;
  for (std::uint32_t j = 0; j < 200; ++j) far.push_back(40000 + 32767 + j * 300);  // first: zigzag 65534
  lists.resize(40001);
  lists[40000] = far;
  lists[39999] = {39999 - 32768, 39999 + 32768};  // zigzag 65535 (direct), then 65536 (escape)
  lists[39998] = {39998 + 32768};                 // zigzag 65536: escape
  NeighborLists nl;
  nl.assign(lists);
  ASSERT_EQ(nl.size(), lists.size());
  std::size_t entries = 0;
  for (std::size_t i = 0; i < lists.size(); ++i) {
    ASSERT_EQ(nl.count(i), lists[i].size()) << "particle " << i;
    ASSERT_EQ(nl.copy(i), lists[i]) << "particle " << i;
    entries += lists[i].size();
  }
  EXPECT_EQ(nl.total(), entries);
  // escapes, counted by hand: particle 1: the step of 65536 and the jump
  // to big (2); 2: the owner (1); 4: 5 < 7, 6 == 6, 4 < 6 (3); 5 and
  // 40000: none; 39999: the step of 65536 (1); 39998: zigzag 65536 (1)
  EXPECT_EQ(nl.units(), entries + 2 * (2 + 1 + 3 + 1 + 1));
}

TYPED_TEST(NeighborsTest, RejectsBadInput) {
  constexpr int D = TypeParam::value;
  auto s = uniform_set<D>(100, make_box<D>(0, 1, (1u << D) - 1), 0.2, 81);
  CellList<D> cells;

  // H just above L/2 on a periodic axis: a clear error.
  auto big = s;
  big.H[5] = Real(0.5) * (1 + Real(1e-5));
  try {
    cells.build(big.x.data(), big.H.data(), big.x.size(), big.box);
    ADD_FAILURE() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("half the periodic length"), std::string::npos) << e.what();
  }
  // The same H on open axes is fine.
  big.box = make_box<D>(0, 1, 0);
  EXPECT_NO_THROW(cells.build(big.x.data(), big.H.data(), big.x.size(), big.box));

  auto negative = s;
  negative.H[3] = -1;
  EXPECT_THROW(cells.build(negative.x.data(), negative.H.data(), negative.x.size(), negative.box),
               std::invalid_argument);
  auto nan = s;
  nan.x[4][D - 1] = std::nan("");
  EXPECT_THROW(cells.build(nan.x.data(), nan.H.data(), nan.x.size(), nan.box), std::invalid_argument);
  auto flat = s;
  flat.box.hi[0] = flat.box.lo[0];
  EXPECT_THROW(cells.build(flat.x.data(), flat.H.data(), flat.x.size(), flat.box), std::invalid_argument);
}

}  // namespace
