// Unit tests of the solid-mechanics physics functions: Hooke's law with the
// Jaumann rate, plane-strain J2, the symmetric eigen-solver used by the
// artificial stress (against Eigen), the artificial stress itself, and the
// kernel-gradient correction.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>

#include "rubble/drivers/particle_rates.hpp"
#include "rubble/physics/artificial_stress.hpp"
#include "rubble/physics/jaumann_rate.hpp"
#include "rubble/physics/kernel_gradient_correction.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/hydro.hpp"
#include "rubble/physics/solid.hpp"
#include "rubble/physics/symmetric_eigen.hpp"

using namespace rubble;

namespace {

template <int D>
Mat<D> random_symmetric(std::mt19937& gen) {
  std::uniform_real_distribution<double> U(-1, 1);
  Mat<D> A;
  for (int i = 0; i < D; ++i)
    for (int j = i; j < D; ++j) A.m[i][j] = A.m[j][i] = U(gen);
  return A;
}

template <int D>
double max_abs_diff(const Mat<D>& a, const Mat<D>& b) {
  double d = 0;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) d = std::max(d, std::fabs(a.m[i][j] - b.m[i][j]));
  return d;
}

// Rotation by angle t about z (2-D) or about the axis (1,2,3)/|.| (3-D).
template <int D>
Mat<D> rotation(double t);
template <>
Mat<2> rotation<2>(double t) {
  Mat<2> Q;
  Q.m[0][0] = std::cos(t); Q.m[0][1] = -std::sin(t);
  Q.m[1][0] = std::sin(t); Q.m[1][1] = std::cos(t);
  return Q;
}
template <>
Mat<3> rotation<3>(double t) {
  const double n[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
  const double c = std::cos(t), s = std::sin(t);
  Mat<3> Q;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Q.m[i][j] = (i == j ? c : 0) + (1 - c) * n[i] * n[j];
  Q.m[0][1] -= s * n[2]; Q.m[0][2] += s * n[1];
  Q.m[1][0] += s * n[2]; Q.m[1][2] -= s * n[0];
  Q.m[2][0] -= s * n[1]; Q.m[2][1] += s * n[0];
  return Q;
}

// Rigid rotation with angular speed omega: L = dQ/dt Q^T is the constant
// spin tensor; integrate dS/dt with RK4 and compare with Q S0 Q^T.
template <int D>
void check_corotation() {
  std::mt19937 gen(7);
  Mat<D> S0 = random_symmetric<D>(gen);
  S0 -= (trace(S0) / D) * Mat<D>::identity();
  const double omega = 0.7, h = 1e-3;
  const Mat<D> L = (1 / h) * (rotation<D>(omega * h) - rotation<D>(-omega * h)) * 0.5;  // dQ/dt at t=0
  Mat<D> S = S0;
  const double mu = 3.0;
  const int steps = 2000;
  const double dt = 1.0 / steps;
  for (int n = 0; n < steps; ++n) {
    const Mat<D> k1 = deviatoric_stress_rate(S, L, mu);
    const Mat<D> k2 = deviatoric_stress_rate(S + (0.5 * dt) * k1, L, mu);
    const Mat<D> k3 = deviatoric_stress_rate(S + (0.5 * dt) * k2, L, mu);
    const Mat<D> k4 = deviatoric_stress_rate(S + dt * k3, L, mu);
    S += (dt / 6) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  const Mat<D> Q = rotation<D>(omega * 1.0);
  const Mat<D> expected = Q * S0 * transpose(Q);
  // |S| is unchanged (the rotation does no work)...
  EXPECT_NEAR(double_dot(S, S), double_dot(S0, S0), 1e-9);
  // ...and S turns with the body; the bound covers the finite-difference L
  // (O(h^2) = 1e-7 relative) and RK4 (negligible at dt = 5e-4).
  EXPECT_LT(max_abs_diff(S, expected), 1e-6);
  // A strain-free rotation creates no deviatoric stress from nothing.
  const Mat<D> zero_rate = deviatoric_stress_rate(Mat<D>::zero(), L, mu);
  EXPECT_LT(max_abs_diff(zero_rate, Mat<D>::zero()), 1e-12);
}

}  // namespace

TEST(JaumannRate, StressCoRotatesWithRigidRotation2D) { check_corotation<2>(); }
TEST(JaumannRate, StressCoRotatesWithRigidRotation3D) { check_corotation<3>(); }

// Uniaxial strain rate L = diag(e, 0, 0): dS_xx/dt = (4/3) mu e,
// dS_yy/dt = dS_zz/dt = -(2/3) mu e (Hooke's law, deviatoric part).
TEST(JaumannRate, UniaxialStrainRate) {
  const double mu = 2.5, e = 0.3;
  Mat<3> L = Mat<3>::zero();
  L.m[0][0] = e;
  const Mat<3> dS = deviatoric_stress_rate(Mat<3>::zero(), L, mu);
  EXPECT_NEAR(dS.m[0][0], 4.0 / 3.0 * mu * e, 1e-14);
  EXPECT_NEAR(dS.m[1][1], -2.0 / 3.0 * mu * e, 1e-14);
  EXPECT_NEAR(dS.m[2][2], -2.0 / 3.0 * mu * e, 1e-14);
  EXPECT_NEAR(dS.m[0][1], 0.0, 1e-15);

  // 2-D plane strain: the same in-plane rates, and the implied S_zz rate
  // -(dS_xx + dS_yy) equals the 3-D one.
  Mat<2> L2 = Mat<2>::zero();
  L2.m[0][0] = e;
  const Mat<2> dS2 = deviatoric_stress_rate(Mat<2>::zero(), L2, mu);
  EXPECT_NEAR(dS2.m[0][0], dS.m[0][0], 1e-14);
  EXPECT_NEAR(dS2.m[1][1], dS.m[1][1], 1e-14);
  EXPECT_NEAR(-(dS2.m[0][0] + dS2.m[1][1]), dS.m[2][2], 1e-14);
}

// Pure shear L_xy = g: dS_xy/dt = mu g (engineering shear rate g).
TEST(JaumannRate, SimpleShearRate) {
  const double mu = 1.7, g = 0.4;
  Mat<2> L = Mat<2>::zero();
  L.m[0][1] = g;
  const Mat<2> dS = deviatoric_stress_rate(Mat<2>::zero(), L, mu);
  EXPECT_NEAR(dS.m[0][1], mu * g, 1e-14);
  EXPECT_NEAR(dS.m[1][0], mu * g, 1e-14);
  EXPECT_NEAR(dS.m[0][0], 0.0, 1e-15);
}

// J2 includes the out-of-plane deviator: a 2-D state and the equivalent
// 3-D state with S_zz = -(S_xx + S_yy) give the same J2.
TEST(PlaneStrain, J2IncludesOutOfPlaneComponent) {
  Mat<2> S2;
  S2.m[0][0] = 1.0; S2.m[1][1] = 0.5; S2.m[0][1] = S2.m[1][0] = 0.3;
  Mat<3> S3 = Mat<3>::zero();
  S3.m[0][0] = 1.0; S3.m[1][1] = 0.5; S3.m[0][1] = S3.m[1][0] = 0.3; S3.m[2][2] = -1.5;
  EXPECT_NEAR(deviatoric_j2(S2), deviatoric_j2(S3), 1e-14);
  EXPECT_NEAR(deviatoric_j2(S3), 0.5 * (1 + 0.25 + 2.25 + 2 * 0.09), 1e-14);
  Mat<1> S1;
  S1.m[0][0] = 2.0;  // uniaxial: S_yy = S_zz = -1
  EXPECT_NEAR(deviatoric_j2(S1), 0.5 * (4 + 1 + 1), 1e-14);
}

// The principal frame used by the artificial stress matches Eigen's
// self-adjoint solver (eigenvalues to 1e-12, and A V = V diag(lambda)).
template <int D>
void check_eigen_against_eigen_library() {
  std::mt19937 gen(11 + D);
  for (int trial = 0; trial < 200; ++trial) {
    const Mat<D> A = random_symmetric<D>(gen);
    const SymmetricEigen<D> ours = symmetric_eigen(A);
    Eigen::Matrix<double, D, D> E;
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) E(i, j) = A.m[i][j];
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, D, D>> solver(E);
    std::vector<double> mine(ours.lambda, ours.lambda + D);
    std::sort(mine.begin(), mine.end());
    for (int i = 0; i < D; ++i) EXPECT_NEAR(mine[i], solver.eigenvalues()(i), 1e-12);
    for (int k = 0; k < D; ++k) {  // A v_k = lambda_k v_k, |v_k| = 1
      double norm2 = 0;
      for (int i = 0; i < D; ++i) {
        double av = 0;
        for (int j = 0; j < D; ++j) av += A.m[i][j] * ours.V.m[j][k];
        EXPECT_NEAR(av, ours.lambda[k] * ours.V.m[i][k], 1e-12);
        norm2 += ours.V.m[i][k] * ours.V.m[i][k];
      }
      EXPECT_NEAR(norm2, 1.0, 1e-12);
    }
  }
}

