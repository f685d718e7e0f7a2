// The CUDA backend's neighbour search (rubble/neighbors/uniform_grid.hpp),
// checked on the CPU against the CPU cell list: for every particle the
// grid visitor must offer exactly the CPU's neighbours - all pairs with
// |x_a - x_b| < max(R_a, R_b), b != a - on open, periodic and mixed
// domains in 1, 2 and 3 D, with radii varying strongly, with periodic axes
// of only one or two cells, in the hashed mode (more cells than slots),
// and with a far outlier. Also: the candidates scanned for a polytrope-like
// distribution against the grid before issue #15, the 64-bit cell
// arithmetic of a grid of more than 2^31 cells, and the candidate list of
// summation density (candidate_list.hpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "rubble/neighbors/candidate_list.hpp"
#include "rubble/neighbors/cell_list.hpp"
#include "rubble/neighbors/uniform_grid.hpp"

using namespace rubble;

namespace {

template <int D>
struct Case {
  Box<D> domain;
  std::vector<Vec<D>> x;
  std::vector<Real> R;
};

template <int D>
Case<D> random_case(const Vec<D>& lo, const Vec<D>& hi, bool periodic, std::size_t n, Real r_lo, Real r_hi,
                    unsigned seed) {
  Case<D> c;
  c.domain.lo = lo;
  c.domain.hi = hi;
  for (int k = 0; k < D; ++k) c.domain.periodic[k] = periodic;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<Real> u(0, 1), r(r_lo, r_hi);
  for (std::size_t i = 0; i < n; ++i) {
    Vec<D> p;
    for (int k = 0; k < D; ++k) p[k] = lo[k] + u(rng) * (hi[k] - lo[k]);
    c.x.push_back(p);
    c.R.push_back(r(rng));
  }
  return c;
}

// Radii spread log-uniformly over [r_lo, r_hi] (strongly varying, unrelated
// to position: the hardest case for the reach bound).
template <int D>
Case<D> log_radius_case(const Vec<D>& lo, const Vec<D>& hi, bool periodic, std::size_t n, Real r_lo, Real r_hi,
                        unsigned seed) {
  Case<D> c = random_case<D>(lo, hi, periodic, n, r_lo, r_hi, seed);
  std::mt19937_64 rng(seed + 1000);
  std::uniform_real_distribution<Real> u(0, 1);
  for (auto& r : c.R) r = r_lo * std::pow(r_hi / r_lo, u(rng));
  return c;
}

// The grid as the CUDA backend builds it (there with a device radix sort
// and atomic maxima).
template <int D>
struct CpuGrid {
  GridNeighbors<D> g{};
  std::vector<std::uint64_t> slot;
  std::vector<std::uint32_t> order, start, end;
  std::vector<Real> rmax, reach;

  CpuGrid(const Case<D>& c, double max_cells) {
    const std::size_t n = c.x.size();
    Vec<D> mn = c.x[0], mx = c.x[0];
    for (const auto& p : c.x)
      for (int k = 0; k < D; ++k) mn[k] = std::min(mn[k], p[k]), mx[k] = std::max(mx[k], p[k]);
    Real r_max = 0;
    double log_sum = 0;
    for (Real r : c.R) r_max = std::max(r_max, r), log_sum += std::log(double(r));
    g.grid = make_uniform_grid<D>(c.domain, mn, mx, Real(std::exp(log_sum / double(n))), r_max, max_cells);
    const std::size_t slots = g.grid.cell_count();
    slot.resize(n);
    start.assign(slots, 0);
    end.assign(slots, 0);
    rmax.assign(slots, 0);
    reach.assign(slots, 0);
    for (std::size_t i = 0; i < n; ++i) {
      slot[i] = g.grid.bucket_of(c.x[i]);
      EXPECT_LT(slot[i], slots);
      rmax[slot[i]] = std::max(rmax[slot[i]], c.R[i]);
      stamp_reach<D>(g.grid, c.x[i], c.R[i], [&](std::uint64_t s, Real r) {
        ASSERT_LT(s, slots);
        reach[s] = std::max(reach[s], r);
      });
    }
    order.resize(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return slot[a] < slot[b]; });
    for (std::size_t s = 0; s < n; ++s) {
      const std::uint64_t cc = slot[order[s]];
      if (s == 0 || slot[order[s - 1]] != cc) start[cc] = std::uint32_t(s);
      if (s + 1 == n || slot[order[s + 1]] != cc) end[cc] = std::uint32_t(s + 1);
    }
    g.x = c.x.data();
    g.R = c.R.data();
    g.order = order.data();
    g.start = start.data();
    g.end = end.data();
    g.cell_rmax = rmax.data();
    g.cell_reach = reach.data();
  }

