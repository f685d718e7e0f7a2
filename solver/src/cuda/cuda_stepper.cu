// The CUDA backend (issue #6): device-resident particles, a cell list over a
// device radix sort, and the step sequence the CPU runs
// (rubble/drivers/step_sequence.hpp; issue #51): this file supplies only
// the backend (CudaBackend below: loops as kernels, reductions, device
// arrays, sort, search, gravity). See cuda_stepper.hpp for the time loop's
// interface and DESIGN.md principles 1, 4, 5 and 6 for why it is shaped
// this way.
//
// What runs where:
//   sort_particles   Morton keys of the positions (morton.hpp), a stable
//                    radix sort of (key, index) on the device (Thrust, which
//                    uses CUB's radix sort for integer keys), and a gather of
//                    every allocated field: the same permutation as the CPU's
//                    spatial_sort_permutation.
//   neighbours       a uniform grid of cells max(r_typ / 2, r_max / 4) wide
//                    (r_typ the geometric mean of the search radii; cells
//                    hashed into at most 2n slots when the particles' extent
//                    holds more, e.g. a far outlier); (slot, index) pairs
//                    radix-sorted on the device, per slot a start/end range,
//                    the largest R of its particles and the largest R of any
//                    ball touching it (atomic maxima), and a visitor
//                    (GridNeighbors) that inspects the cells within
//                    max(R_a, that reach) and offers the particles of those
//                    within max(R_a, cell's R max) to the loop body, which
//                    keeps those within max(R_a, R_b) - the CPU cell list's
//                    criterion. See uniform_grid.hpp (why, and the test
//                    against the CPU cell list). Summation density gathers
//                    each particle's candidates within its own radius once
//                    into a list in thread-local memory and reuses it over
//                    its smoothing-length Newton iterations
//                    (candidate_list.hpp).
//   right-hand side  one kernel per pass of the step sequence, each a loop
//                    body of rubble/drivers/particle_rates.hpp.
//   integrators      leapfrog_step and rk2_adaptive_step (integrate/), their
//                    per-particle steps as kernels.
//   reductions       time-step limit, conserved sums, finiteness, counts:
//                    thrust::transform_reduce over the particle index.
// The sums over neighbours run in cell order, not in ascending index order
// as on the CPU, so results differ by rounding (the parity test bounds it).
//
// Per-step host traffic (issue #15 item 5). Nothing is allocated inside a
// step: buffers grow only when they must hold more than ever before (in
// practice while the stepper is set up and in its first step), and the
// sorts and reductions take their temporary storage from a caching
// allocator (CachingDeviceAllocator) instead of a cudaMalloc and cudaFree
// per call. All work is queued on one stream; the host waits for the
// device only where it needs a result (a "host synchronisation", counted
// in cuda_backend_counts()). Reductions that read the same data in the
// same phase are one reduction over a struct. Per step:
//   state check + next step's time-step limit   1  (StateCheck: the loop's
//                    first_non_finite() after a step and dt_limit() before
//                    the next read the same state)
//   per right-hand-side evaluation              1  the grid's extent and
//                    largest search radius (Extent)
//     + summation density                       1  per smoothing-length
//                    attempt (whether an h outgrew its search radius)
//     + Barnes-Hut                              1  the octree's level
//                    counts (its extent is the grid's)
//     solids' correction fallbacks, direct gravity, sorts, scatters: none
//   re-sort along the curve (every 16 steps)    1  the extent
//   conserved.csv row (when one is due)         1
// so a leapfrog step (one evaluation) of 3-D hydro with summation density
// takes 3 (plus 1 every 16th step), of a continuity-density solid 2, and
// with Barnes-Hut gravity one more; an RK2 step (three evaluations and its
// error norm) 2 + 3 x (1, 2 or 3). Snapshots download the store (one copy
// per field). Before issue #15 the 3-D hydro step took 11 (six per-axis
// extent reductions, the largest radius, the time-step limit, the state
// check, the h check and the cell sort, each with a cudaMalloc and a
// cudaFree of Thrust's temporary storage), solids one more per evaluation
// (their fallback count), and Barnes-Hut 3L + 10 more (L the tree's
// levels: a scan and two copies per level).
#include <cuda/functional>
#include <cuda_runtime.h>
#include <thrust/device_ptr.h>
#include <thrust/execution_policy.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/reduce.h>
#include <thrust/sort.h>
#include <thrust/system/cuda/execution_policy.h>
#include <thrust/transform_reduce.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "cuda/cuda_check.hpp"
#include "cuda/cuda_stepper.hpp"
#include "rubble/core/error.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/drivers/particle_rates.hpp"
#include "rubble/drivers/run_physics.hpp"
#include "rubble/drivers/step_sequence.hpp"
#include "rubble/gravity/direct.hpp"
#include "rubble/gravity/octree.hpp"
#include "rubble/gravity/octree_build.hpp"
#include "rubble/gravity/device_gravity.hpp"
#include "rubble/integrate/leapfrog.hpp"
#include "rubble/integrate/rk2_adaptive.hpp"
#include "rubble/io/conserved_sums.hpp"
#include "rubble/neighbors/candidate_list.hpp"
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

