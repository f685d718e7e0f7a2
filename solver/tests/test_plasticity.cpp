// Unit tests of the plasticity physics (physics/plasticity.hpp): von Mises and
// Drucker–Prager (Bui, Fukagawa, Sako & Ohno 2008) on a homogeneous element
// driven by a prescribed velocity gradient L (no neighbours). Each step is
//   S += dt * deviatoric_stress_rate<D>(S, L, G)       (Hooke + Jaumann)
//   p += -dt * K * tr(eps_dot)                          (linear elastic pressure,
//                                                        trace over the D
//                                                        components: plane
//                                                        strain has eps_zz = 0)
//   (S, p) <- plastic_return(...)
// For a constant diagonal L the Jaumann terms vanish, the elastic path is
// linear in time and explicit Euler is exact, so onsets are compared with the
// closed form to one step; with rotation (simple shear) Euler is first order
// and the bracket is widened by one step (justified where used).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "rubble/physics/jaumann_rate.hpp"
#include "rubble/physics/plasticity.hpp"

using namespace rubble;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSqrt3 = 1.7320508075688772;

// Regolith-like elastic constants: K = 200 MPa, Poisson ratio 0.3.
constexpr double kK = 2.0e8;
constexpr double kNu = 0.3;
const double kG = 3 * kK * (1 - 2 * kNu) / (2 * (1 + kNu));  // 92.3 MPa
const double kE = 9 * kK * kG / (3 * kK + kG);

// D x D block of a 3 x 3 velocity gradient.
template <int D>
Mat<D> block(const double (&L3)[3][3]) {
  Mat<D> L;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) L.m[i][j] = L3[i][j];
  return L;
}

// Relative scale of the yield function for a state: f is compared with
// 1e-12 of this (a return costs a few roundings of O(eps) = 2e-16 each, so
// 1e-12 is ~1000x margin, while any formula error is O(1) of the scale).
double f_scale(const PlasticityParams& pp, double sj2, double p) {
  return std::max({pp.k_c, pp.yield_stress, pp.strength_limit, std::fabs(3 * pp.alpha_phi * p), sj2, 1.0});
}

template <int D>
struct Element {
  PlasticityParams pp;
  Mat<D> S = Mat<D>::zero();
  double p = 0;
  double G = kG, K = kK;
  double damage = 0, u = 0;  // enter the Collins surface only
  // diagnostics of the last step
  double f_trial = 0;
  PlasticReturn<D> last{};

  // One explicit step; returns true when the return mapping acted.
  bool step(const Mat<D>& L, double dt) {
    S += dt * deviatoric_stress_rate<D>(S, L, G);
    p += -dt * K * trace(strain_rate(L));
    f_trial = yield_function<D>(pp, S, p, damage, u);
    const Mat<D> S_tr = S;
    const double p_tr = p;
    last = plastic_return<D>(pp, S, p, G, K, damage, u);
    S = last.S;
    p = last.p;
    return !(S_tr == S) || p_tr != p;
  }
  double f() const { return yield_function<D>(pp, S, p, damage, u); }
  double sj2() const { return std::sqrt(deviatoric_j2(S)); }
};

// Plastic onset along a path: the first step n (1-based) whose trial state is
// outside; -1 if none in nmax steps. Also checks f <= tol after every return.
template <int D>
int run_to_onset(Element<D>& el, const Mat<D>& L, double dt, int nmax) {
  for (int n = 1; n <= nmax; ++n) {
    const bool plastic = el.step(L, dt);
    EXPECT_LE(el.f(), 1e-12 * f_scale(el.pp, el.sj2(), el.p)) << "step " << n;
    if (plastic) return n;
  }
  return -1;
}

// The exact onset time t_y of a linear elastic path must lie in the step
// that first goes plastic: (n-1) dt < t_y <= n dt. The paths below are chosen
// so that t_y/dt is not within 1e-6 of an integer, so rounding (1e-15
// relative) cannot move the step.
void expect_onset_step(int n, double t_y, double dt) {
  ASSERT_GT(n, 0) << "never yielded; analytic onset at step " << t_y / dt;
  EXPECT_LT((n - 1) * dt, t_y) << "yielded too late: step " << n << ", analytic " << t_y / dt;
  EXPECT_GE(n * dt, t_y) << "yielded too early: step " << n << ", analytic " << t_y / dt;
}

std::vector<PlasticityParams> cohesive_models() {
  return {von_mises_params(1.0e6), drucker_prager_params(19.8, 2.0e5, 0, DpConeFit::PlaneStrain),
          drucker_prager_params(19.8, 2.0e5, 0, DpConeFit::Compression),
          drucker_prager_params(30.0, 1.0e5, 10.0, DpConeFit::Compression)};
}

}  // namespace

// ---------------------------------------------------------------------------
// Constants

// phi = 19.8 deg (PHYSICS.md). Independent forms: tan/sqrt(9+12tan^2) =
// sin/(sqrt(3) sqrt(3 + sin^2)) and 3/sqrt(9+12tan^2) = sqrt(3) cos/sqrt(3 +
// sin^2); literals computed by hand to 6 digits. The two fits differ by the
// same factor for alpha and k (the cones share the Mohr–Coulomb apex
// I1 = 3 c cot phi): 1.32634, i.e. the compression cone is 32.6 % wider than
// the plane-strain one (the plane-strain one 24.6 % narrower) — PHYSICS.md's
// "~33 %" holds as the compression/plane-strain ratio.
TEST(PlasticityConstants, Phi19_8AllFits) {
  const double phi = 19.8 * kPi / 180, c = 1.0e4, s = std::sin(phi), co = std::cos(phi);
  const PlasticityParams ps = drucker_prager_params(19.8, c, 0, DpConeFit::PlaneStrain);
  const PlasticityParams cp = drucker_prager_params(19.8, c, 0, DpConeFit::Compression);
  EXPECT_EQ(ps.model, PlasticityModel::DruckerPrager);
  EXPECT_NEAR(ps.alpha_phi, s / (kSqrt3 * std::sqrt(3 + s * s)), 1e-15);
  EXPECT_NEAR(ps.k_c, c * kSqrt3 * co / std::sqrt(3 + s * s), 1e-15 * c);
  EXPECT_NEAR(ps.alpha_phi, 0.110813, 1e-6);
  EXPECT_NEAR(ps.k_c / c, 0.923388, 1e-6);
  EXPECT_NEAR(cp.alpha_phi, 0.146976, 1e-6);
  EXPECT_NEAR(cp.k_c / c, 1.224722, 1e-6);
  EXPECT_EQ(ps.alpha_psi, 0.0);
  EXPECT_EQ(cp.alpha_psi, 0.0);
  EXPECT_NEAR(cp.alpha_phi / ps.alpha_phi, 1.326336, 1e-6);
  EXPECT_NEAR(cp.k_c / ps.k_c, 1.326336, 1e-6);
  // the extension (inner 3-D) cone: 2 s/(sqrt(3)(3 + s)) and 6 c cos/(sqrt(3)(3 + s))
  const PlasticityParams ex = drucker_prager_params(19.8, c, 0, DpConeFit::Extension);
  EXPECT_NEAR(ex.alpha_phi, 2 * s / (kSqrt3 * (3 + s)), 1e-15);
  EXPECT_NEAR(ex.alpha_phi, 0.117152, 1e-6);
  EXPECT_NEAR(ex.k_c / c, 0.976209, 1e-6);
  EXPECT_NEAR(ex.alpha_phi / ps.alpha_phi, 1.057204, 1e-6);
  EXPECT_NEAR(ex.k_c / ex.alpha_phi, 3 * c * co / s, 1e-9 * c);
  // common apex I1 = k_c/alpha_phi = 3 c cot(phi)
  EXPECT_NEAR(ps.k_c / ps.alpha_phi, 3 * c * co / s, 1e-9 * c);
  EXPECT_NEAR(cp.k_c / cp.alpha_phi, 3 * c * co / s, 1e-9 * c);
  EXPECT_NEAR(dp_apex_pressure(ps), -c * co / s, 1e-9 * c);
  // alpha_psi uses the same fit, applied to psi
  EXPECT_DOUBLE_EQ(drucker_prager_params(19.8, c, 12.0, DpConeFit::PlaneStrain).alpha_psi,
                   dp_cone_alpha(12.0, DpConeFit::PlaneStrain));
  EXPECT_DOUBLE_EQ(drucker_prager_params(30.0, c, 30.0, DpConeFit::Compression).alpha_psi,
                   drucker_prager_params(30.0, c, 0.0, DpConeFit::Compression).alpha_phi);
  const PlasticityParams vm = von_mises_params(3.0e8);
  EXPECT_EQ(vm.model, PlasticityModel::VonMises);
  EXPECT_EQ(vm.yield_stress, 3.0e8);
}

