#pragma once
// How far both backends search for neighbours, as multiples of a
// particle's support radius h: one place for the constants, which the step
// sequence applies (rubble/drivers/step_sequence.hpp) and the memory
// estimate reads (initial_conditions.cpp).
//
// kSearchSkin: every search lists the pairs within max(R_a, R_b), R =
// kSearchSkin h. With summation density it is the room h has to grow in
// the smoothing-length iteration before the lists must be rebuilt; a
// particle whose h outgrows it searches again at kRegrowSkin times the h
// it reached. With continuity density the CPU keeps its lists across
// evaluations while no particle has moved by more than the skin allows
// (CpuBackend::search_still_holds).
// Issue #14: with 15 % the CPU's lists held 88 entries per particle in 3-D
// for 58 inside the support, and the density and force loops walked them
// all; at 5 % they hold ~67, the 3-D Sedov blast needs no extra rebuild (48
// searches in 48 evaluations at 32^3), and the results are those of a
// wider search (entries outside the support add exact zeros).
namespace rubble {

inline constexpr double kSearchSkin = 1.05;
inline constexpr double kRegrowSkin = 1.3;

}  // namespace rubble
