// The CUDA backend (issue #6): device-resident particles, a cell list over a
// device radix sort, and the same per-particle loop bodies as the CPU
// driver. See cuda_stepper.hpp for the interface and DESIGN.md principles
// 1, 4, 5 and 6 for why it is shaped this way.
//
// What runs where:
//   sort_particles   Morton keys of the positions (morton.hpp), a stable
//                    radix sort of (key, index) on the device (Thrust, which
//                    uses CUB's radix sort for integer keys), and a gather of
//                    every allocated field: the same permutation as the CPU's
//                    spatial_sort_permutation.
//   neighbours       a uniform grid whose cells are at least the largest
//                    search radius wide; (cell, index) pairs radix-sorted on
//                    the device, a start/end range per cell, and a visitor
//                    (GridNeighbors) that offers every particle of the 3^D
//                    surrounding cells to the loop body, which keeps those
//                    within max(R_a, R_b) - the CPU cell list's criterion.
//   right-hand side  one kernel per loop body of rubble/drivers/particle_rates.hpp.
//   integrators      the per-particle steps of leapfrog.hpp and rk2_adaptive.hpp.
//   reductions       time-step limit, conserved sums, finiteness, counts:
//                    thrust::transform_reduce over the particle index.
// The sums over neighbours run in cell order, not in ascending index order
// as on the CPU, so results differ by rounding (the parity test bounds it).
#include <cuda/functional>
#include <cuda_runtime.h>
#include <thrust/device_ptr.h>
#include <thrust/execution_policy.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/scan.h>
#include <thrust/sequence.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "cuda/cuda_check.hpp"
#include "cuda/cuda_stepper.hpp"
#include "rubble/core/error.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/rhs_features.hpp"
#include "rubble/gravity/direct.hpp"
#include "rubble/gravity/octree.hpp"
#include "rubble/gravity/octree_build.hpp"
#include "rubble/gravity/device_gravity.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/io/conserved_sums.hpp"
#include "rubble/neighbors/morton.hpp"
#include "rubble/neighbors/spatial_order.hpp"
#include "rubble/neighbors/uniform_grid.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/run.hpp"

namespace rubble {

std::string gpu_description() {
  int count = 0;
  const cudaError_t err = cudaGetDeviceCount(&count);
  if (err != cudaSuccess || count == 0)
    return std::string("none (CUDA build; ") + (err != cudaSuccess ? cudaGetErrorString(err) : "no device") + ")";
  cudaDeviceProp prop{};
  RUBBLE_CUDA(cudaGetDeviceProperties(&prop, 0));
  return std::string(prop.name) + " (compute capability " + std::to_string(prop.major) + "." +
         std::to_string(prop.minor) + ", " + std::to_string(prop.totalGlobalMem >> 20) + " MiB)" +
         (count > 1 ? " and " + std::to_string(count - 1) + " more" : "");
}

namespace {

constexpr unsigned kBlock = 128;

template <class F>
__global__ void each_kernel(std::size_t n, F f) {
  const std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (i < n) f(i);
}

// Run f(i) for i in [0, n) on the device; `what` names the kernel in errors.
template <class F>
void for_each_index(const char* what, std::size_t n, F f) {
  if (n == 0) return;
  each_kernel<<<unsigned((n + kBlock - 1) / kBlock), kBlock>>>(n, f);
  cuda::check(cudaGetLastError(), what, __FILE__, __LINE__);
  if (cuda::sync_check_enabled()) cuda::check(cudaDeviceSynchronize(), what, __FILE__, __LINE__);
}

// Reduce op(f(i)) over i in [0, n) on the device.
template <class T, class F, class Op>
T reduce_index(std::size_t n, F f, T init, Op op) {
  const thrust::counting_iterator<std::size_t> first(0);
  // the device lambda's result type, stated for the host side of Thrust
  T r = thrust::transform_reduce(thrust::device, first, first + n, ::cuda::proclaim_return_type<T>(f), init, op);
  cuda::check(cudaGetLastError(), "thrust::transform_reduce", __FILE__, __LINE__);
  return r;
}

// An owned device allocation (move-only).
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(std::size_t bytes) { resize(bytes); }
  ~DeviceBuffer() {
    if (p_) cudaFree(p_);  // no throw from a destructor
  }
  DeviceBuffer(DeviceBuffer&& o) noexcept : p_(o.p_), bytes_(o.bytes_) { o.p_ = nullptr, o.bytes_ = 0; }
  DeviceBuffer& operator=(DeviceBuffer&&) = delete;
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;

  // Grow to at least `bytes` (contents are not kept).
  void resize(std::size_t bytes) {
    if (bytes <= bytes_) return;
    if (p_) RUBBLE_CUDA(cudaFree(p_));
    p_ = nullptr;
    bytes_ = 0;
    RUBBLE_CUDA(cudaMalloc(&p_, bytes));
    bytes_ = bytes;
  }
  void* get() const { return p_; }
  template <class T>
  T* as() const {
    return static_cast<T*>(p_);
  }

