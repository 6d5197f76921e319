#include "lazyboe/planning/execution.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

// Peak |s'| and |s''| of the minimum-jerk blend on [0, 1] (command_profile.cpp).
constexpr double kPeakSlope = 1.875;
constexpr double kPeakCurvature = 5.773502691896258;

// A rollout of this stage, kept with checkpoints at its knots, so that a later command from
// the same start that agrees with it up to some knot goes on from there rather than being
// simulated again (issue 27): a correction round (it changes the last interior knot), the
// settle of a rollout stopped where its command ends, a junction tried again or split into a
// stop, a segment that begins with a shortcut's simulated command.
struct Trail {
  const Simulator* sim = nullptr;
  JointVector q0;  // its start (empty: no rollout)
  std::vector<double> times, knots;
  bool uniform = false;
  std::vector<int> knot_ticks;                 // ticks_before(times[k]), k >= 1
  std::vector<RolloutCheckpoint> checkpoints;  // at those ticks the rollout got to
  std::vector<double> rows;                    // its per-tick rows
  int stopped_at = -1;  // the tick it stopped at (RolloutResume::stop_at), or -1
};

// A step of the path being processed: its command with knot times, and the raw chain's state
// it should end at.
struct Step {
  std::vector<double> times, knots;
  JointVector target;
  int first_raw = 0, last_raw = 0;  // the raw steps it stands for
  bool uniform = false;             // evenly spaced knots (a raw step's)
  // A shortcut's accepted simulation from the raw chain's state (the blend pass reuses it for a
  // segment of this step alone from that same state, and goes on from its checkpoints for a
  // segment that begins with it).
  bool simulated = false;
  RolloutResult result;
  Trail trail;
};

// The raw chain: the planner's path, each step from the previous end, as realize_path has it.
struct RawChain {
  std::vector<JointVector> states;  // start, then each step's end
  std::vector<double> cost;         // per step
  double duration = 0;
};

struct Work {
  const Simulator& sim;        // segments that end at a stop: execution_simulator
  const Simulator& final_sim;  // the last segment, after which the arm holds: the planners'
  SimulatorWorkspace& ws;
  const ExecutionOptions& options;
  ExecutionStats& stats;
  Trail trail = {};  // the last rollout made or reused (its rows: the segment's per-tick rows)
  Trail spare = {};  // scratch for the next one
  bool looked_shortcut_failed = false;  // blend_segments gave up on a looked shortcut's segment
};

bool within_limits(const RobotModel& robot, const CommandSampling& limits, int joint, double dv,
                   double h) {
  return kPeakSlope * std::abs(dv) / h <= limits.limit_scale * robot.ddq_max[joint] &&
         kPeakCurvature * std::abs(dv) / (h * h) <= limits.limit_scale * robot.dddq_max[joint];
}

RolloutResult simulate_step(Work& w, const JointVectorRef& from, const PathStep& s) {
  const int n = w.sim.robot.dof;
  const RolloutResult r = simulate(w.sim, w.ws, from, s.profile(n));
  w.stats.count(r);
  return r;
}

// The raw chain: the planner's simulation of each step where it handed it over, else each step
// simulated from the previous end, as realize_path does.
RawChain simulate_raw(Work& w, const JointVectorRef& start, const std::vector<PathStep>& steps,
                      const Goal& goal) {
  const int n = w.sim.robot.dof;
  RawChain raw;
  raw.states.push_back(start);
  for (size_t k = 0; k < steps.size(); ++k) {
    const PathStep& s = steps[k];
    const RolloutResult r = s.outcome ? *s.outcome : simulate_step(w, raw.states.back(), s);
    if (!r.valid() || r.qf.size() != n) {
      fail("path",
           "step " + std::to_string(k) + " fails re-validation: " + rollout_status_name(r.status));
    }
    raw.states.push_back(r.qf);
    raw.cost.push_back(r.path_length);
    raw.duration += r.duration;
  }
  if (steps.empty() || !goal.contains(w.sim.robot, w.ws.robot, raw.states.back())) {
    fail("path", "does not end inside the goal region");
  }
  return raw;
}

std::vector<Step> raw_steps(const std::vector<PathStep>& steps, const RawChain& raw, int n) {
  std::vector<Step> out(steps.size());
  for (size_t k = 0; k < steps.size(); ++k) {
    const int knots = static_cast<int>(steps[k].knots.size() / n);
    out[k].knots = steps[k].knots;
    out[k].uniform = steps[k].knot_times.empty();
    out[k].times = steps[k].knot_times;
    for (int j = 0; out[k].uniform && j < knots; ++j)
      out[k].times.push_back(steps[k].command_duration * j / (knots - 1));
    out[k].target = raw.states[k + 1];
    out[k].first_raw = out[k].last_raw = static_cast<int>(k);
    // The last step alone, from the raw chain's state, is simulated with the planners' settle
    // (final_sim): the planner's own simulation of it is that segment's, when it kept the rows.
    if (k + 1 == steps.size() && steps[k].outcome && !steps[k].outcome_rows.empty()) {
      out[k].simulated = true;
      out[k].result = *steps[k].outcome;
      out[k].trail.rows = steps[k].outcome_rows;  // no checkpoints: never gone on from
    }
  }
  return out;
}

