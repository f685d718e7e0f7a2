#pragma once
// The CUDA backend's neighbour search (solver/src/cuda/cuda_stepper.cu): a
// uniform grid whose cells are at least the largest search radius wide, and
// a visitor that offers every particle of the 3^D cells around particle a
// to a loop body (the `each` of rubble/drivers/particle_rates.hpp), keeping
// those with |x_a - x_b| < max(R_a, R_b), b != a (minimum image on periodic
// axes) - the criterion of the CPU's cell_list.hpp, so both backends see the
// same pairs. Here, not in the .cu, so that the CPU unit tests check it
// against the CPU cell list (test_uniform_grid.cpp).
//
// The grid itself is: cell ids of the particles (cell_of), (cell, index)
// pairs sorted by cell, and per cell the range [start, end) of its entries
// in that sorted order (empty cells: start = end = 0).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

template <int D>
struct UniformGrid {
  Box<D> domain;
  Vec<D> lo;       // corner of cell 0
  Real inv_w[D];   // 1 / cell width per axis
  int G[D];        // cells per axis

  RUBBLE_HD int cell_coord(Real xk, int k) const {
    const Real c = std::floor((xk - lo[k]) * inv_w[k]);
    return c < Real(0) ? 0 : c > Real(G[k] - 1) ? G[k] - 1 : int(c);
  }
  // Linear cell id (axis 0 fastest).
  RUBBLE_HD std::size_t cell_of(const Vec<D>& x) const {
    std::size_t lin = 0, stride = 1;
    for (int k = 0; k < D; ++k) {
      lin += std::size_t(cell_coord(x[k], k)) * stride;
      stride *= std::size_t(G[k]);
    }
    return lin;
  }
  std::size_t cell_count() const {
    std::size_t c = 1;
    for (int k = 0; k < D; ++k) c *= std::size_t(G[k]);
    return c;
  }
};

// Grid geometry for particles within [mn, mx] (open axes) and the largest
// search radius r_max: cells at least r_max wide; on periodic axes a whole
// number of cells spans the domain. If that would make more than max_cells
// cells, the cells grow (same neighbours, more candidates each).
// Throws std::invalid_argument for r_max <= 0 or non-finite, or r_max above
// half a periodic length.
template <int D>
UniformGrid<D> make_uniform_grid(const Box<D>& domain, const Vec<D>& mn, const Vec<D>& mx, Real r_max,
                                 double max_cells) {
  if (!(r_max > Real(0)) || !std::isfinite(r_max))
    throw std::invalid_argument("uniform grid: search radius must be positive and finite");
  UniformGrid<D> g{};
  g.domain = domain;
  for (;;) {
    double cells = 1;
    for (int k = 0; k < D; ++k) {
      if (domain.periodic[k]) {
        const Real L = domain.length(k);
        if (r_max > Real(0.5) * L)
          throw std::invalid_argument("uniform grid: a search radius exceeds half the periodic length along axis " +
                                      std::to_string(k));
        g.G[k] = std::floor(L / r_max) < Real(1) ? 1 : int(std::floor(L / r_max));
        g.lo[k] = domain.lo[k];
        g.inv_w[k] = Real(g.G[k]) / L;
      } else {
        if (!std::isfinite(mn[k]) || !std::isfinite(mx[k]))
          throw std::invalid_argument("uniform grid: non-finite particle position");
        g.G[k] = int(std::floor((mx[k] - mn[k]) / r_max)) + 1;
        g.lo[k] = mn[k];
        g.inv_w[k] = Real(1) / r_max;
      }
      cells *= double(g.G[k]);
    }
    if (cells <= max_cells) return g;
    r_max *= Real(1.26);  // coarser cells: fewer of them, same neighbours
  }
}

template <int D>
struct GridNeighbors {
  UniformGrid<D> grid;
  const Vec<D>* x = nullptr;
  const Real* R = nullptr;              // search radii
  const std::uint32_t* order = nullptr; // particle indices sorted by cell
  const std::uint32_t* start = nullptr; // per cell: first position in `order`
  const std::uint32_t* end = nullptr;   // per cell: one past the last
  std::uint32_t a = 0;                  // the particle whose neighbours are visited

  template <class F>
  RUBBLE_HD void operator()(F&& f) const {
    // the candidate cell coordinates along each axis, each cell once (a
    // periodic axis of fewer than 3 cells has them all)
    int cand[D][3], cnt[D];
    for (int k = 0; k < D; ++k) {
      const int c = grid.cell_coord(x[a][k], k);
      cnt[k] = 0;
      if (grid.domain.periodic[k] && grid.G[k] < 3) {
        for (int j = 0; j < grid.G[k]; ++j) cand[k][cnt[k]++] = j;
      } else {
        for (int o = -1; o <= 1; ++o) {
          int j = c + o;
          if (grid.domain.periodic[k]) j = (j + grid.G[k]) % grid.G[k];
          else if (j < 0 || j >= grid.G[k]) continue;
          cand[k][cnt[k]++] = j;
        }
      }
    }
    int total = 1;
    for (int k = 0; k < D; ++k) total *= cnt[k];
    const Real Ra = R[a];
    for (int t = 0; t < total; ++t) {
      std::size_t lin = 0, stride = 1;
      int rest = t;
      for (int k = 0; k < D; ++k) {
        lin += std::size_t(cand[k][rest % cnt[k]]) * stride;
        rest /= cnt[k];
        stride *= std::size_t(grid.G[k]);
      }
      for (std::uint32_t j = start[lin]; j < end[lin]; ++j) {
        const std::uint32_t b = order[j];
        if (b == a) continue;
        const Real rb = R[b], rm = Ra > rb ? Ra : rb;
        if (norm2(grid.domain.separation(x[a], x[b])) < rm * rm) f(b);
      }
    }
  }
};

}  // namespace rubble