 private:
  void* p_ = nullptr;
  std::size_t bytes_ = 0;
};

// Gather `words` 32-bit words per element: dst[i] = src[perm[i]].
__global__ void gather_words(std::uint32_t* dst, const std::uint32_t* src, const std::uint32_t* perm, std::size_t n,
                             unsigned words) {
  const std::size_t k = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (k >= n * words) return;
  const std::size_t i = k / words, w = k % words;
  dst[k] = src[std::size_t(perm[i]) * words + w];
}

// The element type of a field-table member pointer (std::vector<T> PS::*).
template <class M>
struct MemberValue;
template <class C, class T>
struct MemberValue<std::vector<T> C::*> {
  using type = T;
};

// The allocated fields of a ParticleStore, one device array each, with the
// same names and element types (the field table of particle_store.hpp).
template <int D>
class DeviceStore {
 public:
  void allocate_like(const ParticleStore<D>& ps) {
    n_ = ps.n;
    fields_.clear();
    for (const auto& f : field_table<D>())
      std::visit([&](auto member) {
        const auto& arr = ps.*member;
        if (arr.empty()) return;
        using T = typename std::decay_t<decltype(arr)>::value_type;
        static_assert(sizeof(T) % 4 == 0, "fields are gathered as 32-bit words");
        fields_.push_back(Field{std::string(f.name), DeviceBuffer(n_ * sizeof(T)), sizeof(T)});
      }, f.member);
  }

  void upload(const ParticleStore<D>& ps) {
    for_each_pair(const_cast<ParticleStore<D>&>(ps), [&](Field& d, void* host, std::size_t bytes) {
      RUBBLE_CUDA(cudaMemcpy(d.buf.get(), host, bytes, cudaMemcpyHostToDevice));
    });
  }
  // Returns the bytes copied.
  std::size_t download(ParticleStore<D>& ps) const {
    std::size_t total = 0;
    for_each_pair(ps, [&](const Field& d, void* host, std::size_t bytes) {
      RUBBLE_CUDA(cudaMemcpy(host, d.buf.get(), bytes, cudaMemcpyDeviceToHost));
      total += bytes;
    });
    return total;
  }
  // Copy another store of the same layout, device to device.
  void copy_from(const DeviceStore& o) {
    if (fields_.size() != o.fields_.size()) throw RunError("DeviceStore::copy_from: layouts differ");
    for (std::size_t k = 0; k < fields_.size(); ++k)
      RUBBLE_CUDA(cudaMemcpy(fields_[k].buf.get(), o.fields_[k].buf.get(), n_ * fields_[k].elem,
                             cudaMemcpyDeviceToDevice));
  }
  // A store of the same layout (contents undefined).
  void allocate_as(const DeviceStore& o) {
    n_ = o.n_;
    fields_.clear();
    for (const Field& f : o.fields_) fields_.push_back(Field{f.name, DeviceBuffer(n_ * f.elem), f.elem});
  }

  // The snapshot fields of `o` (the field table's `snapshot` flag), device
  // to device; allocated on the first call. The state check's last good
  // state (CudaStepper::keep_good).
  void copy_snapshot_fields_from(const DeviceStore& o) {
    if (fields_.empty()) {
      n_ = o.n_;
      for (const Field& f : o.fields_)
        for (const auto& t : field_table<D>())
          if (t.snapshot && t.name == f.name) fields_.push_back(Field{f.name, DeviceBuffer(n_ * f.elem), f.elem});
    }
    for (Field& f : fields_)
      for (const Field& g : o.fields_)
        if (g.name == f.name)
          RUBBLE_CUDA(cudaMemcpy(f.buf.get(), g.buf.get(), n_ * f.elem, cudaMemcpyDeviceToDevice));
  }
  // A host store holding exactly this store's fields, n entries each.
  void allocate_host(ParticleStore<D>& ps) const {
    ps.n = n_;
    for (const auto& t : field_table<D>())
      std::visit([&](auto member) {
        for (const Field& f : fields_)
          if (f.name == t.name) (ps.*member).resize(n_);
      }, t.member);
  }

  // New element i of every field is old element perm[i] (perm on the device).
  void permute(const std::uint32_t* perm, DeviceBuffer& scratch) {
    for (Field& f : fields_) {
      const std::size_t bytes = n_ * f.elem;
      scratch.resize(bytes);
      const unsigned words = unsigned(f.elem / 4);
      const std::size_t total = n_ * words;
      if (total == 0) continue;
      gather_words<<<unsigned((total + kBlock - 1) / kBlock), kBlock>>>(scratch.as<std::uint32_t>(),
                                                                        static_cast<std::uint32_t*>(f.buf.get()), perm, n_, words);
      cuda::check(cudaGetLastError(), "gather_words", __FILE__, __LINE__);
      RUBBLE_CUDA(cudaMemcpy(f.buf.get(), scratch.get(), bytes, cudaMemcpyDeviceToDevice));
    }
  }

  StoreView<D> view() const {
    StoreView<D> s;
    s.n = n_;
    for (const auto& f : field_table<D>())
      std::visit([&](auto member) {
        using T = typename MemberValue<decltype(member)>::type;
        for (const Field& d : fields_)
          if (d.name == f.name) s.bind(f.name, d.buf.template as<T>());
      }, f.member);
    return s;
  }
  std::size_t size() const { return n_; }

 private:
  struct Field {
    std::string name;
    DeviceBuffer buf;
    std::size_t elem;  // bytes per element
  };

  // f(device field, host data, bytes) for every allocated field.
  template <class Fn>
  void for_each_pair(ParticleStore<D>& ps, Fn&& fn) const {
    for (const auto& f : field_table<D>())
      std::visit([&](auto member) {
        auto& arr = ps.*member;
        if (arr.empty()) return;
        for (const Field& d : fields_)
          if (d.name == f.name) fn(const_cast<Field&>(d), static_cast<void*>(arr.data()), arr.size() * d.elem);
      }, f.member);
  }

