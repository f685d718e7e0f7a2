#pragma once
// The CUDA backend's neighbour search (solver/src/cuda/cuda_stepper.cu),
// here, not in the .cu, so that the CPU unit tests check it against the CPU
// cell list (test_uniform_grid.cpp). The criterion is the CPU cell list's
// (cell_list.hpp): b is a neighbour of a when |x_a - x_b| < max(R_a, R_b),
// b != a, minimum image on periodic axes - so both backends see the same
// pairs however much R varies.
//
// Why not one cell per largest radius (the grid before issue #15): with
// cells r_max wide, a particle whose R is ten times smaller than r_max (the
// centre of a polytrope) scans 27 r_max^3 of particles for a ball of
// 4.19 R^3, and one far outlier made the grid so large that the cell cap
// coarsened every cell. Here:
//
//  * Cells are w = max(r_typ / 2, r_max / 4) wide, r_typ the geometric mean
//    of the radii (one more sum in the extent reduction the grid needs
//    anyway; for a polytrope it lies near the median, and unlike a quantile
//    it costs no sort). Half a typical radius: a particle scans the cells
//    its ball touches, about (4/3) pi (R + 0.8 w)^3 of volume, 2.8 times the
//    ball at w = R/2 against 6.4 times (27 cells) at w = R. The floor
//    r_max / 4 bounds the cells a particle of the largest radius inspects
//    (at most 10 per axis, 1000 in 3-D); on the polytrope-like star of
//    test_uniform_grid.cpp (R ten times larger at the surface) it also gave
//    fewer candidates than r_max / 8 or r_max / 16: where R changes steeply
//    the reach of the small-R particles is set by their large-R
//    neighbours, and finer cells then only add cells to inspect.
//  * Each cell stores the largest R of its particles (cell_rmax) and the
//    largest R of any particle whose ball touches the cell (cell_reach,
//    "stamped" by every particle onto the cells within its R). Particle a
//    inspects the cells within reach = max(R_a, cell_reach of its own cell)
//    - every b with |x_a - x_b| < R_b has touched a's cell, so R_b <= reach
//    - and scans only the cells whose box lies within max(R_a, cell_rmax)
//    of x_a. With smoothly varying R the reach is about R_a and the scanned
//    volume follows each particle's own radius, not the largest one.
//  * Cell ids are 64-bit (cells per axis up to 2^(60/D); positions beyond
//    that are clamped into the edge cells, which on open axes reach to
//    infinity - clamping is monotone, so no neighbour is lost). Storage is
//    one slot per cell while the cells number at most max_cells (a small
//    multiple of the particle count); above that (far outliers, bodies far
//    apart) the cell ids are hashed into a power-of-two table of slots
//    ("hashed" mode): a slot may then hold several cells, the visitor skips
//    entries of other cells, and a slot's cell_rmax / cell_reach are maxima
//    over its cells - still upper bounds, so still exact. A far outlier now
//    costs one slot, not coarser cells for everyone.
//
// Per slot (cell) the device stores: the range [start, end) of its particles
// in the sorted order (empty: start = end = 0), cell_rmax and cell_reach
// (zero when nothing lies there or reaches there).
//
// Summation density also reuses candidate lists across its smoothing-length
// Newton iterations (candidate_list.hpp): it needs only the b within R_a
// (its h never exceeds R_a), which visit_own_radius offers.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// Cell width: w = max(r_typ / kGridCellsPerTypicalRadius, r_max / kGridMaxCellsPerRadius).
inline constexpr double kGridCellsPerTypicalRadius = 2.0;
inline constexpr double kGridMaxCellsPerRadius = 4.0;

// A 64-bit mix (the splitmix64 finaliser): neighbouring cells land in
// unrelated slots of a hashed grid.
RUBBLE_HD inline std::uint64_t grid_cell_hash(std::uint64_t v) {
  v ^= v >> 30;
  v *= 0xbf58476d1ce4e5b9ull;
  v ^= v >> 27;
  v *= 0x94d049bb133111ebull;
  v ^= v >> 31;
  return v;
}