  // every particle's neighbours (sorted), and the candidates scanned
  std::vector<std::vector<std::uint32_t>> neighbours(std::uint64_t* scanned = nullptr) {
    const std::size_t n = order.size();
    std::vector<std::vector<std::uint32_t>> out(n);
    for (std::uint32_t a = 0; a < n; ++a) {
      g.a = a;
      g.visit([&](std::uint32_t b) { out[a].push_back(b); }, scanned);
      std::sort(out[a].begin(), out[a].end());
    }
    return out;
  }
};

template <int D>
std::vector<std::vector<std::uint32_t>> cell_list_neighbours(const Case<D>& c) {
  CellList<D> cl;
  cl.build(c.x.data(), c.R.data(), c.x.size(), c.domain);
  NeighborLists ref;
  cl.find_neighbors(ref);
  std::vector<std::vector<std::uint32_t>> out(c.x.size());
  for (std::size_t a = 0; a < c.x.size(); ++a) {
    out[a] = ref.copy(a);
    std::sort(out[a].begin(), out[a].end());
  }
  return out;
}

template <int D>
void expect_same_as_cell_list(const Case<D>& c, double max_cells = 1e9, bool expect_hashed = false) {
  const auto want = cell_list_neighbours<D>(c);
  CpuGrid<D> grid(c, max_cells);
  EXPECT_EQ(grid.g.grid.hashed, expect_hashed);
  const auto got = grid.neighbours();
  std::size_t pairs = 0;
  for (std::size_t a = 0; a < c.x.size(); ++a) {
    ASSERT_EQ(got[a], want[a]) << "particle " << a;
    pairs += want[a].size();
  }
  EXPECT_GT(pairs, c.x.size()) << "the case must have neighbours to compare";
  // the own-radius visitor (summation density) offers the b within R_a
  for (std::uint32_t a = 0; a < c.x.size(); a += 7) {
    grid.g.a = a;
    std::vector<std::uint32_t> own;
    grid.g.visit_own_radius([&](std::uint32_t b) { own.push_back(b); }, nullptr);
    std::sort(own.begin(), own.end());
    std::vector<std::uint32_t> expect;
    for (std::uint32_t b : want[a])
      if (norm2(c.domain.separation(c.x[a], c.x[b])) < c.R[a] * c.R[a]) expect.push_back(b);
    ASSERT_EQ(own, expect) << "own radius, particle " << a;
  }
}

// Candidates the grid before issue #15 scanned: cells r_max wide (grown by
// 1.26 until at most max(64, 4n) cells), all particles of the 3^D cells
// around each particle. Open axes only.
template <int D>
std::uint64_t old_grid_candidates(const Case<D>& c) {
  const std::size_t n = c.x.size();
  Vec<D> mn = c.x[0], mx = c.x[0];
  for (const auto& p : c.x)
    for (int k = 0; k < D; ++k) mn[k] = std::min(mn[k], p[k]), mx[k] = std::max(mx[k], p[k]);
  Real w = *std::max_element(c.R.begin(), c.R.end());
  std::int64_t G[D];
  for (;;) {
    double cells = 1;
    for (int k = 0; k < D; ++k) cells *= double(G[k] = std::int64_t(std::floor((mx[k] - mn[k]) / w)) + 1);
    if (cells <= std::max(64.0, 4.0 * double(n))) break;
    w *= Real(1.26);
  }
  auto coord = [&](Real v, int k) { return std::min<std::int64_t>(G[k] - 1, std::int64_t(std::floor((v - mn[k]) / w))); };
  std::size_t cells = 1;
  for (int k = 0; k < D; ++k) cells *= std::size_t(G[k]);
  std::vector<std::uint64_t> occupancy(cells, 0);
  std::vector<std::size_t> cell(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t lin = 0, stride = 1;
    for (int k = 0; k < D; ++k) lin += std::size_t(coord(c.x[i][k], k)) * stride, stride *= std::size_t(G[k]);
    ++occupancy[cell[i] = lin];
  }
  std::uint64_t total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::int64_t ci[D];
    std::size_t rest = cell[i];
    for (int k = 0; k < D; ++k) ci[k] = std::int64_t(rest % std::size_t(G[k])), rest /= std::size_t(G[k]);
    int t_max = 1;
    for (int k = 0; k < D; ++k) t_max *= 3;
    for (int t = 0; t < t_max; ++t) {
      int r = t;
      std::size_t lin = 0, stride = 1;
      bool inside = true;
      for (int k = 0; k < D; ++k) {
        const std::int64_t j = ci[k] + (r % 3) - 1;
        r /= 3;
        inside = inside && j >= 0 && j < G[k];
        lin += std::size_t(j) * stride, stride *= std::size_t(G[k]);
      }
      if (inside) total += occupancy[lin];
    }
  }
  return total;
}