// Adds `delta` (a displacement, per joint) to the commanded displacement of the knots
// [first, last) of a command, evenly: knot j carries (t_{j+1} - t_{j-1}) / 2 of the integral.
void correct_command(const std::vector<double>& times, std::vector<double>& knots, int first,
                     int last, const JointVector& delta) {
  const int n = static_cast<int>(delta.size());
  double weight = 0;
  for (int j = first; j < last; ++j) weight += 0.5 * (times[j + 1] - times[j - 1]);
  if (!(weight > 0)) return;
  for (int j = first; j < last; ++j)
    for (int i = 0; i < n; ++i) knots[j * n + i] += delta[i] / weight;
}

// The latest checkpoint of `t` a command from q0 can go on from: commands that agree in their
// first d knots (times and values) agree at every tick before times[d - 1] (the command there
// depends on knots d - 2 and d - 1 only). Evenly spaced knots agree only with the same times.
const RolloutCheckpoint* resume_point(const Trail& t, const Simulator& sim,
                                      const JointVectorRef& q0, const std::vector<double>& times,
                                      const std::vector<double>& knots, bool uniform) {
  const int n = sim.robot.dof;
  if (t.checkpoints.empty() || !same_until_settling(*t.sim, sim) || t.uniform != uniform ||
      t.q0.size() != q0.size() || t.q0 != q0 || (uniform && t.times != times))
    return nullptr;
  size_t d = 0;
  while (d < times.size() && d < t.times.size() && times[d] == t.times[d] &&
         std::equal(knots.begin() + d * n, knots.begin() + (d + 1) * n, t.knots.begin() + d * n))
    ++d;
  if (d < 2) return nullptr;
  const int before = t.knot_ticks[d - 2];  // ticks_before(times[d - 1])
  const RolloutCheckpoint* best = nullptr;
  for (const RolloutCheckpoint& c : t.checkpoints)
    if (c.tick <= before) best = &c;
  return best;
}

// Simulates a command from rest at q0, going on from the latest checkpoint of the last rollout
// or of `also` that it agrees with; it becomes the last rollout (w.trail, its rows included).
// With stop_at >= 0 it stops at that tick (a knot's: its checkpoint is the trail's last).
RolloutResult rollout(Work& w, const Simulator& sim, const JointVectorRef& q0,
                      const std::vector<double>& times, const std::vector<double>& knots,
                      bool uniform, const Trail* also, int stop_at = -1) {
  const bool resume = w.options.resume;
  const Trail* source = &w.trail;
  const RolloutCheckpoint* from = resume || w.trail.stopped_at >= 0
                                      ? resume_point(w.trail, sim, q0, times, knots, uniform)
                                      : nullptr;
  // Without resume, only the rollout that stopped where its command ends is finished from there.
  if (!resume && from && from->tick != w.trail.stopped_at) from = nullptr;
  const RolloutCheckpoint* other =
      resume && also ? resume_point(*also, sim, q0, times, knots, uniform) : nullptr;
  if (other && (!from || other->tick > from->tick)) {
    source = also;
    from = other;
  }
  Trail& next = w.spare;
  next.sim = &sim;
  next.q0 = q0;
  next.times = times;
  next.knots = knots;
  next.uniform = uniform;
  next.knot_ticks.clear();
  if (resume || stop_at >= 0)  // a stopped rollout's checkpoint is where it is gone on from
    for (size_t k = 1; k < times.size(); ++k)
      next.knot_ticks.push_back(ticks_before(sim, times[k]));
  next.checkpoints.clear();
  next.rows.clear();
  if (from) {  // the shared part: its rows and the checkpoints before the one gone on from
    for (const RolloutCheckpoint& c : source->checkpoints)
      if (c.tick < from->tick) next.checkpoints.push_back(c);
    next.rows.assign(source->rows.begin(), source->rows.begin() + from->tick_values);
  }
  const CommandProfile p{knots.data(), static_cast<int>(times.size()), sim.robot.dof, times.back(),
                         uniform ? nullptr : times.data()};
  // Going on from where the last rollout stopped finishes that rollout: one simulation.
  const bool finishes = from && source == &w.trail && from->tick == w.trail.stopped_at;
  const RolloutResult r = simulate(sim, w.ws, q0, p, {nullptr, nullptr, 0, &next.rows},
                                   {from, &next.knot_ticks, &next.checkpoints, stop_at});
  next.stopped_at = r.stopped ? r.ticks : -1;
  if (finishes)
    w.stats.simulated_ticks += r.ticks - from->tick;
  else
    w.stats.count(r, from ? from->tick : 0);
  std::swap(w.trail, w.spare);
  return r;
}