// The counts behind cuda_backend_counts() (cuda_stepper.hpp).
std::atomic<std::int64_t> g_device_allocations{0};
std::atomic<std::int64_t> g_host_synchronisations{0};

// Every cudaMalloc of the backend goes through here, so that it is counted.
void* device_malloc(std::size_t bytes) {
  void* p = nullptr;
  RUBBLE_CUDA(cudaMalloc(&p, bytes));
  ++g_device_allocations;
  return p;
}

// A device-to-host copy into pageable host memory: the host waits for the
// device's earlier work and the copy (one host synchronisation, counted).
void copy_to_host(void* host, const void* device, std::size_t bytes) {
  RUBBLE_CUDA(cudaMemcpy(host, device, bytes, cudaMemcpyDeviceToHost));
  ++g_host_synchronisations;
}

// Temporary storage of Thrust's algorithms (radix sorts, reductions), kept
// for reuse instead of Thrust's default cudaMalloc and cudaFree per call
// (cudaFree also stalls the host until the device is idle). Passed through
// the execution policy: thrust::cuda::par_nosync(alloc).
//
// A freed block goes back to the cache and the next request takes the
// smallest cached block that fits; a block is released only by the
// destructor. Every call asks for one temporary block at a time, its size a
// function of the particle count (constant over a run), so once each call
// of a step has run once every request finds its block: no allocation
// inside a step after the first. Safe to reuse at once because all of the
// backend's work is on one stream (the default): a kernel that still reads
// a freed block runs before any later kernel that gets it.
class CachingDeviceAllocator {
 public:
  using value_type = char;  // the interface Thrust expects of a temporary allocator

  CachingDeviceAllocator() = default;
  ~CachingDeviceAllocator() {
    for (const auto& [bytes, p] : free_) cudaFree(p);  // no throw from a destructor
    for (const auto& [p, bytes] : used_) cudaFree(p);
  }
  CachingDeviceAllocator(const CachingDeviceAllocator&) = delete;
  CachingDeviceAllocator& operator=(const CachingDeviceAllocator&) = delete;

  char* allocate(std::ptrdiff_t count) {
    const std::size_t bytes = count > 0 ? std::size_t(count) : 1;
    char* p = nullptr;
    std::size_t size = bytes;
    const auto fit = free_.lower_bound(bytes);  // the smallest cached block that is large enough
    if (fit != free_.end()) {
      size = fit->first;
      p = fit->second;
      free_.erase(fit);
    } else {
      p = static_cast<char*>(device_malloc(bytes));
    }
    used_.emplace(p, size);
    return p;
  }

  // Thrust passes the requested size; the block's own size is in used_.
  void deallocate(char* p, std::size_t) noexcept {
    const auto it = used_.find(p);
    if (it == used_.end()) return;  // not ours (cannot happen): leave it
    free_.emplace(it->second, p);
    used_.erase(it);
  }

 private:
  std::multimap<std::size_t, char*> free_;  // cached blocks by size
  std::map<char*, std::size_t> used_;       // blocks handed out, with their sizes
};

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

// Reduce op(f(i)) over i in [0, n) on the device, temporary storage from
// `alloc`. Returning the result to the host is one host synchronisation:
// where several reductions read the same data in the same phase, they are
// one reduction over a struct (Extent, StateCheck below).
template <class T, class F, class Op>
T reduce_index(CachingDeviceAllocator& alloc, std::size_t n, F f, T init, Op op) {
  if (n == 0) return init;
  const thrust::counting_iterator<std::size_t> first(0);
  // the device lambda's result type, stated for the host side of Thrust
  T r = thrust::transform_reduce(thrust::cuda::par_nosync(alloc), first, first + n,
                                 ::cuda::proclaim_return_type<T>(f), init, op);
  cuda::check(cudaGetLastError(), "thrust::transform_reduce", __FILE__, __LINE__);
  ++g_host_synchronisations;
  return r;
}

// Stable radix sort of (key, value) pairs on the device, temporary storage
// from `alloc`; par_nosync: the host does not wait for it.
template <class K, class V>
void sort_pairs(CachingDeviceAllocator& alloc, K* keys, V* values, std::size_t n, const char* what) {
  if (n == 0) return;
  thrust::sort_by_key(thrust::cuda::par_nosync(alloc), thrust::device_pointer_cast(keys),
                      thrust::device_pointer_cast(keys + n), thrust::device_pointer_cast(values));
  cuda::check(cudaGetLastError(), what, __FILE__, __LINE__);
  if (cuda::sync_check_enabled()) cuda::check(cudaDeviceSynchronize(), what, __FILE__, __LINE__);
}

// Atomic maximum of a non-negative Real (a search radius) in device memory:
// the bit patterns of non-negative IEEE numbers order as unsigned integers.
// The read first skips the atomic where a larger value is already there
// (values only grow during a kernel, from the zeros written before it).
__device__ inline void atomic_max_positive(Real* p, Real v) {
  if (*p >= v) return;
  if constexpr (sizeof(Real) == 8) {
    atomicMax(reinterpret_cast<unsigned long long*>(p), static_cast<unsigned long long>(__double_as_longlong(double(v))));
  } else {
    atomicMax(reinterpret_cast<unsigned int*>(p), __float_as_uint(float(v)));
  }
}

