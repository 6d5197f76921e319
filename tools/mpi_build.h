// lazyboe-build across MPI ranks (mpi_offline.h): rank 0 runs the build; every round it
// broadcasts (first attempt, attempts per rank), each rank r computes attempts
// [first + r x per, first + (r + 1) x per) on its threads, and rank 0 gathers them in order.
// Per valid edge about 1.35 kB travels to rank 0 (its states, knots and samples); per rejected
// attempt 24 bytes.
#pragma once
#ifdef LAZYBOE_HAVE_MPI

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "lazyboe/bundle/builder.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/common/bytes.h"
#include "lazyboe/common/journal.h"
#include "lazyboe/robot/robot_config.h"
#include "mpi_offline.h"

namespace lazyboe::mpi {

// The inputs every rank loads, as rank 0 resolved their paths, with their content hashes (a rank
// that reads other content refuses to compute).
struct SceneInputs {
  std::string robot_path, env_path, robot_hash, env_hash;
};

inline void put_scene_inputs(ByteWriter& w, const std::string& robot_path,
                             const std::string& env_path, const BundleHeader& h) {
  w.put_string(robot_path);
  w.put_string(env_path);
  w.put_string(h.robot_hash);
  w.put_string(h.env_hash);
}

inline SceneInputs get_scene_inputs(ByteReader& r) {
  SceneInputs in;
  in.robot_path = r.get_string();
  in.env_path = r.get_string();
  in.robot_hash = r.get_string();
  in.env_hash = r.get_string();
  return in;
}

// What every rank needs to compute attempts: the inputs and the settings.
inline std::string build_job(const std::string& robot_path, const std::string& env_path,
                             const BundleHeader& h, const BuildSettings& s) {
  std::string out;
  ByteWriter w(out);
  put_scene_inputs(w, robot_path, env_path, h);
  w.put(s.edges);
  w.put(s.seed);
  w.put_array(s.region_lower.data(), s.region_lower.size());
  w.put_array(s.region_upper.data(), s.region_upper.size());
  w.put(s.command);
  w.put(s.simulation);
  w.put(s.design_theta);
  return out;
}

// The robot, environment and simulator a rank rebuilds from a job.
struct RankScene {
  RobotModel robot;
  Environment env;
  std::unique_ptr<CollisionModel> collision;
  std::unique_ptr<Simulator> sim;
};

inline void load_rank_scene(RankScene& scene, const SceneInputs& in,
                            const SimulationOptions& options) {
  scene.robot = load_robot(in.robot_path);
  if (robot_identity(scene.robot) != in.robot_hash)
    fail(in.robot_path, "differs on this rank from rank 0's robot (content hash " +
                            robot_identity(scene.robot) + ", rank 0: " + in.robot_hash + ")");
  scene.env = load_environment(in.env_path);
  if (environment_identity(scene.env) != in.env_hash)
    fail(in.env_path, "differs on this rank from rank 0's environment");
  scene.collision = std::make_unique<CollisionModel>(build_collision_model(scene.robot, scene.env));
  scene.sim = std::make_unique<Simulator>(scene.robot, *scene.collision, options);
}

inline void put_attempt(ByteWriter& w, const EdgeAttempt& e) {
  w.put<uint8_t>(e.start_found);
  w.put<int32_t>(static_cast<int32_t>(e.status));
  w.put(e.start_resamples);
  w.put(e.duration);
  if (!e.valid()) return;
  w.put(e.command_duration);
  w.put_array(e.q0.data(), static_cast<size_t>(e.q0.size()));
  w.put_array(e.qf.data(), static_cast<size_t>(e.qf.size()));
  w.put_vector(e.knots);
  w.put_vector(e.sample_q);
  w.put_vector(e.sample_dq);
}

inline void get_attempt(ByteReader& r, EdgeAttempt& e) {
  e.start_found = r.get<uint8_t>() != 0;
  e.status = static_cast<RolloutStatus>(r.get<int32_t>());
  e.start_resamples = r.get<uint64_t>();
  e.duration = r.get<double>();
  if (!e.valid()) return;
  e.command_duration = r.get<double>();
  const std::vector<double> q0 = r.get_vector<double>(), qf = r.get_vector<double>();
  e.q0 = Eigen::Map<const Eigen::VectorXd>(q0.data(), static_cast<Eigen::Index>(q0.size()));
  e.qf = Eigen::Map<const Eigen::VectorXd>(qf.data(), static_cast<Eigen::Index>(qf.size()));
  e.knots = r.get_vector<double>();
  e.sample_q = r.get_vector<float>();
  e.sample_dq = r.get_vector<float>();
}

// Rank 0: set `control` to spread each round over the ranks, `generator` computing rank 0's
// own share. Call build_job's broadcast first.
inline void distribute_build(BuildControl& control, AttemptGenerator& generator) {
  const size_t per = std::max<size_t>(64, 32 * static_cast<size_t>(generator.threads()));
  control.round_attempts = per * static_cast<size_t>(world().size);
  control.run_round = [&generator, per](uint64_t first, std::vector<EdgeAttempt>& results) {
    uint64_t header[2] = {first, per};
    MPI_Bcast(header, 2, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    generator.generate(first, per, results.data());
    const std::vector<std::string> parts = gather("");
    for (int r = 1; r < world().size; ++r) {
      ByteReader in(parts[r].data(), parts[r].size(), "rank " + std::to_string(r));
      for (size_t k = 0; k < per; ++k) get_attempt(in, results[r * per + k]);
    }
  };
}

// Rank 0, after the build: the other ranks stop.
inline void stop_build_ranks() {
  uint64_t header[2] = {0, 0};
  MPI_Bcast(header, 2, MPI_UINT64_T, 0, MPI_COMM_WORLD);
}

// Ranks other than 0: wait for the job, then compute their share of every round until told to
// stop. An empty job (rank 0 had nothing to build) ends at once.
inline void serve_build(int threads) {
  std::string job;
  broadcast(job);
  if (job.empty()) return;
  ByteReader r(job.data(), job.size(), "job");
  const SceneInputs inputs = get_scene_inputs(r);
  BuildSettings s;
  s.edges = r.get<uint64_t>();
  s.seed = r.get<uint64_t>();
  const std::vector<double> lo = r.get_vector<double>(), hi = r.get_vector<double>();
  s.region_lower = Eigen::Map<const Eigen::VectorXd>(lo.data(), lo.size());
  s.region_upper = Eigen::Map<const Eigen::VectorXd>(hi.data(), hi.size());
  s.command = r.get<CommandSampling>();
  s.simulation = r.get<SimulationOptions>();
  s.design_theta = r.get<double>();
  RankScene scene;
  load_rank_scene(scene, inputs, s.simulation);
  AttemptGenerator generator(*scene.sim, s, threads);
  std::vector<EdgeAttempt> mine;
  std::string bytes;
  for (;;) {
    uint64_t header[2];
    MPI_Bcast(header, 2, MPI_UINT64_T, 0, MPI_COMM_WORLD);
    const uint64_t first = header[0], per = header[1];
    if (per == 0) return;
    mine.resize(per);
    generator.generate(first + world().rank * per, per, mine.data());
    crash_point("rank-round");
    bytes.clear();
    ByteWriter w(bytes);
    for (const EdgeAttempt& e : mine) put_attempt(w, e);
    gather(bytes);
  }
}

}  // namespace lazyboe::mpi

#endif
