// The edge-to-workspace index (issue 26, item 3; workspace_index.h), on the small bundle of the
// planning tests written to a file: in random scenes of primitives, a mesh and a point cloud,
// every edge whose stored samples come closer to an obstacle than the margin is marked (no false
// negative), and every edge whose re-simulation collides; an obstacle's allowed links do not
// mark; the file does not depend on the thread count; a damaged, truncated or foreign index is
// refused with the reason and planning goes on without it until it is rewritten; the bundle's
// own scene keeps the stored P_collision and any other scene gets marks.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "box_files.h"
#include "cli_util.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/error.h"
#include "lazyboe/common/json_fields.h"
#include "lazyboe/planning/planning_session.h"
#include "lazyboe/planning/workspace_index.h"
#include "lazyboe/robot/kinematics.h"
#include "planning_fixture.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct Small {
  std::shared_ptr<const Bundle> bundle = build_small_bundles().unperturbed;
};
const Bundle& small_bundle() { return *shared_fixture<Small>().bundle; }

// The small bundle in a file, with its workspace index written (2 threads).
struct IndexedBundle {
  std::string path;
  IndexedBundle() {
    path = temp_dir() + "/ws-bundle.h5";
    write_bundle(path, small_bundle());
    WorkspaceIndexOptions options;
    options.threads = 2;
    write_workspace_index(BundleView::open(path), panda(), options);
  }
};

const IndexedBundle& indexed() { return shared_fixture<IndexedBundle>(); }

json object(const std::string& name, const std::string& type) {
  return {{"name", name}, {"type", type}};
}

// The table and 3-6 random primitives over it (some turned), and for some seeds a mesh box and a
// point-cloud box: obstacles where the bundle's edges pass.
json random_scene(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  json scene = json::parse(read_file(source_path("data/environments/table.json")));
  scene["name"] = "random-" + std::to_string(seed);
  const char* types[] = {"box", "sphere", "cylinder", "capsule"};
  const int count = 1 + static_cast<int>(seed % 3);
  for (int k = 0; k < count; ++k) {
    json o = object("o" + std::to_string(k), types[(seed + k) % 4]);
    const double s = 0.02 + 0.08 * u(rng);
    if (o["type"] == "box") o["size"] = {s, 0.5 * s + 0.1 * u(rng), s};
    if (o["type"] != "box") o["radius"] = s / 2;
    if (o["type"] == "cylinder" || o["type"] == "capsule") o["length"] = 0.05 + 0.2 * u(rng);
    o["position"] = {0.3 + 0.4 * u(rng), -0.3 + 0.6 * u(rng), 0.3 + 0.5 * u(rng)};
    const json rpy = {u(rng), u(rng), 3 * u(rng)};
    if (o["type"] != "sphere") o["rpy"] = rpy;  // a sphere has no orientation
    scene["objects"].push_back(o);
  }
  BoxFiles box;
  box.centre = {0.35 + 0.3 * u(rng), -0.2 + 0.4 * u(rng), 0.45 + 0.2 * u(rng)};
  box.size = {0.06, 0.05, 0.08};
  box.name = "ws-box-" + std::to_string(seed);
  if (seed % 2 == 0) {
    json mesh = object("mesh", "mesh");
    mesh["file"] = box.obj();
    mesh["position"] = {box.centre[0], box.centre[1], box.centre[2]};
    scene["objects"].push_back(mesh);
  } else {
    json cloud = object("cloud", "points");
    cloud["file"] = box.ply(seed % 4 == 1);
    cloud["resolution"] = 0.02;
    scene["objects"].push_back(cloud);
  }
  return scene;
}

Environment environment(const json& scene) {
  return environment_from_json(JsonField(scene, "scene", ""), "");
}

bool samples_collide(const BundleView& b, const CollisionModel& cm, size_t e, RobotData& rd,
                     CollisionData& cd) {
  JointVector q(b.dof());
  for (size_t i = 0; i < b.sample_count(e); ++i) {
    for (int j = 0; j < b.dof(); ++j) q[j] = b.samples(e)[i * b.dof() + j];
    forward_kinematics(panda(), rd, q);
    update_collision_transforms(cm, cd, rd);
    if (check_collision(cm, cd).env_collision) return true;
  }
  return false;
}

