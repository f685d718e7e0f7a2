#pragma once
// The per-node steps of the Barnes-Hut octree build (gravity/octree.hpp),
// as RUBBLE_HD functions: the CPU's recursive build (solver/src/octree.cpp)
// calls them, and so does a level-synchronous build that a GPU can run one
// thread per node (octree_build_by_levels below, here driven by host loops;
// the CUDA driver is the next step of issue #6). Both builds produce the
// same depth-first node array: the unit tests compare them node by node.
//
// A node is a key prefix: the sorted particles [begin, end) whose Morton
// keys share their first 3*level bits.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/gravity/octree.hpp"
#include "rubble/neighbors/morton.hpp"
#include "rubble/physics/gravity.hpp"

namespace rubble {

constexpr std::uint32_t kOctreeMaxLevel = std::uint32_t(morton_bits<3>);  // 21 levels of 3 key bits

// The octant (3 key bits) that a key selects below a cell of `level`
// (0 <= level < kOctreeMaxLevel).
RUBBLE_HD_INLINE unsigned octree_octant(std::uint64_t key, std::uint32_t level) {
  return unsigned(key >> (3 * (kOctreeMaxLevel - 1 - level))) & 7u;
}

// Inverse of spread_bits_by_2 (morton.hpp): gather every third bit.
RUBBLE_HD_INLINE std::uint32_t octree_compact_bits(std::uint64_t v) {
  v &= 0x1249249249249249ull;
  v = (v ^ (v >> 2)) & 0x10C30C30C30C30C3ull;
  v = (v ^ (v >> 4)) & 0x100F00F00F00F00Full;
  v = (v ^ (v >> 8)) & 0x001F0000FF0000FFull;
  v = (v ^ (v >> 16)) & 0x001F00000000FFFFull;
  v = (v ^ (v >> 32)) & 0x00000000001FFFFFull;
  return std::uint32_t(v);
}

// The level a node of sorted range [begin, end) that starts at `level`
// really splits at: levels where all its particles fall into one octant
// add nothing and are skipped. Sets `leaf` (at most leaf_size particles,
// or particles sharing one finest-level key).
RUBBLE_HD_INLINE std::uint32_t octree_split_level(const std::uint64_t* keys, std::uint32_t begin, std::uint32_t end,
                                                  std::uint32_t level, std::uint32_t leaf_size, bool& leaf) {
  const std::uint32_t count = end - begin;
  while (count > leaf_size && level < kOctreeMaxLevel &&
         octree_octant(keys[begin], level) == octree_octant(keys[end - 1], level))
    ++level;
  leaf = count <= leaf_size || level == kOctreeMaxLevel;
  return level;
}

// The children of an inner node split at `level`: up to 8 sorted ranges,
// one per non-empty octant, in octant order. first[c] is the first particle
// of child c; first[count] = end. Returns the number of children.
RUBBLE_HD_INLINE int octree_children(const std::uint64_t* keys, std::uint32_t begin, std::uint32_t end,
                                     std::uint32_t level, std::uint32_t first[9]) {
  int n = 0;
  for (std::uint32_t f = begin; f < end;) {
    const unsigned oct = octree_octant(keys[f], level);
    // first particle of a later octant (binary search: keys are sorted)
    std::uint32_t lo = f + 1, hi = end;
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (octree_octant(keys[mid], level) == oct) lo = mid + 1;
      else hi = mid;
    }
    first[n++] = f;
    f = lo;
  }
  first[n] = end;
  return n;
}

// The cell of a node's key prefix: corners in the key box.
RUBBLE_HD_INLINE void octree_cell_bounds(const Box<3>& box, std::uint64_t key, std::uint32_t level, Vec<3>& lo,
                                         Vec<3>& hi) {
  const std::uint32_t shift = kOctreeMaxLevel - level;
  for (int k = 0; k < 3; ++k) {
    const std::uint64_t cell = std::uint64_t(octree_compact_bits(key >> k)) >> shift;
    const Real len = (box.hi[k] - box.lo[k]) / Real(std::uint64_t(1) << level);
    lo[k] = box.lo[k] + Real(cell) * len;
    hi[k] = lo[k] + len;
  }
}