TEST(SymmetricEigen, MatchesEigenLibrary2D) { check_eigen_against_eigen_library<2>(); }
TEST(SymmetricEigen, MatchesEigenLibrary3D) { check_eigen_against_eigen_library<3>(); }

TEST(ArtificialStress, OnlyTensilePrincipalStressesAreCorrected) {
  // principal stresses +2 (tension) and -1 (compression) along axes rotated by 30 degrees
  const Mat<2> Q = rotation<2>(M_PI / 6);
  Mat<2> P = Mat<2>::zero();
  P.m[0][0] = 2.0;
  P.m[1][1] = -1.0;
  const Mat<2> sigma = Q * P * transpose(Q);
  const double rho = 2.0, eps = 0.3;
  const Mat<2> R = artificial_stress_tensor(sigma, rho, eps);
  // In the principal frame R' = diag(-eps * 2 / rho^2, 0).
  const Mat<2> Rp = transpose(Q) * R * Q;
  EXPECT_NEAR(Rp.m[0][0], -eps * 2.0 / (rho * rho), 1e-13);
  EXPECT_NEAR(Rp.m[1][1], 0.0, 1e-13);
  EXPECT_NEAR(Rp.m[0][1], 0.0, 1e-13);
  // purely compressive stress: no correction
  const Mat<2> Rc = artificial_stress_tensor(-1.0 * Mat<2>::identity(), rho, eps);
  EXPECT_LT(max_abs_diff(Rc, Mat<2>::zero()), 1e-15);
}