// Simulates a command from rest at q0 (a rollout); corrects its end offset from `target` up to
// max_corrections times. `offset` is the predicted end offset before any simulation (the
// start's offset from the raw chain), spread over knots [first, last); a measured one goes into
// the last correction_knots of them. `uniform`: the knots are evenly spaced, simulated as such
// (a raw step alone is then its own bundle command, bit for bit). A correction round goes on
// from where it changes the command (its checkpoint before the corrected knots).
RolloutResult simulate_to_target(Work& w, const JointVectorRef& q0, std::vector<double>& times,
                                 std::vector<double>& knots, int first, int last,
                                 const JointVector& target, const JointVector& predicted_offset,
                                 bool ends_trajectory, bool uniform = false,
                                 const Trail* also = nullptr) {
  const Simulator& sim = ends_trajectory ? w.final_sim : w.sim;
  if (predicted_offset.cwiseAbs().maxCoeff() > 0)
    correct_command(times, knots, first, last, -predicted_offset);
  const int late = w.options.correction_knots;
  const int from = late > 0 ? std::max(first, last - late) : first;
  for (int round = 0;; ++round) {
    // A round that a correction may follow stops where the command ends; the settle's
    // displacement is predicted, and only a round whose predicted end needs no correction
    // settles (going on from there).
    if (w.options.predict_settle && round < w.options.max_corrections) {
      const RolloutResult part =
          rollout(w, sim, q0, times, knots, uniform, also, ticks_before(sim, times.back()));
      if (!part.valid()) return part;
      const std::vector<RolloutCheckpoint>& saved = w.trail.checkpoints;
      if (part.stopped && !saved.empty() && saved.back().tick == part.ticks) {
        const RolloutCheckpoint& end = saved.back();
        const JointVector residual =
            target - end.q - settle_displacement(sim, w.ws.robot, end.q, end.dq);
        if (residual.cwiseAbs().maxCoeff() > w.options.correction_tolerance) {
          correct_command(times, knots, from, last, residual);
          continue;
        }
      }
    }
    const RolloutResult r = rollout(w, sim, q0, times, knots, uniform, also);
    if (!r.valid() || round >= w.options.max_corrections) return r;
    const JointVector residual = target - r.qf;
    if (residual.cwiseAbs().maxCoeff() <= w.options.correction_tolerance) return r;
    correct_command(times, knots, from, last, residual);
  }
}

// One state at rest: the answer when the start was in the goal (an executable trajectory has
// its zero acceleration and command too).
Trajectory at_rest(const JointVector& q, bool executable) {
  Trajectory t;
  t.t = {0.0};
  t.q = {q};
  t.dq = {JointVector::Zero(q.size())};
  if (executable) t.ddq = t.cmd = t.dq;
  return t;
}

}  // namespace

Trajectory returned_trajectory(const Simulator& sim, SimulatorWorkspace& ws,
                               const PlanningProblem& problem, const std::vector<PathStep>& path,
                               bool raw, const ExecutionOptions& options, int sample_every,
                               ExecutionStats& stats) {
  if (path.empty()) return at_rest(problem.start, !raw);  // the start was in the goal
  if (raw) return realize_path(sim, ws, problem.start, path, problem.goal, sample_every);
  ExecutableTrajectory e =
      make_executable(sim, ws, problem.start, path, problem.goal, options, sample_every);
  stats = e.stats;
  return std::move(e.trajectory);
}

JointVector settle_displacement(const Simulator& sim, RobotData& data, const JointVector& q,
                                const JointVector& dq) {
  const RobotModel& robot = sim.robot;
  JointVector out = mass_matrix(robot, data, q) * dq;
  constexpr double kStep = 1e-6;  // rad/s: the slope by a central difference
  for (int i = 0; i < robot.dof; ++i) {
    const Friction& f = robot.joints[i].friction;
    const double slope = (friction_torque(f, kStep) - friction_torque(f, -kStep)) / (2 * kStep);
    out[i] /= robot.controller.kv[i] + slope;
  }
  return out;
}

