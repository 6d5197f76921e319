#include "lazyboe/planning/problem.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lazyboe/common/error.h"

namespace lazyboe {

PoseTarget Goal::pose_target() const {
  PoseTarget t;
  t.link = link;
  t.position = position;
  t.position_tolerance = tolerance;
  t.has_orientation = kind == Kind::Pose;
  t.rotation = orientation.normalized().toRotationMatrix();
  t.has_free_axis = has_free_axis;
  t.free_axis = free_axis;
  t.orientation_tolerance = orientation_tolerance;
  return t;
}

std::pair<const JointVector*, double> Goal::nearest_configuration(const JointVectorRef& q) const {
  std::pair<const JointVector*, double> best{nullptr, std::numeric_limits<double>::infinity()};
  for (const JointVector& c : configurations) {
    const double d = (c - q).norm();
    if (d < best.second) best = {&c, d};
  }
  return best;
}

double Goal::distance(const RobotModel& robot, RobotData& data, const JointVectorRef& state) const {
  switch (kind) {
    case Kind::Joint:
      return (state - q).norm();
    case Kind::Position:
      forward_kinematics(robot, data, state);
      return (link_pose(robot, data, link).p - position).norm();
    case Kind::Pose: {
      forward_kinematics(robot, data, state);
      const PoseError e = pose_error(pose_target(), link_pose(robot, data, link));
      return std::max(e.position, e.orientation * tolerance / orientation_tolerance);
    }
    case Kind::Set:
      break;
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Goal& m : members)
    best = std::min(best, m.distance(robot, data, state) * tolerance / m.tolerance);
  return best;
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

// A goal position inside an obstacle's solid: no link origin can get there.
ProblemIssue inside_obstacle(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                             const Eigen::Vector3d& position) {
  const int o = obstacle_at(sim.collision, ws.collision, position);
  if (o < 0) return {};
  return {field, "inside obstacle '" + sim.collision.obstacles[o].name + "'"};
}

ProblemIssue pose_issue(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                        const Goal& g) {
  if (g.link < 0 || g.link >= static_cast<int>(sim.robot.links.size()))
    return {field + ".pose.link", "no link " + std::to_string(g.link)};
  if (!(g.tolerance > 0)) return {field + ".position_tolerance", "must be > 0"};
  if (!(g.orientation_tolerance > 0)) return {field + ".orientation_tolerance", "must be > 0"};
  if (ProblemIssue i = inside_obstacle(sim, ws, field + ".pose.position", g.position); i.any())
    return i;
  if (g.resolved && g.reached == 0) {
    return {field + ".pose",
            "no configuration within the joint limits reaches it within the tolerances (" +
                std::to_string(g.attempts) + " attempts of inverse kinematics)"};
  }
  // Every configuration found that reaches it collides (the link there touches an obstacle, or
  // the arm itself, whichever way the arm reaches it, as far as the search saw) or tilts the
  // carried container beyond the task's limit.
  if (g.resolved && g.configurations.empty()) {
    const std::string found = "every configuration found that reaches it (" +
                              std::to_string(g.reached) + " in " + std::to_string(g.attempts) +
                              " attempts of inverse kinematics) ";
    if (g.tilted == 0) return {field + ".pose", found + "is in collision"};
    char tilt[160];
    std::snprintf(tilt, sizeof tilt, "end_effector_limits.max_tilt %.3g rad",
                  sim.end_effector.max_tilt);
    if (g.tilted == g.reached)
      return {field + ".pose", found + "tilts " + sim.robot.links[sim.end_effector.link].name +
                                   "'s axis beyond " + tilt +
                                   ": the goal's own orientation is tilted more than that"};
    return {field + ".pose", found + "is in collision (" + std::to_string(g.reached - g.tilted) +
                                 ") or tilted beyond " + tilt + " (" + std::to_string(g.tilted) +
                                 ")"};
  }
  return {};
}

ProblemIssue goal_issue(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                        const Goal& g);

// A set is refused only when no member is acceptable (then for its first member's issue).
ProblemIssue set_issue(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                       const Goal& g) {
  if (g.members.empty()) return {field, "an empty goal set"};
  ProblemIssue first;
  for (size_t i = 0; i < g.members.size(); ++i) {
    const ProblemIssue issue =
        goal_issue(sim, ws, field + "[" + std::to_string(i) + "]", g.members[i]);
    if (!issue.any()) return {};
    if (!first.any()) first = issue;
  }
  first.what += " (and no member of the goal set is acceptable)";
  return first;
}

ProblemIssue goal_issue(const Simulator& sim, SimulatorWorkspace& ws, const std::string& field,
                        const Goal& g) {
  switch (g.kind) {
    case Goal::Kind::Joint:
      if (ProblemIssue i = state_issue(sim, ws, field + ".q", g.q); i.any()) return i;
      break;
    case Goal::Kind::Position:
      if (g.link < 0 || g.link >= static_cast<int>(sim.robot.links.size()))
        return {field + ".link", "no link " + std::to_string(g.link)};
      if (out_of_reach(sim.robot, g))
        return {field + ".position", "unreachable: farther than the arm can reach"};
      if (ProblemIssue i = inside_obstacle(sim, ws, field + ".position", g.position); i.any())
        return i;
      break;
    case Goal::Kind::Pose:
      return pose_issue(sim, ws, field, g);
    case Goal::Kind::Set:
      return set_issue(sim, ws, field, g);
  }
  if (!(g.tolerance > 0)) return {field + ".tolerance", "must be > 0"};
  return {};
}

}  // namespace

ProblemIssue find_problem_issue(const Simulator& sim, SimulatorWorkspace& ws,
                                const PlanningProblem& p) {
  if (ProblemIssue i = state_issue(sim, ws, "start", p.start); i.any()) return i;
  if (ProblemIssue i = goal_issue(sim, ws, "goal", p.goal); i.any()) return i;
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
    const CommandProfile profile = s.profile(n);
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