// What the plane-strain fit means: in plane strain with associated flow and
// no plastic out-of-plane strain rate (eps^p_zz = dlambda (alpha + S_zz/(2
// sqrt J2)) = 0, so S_zz = -2 alpha sqrt(J2)), every state on the DP cone
// satisfies the in-plane Mohr–Coulomb criterion R = c cos(phi) - s sin(phi)
// (R the in-plane Mohr radius, s its centre, tension positive). Algebra:
// J2 = 3 m^2 + R^2 with S_zz = -2m gives R = sqrt(J2) sqrt(1 - 3 alpha^2);
// with alpha = tan/Q, k = 3c/Q, Q^2 = 9 + 12 tan^2 both sides are
// 9 (c + p tan)/(Q^2 cos). Tolerance 1e-12 relative: pure rounding.
TEST(PlasticityConstants, PlaneStrainFitIsMohrCoulombInPlaneStrain) {
  for (double phi_deg : {10.0, 19.8, 35.0}) {
    const double c = 3.0e4, phi = phi_deg * kPi / 180;
    const PlasticityParams pp = drucker_prager_params(phi_deg, c, phi_deg, DpConeFit::PlaneStrain);
    for (double p : {-0.5 * c, 0.0, 2.0 * c, 40.0 * c}) {
      for (double theta : {0.0, 0.4, 1.3}) {  // orientation of the in-plane deviator
        const double sj2 = pp.k_c + 3 * pp.alpha_phi * p;  // on the cone
        ASSERT_GT(sj2, 0);
        const double m = pp.alpha_phi * sj2;  // S_zz = -2m
        const double R = std::sqrt(sj2 * sj2 - 3 * m * m);
        Mat<2> S;
        S.m[0][0] = m + R * std::cos(theta);
        S.m[1][1] = m - R * std::cos(theta);
        S.m[0][1] = S.m[1][0] = R * std::sin(theta);
        EXPECT_NEAR(yield_function<2>(pp, S, p), 0, 1e-12 * f_scale(pp, sj2, p));
        const double sxx = -p + S.m[0][0], syy = -p + S.m[1][1], sxy = S.m[0][1];
        const double centre = 0.5 * (sxx + syy);
        const double radius = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
        EXPECT_NEAR(radius, c * std::cos(phi) - centre * std::sin(phi), 1e-12 * f_scale(pp, sj2, p))
            << "phi " << phi_deg << " p " << p;
      }
    }
  }
}

// What the two 3-D fits mean: each cone passes through one meridian of the
// Mohr–Coulomb pyramid. With sigma_1 >= sigma_2 >= sigma_3 the principal
// compressive stresses, Mohr–Coulomb reads
//   sigma_1 = sigma_3 (1 + sin phi)/(1 - sin phi) + 2 c cos(phi)/(1 - sin phi).
// Triaxial compression (sigma_2 = sigma_3, one major stress) lies on the
// compression cone, triaxial extension (sigma_1 = sigma_2, two major
// stresses) on the extension cone; uniaxial tension (the tensile strength
// 2 c cos/(1 + sin)) and equal biaxial compression are extension states. Each
// cone misses the other meridian by a finite amount (checked, so the test
// tells the fits apart). Tolerance 1e-12 relative: pure rounding.
TEST(PlasticityConstants, ThreeDFitsAreMohrCoulombOnTheirMeridians) {
  for (double phi_deg : {10.0, 19.8, 35.0}) {
    const double c = 3.0e4, phi = phi_deg * kPi / 180, s = std::sin(phi);
    const PlasticityParams comp = drucker_prager_params(phi_deg, c, 0, DpConeFit::Compression);
    const PlasticityParams ext = drucker_prager_params(phi_deg, c, 0, DpConeFit::Extension);
    // f of the principal stress state (compression positive) sig_a, sig_b, sig_b
    auto f_of = [](const PlasticityParams& pp, double sig_a, double sig_b) {
      const double p = (sig_a + 2 * sig_b) / 3;
      Mat<3> S = Mat<3>::zero();
      S.m[0][0] = -(sig_a - p);
      S.m[1][1] = S.m[2][2] = -(sig_b - p);
      return yield_function<3>(pp, S, p);
    };
    for (double sigma_3 : {-0.5 * c * std::cos(phi) / (1 + s), 0.0, 2.0 * c, 40.0 * c}) {
      const double sigma_1 = (sigma_3 * (1 + s) + 2 * c * std::cos(phi)) / (1 - s);
      const double scale = c + sigma_1;
      // triaxial compression: the major stress alone on axis a
      EXPECT_NEAR(f_of(comp, sigma_1, sigma_3), 0, 1e-12 * scale) << "phi " << phi_deg << " s3 " << sigma_3;
      EXPECT_GT(f_of(ext, sigma_1, sigma_3), 1e-3 * scale);  // the inner cone has yielded there already
      // triaxial extension: the minor stress alone on axis a
      EXPECT_NEAR(f_of(ext, sigma_3, sigma_1), 0, 1e-12 * scale) << "phi " << phi_deg << " s3 " << sigma_3;
      EXPECT_LT(f_of(comp, sigma_3, sigma_1), -1e-3 * scale);  // the outer cone has strength to spare there
    }
    // the named extension states: uniaxial tension, equal biaxial compression
    const double sigma_t = 2 * c * std::cos(phi) / (1 + s), sigma_b = 2 * c * std::cos(phi) / (1 - s);
    EXPECT_NEAR(f_of(ext, -sigma_t, 0.0), 0, 1e-12 * sigma_b);
    EXPECT_NEAR(f_of(ext, 0.0, sigma_b), 0, 1e-12 * sigma_b);
  }
}

