#pragma once
// Neighbour search over the spatial (Morton) order.
//
// Criterion: b is a neighbour of a iff a != b and
//     |x_a - x_b| < max(H_a, H_b)
// (minimum image on periodic axes). It is symmetric, and H may differ
// between particles by any factor.
//
// How: build() sorts the particles by Morton key and cuts the sorted order
// into cells, each a contiguous range of at most max_cell_size particles
// (more only for particles sharing one finest-level key). The cells are the
// leaves of the tree the keys define (each level halves its parent's region
// along the next axis; every D levels are one octree level): a node is
// split only while it holds too many particles, so empty space costs
// nothing and dense clusters get small cells - memory is O(n) however
// clustered the set is. Every node stores the tight bounds of its particles
// and their largest H.
// find_neighbors() takes the particles a group at a time (a subtree of at
// most max_group_size particles), collects the cells within reach of the
// group (distance < max of the two H_max) by walking the tree from the
// root, then tests each particle against the cells within its own reach.
// With one fixed cell size, a particle with a 10x larger H would scan 1000x
// more cells; here the walk skips whole empty or far regions at once.
//
// Periodic axes use the minimum image, for the bounds as for the pairs, so a
// pair is seen exactly once whatever the box size; this is exact as long as
// H <= L/2 on every periodic axis, which build() checks.
//
// The functions are defined in solver/src/cell_list.cpp for D = 1, 2, 3.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/neighbors/search_radius.hpp"

namespace rubble {

// The search radii both backends use: rubble/neighbors/search_radius.hpp.

// The neighbour lists of n particles, each in ascending order, as the
// search threads wrote them, in blocks owned by the thread that found them.
// Nothing is copied into one array (that copy doubled the peak memory of
// the lists), and a thread that fills a block starts a new one instead of
// growing the old (growing by reallocation held the old and the new buffer
// at once, and left up to a quarter of the room spare). Blocks persist from
// one search to the next and each thread reuses its own in order, so a run
// settles at about the lists' size plus an eighth (issue #14: memory per
// particle).
//
// Each list is stored as 16-bit differences (issue #14: the lists were half
// of a particle's memory). The particles are in spatial (Morton) order, so a
// neighbour's index is close to the previous one's: particle a's list
// j_0 < j_1 < ... is written as zigzag(j_0 - a), then j_k - j_(k-1), one
// 16-bit unit each when the value lies in 1 ... 65535; any other value (a
// jump across a large block of the Morton order, or a list out of order) is
// an escape: the unit 0 followed by j in two units (low, high). Decoding
// needs one add per entry and a branch that is almost never taken; any list
// of indices round-trips exactly, an unordered one only takes more room.
class NeighborLists {
 public:
  std::size_t size() const { return begin_.size(); }
  std::size_t count(std::size_t i) const { return count_[i]; }
  // Calls f(j) for each neighbour j of particle i, in ascending order. The
  // list is decoded a chunk at a time into a small local array and f is
  // called from one plain loop over it: decoding inside the loop (f inlined
  // at two call sites, the add chain between calls) made the force loop
  // over a third slower.
  template <class F>
  void for_each(std::size_t i, F&& f) const {
    std::uint32_t left = count_[i];
    if (left == 0) return;
    const std::uint16_t* p = blocks_[block_[i]].data() + begin_[i];
    constexpr std::uint32_t kChunk = 128;
    std::uint32_t buf[kChunk];
    // the first entry: zigzag difference from the owner
    std::uint32_t j = std::uint32_t(i);
    bool first = true;
    while (left > 0) {
      const std::uint32_t n = left < kChunk ? left : kChunk;
      for (std::uint32_t k = 0; k < n; ++k) {
        const std::uint32_t c = *p++;
        if (c == 0) [[unlikely]] {
          j = std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 16);
          p += 2;
        } else if (first) [[unlikely]] {
          j = (c & 1u) ? j - ((c + 1) >> 1) : j + (c >> 1);
        } else {
          j += c;
        }
        first = false;
        buf[k] = j;
      }
      for (std::uint32_t k = 0; k < n; ++k) f(buf[k]);
      left -= n;
    }
  }
  // particle i's list as a vector (tests, rare uses)
  std::vector<std::uint32_t> copy(std::size_t i) const {
    std::vector<std::uint32_t> out;
    out.reserve(count_[i]);
    for_each(i, [&](std::uint32_t j) { out.push_back(j); });
    return out;
  }
  // Replaces the lists by the given ones (list i belongs to particle i; any
  // indices below 2^32 - 1, in any order): tests of the encoding.
  void assign(const std::vector<std::vector<std::uint32_t>>& lists);
  // entries over all lists
  std::size_t total() const {
    std::size_t t = 0;
    for (std::uint32_t c : count_) t += c;
    return t;
  }
  // 16-bit units the lists take (one per entry, three per escape)
  std::size_t units() const {
    std::size_t u = 0;
    for (std::size_t i = 0; i < size(); ++i) {
      if (count_[i] == 0) continue;
      const std::uint16_t* p = blocks_[block_[i]].data() + begin_[i];
      std::size_t k = 0;
      for (std::uint32_t e = 0; e < count_[i]; ++e) k += (p[k] == 0) ? 3 : 1;
      u += k;
    }
    return u;
  }
  // bytes held: the blocks (with their spare room) and the per-particle index
  std::size_t bytes() const {
    std::size_t b = (begin_.capacity() + count_.capacity() + block_.capacity()) * sizeof(std::uint32_t);
    for (const auto& blk : blocks_) b += blk.capacity() * sizeof(std::uint16_t);
    return b;
  }
  std::size_t block_count() const { return blocks_.size(); }

