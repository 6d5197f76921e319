// End-to-end tests of the lazyboe-robot command-line tool: the real binary is run on real files
// and its output is compared with the library. Bad input must give a non-zero exit status and
// exactly one line on stderr naming the file (or option) and the line or field at fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "lazyboe/collision/collision_model.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/io/csv.h"
#include "lazyboe/robot/dynamics.h"
#include "lazyboe/robot/kinematics.h"
#include "test_util.h"

namespace lazyboe::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Runs lazyboe-robot with the given arguments (each is shell-quoted).
CommandResult robot_tool(const std::vector<std::string>& args) {
  std::string cmd = quote(tool_path("lazyboe-robot"));
  for (const std::string& a : args) cmd += " " + quote(a);
  return run(cmd);
}

std::string table_env() { return source_path("data/environments/table.json"); }

// Replaces the first occurrence of `from`; the edit must apply, or the test means nothing.
std::string replace_once(const std::string& text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: '" << from << "' not found";
  if (at == std::string::npos) return text;
  std::string out = text;
  out.replace(at, from.size(), to);
  return out;
}

std::string panda_json_text() { return read_file(source_path("data/robots/panda.json")); }
std::string panda_urdf_text() { return read_file(source_path("data/robots/panda.urdf")); }

// Writes <dir>/panda.json and <dir>/panda.urdf into the temp dir; returns the config path.
std::string write_robot(const std::string& dir, const std::string& config_text,
                        const std::string& urdf_text) {
  write_temp_file(dir + "/panda.urdf", urdf_text);
  return write_temp_file(dir + "/panda.json", config_text);
}

// A robot whose config JSON is the bundled one after `edit`.
std::string robot_with_config(const std::string& dir, const std::function<void(json&)>& edit) {
  json config = json::parse(panda_json_text());
  edit(config);
  return write_robot(dir, config.dump(2), panda_urdf_text());
}

std::string robot_with_urdf(const std::string& dir, const std::string& urdf_text) {
  return write_robot(dir, panda_json_text(), urdf_text);
}

std::string join_row(const std::vector<double>& v) {
  std::string s;
  char buf[64];
  for (size_t i = 0; i < v.size(); ++i) {
    std::snprintf(buf, sizeof buf, "%.17g", v[i]);
    s += (i ? "," : "") + std::string(buf);
  }
  return s;
}

std::string join_names(const std::vector<std::string>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + v[i];
  return s;
}

std::vector<std::string> state_header() {
  std::vector<std::string> h = numbered_columns("q", 7);
  for (const char* p : {"dq", "ddq"}) {
    for (const std::string& c : numbered_columns(p, 7)) h.push_back(c);
  }
  return h;
}

std::string zero_state_row() { return join_row(std::vector<double>(21, 0.0)); }

// A row of 21 cells with `cell` in column `column` (0-based) and zeros elsewhere.
std::string state_row_with(int column, const std::string& cell) {
  std::string s;
  for (int i = 0; i < 21; ++i) s += std::string(i ? "," : "") + (i == column ? cell : "0");
  return s;
}

std::vector<double> split_doubles(const std::string& line) {
  std::vector<double> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(std::stod(cell));
  return out;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string line;
  while (std::getline(ss, line)) {
    if (!line.empty()) out.push_back(line);
  }
  return out;
}

JointVector random_q(std::mt19937& rng) {
  const RobotModel& robot = panda();
  JointVector q(robot.dof);
  for (int i = 0; i < robot.dof; ++i) {
    q[i] = std::uniform_real_distribution<double>(robot.q_min[i], robot.q_max[i])(rng);
  }
  return q;
}

std::string q_arg(const JointVector& q) {
  return join_row(std::vector<double>(q.data(), q.data() + q.size()));
}

// The library's view of a configuration in an environment.
CollisionReport library_check(const JointVector& q, const Environment& env) {
  const RobotModel& robot = panda();
  const CollisionModel cm = build_collision_model(robot, env);
  RobotData rd(robot);
  CollisionData cd(cm);
  forward_kinematics(robot, rd, q);
  update_collision_transforms(cm, cd, rd);
  return check_collision(cm, cd);
}

