#include "planning_fixture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/registry.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe::test {

std::vector<double> vec(const JointVectorRef& q) {
  return std::vector<double>(q.data(), q.data() + q.size());
}
JointVector joint(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::string str(const JointVectorRef& q) {
  std::ostringstream s;
  s.precision(17);
  s << "[";
  for (Eigen::Index i = 0; i < q.size(); ++i) s << (i ? ", " : "") << q[i];
  return s.str() + "]";
}

SimulationOptions options_of(const BundleHeader& h) {
  SimulationOptions o;
  o.integrator = parse_integrator(h.integrator, "integrator");
  o.substeps = h.substeps;
  o.sample_every = 0;
  return o;
}

// ------------------------------------------------------------------------------------------
// The bundle through the library
// ------------------------------------------------------------------------------------------

namespace {

// kRegion read as lazyboe-build reads --region lo:hi pairs (so the bounds are the same doubles).
void region_of(const std::string& text, int dof, JointVector& lower, JointVector& upper) {
  lower.resize(dof);
  upper.resize(dof);
  std::stringstream ss(text);
  std::string item;
  int i = 0;
  while (std::getline(ss, item, ',')) {
    double lo = 0, hi = 0;
    char colon = 0;
    std::istringstream is(item);
    if (!(is >> lo >> colon >> hi) || colon != ':' || i >= dof)
      throw std::runtime_error("bad region item '" + item + "'");
    lower[i] = lo;
    upper[i] = hi;
    ++i;
  }
  if (i != dof) throw std::runtime_error("the region has " + std::to_string(i) + " pairs");
}

}  // namespace

SmallBundles build_small_bundles() {
  const RobotModel robot = load_robot(default_robot_path());
  const Environment env = load_environment(default_environment_path());
  const CollisionModel collision = build_collision_model(robot, env);

  // lazyboe-build --edges kEdges --region=kRegion --theta kTheta: its defaults otherwise, which
  // differ from the library's in the integrator (euler) and the sampling (--sample-interval 0.05).
  BuildSettings s;
  s.edges = kEdges;
  s.design_theta = kTheta;
  s.simulation.integrator = Integrator::SemiImplicitEuler;
  s.simulation.sample_every = static_cast<int>(std::lround(0.05 * robot.control_rate));
  region_of(kRegion, robot.dof, s.region_lower, s.region_upper);
  const Simulator sim(robot, collision, s.simulation);
  check_region(sim, s);
  Bundle built = new_bundle(robot, env, s);
  BuildControl build;
  build.quiet = true;
  if (build_bundle(sim, s, built, build) != BuildOutcome::Complete)
    throw std::runtime_error("the in-memory build did not complete");

  // lazyboe-perturb --perturbations kPerturbations: theta is the design theta, default seed.
  Bundle perturbed = built;
  PerturbSettings p;
  p.theta = perturbed.header.design_theta;
  p.perturbations = kPerturbations;
  SimulationOptions options = settings_from_header(perturbed.header).simulation;
  options.sample_every = 0;
  const Simulator perturb_sim(robot, collision, options);
  prepare_perturbation(perturbed, p, false, "the in-memory bundle");
  PerturbControl perturb;
  perturb.quiet = true;
  if (run_perturbation(perturb_sim, perturbed, p, perturb) != PerturbOutcome::Complete)
    throw std::runtime_error("the in-memory perturbation analysis did not complete");

  SmallBundles out;
  out.unperturbed = std::make_shared<const Bundle>(std::move(built));
  out.perturbed = std::make_shared<const Bundle>(std::move(perturbed));
  return out;
}

// ------------------------------------------------------------------------------------------
// The fixture
// ------------------------------------------------------------------------------------------

PlanningFixture::PlanningFixture(std::shared_ptr<const Bundle> bundle_, BundleView view_)
    : bundle(std::move(bundle_)),
      data(*bundle),
      robot(load_robot(data.header.robot_config)),
      env(load_environment(data.header.env_file)),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options_of(data.header)),
      view(std::move(view_)) {
  const int n = data.dof();
  const JointVector centre =
      (joint(data.header.region_lower) + joint(data.header.region_upper)) / 2;
  std::vector<size_t> order(data.size());
  for (size_t e = 0; e < order.size(); ++e) order[e] = e;
  auto start = [&](size_t e) {
    return joint(std::vector<double>(&data.q0[e * n], &data.q0[e * n] + n));
  };
  std::sort(order.begin(), order.end(), [&](size_t x, size_t y) {
    return (start(x) - centre).norm() < (start(y) - centre).norm();
  });
  for (size_t i = 0; i < 60 && a.size() == 0; ++i) {
    for (size_t j = i + 1; j < 60; ++j) {
      const double d = (start(order[i]) - start(order[j])).norm();
      if (d >= 0.35 && d <= 0.45) {
        a = start(order[i]);
        b = start(order[j]);
        break;
      }
    }
  }
  if (a.size() == 0)
    throw std::runtime_error("no easy start/goal pair among the bundle's edge starts");
  for (size_t i = 0; i < order.size() && c.size() == 0; ++i) {
    const double d = (start(order[i]) - a).norm();
    if (d >= 0.7 && d <= 0.85) c = start(order[i]);
  }
  if (c.size() == 0) throw std::runtime_error("no edge start 0.7-0.85 rad from the easy start");
}

