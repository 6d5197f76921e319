// What lazyboe-view puts into its page, as JSON for the page's script (viewer/viewer.js): the
// robot's kinematic chain and collision geometry (the page poses it by forward kinematics from
// the joint origins and axes), the obstacles, the planned trajectories and failed queries of a
// results file, and a sample of the bundle's edge ends.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle_view.h"
#include "lazyboe/collision/environment.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

// {"name", "dof", "joints": [{name, type, origin: {R (row-major), p}, axis}], "links": [{name,
// body, in_body}], "shapes": [{name, link, type, radius, length, size, pose}], "visuals": [the
// same, from the URDF's <visual> elements (robot_visuals.h)], "tip"}. `warnings` gets a line per
// link whose visuals could not be read (drawn from its collision geometry).
nlohmann::json robot_view_json(const RobotModel& robot, std::vector<std::string>& warnings);

// {"name", "obstacles": [{name, type, radius, length, size, pose}]}.
nlohmann::json environment_view_json(const Environment& env);

struct ResultsViewOptions {
  // The query batch the results answer (optional): start and goal of every query, matched by
  // line, so a failed query is shown with them. Results alone carry neither.
  std::string queries_path;
  // Samples kept at least this far apart (s; the first and last always): the page interpolates
  // linearly between them, a 1 kHz trajectory needs no more to be drawn, and the page stays
  // small. Joint positions are kept to 1e-7 rad (the drawn pose within ~1e-6 m of the exact).
  double min_sample_interval = 0.02;
};

// Reads a results file (schemas/result.schema.json), trajectories inline or as CSV files
// (a relative trajectory_file is looked up as written, then next to the results file).
// {"path", "results", "trajectories": [...], "failures": [...], "without_trajectory": [...]}.
// Throws Error("<file>:<line>: <field>: ...") for a line that is not a result.
nlohmann::json results_view_json(const std::string& results_path, const RobotModel& robot,
                                 const ResultsViewOptions& options);

struct BundleSampleOptions {
  size_t points = 20000;  // edge starts and ends together (two per sampled edge)
  uint64_t seed = 1;
};

// End-effector (tip link) positions of the starts and ends of a seeded sample of edges, with
// each edge's P_lazy_prop and P_collision (when analysed) and the neighbour density of each
// point: bundle edge starts within the bundle's design theta of it (joint space), what a
// planner at that state can continue with. {"edge_ids": sampled edges, "points": [x, y, z, ...]
// (start and end of each sampled edge in turn), "density", "p_lazy_prop", "p_collision": one
// value per point, ...}.
nlohmann::json bundle_sample_json(const BundleView& bundle, const RobotModel& robot,
                                  const BundleSampleOptions& options);

}  // namespace lazyboe
