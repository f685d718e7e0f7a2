#pragma once
// The spatial order (DESIGN.md principle 5): at each rebuild the particles
// are sorted by the Morton key of their position, so that particles close in
// space are close in memory. The neighbour search (cell_list.hpp) and the
// Barnes-Hut octree both work over this one order.
//
// Typical use:
//   const Box<D> bb = bounding_box(x, n, domain);
//   const auto perm = spatial_sort_permutation(x, n, bb);
//   store.permute(perm);   // new particle i is old particle perm[i]
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <utility>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/neighbors/morton.hpp"

namespace rubble {

// The box the keys are quantised in. On open axes: the particles' bounds,
// padded slightly so that the largest coordinate lies strictly inside (keys
// then use the full resolution). On periodic axes: the domain, so that keys
// do not depend on where the particles happen to be.
template <int D>
Box<D> bounding_box_from_extent(const Box<D>& domain, const Vec<D>& mn, const Vec<D>& mx) {
  Box<D> b = domain;
  for (int k = 0; k < D; ++k) {
    if (domain.periodic[k]) continue;
    // Pad by a small fraction of the extent, but never less than a few
    // rounding units of the coordinates (or anything at all if they are 0).
    const Real eps = std::numeric_limits<Real>::epsilon();
    const Real scale = std::max(std::abs(mn[k]), std::abs(mx[k]));
    Real pad = std::max(Real(1e-6) * (mx[k] - mn[k]), Real(4) * eps * scale);
    pad = std::max(pad, std::numeric_limits<Real>::min());
    b.lo[k] = mn[k] - pad;
    b.hi[k] = mx[k] + pad;
  }
  return b;
}

template <int D>
Box<D> bounding_box(const Vec<D>* x, std::size_t n, const Box<D>& domain) {
  if (n == 0) return domain;
  Vec<D> mn = x[0], mx = x[0];
  for (std::size_t i = 1; i < n; ++i)
    for (int k = 0; k < D; ++k) {
      mn[k] = std::min(mn[k], x[i][k]);
      mx[k] = std::max(mx[k], x[i][k]);
    }
  return bounding_box_from_extent<D>(domain, mn, mx);  // the particles' extent (the CUDA backend reduces on the device)
}

// Morton key of every position, quantised within box.
template <int D>
std::vector<std::uint64_t> morton_keys(const Vec<D>* x, std::size_t n, const Box<D>& box) {
  std::vector<std::uint64_t> keys(n);
  for (std::size_t i = 0; i < n; ++i) keys[i] = morton_key<D>(x[i], box);
  return keys;
}

// perm[i] = index of the element that goes to sorted position i, sorting by
// key; equal keys keep their input order (stable). Already sorted input (the
// usual case from one rebuild to the next) costs one pass.
inline std::vector<std::uint32_t> sort_permutation(const std::vector<std::uint64_t>& keys) {
  if (keys.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("sort_permutation: more than 2^32 - 1 particles");
  std::vector<std::uint32_t> perm(keys.size());
  std::iota(perm.begin(), perm.end(), std::uint32_t(0));
  if (std::is_sorted(keys.begin(), keys.end())) return perm;
  // Sorting (key, index) pairs is stable by construction and faster than
  // std::stable_sort on an index array.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> kv(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) kv[i] = {keys[i], std::uint32_t(i)};
  std::sort(kv.begin(), kv.end());
  for (std::size_t i = 0; i < kv.size(); ++i) perm[i] = kv[i].second;
  return perm;
}

// The permutation that puts particles in Morton order within box (see
// sort_permutation for its meaning).
template <int D>
std::vector<std::uint32_t> spatial_sort_permutation(const Vec<D>* x, std::size_t n, const Box<D>& box) {
  return sort_permutation(morton_keys(x, n, box));
}

}  // namespace rubble
