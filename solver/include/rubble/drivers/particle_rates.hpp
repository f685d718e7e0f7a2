#pragma once
// The loop bodies of the right-hand side, one particle at a time, shared by
// the CPU (OpenMP) and CUDA drivers (DESIGN.md principles 1 and 6). Each
// function works on particle `a` of a StoreView and sums over its
// neighbours through `each`, a callable that calls f(b) for every candidate
// neighbour b != a: the CPU passes the neighbour lists, the GPU its cell
// list. A candidate may lie beyond the support; every pair function below
// treats such a pair as absent (its terms are zero), so the two backends
// see the same pairs. The formulas themselves live in rubble/physics/.
#include <cstdint>
#include <limits>

#include "rubble/core/box.hpp"
#include "rubble/core/hd.hpp"
#include "rubble/drivers/material_params.hpp"
#include "rubble/drivers/state_check.hpp"
#include "rubble/particles/store_view.hpp"
#include "rubble/physics/artificial_stress.hpp"
#include "rubble/physics/damage.hpp"
#include "rubble/physics/hydro.hpp"
#include "rubble/physics/jaumann_rate.hpp"
#include "rubble/physics/kernel_gradient_correction.hpp"
#include "rubble/physics/kernels.hpp"
#include "rubble/physics/particle_shifting.hpp"
#include "rubble/physics/plasticity.hpp"
#include "rubble/physics/porosity.hpp"
#include "rubble/physics/smoothing_length.hpp"
#include "rubble/physics/solid.hpp"
#include "rubble/physics/stress_diffusion.hpp"
#include "rubble/physics/timestep.hpp"
#include "rubble/physics/wall_extrapolation.hpp"
#include "rubble/physics/wall_friction.hpp"
#include "rubble/physics/xsph.hpp"

namespace rubble {

// What is fixed over one evaluation of the right-hand side.
// The relative tolerance |dh|/h of the smoothing-length iteration for
// simulation.h_tolerance (0: the precision's default, 1e-10 in double and
// 1e-5 in single precision; a value below 100 units of rounding of the
// precision is raised to that, where the iteration could never settle).
inline Real h_iteration_tolerance(double scene_value) {
  const double floor = 100 * double(std::numeric_limits<Real>::epsilon());
  if (scene_value <= 0) return sizeof(Real) == 8 ? Real(1e-10) : Real(1e-5);
  return Real(scene_value > floor ? scene_value : floor);
}

template <int D>
struct RhsContext {
  StoreView<D> s;
  const MaterialParams* mat = nullptr;  // indexed by material_id
  Box<D> domain;
  KernelType kernel = KernelType::CubicSpline;
  Real hfact = 0;
  bool summation = false;          // summation density (grad-h terms) or continuity
  bool geometric_force = false;    // continuity: the geometric pressure force (physics/hydro.hpp)
  bool kernel_correction = false;  // solids: corrected velocity gradient
  bool stress_diffusion = false;   // solids: a material diffuses its deviator (stress_diffusion.hpp)
  Mat<D>* art_R = nullptr;         // solids with artificial stress: R_a (scratch)
  // solids: each particle's solid_inverses, computed once per evaluation
  // (solid_inverses_particle); nullptr: computed at every pair instead
  const SolidInverses* solid_inv = nullptr;
  Real xsph_epsilon = 0;
  Real courant = 0, force_factor = 0;
  Real density_step_fraction = 0;  // continuity density: the step's largest |d rho|/rho (0: none)
  // summation density: |dh|/h of the Newton iteration (h_iteration_tolerance)
  Real h_tolerance = h_iteration_tolerance(0);
  Vec<D> body_force = Vec<D>::zero();  // uniform external acceleration (simulation.gravity)
  bool has_body_force = false;
  // Solids, leapfrog with simulation.stress_update = "staggered": the step
  // over which pass 1's rates advance S and rho before pass 2
  // (staggered_update_particle); 0 in every other evaluation.
  Real stagger_dt = 0;
  // ... its scratch (n each, set when stagger_dt > 0): pass 1's mass-weighted
  // velocity gradient sum_b m_b (v_b - v_a) (x) g_a (g_a the gradient a's
  // stress acts along: K_a gbar with the correction), the correction that
  // makes du/dt the step's trapezoidal work (staggered_update_particle), and,
  // with artificial stress, the clumping weight chi_a (R_a is taken from the
  // advanced stress)
  Mat<D>* stagger_Lm = nullptr;
  Real* stagger_du = nullptr;
  Real* as_chi = nullptr;
};

// Largest inelastic volume strain a Drucker-Prager particle remembers
// (plastic_return_particle): ln 2, a particle whose volume has doubled. Far
// beyond any granular packing (random loose packing of spheres is ~15 %
// looser than the densest random one), such a particle has lost contact with
// its neighbours (an ejected grain); it is then stress-free until its density
// recovers instead of carrying the whole opening as memory. Without the cap
// an ejected particle of the a = 4 column collapse reached eps_v = 1.28 at
// 0.28 rho0, where a slight re-compression pushed with sigma/rho^2 ~13 times
// a normal particle's and the run blew up (with particle shifting).
constexpr Real kMaxInelasticVolume = Real(0.69314718055994531);

// Largest fractional change of the distention alpha in one step (PHYSICS.md
// §1 "rate limits on the evolved quantities"; §4 "~1e-2"): dt <= this *
// alpha / |d alpha/dt| (dt_limit_particle).
constexpr Real kAlphaStepFraction = Real(1e-2);

// Condition limit of the kernel-gradient correction matrix
// (kernel_gradient_correction.hpp): below it the identity is used.
constexpr Real kCorrectionMinDet = Real(1e-3);

// ---- walls ---------------------------------------------------------------

// Whether neighbour b of free particle a is a sliding-wall particle (a
// boundary particle with a wall normal: wall_slip = "free_slip" or
// "coulomb"). A no-slip wall particle in the same run has a zero normal.
template <int D>
RUBBLE_HD_INLINE bool sliding_wall_pair(const StoreView<D>& s, std::uint32_t a, std::uint32_t b) {
  return s.wall_normal && s.boundary[b] && !s.boundary[a] && norm2(s.wall_normal[b]) > Real(0);
}

// The velocity particle a sees for neighbour b. A sliding-wall particle
// (sliding_wall_pair) takes a's own tangential velocity,
// v_b' = v_a - ((v_a - v_b).n) n, so that only the approach along the
// normal acts (no wall friction in the velocity gradient, the viscosity or
// XSPH; a Coulomb wall's friction is a force of its own, wall_friction.hpp);
// any other neighbour is seen as it moves.
template <int D>
RUBBLE_HD_INLINE Vec<D> seen_velocity(const StoreView<D>& s, std::uint32_t a, std::uint32_t b) {
  if (!sliding_wall_pair<D>(s, a, b)) return s.v[b];
  const Vec<D> n = s.wall_normal[b];
  return s.v[a] - dot(s.v[a] - s.v[b], n) * n;
}

// The pair acceleration f that free particle a receives from neighbour b:
// all of it from any neighbour but a sliding-wall particle, whose part is
// collected in w instead and applied after the sum (wall_reaction_particle).
template <int D>
RUBBLE_HD_INLINE Vec<D> wall_filtered_force(const StoreView<D>& s, std::uint32_t a, std::uint32_t b, const Vec<D>& f,
                                            WallContact<D>& w) {
  if (!sliding_wall_pair<D>(s, a, b)) return f;
  wall_contact_add<D>(w, f, s.wall_normal[b], s.wall_friction ? s.wall_friction[b] : Real(0), s.v[b]);
  return Vec<D>::zero();
}

// The frequency of particle a's wall-friction spring: c_a / hM_a
// (wall_friction.hpp; 1/hM_a for a particle without sound speed).
template <int D>
RUBBLE_HD_INLINE Real wall_spring_frequency(const RhsContext<D>& c, std::uint32_t a) {
  const Real hM = monaghan_h<D>(c.kernel, c.s.h[a]);
  return (c.s.cs[a] > Real(0) ? c.s.cs[a] : Real(1)) / hM;
}

// The sliding walls' push and Coulomb friction on free particle a from its
// contact sums (wall_friction.hpp); records the walls' grip on a for the
// end of the step.
template <int D>
RUBBLE_HD_INLINE WallReaction<D> wall_reaction_particle(const RhsContext<D>& c, std::uint32_t a,
                                                        const WallContact<D>& w) {
  const StoreView<D>& s = c.s;
  WallReaction<D> r;
  if (w.count > 0) {
    const Vec<D> d = s.wall_anchor ? c.domain.separation(s.x[a], s.wall_anchor[a]) : Vec<D>::zero();
    r = wall_reaction<D>(w, s.v[a], d, wall_spring_frequency<D>(c, a));
  }
  if (s.wall_grip) s.wall_grip[a] = r.grip;
  return r;
}

// End of an accepted step, Coulomb walls: particle a's friction anchor
// follows its slip, and is its position off the walls (wall_friction.hpp).
template <int D>
RUBBLE_HD_INLINE void wall_anchor_end_step_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  if (!s.wall_anchor || s.boundary[a]) return;
  const Vec<D> d = wall_anchor_update<D>(c.domain.separation(s.x[a], s.wall_anchor[a]), s.wall_grip[a],
                                         wall_spring_frequency<D>(c, a));
  s.wall_anchor[a] = c.domain.wrap(s.x[a] - d);
}