TEST(ArtificialStress, PairFactor) {
  EXPECT_NEAR(artificial_stress_factor(0.5, 1.0, 4.0), 0.0625, 1e-15);
  EXPECT_NEAR(artificial_stress_factor(1.0, 1.0, 4.0), 1.0, 1e-15);  // at r = dp
  EXPECT_NEAR(artificial_stress_factor(0.5, 1.0, 2.5), std::pow(0.5, 2.5), 1e-15);
  EXPECT_EQ(artificial_stress_factor(0.5, 0.0, 4.0), 0.0);
}

TEST(ArtificialStress, LocalSpacingIsTheCubicLatticeSpacing) {
  // m = rho s^D on a cubic lattice of spacing s
  EXPECT_NEAR(local_spacing<1>(0.3 * 2.0, 2.0), 0.3, 1e-15);
  EXPECT_NEAR(local_spacing<2>(0.3 * 0.3 * 2.0, 2.0), 0.3, 1e-15);
  EXPECT_NEAR(local_spacing<3>(0.3 * 0.3 * 0.3 * 2.0, 2.0), 0.3, 1e-15);
}

TEST(ArtificialStress, ClumpingWeightRampsFromOnsetToFull) {
  const double s = 0.2, on = 1.0, full = 0.9;
  // a regular lattice, or one stretched: the nearest neighbour is >= s away
  EXPECT_EQ(clumping_weight(s, s, on, full), 0.0);
  EXPECT_EQ(clumping_weight(1.05 * s, s, on, full), 0.0);
  // clumped: full weight at and below full * s
  EXPECT_EQ(clumping_weight(0.9 * s, s, on, full), 1.0);
  EXPECT_EQ(clumping_weight(0.3 * s, s, on, full), 1.0);
  // linear in between, and continuous at both ends
  EXPECT_NEAR(clumping_weight(0.95 * s, s, on, full), 0.5, 1e-12);
  EXPECT_NEAR(clumping_weight((1.0 - 1e-9) * s, s, on, full), 1e-8, 1e-12);
  EXPECT_NEAR(clumping_weight((0.9 + 1e-9) * s, s, on, full), 1.0 - 1e-8, 1e-12);
  // onset <= 0 is Monaghan's form: full weight everywhere
  EXPECT_EQ(clumping_weight(2.0 * s, s, 0.0, 0.0), 1.0);
}

