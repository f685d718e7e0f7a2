#pragma once
// Floating-point type of every particle field. Double by default; the CMake
// option RUBBLE_FLOAT=ON switches to single precision so that the ladder can
// report what that costs.
namespace rubble {
#if defined(RUBBLE_USE_FLOAT)
using Real = float;
#else
using Real = double;
#endif
}  // namespace rubble