// Whether particle a's state (rho, u, S, alpha, plastic strain) follows
// the material's evolution equations: free particles and evolving boundary
// particles; frozen and extrapolated boundary particles do not.
template <int D>
RUBBLE_HD_INLINE bool state_evolves(const StoreView<D>& s, std::uint32_t a) {
  return !s.boundary || s.boundary[a] == kFreeParticle || s.boundary[a] == kBoundaryEvolving;
}

// ---- density -------------------------------------------------------------

struct DensitySums {
  Real rho, dwdh;  // sum_b m_b W_ab(h), sum_b m_b dW_ab/dh (self included)
};

template <int D, class Each>
RUBBLE_HD_INLINE DensitySums density_sums(const RhsContext<D>& c, std::uint32_t a, Real h, Each&& each) {
  const StoreView<D>& s = c.s;
  const KernelAt<D> K = kernel_at<D>(c.kernel, h);
  const KernelWDwdh self = kernel_w_dwdh<D>(K, Real(0));
  DensitySums out{s.m[a] * self.w, s.m[a] * self.dwdh};
  const Real h2 = h * h;
  each([&](std::uint32_t b) {
    // the lists hold neighbours a little beyond the support (the search
    // radius' skin): those stop here, before the square root
    const Real r2 = norm2(c.domain.separation(s.x[a], s.x[b]));
    if (r2 >= h2) return;
    const KernelWDwdh w = kernel_w_dwdh<D>(K, std::sqrt(r2));
    out.rho += s.m[b] * w.w;
    out.dwdh += s.m[b] * w.dwdh;
  });
  return out;
}

// Summation density with h and rho solved together by Newton's method
// (smoothing_length.hpp), starting from the stored h, until one step moves
// h by at most c.h_tolerance of itself. Writes h, rho and
// Omega of particle a and returns true, or, when h grows past the search
// radius (the neighbours listed do not cover the new support), writes only
// the grown h and returns false: the driver then rebuilds with a larger radius.
template <int D, class Each>
RUBBLE_HD_INLINE bool summation_density_particle(const RhsContext<D>& c, std::uint32_t a, Real search_radius,
                                                 Each&& each) {
  const StoreView<D>& s = c.s;
  constexpr int kMaxNewton = 50;
  const Real tol = c.h_tolerance;
  Real h = s.h[a] < search_radius ? s.h[a] : search_radius;
  for (int it = 0; it < kMaxNewton; ++it) {
    const DensitySums d = density_sums<D>(c, a, h, each);
    const Real h_new = newton_h_step<D>(h, d.rho, d.dwdh, c.hfact, s.m[a]);
    if (std::fabs(h_new - h) <= tol * h) {
      // converged: h and the sums at h agree to tol (Newton's next step
      // would move h by less), so no further pass over the neighbours
      s.h[a] = h;
      s.rho[a] = d.rho;
      s.omega[a] = grad_h_omega<D>(h, d.rho, d.dwdh);
      return true;
    }
    h = h_new;
    if (h > search_radius) break;  // needs more neighbours than listed
  }
  s.h[a] = h;
  if (h > search_radius) return false;
  const DensitySums d = density_sums<D>(c, a, h, each);  // no convergence in kMaxNewton steps: the last h
  s.rho[a] = d.rho;
  s.omega[a] = grad_h_omega<D>(h, d.rho, d.dwdh);
  return true;
}

// Continuity density: h follows the evolved density.
template <int D>
RUBBLE_HD_INLINE void h_from_density_particle(const RhsContext<D>& c, std::uint32_t a) {
  c.s.h[a] = h_from_density<D>(c.hfact, c.s.m[a], c.s.rho[a]);
}

// The elastic density of particle a: rho exp(eps_v) for a Drucker-Prager
// material, whose inelastic volume change (cracking, dilatancy) eps_v does
// not load its equation of state; rho otherwise. What the EOS, and for a
// porous material the crush curve, d alpha/dt and the end-of-step return,
// see (one density for all of them; issue #49 item 4b).
template <int D>
RUBBLE_HD_INLINE Real elastic_density_particle(const RhsContext<D>& c, std::uint32_t a) {
  return c.s.eps_v ? c.s.rho[a] * std::exp(c.s.eps_v[a]) : c.s.rho[a];
}

// Pressure and c_s^2 of particle a's intact material from its equation of
// state at its elastic density; for a porous material
// p = p_s(alpha rho, u)/alpha (physics/porosity.hpp).
template <int D>
RUBBLE_HD_INLINE EosState intact_eos_particle(const RhsContext<D>& c, std::uint32_t a) {
  const MaterialParams& mat = c.mat[c.s.material_id[a]];
  const Real rho = elastic_density_particle<D>(c, a);
  if (mat.porosity.enabled) {
    const PorousEosState e = porous_eos_evaluate(mat.eos, mat.porosity, rho, c.s.u[a], c.s.alpha[a]);
    return EosState{e.p, e.c2};
  }
  return eos_evaluate(mat.eos, rho, c.s.u[a]);
}

