// Micro-benchmarks of the robot model (issue 2): kinematics, dynamics and collision checking of
// the bundled Panda. Every benchmark cycles through a fixed, seeded pool of random states within
// the joint limits, so the timings are not of one memorised input. Single-threaded.
//
//   ./build/bin/bench_robot --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "lazyboe/sim/rollout_pool.h"
#include "lazyboe/sim/simulator.h"
#include "lazyboe/sim/trajectory_check.h"

namespace {

using namespace lazyboe;

constexpr std::size_t kPoolSize = 1024;  // power of two: the index wraps with a mask
constexpr std::size_t kPoolMask = kPoolSize - 1;
constexpr std::uint64_t kSeed = 20240502;

const RobotModel& robot() {
  static const RobotModel model = load_robot(default_robot_path());
  return model;
}

// Uniform in [lo, hi] per joint.
JointVector uniform(std::mt19937_64& rng, const JointVector& lo, const JointVector& hi) {
  JointVector v(lo.size());
  for (int i = 0; i < lo.size(); ++i)
    v[i] = std::uniform_real_distribution<double>(lo[i], hi[i])(rng);
  return v;
}

struct StatePool {
  std::vector<JointVector> q, dq, ddq, tau;
};

// q in [q_min, q_max], dq in +-dq_max, ddq in +-ddq_max, tau in +-tau_max.
const StatePool& state_pool() {
  static const StatePool pool = [] {
    const RobotModel& m = robot();
    std::mt19937_64 rng(kSeed);
    StatePool p;
    for (std::size_t k = 0; k < kPoolSize; ++k) {
      p.q.push_back(uniform(rng, m.q_min, m.q_max));
      p.dq.push_back(uniform(rng, -m.dq_max, m.dq_max));
      p.ddq.push_back(uniform(rng, -m.ddq_max, m.ddq_max));
      p.tau.push_back(uniform(rng, -m.tau_max, m.tau_max));
    }
    return p;
  }();
  return pool;
}

// A collision scene: the robot against one bundled environment, plus configuration pools.
struct Scene {
  CollisionModel model;
  std::vector<JointVector> free_q;    // collision-free configurations only
  std::vector<JointVector> random_q;  // unfiltered
  double random_collision_fraction = 0;
  double free_acceptance = 0;  // fraction of random draws that were collision-free
};

bool check(const CollisionModel& model, RobotData& rd, CollisionData& cd, const JointVector& q) {
  forward_kinematics(robot(), rd, q);
  update_collision_transforms(model, cd, rd);
  return in_collision(model, cd);
}

Scene make_scene(const std::string& environment_file, std::uint64_t seed) {
  const RobotModel& m = robot();
  Scene s{
      build_collision_model(m, load_environment(data_dir() + "/environments/" + environment_file)),
      {},
      {},
      0,
      0};
  RobotData rd(m);
  CollisionData cd(s.model);
  std::mt19937_64 rng(seed);
  int colliding = 0;
  for (std::size_t k = 0; k < kPoolSize; ++k) {
    s.random_q.push_back(uniform(rng, m.q_min, m.q_max));
    colliding += check(s.model, rd, cd, s.random_q.back());
  }
  s.random_collision_fraction = static_cast<double>(colliding) / kPoolSize;
  std::size_t draws = 0;
  while (s.free_q.size() < kPoolSize) {
    if (++draws > 1000 * kPoolSize) throw std::runtime_error("no collision-free configurations");
    JointVector q = uniform(rng, m.q_min, m.q_max);
    if (!check(s.model, rd, cd, q)) s.free_q.push_back(q);
  }
  s.free_acceptance = static_cast<double>(kPoolSize) / draws;
  return s;
}

const Scene& table_scene() {
  static const Scene scene = make_scene("table.json", kSeed + 1);
  return scene;
}
const Scene& shelf_scene() {
  static const Scene scene = make_scene("shelf.json", kSeed + 2);
  return scene;
}

// ---- Kinematics and dynamics ------------------------------------------------------------------

void BM_ForwardKinematics(benchmark::State& state) {
  const RobotModel& m = robot();
  const StatePool& p = state_pool();
  RobotData data(m);
  std::size_t k = 0;
  for (auto _ : state) {
    forward_kinematics(m, data, p.q[k]);
    benchmark::DoNotOptimize(data.body_pose.back());
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardKinematics);

void BM_InverseDynamics(benchmark::State& state) {
  const RobotModel& m = robot();
  const StatePool& p = state_pool();
  RobotData data(m);
  std::size_t k = 0;
  for (auto _ : state) {
    const JointVector& tau = inverse_dynamics(m, data, p.q[k], p.dq[k], p.ddq[k]);
    benchmark::DoNotOptimize(tau);
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InverseDynamics);

void BM_MassMatrix(benchmark::State& state) {
  const RobotModel& m = robot();
  const StatePool& p = state_pool();
  RobotData data(m);
  std::size_t k = 0;
  for (auto _ : state) {
    const JointMatrix& M = mass_matrix(m, data, p.q[k]);
    benchmark::DoNotOptimize(M);
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MassMatrix);

void BM_ForwardDynamics(benchmark::State& state) {
  const RobotModel& m = robot();
  const StatePool& p = state_pool();
  RobotData data(m);
  std::size_t k = 0;
  for (auto _ : state) {
    const JointVector& ddq = forward_dynamics(m, data, p.q[k], p.dq[k], p.tau[k]);
    benchmark::DoNotOptimize(ddq);
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ForwardDynamics);

// What one simulated tick spends in dynamics: the shared terms (joint poses, mass matrix and its
// factor, gravity, velocity terms with friction) and the accelerations for one torque.
// noinline: callgrind --toggle-collect='*run_dynamics_tick*' isolates the loop.
[[gnu::noinline]] void run_dynamics_tick(benchmark::State& state, const StatePool& p) {
  const RobotModel& m = robot();
  RobotData data(m);
  std::size_t k = 0;
  for (auto _ : state) {
    dynamics_terms(m, data, p.q[k], p.dq[k]);
    const JointVector& ddq = forward_dynamics_from_terms(data, p.tau[k]);
    benchmark::DoNotOptimize(ddq);
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
void BM_DynamicsTick(benchmark::State& state) { run_dynamics_tick(state, state_pool()); }
BENCHMARK(BM_DynamicsTick);

// Whole rollouts as the bundle builder runs them (default settings: semi-implicit Euler at the
// control rate, table.json), replayed from a fixed pool of generated edges. Items are simulated
// ticks, so items_per_second is ticks per second and instructions per tick is the callgrind
// total of run_simulate divided by the "ticks" counter times the iterations.
struct EdgePool {
  Simulator sim;
  std::vector<EdgeAttempt> edges;
};

const EdgePool& edge_pool() {
  static const EdgePool pool = [] {
    const RobotModel& m = robot();
    static const CollisionModel model = table_scene().model;
    BuildSettings settings;
    settings.region_lower = m.region.lower;
    settings.region_upper = m.region.upper;
    settings.seed = kSeed;
    settings.simulation.integrator = Integrator::SemiImplicitEuler;  // lazyboe-build's default
    EdgePool p{Simulator(m, model, settings.simulation), {}};
    SimulatorWorkspace ws(p.sim);
    for (uint64_t a = 0; p.edges.size() < 64; ++a) {
      EdgeAttempt e;
      generate_edge(p.sim, ws, settings, a, e);
      if (e.valid()) p.edges.push_back(std::move(e));
    }
    return p;
  }();
  return pool;
}

[[gnu::noinline]] void run_simulate(benchmark::State& state, const EdgePool& pool) {
  const int dof = robot().dof;
  SimulatorWorkspace ws(pool.sim);
  std::size_t k = 0;
  int64_t ticks = 0;
  for (auto _ : state) {
    const EdgeAttempt& e = pool.edges[k];
    const CommandProfile profile{e.knots.data(), static_cast<int>(e.knots.size() / dof), dof,
                                 e.command_duration};
    const RolloutResult r = simulate(pool.sim, ws, e.q0, profile);
    benchmark::DoNotOptimize(r.qf);
    ticks += r.ticks;
    k = (k + 1) % pool.edges.size();
  }
  state.SetItemsProcessed(ticks);
  state.counters["ticks"] = static_cast<double>(ticks) / static_cast<double>(state.iterations());
}
void BM_SimulateEdge(benchmark::State& state) { run_simulate(state, edge_pool()); }
BENCHMARK(BM_SimulateEdge);

// The trajectory checker on the same edges sampled at every control tick (as lazyboe-query
// --sample-interval 0.001 writes them): items are samples, so items_per_second is samples
// checked per second. Arg 0: without the collision checks.
struct SampledEdges {
  std::vector<std::vector<double>> t, q, dq;
};

const SampledEdges& sampled_edges() {
  static const SampledEdges sampled = [] {
    const EdgePool& pool = edge_pool();
    const int dof = robot().dof;
    SimulatorWorkspace ws(pool.sim);
    SampledEdges out;
    for (const EdgeAttempt& e : pool.edges) {
      const CommandProfile profile{e.knots.data(), static_cast<int>(e.knots.size() / dof), dof,
                                   e.command_duration};
      std::vector<float> sq, sdq;
      simulate(pool.sim, ws, e.q0, profile, {&sq, &sdq, 1});
      out.q.emplace_back(sq.begin(), sq.end());
      out.dq.emplace_back(sdq.begin(), sdq.end());
      for (int i = 0; i < dof; ++i) out.dq.back()[i] = 0;  // the exact start
      std::vector<double> t(sq.size() / dof);
      for (size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * pool.sim.dt;
      out.t.push_back(std::move(t));
    }
    return out;
  }();
  return sampled;
}

void BM_CheckTrajectory(benchmark::State& state) {
  const SampledEdges& edges = sampled_edges();
  TrajectoryCheckOptions options;
  options.check_collision = state.range(0) != 0;
  const TrajectoryChecker checker(robot(), edge_pool().sim.collision, options);
  TrajectoryCheckWorkspace ws(checker);
  std::size_t k = 0;
  int64_t samples = 0;
  for (auto _ : state) {
    const TrajectoryView view{static_cast<int>(edges.t[k].size()), robot().dof, edges.t[k].data(),
                              edges.q[k].data(), edges.dq[k].data()};
    const TrajectoryCheckResult r = check_trajectory(checker, ws, view);
    if (!r.valid) state.SkipWithError("an edge of the pool fails the check");
    samples += r.samples;
    k = (k + 1) % edges.t.size();
  }
  state.SetItemsProcessed(samples);
}
BENCHMARK(BM_CheckTrajectory)->Arg(1)->Arg(0);

// The same rollouts in waves on a RolloutPool, as BoE and LazyBoE run an expansion's rollouts
// (--sim-threads): args are threads and wave size. Items are rollouts, and the time is wall
// time, so threads 2 against 1 at the same wave size is the pool's speed-up.
void BM_RolloutPool(benchmark::State& state) {
  const EdgePool& edges = edge_pool();
  const int dof = robot().dof;
  RolloutPool pool(edges.sim, static_cast<int>(state.range(0)));
  const int wave = static_cast<int>(state.range(1));
  std::vector<RolloutTask> tasks(wave);
  std::vector<RolloutResult> results(wave);
  std::size_t k = 0;
  for (auto _ : state) {
    for (RolloutTask& t : tasks) {
      const EdgeAttempt& e = edges.edges[k];
      t = {e.q0.data(), CommandProfile{e.knots.data(), static_cast<int>(e.knots.size() / dof), dof,
                                       e.command_duration}};
      k = (k + 1) % edges.edges.size();
    }
    pool.run(edges.sim, tasks.data(), results.data(), wave);
    benchmark::DoNotOptimize(results.data());
  }
  state.SetItemsProcessed(state.iterations() * wave);
}
BENCHMARK(BM_RolloutPool)
    ->ArgsProduct({{1, 2}, {2, 16}})
    ->ArgNames({"threads", "wave"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// ---- Collision: forward kinematics + transform update + self and environment check -----------

// noinline: lets a profiler (callgrind --toggle-collect) isolate the timed loop from pool setup.
[[gnu::noinline]] void run_collision_check(benchmark::State& state, const Scene& scene,
                                           const std::vector<JointVector>& pool) {
  const RobotModel& m = robot();
  RobotData rd(m);
  CollisionData cd(scene.model);
  std::size_t k = 0, hits = 0;
  for (auto _ : state) {
    forward_kinematics(m, rd, pool[k]);
    update_collision_transforms(scene.model, cd, rd);
    const bool hit = in_collision(scene.model, cd);
    benchmark::DoNotOptimize(hit);
    hits += hit;
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["colliding"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
  state.counters["self_pairs"] = static_cast<double>(scene.model.self_pairs.size());
  state.counters["env_pairs"] = static_cast<double>(scene.model.env_pairs.size());
}

void BM_CollisionCheck_Table_CollisionFree(benchmark::State& state) {
  run_collision_check(state, table_scene(), table_scene().free_q);
}
BENCHMARK(BM_CollisionCheck_Table_CollisionFree);

void BM_CollisionCheck_Table_Unfiltered(benchmark::State& state) {
  run_collision_check(state, table_scene(), table_scene().random_q);
}
BENCHMARK(BM_CollisionCheck_Table_Unfiltered);

void BM_CollisionCheck_Shelf_CollisionFree(benchmark::State& state) {
  run_collision_check(state, shelf_scene(), shelf_scene().free_q);
}
BENCHMARK(BM_CollisionCheck_Shelf_CollisionFree);

// The exact-distance path: FCL distance on every tested pair, no culling. For reference only.
void BM_MinDistance_Table(benchmark::State& state) {
  const RobotModel& m = robot();
  const Scene& scene = table_scene();
  RobotData rd(m);
  CollisionData cd(scene.model);
  std::size_t k = 0;
  for (auto _ : state) {
    forward_kinematics(m, rd, scene.free_q[k]);
    update_collision_transforms(scene.model, cd, rd);
    const DistanceReport d = min_distance(scene.model, cd);
    benchmark::DoNotOptimize(d);
    k = (k + 1) & kPoolMask;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MinDistance_Table);

}  // namespace