  std::size_t n_ = 0;
  std::vector<Field> fields_;
};

// A plain device array of T.
template <class T>
struct DeviceArray {
  DeviceBuffer buf;
  std::size_t n = 0;
  void resize(std::size_t count) {
    buf.resize(count * sizeof(T));
    n = count;
  }
  T* data() const { return buf.as<T>(); }
};

// Barnes-Hut on the device: the octree of gravity/octree_build.hpp built
// level by level over the particles sorted by the tree's own keys (the cube
// around their bounding box, as Octree::build), then one walk per particle
// (octree_field, as Octree with group_size 0 or 1). The same tree as the
// CPU's, node for node; with the CPU's default group walk the fields differ
// by the multipole error, not by rounding.
class DeviceOctree {
 public:
  // Field of n particles (device arrays x, m, eps; store order) times G:
  // a_grav and phi written, a_grav added to dvdt when dvdt is not null.
  // Build and walk times (device-synchronised) go to *timing when given.
  void field(const Vec<3>* x, const Real* m, const Real* e, std::size_t count, const GravityConfig& gravity,
             KernelType kernel, Vec<3>* a_grav, Real* phi, Vec<3>* dvdt, DeviceGravityTiming* timing = nullptr) {
    if (count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    const std::uint32_t n32 = std::uint32_t(count);
    // the tree's keys and sorted copies
    Vec<3> mn, mx;
    for (int k = 0; k < 3; ++k) {
      mn[k] = reduce_index<Real>(count, [=] __device__(std::size_t i) { return x[i][k]; },
                                 std::numeric_limits<Real>::max(), thrust::minimum<Real>());
      mx[k] = reduce_index<Real>(count, [=] __device__(std::size_t i) { return x[i][k]; },
                                 std::numeric_limits<Real>::lowest(), thrust::maximum<Real>());
    }
    const Box<3> kb = octree_key_box(bounding_box_from_extent<3>(Box<3>{}, mn, mx));
    keys_.resize(count);
    order_.resize(count);
    x_.resize(count);
    m_.resize(count);
    eps_.resize(count);
    std::uint64_t* k = keys_.data();
    std::uint32_t* o = order_.data();
    for_each_index("tree keys", count, [=] __device__(std::size_t i) {
      k[i] = morton_key<3>(x[i], kb);
      o[i] = std::uint32_t(i);
    });
    thrust::sort_by_key(thrust::device, thrust::device_pointer_cast(k), thrust::device_pointer_cast(k + count),
                        thrust::device_pointer_cast(o));
    cuda::check(cudaGetLastError(), "thrust::sort_by_key (tree keys)", __FILE__, __LINE__);
    Vec<3>* tx = x_.data();
    Real* tm = m_.data();
    Real* te = eps_.data();
    for_each_index("tree gather", count, [=] __device__(std::size_t j) {
      tx[j] = x[o[j]];
      tm[j] = m[o[j]];
      te[j] = e[o[j]];
    });

    // 1. discovery, level by level
    const std::uint32_t leaf_size = std::uint32_t(gravity.leaf_size);
    std::size_t L = 0;  // levels in use (their arrays are kept between calls)
    int cur = 0;
    frontier_[cur].resize(1);
    const OctreePending root{0, n32, 0, 0xFFFFFFFFu};
    RUBBLE_CUDA(cudaMemcpy(frontier_[cur].data(), &root, sizeof root, cudaMemcpyHostToDevice));
    std::size_t F = 1;
    while (F > 0) {
      if (L == levels_.size()) levels_.emplace_back();
      levels_[L].resize(F);
      counts_.resize(F);
      offsets_.resize(F);
      OctreeLevelNode* lv = levels_[L++].data();
      const OctreePending* fr = frontier_[cur].data();
      std::uint32_t* cnt = counts_.data();
      std::uint32_t* off = offsets_.data();
      for_each_index("octree discovery", F, [=] __device__(std::size_t i) {
        std::uint32_t first[9];
        cnt[i] = octree_discover(k, fr[i], leaf_size, lv[i], first);
      });
      thrust::exclusive_scan(thrust::device, thrust::device_pointer_cast(cnt), thrust::device_pointer_cast(cnt + F),
                             thrust::device_pointer_cast(off));
      cuda::check(cudaGetLastError(), "thrust::exclusive_scan (octree children)", __FILE__, __LINE__);
      std::uint32_t last_off = 0, last_cnt = 0;
      RUBBLE_CUDA(cudaMemcpy(&last_off, off + F - 1, sizeof last_off, cudaMemcpyDeviceToHost));
      RUBBLE_CUDA(cudaMemcpy(&last_cnt, cnt + F - 1, sizeof last_cnt, cudaMemcpyDeviceToHost));
      const std::size_t total = std::size_t(last_off) + last_cnt;
      frontier_[1 - cur].resize(std::max<std::size_t>(total, 1));
      OctreePending* nx = frontier_[1 - cur].data();
      for_each_index("octree children", F, [=] __device__(std::size_t i) {
        lv[i].first_child = off[i];
        if (cnt[i] == 0) return;
        std::uint32_t first[9];
        octree_children(k, lv[i].node.begin, lv[i].node.end, lv[i].node.level, first);
        for (std::uint32_t c = 0; c < cnt[i]; ++c)
          nx[off[i] + c] = OctreePending{first[c], first[c + 1], lv[i].node.level + 1, std::uint32_t(i)};
      });
      cur = 1 - cur;
      F = total;
    }
    // 2. subtree sizes, bottom up
    for (std::size_t l = L; l-- > 1;) {
      const OctreeLevelNode* lv = levels_[l].data();
      OctreeLevelNode* up = levels_[l - 1].data();
      for_each_index("octree sizes", levels_[l].n, [=] __device__(std::size_t i) {
        atomicAdd(reinterpret_cast<unsigned int*>(&up[lv[i].parent].size), unsigned(lv[i].size));
      });
    }
    // 3. depth-first ids, top down
    for (std::size_t l = 0; l + 1 < L; ++l) {
      const OctreeLevelNode* lv = levels_[l].data();
      OctreeLevelNode* down = levels_[l + 1].data();
      for_each_index("octree ids", levels_[l].n, [=] __device__(std::size_t i) { octree_number_children(lv[i], down); });
    }
    OctreeLevelNode root_node;
    RUBBLE_CUDA(cudaMemcpy(&root_node, levels_[0].data(), sizeof root_node, cudaMemcpyDeviceToHost));
    const std::uint32_t node_count = root_node.size;
    nodes_.resize(node_count);
    OctreeNode* nodes = nodes_.data();
    // 4. moments bottom up, into the depth-first array
    const Real theta = Real(gravity.theta);
    for (std::size_t l = L; l-- > 0;) {
      OctreeLevelNode* lv = levels_[l].data();
      const OctreeLevelNode* next = l + 1 < L ? levels_[l + 1].data() : nullptr;
      for_each_index("octree moments", levels_[l].n, [=] __device__(std::size_t i) {
        nodes[lv[i].id] = octree_finish_level_node(lv[i], next, k, tx, tm, te, kb, theta);
      });
    }
    RUBBLE_CUDA(cudaDeviceSynchronize());
    const auto t1 = std::chrono::steady_clock::now();
    // 5. one walk per particle
    OctreeView view;
    view.nodes = nodes;
    view.node_count = node_count;
    view.x = tx;
    view.m = tm;
    view.eps = te;
    view.kernel = kernel;
    view.order = gravity.order;
    const Real G = Real(gravity.G);
    for_each_index("octree walk", count, [=] __device__(std::size_t j) {
      const GravityField f = octree_field(view, tx[j], te[j], std::uint32_t(j));
      const std::uint32_t i = o[j];
      a_grav[i] = f.a * G;
      if (phi) phi[i] = f.phi * G;
      if (dvdt) dvdt[i] += a_grav[i];
    });
    if (timing) {
      RUBBLE_CUDA(cudaDeviceSynchronize());
      timing->build_seconds = std::chrono::duration<double>(t1 - t0).count();
      timing->walk_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      timing->nodes = node_count;
    }
  }

 private:
  DeviceArray<std::uint64_t> keys_;
  DeviceArray<std::uint32_t> order_, counts_, offsets_;
  DeviceArray<Vec<3>> x_;
  DeviceArray<Real> m_, eps_;
  DeviceArray<OctreePending> frontier_[2];
  std::vector<DeviceArray<OctreeLevelNode>> levels_;
  DeviceArray<OctreeNode> nodes_;
};

}  // namespace

template <int D>
struct CudaStepper<D>::Impl {
  ParticleStore<D>& host;
  Box<D> domain;
  std::vector<MaterialParams> materials_host;
  DeviceArray<MaterialParams> materials;
  DeviceStore<D> store;
  DeviceBuffer scratch;
  KernelType kernel;
  Real hfact, courant, force_factor, xsph_epsilon, shifting;
  bool summation, solid = false, kernel_correction = false, artificial_stress = false;
  bool porosity = false, plasticity = false, damage = false, body_force = false, wall_extrapolation = false;
  Vec<D> g = Vec<D>::zero();  // simulation.gravity
  GravityConfig gravity;
  DeviceArray<Mat<D>> art_R;
  DeviceArray<Real> search_radius, eps;
  DeviceArray<int> flags;
  // grid cell list
  DeviceArray<std::uint64_t> keys;
  DeviceArray<std::uint32_t> order, cell_start, cell_end, perm;
  GridNeighbors<D> grid{};
  // integrator scratch
  DeviceArray<Vec<D>> v_half, shift;  // shift: particle shifting
  DeviceArray<Real> u_half, rho_half, alpha_half, alpha_start, damage_half;
  DeviceArray<Mat<D>> S_half;
  DeviceStore<D> y0, y1;
  DeviceStore<D> good;           // keep_good(): the snapshot fields before the step
  ParticleStore<D> good_host;    // last_good(): their host copy
  DeviceOctree octree;  // Barnes-Hut (3-D)
  std::int64_t fallbacks_total = 0, evaluations = 0;
  bool host_current = true;
  std::int64_t bytes_downloaded = 0;  // device-to-host bytes of host()

