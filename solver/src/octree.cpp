// Barnes-Hut octree: build over the Morton order and the OpenMP walk.
// See rubble/gravity/octree.hpp for the structure and physics/gravity.hpp
// for the interaction, the multipoles and the opening criterion.
#include "rubble/gravity/octree.hpp"
#include "rubble/gravity/octree_build.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "rubble/neighbors/morton.hpp"
#include "rubble/neighbors/spatial_order.hpp"

namespace rubble {

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("Octree::build: " + what); }

// The accepted nodes of one group walk, copied out of the tree into one
// array per component so that the evaluation loop vectorises.
struct MultipoleList {
  std::vector<Real> x, y, z, m, q0, q1, q2, q3, q4, q5;
  std::size_t size() const { return x.size(); }
  void assign(const OctreeNode* nodes, const std::vector<std::uint32_t>& ids) {
    for (auto* v : {&x, &y, &z, &m, &q0, &q1, &q2, &q3, &q4, &q5}) v->resize(ids.size());
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const OctreeNode& nd = nodes[ids[k]];
      x[k] = nd.com[0];
      y[k] = nd.com[1];
      z[k] = nd.com[2];
      m[k] = nd.mass;
      q0[k] = nd.quad[0];
      q1[k] = nd.quad[1];
      q2[k] = nd.quad[2];
      q3[k] = nd.quad[3];
      q4[k] = nd.quad[4];
      q5[k] = nd.quad[5];
    }
  }
};

// Field at xa of every multipole of the list, added to f.
template <bool Quadrupole>
void add_multipoles(const MultipoleList& l, const Vec<3>& xa, GravityField& f) {
  const Real* __restrict x = l.x.data();
  const Real* __restrict y = l.y.data();
  const Real* __restrict z = l.z.data();
  const Real* __restrict m = l.m.data();
  const Real *q0 = l.q0.data(), *q1 = l.q1.data(), *q2 = l.q2.data(), *q3 = l.q3.data(), *q4 = l.q4.data(),
             *q5 = l.q5.data();
  Real ax = 0, ay = 0, az = 0, phi = 0;
  const std::size_t n = l.size();
#pragma omp simd reduction(+ : ax, ay, az, phi)
  for (std::size_t k = 0; k < n; ++k)
    multipole_field<Quadrupole>(xa[0] - x[k], xa[1] - y[k], xa[2] - z[k], m[k], q0[k], q1[k], q2[k], q3[k], q4[k],
                                q5[k], ax, ay, az, phi);
  f.a[0] += ax;
  f.a[1] += ay;
  f.a[2] += az;
  f.phi += phi;
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

  // The neighbour search's keys (morton_key, sort_permutation) over the
  // cube that encloses its padded bounding box (same centre, side = the
  // longest side): octree cells must be cubes. A uniformly filled cube has
  // no quadrupole moment, so the monopole's error starts at the next order;
  // elongated cells carry a quadrupole that the opening angle does not see
  // (measured on the Plummer sphere, theta = 0.3: median monopole error
  // 3.7e-4 with the elongated cells of the bounding box, 3.0e-4 with cubes).
  box_ = octree_key_box(bounding_box<3>(x, n, Box<3>{}));
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
  groups_.clear();
  leaves_ = 0;
  if (n > 0) {
    nodes_.reserve(2 * n / std::max<std::uint32_t>(options_.leaf_size, 1) + 16);
    build_node(0, std::uint32_t(n), 0, false);
  }
}

// Emit the node of sorted range [begin, end), whose keys share their first
// 3*level bits, and its subtree; returns its index. The first node down a
// branch with at most group_size particles (or a leaf) becomes a group.
std::uint32_t Octree::build_node(std::uint32_t begin, std::uint32_t end, std::uint32_t level, bool in_group) {
  const std::uint32_t count = end - begin;
  bool leaf = false;
  level = octree_split_level(keys_.data(), begin, end, level, options_.leaf_size, leaf);

  const std::uint32_t id = std::uint32_t(nodes_.size());
  {
    OctreeNode nd{};
    nd.begin = begin;
    nd.end = end;
    nd.level = level;
    nd.leaf = leaf ? 1u : 0u;
    nodes_.push_back(nd);
  }
  if (!in_group && (leaf || count <= options_.group_size)) {
    groups_.push_back(id);
    in_group = true;
  }

  // Children first (depth first), then this node's moments from them
  // (octree_build.hpp: the same steps as the level-synchronous build).
  std::uint32_t child_ids[8];
  int n_children = 0;
  if (leaf) {
    ++leaves_;
  } else {
    std::uint32_t first[9];
    n_children = octree_children(keys_.data(), begin, end, level, first);
    for (int c = 0; c < n_children; ++c) child_ids[c] = build_node(first[c], first[c + 1], level + 1, in_group);
  }
  const OctreeNode* children[8];
  for (int c = 0; c < n_children; ++c) children[c] = &nodes_[child_ids[c]];  // nodes_ no longer grows here
  octree_finish_node(nodes_[id], children, n_children, x_.data(), m_.data(), eps_.data(), box_, keys_[begin],
                     options_.theta);
  nodes_[id].skip = std::uint32_t(nodes_.size());
  return id;
}