// The particles' extent on every axis and, where R is given, their largest
// search radius: one reduction where the grid needs all three.
template <int D>
struct Extent {
  Vec<D> lo, hi;
  Real r_max;
  double log_r_sum;  // sum of log R: the grid's typical radius (geometric mean)
};

// thrust::minimum's and thrust::maximum's rules, per component.
template <int D>
struct ExtentUnion {
  __host__ __device__ Extent<D> operator()(const Extent<D>& a, const Extent<D>& b) const {
    Extent<D> r;
    for (int k = 0; k < D; ++k) {
      r.lo[k] = a.lo[k] < b.lo[k] ? a.lo[k] : b.lo[k];
      r.hi[k] = a.hi[k] < b.hi[k] ? b.hi[k] : a.hi[k];
    }
    r.r_max = a.r_max < b.r_max ? b.r_max : a.r_max;
    r.log_r_sum = a.log_r_sum + b.log_r_sum;
    return r;
  }
};

template <int D>
Extent<D> extent_of(CachingDeviceAllocator& alloc, const Vec<D>* x, const Real* R, std::size_t n) {
  Extent<D> init;
  for (int k = 0; k < D; ++k) {
    init.lo[k] = std::numeric_limits<Real>::max();
    init.hi[k] = std::numeric_limits<Real>::lowest();
  }
  init.r_max = Real(0);
  init.log_r_sum = 0;
  return reduce_index<Extent<D>>(
      alloc, n,
      [=] __device__(std::size_t i) {
        Extent<D> e;
        e.lo = x[i];
        e.hi = x[i];
        e.r_max = R ? R[i] : Real(0);
        e.log_r_sum = R ? ::log(double(R[i])) : 0.0;
        return e;
      },
      init, ExtentUnion<D>());
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
    p_ = device_malloc(bytes);
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
      copy_to_host(host, d.buf.get(), bytes);
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
  std::size_t size() const { return n; }
};

// Barnes-Hut on the device: the octree of gravity/octree_build.hpp built
// level by level over the particles sorted by the tree's own keys (the cube
// around their bounding box, as Octree::build), then one walk per particle
// (octree_field, as Octree with group_size 0 or 1). The same tree as the
// CPU's, node for node; with the CPU's default group walk the fields differ
// by the multipole error, not by rounding.
//
// Host synchronisations: one per build (the level counts), plus the extent
// reduction when the caller does not pass the extent (the stepper passes
// the neighbour grid's, computed from the same positions in the same
// evaluation).
//
// Why the discovery needs no copy per level. The breadth-first levels are
// discovered on the device with their counts kept there: a node's children
// take their places in the next level with one atomicAdd on that level's
// count, and every level's kernel is launched without the host knowing its
// size (a grid-stride loop over the count it reads from device memory).
// That needs, known beforehand,
//   - the number of levels: at most kOctreeMaxLevel + 1, since each level
//     starts at least one key level below its parent's (octree_split_level)
//     and a node at the finest key level is a leaf;
//   - room for the nodes: the levels are stored one after the other in one
//     array. Every inner node has at least two children (levels where all
//     particles fall into one octant are skipped) and every leaf at least
//     one particle, so a tree has at most 2n - 1 nodes. The array starts
//     smaller (most trees have far fewer nodes), a child that does not fit
//     sets an overflow flag that stops the later levels, and the build is
//     repeated with twice the room, up to 2n - 1 (kept for later builds).
// After the discovery the level counts (a few bytes) are downloaded once:
// the host then knows every level's size and offset and the node count, and
// the remaining passes run as exact per-level launches, as before. The
// order of a level's nodes depends on the order of the atomic adds, but
// nothing else does: a node's children stay contiguous and in octant order,
// and the depth-first ids (from subtree sizes) fix the final node array.
// The remaining passes launch one kernel per level, with no host
// synchronisation.
constexpr std::uint32_t kOctreeLevels = kOctreeMaxLevel + 1;  // breadth-first levels at most
// The device counts: one per level; one more for the children of the
// deepest level (there are none: it must stay 0); an overflow flag.
constexpr std::uint32_t kOctreeCountSlots = kOctreeLevels + 2;
constexpr std::uint32_t kOctreeOverflow = kOctreeLevels + 1;
constexpr unsigned kMaxGridStrideBlocks = 2048;

// Discovery of level l (one launch per level): the level's nodes are
// nodes[begin, begin + counts[l]), begin the sum of the earlier levels'
// counts; their pending ranges are at the same indices of `pending`. Each
// node is discovered (octree_discover) and its children are appended to the
// next level: parent and first_child are indices within their levels, as
// octree_build_by_levels has them.
__global__ void octree_discover_level(std::uint32_t l, const std::uint64_t* keys, std::uint32_t leaf_size,
                                      OctreePending* pending, OctreeLevelNode* nodes, std::uint32_t* counts,
                                      std::size_t capacity) {
  if (counts[kOctreeOverflow] != 0) return;  // an earlier level did not fit: the build is repeated
  std::size_t begin = 0;
  for (std::uint32_t j = 0; j < l; ++j) begin += counts[j];
  const std::uint32_t F = counts[l];
  const std::size_t next_begin = begin + F;
  const std::size_t stride = std::size_t(gridDim.x) * blockDim.x;
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < F; i += stride) {
    OctreeLevelNode& nd = nodes[begin + i];
    std::uint32_t first[9];
    const std::uint32_t c = octree_discover(keys, pending[begin + i], leaf_size, nd, first);
    if (c == 0) continue;
    // a level's nodes are disjoint non-empty particle ranges, so no count
    // exceeds n (< 2^31, checked by the caller): no wrap-around
    const std::uint32_t slot = atomicAdd(&counts[l + 1], c);
    if (next_begin + slot + c > capacity) {
      atomicOr(&counts[kOctreeOverflow], 1u);
      continue;
    }
    nd.first_child = slot;
    for (std::uint32_t k = 0; k < c; ++k)
      pending[next_begin + slot + k] = OctreePending{first[k], first[k + 1], nd.node.level + 1, std::uint32_t(i)};
  }
}