Simulator execution_simulator(const Simulator& sim) {
  Simulator stopping = sim;
  stopping.options.settle_for_stop = true;
  // Settling for a dead stop takes longer than the planners' settle, the more so with a payload
  // (a 3 kg load 30 cm out from the Panda's flange needed up to 0.9 s more, issue 29).
  stopping.options.max_settle_time = std::max(sim.options.max_settle_time, kExecutionSettleTime);
  return stopping;
}

bool direct_command(const RobotModel& robot, const CommandSampling& limits,
                    const JointVectorRef& displacement, double dt, std::vector<double>& times,
                    std::vector<double>& knots) {
  const int n = robot.dof;
  if (!(displacement.cwiseAbs().maxCoeff() > 1e-9)) return false;
  int best_intervals = 0;
  double best_h = 0;
  for (int intervals = 2; intervals <= 8; ++intervals) {
    // v_i = D_i / ((N - 1) h): the plateau knots carry the whole displacement.
    double h = 2 * dt;
    for (int i = 0; i < n; ++i) {
      const double d = std::abs(displacement[i]) / (intervals - 1);
      h = std::max(h, d / (limits.velocity_scale * robot.dq_max[i]));
      h = std::max(h, std::sqrt(kPeakSlope * d / (limits.limit_scale * robot.ddq_max[i])));
      h = std::max(h, std::cbrt(kPeakCurvature * d / (limits.limit_scale * robot.dddq_max[i])));
    }
    if (best_intervals == 0 || intervals * h < best_intervals * best_h) {
      best_intervals = intervals;
      best_h = h;
    }
  }
  times.resize(best_intervals + 1);
  knots.assign(static_cast<size_t>(best_intervals + 1) * n, 0.0);
  for (int j = 0; j <= best_intervals; ++j) times[j] = j * best_h;
  for (int j = 1; j < best_intervals; ++j)
    for (int i = 0; i < n; ++i)
      knots[j * n + i] = displacement[i] / ((best_intervals - 1) * best_h);
  return true;
}

