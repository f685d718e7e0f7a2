// Barnes-Hut octree: build over the Morton order and the OpenMP walk.
// See rubble/gravity/octree.hpp for the structure and physics/gravity.hpp
// for the interaction, the multipoles and the opening criterion.
#include "rubble/gravity/octree.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "rubble/neighbors/morton.hpp"
#include "rubble/neighbors/spatial_order.hpp"

namespace rubble {

namespace {

constexpr std::uint32_t kMaxLevel = std::uint32_t(morton_bits<3>);  // 21 levels of 3 key bits

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("Octree::build: " + what); }

// The octant (3 key bits) that a key selects below a cell of `level`
// (0 <= level < kMaxLevel): key bits 3(20 - level) .. 3(20 - level) + 2.
inline unsigned octant(std::uint64_t key, std::uint32_t level) {
  return unsigned(key >> (3 * (kMaxLevel - 1 - level))) & 7u;
}

// Inverse of detail::spread_bits_by_2 (morton.hpp): gather every third bit.
inline std::uint32_t compact_bits_by_2(std::uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10C30C30C30C30C3ull;
  v = (v ^ (v >> 4)) & 0x100F00F00F00F00Full;
  v = (v ^ (v >> 8)) & 0x001F0000FF0000FFull;
  v = (v ^ (v >> 16)) & 0x001F00000000FFFFull;
  v = (v ^ (v >> 32)) & 0x00000000001FFFFFull;
  return std::uint32_t(v);
}

}  // namespace

Octree::Octree(const OctreeOptions& options) : options_(options) {}

void Octree::build(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n) {
  if (!(options_.theta >= Real(0) && options_.theta <= Real(1)))
    fail("theta = " + std::to_string(double(options_.theta)) + " is outside [0, 1]");
  if (options_.leaf_size == 0) fail("leaf_size must be >= 1");
  if (n >= std::numeric_limits<std::uint32_t>::max()) fail("more than 2^32 - 2 particles");

  std::size_t bad = n;
#pragma omp parallel for reduction(min : bad) if (n > 4096)
  for (std::size_t i = 0; i < n; ++i) {
    bool ok = std::isfinite(m[i]) && m[i] >= Real(0);
    if (eps) ok = ok && std::isfinite(eps[i]) && eps[i] >= Real(0);
    for (int k = 0; k < 3; ++k) ok = ok && std::isfinite(x[i][k]);
    if (!ok) bad = std::min(bad, i);
  }
  if (bad < n)
    fail("particle " + std::to_string(bad) +
         " has a non-finite position or a negative or non-finite mass or softening length");

  // The same keys as the neighbour search: Morton keys within the padded
  // bounding box of the particles (open axes).
  box_ = bounding_box<3>(x, n, Box<3>{});
  std::vector<std::uint64_t> keys(n);
#pragma omp parallel for if (n > 4096)
  for (std::size_t i = 0; i < n; ++i) keys[i] = morton_key<3>(x[i], box_);
  order_ = sort_permutation(keys);

  keys_.resize(n);
  x_.resize(n);
  m_.resize(n);
  eps_.resize(n);
#pragma omp parallel for if (n > 4096)
  for (std::size_t s = 0; s < n; ++s) {
    const std::uint32_t i = order_[s];
    keys_[s] = keys[i];
    x_[s] = x[i];
    m_[s] = m[i];
    eps_[s] = eps ? eps[i] : Real(0);
  }

  nodes_.clear();
  leaves_ = 0;
  if (n > 0) {
    nodes_.reserve(2 * n / std::max<std::uint32_t>(options_.leaf_size, 1) + 16);
    build_node(0, std::uint32_t(n), 0);
  }
}

