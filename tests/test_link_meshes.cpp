// Robot links with mesh collision geometry (issue 28, item 1): STL and COLLADA meshes under
// package:// URIs load; a fitted capsule encloses every vertex; exact meshes and fitted capsules
// agree far from contact and the fitted one is never less conservative; a box given as a mesh
// collides as the box primitive does; every bad mesh is one error naming the file and the link.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <string>

#include "box_files.h"
#include "lazyboe/bundle/scene.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/convex_hull.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/common/error.h"
#include "lazyboe/robot/kinematics.h"
#include "lazyboe/robot/robot_config.h"
#include "lazyboe/robot/robot_model.h"
#include "test_util.h"

namespace lazyboe {
namespace {

const char* kInertia =
    R"(<inertial><origin xyz="0.2 0 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>)";

// A post on the base and two links reaching out along x; `upper`, `fore` and `post` are the
// collision geometry elements of the three links.
std::string urdf(const std::string& upper, const std::string& fore, const std::string& post) {
  return std::string(R"(<?xml version="1.0"?>
<robot name="mesher">
  <link name="base"><collision><origin xyz="0.45 0 0.1"/><geometry>)") +
         post + R"(</geometry></collision></link>
  <link name="upper">)" +
         kInertia + R"(<collision><origin xyz="0.2 0 0"/><geometry>)" + upper +
         R"(</geometry></collision></link>
  <link name="fore">)" +
         kInertia + R"(<collision><origin xyz="0.15 0 0"/><geometry>)" + fore +
         R"(</geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.2"/>
    <axis xyz="0 0 1"/><limit lower="-3.1" upper="3.1" velocity="2" effort="50"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" velocity="2" effort="50"/></joint>
</robot>)";
}

std::string config(const std::string& urdf_name, const std::string& extra = "",
                   double margin = 0.005, const std::string& meshes = "") {
  return R"({"schema_version": 1, "name": "mesher", "urdf": ")" + urdf_name + R"(", )" + extra +
         R"(
    "joints": [
      {"name": "j1", "max_acceleration": 10, "max_jerk": 500, "max_torque_rate": 5000,
       "friction": {"model": "none"}},
      {"name": "j2", "max_acceleration": 10, "max_jerk": 500, "max_torque_rate": 5000,
       "friction": {"model": "none"}}],
    "collision": {"margin": )" +
         std::to_string(margin) + meshes + R"(, "allowed_pairs": [["upper", "fore"]]}})";
}

// The three boxes as files of the package `meshtest` under <temp>/mesher/pkgs.
struct MeshFiles {
  test::BoxFiles upper{{0, 0, 0}, {0.4, 0.06, 0.06}, 0.01, "mesher/pkgs/meshtest/meshes/upper"};
  test::BoxFiles fore{{0, 0, 0}, {0.3, 0.05, 0.05}, 0.01, "mesher/pkgs/meshtest/meshes/fore"};
  test::BoxFiles post{{0, 0, 0}, {0.05, 0.05, 0.2}, 0.01, "mesher/pkgs/meshtest/meshes/post"};
  MeshFiles() {
    upper.binary_stl();
    fore.collada();
    post.obj();
  }
};