// A polytrope-like star: radius 1, search radius R(r) = Rc (1 + 9 r^2)
// (ten times larger at the surface than at the centre) and a number
// density n(r) = N_R / ((4/3) pi R(r)^3), so that every particle has about
// N_R = 60 others within its own R (constant neighbour number, as h
// follows the density).
Case<3> polytrope_case(std::size_t n, unsigned seed, Real& Rc) {
  // N = integral n dV = N_R / ((4/3) pi Rc^3) * I, I = int_0^1 4 pi r^2 / (1 + 9 r^2)^3 dr
  double I = 0;
  const int steps = 20000;
  for (int s = 0; s < steps; ++s) {
    const double r = (s + 0.5) / steps;
    I += 4 * M_PI * r * r / std::pow(1 + 9 * r * r, 3) / steps;
  }
  const double N_R = 60;
  Rc = Real(std::cbrt(N_R * I / (4.0 / 3.0 * M_PI * double(n))));
  Case<3> c;
  c.domain.lo = Vec<3>{-1, -1, -1};
  c.domain.hi = Vec<3>{1, 1, 1};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  // rejection sampling of r with density r^2 / (1 + 9 r^2)^3 (at most 0.01646, at r = 0.236)
  while (c.x.size() < n) {
    const double r = u(rng), y = u(rng) * 0.0165;
    if (y > r * r / std::pow(1 + 9 * r * r, 3)) continue;
    const double z = 2 * u(rng) - 1, phi = 2 * M_PI * u(rng), s = std::sqrt(1 - z * z);
    c.x.push_back(Vec<3>{Real(r * s * std::cos(phi)), Real(r * s * std::sin(phi)), Real(r * z)});
    c.R.push_back(Real(Rc * (1 + 9 * r * r)));
  }
  return c;
}

}  // namespace

TEST(UniformGrid, OpenBox3DMatchesTheCellList) {
  expect_same_as_cell_list<3>(random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 2000, 0.03, 0.09, 1));
}

TEST(UniformGrid, PeriodicBox3DMatchesTheCellList) {
  expect_same_as_cell_list<3>(random_case<3>(Vec<3>{-1, 0, 0}, Vec<3>{1, 1, 1}, true, 2000, 0.05, 0.15, 2));
}

TEST(UniformGrid, PeriodicAxisOfOneOrTwoCellsVisitsEachCellOnce) {
  // axis 1 is 0.25 long and R reaches 0.12: the radii are nearly equal, so
  // the cells are r_typ / 2 ~ 0.06 wide - four along axis 1, and the block
  // of a radius 0.12 covers them all (the whole-axis path)
  auto c = random_case<2>(Vec<2>{0, 0}, Vec<2>{1, 0.25}, true, 800, 0.11, 0.12, 3);
  expect_same_as_cell_list<2>(c);
  // radii 0.02-0.12 log-uniformly, a very thin periodic axis: one or two cells
  auto t = log_radius_case<2>(Vec<2>{0, 0}, Vec<2>{2, 0.25}, true, 600, 0.02, 0.12, 4);
  const Vec<2> mn{0, 0}, mx{2, 0.25};
  EXPECT_LE(make_uniform_grid<2>(t.domain, mn, mx, Real(0.03), Real(0.12), 1e9).G[1], 16);
  EXPECT_EQ(make_uniform_grid<2>(t.domain, mn, mx, Real(0.12), Real(0.12), 1e9).G[1], 4);
  Box<1> b;
  b.lo = Vec<1>{0};
  b.hi = Vec<1>{0.1};
  b.periodic[0] = true;
  EXPECT_EQ(make_uniform_grid<1>(b, Vec<1>{0}, Vec<1>{0.1}, Real(0.05), Real(0.05), 1e9).G[0], 4);
  expect_same_as_cell_list<2>(t);
}

