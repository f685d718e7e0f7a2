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

namespace rubble {

// The CPU driver's search radius for summation density, as a multiple of
// the particle's current support radius: the room h has to grow in the
// smoothing-length iteration before its lists must be rebuilt
// (hydro_cpu.cpp; also the memory estimate of initial_conditions.cpp).
inline constexpr double kSearchSkin = 1.05;

// The neighbour lists of n particles, each in ascending order, as the
// search threads wrote them: particle i's list is `count(i)` indices from
// `list(i)`, in one of the blocks of the thread that found them. Nothing is
// copied into one array (that copy doubled the peak memory of the lists),
// and a thread that fills a block starts a new one instead of growing the
// old (growing by reallocation held the old and the new buffer at once, and
// left up to a quarter of the room spare). Blocks persist from one search
// to the next and each thread reuses its own in order, so a run settles at
// about the lists' size plus an eighth (issue #14: memory per particle).
class NeighborLists {
 public:
  std::size_t size() const { return begin_.size(); }
  std::size_t count(std::size_t i) const { return count_[i]; }
  const std::uint32_t* list(std::size_t i) const { return blocks_[block_[i]].data() + begin_[i]; }
  // particle i's list as a vector (tests, rare uses)
  std::vector<std::uint32_t> copy(std::size_t i) const { return {list(i), list(i) + count(i)}; }
  // entries over all lists
  std::size_t total() const {
    std::size_t t = 0;
    for (std::uint32_t c : count_) t += c;
    return t;
  }
  // bytes held: the blocks (with their spare room) and the per-particle index
  std::size_t bytes() const {
    std::size_t b = (begin_.capacity() + count_.capacity() + block_.capacity()) * sizeof(std::uint32_t);
    for (const auto& blk : blocks_) b += blk.capacity() * sizeof(std::uint32_t);
    return b;
  }
  std::size_t block_count() const { return blocks_.size(); }

 private:
  template <int D>
  friend class CellList;
  std::vector<std::vector<std::uint32_t>> blocks_;         // all blocks, of every thread
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
