#pragma once
// Self-gravity: the softened pair interaction and the multipole expansion
// (PHYSICS.md §6). Every function is RUBBLE_HD: the direct-summation and
// Barnes-Hut drivers (rubble/gravity/) and the unit tests call these, and a
// CUDA driver will too. Gravity is three-dimensional only.
//
// ---- Sign convention --------------------------------------------------------
// Everything here is per unit G. The acceleration of a test particle at x
// due to a mass m at y is  a = -G m g(r) (x - y)  and its potential is
// phi = -G m psi(r), with r = |x - y|; g and psi are > 0.
//
// ---- Softening consistent with the SPH kernel ----------------------------
// A softened particle is a mass distribution shaped like the SPH kernel
// W(r, eps) with support radius eps (rubble's H convention, kernels.hpp): the
// force on a point at r is that of the mass inside r, and the potential
// solves Poisson's equation for that density (Price & Monaghan 2007, MNRAS
// 374:1347, §2.2 and Appendix A, for the cubic spline; the Wendland forms
// follow the same way). With q = r / eps and M(q) = 4 pi sigma ∫_0^q f s^2 ds
// the kernel mass inside q:
//     g(r)   = M(q) / r^3                                   = ĝ(q) / eps^3
//     psi(r) = M(q) / r + 4 pi sigma / eps ∫_q^1 f(s) s ds  = ψ̂(q) / eps
// for q < 1, and exactly Newtonian, g = 1/r^3 and psi = 1/r, for q >= 1.
// ĝ and ψ̂ are polynomials (derived with sympy by exact integration of the
// kernels of kernels.hpp; the cubic spline's ψ̂ is Price & Monaghan's f with
// h_M = eps/2). Both are finite at r = 0, so coincident particles feel no
// force from each other and a finite potential. They are re-checked in
// solver/tests/test_gravity.cpp (continuity at q = 1, g = (1/r) dpsi/dr by
// finite differences, and M(q) by quadrature of W).
//
// A pair of particles with softening lengths eps_a, eps_b interacts through
// the mean of the two kernels, g_ab = (g(r, eps_a) + g(r, eps_b)) / 2 (and
// likewise psi): symmetric, so momentum is conserved exactly in direct
// summation (Price & Monaghan 2007, eq. 26). eps = 0 is a point mass; two
// unsoftened coincident particles (r = 0, eps = 0) do not interact (the
// Newtonian force is undefined there; this keeps every value finite).
//
// ---- Multipoles -------------------------------------------------------------
// A group of masses m_i at y_i has mass M, centre of mass c and traceless
// quadrupole Q_jk = Σ m_i (3 d_j d_k - |d|^2 δ_jk), d = y_i - c. At
// r = x - c outside the group (and outside every softening kernel),
//     phi = -G [ M / |r| + (r·Q·r) / (2 |r|^5) ]
//     a   = -G [ M r / |r|^3 - Q r / |r|^5 + (5/2) (r·Q·r) r / |r|^7 ]
// The dipole vanishes about the centre of mass. Monopole: the first terms
// only; the error of the quadrupole expansion falls as (size/|r|)^3.
//
// ---- Opening criterion --------------------------------------------------------
// A node whose octree cell (a cube of side s) has its centre of mass c at
// offset delta = c - (cell centre), and all of whose particles lie within
// b_max of c, is accepted (its multipole used) for a target at x when
//     |x - c| > r_open = 2 B / (sqrt(3) theta),   B = |c - farthest cell corner|
//                      = sqrt(Σ_k (s/2 + |delta_k|)^2)
// (the opening radius of PKDGRAV and GASOLINE, Stadel 2001, Wadsley, Stadel
// & Quinn 2004, and of ChaNGa, Jetley et al. 2008, with B to the corner of
// the node's box, here its octree cell: Salmon & Warren's 1994 b_max taken
// over the whole cell, the farthest any of its mass could be from c), and
//     |x - c| > b_max + max(eps_target, eps_max of the node),
// which puts every pair beyond both softening lengths, where the
// kernel-softened interaction is exactly Newtonian: the tree and direct
// summation then compute the same softened forces, up to the truncation of
// the multipole expansion. For a centred c (delta = 0) B = sqrt(3) s / 2 and
// r_open = s / theta: the plain s/d < theta of Barnes & Hut (1986), so theta
// keeps its usual meaning; an off-centre c enlarges r_open, to first order,
// by (2/3) |delta| / theta (offset along an axis) to (2/sqrt(3)) |delta| /
// theta (along a diagonal), up to 2 s / theta with c at a corner, where the
// earlier d > s/theta + delta (Barnes 1994) adds only |delta|. The plain
// s/d < theta can accept a cell whose centre of mass sits near a corner for
// a target inside that very cell (unbounded errors, Salmon & Warren 1994);
// here a point inside a cell is at most B from c, so it is never accepted
// for theta < 2/sqrt(3). theta = 0 opens every node: the walk is then direct
// summation. Measured against the alternatives in docs/physics.md
// (Self-gravity, Choice of criterion).
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/kernel_type.hpp"

