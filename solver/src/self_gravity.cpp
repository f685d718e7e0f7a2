// Self-gravity as the scene asks for it; see rubble/gravity/self_gravity.hpp.
#include "rubble/gravity/self_gravity.hpp"

#include "rubble/gravity/direct.hpp"

namespace rubble {

namespace {

OctreeOptions octree_options(const GravityConfig& c, KernelType kernel) {
  OctreeOptions o;
  o.theta = Real(c.theta);
  o.order = c.order;
  o.leaf_size = std::uint32_t(c.leaf_size);
  o.group_size = std::uint32_t(c.group_size);
  o.kernel = kernel;
  return o;
}

}  // namespace

SelfGravity::SelfGravity(const GravityConfig& config, KernelType kernel)
    : config_(config), kernel_(kernel), tree_(octree_options(config, kernel)) {}

void SelfGravity::compute(const Vec<3>* x, const Real* m, const Real* h, std::size_t n, Vec<3>* acc, Real* phi) {
  if (!enabled()) return;
  const Real* eps = h;
  if (config_.softening == GravitySoftening::Fixed) {
    eps_.assign(n, Real(config_.softening_length));
    eps = eps_.data();
  }
  const Real G = Real(config_.G);
  if (config_.mode == GravityMode::Direct) {
    direct_gravity(x, m, eps, n, kernel_, G, acc, phi);
  } else {
    tree_.build(x, m, eps, n);
    tree_.field(G, acc, phi);
  }
}

}  // namespace rubble