template <int D>
struct UniformGrid {
  Box<D> domain;
  Vec<D> lo;               // corner of cell 0
  Real width[D];           // cell width per axis
  Real inv_w[D];           // 1 / width
  std::int64_t G[D];       // cells per axis
  std::uint64_t cells = 1;    // product of G (may exceed any array)
  std::uint64_t buckets = 1;  // storage slots: cells, or a power of two when hashed
  bool hashed = false;
  // Rounding allowance of the range and pruning tests (positions are
  // assigned to cells by floor((x - lo) / w) in floating point, so a
  // particle may lie a few ulps outside its cell's nominal box).
  Real slack = 0;

  // floor((xk - lo) / w) as an integer, saturated far beyond any grid.
  RUBBLE_HD std::int64_t raw_coord(Real xk, int k) const {
    Real f = std::floor((xk - lo[k]) * inv_w[k]);
    const Real lim = Real(4.0e18);
    f = f < -lim ? -lim : f > lim ? lim : f;
    return std::int64_t(f);
  }
  // The cell coordinate along axis k: wrapped on periodic axes, clamped to
  // [0, G) on open ones.
  RUBBLE_HD std::int64_t wrap_or_clamp(std::int64_t c, int k) const {
    if (domain.periodic[k]) {
      c %= G[k];
      return c < 0 ? c + G[k] : c;
    }
    return c < 0 ? 0 : c > G[k] - 1 ? G[k] - 1 : c;
  }
  RUBBLE_HD std::int64_t cell_coord(Real xk, int k) const { return wrap_or_clamp(raw_coord(xk, k), k); }
  // Linear cell id (axis 0 fastest), 64-bit.
  RUBBLE_HD std::uint64_t cell_id(const Vec<D>& x) const {
    std::uint64_t lin = 0, stride = 1;
    for (int k = 0; k < D; ++k) {
      lin += std::uint64_t(cell_coord(x[k], k)) * stride;
      stride *= std::uint64_t(G[k]);
    }
    return lin;
  }
  // The storage slot of a cell.
  RUBBLE_HD std::uint64_t bucket_of_id(std::uint64_t id) const {
    return hashed ? (grid_cell_hash(id) & (buckets - 1)) : id;
  }
  RUBBLE_HD std::uint64_t bucket_of(const Vec<D>& x) const { return bucket_of_id(cell_id(x)); }
  // Kept for callers that name the slot "cell" (dense grids: the same).
  RUBBLE_HD std::uint64_t cell_of(const Vec<D>& x) const { return bucket_of(x); }
  std::uint64_t cell_count() const { return buckets; }

  // Distance along axis k from coordinate x to the slab of (unwrapped) cell
  // j; on open axes the edge cells reach to infinity (they hold the
  // clamped particles).
  RUBBLE_HD Real slab_distance(Real x, std::int64_t j, int k) const {
    const bool open = !domain.periodic[k];
    const Real a = lo[k] + Real(j) * width[k], b = a + width[k];
    if (x < a && !(open && j == 0)) return a - x;
    if (x > b && !(open && j == G[k] - 1)) return x - b;
    return Real(0);
  }

  // Calls f(cell id, d2) once for every cell with a point within r of x
  // (and a few more: the test is on boxes, with the slack), d2 the squared
  // distance from x to the cell's box (minimum image on periodic axes).
  // Cells in odometer order, axis 0 fastest.
  template <class F>
  RUBBLE_HD void for_each_cell(const Vec<D>& x, Real r, F&& f) const {
    std::int64_t first[D], last[D], j[D];
    bool full[D];
    Real xs[D];
    const Real rr = r + slack;
    for (int k = 0; k < D; ++k) {
      xs[k] = x[k];
      full[k] = false;
      if (domain.periodic[k]) {
        first[k] = raw_coord(x[k] - rr, k);
        last[k] = raw_coord(x[k] + rr, k);
        if (last[k] - first[k] + 1 >= G[k]) {
          // the whole axis, each cell once, at its nearest image
          full[k] = true;
          first[k] = 0;
          last[k] = G[k] - 1;
          const Real L = domain.length(k);
          xs[k] = x[k] - L * std::floor((x[k] - lo[k]) / L);
        }
      } else {
        first[k] = cell_coord(x[k] - rr, k);
        last[k] = cell_coord(x[k] + rr, k);
      }
      j[k] = first[k];
    }
    for (;;) {
      Real d2 = 0;
      std::uint64_t id = 0, stride = 1;
      for (int k = 0; k < D; ++k) {
        Real d = slab_distance(xs[k], j[k], k);
        if (full[k]) {
          const Real lo_img = slab_distance(xs[k], j[k] - G[k], k), hi_img = slab_distance(xs[k], j[k] + G[k], k);
          d = d < lo_img ? d : lo_img;
          d = d < hi_img ? d : hi_img;
        }
        d2 += d * d;
        id += std::uint64_t(wrap_or_clamp(j[k], k)) * stride;
        stride *= std::uint64_t(G[k]);
      }
      f(id, d2);
      int k = 0;
      for (; k < D; ++k) {
        if (++j[k] <= last[k]) break;
        j[k] = first[k];
      }
      if (k == D) return;
    }
  }
};