// Damage D = delta^d of particle a (0 for materials without damage).
template <int D>
RUBBLE_HD_INLINE Real damage_particle(const RhsContext<D>& c, std::uint32_t a) {
  return c.s.damage_root && c.mat[c.s.material_id[a]].damage.enabled ? damage_from_root<D>(c.s.damage_root[a])
                                                                     : Real(0);
}

// Pressure and sound speed: the intact material's, with a damaged
// material's tension carried by its intact fraction (physics/damage.hpp).
template <int D>
RUBBLE_HD_INLINE void eos_particle(const RhsContext<D>& c, std::uint32_t a) {
  if (c.s.boundary && c.s.boundary[a] == kBoundaryExtrapolated) return;  // p, c_s from wall_extrapolation_particle
  const EosState e = intact_eos_particle<D>(c, a);
  c.s.p[a] = c.s.damage_root ? damaged_pressure(e.p, damage_particle<D>(c, a)) : e.p;
  c.s.cs[a] = std::sqrt(e.c2 > Real(0) ? e.c2 : Real(0));
}

// ---- porosity and plasticity (per particle, no neighbours) ----------------

// The factor between the evolved deviatoric stress S and that of the intact
// material: porous solids scale it with alpha (porosity.hpp's
// porous_deviatoric_factor); 1 otherwise. The plastic return works on it.
template <int D>
RUBBLE_HD_INLINE Real intact_deviatoric_factor_particle(const RhsContext<D>& c, std::uint32_t a) {
  const MaterialParams& mat = c.mat[c.s.material_id[a]];
  return mat.porosity.enabled ? porous_deviatoric_factor(mat.porosity, c.s.alpha[a]) : Real(1);
}

// The factor between the evolved deviatoric stress S and the one that acts
// in the momentum equation: the intact factor, times 1 - D for a damaged
// material whose damage acts on the deviator (physics/damage.hpp).
template <int D>
RUBBLE_HD_INLINE Real deviatoric_factor_particle(const RhsContext<D>& c, std::uint32_t a) {
  const Real f = intact_deviatoric_factor_particle<D>(c, a);
  if (!c.s.damage_root) return f;
  const DamageParams& dp = c.mat[c.s.material_id[a]].damage;
  return dp.enabled ? f * damaged_deviatoric_factor(dp, damage_from_root<D>(c.s.damage_root[a])) : f;
}

// Extrapolated wall particle a (kBoundaryExtrapolated): p, S, rho and c_s
// from its free neighbours' acting stress (physics/wall_extrapolation.hpp), with the body
// force as the wall's hydrostatic gradient (self-gravity is not included).
// Free and other boundary particles are left alone, so it may run over all
// particles at once: it reads only free particles and writes only walls.
// A wall particle without free neighbours keeps its last state.
template <int D, class Each>
RUBBLE_HD_INLINE void wall_extrapolation_particle(const RhsContext<D>& c, std::uint32_t a, Each&& each) {
  const StoreView<D>& s = c.s;
  if (!s.boundary || s.boundary[a] != kBoundaryExtrapolated) return;
  WallSums<D> sum;
  each([&](std::uint32_t b) {
    if (s.boundary[b] != kFreeParticle) return;
    const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
    const Real w = kernel_w<D>(c.kernel, norm(dx), s.h[a]);
    if (w <= Real(0)) return;
    // the deviator that ACTS at b (1/alpha porous, 1 - D damaged), as p_b is the acting pressure
    wall_sums_add<D>(sum, w, dx, s.p[b], s.rho[b], s.cs[b],
                     s.S ? deviatoric_factor_particle<D>(c, b) * s.S[b] : Mat<D>::zero());
  });
  if (sum.w <= Real(0)) return;
  const WallState st = wall_state<D>(sum, c.body_force);
  s.p[a] = st.p;
  s.rho[a] = st.rho;
  s.cs[a] = st.cs;
  // stored so that the wall's own factor turns it back into the extrapolated
  // acting deviator (a wall's factor is > 0: walls take no damage)
  if (s.S) {
    const Real f = deviatoric_factor_particle<D>(c, a);
    s.S[a] = (f > Real(0) ? Real(1) / f : Real(1)) * wall_deviator<D>(sum);
  }
}

// d alpha/dt of particle a from the chain rule, given its d rho/dt and
// du/dt (porosity.hpp: porosity_dalpha_dt); 0 for non-porous materials and
// frozen boundary particles. Called by the rate passes as soon as the pair
// sums are done: d rho/dt is the SPH continuity rate, which summation
// density computes too (hydro.hpp), so porous fluids may use either form.
// At the elastic density rho exp(eps_v) (elastic_density_particle), whose
// rate within a step is exp(eps_v) d rho/dt (eps_v changes only at the end
// of a step).
template <int D>
RUBBLE_HD_INLINE Real porosity_rate_particle(const RhsContext<D>& c, std::uint32_t a, Real drhodt, Real dudt) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  if (!mat.porosity.enabled || !state_evolves<D>(s, a)) return Real(0);
  const Real scale = s.eps_v ? std::exp(s.eps_v[a]) : Real(1);
  return porosity_dalpha_dt(mat.eos, mat.porosity, scale * s.rho[a], s.u[a], s.alpha[a], scale * drhodt, dudt);
}

// Once a's d rho/dt and du/dt are complete: d alpha/dt, and for a porous
// solid J08's factor on its deviatoric stress rate (porosity.hpp:
// porous_deviatoric_rate_factor; pass 1 computed dS/dt, pass 2 the rates it
// needs). Both backends' loops end with this.
template <int D>
RUBBLE_HD_INLINE void porosity_rates_particle(const RhsContext<D>& c, std::uint32_t a, Real drhodt, Real dudt) {
  const StoreView<D>& s = c.s;
  s.dalphadt[a] = porosity_rate_particle<D>(c, a, drhodt, dudt);
  const PorosityParams& pp = c.mat[s.material_id[a]].porosity;
  if (s.dSdt && pp.enabled && pp.deviatoric_rate_factor && state_evolves<D>(s, a))
    s.dSdt[a] = porous_deviatoric_rate_factor(s.rho[a], s.alpha[a], drhodt, s.dalphadt[a]) * s.dSdt[a];
}

