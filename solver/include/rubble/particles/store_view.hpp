#pragma once
// A StoreView is the particle store as plain pointers, one per field
// (nullptr when the run does not allocate the field). The CPU driver makes
// one over a ParticleStore's std::vectors, the CUDA driver over its device
// arrays; the per-particle functions of rubble/drivers/particle_rates.hpp
// take a view, so both backends run the same loop bodies.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"
#include "rubble/core/real.hpp"
#include "rubble/core/vec.hpp"

namespace rubble {

// Values of the `boundary` field. A boundary particle is fixed or moves with
// its body's prescribed velocity; its state is
//   kBoundaryFrozen:       kept (not integrated);
//   kBoundaryEvolving:     integrated like a free particle's (rho, u, S);
//   kBoundaryExtrapolated: set in every evaluation from the free particles
//                          around it (physics/wall_extrapolation.hpp).
constexpr std::int32_t kFreeParticle = 0;
constexpr std::int32_t kBoundaryFrozen = 1;
constexpr std::int32_t kBoundaryEvolving = 2;
constexpr std::int32_t kBoundaryExtrapolated = 3;

template <int D>
struct StoreView {
  std::size_t n = 0;
  Real* m = nullptr;
  std::int32_t* material_id = nullptr;
  std::int32_t* id = nullptr;  // the particle's number at generation (its body: body_first ranges)
  Vec<D>* x = nullptr;
  Vec<D>* v = nullptr;
  Real* u = nullptr;
  Real* rho = nullptr;
  Real* h = nullptr;
  Real* p = nullptr;
  Real* cs = nullptr;
  Real* omega = nullptr;
  Vec<D>* dvdt = nullptr;
  Real* dudt = nullptr;
  Real* drhodt = nullptr;
  Real* mu_max = nullptr;
  Vec<D>* a_grav = nullptr;
  Real* phi = nullptr;
  Mat<D>* S = nullptr;
  Mat<D>* dSdt = nullptr;
  std::int32_t* boundary = nullptr;
  Vec<D>* wall_force = nullptr;
  std::int32_t* tool = nullptr;
  Vec<D>* tool_offset = nullptr;
  Vec<D>* xsph_v = nullptr;
  Mat<D>* corr_K = nullptr;
  Real* alpha = nullptr;
  Real* dalphadt = nullptr;
  Real* eps_p = nullptr;
  Real* eps_v = nullptr;
  Vec<D>* wall_normal = nullptr;
  Real* wall_friction = nullptr;
  Vec<D>* wall_anchor = nullptr;
  Vec<D>* wall_grip = nullptr;
  Real* damage_root = nullptr;
  Real* ddamage_root_dt = nullptr;
  std::int32_t* flaw_count = nullptr;
  Real* flaw_eps_min = nullptr;
  Real* flaw_eps_max = nullptr;
  Real* flaws_active = nullptr;
  Real* av_alpha = nullptr;
  Real* dav_alpha_dt = nullptr;

  // Point the field called `name` (the field table's names) at `ptr`;
  // false if the name is unknown or the element type does not match.
  template <class T>
  bool bind(std::string_view name, T* ptr) {
    bool ok = false;
    auto set = [&](auto*& slot, std::string_view field) {
      using Slot = std::remove_reference_t<decltype(*slot)>;
      if constexpr (std::is_same_v<Slot, T>) {
        if (name == field) {
          slot = ptr;
          ok = true;
        }
      }
    };
    set(m, "m"), set(material_id, "material_id"), set(id, "id"), set(x, "x"), set(v, "v"), set(u, "u"), set(rho, "rho");
    set(h, "h"), set(p, "p"), set(cs, "cs"), set(omega, "omega"), set(dvdt, "dvdt"), set(dudt, "dudt");
    set(drhodt, "drhodt"), set(mu_max, "mu_max"), set(a_grav, "a_grav"), set(phi, "phi"), set(S, "S");
    set(dSdt, "dSdt"), set(boundary, "boundary"), set(xsph_v, "xsph_v");
    set(wall_force, "wall_force"), set(tool, "tool"), set(tool_offset, "tool_offset");
    set(corr_K, "corr_K");
    set(alpha, "alpha"), set(dalphadt, "dalphadt"), set(eps_p, "eps_p"), set(eps_v, "eps_v");
    set(wall_normal, "wall_normal"), set(wall_friction, "wall_friction"), set(wall_anchor, "wall_anchor");
    set(wall_grip, "wall_grip");
    set(damage_root, "damage_root"), set(ddamage_root_dt, "ddamage_root_dt"), set(flaw_count, "flaw_count");
    set(flaw_eps_min, "flaw_eps_min"), set(flaw_eps_max, "flaw_eps_max"), set(flaws_active, "flaws_active");
    set(av_alpha, "av_alpha"), set(dav_alpha_dt, "dav_alpha_dt");
    return ok;
  }

  // dx/dt of particle i: v, plus the XSPH correction when the run has it.
  RUBBLE_HD Vec<D> position_rate(std::size_t i) const { return xsph_v ? v[i] + xsph_v[i] : v[i]; }
};

}  // namespace rubble
