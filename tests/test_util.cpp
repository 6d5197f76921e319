#include "test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "lazyboe/common/error.h"
#include "lazyboe/common/hash.h"
#include "lazyboe/robot/robot_config.h"

namespace lazyboe::test {

namespace fs = std::filesystem;

std::string source_path(const std::string& relative) {
  return std::string(LAZYBOE_SOURCE_DIR) + "/" + relative;
}

std::string tool_path(const std::string& tool) {
  return std::string(LAZYBOE_TOOLS_DIR) + "/" + tool;
}

Bundle random_bundle(size_t n, int dof, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::uniform_int_distribution<int> knots_per_edge(0, 5), samples_per_edge(1, 12);
  Bundle b;
  BundleHeader& h = b.header;
  h.tool_version = "0.1.0";
  h.complete = true;
  h.robot_name = "panda";
  h.robot_config = "data/robots/panda.json";
  h.robot_hash = fnv1a64_hex("robot" + std::to_string(seed));
  h.env_name = "table \xc3\xa9t\xc3\xa9";  // UTF-8
  h.env_file = "data/environments/table.json";
  h.env_hash = fnv1a64_hex("env");
  h.dof = dof;
  h.seed = seed;
  h.target_edges = 0xfedcba9876543210ull;
  for (int j = 0; j < dof; ++j) {
    h.region_lower.push_back(u(rng) - 3);
    h.region_upper.push_back(u(rng) + 3);
  }
  h.min_duration = 0.2;
  h.max_duration = 1.7;
  h.knot_interval = 0.1;
  h.velocity_scale = 0.55;
  h.limit_scale = 0.8;
  h.control_rate = 1000;
  h.sample_interval = 0.01;
  h.design_theta = 0.3;
  h.attempts = 123456789012ull;
  h.valid = n;
  h.rejected = {
      {"collision", 17}, {"joint_limit", 4}, {"torque_limit", 0}, {"unstable settle", 99}};
  h.start_resamples = 77;
  h.integrator = "rk4";
  h.substeps = 3;
  h.simulated_seconds = 1234.5678;
  h.wall_seconds = 0.1 + 0.2;

  b.knot_offset.push_back(0);
  b.sample_offset.push_back(0);
  for (size_t k = 0; k < n; ++k) {
    for (int j = 0; j < dof; ++j) {
      b.q0.push_back(u(rng));
      b.qf.push_back(u(rng));
    }
    b.duration.push_back(u(rng) + 4);
    b.command_duration.push_back(u(rng) + 3);
    b.attempt.push_back(rng());
    const int nk = knots_per_edge(rng), ns = samples_per_edge(rng);
    for (int r = 0; r < nk * dof; ++r) b.knots.push_back(u(rng));
    for (int r = 0; r < ns * dof; ++r) {
      b.sample_q.push_back(static_cast<float>(u(rng)));
      b.sample_dq.push_back(static_cast<float>(u(rng)));
    }
    b.knot_offset.push_back(b.knot_offset.back() + nk);
    b.sample_offset.push_back(b.sample_offset.back() + ns);
  }
  if (!b.knots.empty()) b.knots[0] = -0.0;  // signs of zero survive too
  return b;
}

Bundle viewable_bundle(size_t n, int dof, uint64_t seed) {
  Bundle b = random_bundle(n, dof, seed);
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  b.knots.clear();
  b.knot_offset = {0};
  for (size_t k = 0; k < n; ++k) {
    const uint64_t nk = 2 + k % 4;
    for (uint64_t r = 0; r < nk * static_cast<uint64_t>(dof); ++r) b.knots.push_back(u(rng));
    b.knot_offset.push_back(b.knot_offset.back() + nk);
  }
  Perturbation& p = b.perturbation;
  p.present = true;
  p.complete = true;
  p.theta = 0.3;
  p.perturbations = 4;
  p.seed = 5;
  for (size_t k = 0; k < n; ++k) {
    const uint64_t valid = k % 5, lazy = valid / 2, collision = 4 - valid;
    p.done.push_back(4);
    p.valid.push_back(valid);
    p.lazy.push_back(lazy);
    p.collision.push_back(collision);
    p.max_error.push_back(valid ? u(rng) + 3 : std::nan(""));
    p.p_lazy_prop.push_back(valid ? static_cast<double>(lazy) / valid : 0.0);
    p.p_collision.push_back(collision / 4.0);
  }
  return b;
}

std::string robot_load_error(const std::string& config_path) {
  try {
    load_robot(config_path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const RobotModel& panda() {
  static const RobotModel model = load_robot(source_path("data/robots/panda.json"));
  return model;
}

Scene::Scene(const std::string& env_name, SimulationOptions options)
    : robot(panda()),
      env(load_environment(source_path("data/environments/" + env_name + ".json"))),
      collision(build_collision_model(robot, env)),
      sim(robot, collision, options) {}

namespace {
struct TempDir {
  std::string path;
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "lazyboe-test-XXXXXX").string();
    path = ::mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};
}  // namespace

std::string temp_dir() {
  static TempDir dir;
  return dir.path;
}

std::string write_temp_file(const std::string& name, const std::string& content) {
  const std::string path = temp_dir() + "/" + name;
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << content;
  return path;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult run(const std::string& command) {
  const std::string out = temp_dir() + "/cmd.out", err = temp_dir() + "/cmd.err";
  const int status = std::system((command + " >" + out + " 2>" + err).c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_file(out);
  r.err = read_file(err);
  return r;
}

double time_scale() {
  const char* s = std::getenv("LAZYBOE_TEST_TIME_SCALE");
  const double v = s ? std::atof(s) : 1.0;
  return v > 0 ? v : 1.0;
}

std::string watchdog(double seconds) {
  return "timeout -s KILL " + std::to_string(seconds * time_scale()) + " ";
}

}  // namespace lazyboe::test