// The plastic return mapping of particle a's deviatoric stress onto its
// material's yield surface (plasticity.hpp: plastic_return), at the
// pressure of the last eos_particle. The return acts on the intact stress
// -p I + f S (f the porous factor): for a damaged material in tension the
// intact pressure is recovered from the acting (1 - D) p, and the returned
// pressure — a Drucker-Prager apex, a dilatant increase — is stored as the
// acting one again, so damage still carries only (1 - D) of the returned
// tension (issue #49 item 4c; before, the return saw the damaged pressure
// and left the undamaged apex tension acting). With `accumulate` (once per accepted
// step, at its end) the equivalent plastic strain grows by the return's
// increment; the returns inside an evaluation (stage states the integrator
// discards) only keep the stress on the surface.
//
// The inelastic volume change persists (Drucker-Prager materials store
// eps_v): at the end of each step eps_v grows by the return's deps_v
// (dilatant flow, psi > 0) and deps_crack (the opening of tension cracking,
// (p_apex - p_trial)/K), and the EOS then sees the elastic density
// rho exp(eps_v), whose pressure is the returned p to first order, up to
// eps_v = kMaxInelasticVolume. So a
// granular material that opened in tension sits at the apex and is
// compressed again as soon as it closes, as in Bui et al. 2008, whose
// stress-rate form resets the stress to the apex (the mean stress has no
// memory of the opening). Without it, a dilated particle has p(rho) below
// the apex until its density recovers: a layer of stress-free particles
// that do not repel each other (clumping at a granular flow's front).
template <int D>
RUBBLE_HD_INLINE void plastic_return_particle(const RhsContext<D>& c, std::uint32_t a, bool accumulate) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  if (mat.plasticity.model == PlasticityModel::None || !state_evolves<D>(s, a)) return;
  const Real f = intact_deviatoric_factor_particle<D>(c, a);
  const Real K = s.rho[a] * s.cs[a] * s.cs[a];
  const Real dmg = damage_particle<D>(c, a);
  Real p = s.p[a];  // acting; the intact one differs only in tension
  if (dmg > Real(0) && p <= Real(0) && mat.plasticity.model != PlasticityModel::VonMises)
    p = dmg < Real(1) ? p / (Real(1) - dmg) : intact_eos_particle<D>(c, a).p;
  const PlasticReturn<D> r = plastic_return<D>(mat.plasticity, f * s.S[a], p, f * mat.shear_modulus, K, dmg, s.u[a]);
  s.S[a] = (Real(1) / f) * r.S;
  s.p[a] = dmg > Real(0) ? damaged_pressure(r.p, dmg) : r.p;
  if (accumulate) {
    s.eps_p[a] += r.deps_p;
    if (s.eps_v) s.eps_v[a] = std::fmin(s.eps_v[a] + r.deps_v + r.deps_crack, kMaxInelasticVolume);
  }
}

// End of an accepted step: alpha is returned to the loading envelope from
// its value at the start of the step, alpha = alpha_env(rho, u; <= bound)
// (porosity.hpp: porous_alpha_on_loading_curve) with bound = alpha_start,
// or alpha_e for a state on the virgin elastic curve (porosity_return_bound).
// On loading this puts the state exactly on the envelope at the step's
// final (rho, u), whether the chain-rule stages overshot it (a step across
// the kink at p_e, a shock, p beyond p_s) or fell short of it (an explicit
// stage just below the envelope sees d alpha/dt = 0, which alone would make
// the scheme first order); on unloading a virgin elastic state goes back up
// the reversible elastic curve, while a crushed one, or one below the
// envelope, keeps alpha_start. So a crushed alpha is the min over the path
// of alpha_env and never rises; the chain rule supplies the stage values,
// the step control and the rates.
template <int D>
RUBBLE_HD_INLINE void porosity_end_step_particle(const RhsContext<D>& c, std::uint32_t a, const Real* alpha_start) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  if (!mat.porosity.enabled || !state_evolves<D>(s, a)) return;
  s.alpha[a] = porous_alpha_on_loading_curve(mat.eos, mat.porosity, elastic_density_particle<D>(c, a), s.u[a],
                                             porosity_return_bound(mat.eos, mat.porosity, alpha_start[a]));
}

// ---- tensile damage (per particle, no neighbours; physics/damage.hpp) ----

// What the growth law needs of particle a: the local tensile strain of the
// stress that acts, over (1 - D) E (damage.hpp: damage_local_strain), the
// flaws active at it, the crack speed and the crack-growth length.
struct DamageDrive {
  Real n_act;   // flaws active at the current strain
  Real c_g;     // crack growth speed [m/s]
  Real radius;  // R_s [m]
};

// `delta` is the damage root the strain is taken at (the particle's own in
// the rates; see damage_end_step_particle for the end of a step).
template <int D>
RUBBLE_HD_INLINE DamageDrive damage_drive_particle(const RhsContext<D>& c, std::uint32_t a, Real delta) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  const EosState e = intact_eos_particle<D>(c, a);
  const Real f = intact_deviatoric_factor_particle<D>(c, a);
  const Real mu = f * mat.shear_modulus;
  const Real c2 = e.c2 > Real(0) ? e.c2 : Real(0);
  const Real E = youngs_modulus(s.rho[a] * c2, mu);
  const Real dmg = damage_from_root<D>(delta);
  const Real eps = damage_local_strain<D>(f * damaged_deviatoric_factor(mat.damage, dmg) * s.S[a],
                                          damaged_pressure(e.p, dmg), dmg, E);
  const Real n_act = active_flaws(eps, s.flaw_count[a], s.flaw_eps_min[a], s.flaw_eps_max[a], mat.damage.weibull_m);
  const Real cl = elastic_signal_speed(std::sqrt(c2), mu, s.rho[a]);
  const Real radius =
      mat.damage.crack_length == CrackLength::KernelSupport ? s.h[a] : particle_radius<D>(s.m[a] / s.rho[a]);
  return DamageDrive{n_act, mat.damage.crack_speed * cl, radius};
}

// d delta/dt of particle a (0 for materials without damage, walls, and
// particles out of tension or at their cap).
template <int D>
RUBBLE_HD_INLINE Real damage_rate_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  if (!c.mat[s.material_id[a]].damage.enabled || !state_evolves<D>(s, a) || s.flaw_count[a] <= 0) return 0;
  const DamageDrive d = damage_drive_particle<D>(c, a, s.damage_root[a]);
  return damage_root_rate<D>(s.damage_root[a], d.n_act, s.flaws_active[a], s.flaw_count[a], d.c_g, d.radius,
                             c.mat[s.material_id[a]].damage.capped);
}

// The damage limit on particle a's step (damage.hpp: damage_dt_limit) from
// its rate and its room below the cap of the flaws active now.
template <int D>
RUBBLE_HD_INLINE Real damage_dt_limit_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  const Real rate = s.ddamage_root_dt[a];
  if (!(rate > Real(0))) return Real(1e30);
  const DamageDrive d = damage_drive_particle<D>(c, a, s.damage_root[a]);
  const Real n_max = d.n_act > s.flaws_active[a] ? d.n_act : s.flaws_active[a];
  const Real cap = damage_root_cap<D>(n_max, s.flaw_count[a], c.mat[s.material_id[a]].damage.capped);
  return damage_dt_limit(rate, kDamageStepChange, cap - s.damage_root[a]);
}

// End of an accepted step: the flaws active at the final state join the
// particle's record (n_active never falls), and delta is held to its cap
// (n_active/n_flaws)^(1/d) when the material is capped — the growth of the
// step's last stage may have passed it.
// The final state's strain is taken at the damage the record admitted
// before this step, min(delta, cap(n_active)), not at the grown delta: the
// strain falls as D grows under a compression (damage_local_strain), so
// counting at the grown delta would drop flaws the step's stages found
// active and clip delta back to where it started — a particle that then
// never grows while its rate (> 0) holds the time step (the Nakamura rung
// stalled at 5e-9 s steps that way).
template <int D>
RUBBLE_HD_INLINE void damage_end_step_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  if (!c.mat[s.material_id[a]].damage.enabled || !state_evolves<D>(s, a) || s.flaw_count[a] <= 0) return;
  const Real admitted = damage_root_cap<D>(s.flaws_active[a], s.flaw_count[a], c.mat[s.material_id[a]].damage.capped);
  const DamageDrive d =
      damage_drive_particle<D>(c, a, s.damage_root[a] < admitted ? s.damage_root[a] : admitted);
  const Real n_max = d.n_act > s.flaws_active[a] ? d.n_act : s.flaws_active[a];
  s.flaws_active[a] = n_max;
  const Real cap = damage_root_cap<D>(n_max, s.flaw_count[a], c.mat[s.material_id[a]].damage.capped);
  if (s.damage_root[a] > cap) s.damage_root[a] = cap;
}

