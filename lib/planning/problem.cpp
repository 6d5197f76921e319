#include "lazyboe/planning/problem.h"

#include "lazyboe/common/error.h"

namespace lazyboe {

double Goal::distance(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const {
  if (kind == Kind::Joint) return (state - q).norm();
  forward_kinematics(robot, data, state);
  return (link_pose(robot, data, link).p - position).norm();
}

Trajectory realize_path(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                        const std::vector<PathStep>& steps, const Goal& goal, int sample_every) {
  const int n = sim.robot.dof;
  Trajectory traj;
  Simulator sampled(sim.robot, sim.collision, sim.options);
  sampled.options.sample_every = sample_every;
  JointVector q = start;
  double t0 = 0;
  std::vector<float> sq, sdq;
  for (size_t k = 0; k < steps.size(); ++k) {
    const PathStep& s = steps[k];
    const CommandProfile profile{s.knots.data(), static_cast<int>(s.knots.size() / n), n,
                                 s.command_duration};
    sq.clear();
    sdq.clear();
    const RolloutResult r = simulate(sampled, ws, q, profile, {&sq, &sdq});
    if (!r.valid()) {
      fail("path",
           "step " + std::to_string(k) + " fails re-validation: " + rollout_status_name(r.status));
    }
    const size_t rows = sq.size() / n;
    for (size_t i = (k == 0 ? 0 : 1); i < rows; ++i) {  // a step starts where the last ended
      const bool last = i + 1 == rows;
      traj.t.push_back(t0 +
                       (last ? r.duration : static_cast<double>(i * sample_every) * sampled.dt));
      // The start and each step's end are exact; samples in between are stored as float32
      // by the simulator (to about 1e-7 rad).
      JointVector qi(n), dqi(n);
      for (int j = 0; j < n; ++j) {
        qi[j] = last ? r.qf[j] : (k == 0 && i == 0) ? start[j] : sq[i * n + j];
        dqi[j] = (k == 0 && i == 0) ? 0.0 : sdq[i * n + j];
      }
      traj.q.push_back(qi);
      traj.dq.push_back(dqi);
    }
    traj.edges.push_back(s.bundle_edge);
    traj.cost += r.path_length;
    t0 += r.duration;
    q = r.qf;
  }
  traj.duration = t0;
  if (steps.empty() || !goal.contains(sim.robot, ws.robot, q)) {
    fail("path", "does not end inside the goal region");
  }
  return traj;
}

}  // namespace lazyboe