class DeviceOctree {
 public:
  // Field of n particles (device arrays x, m, eps; store order) times G:
  // a_grav and phi written, a_grav added to dvdt when dvdt is not null.
  // `extent`: the positions' extent when the caller has it (else reduced
  // here). Build and walk times (device-synchronised) go to *timing when
  // given.
  void field(const Vec<3>* x, const Real* m, const Real* e, std::size_t count, const GravityConfig& gravity,
             KernelType kernel, Vec<3>* a_grav, Real* phi, Vec<3>* dvdt, const Extent<3>* extent = nullptr,
             DeviceGravityTiming* timing = nullptr) {
    if (count == 0) return;
    // node indices are 32-bit and a tree has up to 2n - 1 nodes
    if (count > (std::size_t(1) << 31)) throw RunError("Barnes-Hut on the device: more than 2^31 particles");
    const auto t0 = std::chrono::steady_clock::now();
    const std::uint32_t n32 = std::uint32_t(count);
    // the tree's keys and sorted copies
    const Extent<3> ext = extent ? *extent : extent_of<3>(temp_, x, nullptr, count);
    const Box<3> kb = octree_key_box(bounding_box_from_extent<3>(Box<3>{}, ext.lo, ext.hi));
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
    sort_pairs(temp_, k, o, count, "thrust::sort_by_key (tree keys)");
    Vec<3>* tx = x_.data();
    Real* tm = m_.data();
    Real* te = eps_.data();
    for_each_index("tree gather", count, [=] __device__(std::size_t j) {
      tx[j] = x[o[j]];
      tm[j] = m[o[j]];
      te[j] = e[o[j]];
    });

    // 1. discovery, all levels on the device; then the level counts, once
    const std::uint32_t leaf_size = std::uint32_t(std::max(1, gravity.leaf_size));
    const std::size_t bound = 2 * count - 1;  // nodes of any tree of `count` particles (above)
    // first guess: uniform particles make about 0.5 n nodes at leaf_size 8
    // and 0.12 n at 32 (a host simulation of this build), clustered ones fewer
    if (capacity_ == 0) capacity_ = std::min(bound, std::max<std::size_t>(1024, 6 * count / leaf_size));
    counts_.resize(kOctreeCountSlots);
    std::uint32_t counts[kOctreeCountSlots];
    for (;;) {
      pending_.resize(capacity_);
      lnodes_.resize(capacity_);
      OctreePending* pend = pending_.data();
      OctreeLevelNode* lnodes = lnodes_.data();
      std::uint32_t* cnt = counts_.data();
      for_each_index("octree root", kOctreeCountSlots, [=] __device__(std::size_t i) {
        cnt[i] = i == 0 ? 1u : 0u;
        if (i == 0) pend[0] = OctreePending{0, n32, 0, 0xFFFFFFFFu};
      });
      for (std::uint32_t l = 0; l < kOctreeLevels; ++l) {
        // level l has at most min(n, 8^l) nodes
        const std::size_t most = l < 10 ? std::min<std::size_t>(count, std::size_t(1) << (3 * l)) : count;
        const unsigned blocks = unsigned(std::min<std::size_t>((most + kBlock - 1) / kBlock, kMaxGridStrideBlocks));
        octree_discover_level<<<blocks, kBlock>>>(l, k, leaf_size, pend, lnodes, cnt, capacity_);
        cuda::check(cudaGetLastError(), "octree discovery", __FILE__, __LINE__);
        if (cuda::sync_check_enabled()) cuda::check(cudaDeviceSynchronize(), "octree discovery", __FILE__, __LINE__);
      }
      copy_to_host(counts, cnt, sizeof counts);  // the build's one host synchronisation
      if (counts[kOctreeOverflow] == 0) break;
      if (capacity_ >= bound) throw RunError("octree build: more nodes than a tree can have (a bug)");
      capacity_ = std::min(bound, 2 * capacity_);
    }
    std::size_t L = 0, node_count = 0;  // levels in use, nodes in all
    std::size_t begin[kOctreeLevels];   // each level's first node in lnodes_
    while (L < kOctreeLevels && counts[L] > 0) {
      begin[L] = node_count;
      node_count += counts[L++];
    }
    for (std::size_t l = L; l <= kOctreeLevels; ++l)
      if (counts[l] != 0) throw RunError("octree build: a level below an empty one (a bug)");
    if (node_count > capacity_) throw RunError("octree build: more nodes than room (a bug)");
    OctreeLevelNode* const lnodes = lnodes_.data();
    // 2. subtree sizes, bottom up
    for (std::size_t l = L; l-- > 1;) {
      const OctreeLevelNode* lv = lnodes + begin[l];
      OctreeLevelNode* up = lnodes + begin[l - 1];
      for_each_index("octree sizes", counts[l], [=] __device__(std::size_t i) {
        atomicAdd(reinterpret_cast<unsigned int*>(&up[lv[i].parent].size), unsigned(lv[i].size));
      });
    }
    // 3. depth-first ids, top down (the root's id, 0, is set by the discovery)
    for (std::size_t l = 0; l + 1 < L; ++l) {
      const OctreeLevelNode* lv = lnodes + begin[l];
      OctreeLevelNode* down = lnodes + begin[l + 1];
      for_each_index("octree ids", counts[l], [=] __device__(std::size_t i) { octree_number_children(lv[i], down); });
    }
    // every node is in the root's subtree: its size is node_count
    nodes_.resize(node_count);
    OctreeNode* nodes = nodes_.data();
    // 4. moments bottom up, into the depth-first array
    const Real theta = Real(gravity.theta);
    for (std::size_t l = L; l-- > 0;) {
      OctreeLevelNode* lv = lnodes + begin[l];
      const OctreeLevelNode* next = l + 1 < L ? lnodes + begin[l + 1] : nullptr;
      for_each_index("octree moments", counts[l], [=] __device__(std::size_t i) {
        nodes[lv[i].id] = octree_finish_level_node(lv[i], next, k, tx, tm, te, kb, theta);
      });
    }
    if (timing) RUBBLE_CUDA(cudaDeviceSynchronize());  // only to time the build
    const auto t1 = std::chrono::steady_clock::now();
    // 5. one walk per particle
    OctreeView view;
    view.nodes = nodes;
    view.node_count = std::uint32_t(node_count);
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
      timing->nodes = std::uint32_t(node_count);
    }
  }

 private:
  CachingDeviceAllocator temp_;  // the sort's and the extent's temporary storage
  DeviceArray<std::uint64_t> keys_;
  DeviceArray<std::uint32_t> order_, counts_;
  DeviceArray<Vec<3>> x_;
  DeviceArray<Real> m_, eps_;
  std::size_t capacity_ = 0;            // room for nodes in pending_ and lnodes_ (grows, kept)
  DeviceArray<OctreePending> pending_;  // every level's pending ranges, level after level
  DeviceArray<OctreeLevelNode> lnodes_; // every level's nodes, at the same indices
  DeviceArray<OctreeNode> nodes_;       // the depth-first node array the walk reads
};

}  // namespace