// The uniform external acceleration (simulation.gravity) on free particles.
template <int D>
RUBBLE_HD_INLINE void body_force_particle(const RhsContext<D>& c, std::uint32_t a) {
  if (c.s.boundary && c.s.boundary[a]) return;
  c.s.dvdt[a] += c.body_force;
}

// ---- feature set Hydro ---------------------------------------------------

template <int D>
RUBBLE_HD_INLINE HydroParticle<D> hydro_particle(const RhsContext<D>& c, std::uint32_t i) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[i]];
  const ViscosityParams av = mat.av_switch.enabled ? switched_viscosity(mat.av, s.av_alpha[i]) : mat.av;
  return HydroParticle<D>{s.x[i], s.v[i], s.m[i],  s.rho[i], s.p[i], s.u[i], s.h[i],
                          c.summation ? s.omega[i] : Real(1), s.cs[i], av, mat.alpha_u};
}

// d alpha/dt of particle a's viscosity switch (physics/viscosity_switch.hpp)
// from its continuity rate drho/dt = -rho div v (the force loop's sum);
// 0 for materials without the switch and particles whose state does not
// evolve (frozen walls keep their alpha).
template <int D>
RUBBLE_HD_INLINE Real viscosity_switch_rate_particle(const RhsContext<D>& c, std::uint32_t a, Real drhodt) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  if (!mat.av_switch.enabled || !state_evolves<D>(s, a)) return 0;
  const Real compression = s.rho[a] > Real(0) ? drhodt / s.rho[a] : Real(0);  // -div v
  const Real hM = monaghan_h<D>(c.kernel, s.h[a]);
  return viscosity_switch_rate(s.av_alpha[a], compression, hM, s.cs[a], mat.av.alpha, mat.av_switch);
}

// End of an accepted step: the switch's alpha back within [alpha_min,
// alpha_max] (an explicit step may overshoot a bound).
template <int D>
RUBBLE_HD_INLINE void viscosity_switch_end_step_particle(const RhsContext<D>& c, std::uint32_t a) {
  const MaterialParams& mat = c.mat[c.s.material_id[a]];
  if (mat.av_switch.enabled) c.s.av_alpha[a] = viscosity_switch_bound(c.s.av_alpha[a], mat.av.alpha, mat.av_switch);
}

// Pressure, viscosity and conductivity: dv/dt, du/dt, (drho/dt), mu_max.
template <int D, class Each>
RUBBLE_HD_INLINE void hydro_rates_particle(const RhsContext<D>& c, std::uint32_t a, Each&& each) {
  const StoreView<D>& s = c.s;
  const HydroSide<D> pa = hydro_side<D>(c.kernel, hydro_particle<D>(c, a), false, c.geometric_force);
  Vec<D> dvdt = Vec<D>::zero();
  Real dudt = 0, drhodt = 0, mu_max = 0;
  WallContact<D> wall;
  each([&](std::uint32_t b) {
    // A listed neighbour outside both supports (the search skin) adds
    // nothing: skip it before b's side (two divisions) is prepared.
    const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
    const Real h_max = pa.q.h > s.h[b] ? pa.q.h : s.h[b];
    if (norm2(dx) >= h_max * h_max) return;
    HydroParticle<D> pb = hydro_particle<D>(c, b);
    pb.v = seen_velocity<D>(s, a, b);
    const HydroPairRates<D> r = hydro_pair<D>(pa, hydro_side<D>(c.kernel, pb, true, c.geometric_force), dx, !c.summation);
    dvdt += wall_filtered_force<D>(s, a, b, r.dvdt, wall);
    dudt += r.dudt;
    drhodt += r.drhodt;
    mu_max = r.mu > mu_max ? r.mu : mu_max;
  });
  const WallReaction<D> reaction = wall_reaction_particle<D>(c, a, wall);
  dvdt += reaction.dvdt;
  dudt += reaction.dudt;
  s.dvdt[a] = dvdt;
  s.dudt[a] = dudt;
  if (!c.summation) s.drhodt[a] = drhodt;
  if (s.dalphadt) porosity_rates_particle<D>(c, a, drhodt, dudt);
  if (s.dav_alpha_dt) s.dav_alpha_dt[a] = viscosity_switch_rate_particle<D>(c, a, drhodt);
  s.mu_max[a] = mu_max;
}

// ---- feature set Solid ---------------------------------------------------

// 1/H and 1/rho^2 of particle i (solid.hpp: SolidInverses): from the
// driver's table when it keeps one, else computed (the same values).
template <int D>
RUBBLE_HD_INLINE SolidInverses solid_inverses_particle(const RhsContext<D>& c, std::uint32_t i) {
  return c.solid_inv ? c.solid_inv[i] : solid_inverses(c.s.h[i], c.s.rho[i]);
}

// Pass 1: the velocity gradient L_a (with the kernel-gradient correction
// when on), the Jaumann stress rate dS/dt and the artificial stress R_a.
// With the correction it also stores K_a = C_a^T, with which pass 2 turns
// gbar into the corrected gradient of a's stress terms (solid.hpp), so that
// Hooke's law, continuity and the energy equation share one strain rate.
//
// The neighbour sums of one particle: L_a = sum_b V_b (v_b - v_a) (x) gbar,
// the correction's M_a = sum_b V_b (x_b - x_a) (x) gbar (V_b = m_b/rho_w,
// solid.hpp: velocity_gradient_pair_term) and the nearest neighbour's
// squared distance (artificial stress).
template <int D>
struct GradientSums {
  // M: the correction's moment matrix; without the correction, under the
  // staggered stress update, sum_b m_b (v_b - v_a) (x) gbar instead (with
  // the correction that sum is rho_a L_a), and unused otherwise
  Mat<D> L = Mat<D>::zero(), M = Mat<D>::zero();
  Real r2_min = std::numeric_limits<Real>::max();
};

// One pair of pass 1 as seen from a: gbar, v_b - v_a (the velocity a sees
// of b) and x_b - x_a. Seen from b all three change sign, exactly, so the
// CPU's pair-once loop adds the negated vectors to b's sums (other_side).
// inactive: beyond both supports or r = 0; r2 = |dx|^2 either way (the
// nearest-neighbour distance).
template <int D>
struct GradientPairTerms {
  bool active = false;
  Real r2 = 0;
  Vec<D> g, v_ba, x_ba;
};

template <int D>
RUBBLE_HD_INLINE GradientPairTerms<D> gradient_pair_terms(const RhsContext<D>& c, std::uint32_t a, std::uint32_t b,
                                                          const KernelAt<D>& ka, const Vec<D>& dx) {
  const StoreView<D>& s = c.s;
  GradientPairTerms<D> t;
  t.r2 = norm2(dx);
  // a candidate beyond both supports (search skin, GPU cell) adds nothing:
  // skip it before the square root
  const Real h_max = s.h[a] > s.h[b] ? s.h[a] : s.h[b];
  if (t.r2 <= Real(0) || t.r2 >= h_max * h_max) return t;
  const Real r = std::sqrt(t.r2);
  if (r >= s.h[a] && r >= s.h[b]) return t;
  t.active = true;
  t.g = Real(0.5) * (kernel_grad<D>(ka, dx, r) +
                     kernel_grad<D>(kernel_at_inv<D>(c.kernel, solid_inverses_particle<D>(c, b).inv_h), dx, r));
  t.v_ba = seen_velocity<D>(s, a, b) - s.v[a];
  t.x_ba = -dx;
  return t;
}

