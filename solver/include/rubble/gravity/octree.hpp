#pragma once
// Barnes-Hut octree for self-gravity (PHYSICS.md §6; Barnes & Hut 1986),
// built from the same Morton keys as the neighbour search (DESIGN.md
// principle 5: morton_key over bounding_box, sort_permutation).
//
// Structure. Particles are sorted by key; every node is a key prefix, i.e.
// a contiguous range [begin, end) of the sorted particles whose keys share
// their first 3*level bits: an octree cell of side (box side)/2^level on
// each axis. A node holding more than leaf_size particles is split into its
// (up to 8) non-empty child cells; levels at which all of a node's
// particles fall into one child are skipped, so chains of single-child
// cells cost nothing and clustered sets stay O(n) in memory. A node with at
// most leaf_size particles (or particles sharing one finest-level key:
// coincident ones) is a leaf. Nodes are stored depth first in one flat
// array with a `skip` index (the node just past the subtree), so the walk
// needs no stack and no pointers: ready for a CUDA driver, which can copy
// the arrays as they are and call octree_field() per thread.
//
// Every node carries its mass, centre of mass, traceless quadrupole about
// it (parallel-axis sums of its children's), the radius b_max around the
// centre of mass that holds all its particles, the largest softening length
// eps_max of its particles, and its opening radius 2 B / (sqrt(3) theta),
// B the distance from the centre of mass to the cell's farthest corner
// (physics/gravity.hpp). The walk accepts a node's multipole when
// node_accepted() holds and otherwise opens it; at a leaf it sums the
// softened pair interactions of its particles (the same function as direct
// summation), skipping the target itself.
//
// The build and the OpenMP walk are in solver/src/octree.cpp.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/gravity.hpp"
#include "rubble/physics/kernel_type.hpp"

namespace rubble {

struct OctreeNode {
  Vec<3> com;           // centre of mass
  Real mass;            // total mass
  Real quad[6];         // traceless quadrupole about com (xx, xy, xz, yy, yz, zz)
  Real open_radius;     // 2 B / (sqrt(3) theta), B = |com - farthest cell corner| (infinite for theta = 0)
  Real b_max;           // max |x_i - com| over the node's particles
  Real eps_max;         // largest softening length in the node
  std::uint32_t begin;  // sorted particle range [begin, end)
  std::uint32_t end;
  std::uint32_t skip;   // index of the node after this subtree
  std::uint32_t level;  // octree level of the cell (0 = the bounding box)
  std::uint32_t leaf;   // 1 for a leaf
};

// What the walk reads: plain pointers into the tree's arrays (sorted
// particle order), copyable to a device as is.
struct OctreeView {
  const OctreeNode* nodes = nullptr;
  std::uint32_t node_count = 0;
  const Vec<3>* x = nullptr;    // positions, sorted
  const Real* m = nullptr;      // masses, sorted
  const Real* eps = nullptr;    // softening lengths, sorted
  KernelType kernel = KernelType::CubicSpline;     // softening kernel
  MultipoleOrder order = MultipoleOrder::Quadrupole;
};

// Interactions one walk evaluated.
struct WalkCounts {
  std::uint64_t multipoles = 0;  // accepted nodes
  std::uint64_t pairs = 0;       // particle-particle interactions
};

// Field (per unit G) at x of every particle of the tree except sorted index
// `self` (pass 0xFFFFFFFF for a point that is not one of the particles), for
// a target with softening length eps. Stackless depth-first walk.
RUBBLE_HD_INLINE GravityField octree_field(const OctreeView& t, const Vec<3>& x, Real eps, std::uint32_t self,
                                           WalkCounts* counts = nullptr) {
  GravityField f{Vec<3>::zero(), Real(0)};
  std::uint64_t n_multipole = 0, n_pair = 0;
  std::uint32_t i = 0;
  while (i < t.node_count) {
    const OctreeNode& nd = t.nodes[i];
    const Vec<3> r = x - nd.com;
    if (node_accepted(norm2(r), nd.open_radius, nd.b_max, nd.eps_max, eps)) {
      multipole_add(r, nd.mass, nd.quad, t.order, f);
      ++n_multipole;
      i = nd.skip;
    } else if (nd.leaf) {
      for (std::uint32_t b = nd.begin; b < nd.end; ++b) {
        if (b == self) continue;
        gravity_pair_add(t.kernel, x - t.x[b], t.m[b], eps, t.eps[b], f);
        ++n_pair;
      }
      i = nd.skip;
    } else {
      ++i;  // first child
    }
  }
  if (counts) {
    counts->multipoles += n_multipole;
    counts->pairs += n_pair;
  }
  return f;
}

// Squared distance from point p to the box [lo, hi] (0 inside).
RUBBLE_HD_INLINE Real box_point_distance2(const Vec<3>& lo, const Vec<3>& hi, const Vec<3>& p) {
  Real s = 0;
  for (int k = 0; k < 3; ++k) {
    const Real below = lo[k] - p[k], above = p[k] - hi[k];
    const Real g = below > Real(0) ? below : (above > Real(0) ? above : Real(0));
    s += g * g;
  }
  return s;
}

struct OctreeOptions {
  Real theta = Real(0.5);                             // opening angle, 0 <= theta <= 1
  MultipoleOrder order = MultipoleOrder::Quadrupole;  // expansion order of accepted nodes
  std::uint32_t leaf_size = 8;                        // most particles per leaf (>= 1)
  // Targets that share one walk: the first node down each branch with at
  // most group_size particles walks the tree once for all of them, judging
  // each node from the nearest point of the group's bounding box (and the
  // group's largest softening), so every acceptance is one that each member
  // would have made alone: at most as large an error as the per-particle
  // walk, at a fraction of the cost. 0 or 1: every particle walks alone.
  std::uint32_t group_size = 32;
  KernelType kernel = KernelType::CubicSpline;        // softening kernel shape
};

class Octree {
 public:
  explicit Octree(const OctreeOptions& options = {});