// A particle's neighbours within its own search radius, for summation
// density (the `OwnNeighbours` of the step sequence): the candidates the
// kernel gathered into its thread's list, or, when they did not fit, the
// grid walked again on every Newton iteration (the same particles in the
// same order, candidate_list.hpp).
template <int D>
struct OwnCandidates {
  const CandidateList<kCandidateListCapacity<D>>* list;  // nullptr: walk the grid
  GridOwnRadius<D> own;
  template <class F>
  RUBBLE_HD void operator()(F&& f) const {
    if (list) (*list)(f);
    else own(f);
  }
};

// What the step sequence (rubble/drivers/step_sequence.hpp) asks of a
// backend, on the device: loops as kernels, reductions through Thrust,
// arrays in device memory, the radix sort along the curve, the uniform-grid
// neighbour search and self-gravity. Every member function that launches a
// lambda is public (nvcc's extended lambdas).
template <int D>
class CudaBackend {
 public:
  template <class T>
  using Array = DeviceArray<T>;
  using Store = DeviceStore<D>;
  using Neighbours = GridNeighbors<D>;
  using OwnNeighbours = OwnCandidates<D>;

  CudaBackend(const RunPhysics& physics, const ParticleStore<D>& ps, const Box<D>& dom)
      : domain(dom), kernel(physics.kernel), gravity(physics.gravity) {
    int devices = 0;
    const cudaError_t err = cudaGetDeviceCount(&devices);
    if (err != cudaSuccess || devices == 0)
      throw RunError(std::string("--backend cuda: no CUDA device available (") +
                     (err != cudaSuccess ? cudaGetErrorString(err) : "device count 0") + ")");
    if (ps.n > std::numeric_limits<std::uint32_t>::max()) throw RunError("more than 2^32 - 1 particles");
    require_fields<D>(physics.on, ps);
    materials_.resize(physics.materials.size());
    RUBBLE_CUDA(cudaMemcpy(materials_.data(), physics.materials.data(),
                           physics.materials.size() * sizeof(MaterialParams), cudaMemcpyHostToDevice));
    const std::size_t n = ps.n;
    store.allocate_like(ps);
    store.upload(ps);
    if (physics.on.gravity) eps.resize(n);
    keys.resize(n);
    order.resize(n);
    perm.resize(n);
  }

  std::size_t size() const { return store.size(); }
  StoreView<D> view() const { return store.view(); }
  const MaterialParams* materials() const { return materials_.data(); }

