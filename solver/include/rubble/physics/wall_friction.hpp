#pragma once
// Sliding walls: free-slip and Coulomb friction (issue #12 item 5;
// docs/physics.md "Body force and walls").
//
// A sliding wall (wall_slip = "free_slip" or "coulomb", with the wall's
// unit normal n pointing into the material) acts on a free particle a only
// along n, and only by pushing. Of each pair acceleration f_ab that a wall
// particle b would exert on a, only the normal part (f_ab·n_b) n_b is kept
// (wall_contact_add); their sum N = sum_b f_ab·n_b is the wall's push, and
// when it is not positive (a particle in tension next to the wall would be
// pulled towards it) the wall does nothing: a wall holds material, it does
// not stick to it. The sum is clipped as a whole, not pair by pair: with
// shear stress at the wall the pairs' normal parts scatter about their sum.
// The wall's tangential action is then friction alone, which for a Coulomb
// wall is bounded by mu times the push (Coulomb's law of dry friction):
//
//   a_fric = -k v_t,   k = min(mu N / |v_t|, k_max),
//
// with v_t the velocity of a relative to the wall, tangential to the push's
// direction sum_b (f_ab·n_b) n_b. For |v_t| above the stick speed
// v_s = mu N / k_max this is exactly Coulomb's kinetic friction, mu N
// against the sliding direction; below it the friction is viscous with
// rate k_max (a regularised Coulomb law, the usual way to write static
// friction in an explicit scheme: e.g. Oden & Martins 1985, Comput. Methods
// Appl. Mech. Eng. 52:527). The driver takes k_max = c_a / hM_a
// (sound speed over Monaghan's smoothing length): the Courant limit
// dt <= C hM / c then keeps k_max dt <= C < 1, so the viscous branch can
// never reverse the sliding within a step, and v_s = mu N hM / c vanishes
// with resolution. The friction's work goes into a's internal energy
// (k |v_t|^2 >= 0 per unit mass), so a run against a wall at rest keeps its
// total energy.
#include "rubble/core/hd.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// What the sliding-wall neighbours of one free particle add up to.
template <int D>
struct WallContact {
  Real push = 0;                     // N = sum of the normal parts f_ab·n_b (> 0: a push)
  Real mu_push = 0;                  // sum of mu_b (f_ab·n_b): mu N for one wall
  Vec<D> normal = Vec<D>::zero();    // sum of (f_ab·n_b) n_b: the push
  Vec<D> velocity = Vec<D>::zero();  // sum of v_b
  int count = 0;                     // how many wall particles: velocity / count is the wall's
};

// Adds the pair acceleration f that sliding-wall particle b (normal n,
// friction coefficient mu, velocity vb) would exert on free particle a.
template <int D>
RUBBLE_HD_INLINE void wall_contact_add(WallContact<D>& w, const Vec<D>& f, const Vec<D>& n, Real mu, const Vec<D>& vb) {
  const Real fn = dot(f, n);
  w.push += fn;
  w.mu_push += mu * fn;
  w.normal += fn * n;
  w.velocity += vb;
  ++w.count;
}

template <int D>
struct WallReaction {
  Vec<D> dvdt = Vec<D>::zero();  // the wall's push plus its friction [m/s^2]
  Real dudt = 0;                 // the friction's heating [J/kg/s], >= 0
};

// What the sliding walls do to a particle moving with velocity va, from its
// contact sums w, with the viscous rate k_max of the stick regime (> 0):
// nothing unless they push; then the push and the Coulomb friction.
template <int D>
RUBBLE_HD_INLINE WallReaction<D> wall_reaction(const WallContact<D>& w, const Vec<D>& va, Real k_max) {
  WallReaction<D> out;
  if (!(w.push > Real(0))) return out;  // no contact, or a pull: the wall does not hold on
  out.dvdt = w.normal;
  if (!(w.mu_push > Real(0))) return out;  // free-slip
  const Real len = norm(w.normal);
  if (!(len > Real(0))) return out;
  const Vec<D> n = (Real(1) / len) * w.normal;
  const Vec<D> rel = va - (Real(1) / Real(w.count)) * w.velocity;
  const Vec<D> vt = rel - dot(rel, n) * n;
  const Real speed = norm(vt);
  if (!(speed > Real(0))) return out;
  const Real coulomb = w.mu_push / speed;
  const Real k = coulomb < k_max ? coulomb : k_max;
  out.dvdt += -k * vt;
  out.dudt = k * speed * speed;
  return out;
}

}  // namespace rubble