TEST(UniformGrid, MixedPeriodicAndOpenAxes) {
  auto c = random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 0.5, 2}, false, 1500, 0.04, 0.1, 4);
  c.domain.periodic[0] = true;  // x periodic, y and z open
  expect_same_as_cell_list<3>(c);
}

// Radii varying 20x independently of position: many pairs are found only
// through the larger radius of the two (R_b > |x_a - x_b| >= R_a), which
// the reach stamped onto a's cell must cover.
TEST(UniformGrid, StronglyVaryingRadiiMatchTheCellList) {
  for (bool periodic : {false, true}) {
    SCOPED_TRACE(periodic ? "periodic" : "open");
    expect_same_as_cell_list<3>(log_radius_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, periodic, 2500, 0.01, 0.2, 10));
    expect_same_as_cell_list<2>(log_radius_case<2>(Vec<2>{-1, 0}, Vec<2>{1, 1}, periodic, 2500, 0.005, 0.1, 11));
    expect_same_as_cell_list<1>(log_radius_case<1>(Vec<1>{0}, Vec<1>{1}, periodic, 1500, 0.0005, 0.02, 12));
  }
  // the case has pairs that only the larger radius makes
  const auto c = log_radius_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 2500, 0.01, 0.2, 10);
  std::size_t one_sided = 0;
  const auto want = cell_list_neighbours<3>(c);
  for (std::size_t a = 0; a < c.x.size(); ++a)
    for (std::uint32_t b : want[a]) one_sided += norm2(c.x[a] - c.x[b]) >= c.R[a] * c.R[a];
  EXPECT_GT(one_sided, c.x.size());
}

// More cells than slots: the hashed mode (several cells per slot) finds
// the same neighbours.
TEST(UniformGrid, HashedGridGivesTheSameNeighbours) {
  const auto c = log_radius_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 1500, 0.03, 0.1, 5);
  expect_same_as_cell_list<3>(c, 100.0, true);  // 64 slots for far more cells
  auto p = log_radius_case<2>(Vec<2>{0, 0}, Vec<2>{1, 1}, true, 1500, 0.01, 0.1, 6);
  p.domain.periodic[1] = false;
  expect_same_as_cell_list<2>(p, 200.0, true);
}

TEST(UniformGrid, FarOutlierInEveryDimension) {
  auto c = log_radius_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 1000, 0.03, 0.1, 6);
  c.x.push_back(Vec<3>{1e4, -3e3, 2e4});  // without hashing the grid would be huge
  c.R.push_back(0.1);
  c.x.push_back(Vec<3>{1e4 + 0.05, -3e3, 2e4});  // ... with a neighbour out there
  c.R.push_back(0.06);
  expect_same_as_cell_list<3>(c, 2.0 * double(c.x.size()), true);
  {
    // the bulk keeps its fine cells: the outlier does not coarsen them
    CpuGrid<3> g(c, 2.0 * double(c.x.size()));
    EXPECT_LT(g.g.grid.width[0], Real(0.1));
  }
  auto d = log_radius_case<2>(Vec<2>{0, 0}, Vec<2>{1, 1}, false, 1000, 0.01, 0.05, 7);
  d.x.push_back(Vec<2>{-5e5, 3e7});  // beyond 2^30 cells per axis: clamped into the edge cells
  d.R.push_back(0.03);
  expect_same_as_cell_list<2>(d, 2.0 * double(d.x.size()), true);
  auto e = log_radius_case<1>(Vec<1>{0}, Vec<1>{1}, false, 500, 0.002, 0.02, 8);
  e.x.push_back(Vec<1>{1e9});
  e.R.push_back(0.01);
  expect_same_as_cell_list<1>(e, 2.0 * double(e.x.size()), true);
  expect_same_as_cell_list<1>(random_case<1>(Vec<1>{0}, Vec<1>{1}, true, 500, 0.005, 0.02, 7));
}