  template <class F>
  void for_each(const char* what, std::size_t n, F f) {
    for_each_index(what, n, f);
  }
  template <class F>
  void for_each_neighbours(const char* what, F f) {
    const GridNeighbors<D> g = grid;
    for_each_index(what, size(), [=] __device__(std::size_t i) {
      GridNeighbors<D> each = g;
      each.a = std::uint32_t(i);
      f(std::uint32_t(i), each);
    });
  }
  // Summation density's Newton iterations on h (h <= R[i] throughout) need
  // only the particles within R[i]: gathered once into a list in the
  // thread's local memory and offered again on every iteration.
  template <class F>
  void for_each_in_own_radius(const char* what, const Real* /*R: the grid's*/, F f) {
    const GridNeighbors<D> g = grid;
    for_each_index(what, size(), [=] __device__(std::size_t i) {
      GridNeighbors<D> each = g;
      each.a = std::uint32_t(i);
      const GridOwnRadius<D> own{each};
      CandidateList<kCandidateListCapacity<D>> list;
      const bool listed = list.gather(own);
      f(std::uint32_t(i), OwnCandidates<D>{listed ? &list : nullptr, own});
    });
  }
  // One host synchronisation (the result).
  template <class T, class F, class Op>
  T reduce(std::size_t n, F f, T init, Op op) {
    return reduce_index<T>(temp, n, f, init, op);
  }

  IntegratorScratch<D, DeviceArray, DeviceStore<D>>& integrator_scratch() { return scratch; }
  void save_state(DeviceStore<D>& copy) {
    if (copy.size() != store.size()) copy.allocate_as(store);
    copy.copy_from(store);
  }
  void restore_state(const DeviceStore<D>& copy) { store.copy_from(copy); }
  static StoreView<D> view_of(DeviceStore<D>& copy) { return copy.view(); }

  template <class T>
  static void zero(DeviceArray<T>& a) {
    RUBBLE_CUDA(cudaMemset(a.data(), 0, a.size() * sizeof(T)));
  }
  static std::int64_t read_count(const DeviceArray<unsigned long long>& a) {
    unsigned long long count = 0;
    copy_to_host(&count, a.data(), sizeof count);
    return std::int64_t(count);
  }

  // The CPU's pair-once loops have no device form: the gather loops run.
  bool hydro_pair_once(const RhsContext<D>&) { return false; }
  bool solid_gradients_pair_once(const RhsContext<D>&, unsigned long long*) { return false; }
  bool solid_forces_pair_once(const RhsContext<D>&) { return false; }
  // The grid is built anew for every evaluation.
  bool search_still_holds(const Real*) const { return false; }

  // Sort along the space-filling curve: the CPU's permutation, on the device.
  // One host synchronisation (the extent).
  void sort(const Box<D>& dom) {
    const std::size_t count = size();
    if (count == 0) return;
    const Extent<D> ext = extent_of<D>(temp, store.view().x, nullptr, count);
    const Box<D> box = bounding_box_from_extent<D>(dom, ext.lo, ext.hi);
    const Vec<D>* x = store.view().x;
    std::uint64_t* k = keys.data();
    std::uint32_t* p = perm.data();
    for_each_index("morton keys", count, [=] __device__(std::size_t i) {
      k[i] = morton_key<D>(x[i], box);
      p[i] = std::uint32_t(i);
    });
    // LSD radix sort: stable, so equal keys keep their index order as on the CPU
    sort_pairs(temp, k, p, count, "thrust::sort_by_key (Morton keys)");
    store.permute(p, scratch_buffer);
  }

