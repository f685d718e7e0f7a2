#pragma once
// Rigid tools (issue #54 item 1): boundary bodies that move as one rigid
// body, translating and turning about an axis of fixed direction.
//
// A tool's pose is its reference point c(t) and its rotation angle
// theta(t) about the unit axis n (the z axis in 2-D, where the plane is
// x-y); its motion is the velocity V = dc/dt and the angular velocity
// omega = d theta/dt. Each of its particles keeps the offset r0 = x0 - c0
// it had at t = 0, and is placed from it at every stage of a step:
//
//   x(t) = c(t) + R(n, theta(t)) r0,      v(t) = V(t) + omega(t) n x (x(t) - c(t)),
//
// so a tool keeps its shape to round-off however long it turns (no
// integration of its particles' positions, whose drift would stretch it).
// R(n, theta) is Rodrigues' rotation (e.g. Goldstein, Poole & Safko 2002,
// Classical Mechanics, 3rd ed., eq. 4.92).
//
// A prescribed tool (boundary = "moving" with an angular_velocity) has
// constant V and omega. A driven tool (boundary = "driven") obeys
//
//   M dV/dt = F + F_applied + M g,        I d omega/dt = T . n + T_applied,
//
// F and T the force and torque (about c) that the rest of the particles
// exert on its particles (rigid_reaction below), M its mass, I its moment
// of inertia about the axis through c; components it is not free in keep
// their initial value. Rotation about a fixed axis direction only: a 3-D
// tool does not precess (what brushes, wheels, augers and footings need).
// The tool's state is advanced by the same integrator as the particles, at
// the same stages (integrate/leapfrog.hpp, rk2_adaptive.hpp).
#include <cmath>
#include <cstdint>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// At most this many rigid tools per run (their poses travel by value into
// every placement loop, on the GPU as a kernel argument).
inline constexpr int kMaxRigidTools = 8;

// The rotation by theta about the unit axis n (Rodrigues); in 2-D about z.
template <int D>
RUBBLE_HD_INLINE Mat<D> rotation_about(const Vec<3>& n, Real theta) {
  const Real c = std::cos(theta), s = std::sin(theta);
  Mat<D> R = Mat<D>::identity();
  if constexpr (D == 2) {
    R[0][0] = c;
    R[0][1] = -s;
    R[1][0] = s;
    R[1][1] = c;
  } else if constexpr (D == 3) {
    const Real k = Real(1) - c;
    R[0][0] = c + k * n[0] * n[0];
    R[0][1] = k * n[0] * n[1] - s * n[2];
    R[0][2] = k * n[0] * n[2] + s * n[1];
    R[1][0] = k * n[1] * n[0] + s * n[2];
    R[1][1] = c + k * n[1] * n[1];
    R[1][2] = k * n[1] * n[2] - s * n[0];
    R[2][0] = k * n[2] * n[0] - s * n[1];
    R[2][1] = k * n[2] * n[1] + s * n[0];
    R[2][2] = c + k * n[2] * n[2];
  }
  return R;
}

// omega n x r: the velocity of a turning body at r from its axis point
// (2-D: n = z, so omega (-r_y, r_x); 1-D: nothing turns).
template <int D>
RUBBLE_HD_INLINE Vec<D> turning_velocity(const Vec<3>& n, Real omega, const Vec<D>& r) {
  Vec<D> w = Vec<D>::zero();
  if constexpr (D == 2) {
    w[0] = -omega * r[1];
    w[1] = omega * r[0];
  } else if constexpr (D == 3) {
    w[0] = omega * (n[1] * r[2] - n[2] * r[1]);
    w[1] = omega * (n[2] * r[0] - n[0] * r[2]);
    w[2] = omega * (n[0] * r[1] - n[1] * r[0]);
  }
  return w;
}

// |r|^2 - (r.n)^2: the squared distance of r from the axis n (2-D: n = z,
// so |r|^2), each particle's share of the moment of inertia over its mass.
template <int D>
RUBBLE_HD_INLINE Real axial_distance2(const Vec<3>& n, const Vec<D>& r) {
  Real along = 0;
  if constexpr (D == 3) along = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
  return norm2(r) - along * along;
}

// (r x f) . n: the torque of force f at r about the axis n (2-D: the z
// component r_x f_y - r_y f_x).
template <int D>
RUBBLE_HD_INLINE Real axial_torque(const Vec<3>& n, const Vec<D>& r, const Vec<D>& f) {
  if constexpr (D == 2) {
    return r[0] * f[1] - r[1] * f[0];
  } else if constexpr (D == 3) {
    return n[0] * (r[1] * f[2] - r[2] * f[1]) + n[1] * (r[2] * f[0] - r[0] * f[2]) + n[2] * (r[0] * f[1] - r[1] * f[0]);
  } else {
    return Real(0);
  }
}

