// Neighbour search over the Morton order; see cell_list.hpp for the method.
#include "rubble/neighbors/cell_list.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "rubble/neighbors/morton.hpp"
#include "rubble/neighbors/spatial_order.hpp"

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace rubble {

namespace {

#if defined(_OPENMP)
int max_threads() { return omp_get_max_threads(); }
int thread_id() { return omp_get_thread_num(); }
#else
int max_threads() { return 1; }
int thread_id() { return 0; }
#endif

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("CellList::build: " + what); }

std::string str(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// The tree over the keys splits one key bit per level: each level halves
// its parent's region along the next axis (x, y, z, x, ...), so every D
// levels are one octree level. Halving rather than splitting in 2^D keeps
// the cells fuller (between about max_cell_size/2 and max_cell_size).
template <int D>
constexpr int kKeyBits = D * morton_bits<D>;

// Bit of a key that decides the side at a tree level (level 0: the top bit).
template <int D>
std::uint32_t key_bit(std::uint64_t key, int level) {
  return std::uint32_t(key >> (kKeyBits<D> - 1 - level)) & 1u;
}

// Lower bound on the distance between a point of [alo, ahi] and a point of
// [blo, bhi] along one axis. On a periodic axis (wrap = L; both intervals in
// [lo, hi)) the gap the other way round counts too; on an open axis
// wrap = +infinity removes it. Branch-free: of the two one-sided gaps at most
// one is positive. The result is reduced by `slack` so that rounding, here
// and in Box::separation, can never make it exceed a computed pair distance.
inline Real axis_gap(Real alo, Real ahi, Real blo, Real bhi, Real wrap, Real slack) {
  const Real right = std::min(blo - ahi, alo + wrap - bhi);  // b to the right of a
  const Real left = std::min(alo - bhi, blo + wrap - ahi);   // b to the left of a
  return std::max(std::max(right, left) - slack, Real(0));
}

}  // namespace

template <int D>
void CellList<D>::build(const Vec<D>* x, const Real* H, std::size_t n, const Box<D>& box) {
  if (n >= std::numeric_limits<std::uint32_t>::max()) fail("more than 2^32 - 2 particles");
  box_ = box;
  for (int k = 0; k < D; ++k)
    if (box.periodic[k] && !(box.hi[k] > box.lo[k]))
      fail("periodic axis " + std::to_string(k) + " has hi <= lo");

  // Check the input: finite positions, finite H >= 0. Report the first bad
  // particle so the message is the same on any number of threads.
  std::size_t bad_x = n, bad_h = n;
  Real h_max = 0;
#pragma omp parallel for reduction(min : bad_x, bad_h) reduction(max : h_max)
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < D; ++k)
      if (!std::isfinite(x[i][k])) bad_x = std::min(bad_x, i);
    if (!(H[i] >= Real(0)) || !std::isfinite(H[i])) bad_h = std::min(bad_h, i);
    else h_max = std::max(h_max, H[i]);
  }
  // (the index is the caller's array index; the run names the particle
  // itself by body and original index)
  if (bad_x < n) fail("array index " + std::to_string(bad_x) + " has a non-finite position");
  if (bad_h < n)
    fail("array index " + std::to_string(bad_h) + " has support radius H = " + str(H[bad_h]) +
         "; it must be finite and >= 0");
  // With H <= L/2 the minimum image is the only image within reach, so each
  // pair is found once and none is missed, however few H fit in L.
  for (int k = 0; k < D; ++k)
    if (box.periodic[k] && h_max > Real(0.5) * box.length(k))
      fail("support radius H = " + str(h_max) + " exceeds half the periodic length along axis " +
           std::to_string(k) + " (L/2 = " + str(Real(0.5) * box.length(k)) +
           "); a particle would neighbour several images of another. Enlarge the periodic box "
           "or reduce the smoothing lengths.");

  // Sort by Morton key within the particles' bounding box.
  const Box<D> bb = bounding_box(x, n, box);
  std::vector<std::uint64_t> keys(n);
