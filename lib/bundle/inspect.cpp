#include "lazyboe/bundle/inspect.h"

#include <algorithm>
#include <cmath>

#include "lazyboe/bundle/bundle_file.h"
#include "lazyboe/common/histogram.h"
#include "lazyboe/sim/random.h"

namespace lazyboe {

std::vector<double> neighbour_counts(const Bundle& b, double theta, int points, uint64_t seed) {
  const int n = b.dof();
  const size_t N = b.size();
  Random rng(seed, 0);
  std::vector<double> counts;
  std::vector<double> p(n);
  const double r2 = theta * theta;
  for (int k = 0; k < points; ++k) {
    for (int i = 0; i < n; ++i)
      p[i] = rng.uniform(b.header.region_lower[i], b.header.region_upper[i]);
    size_t c = 0;
    for (size_t e = 0; e < N; ++e) {
      double d2 = 0;
      for (int i = 0; i < n && d2 <= r2; ++i) {
        const double d = b.q0[e * n + i] - p[i];
        d2 += d * d;
      }
      c += d2 <= r2;
    }
    counts.push_back(static_cast<double>(c));
  }
  return counts;
}

void print_perturbation_summary(const Bundle& b, std::FILE* out) {
  const Perturbation& p = b.perturbation;
  if (!p.present) {
    std::fprintf(out, "perturbation analysis: none (run lazyboe-perturb)\n");
    return;
  }
  const size_t N = b.size();
  uint64_t done = 0, valid = 0, collision = 0, finished = 0;
  std::vector<double> select(N), errors;
  size_t usable = 0, never = 0;
  for (size_t e = 0; e < N; ++e) {
    done += p.done[e];
    valid += p.valid[e];
    collision += p.collision[e];
    finished += p.done[e] >= p.perturbations;
    select[e] = (1 - p.p_collision[e]) * p.p_lazy_prop[e];
    usable += select[e] >= 0.5;
    never += select[e] == 0;
    if (p.valid[e]) errors.push_back(p.max_error[e]);
  }
  std::fprintf(out,
               "perturbation analysis: theta %g rad, %llu perturbations per edge, seed %llu, %s\n",
               p.theta, static_cast<unsigned long long>(p.perturbations),
               static_cast<unsigned long long>(p.seed),
               p.complete ? "complete" : "INCOMPLETE (run lazyboe-perturb again to continue)");
  std::fprintf(out,
               "  edges done %llu of %zu; rollouts %llu: valid %.1f%%, collided %.1f%%; simulated "
               "%.0f s in %.1f s wall\n",
               static_cast<unsigned long long>(finished), N, static_cast<unsigned long long>(done),
               done ? 100.0 * valid / done : 0.0, done ? 100.0 * collision / done : 0.0,
               p.simulated_seconds, p.wall_seconds);
  if (N == 0) return;
  const Quantiles ql = quantiles(p.p_lazy_prop), qc = quantiles(p.p_collision),
                  qs = quantiles(select);
  std::fprintf(out, "P_lazy_prop: mean %.3f, median %.3f\n", ql.mean, ql.median);
  std::fputs(text_histogram(p.p_lazy_prop, 0, 1, 10).c_str(), out);
  std::fprintf(out, "P_collision: mean %.3f, median %.3f\n", qc.mean, qc.median);
  std::fputs(text_histogram(p.p_collision, 0, 1, 10).c_str(), out);
  if (!errors.empty()) {
    const Quantiles qe = quantiles(errors);
    std::fprintf(out,
                 "max end-state error per edge (rad): median %.3f, 90th percentile %.3f, max %.3f "
                 "(theta/2 = %.3f)\n"
                 "  (how far an edge's end moved when it started up to theta away; P_lazy_prop "
                 "counts the starts whose end stayed within theta/2 of the stored end)\n",
                 qe.median, qe.p90, qe.max, p.theta / 2);
  }
  std::fprintf(out,
               "P_select = (1 - P_collision) P_lazy_prop: mean %.3f; %.1f%% of edges >= 0.5 "
               "(usable for lazy propagation), %.1f%% never taken lazily (0)\n",
               qs.mean, 100.0 * usable / N, 100.0 * never / N);
  print_transfer_summary(b, out);
}

void print_transfer_summary(const Bundle& b, std::FILE* out) {
  const Perturbation& p = b.perturbation;
  if (!p.present) return;
  if (!p.has_transfer) {
    std::fprintf(out,
                 "transfer statistics: none (an analysis written by an older lazyboe; "
                 "lazyboe-perturb recomputes it with them)\n");
    return;
  }
  const size_t N = b.size();
  if (N == 0) return;
  std::vector<double> stored, transfer;
  for (size_t e = 0; e < N; ++e) {
    if (!p.valid[e]) continue;
    stored.push_back(p.max_error[e]);
    transfer.push_back(p.transfer_max_error[e]);
  }
  const Quantiles ql = quantiles(p.p_lazy_prop), qt = quantiles(p.p_lazy_prop_transfer);
  std::fprintf(out,
               "transfer (the command from q0 + d ends near qf + d): P_lazy_prop under transfer "
               "mean %.3f, median %.3f, vs P_lazy_prop (stored end qf) mean %.3f, median %.3f\n",
               qt.mean, qt.median, ql.mean, ql.median);
  if (!transfer.empty()) {
    const Quantiles qe = quantiles(stored), qr = quantiles(transfer);
    std::fprintf(out,
                 "max transfer residual |q^f - (qf + d)| per edge (rad): median %.4f, 90th "
                 "percentile %.4f, max %.4f; vs max stored-end error |q^f - qf|: median %.4f, "
                 "90th percentile %.4f, max %.4f\n",
                 qr.median, qr.p90, qr.max, qe.median, qe.p90, qe.max);
  }
}

void print_build_summary(const BundleHeader& h, std::FILE* out) {
  std::fprintf(out, "  attempts %llu, valid %llu (%.1f%%), start states resampled %llu\n",
               static_cast<unsigned long long>(h.attempts),
               static_cast<unsigned long long>(h.valid),
               h.attempts ? 100.0 * h.valid / h.attempts : 0.0,
               static_cast<unsigned long long>(h.start_resamples));
  for (const auto& [reason, count] : h.rejected) {
    std::fprintf(out, "  rejected %-20s %llu\n", reason.c_str(),
                 static_cast<unsigned long long>(count));
  }
  std::fprintf(out, "  simulated %.1f s in %.1f s wall: %.0f attempts/s, %.0f valid edges/s\n",
               h.simulated_seconds, h.wall_seconds,
               h.wall_seconds > 0 ? h.attempts / h.wall_seconds : 0.0,
               h.wall_seconds > 0 ? h.valid / h.wall_seconds : 0.0);
}

void print_checkpoint_stats(const CheckpointStats& s, double wall_seconds, std::FILE* out) {
  std::fprintf(out,
               "  checkpoints %llu in %.3f s (%.2f%% of %.1f s wall; longest %.3f s), last save "
               "%.3f s\n",
               static_cast<unsigned long long>(s.checkpoints), s.checkpoint_seconds,
               wall_seconds > 0 ? 100.0 * s.checkpoint_seconds / wall_seconds : 0.0, wall_seconds,
               s.longest_checkpoint_seconds, s.last_save_seconds);
}

std::string checksum_summary(const std::vector<DatasetVerification>& checks) {
  size_t verified = 0, missing = 0;
  std::string bad;
  for (const DatasetVerification& v : checks) {
    if (v.status == DatasetVerification::Status::Verified) ++verified;
    if (v.status == DatasetVerification::Status::NoChecksum) ++missing;
    if (v.status == DatasetVerification::Status::Mismatch)
      bad += (bad.empty() ? "" : ", ") + v.dataset;
  }
  if (!bad.empty()) return "MISMATCH in " + bad + ": the file is damaged";
  if (missing == checks.size()) return "none (written before checksums existed)";
  if (missing > 0)
    return std::to_string(verified) + " of " + std::to_string(checks.size()) +
           " datasets verify, " + std::to_string(missing) + " have no checksum";
  return "all " + std::to_string(verified) + " datasets verify";
}

namespace {

// What the coverage figures mean for a user, in a line, when they call for something (issue 30).
void print_coverage_advice(double uncovered, double median, std::FILE* out) {
  if (uncovered > 0.10) {  // the default 100k bundle: 5.8% (docs/bundle.md)
    std::fprintf(out,
                 "  -> %.0f%% of the region has no edge start within theta: a query starting "
                 "there fails as outside the bundle's coverage. Build more edges (--edges), raise "
                 "--theta, narrow --region to where you plan, or plan with lazysp (its growth "
                 "leaves the bundle)\n",
                 100.0 * uncovered);
  } else if (median < 10) {
    std::fprintf(out,
                 "  -> a median of %.0f edge starts per point: the bundle planners have few edges "
                 "to choose from; more edges (--edges) or a larger --theta help\n",
                 median);
  }
}

}  // namespace

void print_inspection(const std::string& path, std::FILE* out) {
  const Bundle b = read_bundle(path);
  const BundleHeader& h = b.header;
  const int n = b.dof();
  const size_t N = b.size();
  std::fprintf(out, "bundle %s\n", path.c_str());
  std::fprintf(
      out, "  schema version %d, written by lazyboe %s, %s\n", h.schema_version,
      h.tool_version.c_str(),
      h.complete ? "complete" : "INCOMPLETE (resume with lazyboe-build --resume --out FILE)");
  std::fprintf(out, "  robot %s (%s, hash %s), %d joints\n", h.robot_name.c_str(),
               h.robot_config.c_str(), h.robot_hash.c_str(), n);
  std::fprintf(out, "  environment %s (%s, hash %s)\n", h.env_name.c_str(), h.env_file.c_str(),
               h.env_hash.c_str());
  std::fprintf(out, "  edges %zu of %llu, seed %llu, design theta %g rad\n", N,
               static_cast<unsigned long long>(h.target_edges),
               static_cast<unsigned long long>(h.seed), h.design_theta);
  std::fprintf(
      out, "  commands %g-%g s, knots every ~%g s, speed <= %g x limit, accel/jerk <= %g x limit\n",
      h.min_duration, h.max_duration, h.knot_interval, h.velocity_scale, h.limit_scale);
  std::fprintf(out, "  simulation %s x%d at %g Hz, trajectory samples every %g s\n",
               h.integrator.c_str(), h.substeps, h.control_rate, h.sample_interval);
  std::fprintf(out, "  region:");
  for (int i = 0; i < n; ++i) std::fprintf(out, " [%g, %g]", h.region_lower[i], h.region_upper[i]);
  std::fprintf(out, "\n");
  print_build_summary(h, out);
  std::fprintf(out, "  checksums: %s\n", checksum_summary(verify_bundle_checksums(path)).c_str());
  if (N == 0) return;

  std::vector<double> displacement(N);
  for (size_t e = 0; e < N; ++e) {
    double d2 = 0;
    for (int i = 0; i < n; ++i) d2 += std::pow(b.qf[e * n + i] - b.q0[e * n + i], 2);
    displacement[e] = std::sqrt(d2);
  }
  const Quantiles qd = quantiles(b.duration), qx = quantiles(displacement);
  std::fprintf(out, "\nedge duration (s): mean %.3f, median %.3f, min %.3f, max %.3f\n", qd.mean,
               qd.median, qd.min, qd.max);
  std::fputs(text_histogram(b.duration, qd.min, qd.max, 8).c_str(), out);
  std::fprintf(out, "edge displacement |qf - q0| (rad): mean %.3f, median %.3f, max %.3f\n",
               qx.mean, qx.median, qx.max);
  std::fputs(text_histogram(displacement, 0, qx.max, 8).c_str(), out);

  std::fprintf(
      out,
      "coverage of the region by edge starts (share of edges per tenth of each joint's range):\n");
  for (int i = 0; i < n; ++i) {
    int bins[10] = {0};
    for (size_t e = 0; e < N; ++e) {
      const double f =
          (b.q0[e * n + i] - h.region_lower[i]) / (h.region_upper[i] - h.region_lower[i]);
      bins[std::clamp(static_cast<int>(f * 10), 0, 9)]++;
    }
    std::fprintf(out, "  joint %d:", i + 1);
    for (int k = 0; k < 10; ++k) std::fprintf(out, " %4.1f", 100.0 * bins[k] / N);
    std::fprintf(out, " %%\n");
  }
  const std::vector<double> counts = neighbour_counts(b, h.design_theta, 500, 7);
  const Quantiles qn = quantiles(counts);
  size_t zero = 0;
  for (double c : counts) zero += c == 0;
  std::fprintf(out,
               "edge starts within theta = %g of 500 random region points: mean %.1f, median %.0f, "
               "10th percentile %.0f, none for %.1f%% of points\n",
               h.design_theta, qn.mean, qn.median, qn.p10, 100.0 * zero / counts.size());
  print_coverage_advice(static_cast<double>(zero) / counts.size(), qn.median, out);
  std::fputs("\n", out);
  print_perturbation_summary(b, out);
}

}  // namespace lazyboe