JointVector PlanningFixture::edge_start(size_t e) const {
  const int n = data.dof();
  return joint(std::vector<double>(&data.q0[e * n], &data.q0[e * n] + n));
}

std::vector<std::string> own_planners() {
  std::vector<std::string> names;
  for (const PlannerInfo& info : planner_registry())
    if (!info.needs.ompl) names.push_back(info.name);
  return names;
}

bool is_bundle_planner(const std::string& planner) {
  const PlannerInfo* info = find_planner(planner);
  return info && info->needs.bundle;
}

ParameterValues searching(const std::string& planner, ParameterValues values) {
  const PlannerInfo* info = find_planner(planner);
  if (info && info->parameter("direct")) values.set("direct", 0);
  if (info && info->parameter("connect_radius") && !values.has("connect_radius"))
    values.set("connect_radius", 0);
  if (info && info->parameter("candidate_shortcut") && !values.has("candidate_shortcut"))
    values.set("candidate_shortcut", 0);
  return values;
}

double easy_budget(const std::string& planner) { return is_bundle_planner(planner) ? 1.5 : 3.0; }

// ------------------------------------------------------------------------------------------
// Independent re-validation of a trajectory
// ------------------------------------------------------------------------------------------

Trajectory trajectory_from_json(const nlohmann::json& r) {
  Trajectory t;
  const nlohmann::json& tj = r.at("trajectory");
  t.t = tj.at("t").get<std::vector<double>>();
  for (const nlohmann::json& row : tj.at("q")) t.q.push_back(joint(row.get<std::vector<double>>()));
  for (const nlohmann::json& row : tj.at("dq"))
    t.dq.push_back(joint(row.get<std::vector<double>>()));
  if (tj.contains("ddq")) {
    for (const nlohmann::json& row : tj.at("ddq"))
      t.ddq.push_back(joint(row.get<std::vector<double>>()));
    for (const nlohmann::json& row : tj.at("cmd"))
      t.cmd.push_back(joint(row.get<std::vector<double>>()));
  }
  t.edges = r.at("edges").get<std::vector<int64_t>>();
  t.duration = r.at("duration").get<double>();
  t.stops = r.value("stops", -1);
  t.cost = r.at("best_cost").get<double>();
  return t;
}

std::string validate(const PlanningFixture& f, const Trajectory& traj, const JointVectorRef& start,
                     const JointVectorRef& goal, double tolerance, const std::string& planner) {
  std::ostringstream p;
  p.precision(17);
  const RobotModel& robot = f.robot;
  const int n = robot.dof;
  const size_t rows = traj.t.size();
  if (rows < 2) return "  fewer than two samples\n";
  if (traj.q.size() != rows || traj.dq.size() != rows) return "  t, q and dq differ in length\n";
  for (size_t k = 0; k < rows; ++k) {
    if (traj.q[k].size() != n || traj.dq[k].size() != n)
      return "  a sample does not have 7 values\n";
  }
  int reported = 0;
  auto report = [&](const std::string& what) {
    if (reported++ < 12) p << "  " << what << "\n";
  };
  // Time.
  if (traj.t[0] != 0) report("t[0] = " + std::to_string(traj.t[0]) + ", expected 0");
  for (size_t k = 1; k < rows; ++k) {
    if (!(traj.t[k] > traj.t[k - 1])) {
      report("t not strictly increasing at sample " + std::to_string(k) + ": " +
             std::to_string(traj.t[k - 1]) + " then " + std::to_string(traj.t[k]));
    }
  }
  if (std::abs(traj.duration - traj.t.back()) > 1e-9) {
    report("duration " + std::to_string(traj.duration) + " differs from the last t " +
           std::to_string(traj.t.back()));
  }
  // Start: exactly the query's start, at rest.
  const double start_error = (traj.q[0] - start).cwiseAbs().maxCoeff();
  if (!(start_error <= 1e-12)) {
    std::ostringstream s;
    s.precision(17);
    s << "first q differs from the query start by " << start_error
      << " rad (max over joints): " << str(traj.q[0]) << " vs " << str(start);
    report(s.str());
  }
  if (!(traj.dq[0].cwiseAbs().maxCoeff() == 0)) report("first dq is not zero: " + str(traj.dq[0]));
  // Goal.
  const double goal_distance = (traj.q.back() - goal).norm();
  if (!(goal_distance <= tolerance)) {
    report("last q is " + std::to_string(goal_distance) + " rad from the goal (tolerance " +
           std::to_string(tolerance) + ")");
  }
  // Limits, collision and continuity at every sample.
  SimulatorWorkspace ws(f.sim);
  for (size_t k = 0; k < rows; ++k) {
    const JointVector& q = traj.q[k];
    const JointVector& dq = traj.dq[k];
    for (int j = 0; j < n; ++j) {
      if (!(q[j] >= robot.q_min[j] && q[j] <= robot.q_max[j])) {
        report("sample " + std::to_string(k) + ": q" + std::to_string(j + 1) + " = " +
               std::to_string(q[j]) + " outside the joint limits");
      }
      if (!(std::abs(dq[j]) <= robot.dq_max[j])) {
        report("sample " + std::to_string(k) + ": dq" + std::to_string(j + 1) + " = " +
               std::to_string(dq[j]) + " beyond the velocity limit");
      }
    }
    const RolloutStatus s = check_state(f.sim, ws, q);
    if (s != RolloutStatus::Valid) {
      report("sample " + std::to_string(k) + " (t = " + std::to_string(traj.t[k]) +
             "): check_state says " + rollout_status_name(s));
    }
    if (k > 0) {
      const double dt = traj.t[k] - traj.t[k - 1];
      for (int j = 0; j < n; ++j) {
        const double jump = std::abs(q[j] - traj.q[k - 1][j]);
        if (jump > robot.dq_max[j] * dt + 1e-6) {
          report("discontinuity between samples " + std::to_string(k - 1) + " and " +
                 std::to_string(k) + ": joint " + std::to_string(j + 1) + " moves " +
                 std::to_string(jump) + " rad in " + std::to_string(dt) + " s");
        }
      }
    }
  }
  // Edges: one per step; bundle edges for the bundle planners, -1 for RRT/SST commands (and
  // for lazysp's growth, which mixes both).
  if (traj.edges.empty()) report("no edges listed");
  for (int64_t e : traj.edges) {
    if (planner == "lazysp" && e == -1) continue;
    if (is_bundle_planner(planner)) {
      if (e < 0 || e >= static_cast<int64_t>(f.view.size()))
        report("edge " + std::to_string(e) + " is not a bundle edge");
    } else if (e != -1) {
      report("edge " + std::to_string(e) + " listed for an " + planner + " command (expected -1)");
    }
  }
  if (reported > 12) p << "  (" << reported - 12 << " more)\n";
  return p.str();
}