JointVector make_q(std::initializer_list<double> values) {
  JointVector q(static_cast<int>(values.size()));
  int i = 0;
  for (double v : values) q[i++] = v;
  return q;
}

// ------------------------------------------------------------------------------------------
// Normal use
// ------------------------------------------------------------------------------------------

TEST(Cli, InfoNamesJointsAndCollisionBodies) {
  const CommandResult r = robot_tool({"info"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  for (int i = 1; i <= 7; ++i) {
    EXPECT_NE(r.out.find("panda_joint" + std::to_string(i)), std::string::npos) << r.out;
  }
  ASSERT_FALSE(panda().geometry.bodies.empty());
  for (const CollisionBody& c : panda().geometry.bodies) {
    EXPECT_NE(r.out.find(c.name), std::string::npos) << c.name << "\n" << r.out;
  }
  EXPECT_NE(r.out.find("collision bodies"), std::string::npos) << r.out;
  // The gains and the sampling region the simulator and the builder use, per joint.
  EXPECT_NE(r.out.find("tip link panda_link8; controller gains"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("region [-0.3, 0.7]"), std::string::npos) << r.out;  // panda_joint2's
}

TEST(Cli, InfoJsonParsesWithSevenDof) {
  const CommandResult r = robot_tool({"info", "--json"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  json j;
  ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
  EXPECT_EQ(j.at("dof").get<int>(), 7);
  EXPECT_EQ(j.at("name").get<std::string>(), "panda");
  ASSERT_EQ(j.at("joints").size(), 7u);
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(j["joints"][i].at("name").get<std::string>(), "panda_joint" + std::to_string(i + 1));
  }
  ASSERT_EQ(j.at("collision_bodies").size(), panda().geometry.bodies.size());
  for (size_t i = 0; i < panda().geometry.bodies.size(); ++i) {
    EXPECT_EQ(j["collision_bodies"][i].at("name").get<std::string>(),
              panda().geometry.bodies[i].name);
  }
  EXPECT_DOUBLE_EQ(j["joints"][3].at("lower").get<double>(), -3.0718);
  EXPECT_DOUBLE_EQ(j["joints"][3].at("upper").get<double>(), -0.0698);
  EXPECT_EQ(j.at("tip_link").get<std::string>(), "panda_link8");
  EXPECT_EQ(j["sampling_region"]["lower"][1].get<double>(), panda().region.lower[1]);
  EXPECT_EQ(j["controller"]["kv"].size(), 7u);
}

TEST(Cli, FkAtZeroIsTheFlangePose) {
  const CommandResult r = robot_tool({"fk", "--q", "0,0,0,0,0,0,0"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  json j;
  ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
  EXPECT_EQ(j.at("link").get<std::string>(), "panda_link8");
  const std::vector<double> p = j.at("position").get<std::vector<double>>();
  ASSERT_EQ(p.size(), 3u);
  EXPECT_NEAR(p[0], 0.088, 1e-9);
  EXPECT_NEAR(p[1], 0.0, 1e-9);
  EXPECT_NEAR(p[2], 0.926, 1e-9);
  const std::vector<double> quat = j.at("quaternion").get<std::vector<double>>();
  ASSERT_EQ(quat.size(), 4u);
  EXPECT_NEAR(
      std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]), 1.0,
      1e-12);
}

TEST(Cli, FkOfNamedLinkMatchesLibrary) {
  const RobotModel& robot = panda();
  const JointVector q = JointVector::Zero(7);
  const CommandResult r = robot_tool({"fk", "--q", "0,0,0,0,0,0,0", "--link", "panda_link4"});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const json j = json::parse(r.out);
  EXPECT_EQ(j.at("link").get<std::string>(), "panda_link4");
  RobotData data(robot);
  forward_kinematics(robot, data, q);
  const Pose pose = link_pose(robot, data, robot.link_index("panda_link4"));
  const std::vector<double> p = j.at("position").get<std::vector<double>>();
  const std::vector<double> quat = j.at("quaternion").get<std::vector<double>>();
  ASSERT_EQ(p.size(), 3u);
  ASSERT_EQ(quat.size(), 4u);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(p[i], pose.p[i], 1e-12);
  const Eigen::Vector4d qw = pose.quaternion_wxyz();
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(quat[i], qw[i], 1e-12);
  // link4 sits 0.333 + 0.316 above the base at q = 0, offset 0.0825 forward.
  EXPECT_NEAR(p[0], 0.0825, 1e-9);
  EXPECT_NEAR(p[1], 0.0, 1e-9);
  EXPECT_NEAR(p[2], 0.649, 1e-9);
}

TEST(Cli, FkAtRandomConfigurationsMatchesLibrary) {
  const RobotModel& robot = panda();
  std::mt19937 rng(12345);
  RobotData data(robot);
  for (int k = 0; k < 3; ++k) {
    const JointVector q = random_q(rng);
    for (const std::string link : {"", "panda_link3", "panda_link6"}) {
      std::vector<std::string> args = {"fk", "--q", q_arg(q)};
      if (!link.empty()) args.insert(args.end(), {"--link", link});
      const CommandResult r = robot_tool(args);
      ASSERT_EQ(r.exit_code, 0) << describe(r);
      const json j = json::parse(r.out);
      forward_kinematics(robot, data, q);
      const int index = link.empty() ? robot.tip_link() : robot.link_index(link);
      const Pose pose = link_pose(robot, data, index);
      EXPECT_EQ(j.at("link").get<std::string>(), robot.links[index].name);
      const std::vector<double> p = j.at("position").get<std::vector<double>>();
      const std::vector<double> quat = j.at("quaternion").get<std::vector<double>>();
      ASSERT_EQ(p.size(), 3u);
      ASSERT_EQ(quat.size(), 4u);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(p[i], pose.p[i], 1e-12) << "q " << q_arg(q);
      const Eigen::Vector4d qw = pose.quaternion_wxyz();
      for (int i = 0; i < 4; ++i) EXPECT_NEAR(quat[i], qw[i], 1e-12) << "q " << q_arg(q);
    }
  }
}

TEST(Cli, TorquesMatchLibraryInverseDynamics) {
  const RobotModel& robot = panda();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> vel(-1.5, 1.5), acc(-5, 5);
  std::vector<std::vector<double>> states;
  states.push_back(std::vector<double>(21, 0.0));
  for (int k = 0; k < 5; ++k) {
    const JointVector q = random_q(rng);
    std::vector<double> s(q.data(), q.data() + 7);
    for (int i = 0; i < 7; ++i) s.push_back(vel(rng));
    for (int i = 0; i < 7; ++i) s.push_back(acc(rng));
    states.push_back(s);
  }
  std::string csv = join_names(state_header()) + "\n";
  for (const auto& s : states) csv += join_row(s) + "\n";
  const std::string in = write_temp_file("torques_ok/in.csv", csv);
  const std::string out = temp_dir() + "/torques_ok/out.csv";

  const CommandResult r = robot_tool({"torques", "--in", in, "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> lines = split_lines(read_file(out));
  ASSERT_EQ(lines.size(), states.size() + 1) << read_file(out);
  EXPECT_EQ(lines[0], join_names(numbered_columns("tau", 7)));

  RobotData data(robot);
  for (size_t k = 0; k < states.size(); ++k) {
    const std::vector<double> tool_tau = split_doubles(lines[k + 1]);
    ASSERT_EQ(tool_tau.size(), 7u) << lines[k + 1];
    Eigen::Map<const Eigen::VectorXd> all(states[k].data(), 21);
    const Eigen::VectorXd q = all.segment(0, 7), dq = all.segment(7, 7), ddq = all.segment(14, 7);
    const JointVector tau = inverse_dynamics(robot, data, q, dq, ddq);
    for (int i = 0; i < 7; ++i) {
      EXPECT_NEAR(tool_tau[i], tau[i], 1e-7 * std::max(1.0, std::abs(tau[i])))
          << "row " << k << " joint " << i + 1;
    }
  }
}

TEST(Cli, CheckReportsLimitsSelfAndEnvironmentCollision) {
  const Environment env = load_environment(table_env());
  const JointVector zero = JointVector::Zero(7);
  const JointVector ready = make_q({0, -0.785, 0, -2.356, 0, 1.571, 0.785});
  const JointVector into_table = make_q({0, 1.0, 0, -1.0, 0, 1.5, 0});
  const JointVector folded = make_q({0, 0, 0, -3.0, 0, 0.1, 0});

  // The poses are what this test says they are, according to the library.
  const RobotModel& robot = panda();
  auto lib_in_limits = [&](const JointVector& q) {
    return (q.array() >= robot.q_min.array()).all() && (q.array() <= robot.q_max.array()).all();
  };
  ASSERT_FALSE(lib_in_limits(zero));  // q4 = 0 is outside [-3.0718, -0.0698]
  ASSERT_TRUE(lib_in_limits(ready));
  ASSERT_TRUE(lib_in_limits(into_table));
  ASSERT_TRUE(lib_in_limits(folded));
  ASSERT_FALSE(library_check(ready, env).any());
  const CollisionReport table_hit = library_check(into_table, env);
  ASSERT_TRUE(table_hit.env_collision);
  ASSERT_FALSE(table_hit.self_collision);
  const CollisionReport fold_hit = library_check(folded, env);
  ASSERT_TRUE(fold_hit.self_collision);
  ASSERT_FALSE(fold_hit.env_collision);

  std::string csv = join_names(numbered_columns("q", 7)) + "\n";
  for (const JointVector* q : {&zero, &ready, &into_table, &folded}) csv += q_arg(*q) + "\n";
  const std::string in = write_temp_file("check_ok/in.csv", csv);
  const std::string out = temp_dir() + "/check_ok/out.csv";
  const CommandResult r = robot_tool({"check", "--env", table_env(), "--in", in, "--out", out});
  ASSERT_EQ(r.exit_code, 0) << describe(r);
  const std::vector<std::string> lines = split_lines(read_file(out));
  ASSERT_EQ(lines.size(), 5u) << read_file(out);
  EXPECT_EQ(lines[0], "in_limits,self_collision,env_collision,min_distance");
  std::vector<std::vector<double>> rows;
  for (size_t i = 1; i < lines.size(); ++i) {
    rows.push_back(split_doubles(lines[i]));
    ASSERT_EQ(rows.back().size(), 4u) << lines[i];
  }
  // q = 0: outside the joint-4 limits, but not colliding.
  EXPECT_EQ(rows[0][0], 0);
  EXPECT_EQ(rows[0][1], 0);
  EXPECT_EQ(rows[0][2], 0);
  EXPECT_GT(rows[0][3], 0);
  // Ready pose: valid and free.
  EXPECT_EQ(rows[1][0], 1);
  EXPECT_EQ(rows[1][1], 0);
  EXPECT_EQ(rows[1][2], 0);
  EXPECT_GT(rows[1][3], 0);
  // Reaching down into the table.
  EXPECT_EQ(rows[2][0], 1);
  EXPECT_EQ(rows[2][1], 0);
  EXPECT_EQ(rows[2][2], 1);
  EXPECT_EQ(rows[2][3], 0);  // overlapping shapes have distance 0
  // Folded elbow: the forearm hits the upper arm.
  EXPECT_EQ(rows[3][0], 1);
  EXPECT_EQ(rows[3][1], 1);
  EXPECT_EQ(rows[3][2], 0);
  EXPECT_GE(rows[3][3], 0);
  EXPECT_LT(rows[3][3], robot.geometry.margin);

  // Distances agree with the library.
  const CollisionModel cm = build_collision_model(robot, env);
  RobotData rd(robot);
  CollisionData cd(cm);
  const JointVector* qs[] = {&zero, &ready, &into_table, &folded};
  for (int k = 0; k < 4; ++k) {
    forward_kinematics(robot, rd, *qs[k]);
    update_collision_transforms(cm, cd, rd);
    const double d = min_distance(cm, cd).min();
    EXPECT_NEAR(rows[k][3], d, 1e-9 * std::max(1.0, std::abs(d))) << "row " << k;
  }
}

// ------------------------------------------------------------------------------------------
// Bad robot configs
// ------------------------------------------------------------------------------------------

TEST(Cli, MissingRobotConfig) {
  const std::string path = temp_dir() + "/no_such_dir/robot.json";
  expect_one_line_error(robot_tool({"--robot", path, "info"}), {path});
}

TEST(Cli, RobotConfigInvalidJsonNamesLine) {
  const std::string text = panda_json_text();
  const std::string needle = "\"tip_link\": \"panda_link8\"";
  const size_t at = text.find(needle);
  ASSERT_NE(at, std::string::npos);
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
  const std::string bad = replace_once(text, needle, "\"tip_link\": panda_link8");
  const std::string config = write_robot("cfg_syntax", bad, panda_urdf_text());
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_syntax/panda.json", ":" + std::to_string(line) + ":"});
}

TEST(Cli, RobotConfigMissingJoints) {
  const std::string config = robot_with_config("cfg_nojoints", [](json& j) { j.erase("joints"); });
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_nojoints/panda.json", "joints"});
}

TEST(Cli, RobotConfigWrongType) {
  const std::string config =
      robot_with_config("cfg_type", [](json& j) { j["control_rate"] = "fast"; });
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_type/panda.json", "control_rate"});
  const std::string config2 =
      robot_with_config("cfg_type2", [](json& j) { j["collision"]["margin"] = "big"; });
  expect_one_line_error(robot_tool({"--robot", config2, "info"}),
                        {"cfg_type2/panda.json", "collision.margin"});
}

TEST(Cli, RobotConfigZeroMaxJerk) {
  const std::string config =
      robot_with_config("cfg_jerk", [](json& j) { j["joints"][0]["max_jerk"] = 0; });
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_jerk/panda.json", "joints[0].max_jerk"});
}

TEST(Cli, RobotConfigUnknownFrictionModel) {
  const std::string config = robot_with_config(
      "cfg_friction", [](json& j) { j["joints"][2]["friction"]["model"] = "stribeck"; });
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_friction/panda.json", "joints[2].friction.model", "stribeck"});
}

TEST(Cli, RobotConfigUnknownTopLevelField) {
  const std::string config = robot_with_config("cfg_extra", [](json& j) { j["colour"] = "red"; });
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"cfg_extra/panda.json", "colour"});
}

TEST(Cli, RobotConfigAllowedPairUnknownLink) {
  size_t index = 0;
  const std::string config = robot_with_config("cfg_pair", [&](json& j) {
    index = j["collision"]["allowed_pairs"].size();
    j["collision"]["allowed_pairs"].push_back({"panda_link3", "panda_hand"});
  });
  expect_one_line_error(
      robot_tool({"--robot", config, "info"}),
      {"cfg_pair/panda.json", "collision.allowed_pairs[" + std::to_string(index) + "][1]",
       "panda_hand"});
}

TEST(Cli, RobotConfigMissingUrdf) {
  const std::string config =
      robot_with_config("cfg_nourdf", [](json& j) { j["urdf"] = "missing.urdf"; });
  expect_one_line_error(robot_tool({"--robot", config, "info"}), {"cfg_nourdf/missing.urdf"});
}

// ------------------------------------------------------------------------------------------
// Bad URDFs
// ------------------------------------------------------------------------------------------

TEST(Cli, UrdfMalformedXml) {
  const std::string urdf = replace_once(panda_urdf_text(), "</link>", "</lnk>");
  const std::string config = robot_with_urdf("urdf_xml", urdf);
  expect_one_line_error(robot_tool({"--robot", config, "info"}), {"urdf_xml/panda.urdf"});
}

// A syntax error in a 300-line file should say where it is, as the JSON reader does.
TEST(Cli, UrdfMalformedXmlNamesLine) {
  const std::string text = panda_urdf_text();
  const size_t at = text.find("</link>");
  ASSERT_NE(at, std::string::npos);
  const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
  const std::string config =
      robot_with_urdf("urdf_xml_line", replace_once(text, "</link>", "</lnk>"));
  const CommandResult r = robot_tool({"--robot", config, "info"});
  expect_one_line_error(r, {"urdf_xml_line/panda.urdf"});
  const std::regex names_line("(:|line )" + std::to_string(line) + "\\b");
  EXPECT_TRUE(std::regex_search(r.err, names_line)) << "message does not name line " << line << "\n"
                                                    << describe(r);
}

TEST(Cli, UrdfNegativeMass) {
  const std::string urdf =
      replace_once(panda_urdf_text(), "<mass value=\"3.228604\"/>", "<mass value=\"-3.228604\"/>");
  const std::string config = robot_with_urdf("urdf_mass", urdf);
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"urdf_mass/panda.urdf", "panda_link3", "mass"});
}

TEST(Cli, UrdfNonPhysicalInertia) {
  const std::string urdf =
      replace_once(panda_urdf_text(),
                   "ixx=\"2.5853e-02\" ixy=\"7.7960e-03\" ixz=\"-1.3320e-03\" iyy=\"1.9552e-02\" "
                   "iyz=\"8.6410e-03\" izz=\"2.8323e-02\"",
                   "ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"5\"");
  const std::string config = robot_with_urdf("urdf_inertia", urdf);
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"urdf_inertia/panda.urdf", "panda_link4", "inertia"});
}