  Impl(const Scene& scene, ParticleStore<D>& ps, const Box<D>& dom)
      : host(ps),
        domain(dom),
        materials_host(material_params_from_scene(scene)),
        kernel(scene.simulation.kernel),
        hfact(Real(scene.simulation.hfact > 0 ? scene.simulation.hfact : kernel_default_hfact(scene.simulation.kernel))),
        courant(Real(scene.simulation.courant)),
        force_factor(Real(scene.simulation.force_factor)),
        xsph_epsilon(Real(scene.simulation.xsph)),
        shifting(Real(scene.simulation.shifting)),
        summation(scene.simulation.density == DensityForm::Summation),
        gravity(scene.gravity) {
    int devices = 0;
    const cudaError_t err = cudaGetDeviceCount(&devices);
    if (err != cudaSuccess || devices == 0)
      throw RunError(std::string("--backend cuda: no CUDA device available (") +
                     (err != cudaSuccess ? cudaGetErrorString(err) : "device count 0") + ")");
    if (ps.n > std::numeric_limits<std::uint32_t>::max()) throw RunError("more than 2^32 - 1 particles");
    const RhsFeatures f = rhs_features<D>(scene, materials_host, ps);
    solid = f.solid;
    artificial_stress = f.artificial_stress;
    kernel_correction = f.kernel_correction;
    porosity = f.porosity;
    plasticity = f.plasticity;
    damage = f.damage;
    wall_extrapolation = f.wall_extrapolation;
    body_force = f.body_force;
    for (int k = 0; k < D; ++k) g[k] = Real(scene.simulation.gravity[k]);
    materials.resize(materials_host.size());
    RUBBLE_CUDA(cudaMemcpy(materials.data(), materials_host.data(), materials_host.size() * sizeof(MaterialParams),
                           cudaMemcpyHostToDevice));
    const std::size_t n = ps.n;
    store.allocate_like(ps);
    store.upload(ps);
    if (solid && artificial_stress) art_R.resize(n);
    search_radius.resize(n);
    flags.resize(n);
    if (gravity.mode != GravityMode::Off) eps.resize(n);
    keys.resize(n);
    order.resize(n);
    perm.resize(n);
  }