// Grid geometry for particles within [mn, mx] (open axes), radii of
// typical size r_typ (geometric mean) and largest r_max. Cells are
// w = max(r_typ / 2, r_max / 4) wide (on periodic axes a whole number of
// cells, at least w wide, spans the domain). At most max_cells slots: more
// cells are hashed into the largest power of two of slots not above
// max(64, max_cells).
// Throws std::invalid_argument for r_max <= 0 or non-finite, a non-finite
// position, or r_max above half a periodic length.
template <int D>
UniformGrid<D> make_uniform_grid(const Box<D>& domain, const Vec<D>& mn, const Vec<D>& mx, Real r_typ, Real r_max,
                                 double max_cells) {
  if (!(r_max > Real(0)) || !std::isfinite(r_max))
    throw std::invalid_argument("uniform grid: search radius must be positive and finite");
  if (!(r_typ > Real(0)) || !std::isfinite(r_typ) || r_typ > r_max) r_typ = r_max;
  const double w_typ = double(r_typ) / kGridCellsPerTypicalRadius, w_min = double(r_max) / kGridMaxCellsPerRadius;
  const Real w = Real(w_typ > w_min ? w_typ : w_min);
  // cells per axis at most 2^(60/D): cell ids fit 60 bits
  const double max_axis = std::ldexp(1.0, 60 / D);
  UniformGrid<D> g{};
  g.domain = domain;
  double magnitude = double(r_max);
  for (int k = 0; k < D; ++k) {
    if (domain.periodic[k]) {
      const Real L = domain.length(k);
      if (r_max > Real(0.5) * L)
        throw std::invalid_argument("uniform grid: a search radius exceeds half the periodic length along axis " +
                                    std::to_string(k));
      double n = std::floor(double(L) / double(w));
      n = n < 1 ? 1 : n > max_axis ? max_axis : n;
      g.G[k] = std::int64_t(n);
      g.lo[k] = domain.lo[k];
      g.width[k] = L / Real(g.G[k]);
      magnitude = std::fmax(magnitude, std::fmax(std::fabs(double(domain.lo[k])), std::fabs(double(domain.hi[k]))));
    } else {
      if (!std::isfinite(mn[k]) || !std::isfinite(mx[k]))
        throw std::invalid_argument("uniform grid: non-finite particle position");
      double n = std::floor((double(mx[k]) - double(mn[k])) / double(w)) + 1;
      n = n > max_axis ? max_axis : n;
      g.G[k] = std::int64_t(n);
      g.lo[k] = mn[k];
      g.width[k] = w;
      magnitude = std::fmax(magnitude, std::fmax(std::fabs(double(mn[k])), std::fabs(double(mx[k]))));
    }
    g.inv_w[k] = Real(1) / g.width[k];
    g.cells *= std::uint64_t(g.G[k]);
  }
  const double cap = max_cells > 64 ? max_cells : 64;
  if (double(g.cells) <= cap) {
    g.buckets = g.cells;
  } else {
    g.hashed = true;
    g.buckets = 1;
    while (double(g.buckets) * 2 <= cap) g.buckets *= 2;
  }
  g.slack = Real(1e-4 * double(w) + 64.0 * double(std::numeric_limits<Real>::epsilon()) * magnitude);
  return g;
}

