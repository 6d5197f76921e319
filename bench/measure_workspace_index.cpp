// Measures the workspace index of a bundle (issue 26, docs/performance.md): writes it (--write,
// at --cell), then for each scene the marking time and how well the marks predict collisions:
// of the edges as stored (their samples checked, and re-simulated at the control rate with every
// check) and of edges applied shifted from their start by up to theta (as lazysp and LazyBoE's
// transfer apply them). Not a test: it prints figures.
//
//   measure_workspace_index BUNDLE [--write] [--cell 0.05] [--edges 5000] [--seed 1] SCENE...
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "lazyboe/bundle/scene.h"
#include "lazyboe/bundle/settings.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/planning/world.h"

namespace {

using namespace lazyboe;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct Args {
  std::string bundle;
  std::vector<std::string> scenes;
  bool write = false;
  double cell = 0.05;
  size_t edges = 5000;
  uint64_t seed = 1;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--write") {
      a.write = true;
    } else if (s == "--cell" && i + 1 < argc) {
      a.cell = std::atof(argv[++i]);
    } else if (s == "--edges" && i + 1 < argc) {
      a.edges = std::strtoull(argv[++i], nullptr, 10);
    } else if (s == "--seed" && i + 1 < argc) {
      a.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (a.bundle.empty()) {
      a.bundle = s;
    } else {
      a.scenes.push_back(s);
    }
  }
  return a;
}

// Counts of one prediction: marked or not, against collided or not.
struct Confusion {
  size_t tp = 0, fn = 0, fp = 0, tn = 0;
  void add(bool marked, bool collided) {
    (marked ? (collided ? tp : fp) : (collided ? fn : tn)) += 1;
  }
  void print(const char* what) const {
    const double collided = static_cast<double>(tp + fn), free = static_cast<double>(fp + tn);
    std::printf(
        "  %-28s n %6zu  collide %6zu  FN %4zu (%.2f%% of colliding)  FP %6zu (%.1f%% of free)\n",
        what, tp + fn + fp + tn, tp + fn, fn, collided ? 100.0 * fn / collided : 0.0, fp,
        free ? 100.0 * fp / free : 0.0);
  }
};

bool samples_collide(const BundleView& b, const RobotModel& robot, const CollisionModel& cm,
                     size_t e, RobotData& rd, CollisionData& cd) {
  JointVector q(b.dof());
  for (size_t i = 0; i < b.sample_count(e); ++i) {
    for (int j = 0; j < b.dof(); ++j) q[j] = b.samples(e)[i * b.dof() + j];
    forward_kinematics(robot, rd, q);
    update_collision_transforms(cm, cd, rd);
    if (check_collision(cm, cd).env_collision) return true;
  }
  return false;
}

void measure_scene(const PlanningSession& session, const WorkspaceIndex& index,
                   const std::string& scene, const Args& a) {
  const WorldPtr world = session.scenes.load(scene);
  EdgeMarks marks;
  std::vector<double> times;
  for (int k = 0; k < 7; ++k) {
    marks = mark_edges(index, session.robot, world->env, world->collision);
    times.push_back(marks.seconds);
  }
  std::sort(times.begin(), times.end());
  std::printf(
      "%s: %zu objects, %zu occupied cells, marked %zu of %zu edges (%.1f%%), marking "
      "median %.2f ms (min %.2f)\n",
      scene.c_str(), world->env.obstacles.size(), marks.occupied_cells, marks.marked, index.edges(),
      100.0 * marks.marked / index.edges(), 1e3 * times[3], 1e3 * times[0]);
  const BundleView& b = session.bundle;
  std::mt19937_64 rng(a.seed);
  std::vector<size_t> edges(b.size());
  for (size_t e = 0; e < b.size(); ++e) edges[e] = e;
  std::shuffle(edges.begin(), edges.end(), rng);
  edges.resize(std::min(a.edges, edges.size()));
  RobotData rd(session.robot);
  CollisionData cd(world->collision);
  SimulatorWorkspace ws(world->sim);
  Confusion stored, simulated;
  const double theta = session.default_theta();
  const double shifts[] = {0.25, 0.5, 0.75, 1.0};
  Confusion shifted[4];
  std::normal_distribution<double> normal;
  for (const size_t e : edges) {
    const bool marked = marks.may_collide(e);
    stored.add(marked, samples_collide(b, session.robot, world->collision, e, rd, cd));
    const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(b.q0(e), b.dof());
    const RolloutResult exact = simulate(world->sim, ws, q0, b.command(e));
    simulated.add(marked, exact.status == RolloutStatus::EnvCollision);
    for (int s = 0; s < 4; ++s) {
      JointVector d(b.dof());
      for (int j = 0; j < b.dof(); ++j) d[j] = normal(rng);
      d *= shifts[s] * theta / d.norm();  // on the sphere of that radius
      const RolloutResult r = simulate(world->sim, ws, q0 + d, b.command(e));
      if (r.status == RolloutStatus::Valid || r.status == RolloutStatus::EnvCollision)
        shifted[s].add(marked, r.status == RolloutStatus::EnvCollision);
    }
  }
  stored.print("stored samples");
  simulated.print("re-simulated (control rate)");
  for (int s = 0; s < 4; ++s) {
    char what[64];
    std::snprintf(what, sizeof what, "shifted by %.2f theta", shifts[s]);
    shifted[s].print(what);
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    if (a.bundle.empty())
      fail("usage", "measure_workspace_index BUNDLE [--write] [--cell C] SCENE...");
    const PlanningSession session(a.bundle, true, "", "");
    if (a.write) {
      const auto t = Clock::now();
      WorkspaceIndexOptions options;
      options.cell = a.cell;
      const WorkspaceIndexSummary s = write_workspace_index(session.bundle, session.robot, options);
      std::printf(
          "wrote %s: cell %.3f m, grid %dx%dx%d, %zu links, %llu entries, %.1f MB "
          "(bundle %.1f MB), %.1f s\n",
          workspace_index_path(a.bundle).c_str(), s.grid.cell, s.grid.dims[0], s.grid.dims[1],
          s.grid.dims[2], s.links, static_cast<unsigned long long>(s.entries), s.bytes / 1e6,
          std::filesystem::file_size(a.bundle) / 1e6, since(t));
    }
    const auto t = Clock::now();
    const std::shared_ptr<const WorkspaceIndex> index =
        WorkspaceIndex::open(session.bundle, session.robot, true);
    std::printf("opened in %.1f ms\n", 1e3 * since(t));
    for (const std::string& scene : a.scenes) measure_scene(session, *index, scene, a);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "measure_workspace_index: %s\n", e.what());
    return 1;
  }
}