template <int D>
RUBBLE_HD_INLINE GradientPairTerms<D> other_side(GradientPairTerms<D> t) {
  t.g = -t.g;
  t.v_ba = -t.v_ba;
  t.x_ba = -t.x_ba;
  return t;
}

// Adds a pair's terms to a's sums, b being the other particle: volume
// weight m_b/rho_b, or m_b/rho_a with the correction (solid.hpp).
template <int D>
RUBBLE_HD_INLINE void add_gradient_pair(const RhsContext<D>& c, std::uint32_t a, std::uint32_t b,
                                        const GradientPairTerms<D>& t, GradientSums<D>& sums) {
  const StoreView<D>& s = c.s;
  const Real rho_w = c.kernel_correction ? s.rho[a] : s.rho[b];
  sums.L += velocity_gradient_pair_term<D>(s.m[b], rho_w, t.v_ba, t.g);
  if (c.kernel_correction) sums.M += correction_pair_term<D>(s.m[b], rho_w, t.x_ba, t.g);
  else if (c.stagger_dt > Real(0)) sums.M += s.m[b] * Mat<D>::outer(t.v_ba, t.g);
}

// Adds a pair's stress-diffusion term to a's sum D_a (physics/
// stress_diffusion.hpp), b being the other particle: among free particles
// of one material whose material diffuses (not across a contact between
// materials, not with wall particles, whose stress is extrapolated from the
// material itself). Called only when c.stress_diffusion; the sum is kept
// apart from GradientSums so that scenes without it hold no storage for it.
template <int D>
RUBBLE_HD_INLINE void add_stress_diffusion_pair(const RhsContext<D>& c, std::uint32_t a, std::uint32_t b,
                                                const GradientPairTerms<D>& t, Mat<D>& Sd) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  if (!(mat.stress_diffusion > Real(0)) || s.material_id[b] != s.material_id[a] ||
      (s.boundary && (s.boundary[a] || s.boundary[b])))
    return;
  const Vec<D> dx = -t.x_ba;  // x_a - x_b
  const Mat<D> dSH = geostatic_deviator_difference<D>(dx, c.body_force, Real(0.5) * (s.rho[a] + s.rho[b]), mat.k0);
  Sd += stress_diffusion_pair_term<D>(s.S[a], s.S[b], dSH, s.m[b] / s.rho[b], dx, t.g, monaghan_h<D>(c.kernel, s.h[a]));
}

// The total stress sigma = f S - p I that acts in the momentum equation
// (f: deviatoric_factor_particle).
template <int D>
RUBBLE_HD_INLINE Mat<D> total_stress_particle(const RhsContext<D>& c, std::uint32_t a) {
  Mat<D> sigma = deviatoric_factor_particle<D>(c, a) * c.s.S[a];
  for (int i = 0; i < D; ++i) sigma.m[i][i] -= c.s.p[a];
  return sigma;
}

// R_a of the artificial stress from particle a's current total stress and
// its clumping weight chi (artificial_stress.hpp).
template <int D>
RUBBLE_HD_INLINE Mat<D> artificial_stress_particle(const RhsContext<D>& c, std::uint32_t a, Real chi) {
  const MaterialParams& mat = c.mat[c.s.material_id[a]];
  if (!(mat.as_exponent > Real(0)) || !(chi > Real(0))) return Mat<D>::zero();
  return artificial_stress_tensor<D>(total_stress_particle<D>(c, a), c.s.rho[a], chi * mat.as_epsilon);
}

// From a's complete sums: C_a and K_a, L_a, dS/dt, the damage rate and R_a.
// Returns false when the correction matrix was ill-conditioned (identity used).
// Sd: a's stress-diffusion sum D_a, or nullptr when no material diffuses.
template <int D>
RUBBLE_HD_INLINE bool solid_gradient_finish(const RhsContext<D>& c, std::uint32_t a, const GradientSums<D>& sums,
                                            const Mat<D>* Sd = nullptr) {
  const StoreView<D>& s = c.s;
  Mat<D> L = sums.L;
  // sqrt is monotonic and correctly rounded: the nearest distance itself
  const Real r_min =
      sums.r2_min < std::numeric_limits<Real>::max() ? std::sqrt(sums.r2_min) : std::numeric_limits<Real>::max();
  bool well_conditioned = true;
  if (c.kernel_correction) {
    Mat<D> C;
    well_conditioned = correction_matrix<D>(sums.M, kCorrectionMinDet, C);
    L = L * C;  // = sum_b V_b v_ba (x) (C^T gbar)
    if (s.corr_K) s.corr_K[a] = transpose(C);
  }
  const MaterialParams& mat = c.mat[s.material_id[a]];
  s.dSdt[a] = mat.shear_modulus > Real(0) ? deviatoric_stress_rate<D>(s.S[a], L, mat.shear_modulus) : Mat<D>::zero();
  if (Sd && mat.stress_diffusion > Real(0))
    s.dSdt[a] += (mat.stress_diffusion * monaghan_h<D>(c.kernel, s.h[a]) * s.cs[a]) * *Sd;
  if (s.ddamage_root_dt) s.ddamage_root_dt[a] = damage_rate_particle<D>(c, a);
  if (c.stagger_dt > Real(0)) {  // for staggered_update_particle: the gradient and the continuity rate
    const Mat<D> Lm = c.kernel_correction ? s.rho[a] * L : sums.M;
    c.stagger_Lm[a] = Lm;
    s.drhodt[a] = -trace(Lm);  // = pass 2's sum_b m_b (v_a - v_b) . g_a
  }
  if (c.art_R) {
    const Real chi = clumping_weight(r_min, local_spacing<D>(s.m[a], s.rho[a]), mat.as_clump_onset,
                                     mat.as_clump_full);
    if (c.as_chi) c.as_chi[a] = chi;  // R_a follows from the advanced stress
    else c.art_R[a] = artificial_stress_particle<D>(c, a, chi);
  }
  return well_conditioned;
}