TEST(Cli, UrdfLowerAboveUpper) {
  const std::string urdf = replace_once(panda_urdf_text(), "lower=\"-1.7628\" upper=\"1.7628\"",
                                        "lower=\"1.7628\" upper=\"-1.7628\"");
  const std::string config = robot_with_urdf("urdf_limits", urdf);
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"urdf_limits/panda.urdf", "panda_joint2", "lower"});
}

TEST(Cli, UrdfMeshCollision) {
  const std::string urdf =
      replace_once(panda_urdf_text(), "<geometry><sphere radius=\"0.06\"/></geometry>",
                   "<geometry><mesh filename=\"package://panda/meshes/link0.stl\"/></geometry>");
  const std::string config = robot_with_urdf("urdf_mesh", urdf);
  expect_one_line_error(robot_tool({"--robot", config, "info"}),
                        {"urdf_mesh/panda.urdf", "panda_link0", "collision", "mesh"});
}

// ------------------------------------------------------------------------------------------
// Bad fk arguments
// ------------------------------------------------------------------------------------------

TEST(Cli, FkWrongNumberOfValues) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0"}), {"--q", "7", "3"});
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,0,0,0,0,0"}), {"--q", "7", "8"});
}

TEST(Cli, FkNotANumber) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,abc,0,0,0"}), {"--q", "abc"});
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,,0,0,0"}), {"--q"});
}

