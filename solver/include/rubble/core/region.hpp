#pragma once
// A region of space: where a body's lattice is kept (its shape, and the
// shapes it adds and subtracts, scene key `add`/`subtract`), and where a
// measuring region counts mass ([[regions]]; issue #54 item 3). One
// containment test for the initial conditions (host) and the measurement
// (both backends), so a region means the same thing everywhere.
//
// Shapes (first D coordinates used):
//   box       min <= x < max
//   sphere    |x - center| < radius               (a disc in 2-D)
//   ring      inner_radius <= |x - center| < radius (annulus, spherical shell)
//   cylinder  3-D: |t| < length/2 and |x - center - t axis| < radius,
//             t = (x - center).axis (axis unit; center the axis' midpoint)
//   polygon   2-D: inside the closed polygon through `vertices` by the
//             even-odd rule (a point on the boundary may fall either way)
#include <cmath>

#include "rubble/core/hd.hpp"

namespace rubble {

inline constexpr int kMaxPolygonVertices = 64;

enum class RegionShape : int { Box = 0, Sphere = 1, Ring = 2, Cylinder = 3, Polygon = 4 };

struct Region {
  RegionShape shape = RegionShape::Box;
  double min[3] = {0, 0, 0}, max[3] = {0, 0, 0};  // box; for every shape its bounding box (region_bounds)
  double center[3] = {0, 0, 0};
  double radius = 0, inner_radius = 0;
  double axis[3] = {0, 0, 1};  // cylinder: unit
  double length = 0;           // cylinder
  int vertex_count = 0;        // polygon
  double vertices[kMaxPolygonVertices][2] = {};

  // Whether the point x (D coordinates) lies inside.
  template <int D>
  RUBBLE_HD bool contains(const double* x) const {
    switch (shape) {
      case RegionShape::Box: {
        for (int k = 0; k < D; ++k)
          if (!(x[k] >= min[k] && x[k] < max[k])) return false;
        return true;
      }
      case RegionShape::Sphere:
      case RegionShape::Ring: {
        double r2 = 0;
        for (int k = 0; k < D; ++k) r2 += (x[k] - center[k]) * (x[k] - center[k]);
        if (!(r2 < radius * radius)) return false;
        return shape == RegionShape::Sphere || r2 >= inner_radius * inner_radius;
      }
      case RegionShape::Cylinder: {
        if (D != 3) return false;
        double d[3] = {0, 0, 0}, t = 0;
        for (int k = 0; k < D; ++k) {
          d[k] = x[k] - center[k];
          t += d[k] * axis[k];
        }
        if (!(std::fabs(t) < 0.5 * length)) return false;
        double r2 = 0;
        for (int k = 0; k < D; ++k) r2 += (d[k] - t * axis[k]) * (d[k] - t * axis[k]);
        return r2 < radius * radius;
      }
      case RegionShape::Polygon: {
        if (D != 2) return false;
        bool in = false;
        for (int i = 0, j = vertex_count - 1; i < vertex_count; j = i++) {
          const double xi = vertices[i][0], yi = vertices[i][1], xj = vertices[j][0], yj = vertices[j][1];
          if ((yi > x[1]) != (yj > x[1]) && x[0] < (xj - xi) * (x[1] - yi) / (yj - yi) + xi) in = !in;
        }
        return in;
      }
    }
    return false;
  }
};

// What a measuring region holds ([[regions]], regions.csv): the mass of
// the free particles inside it by material, and their count.
inline constexpr int kMaxRegionMaterials = 16;
struct RegionSums {
  double mass[kMaxRegionMaterials] = {};
  unsigned long long count = 0;
};
struct RegionSumOp {
  RUBBLE_HD RegionSums operator()(const RegionSums& a, const RegionSums& b) const {
    RegionSums r;
    for (int k = 0; k < kMaxRegionMaterials; ++k) r.mass[k] = a.mass[k] + b.mass[k];
    r.count = a.count + b.count;
    return r;
  }
};

// The region's bounding box into min/max (for every shape but the box,
// whose min/max are its own), in D dimensions.
template <int D>
inline void region_bounds(Region& r) {
  switch (r.shape) {
    case RegionShape::Box: return;
    case RegionShape::Sphere:
    case RegionShape::Ring:
      for (int k = 0; k < D; ++k) {
        r.min[k] = r.center[k] - r.radius;
        r.max[k] = r.center[k] + r.radius;
      }
      return;
    case RegionShape::Cylinder:
      // the axis' end points +- radius in every direction (a loose box)
      for (int k = 0; k < D; ++k) {
        const double reach = 0.5 * r.length * std::fabs(r.axis[k]) + r.radius;
        r.min[k] = r.center[k] - reach;
        r.max[k] = r.center[k] + reach;
      }
      return;
    case RegionShape::Polygon:
      for (int k = 0; k < 2; ++k) {
        r.min[k] = r.vertices[0][k];
        r.max[k] = r.vertices[0][k];
        for (int i = 1; i < r.vertex_count; ++i) {
          r.min[k] = r.vertices[i][k] < r.min[k] ? r.vertices[i][k] : r.min[k];
          r.max[k] = r.vertices[i][k] > r.max[k] ? r.vertices[i][k] : r.max[k];
        }
      }
      return;
  }
}

}  // namespace rubble