namespace rubble {

// CODATA 2018 Newtonian constant of gravitation [m^3 kg^-1 s^-2].
inline constexpr double kGravitationalConstantSI = 6.67430e-11;

enum class MultipoleOrder : int { Monopole = 0, Quadrupole = 1 };

// psi and g of one interaction (per unit mass and unit G, see above).
struct GravityKernelValue {
  Real psi;  // potential factor: phi = -G m psi
  Real g;    // force factor:     a   = -G m g (x_a - x_b)
};

namespace gravity_detail {

// ψ̂(q) and ĝ(q) for q < 1 (see the header comment), in Horner form.
RUBBLE_HD_INLINE GravityKernelValue softened_shape(KernelType k, Real q) {
  const Real q2 = q * q;
  GravityKernelValue v{Real(0), Real(0)};
  switch (k) {
    case KernelType::CubicSpline:
      if (q < Real(0.5)) {
        // ψ̂ = 14/5 - 16/3 q^2 + 48/5 q^4 - 32/5 q^5;  ĝ = 32/3 - 192/5 q^2 + 32 q^3
        v.psi = Real(14) / Real(5) + q2 * (Real(-16) / Real(3) + q2 * (Real(48) / Real(5) - Real(32) / Real(5) * q));
        v.g = Real(32) / Real(3) + q2 * (Real(-192) / Real(5) + Real(32) * q);
      } else {
        // ψ̂ = 16/5 - 1/(15q) - 32/3 q^2 + 16 q^3 - 48/5 q^4 + 32/15 q^5
        // ĝ  = 64/3 - 1/(15q^3) - 48 q + 192/5 q^2 - 32/3 q^3
        v.psi = Real(16) / Real(5) - Real(1) / (Real(15) * q) +
                q2 * (Real(-32) / Real(3) + q * (Real(16) + q * (Real(-48) / Real(5) + Real(32) / Real(15) * q)));
        v.g = Real(64) / Real(3) - Real(1) / (Real(15) * q2 * q) +
              q * (Real(-48) + q * (Real(192) / Real(5) - Real(32) / Real(3) * q));
      }
      return v;
    case KernelType::WendlandC2:
      // ψ̂ = 3 - 7q^2 + 21q^4 - 28q^5 + 15q^6 - 3q^7;  ĝ = 14 - 84q^2 + 140q^3 - 90q^4 + 21q^5
      v.psi = Real(3) + q2 * (Real(-7) + q2 * (Real(21) + q * (Real(-28) + q * (Real(15) - Real(3) * q))));
      v.g = Real(14) + q2 * (Real(-84) + q * (Real(140) + q * (Real(-90) + Real(21) * q)));
      return v;
    case KernelType::WendlandC4:
      // ψ̂ = 55/16 - 165/16 q^2 + 231/8 q^4 - 825/8 q^6 + 165 q^7 - 1925/16 q^8 + 44 q^9 - 105/16 q^10
      // ĝ  = 165/8 - 231/2 q^2 + 2475/4 q^4 - 1155 q^5 + 1925/2 q^6 - 396 q^7 + 525/8 q^8
      v.psi = Real(55) / Real(16) +
              q2 * (Real(-165) / Real(16) +
                    q2 * (Real(231) / Real(8) +
                          q2 * (Real(-825) / Real(8) +
                                q * (Real(165) + q * (Real(-1925) / Real(16) + q * (Real(44) - Real(105) / Real(16) * q))))));
      v.g = Real(165) / Real(8) +
            q2 * (Real(-231) / Real(2) +
                  q2 * (Real(2475) / Real(4) +
                        q * (Real(-1155) + q * (Real(1925) / Real(2) + q * (Real(-396) + Real(525) / Real(8) * q)))));
      return v;
    case KernelType::WendlandC6:
      // ψ̂ = 245/64 - 455/32 q^2 + 3003/64 q^4 - 2145/16 q^6 + 35035/64 q^8 - 1001 q^9
      //      + 28665/32 q^10 - 455 q^11 + 8085/64 q^12 - 15 q^13
      // ĝ  = 455/16 - 3003/16 q^2 + 6435/8 q^4 - 35035/8 q^6 + 9009 q^7 - 143325/16 q^8
      //      + 5005 q^9 - 24255/16 q^10 + 195 q^11
      v.psi = Real(245) / Real(64) +
              q2 * (Real(-455) / Real(32) +
                    q2 * (Real(3003) / Real(64) +
                          q2 * (Real(-2145) / Real(16) +
                                q2 * (Real(35035) / Real(64) +
                                      q * (Real(-1001) +
                                           q * (Real(28665) / Real(32) +
                                                q * (Real(-455) + q * (Real(8085) / Real(64) - Real(15) * q))))))));
      v.g = Real(455) / Real(16) +
            q2 * (Real(-3003) / Real(16) +
                  q2 * (Real(6435) / Real(8) +
                        q2 * (Real(-35035) / Real(8) +
                              q * (Real(9009) +
                                   q * (Real(-143325) / Real(16) +
                                        q * (Real(5005) + q * (Real(-24255) / Real(16) + Real(195) * q)))))));
      return v;
  }
  return v;
}

}  // namespace gravity_detail

// psi(r) and g(r) of one kernel-softened mass with softening (support)
// length eps >= 0; Newtonian for r >= eps. r = 0 with eps = 0 gives zeros.
RUBBLE_HD_INLINE GravityKernelValue gravity_softened(KernelType k, Real r, Real eps) {
  if (r >= eps) {
    if (!(r > Real(0))) return {Real(0), Real(0)};
    const Real inv = Real(1) / r;
    return {inv, inv * inv * inv};
  }
  const Real inv_eps = Real(1) / eps;
  GravityKernelValue v = gravity_detail::softened_shape(k, r * inv_eps);
  v.psi *= inv_eps;
  v.g *= inv_eps * inv_eps * inv_eps;
  return v;
}

// The symmetric pair interaction: mean of the two particles' kernels.
RUBBLE_HD_INLINE GravityKernelValue gravity_pair(KernelType k, Real r, Real eps_a, Real eps_b) {
  if (eps_a == eps_b) return gravity_softened(k, r, eps_a);
  const GravityKernelValue va = gravity_softened(k, r, eps_a);
  const GravityKernelValue vb = gravity_softened(k, r, eps_b);
  return {Real(0.5) * (va.psi + vb.psi), Real(0.5) * (va.g + vb.g)};
}

// Acceleration and potential per unit G.
struct GravityField {
  Vec<3> a;
  Real phi;
};

// Field at separation dx = x_target - y_source of a source of mass m.
RUBBLE_HD_INLINE void gravity_pair_add(KernelType k, const Vec<3>& dx, Real m, Real eps_a, Real eps_b, GravityField& f) {
  const GravityKernelValue v = gravity_pair(k, norm(dx), eps_a, eps_b);
  f.a -= dx * (m * v.g);
  f.phi -= m * v.psi;
}

// Index of the component (j, k) in the 6 stored components of a symmetric
// 3x3 tensor, ordered xx, xy, xz, yy, yz, zz.
RUBBLE_HD_INLINE int sym_index(int j, int k) {
  if (j > k) {
    const int t = j;
    j = k;
    k = t;
  }
  return j == 0 ? k : (j == 1 ? 2 + k : 5);
}

// Add the traceless quadrupole of a mass m at offset d from the expansion
// centre: Q_jk += m (3 d_j d_k - |d|^2 δ_jk).
RUBBLE_HD_INLINE void quadrupole_add_point(Real q[6], Real m, const Vec<3>& d) {
  const Real d2 = norm2(d);
  for (int j = 0; j < 3; ++j)
    for (int k = j; k < 3; ++k) q[sym_index(j, k)] += m * (Real(3) * d[j] * d[k] - (j == k ? d2 : Real(0)));
}

// Field at r = (rx, ry, rz) = x_target - c of a multipole (mass M,
// traceless quadrupole q0..q5 = xx, xy, xz, yy, yz, zz about the centre of
// mass c), added to (ax, ay, az, phi); scalar arguments so that a loop over
// many multipoles vectorises. The expansion is unsoftened: use it only where
// the opening criterion below holds.
template <bool Quadrupole>
RUBBLE_HD_INLINE void multipole_field(Real rx, Real ry, Real rz, Real mass, Real q0, Real q1, Real q2, Real q3,
                                      Real q4, Real q5, Real& ax, Real& ay, Real& az, Real& phi) {
  const Real r2 = rx * rx + ry * ry + rz * rz;
  const Real inv_r = Real(1) / std::sqrt(r2);
  const Real inv_r2 = inv_r * inv_r;
  const Real inv_r3 = inv_r * inv_r2;
  Real s = mass * inv_r3;  // coefficient of -r in a
  phi -= mass * inv_r;
  if (Quadrupole) {
    const Real qx = q0 * rx + q1 * ry + q2 * rz;
    const Real qy = q1 * rx + q3 * ry + q4 * rz;
    const Real qz = q2 * rx + q4 * ry + q5 * rz;
    const Real rqr = rx * qx + ry * qy + rz * qz;
    const Real inv_r5 = inv_r3 * inv_r2;
    ax += qx * inv_r5;
    ay += qy * inv_r5;
    az += qz * inv_r5;
    s += Real(2.5) * rqr * inv_r5 * inv_r2;
    phi -= Real(0.5) * rqr * inv_r5;
  }
  ax -= rx * s;
  ay -= ry * s;
  az -= rz * s;
}

// The same for a Vec separation and a stored quadrupole q[6].
RUBBLE_HD_INLINE void multipole_add(const Vec<3>& r, Real mass, const Real q[6], MultipoleOrder order, GravityField& f) {
  if (order == MultipoleOrder::Quadrupole)
    multipole_field<true>(r[0], r[1], r[2], mass, q[0], q[1], q[2], q[3], q[4], q[5], f.a[0], f.a[1], f.a[2], f.phi);
  else
    multipole_field<false>(r[0], r[1], r[2], mass, q[0], q[1], q[2], q[3], q[4], q[5], f.a[0], f.a[1], f.a[2], f.phi);
}

// Radius beyond which a node's multipole may be used (first condition of
// the criterion above) for a cubic cell of side `side` whose centre of mass
// sits at `com_offset` from the cell centre: 2 B / (sqrt(3) theta) with B
// the distance from the centre of mass to the farthest cell corner;
// infinite for theta = 0.
RUBBLE_HD_INLINE Real opening_radius(Real side, const Vec<3>& com_offset, Real theta) {
  if (!(theta > Real(0))) return Real(INFINITY);
  Real b2 = 0;
  for (int k = 0; k < 3; ++k) {
    const Real e = Real(0.5) * side + std::fabs(com_offset[k]);
    b2 += e * e;
  }
  // 2 / sqrt(3)
  return Real(1.1547005383792515) * std::sqrt(b2) / theta;
}

// The whole acceptance test for a target at squared distance d2 from the
// node's centre of mass: beyond the opening radius and beyond the reach of
// every softening kernel involved (b_max + max(eps_target, eps_node)).
RUBBLE_HD_INLINE bool node_accepted(Real d2, Real open_radius, Real b_max, Real eps_node, Real eps_target) {
  const Real reach = b_max + (eps_target > eps_node ? eps_target : eps_node);
  const Real need = open_radius > reach ? open_radius : reach;
  return d2 > need * need;
}

}  // namespace rubble