std::string resimulate(const PlanningFixture& f, const JointVectorRef& start,
                       const std::vector<CommandProfile>& commands, const Trajectory& traj) {
  std::ostringstream p;
  p.precision(17);
  SimulatorWorkspace ws(f.sim);
  JointVector q = start;
  double time = 0;
  for (size_t k = 0; k < commands.size(); ++k) {
    const RolloutResult r = simulate(f.sim, ws, q, commands[k]);
    if (!r.valid()) {
      p << "  step " << k
        << " fails when simulated from the previous end: " << rollout_status_name(r.status) << "\n";
      return p.str();
    }
    q = r.qf;
    time += r.duration;
  }
  const double error = (q - traj.q.back()).cwiseAbs().maxCoeff();
  if (!(error <= 1e-9)) {
    p << "  re-simulated end " << str(q) << " differs from the trajectory's last q "
      << str(traj.q.back()) << " by " << error << " rad\n";
  }
  if (!(std::abs(time - traj.t.back()) <= 1e-9)) {
    p << "  re-simulated duration " << time << " s differs from the trajectory's " << traj.t.back()
      << " s\n";
  }
  return p.str();
}

std::vector<CommandProfile> bundle_commands(const PlanningFixture& f,
                                            const std::vector<int64_t>& edges) {
  std::vector<CommandProfile> c;
  for (int64_t e : edges) c.push_back(f.view.command(static_cast<size_t>(e)));
  return c;
}

// ------------------------------------------------------------------------------------------
// States outside the bundle's coverage
// ------------------------------------------------------------------------------------------

double nearest_distance(const PlanningFixture& f, const JointVectorRef& q, bool ends) {
  const int n = f.data.dof();
  const std::vector<double>& v = ends ? f.data.qf : f.data.q0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t e = 0; e < f.data.size(); ++e) {
    best = std::min(best, (joint(std::vector<double>(&v[e * n], &v[e * n] + n)) - q).norm());
  }
  return best;
}

JointVector far_state(const PlanningFixture& f, const JointVectorRef& base,
                      const std::vector<double>& offsets, double clearance, bool ends) {
  SimulatorWorkspace ws(f.sim);
  for (double d : offsets) {
    JointVector q = base;
    q[0] += d;
    if (check_state(f.sim, ws, q) == RolloutStatus::Valid &&
        nearest_distance(f, q, ends) > clearance)
      return q;
  }
  return JointVector();
}

JointVector far_start_state(const PlanningFixture& f) {
  return far_state(f, f.a, {1.5, -1.5, 2.0, -2.0, 1.2, -1.2}, f.view.perturbation_theta(), false);
}

JointVector far_goal_state(const PlanningFixture& f) {
  return far_state(f, f.b, {2.2, -2.2, 2.5, -2.5, 1.8, -1.8},
                   f.view.perturbation_theta() + kTolerance, true);
}

}  // namespace lazyboe::test