// ---------------------------------------------------------------------------
// The stress never leaves the yield surface: a mixed path (compression,
// shear, spin, then expansion through the apex region) for every model, in
// 2-D and 3-D; f <= 1e-12 scale after every return (see f_scale), and the
// path must actually yield and (for DP) crack, so the test can fail.
template <int D>
void check_stays_inside() {
  const double phase1[3][3] = {{-2.0, 1.5, 0.3}, {0.4, -0.5, -0.7}, {0.1, 0.9, -1.0}};   // compress + shear
  const double phase2[3][3] = {{0.0, 2.0, -1.0}, {-2.0, 0.0, 0.5}, {1.0, -0.5, 0.0}};    // rigid spin
  const double phase3[3][3] = {{3.0, -1.0, 0.2}, {0.5, 2.5, 0.3}, {-0.4, 0.0, 3.0}};     // expand + shear
  std::vector<PlasticityParams> models = cohesive_models();
  models.push_back(drucker_prager_params(25.0, 5.0e4, 25.0, DpConeFit::PlaneStrain));  // associated
  for (const PlasticityParams& pp : models) {
    Element<D> el;
    el.pp = pp;
    int plastic_steps = 0, cracked = 0;
    const double dt = 1e-5;  // strain 1e-5 per step at unit rates
    for (int phase = 0; phase < 3; ++phase) {
      const Mat<D> L = block<D>(phase == 0 ? phase1 : phase == 1 ? phase2 : phase3);
      for (int n = 0; n < 3000; ++n) {
        if (el.step(L, dt)) ++plastic_steps;
        if (el.last.deps_crack > 0) ++cracked;
        ASSERT_LE(el.f(), 1e-12 * f_scale(pp, el.sj2(), el.p)) << "phase " << phase << " step " << n;
        ASSERT_GE(el.last.dlambda, 0);
        ASSERT_GE(el.last.deps_p, 0);
      }
    }
    EXPECT_GT(plastic_steps, 100) << "path never yielded: test is vacuous";
    if (pp.model == PlasticityModel::DruckerPrager) {
      EXPECT_GT(cracked, 0) << "expansion never reached the apex";
    }
  }
}
TEST(PlasticReturn, StaysOnOrInsideSurface2D) { check_stays_inside<2>(); }
TEST(PlasticReturn, StaysOnOrInsideSurface3D) { check_stays_inside<3>(); }

// ---------------------------------------------------------------------------
// Onsets.

