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
// wall is bounded by mu times the push (Coulomb's law of dry friction). It
// sticks or slips as a spring-slider does (the tangential contact law of
// Cundall & Strack 1979, Geotechnique 29:47, here between a particle and
// the wall): each free particle keeps an anchor, the point where it would
// sit with its friction spring relaxed; with d_t the tangential part of
// x_a - anchor_a and v_t that of its velocity relative to the wall
// (tangential to the push's direction sum_b (f_ab·n_b) n_b),
//
//   trial  f = -omega^2 d_t - 2 omega v_t       (spring, critically damped)
//   stick  |f| <= mu N:  a_fric = f
//   slip   |f| >  mu N:  a_fric = mu N f/|f|    (kinetic friction), and at
//                        the end of the step the anchor follows so that
//                        omega^2 |d_t| = mu N (wall_anchor_update).
//
// A particle at rest on a wall below the friction angle therefore holds
// (it moves by the spring's stretch mu N / omega^2 and no further), and
// one that slides meets exactly mu N against its sliding (the damping adds
// to the spring's pull along -v_t). The driver takes omega = c_a / hM_a
// (sound speed over Monaghan's smoothing length): the Courant limit
// dt <= C hM / c keeps omega dt <= C, well inside the explicit schemes'
// stability for the spring (omega dt < 2) and its damping (2 omega dt < 2),
// and the stretch mu N hM^2 / c^2 is far below a particle spacing (a
// column of 25 particles at rest: ~1e-3 dx). Off the walls (no push) the
// anchor is the particle's position. The damping's and the slip's work go
// into a's internal energy.
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
  Vec<D> grip = Vec<D>::zero();  // mu N along the push's direction; 0 without push
};

// What the sliding walls do to a particle moving with velocity va, from its
// contact sums w, its spring's stretch d = x_a - anchor_a and the spring's
// frequency omega (> 0): nothing unless they push; then the push and the
// Coulomb friction (stick or slip).
template <int D>
RUBBLE_HD_INLINE WallReaction<D> wall_reaction(const WallContact<D>& w, const Vec<D>& va, const Vec<D>& d,
                                               Real omega) {
  WallReaction<D> out;
  if (!(w.push > Real(0))) return out;  // no contact, or a pull: the wall does not hold on
  out.dvdt = w.normal;
  if (!(w.mu_push > Real(0))) return out;  // free-slip
  const Real len = norm(w.normal);
  if (!(len > Real(0))) return out;
  const Vec<D> n = (Real(1) / len) * w.normal;
  out.grip = w.mu_push * n;
  const Vec<D> rel = va - (Real(1) / Real(w.count)) * w.velocity;
  const Vec<D> vt = rel - dot(rel, n) * n;
  const Vec<D> dt = d - dot(d, n) * n;
  const Vec<D> trial = -(omega * omega) * dt - (Real(2) * omega) * vt;
  const Real size = norm(trial);
  if (size <= w.mu_push) {  // stick
    out.dvdt += trial;
    out.dudt = Real(2) * omega * norm2(vt);  // the damping's work (the spring's is stored)
    return out;
  }
  const Vec<D> slip = (w.mu_push / size) * trial;
  out.dvdt += slip;
  const Real work = -dot(slip, vt);
  out.dudt = work > Real(0) ? work : Real(0);
  return out;
}

// The spring's stretch after a step, from its stretch d = x_a - anchor_a
// at the step's end, the grip of the step's last evaluation and omega: its
// tangential part, shortened to mu N / omega^2 where it pulls harder than
// the friction can hold (the particle slipped); 0 off the walls. The new
// anchor is x_a minus it.
template <int D>
RUBBLE_HD_INLINE Vec<D> wall_anchor_update(const Vec<D>& d, const Vec<D>& grip, Real omega) {
  const Real mu_n = norm(grip);
  if (!(mu_n > Real(0))) return Vec<D>::zero();
  const Vec<D> n = (Real(1) / mu_n) * grip;
  const Vec<D> dt = d - dot(d, n) * n;
  const Real cap = mu_n / (omega * omega);
  const Real stretch = norm(dt);
  return stretch <= cap ? dt : (cap / stretch) * dt;
}

}  // namespace rubble
