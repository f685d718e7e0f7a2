#pragma once
// SPH smoothing kernels: cubic spline (M4) and Wendland C2, C4, C6, in 1, 2
// and 3 dimensions (PHYSICS.md §2).
//
// ---- Smoothing-length convention -----------------------------------------
// The length H passed to every function here is the kernel SUPPORT RADIUS:
//     W(r, H) = sigma_D / H^D * f(q),   q = r / H,   f(q) = 0 for q >= 1,
// (as miluphcuda's `sml` and GADGET's "smoothing length"). Monaghan's h_M,
// with the kernel reaching to 2 h_M, is h_M = H / 2.
//
// ---- Shapes f(q) and normalisations sigma_D (∫ W dV = 1) ----------------
// Cubic spline M4 (Monaghan & Lattanzio 1985, rescaled to support H):
//     f = 1 - 6q^2 + 6q^3   (q < 1/2),   f = 2(1-q)^3   (1/2 <= q < 1)
//     sigma_1 = 4/3, sigma_2 = 40/(7 pi), sigma_3 = 8/pi
// Wendland (Wendland 1995; Dehnen & Aly 2012, MNRAS 425:1068, Table 1).
// The 1-D functions differ from the 2-D/3-D ones:
//     1-D: C2 (1-q)^3 (1+3q)                       sigma_1 = 5/4
//          C4 (1-q)^5 (1+5q+8q^2)                  sigma_1 = 3/2
//          C6 (1-q)^7 (1+7q+19q^2+21q^3)           sigma_1 = 55/32
//     2-D/3-D: C2 (1-q)^4 (1+4q)                   sigma_2 = 7/pi,      sigma_3 = 21/(2 pi)
//              C4 (1-q)^6 (1+6q+35/3 q^2)          sigma_2 = 9/pi,      sigma_3 = 495/(32 pi)
//              C6 (1-q)^8 (1+8q+25q^2+32q^3)       sigma_2 = 78/(7 pi), sigma_3 = 1365/(64 pi)
// Every sigma_D was derived by exact integration (sympy) and is re-checked by
// quadrature in solver/tests/test_kernels.cpp.
//
// ---- Default H / Δx (kernel_default_hfact) --------------------------------
// Resolution is set by the kernel's standard deviation s, s^2 = ∫ x_1^2 W dV
// (Dehnen & Aly 2012 §2.2), not by H. H/s in 3-D (2-D, 1-D):
//     cubic 3.651 (3.556, 3.464)   C2 3.873 (3.795, 3.240)
//     C4    4.416 (4.342, 3.873)   C6 4.899 (4.830, 4.416)
// The cubic spline uses the customary H = 2.4 Δx (h_M = 1.2 Δx, about 58
// neighbours in 3-D). Matching its s in 3-D gives H/Δx = 2.55 (C2),
// 2.90 (C4), 3.22 (C6). Dehnen & Aly show the Wendland kernels are free of
// the pairing instability at any neighbour number and recommend spending some
// resolution on more neighbours to cut the E0 (particle-noise) error; we take
// a modest 10% over s-matching (neighbour count ≈ 1.3x), rounded:
//     kernel   H/Δx   h_M/Δx = H/(2Δx)   N_H = (4pi/3)(H/Δx)^3 in 3-D
//     cubic    2.4    1.2                 58
//     C2       2.8    1.4                 92
//     C4       3.2    1.6                137
//     C6       3.5    1.75               180
// At these values the lattice identity Σ_b V_b (x_b-x_a)⊗∇_a W_ab = I holds
// to ≤ 2.2e-2 (cubic) and ≤ 1.1e-2 (Wendland) in 1-3 D, and the lattice
// density Σ_b V_b W_ab = 1 to ≤ 1.8e-3 (cubic) and ≤ 6.7e-3 (Wendland).
// The extra 10% matters most for C2: at the s-matched 2.55 Δx its errors are
// 3.0e-2 (identity) and 1.2e-2 (density) in 2-D.
#include <string_view>

#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"
#include "rubble/physics/kernel_type.hpp"