  // The grid cell list for search radii R (device array of n), see
  // uniform_grid.hpp. One host synchronisation: the extent, the largest
  // radius and the sum of log R, one reduction.
  void search(const Real* R, bool /*keepable: the grid is not kept*/) {
    const std::size_t count = size();
    const Extent<D> ext = extent_of<D>(temp, store.view().x, R, count);
    const Real r_max = ext.r_max;
    if (!(r_max > Real(0)) || !std::isfinite(r_max)) throw RunError("non-positive or non-finite search radius");
    for (int k = 0; k < D; ++k)
      if (!std::isfinite(ext.lo[k]) || !std::isfinite(ext.hi[k])) throw RunError("non-finite particle position");
    grid_extent = ext;
    const Real r_typ = Real(std::exp(ext.log_r_sum / double(count)));
    GridNeighbors<D> g{};
    try {
      // at most 2n slots (start, end, two radii: 24 bytes each in double)
      g.grid = make_uniform_grid<D>(domain, ext.lo, ext.hi, r_typ, r_max, std::max(64.0, 2.0 * double(count)));
    } catch (const std::invalid_argument& e) {
      throw RunError(e.what());
    }
    const std::size_t slots = std::size_t(g.grid.cell_count());
    // grown with a quarter to spare, so that a grid a few cells larger later
    // in the run needs no new allocation
    if (slots > cell_start.n) {
      cell_start.resize(slots + slots / 4);
      cell_end.resize(slots + slots / 4);
      cell_rmax.resize(slots + slots / 4);
      cell_reach.resize(slots + slots / 4);
    }
    RUBBLE_CUDA(cudaMemsetAsync(cell_start.data(), 0, slots * sizeof(std::uint32_t)));
    RUBBLE_CUDA(cudaMemsetAsync(cell_end.data(), 0, slots * sizeof(std::uint32_t)));
    RUBBLE_CUDA(cudaMemsetAsync(cell_rmax.data(), 0, slots * sizeof(Real)));  // 0.0: all bits zero
    RUBBLE_CUDA(cudaMemsetAsync(cell_reach.data(), 0, slots * sizeof(Real)));

    const StoreView<D> s = store.view();
    g.x = s.x;
    g.R = R;
    g.order = order.data();
    g.start = cell_start.data();
    g.end = cell_end.data();
    g.cell_rmax = cell_rmax.data();
    g.cell_reach = cell_reach.data();
    std::uint64_t* cell = keys.data();
    std::uint32_t* ord = order.data();
    Real* rmax = cell_rmax.data();
    Real* reach = cell_reach.data();
    const UniformGrid<D> geo = g.grid;
    const Vec<D>* x = s.x;
    for_each_index("cell ids and reach", count, [=] __device__(std::size_t i) {
      const std::uint64_t slot = geo.bucket_of(x[i]);
      cell[i] = slot;
      ord[i] = std::uint32_t(i);
      atomic_max_positive(rmax + slot, R[i]);
      stamp_reach<D>(geo, x[i], R[i], [=](std::uint64_t t, Real r) { atomic_max_positive(reach + t, r); });
    });
    sort_pairs(temp, cell, ord, count, "thrust::sort_by_key (cells)");
    std::uint32_t* st = cell_start.data();
    std::uint32_t* en = cell_end.data();
    for_each_index("cell ranges", count, [=] __device__(std::size_t i) {
      const std::uint64_t c = cell[i];
      if (i == 0 || cell[i - 1] != c) st[c] = std::uint32_t(i);
      if (i + 1 == count || cell[i + 1] != c) en[c] = std::uint32_t(i + 1);
    });
    grid = g;
  }

  // Self-gravity (3-D): a_grav and phi by direct summation (the loop body of
  // direct.hpp) or Barnes-Hut (DeviceOctree, over the grid's extent: the
  // same positions, reduced earlier in this evaluation).
  void self_gravity(const StoreView<D>& s) {
    if constexpr (D == 3) {
      const std::size_t count = size();
      eps.resize(count);
      Real* e = eps.data();
      const bool fixed = gravity.softening == GravitySoftening::Fixed;
      const Real eps_fixed = Real(gravity.softening_length);
      for_each_index("softening", count, [=] __device__(std::size_t i) { e[i] = fixed ? eps_fixed : s.h[i]; });
      if (gravity.mode == GravityMode::BarnesHut) {
        octree.field(s.x, s.m, e, count, gravity, kernel, s.a_grav, s.phi, nullptr, &grid_extent);
        return;
      }
      const KernelType k = kernel;
      const Real G = Real(gravity.G);
      for_each_index("direct gravity", count, [=] __device__(std::size_t i) {
        const GravityField f = direct_field_of_particle(s.x, s.m, e, count, k, i);
        s.a_grav[i] = f.a * G;
        s.phi[i] = f.phi * G;
      });
    } else {
      (void)s;
      throw RunError("self-gravity needs a 3-D scene");
    }
  }

  // ---- the device state (the stepper reads the store and the allocator)
  DeviceStore<D> store;
  CachingDeviceAllocator temp;  // temporary storage of the sorts and reductions

 private:
  Box<D> domain;
  KernelType kernel;
  GravityConfig gravity;
  DeviceArray<MaterialParams> materials_;
  DeviceBuffer scratch_buffer;  // the sort's gathers
  DeviceArray<Real> eps;        // gravity softening
  // grid cell list
  DeviceArray<std::uint64_t> keys;
  DeviceArray<std::uint32_t> order, cell_start, cell_end, perm;
  DeviceArray<Real> cell_rmax, cell_reach;  // per slot: largest R of its particles, of a ball touching it
  GridNeighbors<D> grid{};
  Extent<D> grid_extent{};  // the positions' extent when the grid was built (Barnes-Hut reuses it)
  IntegratorScratch<D, DeviceArray, DeviceStore<D>> scratch;
  DeviceOctree octree;  // Barnes-Hut (3-D)
};

// The time loop's interface on the device: the scene's physics, the
// backend and the step sequence (the same one the CPU runs), plus the host
// copies the loop asks for.
template <int D>
struct CudaStepper<D>::Impl {
  ParticleStore<D>& host;
  RunPhysics physics;
  CudaBackend<D> backend;
  StepSequence<D, CudaBackend<D>> steps;
  Vec<D> g = Vec<D>::zero();     // simulation.gravity (its potential energy)
  DeviceStore<D> good;           // keep_good(): the snapshot fields before the step
  ParticleStore<D> good_host;    // last_good(): their host copy
  bool host_current = true;
  std::int64_t bytes_downloaded = 0;  // device-to-host bytes of host()

  Impl(const Scene& scene, ParticleStore<D>& ps, const Box<D>& dom)
      : host(ps), physics(run_physics(scene)), backend(physics, ps, dom), steps(physics, backend, dom) {
    for (int k = 0; k < D; ++k) g[k] = physics.body_force[k];
  }
  std::size_t n() const { return backend.size(); }
};