namespace {

// Shortcut pass: from each step, the farthest later state reachable by one direct command
// that simulates valid from the raw chain's state, lands near that state (inside the goal for
// the last) and is shorter than the run it replaces; with looked_shortcuts, the first whose
// line looks free and is shorter, unsimulated (the blend pass simulates it in its segment).
std::vector<Step> shortcut_steps(Work& w, const RawChain& raw, std::vector<Step> steps,
                                 const Goal& goal) {
  const int m = static_cast<int>(steps.size());
  std::vector<Step> out;
  int attempts = 0;
  for (int i = 0; i < m;) {
    int accepted = -1;
    Step direct;
    for (int j = m - 1; j > i && attempts < w.options.shortcut_attempts; --j) {
      double run_cost = 0;
      for (int k = i; k <= j; ++k) run_cost += raw.cost[k];
      const JointVector& from = raw.states[i];
      const JointVector& to = raw.states[j + 1];
      // A direct command with a neighbouring step keeps room in its acceleration and jerk for
      // the blends at its junctions (at the limits, no blend of it would fit them).
      CommandSampling limits = w.options.limits;
      if (i > 0 || j + 1 < m) limits.limit_scale *= kJunctionRoom;
      if (!direct_command(w.sim.robot, limits, to - from, w.sim.dt, direct.times, direct.knots))
        continue;
      if (w.options.look && !line_looks_free(w.sim, w.ws, from, to)) {
        if (++w.stats.looked_blocked % ExecutionOptions::kLooksPerAttempt == 0) ++attempts;
        continue;
      }
      ++attempts;
      if (w.options.look && w.options.looked_shortcuts) {
        if (!((to - from).norm() < run_cost)) continue;  // a straight line: its length
        accepted = j;
        break;
      }
      const int last = static_cast<int>(direct.times.size()) - 1;
      const RolloutResult r = simulate_to_target(w, from, direct.times, direct.knots, 1, last, to,
                                                 JointVector::Zero(to.size()), j + 1 == m);
      const bool lands = r.valid() && (r.qf - to).norm() <= w.options.end_tolerance &&
                         (j + 1 < m || goal.contains(w.sim.robot, w.ws.robot, r.qf));
      if (lands && r.path_length < run_cost) {
        direct.result = r;
        accepted = j;
        break;
      }
    }
    if (accepted < 0) {
      out.push_back(std::move(steps[i]));
      ++i;
      continue;
    }
    direct.simulated = !(w.options.look && w.options.looked_shortcuts);
    if (direct.simulated) direct.trail = w.trail;  // of the accepted simulation, the last made
    direct.target = raw.states[accepted + 1];
    direct.first_raw = i;
    direct.last_raw = accepted;
    out.push_back(std::move(direct));
    ++w.stats.shortcuts;
    i = accepted + 1;
  }
  return out;
}

// The smallest shortened junction (fraction of its two intervals) whose blend stays within the
// commanded limits, or 0 when none does. a, b: the knots before and after the junction's zero.
double blend_scale(const RobotModel& robot, const ExecutionOptions& options, const double* a,
                   const double* b, double h1, double h2) {
  const CommandSampling& limits = options.limits;
  for (double alpha : options.blend_scales) {
    bool ok = true;
    for (int i = 0; i < robot.dof && ok; ++i) {
      const double v = (1 - alpha) / alpha * (h1 * a[i] + h2 * b[i]) / (h1 + h2);
      ok = std::abs(v) <= limits.velocity_scale * robot.dq_max[i] &&
           within_limits(robot, limits, i, v - a[i], alpha * h1) &&
           within_limits(robot, limits, i, b[i] - v, alpha * h2);
    }
    if (ok) return alpha;
  }
  return 0;
}

// The joined command of steps [a, b] with the junction after step k shortened to scale[k]:
// knots, knot times, the time of each junction, and the first knot of the last step.
struct Joined {
  std::vector<double> times, knots, junction_time;
  int last_step_first_knot = 1;
};

Joined join_steps(const std::vector<Step>& steps, int a, int b, const std::vector<double>& scale,
                  int n) {
  Joined j;
  double shift = 0;  // time of this step's knot 0 in the joined command
  for (int s = a; s <= b; ++s) {
    const Step& st = steps[s];
    const int count = static_cast<int>(st.times.size());
    const int first = s == a ? 0 : 1;            // knot 0 is the junction knot, already placed
    const int end = s == b ? count : count - 1;  // the last zero becomes the junction knot
    if (s == b) j.last_step_first_knot = s == a ? 1 : static_cast<int>(j.times.size());
    for (int k = first; k < end; ++k) {
      j.times.push_back(shift + st.times[k]);
      j.knots.insert(j.knots.end(), st.knots.begin() + k * n, st.knots.begin() + (k + 1) * n);
    }
    if (s == b) break;
    // The junction: intervals h1 (this step's last) and h2 (the next one's first) become
    // alpha h1 and alpha h2; the junction velocity keeps the commanded displacement.
    const Step& next = steps[s + 1];
    const double alpha = scale[s - a];
    const double h1 = st.times[count - 1] - st.times[count - 2];
    const double h2 = next.times[1] - next.times[0];
    const double t_junction = j.times.back() + alpha * h1;
    const double* ka = &st.knots[(count - 2) * n];
    const double* kb = &next.knots[n];
    j.times.push_back(t_junction);
    j.junction_time.push_back(t_junction);
    for (int i = 0; i < n; ++i)
      j.knots.push_back((1 - alpha) / alpha * (h1 * ka[i] + h2 * kb[i]) / (h1 + h2));
    shift = t_junction + alpha * h2 - next.times[1];
  }
  return j;
}

// Tries segment [a, b] (all its junctions blended, scale[k] after step a + k) from rest at q0.
// On success fills `segment`; otherwise returns the junction (index after a) nearest to where
// it failed, or -1 when [a, b] is a single step.
struct Attempt {
  bool ok = false;
  int junction = -1;
};

Attempt try_segment(Work& w, const std::vector<Step>& steps, const RawChain& raw, int a, int b,
                    const std::vector<double>& scale, const JointVectorRef& q0, const Goal& goal,
                    ExecutionSegment& segment) {
  const int n = w.sim.robot.dof;
  Joined j = join_steps(steps, a, b, scale, n);
  const JointVector offset = q0 - raw.states[steps[a].first_raw];
  const bool uniform = a == b && steps[a].uniform;
  const bool last = b + 1 == static_cast<int>(steps.size());
  RolloutResult r;
  if (a == b && steps[a].simulated && offset.cwiseAbs().maxCoeff() == 0) {
    r = steps[a].result;  // this very command from this very state (and settle): simulated
    w.trail = steps[a].trail;
  } else {
    r = simulate_to_target(w, q0, j.times, j.knots, j.last_step_first_knot,
                           static_cast<int>(j.times.size()) - 1, steps[b].target, offset, last,
                           uniform, &steps[a].trail);
  }
  const bool lands = r.valid() && (r.qf - steps[b].target).norm() <= w.options.end_tolerance &&
                     (!last || goal.contains(w.sim.robot, w.ws.robot, r.qf));
  Attempt at;
  if (lands) {
    segment.start = q0;
    segment.times = std::move(j.times);
    segment.knots = std::move(j.knots);
    segment.first_step = a;
    segment.last_step = b;
    segment.result = r;
    segment.uniform = uniform;
    at.ok = true;
    return at;
  }
  if (j.junction_time.empty()) return at;
  // A failed check points at the junction nearest to it; a bad end, at the last junction.
  const double t_fail = r.valid() ? j.times.back() : r.ticks * w.sim.dt;
  double best = 0;
  for (size_t k = 0; k < j.junction_time.size(); ++k) {
    const double d = std::abs(j.junction_time[k] - t_fail);
    if (at.junction < 0 || d < best) {
      at.junction = static_cast<int>(k);
      best = d;
    }
  }
  return at;
}

// The blend scale of the junction between `st` and `next` (0: none within the limits).
double junction_scale(const RobotModel& robot, const ExecutionOptions& options, const Step& st,
                      const Step& next) {
  const int n = robot.dof;
  const int count = static_cast<int>(st.times.size());
  return blend_scale(robot, options, &st.knots[(count - 2) * n], &next.knots[n],
                     st.times[count - 1] - st.times[count - 2], next.times[1] - next.times[0]);
}

// The blend scale of every junction after step a (0: cannot be blended within the limits).
std::vector<double> junction_scales(const Work& w, const std::vector<Step>& steps, int a) {
  std::vector<double> scale;
  for (int s = a; s + 1 < static_cast<int>(steps.size()); ++s) {
    scale.push_back(w.options.blend ? junction_scale(w.sim.robot, w.options, steps[s], steps[s + 1])
                                    : 0.0);
  }
  return scale;
}

// Whether steps [a, b] hold a shortcut taken on its look alone
// (ExecutionOptions::looked_shortcuts).
bool looked_shortcut_in(const std::vector<Step>& steps, int a, int b) {
  for (int k = a; k <= b; ++k)
    if (steps[k].first_raw != steps[k].last_raw && !steps[k].simulated) return true;
  return false;
}

// Blend pass: segments from the left, each as long as its blends allow; a failing junction is
// first tried again with its longest blend, then split into a stop. False when a single step
// cannot be simulated from where the previous segment ended, or at the first failed attempt
// of a segment holding a looked shortcut (w.looked_shortcut_failed; the caller runs the passes
// again with simulated shortcuts, or falls back to the raw chain).
bool blend_segments(Work& w, const std::vector<Step>& steps, const RawChain& raw,
                    const JointVectorRef& start, const Goal& goal,
                    std::vector<ExecutionSegment>& segments, std::vector<double>& tick_rows,
                    std::vector<size_t>& segment_rows) {
  const int m = static_cast<int>(steps.size());
  JointVector q0 = start;
  for (int a = 0; a < m;) {
    std::vector<double> scale = junction_scales(w, steps, a);
    std::vector<bool> retried(scale.size(), false);
    int b = a;
    while (b + 1 < m && scale[b - a] > 0) ++b;
    ExecutionSegment seg;
    for (;;) {
      const Attempt at = try_segment(w, steps, raw, a, b, scale, q0, goal, seg);
      if (at.ok) break;
      if (looked_shortcut_in(steps, a, b)) {
        w.looked_shortcut_failed = true;
        return false;
      }
      if (at.junction < 0) return false;
      const double longest = w.options.blend_scales.back();
      if (!retried[at.junction] && scale[at.junction] < longest) {
        retried[at.junction] = true;
        scale[at.junction] = longest;
        continue;
      }
      b = a + at.junction;  // the junction after step b keeps its stop
    }
    tick_rows.insert(tick_rows.end(), w.trail.rows.begin(), w.trail.rows.end());
    segment_rows.push_back(w.trail.rows.size());
    q0 = seg.result.qf;
    segments.push_back(std::move(seg));
    a = b + 1;
  }
  return true;
}

// The sampled trajectory of the segments: every `every` control ticks of the whole and each
// segment's end; a segment's first row is the previous one's end (skipped).
Trajectory assemble(const Simulator& sim, const std::vector<ExecutionSegment>& segments,
                    const std::vector<double>& rows, const std::vector<size_t>& segment_rows,
                    int every) {
  const int n = sim.robot.dof;
  const size_t width = 4 * static_cast<size_t>(n);
  Trajectory t;
  size_t offset = 0;
  long tick0 = 0;
  for (size_t s = 0; s < segments.size(); ++s) {
    const size_t count = segment_rows[s] / width;
    for (size_t r = s == 0 ? 0 : 1; r < count; ++r) {
      const long tick = tick0 + static_cast<long>(r);
      if (tick % every != 0 && r + 1 != count) continue;
      const double* row = &rows[offset + r * width];
      t.t.push_back(tick * sim.dt);
      t.q.push_back(Eigen::Map<const Eigen::VectorXd>(row, n));
      t.dq.push_back(Eigen::Map<const Eigen::VectorXd>(row + n, n));
      t.ddq.push_back(Eigen::Map<const Eigen::VectorXd>(row + 2 * n, n));
      t.cmd.push_back(Eigen::Map<const Eigen::VectorXd>(row + 3 * n, n));
    }
    offset += segment_rows[s];
    tick0 += static_cast<long>(count) - 1;
    t.cost += segments[s].result.path_length;
  }
  t.duration = tick0 * sim.dt;
  t.stops = static_cast<int>(segments.size()) - 1;
  return t;
}

// The shortcut and blend passes; when an attempt at a segment with a looked shortcut (not
// simulated on its own) fails, both again with the shortcuts simulated. False as
// blend_segments.
bool shorten_and_blend(Work& w, const std::vector<PathStep>& steps, const RawChain& raw,
                       const JointVectorRef& start, const Goal& goal,
                       std::vector<ExecutionSegment>& segments, std::vector<double>& rows,
                       std::vector<size_t>& segment_rows) {
  const int n = w.sim.robot.dof;
  const int looked_blocked = w.stats.looked_blocked;  // the shortcut budget counts from here
  std::vector<Step> work = raw_steps(steps, raw, n);
  if (w.options.shortcut_attempts > 0) work = shortcut_steps(w, raw, std::move(work), goal);
  w.stats.steps = static_cast<int>(work.size());
  w.stats.junctions = w.stats.steps - 1;
  if (blend_segments(w, work, raw, start, goal, segments, rows, segment_rows)) return true;
  if (!w.looked_shortcut_failed) return false;
  ExecutionOptions simulated = w.options;
  simulated.looked_shortcuts = false;
  Work again{w.sim, w.final_sim, w.ws, simulated, w.stats, {}};
  w.stats.shortcuts = 0;
  w.stats.looked_blocked = looked_blocked;  // the passes again, as if they ran alone
  w.stats.shortcuts_simulated_again = true;
  segments.clear();
  rows.clear();
  segment_rows.clear();
  return shorten_and_blend(again, steps, raw, start, goal, segments, rows, segment_rows);
}

}  // namespace

