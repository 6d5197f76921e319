#include "lazyboe/bundle/builder.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "lazyboe/common/checkpoint.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/progress.h"
#include "lazyboe/common/version.h"

namespace lazyboe {

const char* EdgeAttempt::reason() const {
  return start_found ? rollout_status_name(status) : "start_in_collision";
}

namespace {

std::vector<double> to_std(const JointVector& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

// Start-state stream of an attempt: the same generator as the attempt's, drawn first.
bool sample_start(const Simulator& sim, SimulatorWorkspace& ws, const BuildSettings& s, Random& rng,
                  JointVector& q0, uint64_t& resamples) {
  const int n = sim.robot.dof;
  q0.resize(n);
  for (int tries = 0; tries < kMaxStartSamples; ++tries) {
    for (int i = 0; i < n; ++i) q0[i] = rng.uniform(s.region_lower[i], s.region_upper[i]);
    if (check_state(sim, ws, q0) == RolloutStatus::Valid) return true;
    ++resamples;
  }
  return false;
}

void append_edge(Bundle& b, const EdgeAttempt& e, uint64_t attempt) {
  const int n = b.dof();
  b.q0.insert(b.q0.end(), e.q0.data(), e.q0.data() + n);
  b.qf.insert(b.qf.end(), e.qf.data(), e.qf.data() + n);
  b.duration.push_back(e.duration);
  b.command_duration.push_back(e.command_duration);
  b.attempt.push_back(attempt);
  b.knots.insert(b.knots.end(), e.knots.begin(), e.knots.end());
  b.knot_offset.push_back(b.knots.size() / n);
  b.sample_q.insert(b.sample_q.end(), e.sample_q.begin(), e.sample_q.end());
  b.sample_dq.insert(b.sample_dq.end(), e.sample_dq.begin(), e.sample_dq.end());
  b.sample_offset.push_back(b.sample_q.size() / n);
}

std::string percent(uint64_t part, uint64_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f%%", whole ? 100.0 * part / whole : 0.0);
  return buf;
}

// The most frequent rejection reason and its count (empty when nothing was rejected).
std::pair<std::string, uint64_t> top_rejection(const BundleHeader& h) {
  std::pair<std::string, uint64_t> top;
  for (const auto& [reason, count] : h.rejected)
    if (count > top.second) top = {reason, count};
  return top;
}

// What to change when most attempts fail for `reason`.
const char* rejection_advice(const std::string& reason) {
  if (reason == "env_collision")
    return "The arm hits the scene: a base that touches the floor needs \"allowed_links\": "
           "[\"@base\"] in the environment, or choose a region clear of the obstacles "
           "(--region)";
  if (reason == "self_collision" || reason == "start_in_collision")
    return "The links touch each other or the scene at the starts: allowed pairs (lazyboe-robot "
           "allowed-pairs), the collision margin, or a region away from contact (--region)";
  if (reason == "torque_rate_limit")
    return "The torques change faster than the config's max_torque_rate allows: lower gains, "
           "a lower --limit-scale, or check the torque-rate limits (lazyboe-robot info)";
  if (reason == "torque_limit")
    return "The controller asks for more torque than the limits: lower gains, a lower "
           "--limit-scale or --velocity-scale, or check the effort limits and masses "
           "(lazyboe-robot info)";
  if (reason == "position_limit")
    return "The motions run into the joint limits: a region away from them (--region) or a "
           "lower --velocity-scale";
  if (reason == "not_settled")
    return "The arm does not come to rest: the controller's gains cannot track (lazyboe-robot "
           "init checks a step on every joint)";
  return "The controller overshoots the limits: a lower --velocity-scale or --limit-scale, or "
         "check the config's limits (lazyboe-robot info)";
}

}  // namespace

void generate_edge(const Simulator& sim, SimulatorWorkspace& ws, const BuildSettings& settings,
                   uint64_t attempt, EdgeAttempt& out) {
  Random rng(settings.seed, attempt);
  out.start_resamples = 0;
  out.sample_q.clear();
  out.sample_dq.clear();
  out.start_found = sample_start(sim, ws, settings, rng, out.q0, out.start_resamples);
  if (!out.start_found) {
    out.duration = out.command_duration = 0;
    return;
  }
  out.command_duration = sample_command_profile(sim.robot, settings.command, rng, out.knots);
  const int n = sim.robot.dof;
  const CommandProfile profile{out.knots.data(), static_cast<int>(out.knots.size() / n), n,
                               out.command_duration};
  const RolloutResult r = simulate(sim, ws, out.q0, profile, {&out.sample_q, &out.sample_dq});
  out.status = r.status;
  out.qf = r.qf;
  out.duration = r.duration;
}

AttemptGenerator::AttemptGenerator(const Simulator& sim, const BuildSettings& settings, int threads)
    : sim_(sim), settings_(settings), threads_(threads > 0 ? threads : omp_get_max_threads()) {
  workspaces_.reserve(threads_);
  for (int t = 0; t < threads_; ++t) workspaces_.emplace_back(sim);
}

void AttemptGenerator::generate(uint64_t first, size_t count, EdgeAttempt* out) {
#pragma omp parallel for num_threads(threads_) schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(count); ++k) {
    generate_edge(sim_, workspaces_[omp_get_thread_num()], settings_, first + k, out[k]);
  }
}

Bundle new_bundle(const RobotModel& robot, const Environment& env, const BuildSettings& s) {
  Bundle b;
  BundleHeader& h = b.header;
  h.tool_version = version();
  h.robot_name = robot.name;
  h.robot_config = robot.files.config;
  h.robot_hash = robot_identity(robot);
  h.env_name = env.name;
  h.env_file = env.path;
  h.env_hash = environment_identity(env);
  h.dof = robot.dof;
  h.seed = s.seed;
  h.target_edges = s.edges;
  h.region_lower = to_std(s.region_lower);
  h.region_upper = to_std(s.region_upper);
  h.min_duration = s.command.min_duration;
  h.max_duration = s.command.max_duration;
  h.knot_interval = s.command.knot_interval;
  h.velocity_scale = s.command.velocity_scale;
  h.limit_scale = s.command.limit_scale;
  h.integrator = integrator_name(s.simulation.integrator);
  h.substeps = s.simulation.substeps;
  h.control_rate = robot.control_rate;
  h.sample_interval = sample_interval_seconds(s.simulation.sample_every, robot.control_rate);
  h.design_theta = s.design_theta;
  b.knot_offset = {0};
  b.sample_offset = {0};
  return b;
}

void check_resume_compatible(const BundleHeader& have, const BundleHeader& want,
                             const std::string& path) {
  auto differs = [&](const std::string& what, const std::string& a, const std::string& b) {
    fail(path, "cannot resume: " + what + " differs (file: " + a + ", now: " + b + ")");
  };
  auto num = [](double v) {
    std::ostringstream o;
    o.precision(17);
    o << v;
    return o.str();
  };
  auto vec = [&](const std::vector<double>& v) {
    std::string s;
    for (double x : v) s += (s.empty() ? "" : ",") + num(x);
    return s;
  };
  if (have.robot_hash != want.robot_hash) {
    differs("robot (config or URDF content)", have.robot_config, want.robot_config);
  }
  if (have.env_hash != want.env_hash)
    differs("environment (file content)", have.env_file, want.env_file);
  if (have.seed != want.seed) differs("--seed", num(have.seed), num(want.seed));
  if (have.region_lower != want.region_lower || have.region_upper != want.region_upper) {
    differs("--region", vec(have.region_lower) + " .. " + vec(have.region_upper),
            vec(want.region_lower) + " .. " + vec(want.region_upper));
  }
  const std::pair<const char*, std::pair<double, double>> params[] = {
      {"--min-duration", {have.min_duration, want.min_duration}},
      {"--max-duration", {have.max_duration, want.max_duration}},
      {"--knot-interval", {have.knot_interval, want.knot_interval}},
      {"--velocity-scale", {have.velocity_scale, want.velocity_scale}},
      {"--limit-scale", {have.limit_scale, want.limit_scale}},
      {"--substeps", {double(have.substeps), double(want.substeps)}},
      {"--sample-interval", {have.sample_interval, want.sample_interval}},
      {"--theta", {have.design_theta, want.design_theta}},
      {"control_rate", {have.control_rate, want.control_rate}}};
  for (const auto& [name, values] : params) {
    if (values.first != values.second) differs(name, num(values.first), num(values.second));
  }
  if (have.integrator != want.integrator) differs("--integrator", have.integrator, want.integrator);
}

void check_region(const Simulator& sim, const BuildSettings& settings) {
  const int n = sim.robot.dof;
  for (int i = 0; i < n; ++i) {
    if (!(settings.region_lower[i] < settings.region_upper[i])) {
      fail("--region", "joint " + std::to_string(i + 1) + ": lower bound must be below upper");
    }
    if (settings.region_lower[i] < sim.robot.q_min[i] ||
        settings.region_upper[i] > sim.robot.q_max[i]) {
      fail("--region", "joint " + std::to_string(i + 1) + " (" + sim.robot.joints[i].name +
                           "): outside the joint limits [" + std::to_string(sim.robot.q_min[i]) +
                           ", " + std::to_string(sim.robot.q_max[i]) + "]");
    }
  }
  SimulatorWorkspace ws(sim);
  Random rng(settings.seed, ~0ULL);  // a stream no attempt uses
  JointVector q(n);
  for (int k = 0; k < 2000; ++k) {
    for (int i = 0; i < n; ++i)
      q[i] = rng.uniform(settings.region_lower[i], settings.region_upper[i]);
    if (check_state(sim, ws, q) == RolloutStatus::Valid) return;
  }
  fail("--region",
       "no collision-free start state found in 2000 samples: the region is (almost) "
       "entirely in collision in this environment");
}

BuildOutcome build_bundle(const Simulator& sim, const BuildSettings& settings, Bundle& bundle,
                          const BuildControl& control) {
  BundleHeader& h = bundle.header;
  const bool local = !control.run_round;
  AttemptGenerator generator(sim, settings, local ? control.threads : 1);
  const size_t round_size =
      local ? std::max<size_t>(64, 32 * static_cast<size_t>(generator.threads()))
            : control.round_attempts;
  if (round_size == 0) fail("build_bundle", "round_attempts must be > 0");
  std::vector<EdgeAttempt> results(round_size);

  Progress progress("lazyboe-build", settings.edges, control.quiet);
  const double wall_before = h.wall_seconds;
  bool last = false;
  Checkpointer checkpoints(control.checkpoint_seconds, [&] {
    h.wall_seconds = wall_before + progress.elapsed();
    if (control.save_progress) control.save_progress(bundle, last);
  });
  auto save = [&](bool complete) {
    h.complete = complete;
    last = true;
    checkpoints.save_now();
  };
  auto status_line = [&]() {
    const auto [reason, count] = top_rejection(h);
    return "valid " + percent(h.valid, h.attempts) +
           (count ? ", top rejection " + reason + " " + percent(count, h.attempts) : "");
  };
  const bool check_hopeless = control.stop_when_hopeless && h.attempts < kHopelessAttempts;

  progress.update(bundle.size(), status_line());
  if (control.progress) control.progress(bundle.size(), settings.edges);
  while (bundle.size() < settings.edges) {
    if (control.stop_requested && control.stop_requested()) {
      progress.finish();
      save(false);
      if (control.stats) *control.stats = checkpoints.stats();
      return BuildOutcome::Interrupted;
    }
    const uint64_t first = h.attempts;
    if (local) {
      generator.generate(first, round_size, results.data());
    } else {
      control.run_round(first, results);
    }
    // Take results in attempt order, up to the attempt that completes the bundle.
    for (size_t k = 0; k < round_size && bundle.size() < settings.edges; ++k) {
      const EdgeAttempt& e = results[k];
      ++h.attempts;
      h.start_resamples += e.start_resamples;
      h.simulated_seconds += e.duration;
      if (e.valid()) {
        append_edge(bundle, e, first + k);
        ++h.valid;
      } else {
        ++h.rejected[e.reason()];
      }
      if (check_hopeless && h.attempts == kHopelessAttempts &&
          h.valid < kHopelessValidShare * kHopelessAttempts && bundle.size() < settings.edges) {
        progress.finish();
        save(false);
        if (control.stats) *control.stats = checkpoints.stats();
        return BuildOutcome::Hopeless;
      }
    }
    progress.update(bundle.size(), status_line());
    if (control.progress) control.progress(bundle.size(), settings.edges);
    if (bundle.size() < settings.edges) checkpoints.save_if_due();
  }
  progress.finish();
  save(true);
  if (control.stats) *control.stats = checkpoints.stats();
  return BuildOutcome::Complete;
}

std::string rejection_diagnosis(const BundleHeader& h) {
  std::vector<std::pair<uint64_t, std::string>> reasons;
  for (const auto& [reason, count] : h.rejected) reasons.emplace_back(count, reason);
  std::sort(reasons.begin(), reasons.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  std::string text = std::to_string(h.valid) + " of " + std::to_string(h.attempts) +
                     " attempts valid (" + percent(h.valid, h.attempts) + ")";
  for (size_t k = 0; k < reasons.size() && k < 3; ++k) {
    text += (k == 0 ? "; most rejected: " : ", ") + reasons[k].second + " " +
            percent(reasons[k].first, h.attempts);
  }
  if (!reasons.empty()) text += std::string(". ") + rejection_advice(reasons.front().second);
  return text;
}

}  // namespace lazyboe
