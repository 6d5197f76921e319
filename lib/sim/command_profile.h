// Joint-velocity command profiles that vary within an edge (the paper's "varying control
// sequences"): random velocity knots, evenly spaced in time, joined by the minimum-jerk blend
//   v(t) = v_k + (v_{k+1} - v_k) s(tau),  s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5,
// so velocity, acceleration and jerk are continuous, and the profile starts and ends at rest
// (first and last knots are zero). Knot speeds are capped so that the commanded acceleration
// (at most 1.875 |dv| / h) and jerk (at most 5.774 |dv| / h^2) stay within a fraction of the
// robot's limits.
#pragma once

#include <vector>

#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {

struct CommandSampling {
  double min_duration = 0.3;    // s
  double max_duration = 0.7;    // s
  double knot_interval = 0.25;  // nominal spacing of knots, s (at least two intervals per edge)
  double velocity_scale = 0.6;  // knot speed at most this fraction of dq_max
  double limit_scale = 0.8;     // commanded accel and jerk at most this fraction of the limits
};

// A view of one profile: n_knots rows of dof velocities, spanning `duration` seconds, evenly
// spaced (bundle edges, the sampling planners' commands) or, when `times` is given, at those
// increasing times (times[0] = 0, times[n_knots - 1] = duration): a path's edges joined into
// one command (lib/planning/execution.h). The same minimum-jerk blend joins any two knots.
struct CommandProfile {
  const double* knots = nullptr;
  int n_knots = 0;
  int dof = 0;
  double duration = 0;
  const double* times = nullptr;  // n_knots knot times, s; null: evenly spaced
  double interval() const { return duration / (n_knots - 1); }
};

// Draws a profile (duration and knots) into `knots` (resized; reserve to avoid allocating).
double sample_command_profile(const RobotModel& robot, const CommandSampling& sampling, Random& rng,
                              std::vector<double>& knots);

// Velocity, acceleration and the integral of the velocity from t = 0 (the position reference
// offset) at time t; beyond the duration the command is zero and the offset constant. `offset`
// may be null: the simulator does not use it, and its sum over the earlier intervals is the
// costly part (every settle tick summed the whole command).
void evaluate_command(const CommandProfile& profile, double t, double* velocity,
                      double* acceleration, double* offset);

// Largest knot speed allowed for joint i at knot spacing h.
double max_knot_speed(const RobotModel& robot, const CommandSampling& sampling, int joint,
                      double h);

}  // namespace lazyboe
