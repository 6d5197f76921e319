// `lazyboe-build --inspect`: a bundle's header and statistics (edge durations and
// displacements, coverage of the sampling region, neighbours within theta).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "lazyboe/bundle/bundle.h"
#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/checkpoint.h"

namespace lazyboe {

// One line on a bundle's checksums: "all 17 datasets verify", "MISMATCH in /edges/q0: ...",
// "none (written before checksums existed)".
std::string checksum_summary(const std::vector<DatasetVerification>& checks);

void print_inspection(const std::string& path, std::FILE* out);

// The build's tally: attempts, valid share, rejections by reason, simulated and wall time.
void print_build_summary(const BundleHeader& header, std::FILE* out);

// The perturbation analysis of a bundle: settings, distributions of both probabilities
// (text histograms) and the share of edges usable for lazy propagation.
// Ends with print_transfer_summary.
void print_perturbation_summary(const Bundle& bundle, std::FILE* out);

// The transfer statistics beside P_lazy_prop: mean P_lazy_prop under transfer vs P_lazy_prop,
// and the per-edge maximum transfer residual vs the stored-end error (or a line saying the
// analysis predates them). Nothing without an analysis.
void print_transfer_summary(const Bundle& bundle, std::FILE* out);

// Edge starts within `theta` (Euclidean, joint space) of random points of the sampling region:
// the design check that a bundle holds enough neighbours for the planner.
std::vector<double> neighbour_counts(const Bundle& bundle, double theta, int points, uint64_t seed);

// One line: how many checkpoints the run wrote and what they and the last save cost, with the
// checkpoints' share of `wall_seconds` (the bundle's or analysis's total wall time).
void print_checkpoint_stats(const CheckpointStats& stats, double wall_seconds, std::FILE* out);

}  // namespace lazyboe