TEST(WorkspaceIndex, MarksEveryEdgeWhoseStoredMotionCollides) {
  const PlanningSession session(indexed().path, true, "", "");
  ASSERT_TRUE(session.workspace.index) << session.workspace.source;
  const BundleView& b = session.bundle;
  size_t colliding = 0, simulated_colliding = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const WorldPtr world = session.scenes.world(environment(random_scene(seed)));
    ASSERT_TRUE(world->edge_marks);
    const EdgeMarks& marks = *world->edge_marks;
    RobotData rd(panda());
    CollisionData cd(world->collision);
    SimulatorWorkspace ws(world->sim);
    for (size_t e = 0; e < b.size(); ++e) {
      if (samples_collide(b, world->collision, e, rd, cd)) {
        ++colliding;
        EXPECT_TRUE(marks.may_collide(e)) << "seed " << seed << ": edge " << e;
      }
      if (e % 8 != 0) continue;  // re-simulation at the control rate, on every 8th edge
      const JointVector q0 = Eigen::Map<const Eigen::VectorXd>(b.q0(e), b.dof());
      if (simulate(world->sim, ws, q0, b.command(e)).status == RolloutStatus::EnvCollision) {
        ++simulated_colliding;
        EXPECT_TRUE(marks.may_collide(e)) << "seed " << seed << ": edge " << e << " (simulated)";
      }
    }
    EXPECT_LT(marks.marked, b.size()) << "seed " << seed << ": a scene that marks everything";
  }
  // The scenes do block edges: the check above is not vacuous.
  EXPECT_GT(colliding, 100u);
  EXPECT_GT(simulated_colliding, 10u);
}

json floor_scene(bool allow_link1) {
  json floor = object("floor", "box");
  floor["size"] = {2.0, 2.0, 0.02};
  floor["position"] = {0, 0, -0.01};
  floor["allowed_links"] = allow_link1 ? json{"panda_link0", "panda_link1"} : json{"panda_link0"};
  return {{"schema_version", 1}, {"name", "floor"}, {"objects", {floor}}};
}

TEST(WorkspaceIndex, AnObstaclesAllowedLinksDoNotMark) {
  const PlanningSession session(indexed().path, true, "", "");
  const WorkspaceIndex& index = *session.workspace.index;
  // panda_link1's capsule reaches below the floor's top: allowed, it marks nothing (the arm
  // stays above the table); not allowed, it marks every edge, as every state collides.
  for (const bool allow : {true, false}) {
    const Environment env = environment(floor_scene(allow));
    const CollisionModel cm = build_collision_model(panda(), env);
    const EdgeMarks marks = mark_edges(index, panda(), env, cm);
    EXPECT_EQ(marks.marked, allow ? 0u : session.bundle.size()) << "allowed link1: " << allow;
  }
}

TEST(WorkspaceIndex, TheBundlesOwnSceneKeepsItsStoredPrior) {
  const PlanningSession session(indexed().path, true, "", "");
  EXPECT_EQ(session.world().edge_marks, nullptr);  // table.json, the build scene
  EXPECT_EQ(session.context().scene_marks, nullptr);
  const WorldPtr other = session.scenes.world(environment(random_scene(7)));
  ASSERT_TRUE(other->edge_marks);
  EXPECT_EQ(session.context(*other).scene_marks, other->edge_marks.get());
  // The build scene named by file is the default world, without marks.
  EXPECT_EQ(session.scenes.load(source_path("data/environments/table.json")),
            session.scenes.default_world());
}

TEST(WorkspaceIndex, TheFileDoesNotDependOnTheThreadCount) {
  const std::string copy = temp_dir() + "/ws-threads.h5";
  fs::copy_file(indexed().path, copy, fs::copy_options::overwrite_existing);
  WorkspaceIndexOptions one;
  one.threads = 1;
  write_workspace_index(BundleView::open(copy), panda(), one);
  EXPECT_EQ(read_file(workspace_index_path(copy)), read_file(workspace_index_path(indexed().path)));
}

