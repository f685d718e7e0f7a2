// Combinations of material models that the scene parser accepts, each checked
// where the physics meets (issue #49 item 4), on a few particles driven by the
// loop bodies of drivers/particle_rates.hpp (no neighbour search):
//  (a) extrapolated walls take the deviator that ACTS in their neighbours —
//      (1 - D) S of a damaged material, S/alpha of a porous one — not the
//      stored (intact) S: a wall next to fully damaged rock carries no shear;
//  (b) a porous Drucker-Prager material: the equation of state, the crush
//      curve, d alpha/dt and the end-of-step return to the envelope all see
//      the same (elastic) density rho exp(eps_v);
//  (c) Drucker-Prager with damage: the return works on the intact pressure,
//      and the apex tension it returns acts as (1 - D) of itself.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "rubble/drivers/particle_rates.hpp"

using namespace rubble;

namespace {

// A 2-D store of n particles with every field these loop bodies read; the
// optional fields are switched on by the test (nullptr = the feature is off).
struct Store {
  std::size_t n;
  std::vector<Real> m, u, rho, h, p, cs, damage_root, alpha, eps_v, eps_p;
  std::vector<std::int32_t> material_id, boundary;
  std::vector<Vec<2>> x, v;
  std::vector<Mat<2>> S;
  explicit Store(std::size_t count)
      : n(count), m(count, 1), u(count, 0), rho(count, 1), h(count, 1), p(count, 0), cs(count, 1),
        damage_root(count, 0), alpha(count, 1), eps_v(count, 0), eps_p(count, 0), material_id(count, 0),
        boundary(count, kFreeParticle), x(count, Vec<2>::zero()), v(count, Vec<2>::zero()), S(count, Mat<2>::zero()) {}
  StoreView<2> view(bool damage, bool porous, bool inelastic) {
    StoreView<2> s;
    s.n = n;
    s.m = m.data(), s.u = u.data(), s.rho = rho.data(), s.h = h.data(), s.p = p.data(), s.cs = cs.data();
    s.material_id = material_id.data(), s.boundary = boundary.data(), s.x = x.data(), s.v = v.data();
    s.S = S.data(), s.eps_p = eps_p.data();
    if (damage) s.damage_root = damage_root.data();
    if (porous) s.alpha = alpha.data();
    if (inelastic) s.eps_v = eps_v.data();
    return s;
  }
};

MaterialParams murnaghan_solid(Real rho0, Real K, Real mu) {
  MaterialParams mp{};
  mp.eos.kind = EosKind::Murnaghan;
  mp.eos.murnaghan = MurnaghanParams{rho0, K, Real(1)};
  mp.shear_modulus = mu;
  return mp;
}

Mat<2> shear(Real s) {
  Mat<2> S = Mat<2>::zero();
  S.m[0][0] = s, S.m[1][1] = -s, S.m[0][1] = S.m[1][0] = Real(0.3) * s;
  return S;
}

// Runs the wall extrapolation of particle 0 over free particles 1..n-1.
void extrapolate_wall(const RhsContext<2>& c) {
  wall_extrapolation_particle<2>(c, 0, [&](auto&& visit) {
    for (std::uint32_t b = 1; b < c.s.n; ++b) visit(b);
  });
}

}  // namespace

TEST(MaterialCombinations, ExtrapolatedWallsTakeTheActingDeviatorOfDamagedRock) {
  MaterialParams mat = murnaghan_solid(1, 1, Real(0.5));
  mat.damage.enabled = true;
  mat.damage.deviatoric = true;
  Store st(3);
  st.boundary[0] = kBoundaryExtrapolated;
  st.x[1] = Vec<2>{Real(0.1), 0}, st.x[2] = Vec<2>{0, Real(0.2)};
  st.S[1] = st.S[2] = shear(Real(0.04));
  RhsContext<2> c;
  c.s = st.view(true, false, false);
  c.mat = &mat;
  // intact neighbours: the wall carries their deviator
  extrapolate_wall(c);
  EXPECT_NEAR(st.S[0].m[0][0], 0.04, 1e-15);
  // half-damaged (D = delta^2 = 0.5) and fully damaged neighbours: the wall's
  // acting deviator is theirs, (1 - D) S
  for (Real D : {Real(0.5), Real(1)}) {
    st.damage_root[1] = st.damage_root[2] = std::sqrt(D);
    extrapolate_wall(c);
    const Mat<2> acting = deviatoric_factor_particle<2>(c, 0) * st.S[0];
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) EXPECT_NEAR(acting.m[i][j], (1 - D) * shear(Real(0.04)).m[i][j], 1e-15) << D;
  }
}

