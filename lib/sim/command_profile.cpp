#include "lazyboe/sim/command_profile.h"

#include <algorithm>
#include <cmath>

namespace lazyboe {
namespace {

// Peak |s'| and |s''| of the minimum-jerk blend on [0, 1].
constexpr double kPeakSlope = 1.875;
constexpr double kPeakCurvature = 5.773502691896258;  // 10 / sqrt(3)

}  // namespace

double max_knot_speed(const RobotModel& robot, const CommandSampling& sampling, int joint,
                      double h) {
  const double dv_accel = sampling.limit_scale * robot.ddq_max[joint] * h / kPeakSlope;
  const double dv_jerk = sampling.limit_scale * robot.dddq_max[joint] * h * h / kPeakCurvature;
  // Any two knots in [-V, V] differ by at most 2V.
  return std::min(sampling.velocity_scale * robot.dq_max[joint], std::min(dv_accel, dv_jerk) / 2);
}

double sample_command_profile(const RobotModel& robot, const CommandSampling& sampling, Random& rng,
                              std::vector<double>& knots) {
  const double duration = rng.uniform(sampling.min_duration, sampling.max_duration);
  const int intervals =
      std::max(2, static_cast<int>(std::lround(duration / sampling.knot_interval)));
  const double h = duration / intervals;
  const int n = robot.dof;
  knots.assign(static_cast<size_t>(intervals + 1) * n, 0.0);
  for (int i = 0; i < n; ++i) {
    const double v_max = max_knot_speed(robot, sampling, i, h);
    for (int k = 1; k < intervals; ++k) knots[k * n + i] = rng.uniform(-v_max, v_max);
  }
  return duration;
}

namespace {

// evaluate_command with knot times: the interval holding t by binary search, the offset as the
// sum of the whole intervals before it.
void evaluate_timed_command(const CommandProfile& p, double t, double* velocity,
                            double* acceleration, double* offset) {
  const int n = p.dof;
  const int last = p.n_knots - 1;
  const double* times = p.times;
  if (t >= p.duration) {
    for (int i = 0; i < n; ++i) {
      velocity[i] = 0;
      acceleration[i] = 0;
      if (!offset) continue;
      double sum = 0;
      for (int j = 0; j < last; ++j)
        sum += 0.5 * (times[j + 1] - times[j]) * (p.knots[j * n + i] + p.knots[(j + 1) * n + i]);
      offset[i] = sum;
    }
    return;
  }
  const int k = std::max(0, static_cast<int>(std::upper_bound(times, times + last, t) - times) - 1);
  const double h = times[k + 1] - times[k];
  const double tau = std::min(1.0, std::max(0.0, (t - times[k]) / h));
  const double tau2 = tau * tau, tau3 = tau2 * tau;
  const double s = tau3 * (10 - 15 * tau + 6 * tau2);
  const double ds = 30 * tau2 * (1 - 2 * tau + tau2);
  const double S = tau2 * tau2 * (2.5 - 3 * tau + tau2);
  for (int i = 0; i < n; ++i) {
    const double va = p.knots[k * n + i], dv = p.knots[(k + 1) * n + i] - va;
    velocity[i] = va + dv * s;
    acceleration[i] = dv * ds / h;
    if (!offset) continue;
    double sum = 0;
    for (int j = 0; j < k; ++j)
      sum += 0.5 * (times[j + 1] - times[j]) * (p.knots[j * n + i] + p.knots[(j + 1) * n + i]);
    offset[i] = sum + h * (va * tau + dv * S);
  }
}

}  // namespace

void evaluate_command(const CommandProfile& p, double t, double* velocity, double* acceleration,
                      double* offset) {
  if (p.times) {
    evaluate_timed_command(p, t, velocity, acceleration, offset);
    return;
  }
  const int n = p.dof;
  const double h = p.interval();
  const int last = p.n_knots - 1;
  // Integral of each full interval: h (v_k + v_{k+1}) / 2 (the blend integrates to 1/2).
  int k = static_cast<int>(std::floor(t / h));
  if (t >= p.duration || k >= last) {
    for (int i = 0; i < n; ++i) {
      velocity[i] = 0;
      acceleration[i] = 0;
      if (!offset) continue;
      double sum = 0;
      for (int j = 0; j < last; ++j)
        sum += 0.5 * h * (p.knots[j * n + i] + p.knots[(j + 1) * n + i]);
      offset[i] = sum;
    }
    return;
  }
  if (k < 0) k = 0;
  const double tau = std::max(0.0, (t - k * h) / h);
  const double tau2 = tau * tau, tau3 = tau2 * tau;
  const double s = tau3 * (10 - 15 * tau + 6 * tau2);
  const double ds = 30 * tau2 * (1 - 2 * tau + tau2);
  const double S = tau2 * tau2 * (2.5 - 3 * tau + tau2);  // integral of s from 0 to tau
  for (int i = 0; i < n; ++i) {
    const double va = p.knots[k * n + i], dv = p.knots[(k + 1) * n + i] - va;
    velocity[i] = va + dv * s;
    acceleration[i] = dv * ds / h;
    if (!offset) continue;
    double sum = 0;
    for (int j = 0; j < k; ++j) sum += 0.5 * h * (p.knots[j * n + i] + p.knots[(j + 1) * n + i]);
    offset[i] = sum + h * (va * tau + dv * S);
  }
}

}  // namespace lazyboe