// On a regular 2-D lattice, the corrected gradient of a linear field is
// exact, even at a free surface (corner particle), where the uncorrected
// one is far off.
TEST(KernelGradientCorrection, ReproducesLinearFieldsAtFreeSurface) {
  const double dx = 0.1, H = 2.4 * dx, V = dx * dx;
  auto field = [](const Vec<2>& x) { return 2.0 * x[0] - 3.0 * x[1]; };
  for (int corner : {0, 1}) {
    const Vec<2> xa = corner ? Vec<2>{{0.0, 0.0}} : Vec<2>{{1.0, 1.0}};  // corner or interior of a 21x21 block
    Mat<2> sum = Mat<2>::zero();
    Vec<2> grad_raw = Vec<2>::zero();
    std::vector<std::pair<Vec<2>, Vec<2>>> pairs;
    for (int i = 0; i <= 20; ++i)
      for (int j = 0; j <= 20; ++j) {
        const Vec<2> xb{{i * dx, j * dx}};
        const Vec<2> d = xa - xb;
        if (norm(d) == 0 || norm(d) >= H) continue;
        const Vec<2> g = kernel_grad<2>(KernelType::CubicSpline, d, H);
        sum += correction_pair_term<2>(1.0 * V, 1.0, xb - xa, g);
        grad_raw += (V * (field(xb) - field(xa))) * g;
        pairs.push_back({xb, g});
      }
    Mat<2> C;
    ASSERT_TRUE(correction_matrix<2>(sum, 1e-3, C));
    // corrected gradient: sum_b V (f_b - f_a) C grad W  (C applied to the kernel gradient)
    Vec<2> grad = Vec<2>::zero();
    for (const auto& [xb, g] : pairs) grad += (V * (field(xb) - field(xa))) * (C * g);
    EXPECT_NEAR(grad[0], 2.0, 1e-12);
    EXPECT_NEAR(grad[1], -3.0, 1e-12);
    if (corner) {
      EXPECT_GT(std::fabs(grad_raw[0] - 2.0), 0.5);  // uncorrected: badly off at the corner
    }
  }
}

TEST(KernelGradientCorrection, IllConditionedFallsBackToIdentity) {
  Mat<2> sum = Mat<2>::zero();
  sum.m[0][0] = 1.0;  // a single neighbour along x: rank 1
  Mat<2> C;
  EXPECT_FALSE(correction_matrix<2>(sum, 1e-3, C));
  EXPECT_LT(max_abs_diff(C, Mat<2>::identity()), 1e-15);
}