  // Units needed to store `list` (n entries) of particle `owner`; and the
  // encoding itself into `out` (room for encoded_units), returning the
  // units written.
  static std::size_t encoded_units(const std::uint32_t* list, std::size_t n, std::uint32_t owner) {
    std::size_t u = 0;
    std::uint32_t prev = owner;
    for (std::size_t k = 0; k < n; ++k) {
      u += code_of(list[k], prev, k == 0) ? 1 : 3;
      prev = list[k];
    }
    return u;
  }
  static std::size_t encode(const std::uint32_t* list, std::size_t n, std::uint32_t owner, std::uint16_t* out) {
    std::size_t u = 0;
    std::uint32_t prev = owner;
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t c = code_of(list[k], prev, k == 0);
      if (c != 0) {
        out[u++] = std::uint16_t(c);
      } else {
        out[u++] = 0;
        out[u++] = std::uint16_t(list[k] & 0xFFFFu);
        out[u++] = std::uint16_t(list[k] >> 16);
      }
      prev = list[k];
    }
    return u;
  }

 private:
  template <int D>
  friend class CellList;
  // The 16-bit code of entry j after `prev` (the owner for the first
  // entry: zigzag of the signed difference), or 0 when it needs an escape.
  static std::uint32_t code_of(std::uint32_t j, std::uint32_t prev, bool first) {
    std::uint64_t c;
    if (first)
      c = j >= prev ? 2 * std::uint64_t(j - prev) : 2 * std::uint64_t(prev - j) - 1;
    else
      c = j > prev ? std::uint64_t(j - prev) : 0;
    return c <= 0xFFFFu ? std::uint32_t(c) : 0;
  }
  std::vector<std::vector<std::uint16_t>> blocks_;         // all blocks, of every thread
  std::vector<std::vector<std::uint32_t>> thread_blocks_;  // per search thread: its blocks in order of use
  std::vector<std::uint32_t> begin_, count_;               // per particle, in input order
  std::vector<std::uint32_t> block_;                       // the block holding the list
};

template <int D>
class CellList {
 public:
  // Tuning only (any values give the same neighbours): the most particles
  // per cell, and per group of particles that share one tree walk.
  explicit CellList(std::uint32_t max_cell_size = 32, std::uint32_t max_group_size = 64)
      : max_cell_size_(max_cell_size ? max_cell_size : 1), max_group_size_(max_group_size) {}

  // Build over n particles with support radii H (ideally already in spatial
  // order: then the internal sort is a single check). Particle indices in
  // the results are indices into x and H. Positions on periodic axes may lie
  // anywhere in [lo, hi) (others are wrapped into it). Throws std::invalid_argument on non-finite
  // positions, negative or non-finite H, a periodic axis with hi <= lo, or
  // H > L/2 on a periodic axis.
  void build(const Vec<D>* x, const Real* H, std::size_t n, const Box<D>& box);

  // All pairs within max(H_a, H_b), self excluded. OpenMP-parallel over
  // groups; the result does not depend on the number of threads.
  void find_neighbors(NeighborLists& out) const;

  std::size_t size() const { return x_.size(); }
  std::size_t cell_count() const { return cells_.size(); }
  // order()[s] = input index of the particle at sorted position s.
  const std::vector<std::uint32_t>& order() const { return order_; }

 private:
  // One node of the hierarchy: a contiguous range [begin, end) of the sorted
  // particles. Nodes are stored depth first; `skip` is the index just past
  // the node's subtree, so a walk needs no stack.
  struct Node {
    Vec<D> lo, hi;  // tight bounds of the particles' (wrapped) positions
    Real h_max;     // largest H in the node
    std::uint32_t begin, end, skip;
    bool is_cell;   // leaf
  };

  std::uint32_t build_node(std::uint32_t begin, std::uint32_t end, int level, bool in_group);

  std::uint32_t max_cell_size_, max_group_size_;
  Box<D> box_;                          // the domain (periodicity, lengths)
  Real wrap_[D] = {};                   // L on periodic axes, +infinity on open ones
  Real slack_[D] = {};                  // rounding allowance of the pruning test
  std::vector<std::uint32_t> order_;    // sorted position -> input index
  std::vector<std::uint64_t> keys_;     // Morton keys in sorted order
  std::vector<Vec<D>> x_;               // positions in sorted order (wrapped)
  std::vector<Real> h_;                 // H in sorted order
  std::vector<Node> nodes_;             // the hierarchy, depth first
  std::vector<std::uint32_t> cells_;    // indices of the leaf nodes
  std::vector<std::uint32_t> groups_;   // indices of the group roots
};

extern template class CellList<1>;
extern template class CellList<2>;
extern template class CellList<3>;

}  // namespace rubble