// The pose and motion of one tool at one stage: what its particles need.
template <int D>
struct RigidPose {
  Vec<D> c;      // reference point (the rotation centre) [m]
  Mat<D> R;      // rotation since t = 0
  Vec<D> V;      // velocity of c [m/s]
  Vec<3> n;      // unit axis (z in 2-D)
  Real omega;    // angular velocity about n [rad/s]
};

// Every tool's pose, by value (kMaxRigidTools at most).
template <int D>
struct RigidPoses {
  int count = 0;
  RigidPose<D> pose[kMaxRigidTools];
};

// Particle i of tool k placed at its tool's pose from its offset r0.
template <int D>
RUBBLE_HD_INLINE void place_rigid_particle(const RigidPose<D>& p, const Vec<D>& r0, Vec<D>& x, Vec<D>& v) {
  const Vec<D> r = p.R * r0;
  x = p.c + r;
  v = p.V + turning_velocity<D>(p.n, p.omega, r);
}

// A tool's state as a restart snapshot and boundary_forces.csv list it:
// c (D values), theta, V (D), omega, then c0, its reference point at t = 0 (D).
template <int D>
inline constexpr int kRigidStateValues = 3 * D + 2;

// The state of a tool that the integrators advance, and its rates.
template <int D>
struct RigidState {
  Vec<D> c = Vec<D>::zero();  // reference point [m]
  Real theta = 0;             // rotation angle about n since t = 0 [rad]
  Vec<D> V = Vec<D>::zero();  // velocity [m/s]
  Real omega = 0;             // angular velocity [rad/s]
};
template <int D>
struct RigidRates {
  Vec<D> A = Vec<D>::zero();  // dV/dt [m/s^2]
  Real alpha = 0;             // d omega/dt [rad/s^2]
};

// y0 + w (dy/dt of (y_a, k_a)) [+ w (dy/dt of (y_b, k_b))]: the stage
// combination of the integrators (rk2_combine's, leapfrog's halves) for a
// tool, whose dc/dt = V and d theta/dt = omega come from the state itself.
template <int D>
RUBBLE_HD_INLINE RigidState<D> rigid_combine(const RigidState<D>& y0, const RigidState<D>& ya, const RigidRates<D>& ka,
                                             const RigidState<D>* yb, const RigidRates<D>* kb, Real w) {
  RigidState<D> y = y0;
  y.c = y0.c + w * ya.V;
  y.theta = y0.theta + w * ya.omega;
  y.V = y0.V + w * ka.A;
  y.omega = y0.omega + w * ka.alpha;
  if (yb) {
    y.c += w * yb->V;
    y.theta += w * yb->omega;
    y.V += w * kb->A;
    y.omega += w * kb->alpha;
  }
  return y;
}

// The rates of a driven tool from the reaction (F, T) of this evaluation:
// each free component of the translation takes (F + F_applied)/M + g, the
// rotation (T + T_applied)/I when free; a component that is not free keeps
// its velocity (rate 0).
template <int D>
RUBBLE_HD_INLINE RigidRates<D> driven_rates(const Vec<D>& F, Real T, const Vec<D>& F_applied, Real T_applied,
                                            const Vec<D>& g, Real M, Real I, const bool* free_axis, bool free_rotation) {
  RigidRates<D> k;
  for (int a = 0; a < D; ++a) k.A[a] = free_axis[a] ? (F[a] + F_applied[a]) / M + g[a] : Real(0);
  k.alpha = free_rotation ? (T + T_applied) / I : Real(0);
  return k;
}

// The force and torque (about a point p) that the rest exerts on a set of
// held particles, from their wall_force: F = sum f, T = sum (x - p) x f
// (2-D: T[2] only; 1-D: none). Summed in double whatever Real is.
template <int D>
struct ForceSums {
  double F[3] = {0, 0, 0};
  double T[3] = {0, 0, 0};
  RUBBLE_HD ForceSums operator+(const ForceSums& o) const {
    ForceSums r;
    for (int k = 0; k < 3; ++k) {
      r.F[k] = F[k] + o.F[k];
      r.T[k] = T[k] + o.T[k];
    }
    return r;
  }
};
template <int D>
struct ForceSumOp {
  RUBBLE_HD ForceSums<D> operator()(const ForceSums<D>& a, const ForceSums<D>& b) const { return a + b; }
};
// One particle's share: force f at r from the point.
template <int D>
RUBBLE_HD_INLINE ForceSums<D> force_sums_term(const Vec<D>& r, const Vec<D>& f) {
  ForceSums<D> s;
  for (int k = 0; k < D; ++k) s.F[k] = double(f[k]);
  if constexpr (D == 2) {
    s.T[2] = double(r[0]) * double(f[1]) - double(r[1]) * double(f[0]);
  } else if constexpr (D == 3) {
    s.T[0] = double(r[1]) * double(f[2]) - double(r[2]) * double(f[1]);
    s.T[1] = double(r[2]) * double(f[0]) - double(r[0]) * double(f[2]);
    s.T[2] = double(r[0]) * double(f[1]) - double(r[1]) * double(f[0]);
  }
  return s;
}

}  // namespace rubble