ExecutableTrajectory make_executable(const Simulator& sim, SimulatorWorkspace& ws,
                                     const JointVectorRef& start,
                                     const std::vector<PathStep>& steps, const Goal& goal,
                                     const ExecutionOptions& options, int sample_every) {
  const auto clock_start = std::chrono::steady_clock::now();
  ExecutableTrajectory out;
  ExecutionStats& st = out.stats;
  Work raw_work{sim, sim, ws, options, st, {}};
  const RawChain raw = simulate_raw(raw_work, start, steps, goal);
  const Simulator stopping = execution_simulator(sim);
  Work w{stopping, sim, ws, options, st, {}};
  st.raw_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  st.raw_steps = static_cast<int>(steps.size());
  st.raw_duration = raw.duration;
  for (double c : raw.cost) st.raw_cost += c;
  st.raw_stops = st.raw_steps - 1;

  std::vector<double> rows;
  std::vector<size_t> segment_rows;
  if (shorten_and_blend(w, steps, raw, start, goal, out.segments, rows, segment_rows)) {
    out.trajectory = assemble(sim, out.segments, rows, segment_rows, std::max(1, sample_every));
    st.stops = out.trajectory.stops;
    st.blends_kept = st.junctions - st.stops;
  } else {
    // Nothing better could be validated: the raw chain, at the control rate.
    st.fell_back = true;
    out.segments.clear();
    std::vector<Step> plain = raw_steps(steps, raw, sim.robot.dof);
    ExecutionOptions stop_all = options;
    stop_all.blend = false;
    Work again{stopping, sim, ws, stop_all, st, {}};
    rows.clear();
    segment_rows.clear();
    if (!blend_segments(again, plain, raw, start, goal, out.segments, rows, segment_rows)) {
      // A stop that cannot settle for a dead stop within max_settle_time: the raw chain with
      // the planners' settle (valid as they simulated it; its junctions are not executable).
      Work planners{sim, sim, ws, stop_all, st, {}};
      rows.clear();
      segment_rows.clear();
      out.segments.clear();
      if (!blend_segments(planners, plain, raw, start, goal, out.segments, rows, segment_rows))
        fail("path", "the raw chain fails re-validation");
    }
    out.trajectory = assemble(sim, out.segments, rows, segment_rows, std::max(1, sample_every));
    st.steps = st.raw_steps;
    st.junctions = st.raw_steps - 1;
    st.shortcuts = 0;
    st.stops = st.junctions;
    st.blends_kept = 0;
  }
  for (const PathStep& s : steps) out.trajectory.edges.push_back(s.bundle_edge);
  st.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return out;
}

