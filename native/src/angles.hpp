// Angle conventions of the contract.
#pragma once

#include <cmath>

namespace rrosfuzz {

constexpr double kPi = 3.14159265358979323846;

// Continuous joints live in (-pi, pi]: r = fmod(v, 2pi), then one shift.
inline double normalize_angle(double v) {
  double r = std::fmod(v, 2.0 * kPi);
  if (r <= -kPi) {
    r += 2.0 * kPi;
  } else if (r > kPi) {
    r -= 2.0 * kPi;
  }
  return r;
}

}  // namespace rrosfuzz
