#pragma once
// The smoothing kernels rubble offers (see kernels.hpp for the formulas).
namespace rubble {
enum class KernelType : int { CubicSpline = 0, WendlandC2 = 1, WendlandC4 = 2, WendlandC6 = 3 };
}