const std::string kMeshUrdf = urdf(R"(<mesh filename="package://meshtest/meshes/upper.stl"/>)",
                                   R"(<mesh filename="package://meshtest/meshes/fore.dae"/>)",
                                   R"(<mesh filename="package://meshtest/meshes/post.obj"/>)");
const std::string kBoxUrdf =
    urdf(R"(<box size="0.4 0.06 0.06"/>)", R"(<box size="0.3 0.05 0.05"/>)",
         R"(<box size="0.05 0.05 0.2"/>)");
const std::string kPackagePath = R"("package_path": ["pkgs"],)";
const std::string kExact = R"(, "meshes": {"representation": "exact"})";

RobotModel load(const std::string& name, const std::string& urdf_text, const std::string& cfg) {
  static const MeshFiles files;
  test::write_temp_file("mesher/" + name + ".urdf", urdf_text);
  return load_robot(test::write_temp_file("mesher/" + name + ".json", cfg));
}

// A block the fore link sweeps through, away from the post.
Environment block_scene() {
  Environment env;
  Obstacle o;
  o.name = "block";
  o.shape.type = ShapeType::Box;
  o.shape.size = Eigen::Vector3d(0.1, 0.1, 0.1);
  o.pose.p = Eigen::Vector3d(-0.5, 0.3, 0.2);
  env.obstacles.push_back(o);
  return env;
}

struct Outcome {
  bool hit = false;
  double distance = 0;
};

// Collision and exact distance of `robot` at each of `n` seeded random configurations.
std::vector<Outcome> sweep(const RobotModel& robot, int n) {
  const CollisionModel model = build_collision_model(robot, block_scene());
  CollisionData data(model);
  RobotData robot_data(robot);
  std::mt19937_64 rng(7);
  std::vector<Outcome> out;
  for (int k = 0; k < n; ++k) {
    JointVector q(robot.dof);
    for (int i = 0; i < robot.dof; ++i)
      q[i] = std::uniform_real_distribution<double>(robot.q_min[i], robot.q_max[i])(rng);
    forward_kinematics(robot, robot_data, q);
    update_collision_transforms(model, data, robot_data);
    out.push_back({in_collision(model, data), min_distance(model, data).min()});
  }
  return out;
}

TEST(LinkMeshes, StlColladaAndObjLoadUnderPackageUrisAsFittedCapsules) {
  const RobotModel robot = load("fitted", kMeshUrdf, config("fitted.urdf", kPackagePath));
  ASSERT_EQ(robot.geometry.bodies.size(), 3u);
  ASSERT_EQ(robot.files.resources.size(), 3u);
  for (const CollisionBody& b : robot.geometry.bodies) {
    EXPECT_EQ(b.representation, MeshRepresentation::Fitted) << b.name;
    EXPECT_EQ(b.shape.type, ShapeType::Capsule) << b.name;
    EXPECT_TRUE(std::filesystem::exists(b.mesh_file)) << b.mesh_file;
    // A box of half-width w and length l: the capsule's caps overreach its ends by about w.
    EXPECT_GT(b.over_approximation, 0.0) << b.name;
    EXPECT_LT(b.over_approximation, 0.06) << b.name;
  }
  // The COLLADA file is Z_UP: read as written, its long side stays along x.
  const CollisionBody& fore = robot.geometry.bodies[2];
  EXPECT_NEAR(std::abs(fore.in_link.R.col(2).x()), 1.0, 1e-6);
  EXPECT_NEAR(fore.in_link.p.x(), 0.15, 1e-6);
}

TEST(LinkMeshes, AFittedCapsuleEnclosesEveryVertex) {
  const RobotModel robot = load("fitted", kMeshUrdf, config("fitted.urdf", kPackagePath));
  const double origins[3] = {0.45, 0.2, 0.15};  // the collision origins' x (post: base link)
  for (size_t k = 0; k < robot.geometry.bodies.size(); ++k) {
    const CollisionBody& b = robot.geometry.bodies[k];
    const TriangleMesh mesh = load_mesh(b.mesh_file, Eigen::Vector3d::Ones());
    const Pose origin(Eigen::Matrix3d::Identity(),
                      Eigen::Vector3d(origins[k], 0, k == 0 ? 0.1 : 0.0));
    const Pose to_capsule = b.in_link.inverse() * origin;
    for (const Eigen::Vector3d& v : mesh.vertices) {
      const Eigen::Vector3d p = to_capsule * v;
      const double along = std::clamp(p.z(), -b.shape.length / 2, b.shape.length / 2);
      EXPECT_LE((p - Eigen::Vector3d(0, 0, along)).norm(), b.shape.radius) << b.name;
    }
  }
}

TEST(LinkMeshes, ExactAndFittedAgreeFarFromContactAndFittedIsNeverLessConservative) {
  const RobotModel fitted = load("fitted", kMeshUrdf, config("fitted.urdf", kPackagePath));
  const RobotModel exact =
      load("exact", kMeshUrdf, config("exact.urdf", kPackagePath, 0.005, kExact));
  for (const CollisionBody& b : exact.geometry.bodies) EXPECT_EQ(b.shape.type, ShapeType::Mesh);
  double reach = 0;
  for (const CollisionBody& b : fitted.geometry.bodies)
    reach = std::max(reach, b.over_approximation);
  const std::vector<Outcome> f = sweep(fitted, 3000), e = sweep(exact, 3000);
  int exact_hits = 0, far = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    if (e[k].hit) {
      EXPECT_TRUE(f[k].hit) << "configuration " << k;
    }
    if (e[k].distance > reach + fitted.geometry.margin) {
      EXPECT_FALSE(f[k].hit) << "configuration " << k;
      ++far;
    }
    exact_hits += e[k].hit;
  }
  EXPECT_GT(exact_hits, 50);  // the sweep reaches the block and the post
  EXPECT_GT(far, 500);
}