// Issue #4 item 4d: the solid pair force (full stress, artificial stress,
// viscosity) conserves linear momentum to round-off, and du/dt is its work,
// so kinetic + internal energy does not change either. With the
// kernel-gradient correction (issue #17 item 4) each particle's stress acts
// along its own K gbar, K an arbitrary (here random, non-symmetric) matrix:
// both still hold, pair by pair.
template <int D>
void check_solid_pair_conservation(bool corrected) {
  std::mt19937 gen(42 + D);
  std::uniform_real_distribution<double> U(0, 1), S(-1, 1);
  const int n = 40;
  std::vector<SolidParticle<D>> ps(n);
  std::vector<Mat<D>> K(n);
  for (int i = 0; i < n; ++i) {
    K[i] = Mat<D>::identity();
    for (int r = 0; r < D; ++r)
      for (int c = 0; c < D; ++c) K[i].m[r][c] += 0.5 * S(gen);
    if (corrected) ps[i].K = &K[i];
  }
  for (auto& q : ps) {
    for (int k = 0; k < D; ++k) {
      q.x[k] = U(gen);
      q.v[k] = S(gen);
    }
    q.m = 0.5 + U(gen);
    q.rho = 0.8 + 0.4 * U(gen);
    q.p = S(gen);
    q.h = 0.45 + 0.1 * U(gen);
    q.cs = 1 + U(gen);
    q.S = random_symmetric<D>(gen);
    Mat<D> sigma = q.S;
    for (int k = 0; k < D; ++k) sigma.m[k][k] -= q.p;
    q.R = artificial_stress_tensor<D>(sigma, q.rho, 0.3);
    q.av = {1.0, 2.0};
    q.dp = 0.1;
    q.as_exponent = 4;
  }
  Vec<D> P = Vec<D>::zero();
  double scale = 0, power = 0, power_scale = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      if (a == b) continue;
      const auto r = solid_pair<D>(KernelType::CubicSpline, ps[a], ps[b], ps[a].x - ps[b].x);
      P += ps[a].m * r.dvdt;
      scale += ps[a].m * norm(r.dvdt);
      power += ps[a].m * (dot(ps[a].v, r.dvdt) + r.dudt);
      power_scale += ps[a].m * (std::fabs(dot(ps[a].v, r.dvdt)) + std::fabs(r.dudt));
    }
  ASSERT_GT(scale, 0.0);
  const double eps = 100 * std::numeric_limits<Real>::epsilon();
  EXPECT_LT(norm(P), eps * scale);
  EXPECT_LT(std::fabs(power), eps * power_scale);
}
TEST(SolidPair, ConservesMomentumAndEnergy2D) { check_solid_pair_conservation<2>(false); }
TEST(SolidPair, ConservesMomentumAndEnergy3D) { check_solid_pair_conservation<3>(false); }
TEST(SolidPair, ConservesMomentumAndEnergyWithKernelCorrection2D) { check_solid_pair_conservation<2>(true); }
TEST(SolidPair, ConservesMomentumAndEnergyWithKernelCorrection3D) { check_solid_pair_conservation<3>(true); }

// The CPU's solid force loop computes a pair of two particles of a thread's
// range once and takes b's rates from the same terms (solid_pair_rates_b).
// They must be exactly the pair computed from b's side, bit for bit, for
// any pair: random states and masses, h differing by up to 2x, with and
// without the kernel-gradient correction (also on one side only), with
// artificial stress on both, one or neither side (R = 0 skips its factor),
// with and without conductivity, pairs outside both supports included.
template <int D>
void check_two_sides_of_a_solid_pair(int variant) {
  std::mt19937 gen(11 + D + 10 * variant);
  std::uniform_real_distribution<double> U(0, 1), S(-1, 1);
  const bool conductivity = variant & 1;
  int active = 0;
  for (int trial = 0; trial < 400; ++trial) {
    SolidParticle<D> q[2];
    Mat<D> K[2];
    for (int i = 0; i < 2; ++i) {
      for (int k = 0; k < D; ++k) {
        q[i].x[k] = 1.6 * U(gen);
        q[i].v[k] = S(gen);
      }
      q[i].m = 0.5 + U(gen);
      q[i].rho = 0.8 + 0.4 * U(gen);
      q[i].p = S(gen);
      q[i].h = 0.5 + 0.5 * U(gen);
      q[i].cs = 1 + U(gen);
      q[i].S = random_symmetric<D>(gen);
      Mat<D> sigma = q[i].S;
      for (int k = 0; k < D; ++k) sigma.m[k][k] -= q[i].p;
      q[i].R = U(gen) < 0.3 ? Mat<D>::zero() : artificial_stress_tensor<D>(sigma, q[i].rho, 0.3);
      q[i].av = {0.5 + U(gen), 1 + U(gen)};
      q[i].dp = 0.1 + 0.05 * U(gen);
      q[i].as_exponent = 4;
      q[i].u = 1 + U(gen);
      q[i].alpha_u = conductivity ? 1.0 : 0.0;
      K[i] = Mat<D>::identity();
      for (int r = 0; r < D; ++r)
        for (int c = 0; c < D; ++c) K[i].m[r][c] += 0.5 * S(gen);
      if ((variant & 2) && (i == 0 || U(gen) < 0.7)) q[i].K = &K[i];
    }
    const SolidParticle<D>&a = q[0], &b = q[1];
    const Vec<D> dx = a.x - b.x;
    const SolidInverses ia = solid_inverses(a.h, a.rho), ib = solid_inverses(b.h, b.rho);
    const SolidPairTerms<D> t = solid_pair_terms<D>(KernelType::CubicSpline, a, ia, b, ib, dx);
    const SolidPairRates<D> ra = solid_pair_rates_a<D>(t, b.m), rb = solid_pair_rates_b<D>(t, a.m);
    const SolidPairRates<D> want_a = solid_pair<D>(KernelType::CubicSpline, a, b, dx);
    const SolidPairRates<D> want_b = solid_pair<D>(KernelType::CubicSpline, b, a, -dx);
    active += t.active;
    for (int k = 0; k < D; ++k) {
      EXPECT_EQ(ra.dvdt[k], want_a.dvdt[k]) << trial;
      EXPECT_EQ(rb.dvdt[k], want_b.dvdt[k]) << trial;
    }
    EXPECT_EQ(ra.dudt, want_a.dudt) << trial;
    EXPECT_EQ(rb.dudt, want_b.dudt) << trial;
    EXPECT_EQ(ra.drhodt, want_a.drhodt) << trial;
    EXPECT_EQ(rb.drhodt, want_b.drhodt) << trial;
    EXPECT_EQ(ra.mu, want_a.mu) << trial;
    EXPECT_EQ(rb.mu, want_b.mu) << trial;
  }
  EXPECT_GT(active, 50);   // many pairs interact ...
  EXPECT_LT(active, 400);  // ... and some lie outside both supports
}