#pragma omp parallel for
  for (std::size_t i = 0; i < n; ++i) keys[i] = morton_key<D>(x[i], bb);
  order_ = sort_permutation(keys);

  // Copy the particles in sorted order; positions on periodic axes are
  // mapped into [lo, hi) (a no-op for positions already there).
  keys_.resize(n);
  x_.resize(n);
  h_.resize(n);
#pragma omp parallel for
  for (std::size_t s = 0; s < n; ++s) {
    const std::uint32_t i = order_[s];
    keys_[s] = keys[i];
    h_[s] = H[i];
    Vec<D> p = x[i];
    for (int k = 0; k < D; ++k) {
      if (!box.periodic[k] || (p[k] >= box.lo[k] && p[k] < box.hi[k])) continue;
      const Real L = box.length(k);
      p[k] -= L * std::floor((p[k] - box.lo[k]) / L);
      if (!(p[k] >= box.lo[k] && p[k] < box.hi[k])) p[k] = box.lo[k];  // rounding at hi
    }
    x_[s] = p;
  }

  // Rounding allowance of the pruning test (see axis_gap()): a few units in the
  // last place of the coordinates, so that a cell is never skipped when
  // rounding would make a pair inside it pass the exact test.
  for (int k = 0; k < D; ++k) {
    slack_[k] = Real(16) * std::numeric_limits<Real>::epsilon() * (std::abs(bb.lo[k]) + std::abs(bb.hi[k]));
    wrap_[k] = box.periodic[k] ? box.length(k) : std::numeric_limits<Real>::infinity();
  }

  nodes_.clear();
  cells_.clear();
  groups_.clear();
  if (n > 0) build_node(0, std::uint32_t(n), 0, false);
}

// Emit the node for sorted range [begin, end), whose keys agree on their
// first `level` bits, and (recursively) its subtree. Returns its
// index. The first node down a branch with at most max_group_size particles
// (or a cell, whatever its size) becomes a group root.
template <int D>
std::uint32_t CellList<D>::build_node(std::uint32_t begin, std::uint32_t end, int level, bool in_group) {
  constexpr int kLevels = kKeyBits<D>;
  const bool small = end - begin <= max_cell_size_;
  // Levels where all particles fall on one side add nothing: skip them.
  while (!small && level < kLevels && key_bit<D>(keys_[begin], level) == key_bit<D>(keys_[end - 1], level))
    ++level;

  const std::uint32_t id = std::uint32_t(nodes_.size());
  nodes_.push_back(Node{x_[begin], x_[begin], h_[begin], begin, end, 0, false});
  const bool is_cell = small || level == kLevels;
  if (!in_group && (is_cell || end - begin <= max_group_size_)) {
    groups_.push_back(id);
    in_group = true;
  }

  if (is_cell) {  // bounds from its particles
    Node& c = nodes_[id];
    c.is_cell = true;
    for (std::uint32_t s = begin; s < end; ++s) {
      for (int k = 0; k < D; ++k) {
        c.lo[k] = std::min(c.lo[k], x_[s][k]);
        c.hi[k] = std::max(c.hi[k], x_[s][k]);
      }
      c.h_max = std::max(c.h_max, h_[s]);
    }
    c.skip = id + 1;
    cells_.push_back(id);
    return id;
  }

  // Split in two at the first key whose bit at this level is 1 (both halves
  // are non-empty: the loop above stopped at a level where they differ).
  const std::uint32_t mid = std::uint32_t(
      std::partition_point(keys_.begin() + begin, keys_.begin() + end,
                           [&](std::uint64_t key) { return key_bit<D>(key, level) == 0; }) -
      keys_.begin());
  for (const auto& [first, last] : {std::pair{begin, mid}, std::pair{mid, end}}) {
    const std::uint32_t child = build_node(first, last, level + 1, in_group);
    const Node c = nodes_[child];  // copy: build_node may have reallocated
    Node& p = nodes_[id];
    for (int k = 0; k < D; ++k) {
      p.lo[k] = std::min(p.lo[k], c.lo[k]);
      p.hi[k] = std::max(p.hi[k], c.hi[k]);
    }
    p.h_max = std::max(p.h_max, c.h_max);
  }
  nodes_[id].skip = std::uint32_t(nodes_.size());
  return id;
}