// "0,...,0," has an empty eighth value; it must not be read as seven values.
TEST(Cli, FkTrailingCommaRejected) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,-1,0,1,0,"}), {"--q"});
}

TEST(Cli, FkNan) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,nan,0,0,0"}), {"--q", "finite"});
}

TEST(Cli, FkInf) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,0,0,0,inf"}), {"--q", "finite"});
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,0,0,0,1e999"}), {"--q", "finite"});
}

TEST(Cli, FkUnknownLink) {
  expect_one_line_error(robot_tool({"fk", "--q", "0,0,0,-1,0,1,0", "--link", "panda_hand"}),
                        {"--link", "panda_hand"});
}

// ------------------------------------------------------------------------------------------
// Bad torques input
// ------------------------------------------------------------------------------------------

std::string torques_input(const std::string& name, const std::vector<std::string>& data_rows) {
  std::string csv = join_names(state_header()) + "\n";
  for (const std::string& row : data_rows) csv += row + "\n";
  return write_temp_file("torques_bad/" + name, csv);
}

std::string torques_out() { return temp_dir() + "/torques_bad/out.csv"; }

TEST(Cli, TorquesMissingInput) {
  const std::string in = temp_dir() + "/torques_bad/does_not_exist.csv";
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}), {in});
}

TEST(Cli, TorquesWrongHeader) {
  const std::string in =
      write_temp_file("torques_bad/header.csv", "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1,0,1,0\n");
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}),
                        {in + ":1:", "header"});
}