// Stamp particle b's radius onto every cell its ball (radius Rb) touches:
// max_into(slot, Rb) for each, the caller keeping the largest per slot
// (an atomic maximum on the device). Afterwards the slot of every cell
// holds at least the R_b of each particle b whose ball touches the cell.
template <int D, class MaxInto>
RUBBLE_HD void stamp_reach(const UniformGrid<D>& g, const Vec<D>& xb, Real Rb, MaxInto&& max_into) {
  const Real m = Rb + g.slack;
  g.for_each_cell(xb, Rb, [&](std::uint64_t id, Real d2) {
    if (d2 < m * m) max_into(g.bucket_of_id(id), Rb);
  });
}

template <int D>
struct GridNeighbors {
  UniformGrid<D> grid;
  const Vec<D>* x = nullptr;
  const Real* R = nullptr;                // search radii
  const std::uint32_t* order = nullptr;   // particle indices sorted by slot
  const std::uint32_t* start = nullptr;   // per slot: first position in `order`
  const std::uint32_t* end = nullptr;     // per slot: one past the last
  const Real* cell_rmax = nullptr;        // per slot: largest R of its particles
  const Real* cell_reach = nullptr;       // per slot: largest R of a ball touching it
  std::uint32_t a = 0;                    // the particle whose neighbours are visited

  // Offers every b with |x_a - x_b| < max(R_a, R_b), b != a, once.
  template <class F>
  RUBBLE_HD void operator()(F&& f) const {
    visit(f, nullptr);
  }

  // The same; adds the entries it tests (the candidates) to *scanned when given.
  template <class F>
  RUBBLE_HD void visit(F&& f, std::uint64_t* scanned) const {
    const Vec<D> xa = x[a];
    const Real Ra = R[a];
    const Real halo = cell_reach[grid.bucket_of(xa)];
    const Real reach = Ra > halo ? Ra : halo;
    grid.for_each_cell(xa, reach, [&](std::uint64_t id, Real d2) {
      const std::uint64_t s = grid.bucket_of_id(id);
      const std::uint32_t j0 = start[s], j1 = end[s];
      if (j0 == j1) return;
      const Real rc = cell_rmax[s], m = (Ra > rc ? Ra : rc) + grid.slack;
      if (d2 >= m * m) return;
      if (scanned) *scanned += std::uint64_t(j1 - j0);
      for (std::uint32_t j = j0; j < j1; ++j) {
        const std::uint32_t b = order[j];
        if (b == a) continue;
        if (grid.hashed && grid.cell_id(x[b]) != id) continue;  // another cell of the slot
        const Real rb = R[b], rm = Ra > rb ? Ra : rb;
        if (norm2(grid.domain.separation(xa, x[b])) < rm * rm) f(b);
      }
    });
  }

  // Offers every b != a with |x_a - x_b| < R_a (and, by a rounding margin
  // of 64 ulps of R_a^2, a few at R_a itself), once, in cell order: the
  // neighbours a loop needs when it looks no further than a's own radius
  // (summation density: h <= R_a).
  template <class F>
  RUBBLE_HD void visit_own_radius(F&& f, std::uint64_t* scanned) const {
    const Vec<D> xa = x[a];
    const Real Ra = R[a];
    const Real m = Ra + grid.slack, r2 = Ra * Ra * (Real(1) + Real(64) * std::numeric_limits<Real>::epsilon());
    grid.for_each_cell(xa, Ra, [&](std::uint64_t id, Real d2) {
      if (d2 >= m * m) return;
      const std::uint64_t s = grid.bucket_of_id(id);
      const std::uint32_t j0 = start[s], j1 = end[s];
      if (scanned) *scanned += std::uint64_t(j1 - j0);
      for (std::uint32_t j = j0; j < j1; ++j) {
        const std::uint32_t b = order[j];
        if (b == a) continue;
        if (grid.hashed && grid.cell_id(x[b]) != id) continue;
        if (norm2(grid.domain.separation(xa, x[b])) < r2) f(b);
      }
    });
  }
};

// The visitor restricted to a's own radius, as an `each` of particle_rates.hpp.
template <int D>
struct GridOwnRadius {
  GridNeighbors<D> g;
  template <class F>
  RUBBLE_HD void operator()(F&& f) const {
    g.visit_own_radius(f, nullptr);
  }
};

}  // namespace rubble
