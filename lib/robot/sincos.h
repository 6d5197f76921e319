#pragma once

// Inline sin and cos for joint angles (update_joint_poses).

#include <cmath>
#include <cstdint>
#include <cstring>

namespace lazyboe {

// sin and cos of a joint angle, for the joint poses (update_joint_poses), which every simulated
// tick and every collision check computes: libm's sincos is about 120 instructions, this about
// half. x = k pi/2 + r with |r| <= pi/4 (pi/2 in three parts, the first two short enough that k
// times them is exact), then the Taylor series of sin r to r^17 and cos r to r^18 (truncation
// below 1e-19) and the quadrant of k. Within 2 ulp of std::sin and std::cos
// (tests/test_kinematics.cpp); beyond |x| = 1e5 (and for NaN) it calls them.
inline void joint_sincos(double x, double& sin_x, double& cos_x) {
  if (!(std::abs(x) < 1e5)) {
    sin_x = std::sin(x);
    cos_x = std::cos(x);
    return;
  }
  constexpr double kShift = 0x1.8p52;  // adding it rounds to an integer in the low bits
  const double shifted = x * 0x1.45f306dc9c883p-1 + kShift;  // x 2/pi
  std::uint64_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  const auto k = static_cast<std::uint32_t>(bits);  // k mod 2^32, enough for the quadrant
  const double kd = shifted - kShift;
  const double r =
      ((x - kd * 0x1.921fb54400000p+0) - kd * 0x1.0b4611a600000p-34) - kd * 0x1.3198a2e037073p-69;
  // Taylor coefficients of sin r = r + r^3 (a0 + a1 r^2 + ...), cos r = 1 - r^2/2 + r^4 (b0 + ...).
  constexpr double kSin[] = {
      -1.0 / 6,        1.0 / 120,        -1.0 / 5040,          1.0 / 362880,
      -1.0 / 39916800, 1.0 / 6227020800, -1.0 / 1307674368000, 1.0 / 355687428096000};
  constexpr double kCos[] = {
      1.0 / 24,        -1.0 / 720,         1.0 / 40320,          -1.0 / 3628800,
      1.0 / 479001600, -1.0 / 87178291200, 1.0 / 20922789888000, -1.0 / 6402373705728000};
  const double z = r * r;
  double ps = kSin[7], pc = kCos[7];
  for (int i = 6; i >= 0; --i) {  // Horner in z
    ps = kSin[i] + z * ps;
    pc = kCos[i] + z * pc;
  }
  const double s = r + r * z * ps;
  const double c = 1.0 - 0.5 * z + z * z * pc;
  switch (k & 3) {
    case 0:
      sin_x = s;
      cos_x = c;
      break;
    case 1:
      sin_x = c;
      cos_x = -s;
      break;
    case 2:
      sin_x = -s;
      cos_x = -c;
      break;
    default:
      sin_x = -c;
      cos_x = s;
      break;
  }
}

}  // namespace lazyboe