TEST(Cli, TorquesTooFewColumns) {
  const std::string in = torques_input("few.csv", {zero_state_row(), "0,0,0"});
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}),
                        {in + ":3:", "21", "3"});
}

TEST(Cli, TorquesNonNumericCell) {
  const std::string in = torques_input("text.csv", {zero_state_row(), state_row_with(9, "fast")});
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}),
                        {in + ":3:", "dq3", "fast"});
}

TEST(Cli, TorquesNanCell) {
  const std::string in = torques_input("nan.csv", {zero_state_row(), state_row_with(2, "nan")});
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}),
                        {in + ":3:", "q3"});
}

TEST(Cli, TorquesInfCell) {
  const std::string in = torques_input("inf.csv", {zero_state_row(), state_row_with(20, "-inf")});
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", torques_out()}),
                        {in + ":3:", "ddq7"});
  const std::string in2 = torques_input("huge.csv", {state_row_with(15, "1e999")});
  expect_one_line_error(robot_tool({"torques", "--in", in2, "--out", torques_out()}),
                        {in2 + ":2:", "ddq2"});
}

TEST(Cli, TorquesUnwritableOutput) {
  const std::string in = torques_input("ok.csv", {zero_state_row()});
  const std::string out = temp_dir() + "/no_such_dir/out.csv";
  expect_one_line_error(robot_tool({"torques", "--in", in, "--out", out}), {out});
}

