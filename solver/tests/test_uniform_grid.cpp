// The CUDA backend's neighbour search (rubble/neighbors/uniform_grid.hpp),
// checked on the CPU against the CPU cell list: for every particle the
// grid visitor must offer exactly the CPU's neighbours - all pairs with
// |x_a - x_b| < max(R_a, R_b), b != a - on open, periodic and mixed
// domains, with periodic axes of only two cells, with the cell count capped
// (coarser cells), and with a far outlier.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

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

// The grid as the CUDA backend builds it (there with a device radix sort).
template <int D>
std::vector<std::vector<std::uint32_t>> grid_neighbors(const Case<D>& c, double max_cells) {
  const std::size_t n = c.x.size();
  Vec<D> mn = c.x[0], mx = c.x[0];
  for (const auto& p : c.x)
    for (int k = 0; k < D; ++k) mn[k] = std::min(mn[k], p[k]), mx[k] = std::max(mx[k], p[k]);
  const Real r_max = *std::max_element(c.R.begin(), c.R.end());
  GridNeighbors<D> g{};
  g.grid = make_uniform_grid<D>(c.domain, mn, mx, r_max, max_cells);
  std::vector<std::size_t> cell(n);
  for (std::size_t i = 0; i < n; ++i) cell[i] = g.grid.cell_of(c.x[i]);
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return cell[a] < cell[b]; });
  std::vector<std::uint32_t> start(g.grid.cell_count(), 0), end(g.grid.cell_count(), 0);
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t cc = cell[order[s]];
    if (s == 0 || cell[order[s - 1]] != cc) start[cc] = std::uint32_t(s);
    if (s + 1 == n || cell[order[s + 1]] != cc) end[cc] = std::uint32_t(s + 1);
  }
  g.x = c.x.data();
  g.R = c.R.data();
  g.order = order.data();
  g.start = start.data();
  g.end = end.data();
  std::vector<std::vector<std::uint32_t>> out(n);
  for (std::uint32_t a = 0; a < n; ++a) {
    g.a = a;
    g([&](std::uint32_t b) { out[a].push_back(b); });
    std::sort(out[a].begin(), out[a].end());
  }
  return out;
}

template <int D>
void expect_same_as_cell_list(const Case<D>& c, double max_cells = 1e9) {
  CellList<D> cl;
  cl.build(c.x.data(), c.R.data(), c.x.size(), c.domain);
  NeighborLists ref;
  cl.find_neighbors(ref);
  const auto got = grid_neighbors<D>(c, max_cells);
  std::size_t pairs = 0;
  for (std::size_t a = 0; a < c.x.size(); ++a) {
    std::vector<std::uint32_t> want = ref.copy(a);
    std::sort(want.begin(), want.end());
    ASSERT_EQ(got[a], want) << "particle " << a;
    pairs += want.size();
  }
  EXPECT_GT(pairs, c.x.size()) << "the case must have neighbours to compare";
}

}  // namespace

TEST(UniformGrid, OpenBox3DMatchesTheCellList) {
  expect_same_as_cell_list<3>(random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 2000, 0.03, 0.09, 1));
}

TEST(UniformGrid, PeriodicBox3DMatchesTheCellList) {
  expect_same_as_cell_list<3>(random_case<3>(Vec<3>{-1, 0, 0}, Vec<3>{1, 1, 1}, true, 2000, 0.05, 0.15, 2));
}

TEST(UniformGrid, PeriodicAxisOfTwoCellsVisitsEachCellOnce) {
  // axis 1 is 0.25 long and R reaches 0.12: two cells, both neighbours of each other
  auto c = random_case<2>(Vec<2>{0, 0}, Vec<2>{1, 0.25}, true, 800, 0.04, 0.12, 3);
  Vec<2> mn{0, 0}, mx{1, 0.25};
  EXPECT_EQ(make_uniform_grid<2>(c.domain, mn, mx, Real(0.12), 1e9).G[1], 2);
  expect_same_as_cell_list<2>(c);
}

TEST(UniformGrid, MixedPeriodicAndOpenAxes) {
  auto c = random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 0.5, 2}, false, 1500, 0.04, 0.1, 4);
  c.domain.periodic[0] = true;  // x periodic, y and z open
  expect_same_as_cell_list<3>(c);
}

TEST(UniformGrid, CappedCellCountGivesTheSameNeighbours) {
  const auto c = random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 1500, 0.05, 0.1, 5);
  expect_same_as_cell_list<3>(c, 20.0);  // far fewer cells than the 1/0.1^3 uncapped
}

TEST(UniformGrid, FarOutlierAndOneDimension) {
  auto c = random_case<3>(Vec<3>{0, 0, 0}, Vec<3>{1, 1, 1}, false, 1000, 0.05, 0.1, 6);
  c.x.push_back(Vec<3>{1e4, -3e3, 2e4});  // the grid would be huge: capped
  c.R.push_back(0.1);
  expect_same_as_cell_list<3>(c, 4.0 * double(c.x.size()));
  expect_same_as_cell_list<1>(random_case<1>(Vec<1>{0}, Vec<1>{1}, true, 500, 0.005, 0.02, 7));
}

TEST(UniformGrid, RejectsRadiiItCannotServe) {
  Box<2> b;
  b.hi = Vec<2>{1, 1};
  b.periodic[0] = true;
  const Vec<2> mn{0, 0}, mx{1, 1};
  EXPECT_THROW(make_uniform_grid<2>(b, mn, mx, Real(0.6), 1e9), std::invalid_argument);  // > L/2
  EXPECT_THROW(make_uniform_grid<2>(b, mn, mx, Real(0), 1e9), std::invalid_argument);
}