// Candidates scanned for the polytrope-like star (polytrope_case), against
// the grid before issue #15 (cells r_max = 10 Rc wide, 3^3 cells).
//
// Derivation of the factor asserted (10). With n = 20000 and N_R = 60,
// I = 0.0866 gives Rc = 0.0396, r_max = 0.396. New cells: w = max(r_typ / 2,
// r_max / 4) = 2.5 Rc (r_typ, the geometric mean of R, is about 1.9 Rc).
// Where the density is locally uniform, the old grid scans the 27 cells of
// side r_max, 27 r_max^3 n(x), and the new one the cells that a ball of
// radius ~R_a touches, at most a cube of side 2 R_a + w: (2 R_a + w)^3 n(x).
// Per particle the ratio is 27 (10 Rc)^3 / (2 R_a + 2.5 Rc)^3: 98 at the
// median R_a = 1.9 Rc, 16 at 5 Rc, 10 at R_a = 5.9 Rc, beyond which lie
// under 10 % of the particles (r > 0.73); the old count is capped by n for
// the central particles (a 1.2-wide block holds most of the star), which
// lowers the overall ratio towards the outer particles' values. Hence at
// least 10. Measured: old 15006, new 601 candidates per particle (25x),
// 74 neighbours per particle. A rigorous floor on the old count alone: the
// 27 cells around a contain the ball of radius r_max around it, so each of
// the F(0.2) = 22 % of the particles within r < 0.2 scans at least the
// F(0.196) = 21 % within r < 0.196: old >= 0.048 n^2 (asserted too, so the
// scene cannot silently become an easy one).
TEST(UniformGrid, PolytropeScansFarFewerCandidates) {
  Real Rc = 0;
  const std::size_t n = 20000;
  const Case<3> c = polytrope_case(n, 21, Rc);
  EXPECT_NEAR(Rc, 0.0396, 0.0005);
  const std::uint64_t old_candidates = old_grid_candidates<3>(c);
  CpuGrid<3> grid(c, 2.0 * double(n));
  std::uint64_t new_candidates = 0;
  const auto got = grid.neighbours(&new_candidates);
  std::uint64_t pairs = 0;
  for (const auto& l : got) pairs += l.size();
  const double reduction = double(old_candidates) / double(new_candidates);
  std::printf("polytrope n=%zu Rc=%.4f w=%.4f: neighbours %.1f per particle, candidates old %.1f, new %.1f per "
              "particle (%.1fx fewer; new/needed %.2f)\n",
              n, double(Rc), double(grid.g.grid.width[0]), double(pairs) / double(n), double(old_candidates) / double(n),
              double(new_candidates) / double(n), reduction, double(new_candidates) / double(pairs));
  std::uint64_t inspected = 0;
  for (std::uint32_t a = 0; a < n; ++a) {
    const Real reach = std::max(c.R[a], grid.reach[grid.g.grid.bucket_of(c.x[a])]);
    grid.g.grid.for_each_cell(c.x[a], reach, [&](std::uint64_t, Real) { ++inspected; });
  }
  std::printf("cells inspected per particle %.1f, slots %zu\n", double(inspected) / double(n),
              std::size_t(grid.g.grid.cell_count()));
  EXPECT_LT(double(inspected), 1000.0 * double(n));  // at most (2 * 4 + 2)^3 per particle
  EXPECT_GE(double(old_candidates), 0.048 * double(n) * double(n));
  EXPECT_GE(reduction, 10.0);
  // and the same neighbours as the CPU cell list
  const auto want = cell_list_neighbours<3>(c);
  for (std::size_t a = 0; a < n; ++a) ASSERT_EQ(got[a], want[a]) << "particle " << a;
}