// ------------------------------------------------------------------------------------------
// Bad check input
// ------------------------------------------------------------------------------------------

std::string check_input() {
  return write_temp_file("check_bad/in.csv",
                         "q1,q2,q3,q4,q5,q6,q7\n0,-0.785,0,-2.356,0,1.571,0.785\n");
}
std::string check_out() { return temp_dir() + "/check_bad/out.csv"; }

std::string env_with(const std::string& name, const std::function<void(json&)>& edit) {
  json env = json::parse(read_file(table_env()));
  edit(env);
  return write_temp_file("check_bad/" + name, env.dump(2));
}

TEST(Cli, CheckUnknownEnvironmentFile) {
  const std::string env = temp_dir() + "/check_bad/nowhere.json";
  expect_one_line_error(
      robot_tool({"check", "--env", env, "--in", check_input(), "--out", check_out()}), {env});
}

TEST(Cli, CheckEnvironmentUnknownObjectType) {
  const std::string env = env_with("type.json", [](json& j) { j["objects"][1]["type"] = "cone"; });
  expect_one_line_error(
      robot_tool({"check", "--env", env, "--in", check_input(), "--out", check_out()}),
      {env, "objects[1].type", "cone"});
}

TEST(Cli, CheckEnvironmentAllowedLinkUnknown) {
  const std::string env = env_with("links.json", [](json& j) {
    j["objects"][0]["allowed_links"] = {"panda_link0", "panda_hand"};
  });
  const CommandResult r =
      robot_tool({"check", "--env", env, "--in", check_input(), "--out", check_out()});
  expect_one_line_error(r, {env, "panda_hand"});
  EXPECT_TRUE(r.err.find("floor") != std::string::npos ||
              r.err.find("objects[0]") != std::string::npos)
      << "message does not say which object\n"
      << describe(r);
}