// Pass 1 of the solid loop (velocity gradient, correction sums) on the CPU
// adds a pair's terms to b's sums as other_side of a's: they must be the
// terms computed from b's side, bit for bit, for every pair of a random
// cloud (h differing by up to 2x, pairs beyond both supports included),
// so that the pair-once loop differs from the gather loop only in the
// order of the sums.
template <int D>
void check_gradient_pair_sides(bool corrected) {
  std::mt19937 gen(5 + D + 10 * corrected);
  std::uniform_real_distribution<double> U(0, 1), S(-1, 1);
  const std::size_t n = 24;
  std::vector<Vec<D>> x(n), v(n);
  std::vector<Real> m(n), rho(n), h(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < D; ++k) {
      x[i][k] = 1.5 * U(gen);
      v[i][k] = S(gen);
    }
    m[i] = 0.5 + U(gen);
    rho[i] = 0.8 + 0.4 * U(gen);
    h[i] = 0.5 + 0.5 * U(gen);
  }
  RhsContext<D> c;
  c.s.n = n, c.s.x = x.data(), c.s.v = v.data(), c.s.m = m.data(), c.s.rho = rho.data(), c.s.h = h.data();
  c.kernel_correction = corrected;
  int active = 0, pairs = 0;
  for (std::uint32_t a = 0; a < n; ++a)
    for (std::uint32_t b = 0; b < n; ++b) {
      if (a == b) continue;
      const KernelAt<D> ka = kernel_at<D>(c.kernel, h[a]), kb = kernel_at<D>(c.kernel, h[b]);
      const GradientPairTerms<D> ab = gradient_pair_terms<D>(c, a, b, ka, x[a] - x[b]);
      const GradientPairTerms<D> ba = gradient_pair_terms<D>(c, b, a, kb, x[b] - x[a]);
      const GradientPairTerms<D> mirrored = other_side<D>(ab);
      ++pairs;
      active += ab.active;
      ASSERT_EQ(ab.active, ba.active);
      EXPECT_EQ(ab.r2, ba.r2);
      if (!ab.active) continue;
      for (int k = 0; k < D; ++k) {
        EXPECT_EQ(mirrored.g[k], ba.g[k]);
        EXPECT_EQ(mirrored.v_ba[k], ba.v_ba[k]);
        EXPECT_EQ(mirrored.x_ba[k], ba.x_ba[k]);
      }
      GradientSums<D> want, got;
      add_gradient_pair<D>(c, b, a, ba, want);
      add_gradient_pair<D>(c, b, a, mirrored, got);
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) {
          EXPECT_EQ(got.L.m[i][j], want.L.m[i][j]);
          EXPECT_EQ(got.M.m[i][j], want.M.m[i][j]);
        }
    }
  EXPECT_GT(active, pairs / 10);  // many pairs interact ...
  EXPECT_LT(active, pairs);       // ... and some lie beyond both supports
}

