// Measures how a payload changes what a bundle built without it predicts (issue 29,
// docs/performance.md): per payload mass, a sample of edges re-simulated from their own start
// (does the command stay valid, how far does its end move) and from p perturbed starts drawn as
// lazyboe-perturb draws them (P_lazy_prop: valid rollouts ending within theta/2 of the stored
// end; the displacement-transfer residual |q^_f - (qf + d)| and P_lazy_prop under transfer).
// Not a test: it prints figures. The bundle's own perturbation analysis is not read.
//
//   measure_payload BUNDLE [--edges 2000] [--perturbations 8] [--seed 1] [--com 0.05]
//                   [--masses 0,1,2,3]
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "lazyboe/bundle/perturbation.h"
#include "lazyboe/common/error.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/robot/payload.h"

namespace {

using namespace lazyboe;

struct Args {
  std::string bundle;
  size_t edges = 2000;
  uint64_t perturbations = 8, seed = 1;
  double com = 0.05;
  std::vector<double> masses = {0, 1, 2, 3};
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    const bool value = i + 1 < argc;
    if (s == "--edges" && value) {
      a.edges = std::strtoull(argv[++i], nullptr, 10);
    } else if (s == "--perturbations" && value) {
      a.perturbations = std::strtoull(argv[++i], nullptr, 10);
    } else if (s == "--seed" && value) {
      a.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (s == "--com" && value) {
      a.com = std::atof(argv[++i]);
    } else if (s == "--masses" && value) {
      a.masses.clear();
      std::stringstream list(argv[++i]);
      for (std::string m; std::getline(list, m, ',');) a.masses.push_back(std::atof(m.c_str()));
    } else if (a.bundle.empty() && s.rfind("--", 0) != 0) {
      a.bundle = s;
    } else {
      fail("measure_payload", "unknown or incomplete option '" + s + "'");
    }
  }
  if (a.bundle.empty()) fail("usage", "measure_payload BUNDLE [--edges N] [--masses 0,1,2,3]");
  if (a.edges < 1) fail("--edges", "must be a whole number >= 1");
  if (a.perturbations < 1) fail("--perturbations", "must be a whole number >= 1");
  return a;
}

// One edge's rollouts with the payload.
struct EdgeFigures {
  bool own_valid = false;  // the command from the edge's own start
  double own_error = 0;    // |q^_f - qf| of that rollout (valid only)
  uint64_t valid = 0, lazy = 0, transfer_lazy = 0;
  double transfer_max = 0;  // over the valid perturbations
};

EdgeFigures measure_edge(const Simulator& sim, SimulatorWorkspace& ws, const BundleView& b,
                         size_t e, const PerturbSettings& s) {
  EdgeFigures f;
  const Eigen::Map<const JointVector> q0(b.q0(e), b.dof()), qf(b.qf(e), b.dof());
  const CommandProfile command = b.command(e);
  const RolloutResult own = simulate(sim, ws, q0, command);
  f.own_valid = own.status == RolloutStatus::Valid;
  if (f.own_valid) f.own_error = (own.qf - qf).norm();
  for (uint64_t j = 0; j < s.perturbations; ++j) {
    const JointVector d = perturbation_offset(s, b.dof(), e, j);
    const RolloutResult r = simulate(sim, ws, q0 + d, command);
    if (r.status != RolloutStatus::Valid) continue;
    ++f.valid;
    f.lazy += (r.qf - qf).norm() < s.theta / 2;
    const double transfer = (r.qf - (qf + d)).norm();
    f.transfer_lazy += transfer < s.theta / 2;
    f.transfer_max = std::max(f.transfer_max, transfer);
  }
  return f;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
}

void measure_mass(const PlanningSession& session, const std::vector<size_t>& edges, double mass,
                  const Args& a) {
  Task task;
  if (mass > 0) {
    task.payload.link = session.robot.tip_link();
    task.payload.mass = mass;
    task.payload.com = Eigen::Vector3d(0, 0, a.com);
  }
  const WorldPtr world = session.scenes.with_task(session.scenes.default_world(), task);
  PerturbSettings s;
  s.theta = session.default_theta();
  s.perturbations = a.perturbations;
  s.seed = a.seed;
  std::vector<EdgeFigures> figures(edges.size());
#pragma omp parallel
  {
    SimulatorWorkspace ws(world->sim);
#pragma omp for schedule(dynamic, 8)
    for (long k = 0; k < static_cast<long>(edges.size()); ++k)
      figures[k] = measure_edge(world->sim, ws, session.bundle, edges[k], s);
  }
  size_t own_valid = 0;
  std::vector<double> own_error, transfer_max, p_lazy, p_transfer;
  uint64_t valid = 0;
  for (const EdgeFigures& f : figures) {
    own_valid += f.own_valid;
    if (f.own_valid) own_error.push_back(f.own_error);
    valid += f.valid;
    if (f.valid == 0) continue;
    transfer_max.push_back(f.transfer_max);
    p_lazy.push_back(static_cast<double>(f.lazy) / f.valid);
    p_transfer.push_back(static_cast<double>(f.transfer_lazy) / f.valid);
  }
  const auto mean = [](const std::vector<double>& v) {
    double sum = 0;
    for (const double x : v) sum += x;
    return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
  };
  std::printf("| %.1f kg | %.1f%% | %.4f / %.4f | %.1f%% | %.3f | %.4f / %.4f / %.4f | %.3f |\n",
              mass, 100.0 * own_valid / edges.size(), quantile(own_error, 0.5),
              quantile(own_error, 0.9), 100.0 * valid / (edges.size() * a.perturbations),
              mean(p_lazy), quantile(transfer_max, 0.5), quantile(transfer_max, 0.9),
              quantile(transfer_max, 1.0), mean(p_transfer));
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    const PlanningSession session(a.bundle, true, "", "");
    std::vector<size_t> edges;
    const size_t step = std::max<size_t>(1, session.bundle.size() / a.edges);
    for (size_t e = 0; e < session.bundle.size() && edges.size() < a.edges; e += step)
      edges.push_back(e);
    std::printf(
        "%s: %zu of %zu edges, %llu perturbations each, theta %.3f, payload %.2f m from the "
        "flange, %d threads\n\n",
        a.bundle.c_str(), edges.size(), session.bundle.size(),
        static_cast<unsigned long long>(a.perturbations), session.default_theta(), a.com,
        omp_get_max_threads());
    std::printf(
        "| payload | own command valid | own end moved median / p90 (rad) | perturbed valid | "
        "P_lazy_prop | transfer residual (per-edge max) median / p90 / max | P_lazy_prop under "
        "transfer |\n|---|---|---|---|---|---|---|\n");
    for (const double m : a.masses) measure_mass(session, edges, m, a);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "measure_payload: %s\n", e.what());
    return 1;
  }
}