TEST(Cli, CheckEnvironmentNegativeBoxSize) {
  const std::string env = env_with("size.json", [](json& j) {
    j["objects"][1]["size"] = {0.6, -1.2, 0.04};
  });
  expect_one_line_error(
      robot_tool({"check", "--env", env, "--in", check_input(), "--out", check_out()}),
      {env, "objects[1].size"});
}

TEST(Cli, CheckEnvironmentRpyAndQuaternion) {
  const std::string env = env_with("rot.json", [](json& j) {
    j["objects"][1]["quaternion"] = {1, 0, 0, 0};
  });
  expect_one_line_error(
      robot_tool({"check", "--env", env, "--in", check_input(), "--out", check_out()}),
      {env, "objects[1]", "rpy", "quaternion"});
}

TEST(Cli, CheckWrongCsvHeader) {
  const std::string in =
      write_temp_file("check_bad/header.csv", "j1,j2,j3,j4,j5,j6,j7\n0,0,0,-1,0,1,0\n");
  expect_one_line_error(
      robot_tool({"check", "--env", table_env(), "--in", in, "--out", check_out()}),
      {in + ":1:", "header"});
}

// ------------------------------------------------------------------------------------------
// Output files
// ------------------------------------------------------------------------------------------

TEST(Cli, TorquesErrorKeepsExistingOutput) {
  const std::string dir = temp_dir() + "/keep_torques";
  const std::string in = write_temp_file(
      "keep_torques/in.csv", join_names(state_header()) + "\n" + zero_state_row() + "\n" +
                                 state_row_with(4, "oops") + "\n" + zero_state_row() + "\n");
  const std::string out = write_temp_file("keep_torques/out.csv", "old content\n1,2,3\n");
  const std::vector<std::string> before = files_in(dir);
  const CommandResult r = robot_tool({"torques", "--in", in, "--out", out});
  expect_one_line_error(r, {in + ":3:", "q5"});
  EXPECT_EQ(read_file(out), "old content\n1,2,3\n");
  EXPECT_EQ(files_in(dir), before) << "a temporary file was left behind";

  // A good run then replaces it completely.
  const std::string good = write_temp_file(
      "keep_torques/good.csv", join_names(state_header()) + "\n" + zero_state_row() + "\n");
  const CommandResult ok = robot_tool({"torques", "--in", good, "--out", out});
  ASSERT_EQ(ok.exit_code, 0) << describe(ok);
  const std::vector<std::string> lines = split_lines(read_file(out));
  ASSERT_EQ(lines.size(), 2u) << read_file(out);
  EXPECT_EQ(lines[0], join_names(numbered_columns("tau", 7)));
}