TEST(LinkMeshes, ABoxAsAMeshCollidesAsTheBoxPrimitive) {
  for (double margin : {0.0, 0.01}) {
    const RobotModel box = load("box", kBoxUrdf, config("box.urdf", "", margin));
    const RobotModel mesh =
        load("exact", kMeshUrdf, config("exact.urdf", kPackagePath, margin, kExact));
    const std::vector<Outcome> b = sweep(box, 3000), m = sweep(mesh, 3000);
    int hits = 0;
    for (size_t k = 0; k < b.size(); ++k) {
      EXPECT_NEAR(m[k].distance, b[k].distance, 1e-6) << "configuration " << k;
      // The margin grows a box primitive as a box, a mesh's pairs by distance: the same with
      // none, the primitive at most more conservative (at its corners) with one.
      if (margin == 0) {
        EXPECT_EQ(m[k].hit, b[k].hit) << "configuration " << k;
      }
      if (m[k].hit) {
        EXPECT_TRUE(b[k].hit) << "configuration " << k;
      }
      hits += m[k].hit;
    }
    EXPECT_GT(hits, 50);
    EXPECT_LT(hits, 2950);
  }
}

// The convex representation: the hull of a box mesh is the box, so it collides as the exact
// mesh does and as the box primitive at most (which the margin grows as a box); `info`'s shape.
TEST(LinkMeshes, ABoxAsAConvexHullCollidesAsTheExactMesh) {
  const std::string kConvex = R"(, "meshes": {"representation": "convex"})";
  for (double margin : {0.0, 0.01}) {
    const RobotModel box = load("box", kBoxUrdf, config("box.urdf", "", margin));
    const RobotModel exact =
        load("exact", kMeshUrdf, config("exact.urdf", kPackagePath, margin, kExact));
    const RobotModel hull =
        load("hull", kMeshUrdf, config("hull.urdf", kPackagePath, margin, kConvex));
    for (const CollisionBody& b : hull.geometry.bodies) {
      EXPECT_TRUE(b.shape.type == ShapeType::Mesh && b.shape.convex) << b.name;
      EXPECT_EQ(b.shape.mesh->vertices.size(), 8u) << b.name;  // a box's corners
      EXPECT_EQ(b.representation, MeshRepresentation::Convex);
    }
    const std::vector<Outcome> b = sweep(box, 3000), e = sweep(exact, 3000), h = sweep(hull, 3000);
    int hits = 0;
    for (size_t k = 0; k < b.size(); ++k) {
      EXPECT_NEAR(h[k].distance, b[k].distance, 1e-6) << "configuration " << k;
      EXPECT_EQ(h[k].hit, e[k].hit) << "configuration " << k;
      if (h[k].hit) {
        EXPECT_TRUE(b[k].hit) << "configuration " << k;
      }
      hits += h[k].hit;
    }
    EXPECT_GT(hits, 50);
    EXPECT_LT(hits, 2950);
  }
}

// Qhull's hull of a non-convex mesh (two boxes in an L, and points inside): a closed surface
// of outward triangles that encloses every vertex, made of the outer corners only.
TEST(LinkMeshes, TheConvexHullEnclosesEveryVertexWithOutwardTriangles) {
  TriangleMesh l;
  for (const Eigen::Vector3d& corner : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.3, 0, 0),
                                        Eigen::Vector3d(0, 0.1, 0), Eigen::Vector3d(0.3, 0.1, 0)}) {
    for (double z : {0.0, 0.1}) l.vertices.push_back(corner + Eigen::Vector3d(0, 0, z));
  }
  for (const Eigen::Vector3d& corner : {Eigen::Vector3d(0, 0.1, 0), Eigen::Vector3d(0.1, 0.1, 0),
                                        Eigen::Vector3d(0, 0.4, 0), Eigen::Vector3d(0.1, 0.4, 0)}) {
    for (double z : {0.0, 0.1}) l.vertices.push_back(corner + Eigen::Vector3d(0, 0, z));
  }
  l.vertices.push_back({0.05, 0.05, 0.05});  // inside
  l.vertices.push_back({0.05, 0.2, 0.05});   // inside
  const TriangleMesh hull = convex_hull(l, "l.stl");
  EXPECT_EQ(hull.vertices.size(), 10u);  // the L's 5 outer corners in plan, top and bottom
  std::map<std::pair<int, int>, int> edges;
  double volume = 0;
  for (const Eigen::Vector3i& t : hull.triangles) {
    const Eigen::Vector3d &a = hull.vertices[t[0]], &b = hull.vertices[t[1]],
                          &c = hull.vertices[t[2]];
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    for (const Eigen::Vector3d& v : l.vertices) EXPECT_LE(normal.dot(v - a), 1e-12);
    volume += a.dot(b.cross(c)) / 6;
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, count] : edges) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(edges.count({edge.second, edge.first}), 1u) << "an edge with one side";
  }
  EXPECT_GT(volume, 0.3 * 0.4 * 0.1 - 0.2 * 0.3 * 0.1);  // more than the L itself
  EXPECT_THROW(convex_hull(TriangleMesh{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {}}, "t.stl"), Error);
}