// Emit the node of sorted range [begin, end), whose keys share their first
// 3*level bits, and its subtree; returns its index.
std::uint32_t Octree::build_node(std::uint32_t begin, std::uint32_t end, std::uint32_t level) {
  const std::uint32_t count = end - begin;
  // Levels where all particles fall into one octant add nothing: skip them.
  while (count > options_.leaf_size && level < kMaxLevel &&
         octant(keys_[begin], level) == octant(keys_[end - 1], level))
    ++level;
  const bool leaf = count <= options_.leaf_size || level == kMaxLevel;

  const std::uint32_t id = std::uint32_t(nodes_.size());
  {
    OctreeNode nd{};
    nd.begin = begin;
    nd.end = end;
    nd.level = level;
    nd.leaf = leaf ? 1u : 0u;
    nodes_.push_back(nd);
  }

  // Mass and centre of mass: from the particles of a leaf, from the children
  // of an inner node (whose quadrupoles are shifted to the new centre).
  Real mass = 0;
  Vec<3> mx = Vec<3>::zero();
  Real quad[6] = {0, 0, 0, 0, 0, 0};
  if (leaf) {
    ++leaves_;
    for (std::uint32_t s = begin; s < end; ++s) {
      mass += m_[s];
      mx += x_[s] * m_[s];
    }
  } else {
    std::uint32_t children[8];
    int n_children = 0;
    for (std::uint32_t first = begin; first < end;) {
      const unsigned oct = octant(keys_[first], level);
      const std::uint32_t last = std::uint32_t(
          std::partition_point(keys_.begin() + first, keys_.begin() + end,
                               [&](std::uint64_t key) { return octant(key, level) == oct; }) -
          keys_.begin());
      children[n_children++] = build_node(first, last, level + 1);
      first = last;
    }
    for (int c = 0; c < n_children; ++c) {
      const OctreeNode& ch = nodes_[children[c]];
      mass += ch.mass;
      mx += ch.com * ch.mass;
    }
    const Vec<3> com = mass > Real(0) ? mx * (Real(1) / mass) : nodes_[children[0]].com;
    for (int c = 0; c < n_children; ++c) {
      const OctreeNode& ch = nodes_[children[c]];
      for (int j = 0; j < 6; ++j) quad[j] += ch.quad[j];
      quadrupole_add_point(quad, ch.mass, ch.com - com);
    }
  }

  // The cell: key prefix -> integer cell coordinates at this level.
  Real side = 0;
  Vec<3> centre;
  const std::uint32_t shift = kMaxLevel - level;
  for (int k = 0; k < 3; ++k) {
    const std::uint64_t cell = std::uint64_t(compact_bits_by_2(keys_[begin] >> k)) >> shift;
    const Real len = (box_.hi[k] - box_.lo[k]) / Real(std::uint64_t(1) << level);
    centre[k] = box_.lo[k] + (Real(cell) + Real(0.5)) * len;
    side = std::max(side, len);
  }

  OctreeNode& nd = nodes_[id];
  nd.mass = mass;
  if (mass > Real(0)) {
    nd.com = mx * (Real(1) / mass);
  } else {  // massless particles: expand about the cell centre
    nd.com = centre;
  }
  Real b_max = 0, eps_max = 0;
  for (std::uint32_t s = begin; s < end; ++s) {
    const Vec<3> d = x_[s] - nd.com;
    b_max = std::max(b_max, norm2(d));
    eps_max = std::max(eps_max, eps_[s]);
    if (leaf) quadrupole_add_point(quad, m_[s], d);
  }
  for (int j = 0; j < 6; ++j) nd.quad[j] = quad[j];
  nd.b_max = std::sqrt(b_max);
  nd.eps_max = eps_max;
  nd.open_radius = opening_radius(side, norm(nd.com - centre), options_.theta);
  nd.skip = std::uint32_t(nodes_.size());
  return id;
}

OctreeView Octree::view() const {
  OctreeView v;
  v.nodes = nodes_.data();
  v.node_count = std::uint32_t(nodes_.size());
  v.x = x_.data();
  v.m = m_.data();
  v.eps = eps_.data();
  v.kernel = options_.kernel;
  v.order = options_.order;
  return v;
}

void Octree::field(Real G, Vec<3>* acc, Real* phi) const {
  const std::size_t n = x_.size();
  const OctreeView t = view();
  std::uint64_t multipoles = 0, pairs = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : multipoles, pairs)
  for (std::size_t s = 0; s < n; ++s) {
    WalkCounts c;
    const GravityField f = octree_field(t, x_[s], eps_[s], std::uint32_t(s), &c);
    multipoles += c.multipoles;
    pairs += c.pairs;
    const std::uint32_t i = order_[s];
    acc[i] = f.a * G;
    if (phi) phi[i] = f.phi * G;
  }
  counts_.multipoles = multipoles;
  counts_.pairs = pairs;
}

GravityField Octree::field_at(const Vec<3>& x, Real eps) const {
  return octree_field(view(), x, eps, 0xFFFFFFFFu);
}

}  // namespace rubble