TEST(Cli, CheckErrorKeepsExistingOutput) {
  const std::string dir = temp_dir() + "/keep_check";
  const std::string in =
      write_temp_file("keep_check/in.csv",
                      "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1,0,1,0\n0,0,0,-1,0,inf,0\n0,0,0,-1,0,1,0\n");
  const std::string out = write_temp_file("keep_check/out.csv", "previous results\n");
  const std::vector<std::string> before = files_in(dir);
  const CommandResult r = robot_tool({"check", "--env", table_env(), "--in", in, "--out", out});
  expect_one_line_error(r, {in + ":3:", "q6"});
  EXPECT_EQ(read_file(out), "previous results\n");
  EXPECT_EQ(files_in(dir), before) << "a temporary file was left behind";

  // Also when the environment is the bad part.
  const std::string env =
      write_temp_file("keep_check/env.json", "{\"schema_version\": 1,\n  oops\n}\n");
  const std::string good_in =
      write_temp_file("keep_check/good.csv", "q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1,0,1,0\n");
  const CommandResult r2 = robot_tool({"check", "--env", env, "--in", good_in, "--out", out});
  expect_one_line_error(r2, {env + ":2:"});
  EXPECT_EQ(read_file(out), "previous results\n");
}

// Command-line mistakes are CLI11's business: non-zero, no crash, and they name the option.
TEST(Cli, MissingRequiredOption) {
  expect_one_line_error(robot_tool({"torques", "--in", check_input()}), {"--out", "required"});
  expect_one_line_error(robot_tool({}), {"subcommand"});
}

}  // namespace
}  // namespace lazyboe::test