TEST(SolidGradient, PairTermsOfTheOtherSideAreThoseSeenFromIt) {
  for (bool corrected : {false, true}) {
    check_gradient_pair_sides<1>(corrected);
    check_gradient_pair_sides<2>(corrected);
    check_gradient_pair_sides<3>(corrected);
  }
}

TEST(SolidPair, BothSidesFromOneEvaluationAreThePairSeenFromEachSide) {
  for (int variant = 0; variant < 4; ++variant) {
    check_two_sides_of_a_solid_pair<1>(variant);
    check_two_sides_of_a_solid_pair<2>(variant);
    check_two_sides_of_a_solid_pair<3>(variant);
  }
}

// With the correction, a's continuity rate and the pressure and shear work
// in its energy rate use a's corrected gradient K_a gbar: drho_a/dt =
// m_b v_ab . K_a gbar and, without viscosity or artificial stress,
// du_a/dt = -m_b (sigma_a/rho_a^2) : (v_ab (x) K_a gbar), whatever K_b is.
TEST(SolidPair, CorrectedRatesUseTheParticlesOwnGradient) {
  SolidParticle<2> a{}, b{};
  a.x = Vec<2>{{0.0, 0.0}};
  b.x = Vec<2>{{0.3, 0.1}};
  a.v = Vec<2>{{0.2, -0.1}};
  b.v = Vec<2>{{-0.3, 0.05}};
  a.m = 1; b.m = 1.2; a.rho = 1; b.rho = 1.1; a.p = 0.3; b.p = 0.1; a.h = 0.5; b.h = 0.55; a.cs = 1; b.cs = 1.1;
  a.S.m[0][0] = 0.2; a.S.m[1][1] = -0.1; a.S.m[0][1] = a.S.m[1][0] = 0.05;
  b.S.m[0][0] = -0.1; b.S.m[0][1] = b.S.m[1][0] = 0.02;
  a.av = b.av = {0.0, 0.0};
  Mat<2> Ka = Mat<2>::identity(), Kb = Mat<2>::identity();
  Ka.m[0][0] = 1.7; Ka.m[0][1] = 0.2; Ka.m[1][0] = -0.1; Ka.m[1][1] = 1.3;
  Kb.m[0][0] = 0.6; Kb.m[1][1] = 2.1;
  a.K = &Ka;
  b.K = &Kb;
  const Vec<2> dx = a.x - b.x;
  const Vec<2> g = 0.5 * (kernel_grad<2>(KernelType::CubicSpline, dx, a.h) + kernel_grad<2>(KernelType::CubicSpline, dx, b.h));
  const Vec<2> ga = Ka * g, gb = Kb * g;
  const Mat<2> sa = stress_over_rho2<2>(a.p, a.S, a.rho), sb = stress_over_rho2<2>(b.p, b.S, b.rho);
  const auto r = solid_pair<2>(KernelType::CubicSpline, a, b, dx);
  const Vec<2> dv = a.v - b.v;
  EXPECT_NEAR(r.drhodt, b.m * dot(dv, ga), 1e-14);
  EXPECT_NEAR(r.dudt, -b.m * double_dot(sa, Mat<2>::outer(dv, ga)), 1e-14);
  const Vec<2> f = b.m * (sa * ga + sb * gb);
  EXPECT_NEAR(r.dvdt[0], f[0], 1e-14);
  EXPECT_NEAR(r.dvdt[1], f[1], 1e-14);
}

