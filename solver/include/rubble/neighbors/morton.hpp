#pragma once
// Morton (Z-order) keys: the one spatial order of rubble (DESIGN.md
// principle 5). Particles are sorted by the key of their position; the
// neighbour search and the Barnes-Hut octree are both built over that order.
//
// A key interleaves the bits of the integer cell coordinates, most
// significant bits first, axis 0 in the lowest bit of each group:
//   2-D: key bit 2i   = bit i of cell[0],  key bit 2i+1 = bit i of cell[1]
//   3-D: key bit 3i+k = bit i of cell[k]
// so the top D bits of a key name the octant (quadrant) of the box, the next
// D bits the octant within it, and so on: every octree cell is one
// contiguous range of keys.
//
// Everything here is RUBBLE_HD, so the same functions run in CUDA kernels.
#include <cmath>
#include <cstdint>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// Bits per axis: as many as fit in one 64-bit key (63 in 1-D, so that
// 1-D and 3-D keys both leave the sign bit free).
template <int D>
inline constexpr int morton_bits = D == 1 ? 63 : (D == 2 ? 32 : 21);

namespace detail {

// Move bit i of the low 32 bits of v to bit 2i.
RUBBLE_HD_INLINE std::uint64_t spread_bits_by_1(std::uint64_t v) {
  v &= 0x00000000FFFFFFFFull;
  v = (v | (v << 16)) & 0x0000FFFF0000FFFFull;
  v = (v | (v << 8)) & 0x00FF00FF00FF00FFull;
  v = (v | (v << 4)) & 0x0F0F0F0F0F0F0F0Full;
  v = (v | (v << 2)) & 0x3333333333333333ull;
  v = (v | (v << 1)) & 0x5555555555555555ull;
  return v;
}

// Move bit i of the low 21 bits of v to bit 3i.
RUBBLE_HD_INLINE std::uint64_t spread_bits_by_2(std::uint64_t v) {
  v &= 0x1FFFFFull;
  v = (v | (v << 32)) & 0x001F00000000FFFFull;
  v = (v | (v << 16)) & 0x001F0000FF0000FFull;
  v = (v | (v << 8)) & 0x100F00F00F00F00Full;
  v = (v | (v << 4)) & 0x10C30C30C30C30C3ull;
  v = (v | (v << 2)) & 0x1249249249249249ull;
  return v;
}

// floor(t * 2^bits) for t = (x - lo) / (hi - lo), clamped to [0, 2^bits - 1].
// Periodic axes first map t into [0, 1), so a position outside the box gets
// the cell of its periodic image. Computed in double whatever Real is.
RUBBLE_HD_INLINE std::uint64_t quantise(Real x, Real lo, Real hi, bool periodic, int bits) {
  double t = (double(x) - double(lo)) / (double(hi) - double(lo));
  if (periodic) t -= std::floor(t);
  const std::uint64_t max_cell = (std::uint64_t(1) << bits) - 1;
  const double scale = double(std::uint64_t(1) << bits);  // exact power of two
  const double q = t * scale;
  if (!(q > 0.0)) return 0;               // also catches NaN
  if (q >= scale) return max_cell;        // at or beyond hi
  const std::uint64_t c = std::uint64_t(q);
  return c < max_cell ? c : max_cell;
}

}  // namespace detail

// Interleave the bits of integer cell coordinates into one key. Uses the low
// morton_bits<D> bits of each coordinate (all 32 bits in 1-D and 2-D, 21 in
// 3-D); higher bits are ignored.
template <int D>
RUBBLE_HD_INLINE std::uint64_t morton_encode(const std::uint32_t (&cell)[D]) {
  static_assert(D >= 1 && D <= 3, "rubble supports 1, 2 and 3 dimensions");
  if constexpr (D == 1) {
    return cell[0];
  } else if constexpr (D == 2) {
    return detail::spread_bits_by_1(cell[0]) | (detail::spread_bits_by_1(cell[1]) << 1);
  } else {
    return detail::spread_bits_by_2(cell[0]) | (detail::spread_bits_by_2(cell[1]) << 1) |
           (detail::spread_bits_by_2(cell[2]) << 2);
  }
}

// Key of position x: quantise each coordinate within box into 2^morton_bits<D>
// cells and interleave. Positions outside an open axis clamp to the edge
// cell; on a periodic axis they wrap. 1-D keys are the 63-bit coordinate
// itself (morton_encode's 32-bit input would waste resolution).
template <int D>
RUBBLE_HD_INLINE std::uint64_t morton_key(const Vec<D>& x, const Box<D>& box) {
  constexpr int bits = morton_bits<D>;
  if constexpr (D == 1) {
    return detail::quantise(x[0], box.lo[0], box.hi[0], box.periodic[0], bits);
  } else {
    std::uint32_t cell[D];
    for (int k = 0; k < D; ++k)
      cell[k] = std::uint32_t(detail::quantise(x[k], box.lo[k], box.hi[k], box.periodic[k], bits));
    return morton_encode<D>(cell);
  }
}

}  // namespace rubble