// Cell ids beyond 2^31 (and 2^32): geometry only, nothing allocated.
TEST(UniformGrid, CellIdsAreSixtyFourBit) {
  Box<3> b;  // open
  const Vec<3> mn{0, 0, 0}, mx{2047, 2047, 1023};
  const UniformGrid<3> g = make_uniform_grid<3>(b, mn, mx, Real(1), Real(1), 1e12);  // w = 0.5
  EXPECT_EQ(g.G[0], 4095);
  EXPECT_EQ(g.G[2], 2047);
  const std::uint64_t cells = std::uint64_t(4095) * 4095 * 2047;
  EXPECT_GT(cells, std::uint64_t(1) << 34);
  EXPECT_EQ(g.cells, cells);
  EXPECT_FALSE(g.hashed);
  EXPECT_EQ(g.cell_count(), cells);
  EXPECT_EQ(g.cell_id(mx), cells - 1);
  const Vec<3> p{Real(1000.25), Real(2000.75), Real(1000.1)};  // cell (2000, 4001, 2000)
  const std::uint64_t id = 2000 + 4095 * (4001 + std::uint64_t(4095) * 2000);
  EXPECT_EQ(g.cell_id(p), id);
  EXPECT_GT(id, std::uint64_t(1) << 32);
  // the cells around p: ids as the same arithmetic gives them, no wrap-around
  std::size_t visited = 0;
  g.for_each_cell(p, Real(0.6), [&](std::uint64_t cid, Real) {
    const std::uint64_t i = cid % 4095, j = (cid / 4095) % 4095, k = cid / (std::uint64_t(4095) * 4095);
    EXPECT_LE(i >= 2000 ? i - 2000 : 2000 - i, 2u);
    EXPECT_LE(j >= 4001 ? j - 4001 : 4001 - j, 2u);
    EXPECT_LE(k >= 2000 ? k - 2000 : 2000 - k, 2u);
    ++visited;
  });
  EXPECT_GE(visited, 27u);
  // the same geometry hashed into at most 2^20 slots
  const UniformGrid<3> h = make_uniform_grid<3>(b, mn, mx, Real(1), Real(1), double(1 << 20));
  EXPECT_TRUE(h.hashed);
  EXPECT_EQ(h.cell_count(), std::uint64_t(1) << 20);
  EXPECT_EQ(h.cell_id(p), id);
  EXPECT_LT(h.bucket_of(p), h.cell_count());
  // a far point saturates to the last cell instead of overflowing
  EXPECT_EQ(g.cell_id(Vec<3>{Real(1e30), Real(1e30), Real(1e30)}), cells - 1);
}

TEST(UniformGrid, CandidateListOffersTheGatheredNeighboursAndReportsOverflow) {
  const auto c = random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, true, 6000, 0.1, 0.12, 13);
  CpuGrid<3> grid(c, 1e9);
  std::size_t fitted = 0;
  for (std::uint32_t a = 0; a < c.x.size(); a += 11) {
    grid.g.a = a;
    const GridOwnRadius<3> own{grid.g};
    std::vector<std::uint32_t> walk;
    own([&](std::uint32_t b) { walk.push_back(b); });
    ASSERT_GT(walk.size(), 8u);
    CandidateList<kCandidateListCapacity<3>> list;
    ASSERT_TRUE(list.gather(own));
    std::vector<std::uint32_t> again;
    list([&](std::uint32_t b) { again.push_back(b); });
    EXPECT_EQ(again, walk);  // same particles, same order
    CandidateList<8> small;
    EXPECT_FALSE(small.gather(own));
    EXPECT_EQ(small.n, 8u);
    ++fitted;
  }
  EXPECT_GT(fitted, 100u);
}

TEST(UniformGrid, RejectsRadiiItCannotServe) {
  Box<2> b;
  b.hi = Vec<2>{1, 1};
  b.periodic[0] = true;
  const Vec<2> mn{0, 0}, mx{1, 1};
  EXPECT_THROW(make_uniform_grid<2>(b, mn, mx, Real(0.6), Real(0.6), 1e9), std::invalid_argument);  // > L/2
  EXPECT_THROW(make_uniform_grid<2>(b, mn, mx, Real(0.1), Real(0), 1e9), std::invalid_argument);
  EXPECT_THROW(make_uniform_grid<2>(b, mn, Vec<2>{1, Real(NAN)}, Real(0.1), Real(0.1), 1e9), std::invalid_argument);
}