TEST(MaterialCombinations, ExtrapolatedWallsTakeTheActingDeviatorOfPorousSolids) {
  // porous neighbours at alpha = 1.25 act with S/1.25; the wall, whose own
  // alpha is 1.1, must act with the same
  MaterialParams mat = murnaghan_solid(2700, Real(2e10), Real(1e10));
  mat.porosity.enabled = true;
  mat.porosity.alpha_e = Real(1.3), mat.porosity.p_e = Real(1e8), mat.porosity.p_s = Real(1e9);
  Store st(3);
  st.boundary[0] = kBoundaryExtrapolated;
  st.x[1] = Vec<2>{Real(0.1), 0}, st.x[2] = Vec<2>{0, Real(0.2)};
  st.S[1] = st.S[2] = shear(Real(4e6));
  st.alpha[0] = Real(1.1), st.alpha[1] = st.alpha[2] = Real(1.25);
  RhsContext<2> c;
  c.s = st.view(false, true, false);
  c.mat = &mat;
  extrapolate_wall(c);
  const Mat<2> acting = deviatoric_factor_particle<2>(c, 0) * st.S[0];
  EXPECT_NEAR(acting.m[0][1], shear(Real(4e6)).m[0][1] / 1.25, 1e-9);
  EXPECT_NEAR(acting.m[0][0], shear(Real(4e6)).m[0][0] / 1.25, 1e-9);
}

TEST(MaterialCombinations, PorousDruckerPragerSeesOneElasticDensity) {
  // a porous Drucker-Prager particle that has opened (eps_v = 0.02): its
  // pressure, d alpha/dt and the end-of-step alpha are those of the elastic
  // density rho exp(eps_v) — computed here from the porosity functions
  // directly — not of rho
  MaterialParams mat = murnaghan_solid(2700, Real(2e10), Real(1e10));
  mat.porosity.enabled = true;
  mat.porosity.alpha_e = Real(1.3), mat.porosity.p_e = Real(1e8), mat.porosity.p_s = Real(1e9);
  mat.plasticity = drucker_prager_params(30, 1e5, 0, DpConeFit::Compression);
  Store st(1);
  st.eps_v[0] = Real(0.02);
  st.alpha[0] = Real(1.25);
  st.rho[0] = Real(2700) / Real(1.25) * Real(1.02) * std::exp(Real(-0.02));  // matrix 2 % compressed elastically
  RhsContext<2> c;
  c.s = st.view(false, true, true);
  c.mat = &mat;
  const Real rho_el = st.rho[0] * std::exp(st.eps_v[0]);
  eos_particle<2>(c, 0);
  EXPECT_NEAR(st.p[0], porous_eos_evaluate(mat.eos, mat.porosity, rho_el, 0, st.alpha[0]).p, 1e-6);
  EXPECT_GT(st.p[0], mat.porosity.p_e);  // on the crush branch: the rate is not zero
  const Real drhodt = Real(10), dudt = 0;
  const Real rate = porosity_rate_particle<2>(c, 0, drhodt, dudt);
  EXPECT_LT(rate, 0);
  EXPECT_NEAR(rate,
              porosity_dalpha_dt(mat.eos, mat.porosity, rho_el, 0, st.alpha[0], drhodt * std::exp(st.eps_v[0]), 0),
              1e-12 * std::fabs(rate));
  // end of step: back onto the envelope at the elastic density
  std::vector<Real> alpha_start{st.alpha[0]};
  porosity_end_step_particle<2>(c, 0, alpha_start.data());
  EXPECT_EQ(st.alpha[0], porous_alpha_on_loading_curve(mat.eos, mat.porosity, rho_el, 0, Real(1.25)));
  EXPECT_LT(st.alpha[0], Real(1.25));  // the state at rho alone would have been below p_e, untouched
  EXPECT_EQ(porous_alpha_on_loading_curve(mat.eos, mat.porosity, st.rho[0], 0, Real(1.25)), Real(1.25));
}

TEST(MaterialCombinations, DruckerPragerWithDamageReturnsTheApexTensionDamaged) {
  // hydrostatic tension beyond the apex of a half-damaged (D = 0.5) granular
  // solid: the return moves the INTACT pressure to the apex; the acting
  // pressure is then (1 - D) p_apex, and the opening deps_crack is measured
  // from the intact pressure
  MaterialParams mat = murnaghan_solid(2000, Real(1e8), Real(5e7));
  mat.damage.enabled = true;
  mat.plasticity = drucker_prager_params(30, 1e4, 0, DpConeFit::Compression);
  const Real apex = dp_apex_pressure(mat.plasticity);
  Store st(1);
  st.rho[0] = Real(2000) * Real(0.999);  // p = K (rho/rho0 - 1) = -1e5 Pa, beyond the apex
  st.damage_root[0] = std::sqrt(Real(0.5));
  RhsContext<2> c;
  c.s = st.view(true, false, true);
  c.mat = &mat;
  eos_particle<2>(c, 0);
  const Real p_intact = Real(-1e5);
  ASSERT_NEAR(st.p[0], 0.5 * p_intact, 1e-6);  // acting
  ASSERT_LT(p_intact, apex);
  plastic_return_particle<2>(c, 0, true);
  EXPECT_NEAR(st.p[0], 0.5 * apex, 1e-9);
  const Real K = st.rho[0] * st.cs[0] * st.cs[0];
  EXPECT_NEAR(st.eps_v[0], (apex - p_intact) / K, 1e-12);
  // undamaged: the apex itself
  st.damage_root[0] = 0, st.eps_v[0] = 0;
  eos_particle<2>(c, 0);
  plastic_return_particle<2>(c, 0, true);
  EXPECT_NEAR(st.p[0], apex, 1e-9);
}