TEST(LinkMeshes, PackagesResolveThroughRosPackagePathFileUrisAndRelativePaths) {
  const std::string pkgs = test::temp_dir() + "/mesher/pkgs";
  ::setenv("ROS_PACKAGE_PATH", ("/nonexistent:" + pkgs).c_str(), 1);
  EXPECT_EQ(load("fitted", kMeshUrdf, config("fitted.urdf")).files.resources.size(), 3u);
  ::unsetenv("ROS_PACKAGE_PATH");
  const std::string message = test::robot_load_error(test::temp_dir() + "/mesher/fitted.json");
  EXPECT_NE(message.find("package 'meshtest'"), std::string::npos) << message;
  EXPECT_NE(message.find("link 'base'"), std::string::npos) << message;
  const std::string other =
      urdf("<mesh filename=\"file://" + pkgs + "/meshtest/meshes/upper.stl\"/>",
           R"(<mesh filename="pkgs/meshtest/meshes/fore.dae"/>)", R"(<box size="0.05 0.05 0.2"/>)");
  const RobotModel robot = load("uris", other, config("uris.urdf"));
  EXPECT_EQ(robot.files.resources.size(), 2u);
}

TEST(LinkMeshes, TheRobotsIdentityCoversItsMeshes) {
  const RobotModel before = load("fitted", kMeshUrdf, config("fitted.urdf", kPackagePath));
  const std::string id = robot_identity(before);
  test::BoxFiles wider{{0, 0, 0}, {0.4, 0.07, 0.06}, 0.01, "mesher/pkgs/meshtest/meshes/upper"};
  wider.binary_stl();
  EXPECT_NE(robot_identity(before), id);
  test::BoxFiles{{0, 0, 0}, {0.4, 0.06, 0.06}, 0.01, "mesher/pkgs/meshtest/meshes/upper"}
      .binary_stl();
  EXPECT_EQ(robot_identity(before), id);
}

// The message of loading the mesh robot with `upper`'s geometry replaced.
std::string error_with_upper(const std::string& upper, const std::string& meshes = "") {
  test::write_temp_file("mesher/bad.urdf", urdf(upper, R"(<box size="0.3 0.05 0.05"/>)",
                                                R"(<box size="0.05 0.05 0.2"/>)"));
  return test::robot_load_error(
      test::write_temp_file("mesher/bad.json", config("bad.urdf", kPackagePath, 0.005, meshes)));
}

TEST(LinkMeshes, EachBadMeshIsOneErrorNamingTheFileAndTheLink) {
  static const MeshFiles files;
  test::write_temp_file("mesher/pkgs/meshtest/meshes/empty.stl", "");
  test::write_temp_file("mesher/pkgs/meshtest/meshes/text.stl", "not a mesh at all\n");
  test::BoxFiles{{0, 0, 0}, {0.3, 0.2, 0.0}, 0.01, "mesher/pkgs/meshtest/meshes/flat"}.binary_stl();
  const struct {
    std::string uri, says;
  } cases[] = {
      {"package://meshtest/meshes/none.stl", "none.stl"},
      {"package://meshtest/meshes/empty.stl", "empty.stl"},
      {"package://meshtest/meshes/text.stl", "text.stl"},
      {"package://meshtest/meshes", "meshes"},
      {"package://nopackage/meshes/upper.stl", "package 'nopackage'"},
      {"package://meshtest/meshes/flat.stl", "degenerate mesh"},
      {"http://example.com/upper.stl", "only package://"},
  };
  for (const auto& c : cases) {
    const std::string message = error_with_upper("<mesh filename=\"" + c.uri + "\"/>");
    EXPECT_NE(message.find("bad.urdf: link 'upper' collision 0"), std::string::npos) << message;
    EXPECT_NE(message.find(c.says), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  const std::string stl = R"(<mesh filename="package://meshtest/meshes/upper.stl"/>)";
  EXPECT_NE(error_with_upper(stl, R"(, "meshes": {"representation": "round"})")
                .find("collision.meshes.representation: unknown mesh representation 'round'"),
            std::string::npos);
  EXPECT_NE(error_with_upper(stl, R"(, "meshes": {"links": {"uper": "exact"}})")
                .find("unknown link 'uper'"),
            std::string::npos);
}

}  // namespace
}  // namespace lazyboe