// Everything of a node but its place in the array (skip): mass, centre of
// mass, quadrupole, b_max, eps_max, opening radius. For an inner node,
// `children` lists its children (already finished); a leaf sums its
// particles. x, m, eps are in sorted order.
RUBBLE_HD_INLINE void octree_finish_node(OctreeNode& nd, const OctreeNode* const* children, int n_children,
                                         const Vec<3>* x, const Real* m, const Real* eps, const Box<3>& key_box,
                                         std::uint64_t first_key, Real theta) {
  Real mass = 0;
  Vec<3> mx = Vec<3>::zero();
  Real quad[6] = {0, 0, 0, 0, 0, 0};
  if (nd.leaf) {
    for (std::uint32_t s = nd.begin; s < nd.end; ++s) {
      mass += m[s];
      mx += x[s] * m[s];
    }
  } else {
    for (int c = 0; c < n_children; ++c) {
      mass += children[c]->mass;
      mx += children[c]->com * children[c]->mass;
    }
    const Vec<3> com = mass > Real(0) ? mx * (Real(1) / mass) : children[0]->com;
    for (int c = 0; c < n_children; ++c) {
      for (int j = 0; j < 6; ++j) quad[j] += children[c]->quad[j];
      quadrupole_add_point(quad, children[c]->mass, children[c]->com - com);
    }
  }
  Vec<3> lo, hi;
  octree_cell_bounds(key_box, first_key, nd.level, lo, hi);
  Real side = 0;
  Vec<3> centre;
  for (int k = 0; k < 3; ++k) {
    centre[k] = Real(0.5) * (lo[k] + hi[k]);
    side = side > hi[k] - lo[k] ? side : hi[k] - lo[k];
  }
  nd.mass = mass;
  nd.com = mass > Real(0) ? mx * (Real(1) / mass) : centre;  // massless: expand about the cell centre
  Real b_max = 0, eps_max = 0;
  for (std::uint32_t s = nd.begin; s < nd.end; ++s) {
    const Vec<3> d = x[s] - nd.com;
    const Real d2 = norm2(d);
    b_max = b_max > d2 ? b_max : d2;
    eps_max = eps_max > eps[s] ? eps_max : eps[s];
    if (nd.leaf) quadrupole_add_point(quad, m[s], d);
  }
  for (int j = 0; j < 6; ++j) nd.quad[j] = quad[j];
  nd.b_max = std::sqrt(b_max);
  nd.eps_max = eps_max;
  nd.open_radius = opening_radius(side, nd.com - centre, theta);
}

// The cube the octree's keys are quantised in: the padded bounding box
// (spatial_order.hpp), made a cube about its centre (octree cells must be
// cubes; see Octree::build).
inline Box<3> octree_key_box(const Box<3>& bounding) {
  Box<3> b = bounding;
  Real side = 0;
  for (int k = 0; k < 3; ++k) side = side > b.hi[k] - b.lo[k] ? side : b.hi[k] - b.lo[k];
  for (int k = 0; k < 3; ++k) {
    const Real mid = Real(0.5) * (b.lo[k] + b.hi[k]);
    b.lo[k] = mid - Real(0.5) * side;
    b.hi[k] = mid + Real(0.5) * side;
  }
  return b;
}

// ---- the level-synchronous build ------------------------------------------
// Level l of the breadth-first discovery holds the nodes found there; each
// step below is one loop over a level's nodes with a body that touches one
// node (one GPU thread each): the host driver octree_build_by_levels and
// the CUDA driver run the same bodies.

// A node waiting to be discovered: its sorted range, the level it starts
// at, its parent's index in the previous level.
struct OctreePending {
  std::uint32_t begin, end, level, parent;
};

struct OctreeLevelNode {
  OctreeNode node;
  std::uint32_t parent;       // index in the previous level (0xFFFFFFFF: root)
  std::uint32_t n_children;   // 0 for a leaf
  std::uint32_t first_child;  // index in the next level (children are contiguous)
  std::uint32_t size;         // nodes in the subtree
  std::uint32_t id;           // depth-first index
};