namespace rubble {

namespace kernel_detail {

inline constexpr Real kPi = Real(3.14159265358979323846);

// H^n by repeated multiplication (no std::pow on the hot path).
template <int N>
RUBBLE_HD_INLINE Real ipow(Real x) {
  Real p = Real(1);
  for (int i = 0; i < N; ++i) p *= x;
  return p;
}

// Normalisation sigma_D (see the table above).
template <int D>
RUBBLE_HD_INLINE Real sigma(KernelType k) {
  static_assert(D >= 1 && D <= 3, "rubble supports 1, 2 and 3 dimensions");
  switch (k) {
    case KernelType::CubicSpline:
      return D == 1 ? Real(4) / Real(3) : D == 2 ? Real(40) / (Real(7) * kPi) : Real(8) / kPi;
    case KernelType::WendlandC2:
      return D == 1 ? Real(5) / Real(4) : D == 2 ? Real(7) / kPi : Real(21) / (Real(2) * kPi);
    case KernelType::WendlandC4:
      return D == 1 ? Real(3) / Real(2) : D == 2 ? Real(9) / kPi : Real(495) / (Real(32) * kPi);
    case KernelType::WendlandC6:
      return D == 1   ? Real(55) / Real(32)
             : D == 2 ? Real(78) / (Real(7) * kPi)
                      : Real(1365) / (Real(64) * kPi);
  }
  return Real(0);
}

// Dimensionless shape f(q) for 0 <= q < 1 (callers handle q >= 1).
template <int D>
RUBBLE_HD_INLINE Real shape(KernelType k, Real q) {
  const Real u = Real(1) - q;
  switch (k) {
    case KernelType::CubicSpline:
      return q < Real(0.5) ? Real(1) - Real(6) * q * q + Real(6) * q * q * q : Real(2) * u * u * u;
    case KernelType::WendlandC2:
      if (D == 1) return ipow<3>(u) * (Real(1) + Real(3) * q);
      return ipow<4>(u) * (Real(1) + Real(4) * q);
    case KernelType::WendlandC4:
      if (D == 1) return ipow<5>(u) * (Real(1) + q * (Real(5) + Real(8) * q));
      return ipow<6>(u) * (Real(1) + q * (Real(6) + Real(35) / Real(3) * q));
    case KernelType::WendlandC6:
      if (D == 1) return ipow<7>(u) * (Real(1) + q * (Real(7) + q * (Real(19) + Real(21) * q)));
      return ipow<8>(u) * (Real(1) + q * (Real(8) + q * (Real(25) + Real(32) * q)));
  }
  return Real(0);
}

// (df/dq) / q for 0 <= q < 1. Every f'(q) has a factor q near the origin, so
// this is finite at q = 0 and gives a smooth gradient ∇W = sigma/H^(D+2) g dx.
//   cubic: 6(3q-2) (q < 1/2),  -6(1-q)^2/q (q >= 1/2)
//   1-D:   C2 -12(1-q)^2,  C4 -14(1-q)^4(1+4q),  C6 -6(1-q)^6(3+18q+35q^2)
//   2/3-D: C2 -20(1-q)^3,  C4 -56/3(1-q)^5(1+5q), C6 -22(1-q)^7(1+7q+16q^2)
template <int D>
RUBBLE_HD_INLINE Real dshape_over_q(KernelType k, Real q) {
  const Real u = Real(1) - q;
  switch (k) {
    case KernelType::CubicSpline:
      return q < Real(0.5) ? Real(6) * (Real(3) * q - Real(2)) : Real(-6) * u * u / q;
    case KernelType::WendlandC2:
      if (D == 1) return Real(-12) * u * u;
      return Real(-20) * ipow<3>(u);
    case KernelType::WendlandC4:
      if (D == 1) return Real(-14) * ipow<4>(u) * (Real(1) + Real(4) * q);
      return Real(-56) / Real(3) * ipow<5>(u) * (Real(1) + Real(5) * q);
    case KernelType::WendlandC6:
      if (D == 1) return Real(-6) * ipow<6>(u) * (Real(3) + q * (Real(18) + Real(35) * q));
      return Real(-22) * ipow<7>(u) * (Real(1) + q * (Real(7) + Real(16) * q));
  }
  return Real(0);
}

// f'(q) itself, for gradients formed with 1/r known: the cubic spline's
// outer branch without the division by q; q (f'/q) for the Wendland
// kernels, whose f'/q above has no division.
template <int D>
RUBBLE_HD_INLINE Real dshape(KernelType k, Real q) {
  if (k == KernelType::CubicSpline) {
    const Real u = Real(1) - q;
    return q < Real(0.5) ? Real(6) * q * (Real(3) * q - Real(2)) : Real(-6) * u * u;
  }
  return q * dshape_over_q<D>(k, q);
}

}  // namespace kernel_detail

// W(r, H), normalised so that ∫ W dV = 1 in D dimensions; zero for r >= H.
template <int D>
RUBBLE_HD_INLINE Real kernel_w(KernelType k, Real r, Real H) {
  const Real q = r / H;
  if (q >= Real(1)) return Real(0);
  return kernel_detail::sigma<D>(k) / kernel_detail::ipow<D>(H) * kernel_detail::shape<D>(k, q);
}

// ∂W/∂r = sigma/H^(D+1) f'(q) <= 0.
template <int D>
RUBBLE_HD_INLINE Real kernel_dwdr(KernelType k, Real r, Real H) {
  const Real q = r / H;
  if (q >= Real(1)) return Real(0);
  return kernel_detail::sigma<D>(k) / kernel_detail::ipow<D + 1>(H) * q *
         kernel_detail::dshape_over_q<D>(k, q);
}

// ∂W/∂H at fixed r = -(D W + r ∂W/∂r) / H = -sigma/H^(D+1) (D f + q f').
template <int D>
RUBBLE_HD_INLINE Real kernel_dwdh(KernelType k, Real r, Real H) {
  const Real q = r / H;
  if (q >= Real(1)) return Real(0);
  const Real f = kernel_detail::shape<D>(k, q);
  const Real qdf = q * q * kernel_detail::dshape_over_q<D>(k, q);
  return -kernel_detail::sigma<D>(k) / kernel_detail::ipow<D + 1>(H) * (Real(D) * f + qdf);
}

// ∇_a W(|x_a - x_b|, H) with dx = x_a - x_b:  (∂W/∂r) dx / r
// = sigma/H^(D+2) (f'(q)/q) dx, which is the zero vector at r = 0.
template <int D>
RUBBLE_HD_INLINE Vec<D> kernel_grad(KernelType k, const Vec<D>& dx, Real H) {
  const Real q = norm(dx) / H;
  if (q >= Real(1)) return Vec<D>::zero();
  const Real s = kernel_detail::sigma<D>(k) / kernel_detail::ipow<D + 2>(H) *
                 kernel_detail::dshape_over_q<D>(k, q);
  return dx * s;
}

// ---- one support radius, many neighbours ---------------------------------
// A loop over a particle's neighbours evaluates the kernel of one H at many
// r. KernelAt holds 1/H and sigma/H^n once, so that a neighbour costs no
// division (the cubic spline's outer gradient excepted): the formulas are
// those of kernel_w, kernel_dwdh and kernel_grad above, and the results
// agree with them to rounding (q = r * (1/H) instead of r / H; tested in
// test_kernels.cpp). Issue #14: the divisions and square roots of the
// per-call functions were a third of the force loop's time.
template <int D>
struct KernelAt {
  KernelType k;
  Real inv_h;   // 1/H
  Real c_w;     // sigma_D / H^D
  Real c_dh;    // sigma_D / H^(D+1)
  Real c_grad;  // sigma_D / H^(D+2)
};

// The same from 1/H computed elsewhere as Real(1) / H (bit for bit the
// result of kernel_at(k, H)): the solid driver keeps each particle's 1/H for
// its neighbours (SolidInverses in drivers/particle_rates.hpp).
template <int D>
RUBBLE_HD_INLINE KernelAt<D> kernel_at_inv(KernelType k, Real inv) {
  const Real c = kernel_detail::sigma<D>(k) * kernel_detail::ipow<D>(inv);
  return KernelAt<D>{k, inv, c, c * inv, c * inv * inv};
}

template <int D>
RUBBLE_HD_INLINE KernelAt<D> kernel_at(KernelType k, Real H) {
  return kernel_at_inv<D>(k, Real(1) / H);
}

// W(r, H) and ∂W/∂H(r, H) from one evaluation of q (summation density and
// its grad-h term need both at every neighbour).
struct KernelWDwdh {
  Real w, dwdh;
};

template <int D>
RUBBLE_HD_INLINE KernelWDwdh kernel_w_dwdh(const KernelAt<D>& K, Real r) {
  const Real q = r * K.inv_h;
  if (q >= Real(1)) return KernelWDwdh{Real(0), Real(0)};
  const Real f = kernel_detail::shape<D>(K.k, q);
  const Real qdf = q * q * kernel_detail::dshape_over_q<D>(K.k, q);
  return KernelWDwdh{K.c_w * f, -K.c_dh * (Real(D) * f + qdf)};
}

// ∇_a W(|dx|, H) with r = |dx| already known.
template <int D>
RUBBLE_HD_INLINE Vec<D> kernel_grad(const KernelAt<D>& K, const Vec<D>& dx, Real r) {
  const Real q = r * K.inv_h;
  if (q >= Real(1)) return Vec<D>::zero();
  return dx * (K.c_grad * kernel_detail::dshape_over_q<D>(K.k, q));
}

// The same with 1/r known as well (r > 0): sigma/H^(D+1) f'(q) dx/r, so that
// a pair's two gradients share one division.
template <int D>
RUBBLE_HD_INLINE Vec<D> kernel_grad(const KernelAt<D>& K, const Vec<D>& dx, Real r, Real inv_r) {
  const Real q = r * K.inv_h;
  if (q >= Real(1)) return Vec<D>::zero();
  return dx * (K.c_dh * kernel_detail::dshape<D>(K.k, q) * inv_r);
}

// Default H/Δx for each kernel (see "Default H / Δx" above).
RUBBLE_HD constexpr double kernel_default_hfact(KernelType k) {
  switch (k) {
    case KernelType::CubicSpline:
      return 2.4;
    case KernelType::WendlandC2:
      return 2.8;
    case KernelType::WendlandC4:
      return 3.2;
    case KernelType::WendlandC6:
      return 3.5;
  }
  return 2.4;
}

// Monaghan's smoothing length h_M = monaghan_h_factor * H, the length of
// the artificial viscosity's mu_ab and of the Courant limit. For the cubic
// spline it is its own h = H/2 (Monaghan 1992). For the Wendland kernels it
// is the cubic spline's h_M at the same resolution, i.e. at the same kernel
// standard deviation s (see "Default H / Δx" above):
//   h_M = (H/s)_cubic / (2 (H/s)_kernel) * H
// so that a Wendland run gets the viscosity and time step of a cubic-spline
// run of equal resolution rather than of equal support (H/2 for every
// kernel gave 1.17x (C2) to 1.46x (C6) the cubic spline's mu_ab at the
// default H/Δx; issue #17 item 5). Closed forms in 1-D and 3-D: C2 sqrt(2/7),
// sqrt(2)/3; C4 1/sqrt(5), sqrt(20/117); C6 sqrt(2/13), sqrt(5)/6; the
// values are checked against quadrature in test_kernels.cpp.
template <int D>
RUBBLE_HD_INLINE Real monaghan_h_factor(KernelType k) {
  switch (k) {
    case KernelType::CubicSpline:
      return Real(0.5);
    case KernelType::WendlandC2:
      return D == 1 ? Real(0.534522483824849) : D == 2 ? Real(0.468544608526457) : Real(0.471404520791032);
    case KernelType::WendlandC4:
      return D == 1 ? Real(0.447213595499958) : D == 2 ? Real(0.409443749217463) : Real(0.413449115297363);
    case KernelType::WendlandC6:
      return D == 1 ? Real(0.392232270276368) : D == 2 ? Real(0.368081337434607) : Real(0.372677996249965);
  }
  return Real(0.5);
}

// ---- host-only helpers --------------------------------------------------------
inline const char* kernel_name(KernelType k) {
  switch (k) {
    case KernelType::CubicSpline:
      return "cubic_spline";
    case KernelType::WendlandC2:
      return "wendland_c2";
    case KernelType::WendlandC4:
      return "wendland_c4";
    case KernelType::WendlandC6:
      return "wendland_c6";
  }
  return "unknown";
}

// Parses a name written by kernel_name(). Returns false (and leaves `out`
// untouched) for anything else.
inline bool kernel_from_name(std::string_view name, KernelType& out) {
  constexpr KernelType all[] = {KernelType::CubicSpline, KernelType::WendlandC2,
                                KernelType::WendlandC4, KernelType::WendlandC6};
  for (KernelType k : all) {
    if (name == kernel_name(k)) {
      out = k;
      return true;
    }
  }
  return false;
}

}  // namespace rubble