  std::size_t n() const { return store.size(); }

  RhsContext<D> context() const {
    RhsContext<D> c;
    c.s = store.view();
    c.mat = materials.data();
    c.domain = domain;
    c.kernel = kernel;
    c.hfact = hfact;
    c.summation = summation;
    c.kernel_correction = kernel_correction;
    c.art_R = art_R.n ? art_R.data() : nullptr;
    c.xsph_epsilon = xsph_epsilon;
    c.courant = courant;
    c.force_factor = force_factor;
    c.body_force = g;
    c.has_body_force = body_force;
    return c;
  }

  // The particles' extent on every axis (min, max), reduced on the device.
  void extent(Vec<D>& mn, Vec<D>& mx) const {
    const Vec<D>* x = store.view().x;
    for (int k = 0; k < D; ++k) {
      mn[k] = reduce_index<Real>(n(), [=] __device__(std::size_t i) { return x[i][k]; },
                                 std::numeric_limits<Real>::max(), thrust::minimum<Real>());
      mx[k] = reduce_index<Real>(n(), [=] __device__(std::size_t i) { return x[i][k]; },
                                 std::numeric_limits<Real>::lowest(), thrust::maximum<Real>());
    }
  }

  // Sort along the space-filling curve: the CPU's permutation, on the device.
  void sort_particles() {
    const std::size_t count = n();
    if (count == 0) return;
    Vec<D> mn, mx;
    extent(mn, mx);
    const Box<D> box = bounding_box_from_extent<D>(domain, mn, mx);
    const Vec<D>* x = store.view().x;
    std::uint64_t* k = keys.data();
    std::uint32_t* p = perm.data();
    for_each_index("morton keys", count, [=] __device__(std::size_t i) {
      k[i] = morton_key<D>(x[i], box);
      p[i] = std::uint32_t(i);
    });
    // LSD radix sort: stable, so equal keys keep their index order as on the CPU
    thrust::sort_by_key(thrust::device, thrust::device_pointer_cast(k), thrust::device_pointer_cast(k + count),
                        thrust::device_pointer_cast(p));
    cuda::check(cudaGetLastError(), "thrust::sort_by_key (Morton keys)", __FILE__, __LINE__);
    store.permute(p, scratch);
    host_current = false;
  }

  // The grid cell list for search radii R (device array of n).
  void build_grid(const Real* R) {
    const std::size_t count = n();
    Real r_max = reduce_index<Real>(count, [=] __device__(std::size_t i) { return R[i]; }, Real(0),
                                    thrust::maximum<Real>());
    if (!(r_max > Real(0)) || !std::isfinite(r_max)) throw RunError("non-positive or non-finite search radius");
    Vec<D> mn, mx;
    extent(mn, mx);
    for (int k = 0; k < D; ++k)
      if (!std::isfinite(mn[k]) || !std::isfinite(mx[k])) throw RunError("non-finite particle position");
    GridNeighbors<D> g{};
    try {
      g.grid = make_uniform_grid<D>(domain, mn, mx, r_max, std::max(64.0, 4.0 * double(count)));
    } catch (const std::invalid_argument& e) {
      throw RunError(e.what());
    }
    const std::size_t cells = g.grid.cell_count();
    cell_start.resize(cells);
    cell_end.resize(cells);
    RUBBLE_CUDA(cudaMemset(cell_start.data(), 0, cells * sizeof(std::uint32_t)));
    RUBBLE_CUDA(cudaMemset(cell_end.data(), 0, cells * sizeof(std::uint32_t)));

    const StoreView<D> s = store.view();
    g.x = s.x;
    g.R = R;
    g.order = order.data();
    g.start = cell_start.data();
    g.end = cell_end.data();
    std::uint64_t* cell = keys.data();
    std::uint32_t* ord = order.data();
    const GridNeighbors<D> gg = g;
    for_each_index("cell ids", count, [=] __device__(std::size_t i) {
      cell[i] = gg.grid.cell_of(gg.x[i]);
      ord[i] = std::uint32_t(i);
    });
    thrust::sort_by_key(thrust::device, thrust::device_pointer_cast(cell), thrust::device_pointer_cast(cell + count),
                        thrust::device_pointer_cast(ord));
    cuda::check(cudaGetLastError(), "thrust::sort_by_key (cells)", __FILE__, __LINE__);
    std::uint32_t* st = cell_start.data();
    std::uint32_t* en = cell_end.data();
    for_each_index("cell ranges", count, [=] __device__(std::size_t i) {
      const std::uint64_t c = cell[i];
      if (i == 0 || cell[i - 1] != c) st[c] = std::uint32_t(i);
      if (i + 1 == count || cell[i + 1] != c) en[c] = std::uint32_t(i + 1);
    });
    grid = g;
  }