  // Build over n particles with positions x, masses m > 0 and softening
  // lengths eps >= 0 (nullptr: all 0, point masses). Throws
  // std::invalid_argument for non-finite input, negative mass or softening,
  // theta outside [0, 1] or leaf_size 0.
  void build(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n);

  // Acceleration acc[i] and potential phi[i] (may be nullptr) of every
  // particle due to all others, in input order, multiplied by G.
  // OpenMP-parallel; the result does not depend on the thread count.
  void field(Real G, Vec<3>* acc, Real* phi) const;

  // Field per unit G at an arbitrary point x (not one of the particles)
  // with softening length eps.
  GravityField field_at(const Vec<3>& x, Real eps = Real(0)) const;

  OctreeView view() const;
  const OctreeOptions& options() const { return options_; }
  std::size_t size() const { return x_.size(); }
  std::size_t node_count() const { return nodes_.size(); }
  std::size_t leaf_count() const { return leaves_; }
  std::size_t group_count() const { return groups_.size(); }
  const std::vector<OctreeNode>& nodes() const { return nodes_; }
  // The octree cell of a node: the key-prefix cell of side (key box)/2^level.
  void cell_bounds(std::uint32_t node, Vec<3>& lo, Vec<3>& hi) const;
  // The cube the keys are quantised in.
  const Box<3>& key_box() const { return box_; }
  // Group roots (nodes whose particles share one walk).
  const std::vector<std::uint32_t>& groups() const { return groups_; }
  // order()[s] = input index of the particle at sorted position s.
  const std::vector<std::uint32_t>& order() const { return order_; }
  // Interactions of the last field(): totals over all particles.
  const WalkCounts& last_counts() const { return counts_; }

 private:
  std::uint32_t build_node(std::uint32_t begin, std::uint32_t end, std::uint32_t level, bool in_group);
  void field_per_particle(Real G, Vec<3>* acc, Real* phi) const;
  void field_by_groups(Real G, Vec<3>* acc, Real* phi) const;

  OctreeOptions options_;
  Box<3> box_;                        // the key box (bounding_box of the particles)
  std::vector<std::uint32_t> order_;  // sorted position -> input index
  std::vector<std::uint64_t> keys_;   // Morton keys, sorted
  std::vector<Vec<3>> x_;             // sorted positions
  std::vector<Real> m_, eps_;         // sorted masses and softening lengths
  std::vector<OctreeNode> nodes_;     // depth first
  std::vector<std::uint32_t> groups_; // nodes whose particles share one walk
  std::size_t leaves_ = 0;
  mutable WalkCounts counts_;
};

}  // namespace rubble
