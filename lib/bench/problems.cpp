#include "lazyboe/bench/problems.h"

#include <cstdio>
#include <fstream>

#include "lazyboe/common/atomic_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/file_checks.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {
namespace {

JointVector valid_sample(const Simulator& sim, SimulatorWorkspace& ws, const JointVector& lower,
                         const JointVector& upper, Random& rng) {
  JointVector q(lower.size());
  // The region of a usable bundle is mostly free; a million misses means it is not.
  for (int attempt = 0; attempt < 1000000; ++attempt) {
    for (int i = 0; i < q.size(); ++i) q[i] = rng.uniform(lower[i], upper[i]);
    if (check_state(sim, ws, q) == RolloutStatus::Valid) return q;
  }
  fail("problems", "no collision-free configuration found in the sampling region");
}

// A query line without a seed resolves its goal with seed 1; drawn problems do the same, so that
// a study resumed from its problems.jsonl plans for the same configurations.
constexpr uint64_t kGoalSeed = 1;

// The tip's pose at q as a goal, its configurations resolved from `start`.
Goal pose_goal_at(const Simulator& sim, SimulatorWorkspace& ws, const JointVector& start,
                  const JointVector& q, const ProblemGoals& goals) {
  const RobotModel& robot = sim.robot;
  forward_kinematics(robot, ws.robot, q);
  const Pose pose = link_pose(robot, ws.robot, robot.tip_link());
  Goal g;
  g.kind = Goal::Kind::Pose;
  g.link = robot.tip_link();
  g.position = pose.p;
  g.orientation = Eigen::Quaterniond(pose.R);
  g.tolerance = goals.position_tolerance;
  g.orientation_tolerance = goals.orientation_tolerance;
  resolve_goal(sim, ws, start, kGoalSeed, g, goals.coverage);
  return g;
}

nlohmann::json vector_json(const JointVectorRef& q) {
  return std::vector<double>(q.data(), q.data() + q.size());
}

// A goal in the query format, every kind (a set: its members in order).
nlohmann::json goal_json(const RobotModel& robot, const Goal& g) {
  const auto vec3 = [](const Eigen::Vector3d& v) {
    return std::vector<double>{v.x(), v.y(), v.z()};
  };
  switch (g.kind) {
    case Goal::Kind::Joint:
      return {{"q", vector_json(g.q)}, {"tolerance", g.tolerance}};
    case Goal::Kind::Position:
      return {{"position", vec3(g.position)},
              {"link", robot.links[g.link].name},
              {"tolerance", g.tolerance}};
    case Goal::Kind::Pose: {
      const Eigen::Quaterniond& o = g.orientation;
      nlohmann::json pose = {{"position", vec3(g.position)},
                             {"orientation", {o.w(), o.x(), o.y(), o.z()}},
                             {"link", robot.links[g.link].name}};
      if (g.has_free_axis) pose["free_axis"] = vec3(g.free_axis);
      return {{"pose", pose},
              {"position_tolerance", g.tolerance},
              {"orientation_tolerance", g.orientation_tolerance}};
    }
    case Goal::Kind::Set:
      break;
  }
  nlohmann::json members = nlohmann::json::array();
  for (const Goal& m : g.members) members.push_back(goal_json(robot, m));
  return members;
}

}  // namespace

std::vector<BenchProblem> sample_problems(const Simulator& sim, SimulatorWorkspace& ws,
                                          const JointVector& lower, const JointVector& upper,
                                          int count, double tolerance, uint64_t seed,
                                          const ProblemGoals& goals) {
  std::vector<BenchProblem> problems;
  Random rng(seed, 0x9b0b1e75);  // a stream of its own: problems do not depend on planners
  int redrawn = 0;
  for (int k = 0; k < count; ++k) {
    BenchProblem p;
    p.id = "p" + std::to_string(k);
    p.start = valid_sample(sim, ws, lower, upper, rng);
    do {
      p.goal.q = valid_sample(sim, ws, lower, upper, rng);
    } while ((p.goal.q - p.start).norm() <= tolerance);
    p.goal.kind = Goal::Kind::Joint;
    p.goal.tolerance = tolerance;
    if (goals.pose) {
      p.goal = pose_goal_at(sim, ws, p.start, p.goal.q, goals);
      // A pose whose inverse kinematics finds no valid configuration would be refused as a
      // query (and when the study is resumed from problems.jsonl): drawn again.
      if (p.goal.configurations.empty()) {
        if (++redrawn > 10 * count + 100)
          fail("problems", "inverse kinematics found no valid configuration for the drawn poses");
        --k;
        continue;
      }
    }
    problems.push_back(std::move(p));
  }
  return problems;
}

std::vector<BenchProblem> read_problems(const std::string& path, const Simulator& sim,
                                        SimulatorWorkspace& ws, const QueryDefaults& defaults,
                                        const EndPoseIndexes* coverage) {
  require_input_file(path, "problems");
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::vector<BenchProblem> problems;
  std::string text, id;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    try {
      const Query q = parse_query(text, line, sim, ws, defaults, id, nullptr, coverage);
      for (const BenchProblem& other : problems) {
        if (other.id == q.id) fail("line " + std::to_string(line), "id: '" + q.id + "' repeated");
      }
      problems.push_back({q.id, q.request.problem.start, q.request.problem.goal});
    } catch (const Error& e) {
      fail(path, e.what());
    }
  }
  if (problems.empty()) fail(path, "no problems in the file");
  return problems;
}

void write_problems(const std::string& path, const RobotModel& robot,
                    const std::vector<BenchProblem>& problems) {
  AtomicFile file(path);
  for (const BenchProblem& p : problems) {
    const nlohmann::json line = {
        {"id", p.id}, {"start", vector_json(p.start)}, {"goal", goal_json(robot, p.goal)}};
    file.stream() << line.dump() << "\n";
  }
  file.commit();
}

}  // namespace lazyboe