// The time step's correction gain: 1 for the identity (or anything that
// shortens gradients), the largest absolute row sum otherwise.
TEST(KernelGradientCorrection, GainIsTheLargestRowSum) {
  EXPECT_EQ(correction_gain<2>(Mat<2>::identity()), 1.0);
  Mat<2> K = Mat<2>::zero();
  K.m[0][0] = 0.5; K.m[1][1] = 0.5;
  EXPECT_EQ(correction_gain<2>(K), 1.0);
  K.m[0][0] = 2.0; K.m[0][1] = -1.0; K.m[1][1] = 2.5;
  EXPECT_EQ(correction_gain<2>(K), 3.0);
}

// Two neighbouring 2-D particles without stress (S = R = 0), approaching.
static void stress_free_pair(SolidParticle<2>& a, SolidParticle<2>& b) {
  a = SolidParticle<2>{};
  b = SolidParticle<2>{};
  a.x = Vec<2>{{0.0, 0.0}};
  b.x = Vec<2>{{0.3, 0.1}};
  a.v = Vec<2>{{0.2, -0.1}};
  b.v = Vec<2>{{-0.3, 0.05}};
  a.m = 1; b.m = 1.2; a.rho = 1; b.rho = 1.1; a.p = 0.3; b.p = 0.1; a.h = 0.5; b.h = 0.55; a.cs = 1; b.cs = 1.1;
  a.S = b.S = a.R = b.R = Mat<2>::zero();
  a.av = b.av = {1.0, 2.0};
}

// With S = 0 and no artificial stress the solid pair is the hydro pair in
// its continuity-density form.
TEST(SolidPair, ReducesToHydroWithoutStress) {
  SolidParticle<2> a, b;
  stress_free_pair(a, b);
  const HydroParticle<2> ha{a.x, a.v, a.m, a.rho, a.p, 0.0, a.h, 1.0, a.cs, a.av, 0.0};
  const HydroParticle<2> hb{b.x, b.v, b.m, b.rho, b.p, 0.0, b.h, 1.0, b.cs, b.av, 0.0};
  const auto s = solid_pair<2>(KernelType::CubicSpline, a, b, a.x - b.x);
  const auto h = hydro_pair<2>(KernelType::CubicSpline, ha, hb, a.x - b.x, true);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(s.dvdt[k], h.dvdt[k], 100 * std::numeric_limits<Real>::epsilon());
  EXPECT_NEAR(s.dudt, h.dudt, 100 * std::numeric_limits<Real>::epsilon());
  EXPECT_NEAR(s.drhodt, h.drhodt, 100 * std::numeric_limits<Real>::epsilon());
  EXPECT_NEAR(s.mu, h.mu, 100 * std::numeric_limits<Real>::epsilon());
}

// A fluid with artificial conductivity in a scene that also holds a solid
// goes through the solid pair (issue #17 item 6): its conductivity term must
// be hydro_pair's, and it must act (not be dropped).
TEST(SolidPair, KeepsTheArtificialConductivity) {
  SolidParticle<2> a, b;
  stress_free_pair(a, b);
  a.u = 2.0; b.u = 0.5;
  const auto without = solid_pair<2>(KernelType::CubicSpline, a, b, a.x - b.x);
  a.alpha_u = 1.0; b.alpha_u = 0.6;
  const HydroParticle<2> ha{a.x, a.v, a.m, a.rho, a.p, a.u, a.h, 1.0, a.cs, a.av, a.alpha_u};
  const HydroParticle<2> hb{b.x, b.v, b.m, b.rho, b.p, b.u, b.h, 1.0, b.cs, b.av, b.alpha_u};
  const auto s = solid_pair<2>(KernelType::CubicSpline, a, b, a.x - b.x);
  const auto h = hydro_pair<2>(KernelType::CubicSpline, ha, hb, a.x - b.x, true);
  EXPECT_NEAR(s.dudt, h.dudt, 100 * std::numeric_limits<Real>::epsilon());
  // hot a, cold b: conduction takes energy from a
  EXPECT_LT(s.dudt, without.dudt);
  EXPECT_GT(without.dudt - s.dudt, 1e-3 * std::fabs(without.dudt));
}