  void summation_density_and_h() {
    const std::size_t count = n();
    constexpr Real kSkin = Real(1.15);
    Real* R = search_radius.data();
    int* flag = flags.data();
    const StoreView<D> s0 = store.view();
    for_each_index("search radius", count, [=] __device__(std::size_t i) { R[i] = kSkin * s0.h[i]; });
    for (int attempt = 0; attempt < 8; ++attempt) {
      build_grid(R);
      const RhsContext<D> c = context();
      GridNeighbors<D> g = grid;
      for_each_index("summation density", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        // R is read by every thread's neighbour walk: grown radii are
        // written only after this kernel (below), not here
        flag[i] = summation_density_particle<D>(c, std::uint32_t(i), R[i], each) ? 0 : 1;
      });
      const int outgrown = reduce_index<int>(count, [=] __device__(std::size_t i) { return flag[i]; }, 0,
                                             thrust::plus<int>());
      if (outgrown == 0) return;
      for_each_index("grown search radius", count, [=] __device__(std::size_t i) {
        if (flag[i]) R[i] = kSkin * c.s.h[i];
      });
    }
    throw RunError("smoothing-length iteration did not settle after 8 neighbour rebuilds");
  }

  void evaluate() {
    ++evaluations;
    host_current = false;
    const std::size_t count = n();
    if (summation) {
      summation_density_and_h();
    } else {
      const RhsContext<D> c0 = context();
      for_each_index("h from density", count,
                     [=] __device__(std::size_t i) { h_from_density_particle<D>(c0, std::uint32_t(i)); });
      build_grid(c0.s.h);
    }
    const RhsContext<D> c = context();
    const GridNeighbors<D> g = grid;
    for_each_index("equation of state", count, [=] __device__(std::size_t i) { eos_particle<D>(c, std::uint32_t(i)); });
    if (plasticity)
      for_each_index("plastic return", count,
                     [=] __device__(std::size_t i) { plastic_return_particle<D>(c, std::uint32_t(i), false); });
    if (wall_extrapolation)
      for_each_index("wall extrapolation", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        wall_extrapolation_particle<D>(c, std::uint32_t(i), each);
      });
    if (solid) {
      int* flag = flags.data();
      for_each_index("solid velocity gradient", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        flag[i] = solid_gradient_particle<D>(c, std::uint32_t(i), each) ? 0 : 1;
      });
      fallbacks_total +=
          reduce_index<std::int64_t>(count, [=] __device__(std::size_t i) { return std::int64_t(flag[i]); },
                                     std::int64_t(0), thrust::plus<std::int64_t>());
      for_each_index("solid rates", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        solid_rates_particle<D>(c, std::uint32_t(i), each);
      });
    } else {
      for_each_index("hydro rates", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        hydro_rates_particle<D>(c, std::uint32_t(i), each);
      });
    }
    if (gravity.mode == GravityMode::Direct) self_gravity(c);
    else if (gravity.mode == GravityMode::BarnesHut) barnes_hut(c);
    if (body_force)
      for_each_index("body force", count, [=] __device__(std::size_t i) { body_force_particle<D>(c, std::uint32_t(i)); });
    if (c.s.boundary)
      for_each_index("hold boundaries", count,
                     [=] __device__(std::size_t i) { hold_boundary_particle<D>(c, std::uint32_t(i)); });

    if (xsph_epsilon > Real(0))
      for_each_index("xsph", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        xsph_particle<D>(c, std::uint32_t(i), each);
      });
  }

  // Direct summation on the device (3-D): the loop body of direct.hpp.
  void self_gravity(const RhsContext<D>& c) {
    if constexpr (D == 3) {
      const std::size_t count = n();
      Real* e = eps.data();
      const bool fixed = gravity.softening == GravitySoftening::Fixed;
      const Real eps_fixed = Real(gravity.softening_length);
      const StoreView<3> s = c.s;
      for_each_index("softening", count, [=] __device__(std::size_t i) { e[i] = fixed ? eps_fixed : s.h[i]; });
      const KernelType k = kernel;
      const Real G = Real(gravity.G);
      for_each_index("direct gravity", count, [=] __device__(std::size_t i) {
        const GravityField f = direct_field_of_particle(s.x, s.m, e, count, k, i);
        s.a_grav[i] = f.a * G;
        s.phi[i] = f.phi * G;
        s.dvdt[i] += s.a_grav[i];
      });
    } else {
      (void)c;
      throw RunError("self-gravity needs a 3-D scene");
    }
  }

  // Barnes-Hut on the device (3-D): DeviceOctree above.
  void barnes_hut(const RhsContext<D>& c) {
    if constexpr (D == 3) {
      const std::size_t count = n();
      eps.resize(count);
      Real* e = eps.data();
      const bool fixed = gravity.softening == GravitySoftening::Fixed;
      const Real eps_fixed = Real(gravity.softening_length);
      const StoreView<3> s = c.s;
      for_each_index("softening", count, [=] __device__(std::size_t i) { e[i] = fixed ? eps_fixed : s.h[i]; });
      octree.field(s.x, s.m, e, count, gravity, kernel, s.a_grav, s.phi, s.dvdt);
    } else {
      (void)c;
      throw RunError("self-gravity needs a 3-D scene");
    }
  }

  // After the integrator's last update of a step (hydro_cpu.hpp: end_step).
  void end_step(const Real* alpha_start, Real dt) {
    const RhsContext<D> c = context();
    if (porosity)
      for_each_index("end-of-step porosity", n(), [=] __device__(std::size_t i) {
        porosity_end_step_particle<D>(c, std::uint32_t(i), alpha_start);
      });
    if (damage)
      for_each_index("end-of-step damage cap", n(),
                     [=] __device__(std::size_t i) { damage_end_step_particle<D>(c, std::uint32_t(i)); });
    if (plasticity || porosity || damage)
      for_each_index("end-of-step equation of state", n(),
                     [=] __device__(std::size_t i) { eos_particle<D>(c, std::uint32_t(i)); });
    if (plasticity)
      for_each_index("end-of-step plastic return", n(),
                     [=] __device__(std::size_t i) { plastic_return_particle<D>(c, std::uint32_t(i), true); });
    if (shifting > Real(0)) {
      // with the grid of the last evaluation (hydro_cpu.cpp: shift_particles)
      const std::size_t count = n();
      shift.resize(count);
      Vec<D>* out = shift.data();
      const GridNeighbors<D> g = grid;
      const Real A = shifting;
      for_each_index("particle shifting", count, [=] __device__(std::size_t i) {
        GridNeighbors<D> each = g;
        each.a = std::uint32_t(i);
        shifting_particle<D>(c, std::uint32_t(i), A, dt, out, each);
      });
      const Box<D> dom = domain;
      const StoreView<D> s = c.s;
      for_each_index("apply shifts", count,
                     [=] __device__(std::size_t i) { s.x[i] = dom.wrap(s.x[i] + out[i]); });
    }
  }

  double dt_limit() {
    const RhsContext<D> c = context();
    return double(reduce_index<Real>(
        n(), [=] __device__(std::size_t i) { return dt_limit_particle<D>(c, std::uint32_t(i)); }, Real(1e30),
        thrust::minimum<Real>()));
  }

  void leapfrog(Real dt) {
    const std::size_t count = n();
    const StoreView<D> s = store.view();
    v_half.resize(count);
    u_half.resize(count);
    if (s.drhodt) rho_half.resize(count);
    if (s.dSdt) S_half.resize(count);
    if (s.dalphadt) {
      alpha_half.resize(count);
      alpha_start.resize(count);
      RUBBLE_CUDA(cudaMemcpy(alpha_start.data(), s.alpha, count * sizeof(Real), cudaMemcpyDeviceToDevice));
    }
    if (s.ddamage_root_dt) damage_half.resize(count);
    const LeapfrogHalf<D> half{v_half.data(),
                               u_half.data(),
                               s.drhodt ? rho_half.data() : nullptr,
                               s.dSdt ? S_half.data() : nullptr,
                               s.dalphadt ? alpha_half.data() : nullptr,
                               s.ddamage_root_dt ? damage_half.data() : nullptr};
    const Box<D> dom = domain;
    for_each_index("leapfrog kick-drift", count,
                   [=] __device__(std::size_t i) { leapfrog_kick_drift<D>(s, half, dom, i, dt); });
    evaluate();
    for_each_index("leapfrog kick", count, [=] __device__(std::size_t i) { leapfrog_kick<D>(s, half, i, dt); });
    end_step(s.dalphadt ? alpha_start.data() : nullptr, dt);
  }

  Rk2Result rk2(Real dt, Real tol, Real dt_min) {
    const std::size_t count = n();
    if (y0.size() != count) {
      y0.allocate_as(store);
      y1.allocate_as(store);
    }
    y0.copy_from(store);  // state and k1 (its rates)
    const StoreView<D> v0 = y0.view(), v1 = y1.view(), y = store.view();
    const Box<D> dom = domain;
    int rejections = 0;
    for (;;) {
      for_each_index("rk2 stage 2", count,
                     [=] __device__(std::size_t i) { rk2_combine<D>(y, v0, v0, nullptr, dt, dom, i); });
      evaluate();
      y1.copy_from(store);  // k2 = rates of y1
      const Real q = Real(0.25) * dt;
      for_each_index("rk2 stage 3", count, [=] __device__(std::size_t i) {
        rk2_combine<D>(y, v0, v0, &v1, q, dom, i);
      });
      evaluate();  // k3 = rates in the store
      const Real c23 = Real(2) / Real(3) * dt;
      const Real err = reduce_index<Real>(
          count, [=] __device__(std::size_t i) { return rk2_error_particle<D>(v0, v1, y, c23, i); }, Real(0),
          thrust::maximum<Real>());
      const Real factor = rk2_step_factor(err, tol);
      if (err <= tol || dt <= dt_min) {
        const Real h2 = Real(0.5) * dt;
        for_each_index("rk2 final", count, [=] __device__(std::size_t i) {
          rk2_combine<D>(y, v0, v0, &v1, h2, dom, i);
        });
        end_step(v0.alpha, dt);
        evaluate();  // k1 of the next step
        return {dt, dt * factor, rejections};
      }
      store.copy_from(y0);  // rejected: back to y_n with a smaller step
      dt = std::max(dt * factor, dt_min);
      ++rejections;
    }
  }
};