template <int D>
CudaStepper<D>::CudaStepper(const Scene& scene, ParticleStore<D>& ps, const Box<D>& domain, bool resumed)
    : impl_(std::make_unique<Impl>(scene, ps, domain)) {
  if (resumed) return;
  impl_->steps.sort_particles();
  impl_->steps.evaluate();
  impl_->host_current = false;
}

template <int D>
CudaStepper<D>::~CudaStepper() = default;

template <int D>
void CudaStepper<D>::sort_particles() {
  impl_->steps.sort_particles();
  impl_->host_current = false;
}

template <int D>
double CudaStepper<D>::dt_limit() {
  return double(impl_->steps.dt_limit());
}

template <int D>
void CudaStepper<D>::leapfrog(double dt) {
  impl_->host_current = false;
  impl_->steps.leapfrog(Real(dt));
}

template <int D>
Rk2Result CudaStepper<D>::rk2(double dt, double tol, double dt_min) {
  impl_->host_current = false;
  return impl_->steps.rk2(Real(dt), Real(tol), Real(dt_min));
}

template <int D>
void CudaStepper<D>::damp(double f) {
  impl_->host_current = false;
  impl_->steps.damp(Real(f));
}

template <int D>
BodySums<D> CudaStepper<D>::body_sums(std::int32_t lo, std::int32_t hi) {
  return impl_->steps.body_sums(lo, hi);
}

template <int D>
void CudaStepper<D>::damp_body(std::int32_t lo, std::int32_t hi, double f, Vec<D> mean, Vec<D> keep) {
  impl_->host_current = false;
  impl_->steps.damp_body(lo, hi, Real(f), mean, keep);
}

template <int D>
void CudaStepper<D>::add_body_velocity(std::int32_t lo, std::int32_t hi, Vec<D> V, Vec<3> w, Vec<D> centre) {
  impl_->host_current = false;
  impl_->steps.add_body_velocity(lo, hi, V, w, centre);
}

template <int D>
std::vector<double> CudaStepper<D>::tool_state() const {
  return impl_->steps.tool_state();
}

template <int D>
void CudaStepper<D>::set_tool_state(const std::vector<double>& list) {
  impl_->host_current = false;
  impl_->steps.set_tool_state(list);
}

template <int D>
RegionSums CudaStepper<D>::region_sums(const Region& r, int tool) {
  return impl_->steps.region_sums(r, tool);
}

template <int D>
ForceSums<D> CudaStepper<D>::held_force(std::int32_t lo, std::int32_t hi, Vec<D> point) {
  return impl_->steps.held_force(lo, hi, point);
}

// With the next step's time-step limit (StepSequence::check_state): the
// loop asks for both of the same state.
template <int D>
std::size_t CudaStepper<D>::first_non_finite() {
  return impl_->steps.check_state().first_bad;
}

template <int D>
ConservedRecord CudaStepper<D>::conserved(double t, std::int64_t step, double dt) {
  const StoreView<D> s = impl_->backend.view();
  const Vec<D> g = impl_->g;
  const ConservedSums sum = reduce_index<ConservedSums>(
      impl_->backend.temp, impl_->n(), [=] __device__(std::size_t i) { return conserved_particle<D>(s, i, g); },
      ConservedSums{}, thrust::plus<ConservedSums>());
  ConservedRecord r = conserved_record(sum, t, step, dt);
  r.book(impl_->steps.energy_books().wall_work, impl_->steps.energy_books().floor_energy);
  return r;
}

template <int D>
const EnergyBooks& CudaStepper<D>::energy_books() const {
  return impl_->steps.energy_books();
}

template <int D>
void CudaStepper<D>::set_energy_books(const EnergyBooks& b) {
  impl_->steps.set_energy_books(b);
}

template <int D>
std::int64_t CudaStepper<D>::energy_retries() const {
  return impl_->steps.energy_retries();
}

template <int D>
const ParticleStore<D>& CudaStepper<D>::host() {
  if (!impl_->host_current) {
    impl_->bytes_downloaded += std::int64_t(impl_->backend.store.download(impl_->host));
    impl_->host_current = true;
  }
  return impl_->host;
}

template <int D>
void CudaStepper<D>::keep_good() {
  impl_->good.copy_snapshot_fields_from(impl_->backend.store);
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
  return impl_->steps.correction_fallbacks();
}

template <int D>
std::int64_t CudaStepper<D>::evaluations() const {
  return impl_->steps.evaluations();
}

template <int D>
bool CudaStepper<D>::solid() const {
  return impl_->physics.on.solid;
}

CudaBackendCounts cuda_backend_counts() {
  return {g_device_allocations.load(), g_host_synchronisations.load()};
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
  tree.field(dx.data(), dm.data(), de.data(), n, gravity, kernel, da.data(), dp.data(), nullptr, nullptr, &t);
  copy_to_host(acc, da.data(), n * sizeof(Vec<3>));
  if (phi) copy_to_host(phi, dp.data(), n * sizeof(Real));
  return t;
}

template class CudaStepper<1>;
template class CudaStepper<2>;
template class CudaStepper<3>;

}  // namespace rubble