// Discovery: the node of a pending range; returns its number of children
// (their ranges in first[0..count]).
RUBBLE_HD_INLINE std::uint32_t octree_discover(const std::uint64_t* keys, const OctreePending& p,
                                               std::uint32_t leaf_size, OctreeLevelNode& out, std::uint32_t first[9]) {
  bool leaf = false;
  const std::uint32_t level = octree_split_level(keys, p.begin, p.end, p.level, leaf_size, leaf);
  OctreeNode nd{};
  nd.begin = p.begin;
  nd.end = p.end;
  nd.level = level;
  nd.leaf = leaf ? 1u : 0u;
  out.node = nd;
  out.parent = p.parent;
  out.n_children = leaf ? 0u : std::uint32_t(octree_children(keys, p.begin, p.end, level, first));
  out.first_child = 0;
  out.size = 1;
  out.id = 0;
  return out.n_children;
}

// Depth-first ids of a node's children: each follows its parent and the
// subtrees of its earlier siblings.
RUBBLE_HD_INLINE void octree_number_children(const OctreeLevelNode& f, OctreeLevelNode* next_level) {
  std::uint32_t id = f.id + 1;
  for (std::uint32_t c = 0; c < f.n_children; ++c) {
    OctreeLevelNode& ch = next_level[f.first_child + c];
    ch.id = id;
    id += ch.size;
  }
}

// Moments of a node whose children (in the next level) are finished; its
// skip index; returns the finished node.
RUBBLE_HD_INLINE const OctreeNode& octree_finish_level_node(OctreeLevelNode& f, const OctreeLevelNode* next_level,
                                                            const std::uint64_t* keys, const Vec<3>* x, const Real* m,
                                                            const Real* eps, const Box<3>& key_box, Real theta) {
  const OctreeNode* children[8];
  for (std::uint32_t c = 0; c < f.n_children; ++c) children[c] = &next_level[f.first_child + c].node;
  octree_finish_node(f.node, children, int(f.n_children), x, m, eps, key_box, keys[f.node.begin], theta);
  f.node.skip = f.id + f.size;
  return f.node;
}

// The host driver: keys, x, m, eps sorted by key, key_box the cube they
// were quantised in. Returns the depth-first node array of the recursive
// build (Octree), bit for bit (test_octree_build.cpp).
inline std::vector<OctreeNode> octree_build_by_levels(const std::uint64_t* keys, const Vec<3>* x, const Real* m,
                                                      const Real* eps, std::uint32_t n, const Box<3>& key_box,
                                                      Real theta, std::uint32_t leaf_size) {
  if (n == 0) return {};
  std::vector<std::vector<OctreeLevelNode>> levels;
  // 1. discovery, one level at a time (on a GPU, next-level offsets come
  //    from an exclusive scan of the child counts)
  std::vector<OctreePending> frontier = {{0, n, 0, 0xFFFFFFFFu}};
  while (!frontier.empty()) {
    std::vector<OctreeLevelNode> level(frontier.size());
    std::vector<OctreePending> next;
    for (std::size_t i = 0; i < frontier.size(); ++i) {
      std::uint32_t first[9];
      const std::uint32_t c = octree_discover(keys, frontier[i], leaf_size, level[i], first);
      level[i].first_child = std::uint32_t(next.size());
      for (std::uint32_t k = 0; k < c; ++k)
        next.push_back({first[k], first[k + 1], level[i].node.level + 1, std::uint32_t(i)});
    }
    levels.push_back(std::move(level));
    frontier = std::move(next);
  }
  // 2. subtree sizes, bottom up (on a GPU: atomic adds into the parents)
  for (std::size_t l = levels.size(); l-- > 1;)
    for (const OctreeLevelNode& f : levels[l]) levels[l - 1][f.parent].size += f.size;
  // 3. depth-first ids, top down
  levels[0][0].id = 0;
  for (std::size_t l = 0; l + 1 < levels.size(); ++l)
    for (const OctreeLevelNode& f : levels[l]) octree_number_children(f, levels[l + 1].data());
  // 4. moments bottom up, into the depth-first array
  std::vector<OctreeNode> out(levels[0][0].size);
  for (std::size_t l = levels.size(); l-- > 0;) {
    const OctreeLevelNode* next = l + 1 < levels.size() ? levels[l + 1].data() : nullptr;
    for (OctreeLevelNode& f : levels[l]) {
      const OctreeNode& nd = octree_finish_level_node(f, next, keys, x, m, eps, key_box, theta);
      out[f.id] = nd;
    }
  }
  return out;
}

}  // namespace rubble