template <int D>
CudaStepper<D>::CudaStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain, bool resumed)
    : impl_(std::make_unique<Impl>(scene, ps, domain)) {
  if (resumed) return;
  impl_->sort_particles();
  impl_->evaluate();
}

template <int D>
CudaStepper<D>::~CudaStepper() = default;

template <int D>
void CudaStepper<D>::sort_particles() {
  impl_->sort_particles();
}

template <int D>
double CudaStepper<D>::dt_limit() {
  return impl_->dt_limit();
}

template <int D>
void CudaStepper<D>::leapfrog(double dt) {
  impl_->leapfrog(Real(dt));
}

template <int D>
Rk2Result CudaStepper<D>::rk2(double dt, double tol, double dt_min) {
  return impl_->rk2(Real(dt), Real(tol), Real(dt_min));
}

template <int D>
void CudaStepper<D>::damp(double f) {
  const StoreView<D> s = impl_->store.view();
  const Real fr = Real(f);
  for_each_index("damping", impl_->n(), [=] __device__(std::size_t i) { s.v[i] *= fr; });
  impl_->host_current = false;
}

template <int D>
std::size_t CudaStepper<D>::first_non_finite() {
  const StoreView<D> s = impl_->store.view();
  const std::size_t count = impl_->n();
  return reduce_index<std::size_t>(
      count, [=] __device__(std::size_t i) { return finite_particle<D>(s, std::uint32_t(i)) ? count : i; }, count,
      thrust::minimum<std::size_t>());
}