namespace {

// Simulates `step` from `from` with every check and its rows; while it ends valid outside
// `land_in` (null: never), corrects knots [first, last) of its command (knot times `times`) by
// the miss from `target` and simulates again, up to kDirectCorrections times.
void land(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& from,
          const JointVector& target, const Goal* land_in, const std::vector<double>& times,
          int first, PathStep& step, int* simulations) {
  const int last = static_cast<int>(times.size()) - 1;
  for (int round = 0;; ++round) {
    step.outcome_rows.clear();
    step.outcome = simulate(sim, ws, from, step.profile(sim.robot.dof),
                            {nullptr, nullptr, 0, &step.outcome_rows});
    if (simulations) *simulations = round + 1;
    if (!land_in || round >= kDirectCorrections || !step.outcome->valid() ||
        land_in->contains(sim.robot, ws.robot, step.outcome->qf))
      return;
    correct_command(times, step.knots, first, last, target - step.outcome->qf);
  }
}

}  // namespace

std::optional<PathStep> direct_step_to(const Simulator& sim, SimulatorWorkspace& ws,
                                       const CommandSampling& limits, const JointVectorRef& from,
                                       const JointVector& target, const Goal* land_in,
                                       int* simulations) {
  std::vector<double> times;
  PathStep step;
  if (!direct_command(sim.robot, limits, target - from, sim.dt, times, step.knots))
    return std::nullopt;
  // Evenly spaced knots (times[j] = j h), simulated as such: as a path step is.
  step.command_duration = times.back();
  land(sim, ws, from, target, land_in, times, 1, step, simulations);
  return step;
}