// The staggered stress update (simulation.stress_update = "staggered";
// leapfrog.hpp), between pass 1 and pass 2 of a leapfrog step: S and rho
// advance the whole step with pass 1's rates, which the half-step velocity
// gave, and the pressure, the plastic return and R_a follow, so that pass 2
// takes its forces from the stress at the end of the step. Boundary
// particles whose state does not evolve keep theirs.
//
// The energy: pass 2's du/dt is the work of the new stress on the step's
// strain rate, sigma_{n+1} : L / rho (its pair form, with the new rho, as
// pass 2 takes it); the step's work is that of the mean stress, so
//   du = -(1/2) (sigma_{n+1} - sigma_n) : (sum_b m_b v_ba (x) g_a) / rho_{n+1}^2
// is added to du/dt after pass 2 (staggered_energy_particle) and leapfrog
// advances u by dt du/dt: with the kicks' force work this closes the
// elastic energy exactly, up to the bounded term (dt^2/8) sum m |a|^2 of a
// symplectic step. Without it u gains ~(omega dt)/2 of the elastic energy
// per radian of a mode of frequency omega (measured: a free elastic block
// without viscosity at omega dt ~ 0.02 gained 7 times its energy in u over
// ~30 periods). Kicking u in two halves instead leaves an end term of
// (dt/2) times the elastic power, ~(omega dt)/2 of the energy (measured
// 7e-3 on that block). The viscous heating is booked at v_{1/2} while the
// kicks apply the viscous forces of v_{n-1/2} and v_{n+1/2}: a mismatch of
// O(gamma dt) of the heat, gamma the damping rate of the viscosity
// (docs/physics.md, "Stress update").
template <int D>
RUBBLE_HD_INLINE void staggered_update_particle(const RhsContext<D>& c, std::uint32_t a, bool plasticity) {
  const StoreView<D>& s = c.s;
  Real du = 0;
  if (state_evolves<D>(s, a)) {
    const Mat<D> sigma_old = total_stress_particle<D>(c, a);
    s.S[a] += c.stagger_dt * s.dSdt[a];
    s.rho[a] += c.stagger_dt * s.drhodt[a];
    eos_particle<D>(c, a);
    // the step's final stress: the plastic strain is accumulated here (the
    // end-of-step return then finds the state on the surface)
    if (plasticity) plastic_return_particle<D>(c, a, true);
    const Real inv_rho = Real(1) / s.rho[a];
    du = Real(-0.5) * inv_rho * inv_rho * double_dot(total_stress_particle<D>(c, a) - sigma_old, c.stagger_Lm[a]);
  }
  c.stagger_du[a] = du;
  if (c.art_R && c.as_chi) c.art_R[a] = artificial_stress_particle<D>(c, a, c.as_chi[a]);
}

// After pass 2 of a staggered evaluation: du/dt becomes the step's
// trapezoidal work (staggered_update_particle).
template <int D>
RUBBLE_HD_INLINE void staggered_energy_particle(const RhsContext<D>& c, std::uint32_t a) {
  c.s.dudt[a] += c.stagger_du[a];
}

// Pass 1 of particle a over all its neighbours (the gather form: the GPU,
// and the CPU with free-slip walls; the CPU otherwise sums each pair once,
// HydroCpu::solid_rates).
template <int D, class Each>
RUBBLE_HD_INLINE bool solid_gradient_particle(const RhsContext<D>& c, std::uint32_t a, Each&& each) {
  GradientSums<D> sums;
  Mat<D> Sd = Mat<D>::zero();
  const KernelAt<D> ka = kernel_at_inv<D>(c.kernel, solid_inverses_particle<D>(c, a).inv_h);
  each([&](std::uint32_t b) {
    const GradientPairTerms<D> t = gradient_pair_terms<D>(c, a, b, ka, c.domain.separation(c.s.x[a], c.s.x[b]));
    if (t.r2 > Real(0) && t.r2 < sums.r2_min) sums.r2_min = t.r2;
    if (!t.active) return;
    add_gradient_pair<D>(c, a, b, t, sums);
    if (c.stress_diffusion) add_stress_diffusion_pair<D>(c, a, b, t, Sd);
  });
  return solid_gradient_finish<D>(c, a, sums, c.stress_diffusion ? &Sd : nullptr);
}

template <int D>
RUBBLE_HD_INLINE SolidParticle<D> solid_particle(const RhsContext<D>& c, std::uint32_t i) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[i]];
  const Mat<D> S = (s.alpha || s.damage_root) ? deviatoric_factor_particle<D>(c, i) * s.S[i] : s.S[i];
  return SolidParticle<D>{s.x[i],  s.v[i],  s.m[i], s.rho[i], s.p[i], s.h[i], s.cs[i], S,
                          c.art_R ? c.art_R[i] : Mat<D>::zero(), mat.av, mat.dp, mat.as_exponent,
                          s.u[i], mat.alpha_u, s.corr_K ? &s.corr_K[i] : nullptr};
}

// Pass 2: the full-stress momentum, energy and continuity equations.
template <int D, class Each>
RUBBLE_HD_INLINE void solid_rates_particle(const RhsContext<D>& c, std::uint32_t a, Each&& each) {
  const StoreView<D>& s = c.s;
  const SolidParticle<D> pa = solid_particle<D>(c, a);
  const SolidInverses ia = solid_inverses_particle<D>(c, a);
  Vec<D> dvdt = Vec<D>::zero();
  Real dudt = 0, drhodt = 0, mu_max = 0;
  WallContact<D> wall;
  each([&](std::uint32_t b) {
    const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
    const Real h_max = pa.h > s.h[b] ? pa.h : s.h[b];
    if (norm2(dx) >= h_max * h_max) return;  // beyond both supports: skip before b's side is gathered
    SolidParticle<D> pb = solid_particle<D>(c, b);
    pb.v = seen_velocity<D>(s, a, b);
    const SolidPairRates<D> r =
        solid_pair<D>(c.kernel, pa, ia, pb, solid_inverses_particle<D>(c, b), dx);
    dvdt += wall_filtered_force<D>(s, a, b, r.dvdt, wall);
    dudt += r.dudt;
    drhodt += r.drhodt;
    mu_max = r.mu > mu_max ? r.mu : mu_max;
  });
  const WallReaction<D> reaction = wall_reaction_particle<D>(c, a, wall);
  dvdt += reaction.dvdt;
  dudt += reaction.dudt;
  s.dvdt[a] = dvdt;
  s.dudt[a] = dudt;
  s.drhodt[a] = drhodt;
  if (s.dalphadt) porosity_rates_particle<D>(c, a, drhodt, dudt);
  s.mu_max[a] = mu_max;
}

// ---- after the pair sums -------------------------------------------------

// Boundary particles move as prescribed: dv/dt = 0, so they keep their
// velocity (0 when fixed) and move with it (rigid tools are placed by
// their tool's pose instead, StepSequence::place_tools). What the rest
// exerts on them, m dv/dt (the body force never acts on held particles,
// body_force_particle), is kept in wall_force first. Evolving ones
// integrate rho, u and S like the rest; frozen and extrapolated ones are
// not integrated.
template <int D>
RUBBLE_HD_INLINE void hold_boundary_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  if (s.boundary[a] == kFreeParticle) return;
  // the force of the rest on it (boundary_forces.csv; a driven tool's reaction)
  if (s.wall_force) s.wall_force[a] = s.m[a] * s.dvdt[a];
  s.dvdt[a] = Vec<D>::zero();
  if (s.boundary[a] == kBoundaryEvolving) return;
  s.dudt[a] = 0;
  if (s.drhodt) s.drhodt[a] = 0;
  if (s.dSdt) s.dSdt[a] = Mat<D>::zero();
  if (s.dalphadt) s.dalphadt[a] = 0;
  if (s.ddamage_root_dt) s.ddamage_root_dt[a] = 0;
}