template <int D>
ConservedRecord CudaStepper<D>::conserved(double t, std::int64_t step, double dt) {
  const StoreView<D> s = impl_->store.view();
  const Vec<D> g = impl_->g;
  const ConservedSums sum = reduce_index<ConservedSums>(
      impl_->n(), [=] __device__(std::size_t i) { return conserved_particle<D>(s, i, g); }, ConservedSums{},
      thrust::plus<ConservedSums>());
  return conserved_record(sum, t, step, dt);
}

template <int D>
const ParticleStore<D>& CudaStepper<D>::host() {
  if (!impl_->host_current) {
    impl_->bytes_downloaded += std::int64_t(impl_->store.download(impl_->host));
    impl_->host_current = true;
  }
  return impl_->host;
}

template <int D>
void CudaStepper<D>::keep_good() {
  impl_->good.copy_snapshot_fields_from(impl_->store);
}

template <int D>
const ParticleStore<D>& CudaStepper<D>::last_good() {
  if (impl_->good_host.n != impl_->n()) impl_->good.allocate_host(impl_->good_host);
  impl_->bytes_downloaded += std::int64_t(impl_->good.download(impl_->good_host));
  return impl_->good_host;
}

template <int D>
std::size_t CudaStepper<D>::size() const {
  return impl_->n();
}

template <int D>
std::int64_t CudaStepper<D>::bytes_downloaded() const {
  return impl_->bytes_downloaded;
}

template <int D>
std::int64_t CudaStepper<D>::correction_fallbacks() const {
  return impl_->fallbacks_total;
}

template <int D>
std::int64_t CudaStepper<D>::evaluations() const {
  return impl_->evaluations;
}

template <int D>
bool CudaStepper<D>::solid() const {
  return impl_->solid;
}

DeviceGravityTiming cuda_barnes_hut_field(const Vec<3>* x, const Real* m, const Real* eps, std::size_t n,
                                          const GravityConfig& gravity, KernelType kernel, Vec<3>* acc, Real* phi) {
  int devices = 0;
  if (cudaGetDeviceCount(&devices) != cudaSuccess || devices == 0) throw RunError("no CUDA device available");
  DeviceArray<Vec<3>> dx, da;
  DeviceArray<Real> dm, de, dp;
  dx.resize(n);
  da.resize(n);
  dm.resize(n);
  de.resize(n);
  dp.resize(n);
  std::vector<Real> e(n, Real(0));
  if (eps) e.assign(eps, eps + n);
  RUBBLE_CUDA(cudaMemcpy(dx.data(), x, n * sizeof(Vec<3>), cudaMemcpyHostToDevice));
  RUBBLE_CUDA(cudaMemcpy(dm.data(), m, n * sizeof(Real), cudaMemcpyHostToDevice));
  RUBBLE_CUDA(cudaMemcpy(de.data(), e.data(), n * sizeof(Real), cudaMemcpyHostToDevice));
  DeviceOctree tree;
  DeviceGravityTiming t;
  tree.field(dx.data(), dm.data(), de.data(), n, gravity, kernel, da.data(), dp.data(), nullptr, &t);
  RUBBLE_CUDA(cudaMemcpy(acc, da.data(), n * sizeof(Vec<3>), cudaMemcpyDeviceToHost));
  if (phi) RUBBLE_CUDA(cudaMemcpy(phi, dp.data(), n * sizeof(Real), cudaMemcpyDeviceToHost));
  return t;
}

template class CudaStepper<1>;
template class CudaStepper<2>;
template class CudaStepper<3>;

}  // namespace rubble