// The key prefix of a node (its first 3*level bits) -> integer cell
// coordinates at its level -> the cell's corners in the key box.
void Octree::cell_bounds(std::uint32_t node, Vec<3>& lo, Vec<3>& hi) const {
  const OctreeNode& nd = nodes_[node];
  octree_cell_bounds(box_, keys_[nd.begin], nd.level, lo, hi);
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
  if (options_.group_size <= 1) field_per_particle(G, acc, phi);
  else field_by_groups(G, acc, phi);
}

void Octree::field_per_particle(Real G, Vec<3>* acc, Real* phi) const {
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

// One walk per group: collect the accepted nodes and the leaves to sum
// directly (judged from the nearest point of the group's bounding box, with
// the group's largest softening), copy them into contiguous lists, then
// evaluate the lists for every member.
void Octree::field_by_groups(Real G, Vec<3>* acc, Real* phi) const {
  const std::size_t node_count = nodes_.size();
  const OctreeNode* nodes = nodes_.data();
  const KernelType kernel = options_.kernel;
  const MultipoleOrder order = options_.order;
  std::uint64_t multipoles = 0, pairs = 0;
#pragma omp parallel reduction(+ : multipoles, pairs)
  {
    std::vector<std::uint32_t> accepted, direct;
    MultipoleList mp;  // the accepted nodes' moments
    std::vector<Vec<3>> src_x;
    std::vector<Real> src_m, src_eps;
    std::vector<std::uint32_t> src_index;
#pragma omp for schedule(dynamic, 4)
    for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
      const OctreeNode& g = nodes[groups_[gi]];
      Vec<3> lo = x_[g.begin], hi = x_[g.begin];
      for (std::uint32_t s = g.begin + 1; s < g.end; ++s)
        for (int k = 0; k < 3; ++k) {
          lo[k] = std::min(lo[k], x_[s][k]);
          hi[k] = std::max(hi[k], x_[s][k]);
        }
      accepted.clear();
      direct.clear();
      for (std::size_t i = 0; i < node_count;) {
        const OctreeNode& nd = nodes[i];
        if (node_accepted(box_point_distance2(lo, hi, nd.com), nd.open_radius, nd.b_max, nd.eps_max, g.eps_max)) {
          accepted.push_back(std::uint32_t(i));
          i = nd.skip;
        } else if (nd.leaf) {
          direct.push_back(std::uint32_t(i));
          i = nd.skip;
        } else {
          ++i;
        }
      }
      mp.assign(nodes, accepted);
      src_x.clear();
      src_m.clear();
      src_eps.clear();
      src_index.clear();
      for (const std::uint32_t j : direct)
        for (std::uint32_t b = nodes[j].begin; b < nodes[j].end; ++b) {
          src_x.push_back(x_[b]);
          src_m.push_back(m_[b]);
          src_eps.push_back(eps_[b]);
          src_index.push_back(b);
        }
      const std::size_t n_src = src_x.size();
      for (std::uint32_t a = g.begin; a < g.end; ++a) {
        GravityField f{Vec<3>::zero(), Real(0)};
        const Vec<3> xa = x_[a];
        const Real ea = eps_[a];
        if (order == MultipoleOrder::Quadrupole) add_multipoles<true>(mp, xa, f);
        else add_multipoles<false>(mp, xa, f);
        for (std::size_t k = 0; k < n_src; ++k) {
          if (src_index[k] == a) continue;
          gravity_pair_add(kernel, xa - src_x[k], src_m[k], ea, src_eps[k], f);
        }
        const std::uint32_t i = order_[a];
        acc[i] = f.a * G;
        if (phi) phi[i] = f.phi * G;
      }
      const std::uint64_t members = g.end - g.begin;
      multipoles += members * accepted.size();
      pairs += members * n_src - members;  // every member skips itself once
    }
  }
  counts_.multipoles = multipoles;
  counts_.pairs = pairs;
}

GravityField Octree::field_at(const Vec<3>& x, Real eps) const {
  return octree_field(view(), x, eps, 0xFFFFFFFFu);
}

}  // namespace rubble
