#include "lazyboe/planning/problem.h"

#include <cmath>
#include <cstdio>

#include "lazyboe/common/error.h"

namespace lazyboe {

double Goal::distance(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const {
  if (kind == Kind::Joint) return (state - q).norm();
  forward_kinematics(robot, data, state);
  return (link_pose(robot, data, link).p - position).norm();
}

namespace {

// Which joint is outside its limits (as check_state tests them: strictly inside), by how much,
// and, when the values look like degrees, that they are radians.
std::string limits_issue(const RobotModel& robot, const JointVector& q) {
  std::string out = "outside the joint limits";
  for (int i = 0; i < robot.dof; ++i) {
    if (q[i] > robot.q_min[i] && q[i] < robot.q_max[i]) continue;
    char detail[200];
    std::snprintf(detail, sizeof detail, ": joint %d (%s) is %.6g, its limits (%.6g, %.6g)", i + 1,
                  robot.joints[i].name.c_str(), q[i], robot.q_min[i], robot.q_max[i]);
    out += detail;
    break;
  }
  if (q.cwiseAbs().maxCoeff() > 2 * M_PI) out += " (joint values are in rad, not degrees)";
  return out;
}

ProblemIssue state_issue(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                         const JointVector& q) {
  const int n = sim.robot.dof;
  if (q.size() != n) return {field, "expected " + std::to_string(n) + " joint values"};
  switch (check_state(sim, ws, q)) {
    case RolloutStatus::PositionLimit:
      return {field, limits_issue(sim.robot, q)};
    case RolloutStatus::SelfCollision:
      return {field, "in self-collision"};
    case RolloutStatus::EnvCollision:
      return {field, "in collision with the environment"};
    case RolloutStatus::EndEffectorTilt: {
      const EndEffectorLimits& e = sim.end_effector;
      char what[200];
      std::snprintf(what, sizeof what,
                    "tilts %s's axis %.3g rad from the vertical, more than "
                    "end_effector_limits.max_tilt %.3g rad",
                    sim.robot.links[e.link].name.c_str(), end_effector_tilt(sim.robot, ws.robot, e),
                    e.max_tilt);
      return {field, what};
    }
    default:
      return {};
  }
}

// A position farther from the shoulder than the sum of the joint offsets (plus the link's
// offset in its body) cannot be reached.
bool out_of_reach(const RobotModel& robot, const Goal& g) {
  double reach = 0;
  for (const Joint& j : robot.joints) reach += j.origin.p.norm();
  reach += robot.links[g.link].in_body.p.norm();
  const Eigen::Vector3d shoulder = robot.joints[0].origin.p;
  return (g.position - shoulder).norm() > reach + g.tolerance;
}

}  // namespace

ProblemIssue find_problem_issue(const Simulator& sim, SimulatorWorkspace& ws,
                                const PlanningProblem& p) {
  const RobotModel& robot = sim.robot;
  if (ProblemIssue i = state_issue(sim, ws, "start", p.start); i.any()) return i;
  const Goal& g = p.goal;
  if (g.kind == Goal::Kind::Joint) {
    if (ProblemIssue i = state_issue(sim, ws, "goal.q", g.q); i.any()) return i;
  } else {
    if (g.link < 0 || g.link >= static_cast<int>(robot.links.size()))
      return {"goal.link", "no link " + std::to_string(g.link)};
    if (out_of_reach(robot, g))
      return {"goal.position", "unreachable: farther than the arm can reach"};
  }
  if (!(g.tolerance > 0)) return {"goal.tolerance", "must be > 0"};
  if (g.contains(robot, ws.robot, p.start)) return {"goal", "the start already satisfies the goal"};
  if (!(p.termination.budget > 0 && p.termination.budget <= kMaxBudgetSeconds))
    return {"budget", "must be in (0, 1000000] s"};
  return {};
}

void validate_problem(const Simulator& sim, SimulatorWorkspace& ws, const PlanningProblem& p) {
  const ProblemIssue issue = find_problem_issue(sim, ws, p);
  if (issue.any()) fail(issue.field, issue.what);
}

Trajectory realize_path(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& start,
                        const std::vector<PathStep>& steps, const Goal& goal, int sample_every) {
  const int n = sim.robot.dof;
  Trajectory traj;
  JointVector q = start;
  double t0 = 0;
  std::vector<float> sq, sdq;
  for (size_t k = 0; k < steps.size(); ++k) {
    const PathStep& s = steps[k];
    const CommandProfile profile{s.knots.data(), static_cast<int>(s.knots.size() / n), n,
                                 s.command_duration};
    sq.clear();
    sdq.clear();
    const RolloutResult r = simulate(sim, ws, q, profile, {&sq, &sdq, sample_every});
    if (!r.valid()) {
      fail("path",
           "step " + std::to_string(k) + " fails re-validation: " + rollout_status_name(r.status));
    }
    const size_t rows = sq.size() / n;
    for (size_t i = (k == 0 ? 0 : 1); i < rows; ++i) {  // a step starts where the last ended
      const bool last = i + 1 == rows;
      traj.t.push_back(t0 + (last ? r.duration : static_cast<double>(i * sample_every) * sim.dt));
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
  traj.stops = static_cast<int>(steps.size()) - 1;
  if (steps.empty() || !goal.contains(sim.robot, ws.robot, q)) {
    fail("path", "does not end inside the goal region");
  }
  return traj;
}

}  // namespace lazyboe