// Confined (oedometric) compression, L = diag(-rate, 0, 0): the same in 1-D
// (uniaxial strain), 2-D (plane strain) and 3-D. With compressive strain e:
//   p = K e,  S = 2G e (-2/3, 1/3, 1/3)  =>  sqrt(J2) = 2 G e/sqrt(3).
//   von Mises: sqrt(3 J2) = 2 G e = Y               => e_y = Y/(2G)
//   DP:  2Ge/sqrt(3) - 3 alpha_phi K e - k_c = 0    => e_y = k_c/(2G/sqrt(3) - 3 alpha_phi K)
//        (needs 2G/sqrt(3) > 3 alpha_phi K: 0.533 K > 0.332 K and 0.441 K for phi = 19.8 deg;
//         the phi = 30 deg compression cone, 0.693 K, must never yield on this path)
// The onset step must bracket e_y; the last elastic step must match the
// closed-form p and sqrt(J2) (Euler is exact on this linear path up to the
// rounding of ~1e5 additions: 1e-10 relative).
template <int D>
void check_oedometric_onset() {
  for (const PlasticityParams& pp : cohesive_models()) {
    const double rate = 1.0, dt = 1.0e-7 * 1.0000003;  // de = 1e-7 per step
    const double L3[3][3] = {{-rate, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    Element<D> el;
    el.pp = pp;
    double e_y;
    if (pp.model == PlasticityModel::VonMises) e_y = pp.yield_stress / (2 * kG);
    else if (2 * kG / kSqrt3 > 3 * pp.alpha_phi * kK) e_y = pp.k_c / (2 * kG / kSqrt3 - 3 * pp.alpha_phi * kK);
    else {
      // steep cone (phi = 30 deg compression fit: 3 alpha K = 0.69 K > 0.53 K):
      // f = k_c - e (3 alpha K - 2G/sqrt(3)) only decreases, never yields
      EXPECT_EQ(run_to_onset<D>(el, block<D>(L3), dt, 100000), -1);
      EXPECT_LT(el.f(), -pp.k_c);
      continue;
    }
    ASSERT_GT(e_y, 0);
    Element<D> prev = el;
    int n = 0;
    for (n = 1; n < 1000000; ++n) {
      prev = el;
      if (el.step(block<D>(L3), dt)) break;
    }
    expect_onset_step(n, e_y / rate, dt);
    // ~1e5 Euler additions, each rounding <= 1.1e-16 relative: 1e-10 bound
    const double e_prev = (n - 1) * dt * rate;
    EXPECT_NEAR(prev.p, kK * e_prev, 1e-10 * kK * e_y);
    EXPECT_NEAR(prev.sj2(), 2 * kG * e_prev / kSqrt3, 1e-10 * kG * e_y);
    EXPECT_LT(prev.f(), 0);
    EXPECT_NEAR(el.f(), 0, 1e-12 * f_scale(pp, el.sj2(), el.p));
  }
}
TEST(PlasticOnset, Oedometric1D) { check_oedometric_onset<1>(); }
TEST(PlasticOnset, Oedometric2D) { check_oedometric_onset<2>(); }
TEST(PlasticOnset, Oedometric3D) { check_oedometric_onset<3>(); }

// Cohesionless DP (k_c = 0) under oedometric loading: the elastic ratio is
// sqrt(J2)/p = (2G e/sqrt(3))/(K e) = 2G/(sqrt(3) K) = 0.533 for nu = 0.3,
// independent of e. On the cone sqrt(J2)/p = 3 alpha_phi. So
//  * if 2G/(sqrt(3)K) > 3 alpha_phi the element yields at the FIRST step and
//    then stays at sqrt(J2)/p = 3 alpha_phi (p keeps growing as K e since
//    alpha_psi = 0);
//  * otherwise it never yields and keeps sqrt(J2)/p = 2G/(sqrt(3)K).
// phi = 19.8 deg: 3 alpha = 0.332 (plane strain) and 0.441 (compression)
// both yield; phi = 40 deg compression: 3 alpha = 0.945 never yields.
template <int D>
void check_oedometric_cohesionless() {
  const double ratio_el = 2 * kG / (kSqrt3 * kK);
  struct Case { double phi; DpConeFit fit; bool yields; };
  for (const Case cs : {Case{19.8, DpConeFit::PlaneStrain, true}, Case{19.8, DpConeFit::Compression, true},
                        Case{40.0, DpConeFit::Compression, false}}) {
    const PlasticityParams pp = drucker_prager_params(cs.phi, 0.0, 0.0, cs.fit);
    ASSERT_EQ(cs.yields, ratio_el > 3 * pp.alpha_phi);
    const double L3[3][3] = {{-1.0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    Element<D> el;
    el.pp = pp;
    for (int n = 1; n <= 1000; ++n) {
      const bool plastic = el.step(block<D>(L3), 1e-6);
      ASSERT_EQ(plastic, cs.yields) << "step " << n;
      EXPECT_NEAR(el.p, kK * n * 1e-6, 1e-12 * el.p);  // p unchanged by the return (no dilatancy)
      EXPECT_NEAR(el.sj2() / el.p, cs.yields ? 3 * pp.alpha_phi : ratio_el, 1e-12);
    }
  }
}
TEST(PlasticOnset, OedometricCohesionless2D) { check_oedometric_cohesionless<2>(); }
TEST(PlasticOnset, OedometricCohesionless3D) { check_oedometric_cohesionless<3>(); }

// Simple shear, L_xy = gamma_dot only, at a fixed pressure p0 (tr L = 0).
// With the Jaumann rate the hypoelastic solution is S_xy = G sin(gamma),
// S_xx = -S_yy = G (1 - cos gamma), S_zz = 0 (check: dS_xx/dgamma = S_xy,
// dS_xy/dgamma = G - S_xx), so sqrt(J2) = 2 G sin(gamma/2) exactly.
//   von Mises: 2 sqrt(3) G sin(gamma_y/2) = Y
//   DP:        2 G sin(gamma_y/2) = 3 alpha_phi p0 + k_c
// Explicit Euler on the rotation part amplifies the (G - S_xx, S_xy) circle
// by sqrt(1 + dgamma^2) per step: a relative error in sqrt(J2) of about
// gamma dgamma/2 ~ 1e-10 here, far below one step (dgamma/gamma ~ 1e-4),
// so the bracket of expect_onset_step applies unchanged.
template <int D>
void check_simple_shear_onset() {
  const double p0 = 1.0e6, gdot = 1.0, dt = 1.0e-7 * 1.0000007;
  for (const PlasticityParams& pp : cohesive_models()) {
    const double target = pp.model == PlasticityModel::VonMises ? pp.yield_stress / (2 * kSqrt3 * kG)
                                                                : (3 * pp.alpha_phi * p0 + pp.k_c) / (2 * kG);
    const double gamma_y = 2 * std::asin(target);
    const double L3[3][3] = {{0, gdot, 0}, {0, 0, 0}, {0, 0, 0}};
    Element<D> el;
    el.pp = pp;
    el.p = p0;
    const int n = run_to_onset<D>(el, block<D>(L3), dt, 1000000);
    expect_onset_step(n, gamma_y / gdot, dt);
    if (pp.alpha_psi == 0) {
      EXPECT_EQ(el.p, p0);  // isochoric and no dilatancy: p untouched
    } else {
      EXPECT_GT(el.p, p0);  // the first plastic step dilates
    }
  }
}
TEST(PlasticOnset, SimpleShear2D) { check_simple_shear_onset<2>(); }
TEST(PlasticOnset, SimpleShear3D) { check_simple_shear_onset<3>(); }

// Uniaxial stress in 3-D: L = diag(-rate, nu rate, nu rate) keeps
// sigma_yy = sigma_zz = 0 (p = K(1-2nu)e, S_yy = 2G(1+nu)e/3, and
// K(1-2nu) = 2G(1+nu)/3), so sigma_xx = -E e. Onsets:
//   von Mises:  |sigma| = Y
//   DP:         sigma_c/sqrt(3) - alpha_phi sigma_c = k_c  => sigma_c = k_c/(1/sqrt(3) - alpha_phi)
// and for the compression cone sigma_c must equal the Mohr–Coulomb uniaxial
// compressive strength 2 c cos(phi)/(1 - sin(phi)) (the cone passes through
// the compressive meridian).
// Plane-strain "uniaxial" in 2-D: sigma_yy = 0 with eps_zz = 0 needs
// L = diag(-rate, rate nu/(1-nu)); then sigma_xx = -E e/(1-nu^2),
// sigma_zz = nu sigma_xx, sqrt(J2) = |sigma| sqrt((1 - nu + nu^2)/3),
// I1 = (1+nu) sigma:
//   von Mises:  |sigma| sqrt(1 - nu + nu^2) = Y
//   DP:         |sigma| = k_c/(sqrt((1-nu+nu^2)/3) - alpha_phi (1+nu))
template <int D>
void check_uniaxial_stress_onset() {
  const double rate = 1.0, dt = 1.0e-7 * 1.0000011;
  for (const PlasticityParams& pp : cohesive_models()) {
    double L3[3][3] = {{-rate, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    double modulus, sigma_y;  // |sigma_xx| = modulus e ; onset |sigma_xx|
    const double w = std::sqrt(1 - kNu + kNu * kNu);
    if (D == 3) {
      L3[1][1] = L3[2][2] = kNu * rate;
      modulus = kE;
      sigma_y = pp.model == PlasticityModel::VonMises ? pp.yield_stress : pp.k_c / (1 / kSqrt3 - pp.alpha_phi);
    } else {
      L3[1][1] = kNu / (1 - kNu) * rate;
      modulus = kE / (1 - kNu * kNu);
      sigma_y = pp.model == PlasticityModel::VonMises ? pp.yield_stress / w
                                                      : pp.k_c / (w / kSqrt3 - pp.alpha_phi * (1 + kNu));
    }
    Element<D> el;
    el.pp = pp;
    Element<D> prev = el;
    int n;
    for (n = 1; n < 1000000; ++n) {
      prev = el;
      if (el.step(block<D>(L3), dt)) break;
    }
    expect_onset_step(n, sigma_y / (modulus * rate), dt);
    // the path really is uniaxial (sigma_yy = 0) and sigma_xx = -modulus e
    const double e_prev = (n - 1) * dt * rate;
    EXPECT_NEAR(-prev.p + prev.S.m[1][1], 0, 1e-12 * sigma_y);
    EXPECT_NEAR(-prev.p + prev.S.m[0][0], -modulus * e_prev, 1e-12 * sigma_y);
    if (D == 3 && pp.model == PlasticityModel::DruckerPrager && pp.alpha_psi == 0 &&
        std::fabs(pp.alpha_phi - dp_cone_alpha(19.8, DpConeFit::Compression)) < 1e-15) {
      const double phi = 19.8 * kPi / 180;
      EXPECT_NEAR(sigma_y, 2 * 2.0e5 * std::cos(phi) / (1 - std::sin(phi)), 1e-9 * sigma_y);
    }
  }
}
TEST(PlasticOnset, UniaxialStress3D) { check_uniaxial_stress_onset<3>(); }
TEST(PlasticOnset, PlaneStrainUniaxialStress2D) { check_uniaxial_stress_onset<2>(); }

// ---------------------------------------------------------------------------
// Tension cracking: purely hydrostatic expansion (L = rate I) of a cohesive
// DP element carrying an initial deviator. Beyond the apex the state must be
// exactly the apex, p = -k_c/(3 alpha_phi), S = 0 (tolerance 1e-14 relative:
// p is assigned from the formula, S scaled by cap = 0 up to rounding of
// k_c - 3 alpha p). The first cracking step must bracket the elastic time at
// which p reaches the apex, p(t) = p0 - K D rate t (the shear return before
// it leaves p unchanged).
template <int D>
void check_apex() {
  for (DpConeFit fit : {DpConeFit::PlaneStrain, DpConeFit::Compression, DpConeFit::Extension}) {
    for (double psi : {0.0, 10.0}) {
      const PlasticityParams pp = drucker_prager_params(19.8, 2.0e5, psi, fit);
      const double pa = dp_apex_pressure(pp);
      ASSERT_NEAR(pa, -2.0e5 / std::tan(19.8 * kPi / 180), 1e-6);
      Element<D> el;
      el.pp = pp;
      el.p = 1.0e5;
      el.S.m[0][0] = 4.0e4;
      el.S.m[0][D - 1] += 2.0e4;
      el.S.m[D - 1][0] += 2.0e4;
      double L3[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      const double dt = 1.0e-7 * 1.0000013;
      int first_crack = -1;
      for (int n = 1; n <= 20000; ++n) {
        const double p_before = el.p;
        el.step(block<D>(L3), dt);
        if (el.last.deps_crack > 0 && first_crack < 0) {
          first_crack = n;
          // deps_crack = (p_apex - p_trial)/K, p_trial = p_before - K D rate dt
          EXPECT_NEAR(el.last.deps_crack, (pa - (p_before - kK * D * dt)) / kK, 1e-9 * D * dt);
        }
        ASSERT_LE(el.f(), 1e-12 * f_scale(pp, el.sj2(), el.p));
      }
      // without dilatancy the shear return keeps p, so cracking starts when
      // the elastic p reaches the apex; with it p was raised on the way
      if (psi == 0) {
        expect_onset_step(first_crack, (1.0e5 - pa) / (kK * D), dt);
      } else {
        EXPECT_GT(first_crack, 0);
      }
      if (D == 3 || psi == 0) {
        EXPECT_NEAR(el.p, pa, 1e-14 * std::fabs(pa));
        for (int i = 0; i < D; ++i)
          for (int j = 0; j < D; ++j) EXPECT_LE(std::fabs(el.S.m[i][j]), 1e-14 * std::fabs(pa));
      } else {
        // plane strain: in-plane isotropic expansion has eps_zz = 0, so it is
        // not hydrostatic in 3-D (dev = (1/3, 1/3, -2/3) rate); each step adds
        // sqrt(J2) ~ 2G dt rate/sqrt(3) = 21 Pa which the dilatant return
        // turns into p = apex + 3 K alpha_psi dlambda: a few Pa above the apex.
        EXPECT_GT(el.p, pa);
        EXPECT_LT(el.p - pa, 1e-4 * std::fabs(pa));
        EXPECT_LT(el.sj2(), 1e-4 * std::fabs(pa));
      }
    }
  }
  // direct call: a state far beyond the apex with a deviator
  const PlasticityParams pp = drucker_prager_params(30.0, 1.0e5, 0.0, DpConeFit::Compression);
  Mat<D> S = Mat<D>::zero();
  S.m[0][0] = 3.0e5;
  const double p_tr = 5 * dp_apex_pressure(pp);
  const PlasticReturn<D> r = plastic_return<D>(pp, S, p_tr, kG, kK);
  EXPECT_EQ(r.p, dp_apex_pressure(pp));
  EXPECT_EQ(deviatoric_j2(r.S), 0.0);
  EXPECT_NEAR(r.deps_crack, (r.p - p_tr) / kK, 1e-15);
  EXPECT_EQ(r.deps_v, 0.0);
  // shear part removed entirely: dlambda = sqrt(J2)/G, deps_p = dlambda/sqrt(3)
  EXPECT_NEAR(r.dlambda, std::sqrt(deviatoric_j2(S)) / kG, 1e-15);
  EXPECT_NEAR(r.deps_p, r.dlambda / kSqrt3, 1e-15);
}
TEST(PlasticReturn, HydrostaticTensionGoesToApex2D) { check_apex<2>(); }
TEST(PlasticReturn, HydrostaticTensionGoesToApex3D) { check_apex<3>(); }

// ---------------------------------------------------------------------------
// A rigid spin of a yielded state keeps it on the surface with J2 and p
// unchanged. The state is brought to yield by oedometric compression plus
// shear, then L = W (antisymmetric) for one radian. Explicit Euler inflates
// |S| by (1 + (2 w dt)^2)^(1/2) per step; the return pins it back, so J2 must
// stay at its yielded value to 1e-12 relative (rounding) and p exactly (tr W
// = 0). The direction must follow S(t) = Q S0 Q^T to first order in dt:
// Euler inflates only the part of S that does not commute with W while the
// return scales all of S, a distortion of ~(w dt)^2 per step, w^2 t dt = 1e-5
// after the turn; tolerance 1e-4 |S| (a wrong rotation sense would be off by
// O(|S|)).
template <int D>
Mat<D> rotation_about(double t) {
  Mat<D> Q = Mat<D>::identity();
  if constexpr (D == 2) {
    Q.m[0][0] = std::cos(t); Q.m[0][1] = -std::sin(t);
    Q.m[1][0] = std::sin(t); Q.m[1][1] = std::cos(t);
  } else if constexpr (D == 3) {
    const double n[3] = {1 / std::sqrt(14.0), 2 / std::sqrt(14.0), 3 / std::sqrt(14.0)};
    const double c = std::cos(t), s = std::sin(t);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) Q.m[i][j] = (i == j ? c : 0) + (1 - c) * n[i] * n[j];
    Q.m[0][1] -= s * n[2]; Q.m[0][2] += s * n[1];
    Q.m[1][0] += s * n[2]; Q.m[1][2] -= s * n[0];
    Q.m[2][0] -= s * n[1]; Q.m[2][1] += s * n[0];
  }
  return Q;
}
template <int D>
void check_rigid_spin() {
  for (const PlasticityParams& pp : cohesive_models()) {
    Element<D> el;
    el.pp = pp;
    // shear-dominated loading under some compression (yields for every model)
    const double load[3][3] = {{-0.2, 1.0, 0.0}, {0.0, 0.0, 0.3}, {0.0, 0.0, 0.0}};
    bool yielded = false;
    for (int n = 0; n < 1000000 && !yielded; ++n) yielded = el.step(block<D>(load), 1e-7);
    ASSERT_TRUE(yielded);
    const Mat<D> S0 = el.S;
    const double j2_0 = deviatoric_j2(S0), p_0 = el.p;
    const double omega = 1.0;
    // W = dQ/dt Q^T at t = 0 (central difference, exact to 1e-12 for h = 1e-6)
    const double h = 1e-6;
    const Mat<D> Wc = (0.5 / h) * (rotation_about<D>(omega * h) - rotation_about<D>(-omega * h));
    const Mat<D> W = 0.5 * (Wc - transpose(Wc));  // exactly antisymmetric: tr(eps_dot) = 0 exactly
    const int N = 100000;
    const double dt = 1.0 / N;
    // With dilatancy the Euler inflation of |S| (relative 2 (w dt)^2 per step)
    // is returned with a little plastic dilatation, dp ~ 3 K alpha_psi/G
    // * 2 (w dt)^2 sqrt(J2) per step: ~1e-5 relative after N steps, so the
    // dilatant model gets 1e-4; the others must hold J2 and p to rounding.
    const double tol = pp.alpha_psi > 0 ? 1e-4 : 1e-12;
    int returns = 0;
    for (int n = 0; n < N; ++n) {
      if (el.step(W, dt)) ++returns;
      ASSERT_NEAR(deviatoric_j2(el.S), j2_0, tol * j2_0) << "step " << n;
      ASSERT_NEAR(el.p, p_0, tol * std::fabs(p_0));
      ASSERT_NEAR(el.f(), 0, 1e-12 * f_scale(pp, el.sj2(), el.p));
    }
    EXPECT_GT(returns, N / 2) << "spin never pushed the state outside: the test would be vacuous";
    const Mat<D> Q = rotation_about<D>(omega * 1.0);
    const Mat<D> S_exact = Q * S0 * transpose(Q);
    const double Snorm = std::sqrt(2 * j2_0);
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) EXPECT_NEAR(el.S.m[i][j], S_exact.m[i][j], 1e-4 * Snorm);
  }
}
TEST(PlasticReturn, RigidSpinKeepsYieldedState2D) { check_rigid_spin<2>(); }
TEST(PlasticReturn, RigidSpinKeepsYieldedState3D) { check_rigid_spin<3>(); }

// ---------------------------------------------------------------------------
// alpha_psi = 0: the return is Bui's stress scaling at fixed p, bit for bit
// (EXPECT_DOUBLE_EQ: 4 ulps), on random trial states outside the cone.
// alpha_psi > 0: the consistent return lands on f = 0, with
//   dlambda = f_tr/(G + 9 K alpha_phi alpha_psi),
//   sqrt(J2) = sqrt(J2_tr) - G dlambda (radial: S parallel to S_tr),
//   p = p_tr + 3 K alpha_psi dlambda = p_tr + K deps_v, deps_v = 3 alpha_psi dlambda,
//   deps_p = dlambda/sqrt(3),
// and the plastic strain C^-1 : (sigma_tr - sigma) equals dlambda dg/dsigma
// = dlambda (alpha_psi I + S/(2 sqrt J2)) component by component.
// Tolerances 1e-12 relative (a handful of roundings).
template <int D>
void check_dilatancy() {
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> U(-1, 1);
  for (DpConeFit fit : {DpConeFit::PlaneStrain, DpConeFit::Compression, DpConeFit::Extension}) {
    const PlasticityParams p0 = drucker_prager_params(25.0, 5.0e4, 0.0, fit);
    int tested0 = 0, testedpsi = 0;
    for (int k = 0; k < 200; ++k) {
      Mat<D> S;
      for (int i = 0; i < D; ++i)
        for (int j = i; j < D; ++j) S.m[i][j] = S.m[j][i] = 2.0e6 * U(gen);
      const double p = 1.0e6 * (1 + U(gen));  // 0 .. 2 MPa, always inside the apex (-107 kPa)
      const double f_tr = yield_function<D>(p0, S, p);
      if (f_tr <= 0) continue;
      // alpha_psi = 0
      const PlasticReturn<D> r0 = plastic_return<D>(p0, S, p, kG, kK);
      const double r = (-p0.alpha_phi * (-3 * p) + p0.k_c) / std::sqrt(deviatoric_j2(S));
      for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j) EXPECT_DOUBLE_EQ(r0.S.m[i][j], r * S.m[i][j]);
      EXPECT_EQ(r0.p, p);
      EXPECT_EQ(r0.deps_v, 0.0);
      EXPECT_NEAR(r0.dlambda, f_tr / kG, 1e-12 * f_tr / kG);
      ++tested0;
      // alpha_psi > 0 (psi = 10 deg and associated psi = phi)
      for (double psi : {10.0, 25.0}) {
        PlasticityParams pp = p0;
        pp.alpha_psi = dp_cone_alpha(psi, fit);
        const PlasticReturn<D> rr = plastic_return<D>(pp, S, p, kG, kK);
        const double dl = f_tr / (kG + 9 * kK * pp.alpha_phi * pp.alpha_psi);
        const double sj2_tr = std::sqrt(deviatoric_j2(S)), sj2 = std::sqrt(deviatoric_j2(rr.S));
        EXPECT_NEAR(yield_function<D>(pp, rr.S, rr.p), 0, 1e-12 * f_scale(pp, sj2_tr, p));
        EXPECT_NEAR(rr.dlambda, dl, 1e-12 * dl);
        EXPECT_NEAR(sj2, sj2_tr - kG * dl, 1e-12 * sj2_tr);
        EXPECT_NEAR(rr.deps_v, 3 * pp.alpha_psi * rr.dlambda, 1e-15 * rr.deps_v);
        EXPECT_NEAR(rr.p, p + kK * rr.deps_v, 1e-12 * std::fabs(rr.p));
        EXPECT_GT(rr.p, p);  // dilatancy raises the confining pressure
        EXPECT_NEAR(rr.deps_p, rr.dlambda / kSqrt3, 1e-12 * rr.deps_p);
        EXPECT_EQ(rr.deps_crack, 0.0);
        // flow rule: C^-1:(sigma_tr - sigma) = dl (alpha_psi I + S/(2 sqrt J2))
        for (int i = 0; i < D; ++i)
          for (int j = 0; j < D; ++j) {
            // dsigma = sigma_tr - sigma = (S_tr - S) - (p_tr - p) I;
            // C^-1 : dsigma = dev(dsigma)/(2G) + tr(dsigma)/(9K) I
            const double deps = (S.m[i][j] - rr.S.m[i][j]) / (2 * kG) + (i == j ? -3 * (p - rr.p) / (9 * kK) : 0.0);
            const double expect = dl * ((i == j ? pp.alpha_psi : 0.0) + rr.S.m[i][j] / (2 * sj2));
            EXPECT_NEAR(deps, expect, 1e-12 * dl);
          }
        ++testedpsi;
      }
    }
    EXPECT_GT(tested0, 50);
    EXPECT_GT(testedpsi, 100);
  }
  // Dilatancy after tension cracking: trial far beyond the apex with a
  // deviator; cracking moves p to the apex, the dilatant return then pushes
  // p into compression and keeps sqrt(J2) >= 0 on the cone.
  PlasticityParams pp = drucker_prager_params(30.0, 1.0e5, 30.0, DpConeFit::Compression);
  Mat<D> S = Mat<D>::zero();
  S.m[0][D - 1] = S.m[D - 1][0] = 5.0e5;
  if (D == 1) S.m[0][0] = 5.0e5;
  const double p_tr = 3 * dp_apex_pressure(pp);
  const PlasticReturn<D> r = plastic_return<D>(pp, S, p_tr, kG, kK);
  EXPECT_GT(r.deps_crack, 0);
  EXPECT_GT(r.deps_v, 0);
  EXPECT_GT(r.p, dp_apex_pressure(pp));
  EXPECT_NEAR(r.p, p_tr + kK * (r.deps_v + r.deps_crack), 1e-12 * std::fabs(p_tr));
  EXPECT_GE(deviatoric_j2(r.S), 0);
  EXPECT_NEAR(yield_function<D>(pp, r.S, r.p), 0, 1e-12 * f_scale(pp, 5.0e5, r.p));
}
TEST(PlasticReturn, DilatancyConsistent2D) { check_dilatancy<2>(); }
TEST(PlasticReturn, DilatancyConsistent3D) { check_dilatancy<3>(); }

// Driven isochoric simple shear with dilatancy: once plastic, the pressure
// must rise every step by exactly K deps_v (the element cannot expand), the
// state stays on the cone, and without dilatancy p stays fixed.
template <int D>
void check_dilatant_shear() {
  for (double psi : {0.0, 15.0}) {
    Element<D> el;
    el.pp = drucker_prager_params(30.0, 1.0e4, psi, DpConeFit::PlaneStrain);
    el.p = 1.0e5;
    const double L3[3][3] = {{0, 1.0, 0}, {0, 0, 0}, {0, 0, 0}};
    double sum_dv = 0, p_last = el.p;
    int plastic = 0;
    for (int n = 0; n < 20000; ++n) {
      if (el.step(block<D>(L3), 1e-6)) {
        ++plastic;
        if (psi > 0) {
          EXPECT_GT(el.p, p_last);
        }
      }
      sum_dv += el.last.deps_v;
      p_last = el.p;
      ASSERT_LE(el.f(), 1e-12 * f_scale(el.pp, el.sj2(), el.p));
    }
    EXPECT_GT(plastic, 1000);
    EXPECT_NEAR(el.p, 1.0e5 + kK * sum_dv, 1e-9 * el.p);
    if (psi == 0) {
      EXPECT_EQ(el.p, 1.0e5);
    } else {
      EXPECT_GT(el.p, 1.5e5);
    }
  }
}
TEST(PlasticReturn, DilatantIsochoricShear2D) { check_dilatant_shear<2>(); }
TEST(PlasticReturn, DilatantIsochoricShear3D) { check_dilatant_shear<3>(); }

// ---------------------------------------------------------------------------
// Equivalent plastic strain, von Mises, pure shear L = diag(rate, -rate, 0):
// e = rate t, S = 2G e diag(1, -1, 0) (S_zz = 0 also in plane strain), so
// sqrt(3 J2) = 2 sqrt(3) G e and yield at e_y = Y/(2 sqrt(3) G). Beyond it
// (perfect plasticity) all further deviatoric strain is plastic,
// e^p = (e - e_y) diag(1, -1, 0), and
//   eps_p = sqrt(2/3 e^p:e^p) = (2/sqrt(3)) (e - e_y).
// The path is radial (S keeps its direction), so the radial return is exact
// even in the step containing the onset: the sum of deps_p must match to
// rounding (1e-10 relative over 2e5 steps). dlambda equals deps_p for von
// Mises.
template <int D>
void check_vm_plastic_strain() {
  const double Y = 1.0e6, rate = 1.0, dt = 1.0e-8;
  const double e_y = Y / (2 * kSqrt3 * kG);
  Element<D> el;
  el.pp = von_mises_params(Y);
  const double L3[3][3] = {{rate, 0, 0}, {0, -rate, 0}, {0, 0, 0}};
  double eps_p = 0, lam = 0;
  const int N = 2 * static_cast<int>(e_y / (rate * dt));
  for (int n = 0; n < N; ++n) {
    el.step(block<D>(L3), dt);
    eps_p += el.last.deps_p;
    lam += el.last.dlambda;
    ASSERT_LE(el.f(), 1e-12 * Y);
  }
  const double e = N * dt * rate;
  ASSERT_GT(e, e_y);
  const double expect = 2 / kSqrt3 * (e - e_y);
  EXPECT_NEAR(eps_p, expect, 1e-10 * expect);
  EXPECT_NEAR(lam, expect, 1e-10 * expect);
  EXPECT_NEAR(std::sqrt(3 * deviatoric_j2(el.S)), Y, 1e-12 * Y);
  EXPECT_NEAR(el.S.m[0][0], Y / kSqrt3, 1e-12 * Y);  // S = (Y/sqrt3) diag(1,-1,0)
  EXPECT_EQ(el.p, 0.0);
}
TEST(PlasticStrain, VonMisesPureShear2D) { check_vm_plastic_strain<2>(); }
TEST(PlasticStrain, VonMisesPureShear3D) { check_vm_plastic_strain<3>(); }

// deps_p uses the FULL 3-D deviator: a 2-D deviator with S_xx = S_yy = s
// (implied S_zz = -2s) removed entirely has J2 = 3 s^2 and
// deps_p = sqrt(J2/3)/G = s/G; the in-plane components alone would give
// sqrt(2/3 (2 s^2))/(2G) = 0.577 s/G.
TEST(PlasticStrain, UsesImpliedOutOfPlaneComponents) {
  const double s = 1.0e5;
  Mat<2> S = Mat<2>::zero();
  S.m[0][0] = S.m[1][1] = s;
  PlasticityParams pp = von_mises_params(0.0);  // removes everything
  const PlasticReturn<2> r = plastic_return<2>(pp, S, 0.0, kG, kK);
  EXPECT_EQ(deviatoric_j2(r.S), 0.0);
  EXPECT_NEAR(r.deps_p, s / kG, 1e-15 * s / kG);
}

// No model: nothing changes, the yield function says "inside".
TEST(PlasticReturn, NoneIsIdentity) {
  PlasticityParams pp;
  Mat<3> S = Mat<3>::zero();
  S.m[0][1] = S.m[1][0] = 1e12;
  const PlasticReturn<3> r = plastic_return<3>(pp, S, -1e12, kG, kK);
  EXPECT_TRUE(r.S == S);
  EXPECT_EQ(r.p, -1e12);
  EXPECT_EQ(r.dlambda, 0.0);
  EXPECT_EQ(r.deps_p, 0.0);
  EXPECT_EQ(r.deps_v, 0.0);
  EXPECT_LT(yield_function<3>(pp, S, -1e12), 0);
}

// ---------------------------------------------------------------------------
// Collins, Melosh & Ivanov 2004: strength of intact and damaged rock
// (issue #49 item 1). Parameters: the basalt of an iSALE-format input
// (SALEc-2D-public example/sup_material.inp: Y_0 = 20 MPa, mu_i = 1.4,
// Y_M = 3.5 GPa, Y_d0 = 10 kPa, mu_d = 0.6); the checks are of the formulas,
// any rock would do.

namespace {
PlasticityParams collins_basalt(double melt_energy = 0) {
  return collins_params(2.0e7, 1.4, 3.5e9, 1.0e4, 0.6, melt_energy);
}
// Lundborg's curve written out independently of plasticity.hpp.
double lundborg(double Y0, double mu, double YM, double p) { return Y0 + mu * p * (YM - Y0) / (YM - Y0 + mu * p); }
}  // namespace

TEST(Collins, IntactAndDamagedCurvesTheirLimitsAndTheInterpolationInD) {
  const PlasticityParams pp = collins_basalt();
  // p = 0: the cohesions
  EXPECT_DOUBLE_EQ(collins_yield_strength(pp, 0, 0, 0), 2.0e7);
  EXPECT_DOUBLE_EQ(collins_yield_strength(pp, 0, 1, 0), 1.0e4);
  for (double p : {1e5, 1e7, 3e8, 1e9, 5e9, 3e10}) {
    const double yi = lundborg(2.0e7, 1.4, 3.5e9, p);
    const double yd = std::min(1.0e4 + 0.6 * p, yi);
    EXPECT_NEAR(collins_yield_strength(pp, p, 0, 0), yi, 1e-12 * yi) << p;
    EXPECT_NEAR(collins_yield_strength(pp, p, 1, 0), yd, 1e-12 * yi) << p;
    for (double D : {0.25, 0.5, 0.9})  // linear in D between the two branches
      EXPECT_NEAR(collins_yield_strength(pp, p, D, 0), (1 - D) * yi + D * yd, 1e-12 * yi) << p << " " << D;
    EXPECT_LE(yd, yi);
  }
  // p -> infinity: Y_i -> Y_M and the damaged branch meets the intact one
  const double big = 1e16;
  EXPECT_NEAR(collins_yield_strength(pp, big, 0, 0), 3.5e9, 1e-5 * 3.5e9);
  EXPECT_DOUBLE_EQ(collins_yield_strength(pp, big, 1, 0), collins_yield_strength(pp, big, 0, 0));
  // monotone in p, continuous through p = 0
  double last = -1;
  for (double p = -5e7; p < 1e10; p += 1e6) {
    const double y = collins_yield_strength(pp, p, 0.3, 0);
    EXPECT_GE(y, last) << p;
    last = y;
  }
  EXPECT_NEAR(collins_yield_strength(pp, -1.0, 0, 0), 2.0e7, 2.0);
  // tension: each curve reaches 0 at its own zero and stays 0 (no negative strength)
  const double p_i0 = -2.0e7 * (3.5e9 - 2.0e7) / (1.4 * 3.5e9), p_d0 = -1.0e4 / 0.6;
  EXPECT_NEAR(collins_yield_strength(pp, 0.999 * p_i0, 0, 0), lundborg(2.0e7, 1.4, 3.5e9, 0.999 * p_i0), 1e-3);
  EXPECT_GT(collins_yield_strength(pp, 0.999 * p_i0, 0, 0), 0);
  EXPECT_EQ(collins_yield_strength(pp, 1.001 * p_i0, 0, 0), 0);
  EXPECT_EQ(collins_yield_strength(pp, -1e12, 0, 0), 0);
  EXPECT_GT(collins_yield_strength(pp, 0.999 * p_d0, 1, 0), 0);
  EXPECT_EQ(collins_yield_strength(pp, 1.001 * p_d0, 1, 0), 0);
  // without friction the intact strength is Y_0 at every pressure
  EXPECT_EQ(collins_yield_strength(collins_params(1e6, 0, 1e9, 0, 0, 0), 5e8, 0, 0), 1e6);
}

TEST(Collins, ThermalSofteningTowardsTheMeltEnergy) {
  // miluphcuda's COLLINS_PLASTICITY_INCLUDE_MELT_ENERGY form: Y_i (1 - u/u_melt)
  const PlasticityParams pp = collins_basalt(3.4e6);
  const double p = 2e8, yi = lundborg(2.0e7, 1.4, 3.5e9, p);
  EXPECT_DOUBLE_EQ(collins_yield_strength(pp, p, 0, 0), yi);
  EXPECT_NEAR(collins_yield_strength(pp, p, 0, 0.85e6), 0.75 * yi, 1e-9 * yi);
  EXPECT_EQ(collins_yield_strength(pp, p, 0, 3.4e6), 0);
  EXPECT_EQ(collins_yield_strength(pp, p, 0.5, 5e6), 0);
  // the damaged branch is capped by the softened intact one
  EXPECT_LE(collins_yield_strength(pp, 1e10, 1, 3.0e6), collins_yield_strength(pp, 1e10, 0, 3.0e6));
}

// A homogeneous element sheared at fixed pressure (simple shear, tr L = 0;
// sqrt(J2) = 2 G sin(gamma/2), see check_simple_shear_onset) yields at
// sqrt(J2) = Y(p0, D) of its damage, intact and damaged, and then flows on
// that surface with p unchanged.
template <int D>
void check_collins_shear(double p0, double damage) {
  const double G = 2.27e10, K = 2.67e10, gdot = 1.0, dt = 1.0e-7 * 1.0000007;
  const PlasticityParams pp = collins_basalt();
  const double Y = collins_yield_strength(pp, p0, damage, 0);
  const double gamma_y = 2 * std::asin(Y / (2 * G));
  const double L3[3][3] = {{0, gdot, 0}, {0, 0, 0}, {0, 0, 0}};
  Element<D> el;
  el.pp = pp, el.G = G, el.K = K, el.p = p0, el.damage = damage;
  const int n = run_to_onset<D>(el, block<D>(L3), dt, 10000000);
  expect_onset_step(n, gamma_y / gdot, dt);
  for (int k = 0; k < 200; ++k) el.step(block<D>(L3), dt);
  EXPECT_NEAR(el.sj2(), Y, 1e-12 * Y) << "p0 " << p0 << " D " << damage;
  EXPECT_EQ(el.p, p0);
  EXPECT_GT(el.last.deps_p, 0);
  EXPECT_EQ(el.last.deps_v, 0);  // no plastic volume change
}
TEST(Collins, ShearedElementYieldsOnTheIntactDamagedAndMixedSurfaces2D) {
  for (double p0 : {0.0, 1e8, 1e9})
    for (double D : {0.0, 0.5, 1.0}) check_collins_shear<2>(p0, D);
}
TEST(Collins, ShearedElementYieldsOnTheIntactDamagedAndMixedSurfaces3D) {
  for (double p0 : {0.0, 1e8, 1e9})
    for (double D : {0.0, 0.5, 1.0}) check_collins_shear<3>(p0, D);
}