std::optional<PathStep> blended_step_through(const Simulator& sim, SimulatorWorkspace& ws,
                                             const ExecutionOptions& options,
                                             const std::vector<JointVector>& points,
                                             const Goal& land_in, int* simulations) {
  const int n = sim.robot.dof;
  const int parts = static_cast<int>(points.size()) - 1;
  if (parts < 1) return std::nullopt;
  CommandSampling limits = options.limits;
  if (parts > 1) limits.limit_scale *= kJunctionRoom;
  std::vector<Step> steps(parts);
  for (int k = 0; k < parts; ++k) {
    if (!direct_command(sim.robot, limits, points[k + 1] - points[k], sim.dt, steps[k].times,
                        steps[k].knots))
      return std::nullopt;
  }
  std::vector<double> scale;
  for (int k = 0; k + 1 < parts; ++k) {
    scale.push_back(junction_scale(sim.robot, options, steps[k], steps[k + 1]));
    if (scale.back() == 0) return std::nullopt;
  }
  Joined j = join_steps(steps, 0, parts - 1, scale, n);
  PathStep step;
  step.knots = std::move(j.knots);
  step.knot_times = std::move(j.times);
  step.command_duration = step.knot_times.back();
  land(sim, ws, points.front(), points.back(), &land_in, step.knot_times, j.last_step_first_knot,
       step, simulations);
  return step;
}

std::optional<PathStep> direct_step(const Simulator& sim, SimulatorWorkspace& ws,
                                    const CommandSampling& limits, const PlanningProblem& problem,
                                    int* simulations, int target) {
  const Goal& goal = problem.goal;
  const JointVector* to = direct_target(goal, target);
  if (!to) return std::nullopt;
  return direct_step_to(sim, ws, limits, problem.start, *to,
                        goal.kind == Goal::Kind::Joint ? nullptr : &goal, simulations);
}

const JointVector* direct_target(const Goal& goal, int target) {
  if (goal.kind == Goal::Kind::Joint) return &goal.q;
  if (target >= static_cast<int>(goal.configurations.size())) return nullptr;
  return &goal.configurations[target];
}

bool line_looks_free(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& from,
                     const JointVectorRef& to, uint64_t* checks) {
  const JointVector span = to - from;  // of fixed capacity (kMaxDof): no allocation
  const int steps = std::max(1, static_cast<int>(std::ceil(span.norm() / kLineLookStep)));
  JointVector q(from.size());
  for (int k = 1; k <= steps; ++k) {
    q = from + span * (static_cast<double>(k) / steps);
    if (checks) ++*checks;
    if (check_state(sim, ws, q) != RolloutStatus::Valid) return false;
  }
  return true;
}

bool solves(const Simulator& sim, SimulatorWorkspace& ws, const PathStep& step, const Goal& goal) {
  return step.outcome && step.outcome->valid() &&
         goal.contains(sim.robot, ws.robot, step.outcome->qf);
}

bool solved_by_direct_command(const Simulator& sim, SimulatorWorkspace& ws,
                              const CommandSampling& limits, const PlanningProblem& problem) {
  const std::optional<PathStep> step = direct_step(sim, ws, limits, problem);
  return step && solves(sim, ws, *step, problem.goal);
}

}  // namespace lazyboe