template <int D>
void CellList<D>::find_neighbors(NeighborLists& out) const {
  const std::size_t n = x_.size();
  out.begin_.assign(n, 0);
  out.count_.assign(n, 0);
  out.block_.assign(n, 0);
  if (n == 0) return;

  // Squared distance between two boxes (a point is a box with lo == hi).
  const Box<D> box = box_;
  Real wrap[D], slack[D];
  for (int k = 0; k < D; ++k) wrap[k] = wrap_[k], slack[k] = slack_[k];
  auto distance2 = [&](const Vec<D>& alo, const Vec<D>& ahi, const Vec<D>& blo, const Vec<D>& bhi) {
    Real s = 0;
    for (int k = 0; k < D; ++k) {
      const Real g = axis_gap(alo[k], ahi[k], blo[k], bhi[k], wrap[k], slack[k]);
      s += g * g;
    }
    return s;
  };
  const Node* nodes = nodes_.data();
  const std::size_t node_count = nodes_.size();
  const Vec<D>* xs = x_.data();
  const Real* hs = h_.data();
  const std::uint32_t* order = order_.data();

  // Half the periodic lengths, computed as Box::separation computes them.
  Real half[D];
  for (int k = 0; k < D; ++k) half[k] = Real(0.5) * (box.hi[k] - box.lo[k]);

  // Each thread writes the lists of the particles of its groups into its
  // own blocks (kept from the last search) and notes where each list is.
  // Inside the parallel region a thread reads only its own block
  // references; the shared table of blocks is touched in a critical section
  // (a block's data never move: the table holds vectors that are not resized).
  struct BlockRef {
    std::uint32_t id;
    std::uint16_t* data;
    std::size_t size;
  };
  const int threads = max_threads();
  if (int(out.thread_blocks_.size()) < threads) out.thread_blocks_.resize(threads);
  std::vector<std::vector<BlockRef>> refs(threads);
  for (int t = 0; t < threads; ++t)
    for (const std::uint32_t b : out.thread_blocks_[t]) refs[t].push_back({b, out.blocks_[b].data(), out.blocks_[b].size()});
  std::uint32_t* begin = out.begin_.data();
  std::uint32_t* count = out.count_.data();
  std::uint32_t* block_of = out.block_.data();

#pragma omp parallel num_threads(threads)
  {
    const int t = thread_id();
    std::vector<BlockRef>& mine = refs[t];
    std::size_t owned_capacity = 0;  // units in this thread's blocks
    for (const BlockRef& r : mine) owned_capacity += r.size;
    // The block being written (index into `mine`, or none yet); `used`
    // units of it are taken.
    std::size_t k = 0;
    const BlockRef* cur = nullptr;
    std::size_t used = 0;
    // Make the next block current, with room for at least `need` units. A
    // block of this thread's that is too small is skipped (and kept for
    // later searches); a new one holds an eighth of what the thread owns,
    // so the spare room stays small and the count of blocks grows slowly.
    auto next_block = [&](std::size_t need) {
      std::size_t j = cur ? k + 1 : 0;
      while (j < mine.size() && mine[j].size < need) ++j;
      if (j == mine.size()) {
        const std::size_t size = std::max({need, std::size_t(8192), owned_capacity / 8});
        BlockRef r{};
#pragma omp critical(rubble_neighbor_blocks)
        {
          out.blocks_.emplace_back(size);
          r = BlockRef{std::uint32_t(out.blocks_.size() - 1), out.blocks_.back().data(), size};
        }
        mine.push_back(r);
        owned_capacity += size;
      }
      k = j;
      cur = &mine[j];
      used = 0;
    };
    std::vector<std::uint32_t> near;     // cells within reach of the current group
    std::vector<std::uint32_t> scratch;  // the list being found, in full

    // static: each thread takes the same run of groups in every search, so
    // its blocks are reused in the same order and their count settles
    // (with dynamic scheduling a thread's blocks would grow to the most any
    // search ever gave it, up to all the lists)
#pragma omp for schedule(static)
    for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
      const Node& g = nodes[groups_[gi]];

      // Walk the tree depth first, skipping subtrees out of reach.
      near.clear();
      for (std::size_t i = 0; i < node_count;) {
        const Node& m = nodes[i];
        const Real r = std::max(g.h_max, m.h_max);
        if (distance2(g.lo, g.hi, m.lo, m.hi) < r * r) {
          if (m.is_cell) near.push_back(std::uint32_t(i));
          ++i;
        } else {
          i = m.skip;
        }
      }

      for (std::uint32_t a = g.begin; a < g.end; ++a) {
        const Vec<D> xa = xs[a];
        const Real ha = hs[a];
        std::size_t found = 0;
        for (const std::uint32_t j : near) {
          const Node& m = nodes[j];
          const Real rm = std::max(ha, m.h_max);
          if (!(distance2(xa, xa, m.lo, m.hi) < rm * rm)) continue;
          // Room for the whole cell before testing it, so that the test
          // can write every candidate and advance only on a hit (no branch
          // to mispredict).
          if (scratch.size() < found + (m.end - m.begin)) scratch.resize(2 * (found + (m.end - m.begin)));
          std::uint32_t* out_list = scratch.data() + found;
          std::size_t hits = 0;
          // If no coordinate difference to this cell can exceed L/2, the
          // minimum image is the plain difference (what separation would
          // return, bit for bit): skip its wrap tests.
          bool direct = true;
          for (int k2 = 0; k2 < D; ++k2)
            if (box.periodic[k2]) direct = direct && xa[k2] - m.lo[k2] <= half[k2] && xa[k2] - m.hi[k2] >= -half[k2];
          if (direct) {
            for (std::uint32_t b = m.begin; b < m.end; ++b) {
              const Real r = std::max(ha, hs[b]);
              out_list[hits] = order[b];
              hits += (norm2(xa - xs[b]) < r * r) & (b != a);
            }
          } else {
            for (std::uint32_t b = m.begin; b < m.end; ++b) {
              const Real r = std::max(ha, hs[b]);
              out_list[hits] = order[b];
              hits += (norm2(box.separation(xa, xs[b])) < r * r) & (b != a);
            }
          }
          found += hits;
        }
        // Ascending input index (already so when the input was in spatial
        // order), then stored as differences (NeighborLists).
        std::uint32_t* const list = scratch.data();
        if (!std::is_sorted(list, list + found)) std::sort(list, list + found);
        const std::uint32_t i = order[a];  // input index
        const std::size_t units = NeighborLists::encoded_units(list, found, i);
        if (!cur || used + units > cur->size) next_block(units);
        begin[i] = std::uint32_t(used);
        count[i] = std::uint32_t(found);
        block_of[i] = cur->id;
        used += NeighborLists::encode(list, found, i, cur->data + used);
      }
    }
  }
  for (int t = 0; t < threads; ++t) {
    out.thread_blocks_[t].clear();
    for (const BlockRef& r : refs[t]) out.thread_blocks_[t].push_back(r.id);
  }
}

void NeighborLists::assign(const std::vector<std::vector<std::uint32_t>>& lists) {
  const std::size_t n = lists.size();
  begin_.assign(n, 0);
  count_.assign(n, 0);
  block_.assign(n, 0);
  std::size_t units = 0;
  for (std::size_t i = 0; i < n; ++i) units += encoded_units(lists[i].data(), lists[i].size(), std::uint32_t(i));
  blocks_.assign(1, std::vector<std::uint16_t>(units));
  thread_blocks_.clear();
  std::size_t used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    begin_[i] = std::uint32_t(used);
    count_[i] = std::uint32_t(lists[i].size());
    used += encode(lists[i].data(), lists[i].size(), std::uint32_t(i), blocks_[0].data() + used);
  }
}

template class CellList<1>;
template class CellList<2>;
template class CellList<3>;

}  // namespace rubble