// The power the held particles put into the rest (the energy watchdog's
// booked work of walls, drivers/step_sequence.hpp), from particle a's
// rates before hold_boundary_particle zeroes them. A pair's forces and
// heating conserve m_a (v_a.dv_a + du_a) + m_b (v_b.dv_b + du_b) whatever
// pressures they use (extrapolated walls too); a held particle b keeps its
// velocity and (unless evolving) its u, so what it would have gained,
// m_b (v_b.dv_b/dt + du_b/dt), went into the others: their gain is minus
// that. The body force never acts on held particles (body_force_particle;
// their potential energy is not counted either, conserved_sums.hpp). 0 for
// free particles.
template <int D>
RUBBLE_HD_INLINE double wall_power_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  if (s.boundary[a] == kFreeParticle) return 0;
  double held = double(dot(s.v[a], s.dvdt[a]));
  if (s.boundary[a] != kBoundaryEvolving) held += double(s.dudt[a]);
  return -double(s.m[a]) * held;
}

// The lowest u particle a's EOS admits (the state check's bound): its
// internal-energy floor, -infinity where it has none (eos.hpp).
template <int D>
RUBBLE_HD_INLINE Real u_min_particle(const RhsContext<D>& c, std::uint32_t a) {
  return eos_energy_floor(c.mat[c.s.material_id[a]].eos, c.s.rho[a]);
}

// The internal-energy floor after a step (issue #50 item 2; eos.hpp): u
// below its EOS's floor is raised to it. Returns the energy added, m du
// (booked by the caller).
template <int D>
RUBBLE_HD_INLINE double energy_floor_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  const Real floor = u_min_particle<D>(c, a);
  if (!(s.u[a] < floor)) return 0;
  const double added = double(s.m[a]) * (double(floor) - double(s.u[a]));
  s.u[a] = floor;
  return added;
}

// XSPH: the smoothed-velocity correction to dx/dt (physics/xsph.hpp),
// within a material only (not across a contact between bodies of different
// materials); boundary particles get none.
template <int D, class Each>
RUBBLE_HD_INLINE void xsph_particle(const RhsContext<D>& c, std::uint32_t a, Each&& each) {
  const StoreView<D>& s = c.s;
  Vec<D> sum = Vec<D>::zero();
  if (!(s.boundary && s.boundary[a])) {
    each([&](std::uint32_t b) {
      if (s.material_id[b] != s.material_id[a]) return;
      const Real r = norm(c.domain.separation(s.x[a], s.x[b]));
      const Real w = Real(0.5) * (kernel_w<D>(c.kernel, r, s.h[a]) + kernel_w<D>(c.kernel, r, s.h[b]));
      if (w > Real(0)) sum += xsph_pair_term<D>(s.m[b], s.rho[a], s.rho[b], seen_velocity<D>(s, a, b) - s.v[a], w);
    });
  }
  s.xsph_v[a] = c.xsph_epsilon * sum;
}

// Particle shifting (physics/particle_shifting.hpp), once per accepted step:
// the shift of free particle a over the step dt with coefficient A, from
// all its neighbours (wall particles fill the kernel like any other); zero
// for boundary particles. Written to out[a]; the driver applies it after
// every particle's shift is known.
template <int D, class Each>
RUBBLE_HD_INLINE void shifting_particle(const RhsContext<D>& c, std::uint32_t a, Real A, Real dt, Vec<D>* out,
                                        Each&& each) {
  const StoreView<D>& s = c.s;
  out[a] = Vec<D>::zero();
  if (s.boundary && s.boundary[a] != kFreeParticle) return;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  const Real h = s.h[a];
  const Real w_dp = kernel_w<D>(c.kernel, mat.dp, h);
  ShiftSums<D> sum;
  sum.C = s.m[a] / s.rho[a] * kernel_w<D>(c.kernel, Real(0), h);
  Real dv_max = 0;  // the largest speed of a neighbour relative to a
  each([&](std::uint32_t b) {
    const Vec<D> dx = c.domain.separation(s.x[a], s.x[b]);
    const Real r = norm(dx);
    if (r <= Real(0) || r >= h) return;
    shift_sums_add<D>(sum, s.m[b] / s.rho[b], kernel_w<D>(c.kernel, r, h), w_dp, kernel_grad<D>(c.kernel, dx, h));
    const Real dv = norm(s.v[b] - s.v[a]);
    dv_max = dv > dv_max ? dv : dv_max;
  });
  out[a] = shifting_displacement<D>(sum, A, h, dv_max, dt, mat.dp);
}

// Largest stable step of particle a (Courant and force limits); solids use
// the longitudinal wave speed sqrt(c^2 + 4 mu / (3 rho)) with the shear
// modulus that acts, mu times the deviatoric factor (1/alpha of a porous
// solid, 1 - D of a damaged one: deviatoric_factor_particle), because the
// stress in the momentum equation is that factor times the evolved S (a
// fully damaged particle is a fluid and steps at its sound speed). With the
// kernel-gradient correction h is divided by the correction's gain
// (kernel_gradient_correction.hpp: correction_gain), the factor by which the
// corrected stress terms stiffen a truncated kernel.
template <int D>
RUBBLE_HD_INLINE Real dt_limit_particle(const RhsContext<D>& c, std::uint32_t a) {
  const StoreView<D>& s = c.s;
  const MaterialParams& mat = c.mat[s.material_id[a]];
  Real hM = monaghan_h<D>(c.kernel, s.h[a]);
  if (s.corr_K) hM /= correction_gain<D>(s.corr_K[a]);
  const Real mu = mat.shear_modulus > Real(0) ? deviatoric_factor_particle<D>(c, a) * mat.shear_modulus : Real(0);
  const Real cl = mu > Real(0) ? elastic_signal_speed(s.cs[a], mu, s.rho[a]) : s.cs[a];
  const Real dt_c = courant_dt(c.courant, hM, cl, mat.av.alpha, mat.av.beta, s.mu_max[a]);
  const Real dt_f = force_dt(c.force_factor, hM, norm(s.dvdt[a]));
  Real dt = dt_c < dt_f ? dt_c : dt_f;
  if (s.dalphadt) {
    const Real dt_a = porosity_dt_limit(s.alpha[a], s.dalphadt[a], kAlphaStepFraction);
    dt = dt_a < dt ? dt_a : dt;
  }
  // continuity density, where the density falls: -d rho <= density_step_fraction
  // rho per step. An explicit update rho + dt d rho/dt goes negative once
  // dt |div v| exceeds 1, which the Courant limit does not prevent where
  // material expands into vacuum faster than its sound speed (the Einfeldt
  // 1-2-0-3 rarefaction: test_energy_watchdog, Vapour.*). miluphcuda limits
  // its step by SAFETY_FIRST (|rho| + rho_min) / |d rho/dt| with SAFETY_FIRST
  // = 0.1 in its Euler and Heun schemes (src/predictor_corrector_euler.cu,
  // coupled_heun_rk4_sph_nbody.cu), the default here (issue #50 item 3), in
  // both directions; rubble only where rho falls: a rising density cannot
  // turn negative, so compression (shocks, compaction) keeps its Courant step.
  if (s.drhodt && c.density_step_fraction > Real(0) && s.drhodt[a] < Real(0)) {
    const Real dt_r = c.density_step_fraction * s.rho[a] / -s.drhodt[a];
    dt = dt_r < dt ? dt_r : dt;
  }
  if (s.ddamage_root_dt) {
    const Real dt_d = damage_dt_limit_particle<D>(c, a);
    dt = dt_d < dt ? dt_d : dt;
  }
  return dt;
}

}  // namespace rubble