// Copies the indexed bundle and damages its index with `damage`; the reason it is not used.
std::string refusal(const std::string& name, void (*damage)(const std::string& index)) {
  const std::string copy = temp_dir() + "/" + name + ".h5";
  fs::copy_file(indexed().path, copy, fs::copy_options::overwrite_existing);
  fs::copy_file(workspace_index_path(indexed().path), workspace_index_path(copy),
                fs::copy_options::overwrite_existing);
  damage(workspace_index_path(copy));
  const PlanningSession session(copy, true, "", "");
  EXPECT_EQ(session.workspace.index, nullptr);
  EXPECT_EQ(session.scenes.world(environment(random_scene(1)))->edge_marks, nullptr);
  return session.workspace.source;
}

void flip_last_byte(const std::string& index) {
  std::fstream f(index, std::ios::in | std::ios::out | std::ios::binary);
  f.seekg(-1, std::ios::end);
  const char c = static_cast<char>(f.get() ^ 0x5a);
  f.seekp(-1, std::ios::end);
  f.put(c);
}

void truncate(const std::string& index) { fs::resize_file(index, fs::file_size(index) - 8); }

// The index of another bundle (two edge starts swapped) put in its place.
void foreign(const std::string& index) {
  Bundle other = small_bundle();
  std::swap(other.q0[0], other.q0[1]);  // other edge states, same sizes
  const std::string path = temp_dir() + "/ws-other.h5";
  write_bundle(path, other);
  write_workspace_index(BundleView::open(path), panda(), {});
  fs::copy_file(workspace_index_path(path), index, fs::copy_options::overwrite_existing);
}

void replace_with_directory(const std::string& index) {
  fs::remove(index);
  fs::create_directory(index);
}

TEST(WorkspaceIndex, ADamagedOrForeignIndexIsRefusedWithTheReason) {
  EXPECT_NE(refusal("ws-flipped", flip_last_byte).find("checksum mismatch"), std::string::npos);
  EXPECT_NE(refusal("ws-truncated", truncate).find("truncated or malformed"), std::string::npos);
  EXPECT_NE(refusal("ws-foreign", foreign).find("made for other edge states"), std::string::npos);
  EXPECT_NE(refusal("ws-dir", replace_with_directory).find("not a regular file"),
            std::string::npos);
}

TEST(WorkspaceIndex, LazyboeBuildRewritesADamagedIndex) {
  const std::string copy = temp_dir() + "/ws-rewrite.h5";
  fs::copy_file(indexed().path, copy, fs::copy_options::overwrite_existing);
  fs::copy_file(workspace_index_path(indexed().path), workspace_index_path(copy),
                fs::copy_options::overwrite_existing);
  flip_last_byte(workspace_index_path(copy));
  const CommandResult r =
      run(watchdog(120) + quote(tool_path("lazyboe-build")) + " --index " + quote(copy));
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  EXPECT_NE(r.err.find("workspace index written to"), std::string::npos) << r.err;
  const PlanningSession session(copy, true, "", "");
  EXPECT_TRUE(session.workspace.index) << session.workspace.source;
  const CommandResult inspect =
      run(quote(tool_path("lazyboe-build")) + " --inspect " + quote(copy));
  EXPECT_NE(inspect.out.find("workspace index: " + workspace_index_path(copy)), std::string::npos)
      << inspect.out;
}

TEST(WorkspaceIndex, ABundleWithoutSamplesHasNone) {
  Bundle b = small_bundle();
  b.header.sample_interval = 0;
  b.sample_q.clear();
  b.sample_dq.clear();
  std::fill(b.sample_offset.begin(), b.sample_offset.end(), 0);
  const std::string path = temp_dir() + "/ws-no-samples.h5";
  write_bundle(path, b);
  try {
    write_workspace_index(BundleView::open(path), panda(), {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": has no stored trajectory samples"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace lazyboe::test
