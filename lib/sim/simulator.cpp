#include "lazyboe/sim/simulator.h"

#include <algorithm>
#include <cmath>

#include "lazyboe/common/error.h"

namespace lazyboe {

const char* rollout_status_name(RolloutStatus status) {
  switch (status) {
    case RolloutStatus::Valid:
      return "valid";
    case RolloutStatus::PositionLimit:
      return "position_limit";
    case RolloutStatus::VelocityLimit:
      return "velocity_limit";
    case RolloutStatus::AccelerationLimit:
      return "acceleration_limit";
    case RolloutStatus::JerkLimit:
      return "jerk_limit";
    case RolloutStatus::TorqueLimit:
      return "torque_limit";
    case RolloutStatus::TorqueRateLimit:
      return "torque_rate_limit";
    case RolloutStatus::SelfCollision:
      return "self_collision";
    case RolloutStatus::EnvCollision:
      return "env_collision";
    case RolloutStatus::NotSettled:
      return "not_settled";
    case RolloutStatus::EndEffectorSpeed:
      return "end_effector_speed";
    case RolloutStatus::EndEffectorAcceleration:
      return "end_effector_acceleration";
    case RolloutStatus::EndEffectorTilt:
      return "end_effector_tilt";
  }
  return "?";
}

const char* integrator_name(Integrator integrator) {
  return integrator == Integrator::RK4 ? "rk4" : "euler";
}

Integrator parse_integrator(const std::string& name, const std::string& where) {
  if (name == "euler") return Integrator::SemiImplicitEuler;
  if (name == "rk4") return Integrator::RK4;
  fail(where, "expected euler or rk4, got '" + name + "'");
}

int sample_every_ticks(double interval_s, double control_rate) {
  return static_cast<int>(std::lround(interval_s * control_rate));
}

double sample_interval_seconds(int ticks, double control_rate) { return ticks / control_rate; }

int exact_sample_every_ticks(double interval_s, double control_rate, const std::string& where) {
  const int ticks = sample_every_ticks(interval_s, control_rate);
  if (interval_s > 0 &&
      std::abs(sample_interval_seconds(ticks, control_rate) - interval_s) > 1e-9) {
    fail(where,
         "must be a multiple of the control period (" + std::to_string(1 / control_rate) + " s)");
  }
  return ticks;
}

// r_i: a point of a shape on body b >= i is at most
//   sum_{k=i+1..b} |origin of joint k in body k-1| + |shape origin in body b| + shape radius
// from joint i's origin, so turning joint i by dq moves it at most r_i |dq| (a prismatic
// joint moves everything by exactly |dq|). Summed over joints, this bounds the path length of
// every point of the robot for a small joint motion.
JointVector collision_lever_arms(const RobotModel& robot, const CollisionModel& collision) {
  const int n = robot.dof;
  JointVector r = JointVector::Zero(n);
  for (int i = 0; i < n; ++i) {
    if (robot.joints[i].type == JointType::Prismatic) {
      r[i] = 1.0;
      continue;
    }
    for (const CollisionModel::RobotShape& s : collision.robot) {
      if (s.body < i) continue;
      double reach = s.in_body.p.norm() + s.sphere_radius;
      for (int k = i + 1; k <= s.body; ++k) reach += robot.joints[k].origin.p.norm();
      r[i] = std::max(r[i], reach);
    }
  }
  return r;
}

namespace {

bool within(const JointVector& value, const JointVector& bound) {
  return (value.array().abs() <= bound.array()).all();
}

}  // namespace

Simulator::Simulator(const RobotModel& robot_model, const CollisionModel& collision_model,
                     SimulationOptions opts, EndEffectorLimits end_effector_limits)
    : robot(robot_model),
      collision(collision_model),
      options(opts),
      end_effector(end_effector_limits),
      dt(1.0 / robot_model.control_rate),
      lever_arm(collision_lever_arms(robot_model, collision_model)) {
  if (!robot.controller.present) {
    fail(robot.files.config,
         "controller: missing (the simulator needs the joint controller gains)");
  }
  if (options.substeps < 1) fail("substeps", "must be >= 1");
}

SimulatorWorkspace::SimulatorWorkspace(const Simulator& sim)
    : robot(sim.robot), collision(sim.collision) {}

RolloutStatus check_state(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& q) {
  const RobotModel& robot = sim.robot;
  if (!((q.array() > robot.q_min.array()).all() && (q.array() < robot.q_max.array()).all())) {
    return RolloutStatus::PositionLimit;
  }
  forward_kinematics(robot, ws.robot, q);
  update_collision_transforms(sim.collision, ws.collision, ws.robot);
  const CollisionReport report = check_collision(sim.collision, ws.collision);
  if (report.env_collision) return RolloutStatus::EnvCollision;
  if (report.self_collision) return RolloutStatus::SelfCollision;
  if (sim.end_effector.any() &&
      !(end_effector_tilt(robot, ws.robot, sim.end_effector) <= sim.end_effector.max_tilt))
    return RolloutStatus::EndEffectorTilt;
  return RolloutStatus::Valid;
}

namespace {

RolloutStatus collision_status(const Simulator& sim, SimulatorWorkspace& ws, const JointVector& q,
                               int& checks) {
  ++checks;
  forward_kinematics(sim.robot, ws.robot, q);
  update_collision_transforms(sim.collision, ws.collision, ws.robot);
  if (!in_collision(sim.collision, ws.collision)) return RolloutStatus::Valid;
  const CollisionReport report = check_collision(sim.collision, ws.collision);
  return report.env_collision ? RolloutStatus::EnvCollision : RolloutStatus::SelfCollision;
}

// One row of TrajectorySamples::ticks; its acceleration is filled in once known. One resize and
// four copies rather than four range inserts: 1.6 % fewer instructions in a one-rollout query
// (callgrind, docs/performance.md).
void push_tick(std::vector<double>& ticks, const JointVector& q, const JointVector& dq,
               const JointVector& ddq, const JointVector& v_cmd) {
  const size_t n = static_cast<size_t>(q.size()), at = ticks.size();
  ticks.resize(at + 4 * n);
  double* row = ticks.data() + at;
  std::copy_n(q.data(), n, row);
  std::copy_n(dq.data(), n, row + n);
  std::copy_n(ddq.data(), n, row + 2 * n);
  std::copy_n(v_cmd.data(), n, row + 3 * n);
}

// The command's rows and half as many for the settle at once (a blended step of the lazysp
// shortcut test: 1,477 rows for 1,030 of its command), not a vector doubled ten times.
void reserve_ticks(std::vector<double>& ticks, int n, double command_ticks) {
  const auto rows = static_cast<size_t>(1.5 * std::ceil(command_ticks) + 2);
  ticks.reserve(ticks.size() + 4 * static_cast<size_t>(n) * rows);
}

void push_sample(const TrajectorySamples& samples, const JointVector& q, const JointVector& dq) {
  if (!samples.q) return;
  for (int i = 0; i < q.size(); ++i) {
    samples.q->push_back(static_cast<float>(q[i]));
    samples.dq->push_back(static_cast<float>(dq[i]));
  }
}

// Integration stages, allocated once per rollout.
struct Stages {
  explicit Stages(int n) : k1q(n), k1v(n), k2q(n), k2v(n), k3q(n), k3v(n), k4q(n), k4v(n) {}
  JointVector k1q, k1v, k2q, k2v, k3q, k3v, k4q, k4v;
};

// One control period with the torque held: `substeps` steps (of h) of RK4 or semi-implicit Euler.
// The first step reuses the dynamics terms of this tick's state; ddq is its acceleration.
// Both helpers are inlined into simulate (they run every tick), as before they were split out.
[[gnu::always_inline]] inline void integrate_period(const Simulator& sim, RobotData& rd,
                                                    const JointVector& tau, double h,
                                                    JointVector& q, JointVector& dq,
                                                    JointVector& ddq, Stages& k) {
  const RobotModel& robot = sim.robot;
  for (int sub = 0; sub < sim.options.substeps; ++sub) {
    if (sim.options.integrator == Integrator::SemiImplicitEuler) {
      k.k1v =
          sub == 0 ? forward_dynamics_from_terms(rd, tau) : forward_dynamics(robot, rd, q, dq, tau);
      if (sub == 0) ddq = k.k1v;
      dq += h * k.k1v;
      q += h * dq;
      continue;
    }
    k.k1q = dq;
    k.k1v =
        sub == 0 ? forward_dynamics_from_terms(rd, tau) : forward_dynamics(robot, rd, q, dq, tau);
    if (sub == 0) ddq = k.k1v;
    k.k2q = dq + 0.5 * h * k.k1v;
    k.k2v = forward_dynamics(robot, rd, q + 0.5 * h * k.k1q, k.k2q, tau);
    k.k3q = dq + 0.5 * h * k.k2v;
    k.k3v = forward_dynamics(robot, rd, q + 0.5 * h * k.k2q, k.k3q, tau);
    k.k4q = dq + h * k.k3v;
    k.k4v = forward_dynamics(robot, rd, q + h * k.k3q, k.k4q, tau);
    q += (h / 6) * (k.k1q + 2 * k.k2q + 2 * k.k3q + k.k4q);
    dq += (h / 6) * (k.k1v + 2 * k.k2v + 2 * k.k3v + k.k4v);
  }
}

// Collision checks spaced so that no point moves more than the margin between two: `moved`
// bounds the path length of any point since the last check; a tick that moves too far is
// checked in between as well (at `between`, scratch).
[[gnu::always_inline]] inline RolloutStatus check_motion(const Simulator& sim,
                                                         SimulatorWorkspace& ws,
                                                         const JointVector& q_prev,
                                                         const JointVector& q, double& moved,
                                                         JointVector& between, int& checks) {
  const double margin = sim.collision.margin;
  const double step = sim.lever_arm.dot((q - q_prev).cwiseAbs());
  if (!(moved + step > margin)) {
    moved += step;
    return RolloutStatus::Valid;
  }
  if (moved > 0) {
    const RolloutStatus c = collision_status(sim, ws, q_prev, checks);
    if (c != RolloutStatus::Valid) return c;
  }
  moved = step;
  if (step > margin) {
    const int pieces = static_cast<int>(std::ceil(step / margin));
    for (int j = 1; j < pieces; ++j) {
      between = q_prev + (static_cast<double>(j) / pieces) * (q - q_prev);
      const RolloutStatus c = collision_status(sim, ws, between, checks);
      if (c != RolloutStatus::Valid) return c;
    }
    moved = step / pieces;
  }
  return RolloutStatus::Valid;
}

// Stopping dead within one tick from dq takes the acceleration a = -dq / dt, a jerk of
// (a - ddq_prev) / dt and a torque change of about M(q) (a - ddq_prev) (rd.M: this tick's).
bool can_stop_dead(const RobotModel& robot, const RobotData& rd, const JointVector& dq,
                   const JointVector& ddq_prev, double dt) {
  const JointVector jump = -dq / dt - ddq_prev;
  if (!within(dq / dt, robot.ddq_max) || !within(jump, robot.dddq_max * dt)) return false;
  return within(rd.M * jump, 0.5 * robot.dtau_max * dt);
}

// Joint controller: gravity, friction and inertia feed-forward, P on the velocity error (rd:
// this tick's dynamics terms).
[[gnu::always_inline]] inline void controller_torque(const RobotModel& robot, const RobotData& rd,
                                                     const JointVector& v_cmd,
                                                     const JointVector& a_cmd,
                                                     const JointVector& dq, JointVector& tau) {
  const ControllerGains& gains = robot.controller;
  tau = rd.gravity;
  for (int i = 0; i < robot.dof; ++i) {
    tau[i] += gains.ka[i] * a_cmd[i] + gains.kv[i] * (v_cmd[i] - dq[i]);
    if (gains.friction_feedforward) tau[i] += friction_torque(robot.joints[i].friction, v_cmd[i]);
  }
}

// At rest after the command: the next edge could start without a jump in velocity,
// acceleration (jerk) or torque (the next edge starts from holding torque g(q)).
[[gnu::always_inline]] inline bool at_rest(const Simulator& sim, const RobotData& rd,
                                           const JointVector& dq, const JointVector& ddq_prev,
                                           const JointVector& tau, const JointVector& ddq_step_max,
                                           const JointVector& tau_rate_max) {
  return (dq.array().abs() <= sim.options.settle_velocity).all() &&
         within(ddq_prev, ddq_step_max) && within(tau - rd.gravity, tau_rate_max) &&
         (!sim.options.settle_for_stop || can_stop_dead(sim.robot, rd, dq, ddq_prev, sim.dt));
}

// The position and velocity limits of the state reached.
[[gnu::always_inline]] inline RolloutStatus state_limits(const RobotModel& robot,
                                                         const JointVector& q,
                                                         const JointVector& dq) {
  if (!((q.array() > robot.q_min.array()).all() && (q.array() < robot.q_max.array()).all()))
    return RolloutStatus::PositionLimit;
  if (!within(dq, robot.dq_max)) return RolloutStatus::VelocityLimit;
  return RolloutStatus::Valid;
}

// The limited link's velocity at each tick and its change over the tick (a task's end-effector
// limits; nothing when it has none). Before the rollout the arm is at rest.
class EndEffectorTrack {
 public:
  explicit EndEffectorTrack(const Simulator& sim, RobotData& rd)
      : sim_(sim), limits_(sim.end_effector), rd_(rd) {}
  // The state reached by a tick: its speed, acceleration (on the first tick, half the limit:
  // the other half is the previous rollout's last tick) and tilt.
  RolloutStatus step(const JointVector& q, const JointVector& dq, bool first) {
    if (!limits_.any()) return RolloutStatus::Valid;
    forward_kinematics(sim_.robot, rd_, q);
    const Eigen::Vector3d v = link_linear_velocity(sim_.robot, rd_, limits_.link, dq);
    const double acceleration = (v - v_).norm() / sim_.dt;
    v_ = v;
    if (!(v.norm() <= limits_.max_linear_speed)) return RolloutStatus::EndEffectorSpeed;
    if (!(acceleration <= (first ? 0.5 : 1.0) * limits_.max_linear_acceleration))
      return RolloutStatus::EndEffectorAcceleration;
    if (!(end_effector_tilt(sim_.robot, rd_, limits_) <= limits_.max_tilt))
      return RolloutStatus::EndEffectorTilt;
    return RolloutStatus::Valid;
  }
  // Stopping here: the next rollout starts from rest, a change of velocity from v_ to 0 within
  // a tick; half the acceleration limit for that.
  bool can_rest() const {
    return !limits_.any() || v_.norm() / sim_.dt <= 0.5 * limits_.max_linear_acceleration;
  }
  // The velocity of the last tick (a checkpoint's share of this tracker).
  const Eigen::Vector3d& velocity() const { return v_; }
  void set_velocity(const Eigen::Vector3d& v) { v_ = v; }

 private:
  const Simulator& sim_;
  const EndEffectorLimits& limits_;
  RobotData& rd_;
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
};

}  // namespace

int ticks_before(const Simulator& sim, double t) {
  constexpr double kMargin = 1e-9;  // s: a tick at the change (up to rounding) counts as after
  if (!(t - kMargin > 0)) return 0;
  // From the estimate, settled with the comparison simulate's tick times make.
  int tick = static_cast<int>(std::min(std::floor((t - kMargin) / sim.dt), 2e9));
  while (tick > 0 && !((tick - 1) * sim.dt < t - kMargin)) --tick;
  while (tick < 2000000000 && tick * sim.dt < t - kMargin) ++tick;
  return tick;
}

bool same_until_settling(const Simulator& a, const Simulator& b) {
  const SimulationOptions &x = a.options, &y = b.options;
  const EndEffectorLimits &e = a.end_effector, &f = b.end_effector;
  return &a.robot == &b.robot && &a.collision == &b.collision && a.dt == b.dt &&
         x.integrator == y.integrator && x.substeps == y.substeps && e.link == f.link &&
         e.max_linear_speed == f.max_linear_speed &&
         e.max_linear_acceleration == f.max_linear_acceleration && e.max_tilt == f.max_tilt &&
         e.axis == f.axis;
}

namespace {

// What a rollout carries from one control tick to the next (a checkpoint's content).
struct TickState {
  JointVector q, dq, tau_prev, ddq_prev;
  double moved = 0;  // bound on any point's path length since the last collision check
};

// The checkpoints a rollout saves (RolloutResume::save_at, into RolloutResume::saved).
class CheckpointSaver {
 public:
  CheckpointSaver(const RolloutResume& resume, int first_tick)
      : at_(resume.saved ? resume.save_at : nullptr), saved_(resume.saved) {
    while (at_ && next_ < at_->size() && (*at_)[next_] < first_tick) ++next_;
  }
  bool due(int tick) const { return at_ && next_ < at_->size() && (*at_)[next_] == tick; }
  void save(const TickState& s, const RolloutResult& result, int tick,
            const Eigen::Vector3d& end_effector_velocity, const TrajectorySamples& samples) {
    while (due(tick)) ++next_;  // one checkpoint for repeated ticks
    saved_->emplace_back();
    RolloutCheckpoint& out = saved_->back();
    out.tick = tick;
    out.q = s.q;
    out.dq = s.dq;
    out.tau_prev = s.tau_prev;
    out.ddq_prev = s.ddq_prev;
    out.moved = s.moved;
    out.partial = result;
    out.end_effector_velocity = end_effector_velocity;
    out.tick_values = samples.ticks ? samples.ticks->size() : 0;
  }

 private:
  const std::vector<int>* at_;
  std::vector<RolloutCheckpoint>* saved_;
  size_t next_ = 0;
};

// A rollout's first tick: at rest at s.q, its start state checked (-1 and result.status when
// it fails), or on from a checkpoint.
int start_rollout(const Simulator& sim, SimulatorWorkspace& ws, const TrajectorySamples& samples,
                  const RolloutCheckpoint* from, TickState& s, RolloutResult& result,
                  EndEffectorTrack& end_effector) {
  if (from) {
    if (samples.q) fail("simulate", "a resumed rollout takes no float samples");
    if ((samples.ticks ? samples.ticks->size() : 0) != from->tick_values)
      fail("simulate", "a resumed rollout needs the tick rows up to its checkpoint");
    s = TickState{from->q, from->dq, from->tau_prev, from->ddq_prev, from->moved};
    result = from->partial;
    end_effector.set_velocity(from->end_effector_velocity);
    return from->tick;
  }
  // At rest before the edge, the controller holds the arm against gravity.
  s.tau_prev = gravity_torques(sim.robot, ws.robot, s.q);
  const RolloutStatus start = check_state(sim, ws, s.q);
  ++result.collision_checks;
  result.status = start;
  if (start != RolloutStatus::Valid) return -1;
  push_sample(samples, s.q, s.dq);
  return 0;
}

// A rollout's end at rest: the last motion collision-checked, then its last sample and tick.
RolloutStatus end_at_rest(const Simulator& sim, SimulatorWorkspace& ws, const TickState& s,
                          const JointVector& v_cmd, const TrajectorySamples& samples,
                          int sample_every, int tick, RolloutResult& result) {
  if (s.moved > 0) {
    const RolloutStatus c = collision_status(sim, ws, s.q, result.collision_checks);
    if (c != RolloutStatus::Valid) return c;
  }
  if (samples.q && (sample_every <= 0 || tick % sample_every != 0)) push_sample(samples, s.q, s.dq);
  if (samples.ticks) push_tick(*samples.ticks, s.q, s.dq, s.ddq_prev, v_cmd);
  return RolloutStatus::Valid;
}

}  // namespace

RolloutResult simulate(const Simulator& sim, SimulatorWorkspace& ws, const JointVectorRef& q0_in,
                       const CommandProfile& profile, TrajectorySamples samples,
                       RolloutResume resume) {
  const RobotModel& robot = sim.robot;
  const int n = robot.dof;
  const double dt = sim.dt, h = dt / sim.options.substeps;
  const int sample_every = samples.every > 0 ? samples.every : sim.options.sample_every;
  RobotData& rd = ws.robot;

  RolloutResult result;
  TickState s{q0_in, JointVector::Zero(n), {}, JointVector::Zero(n), 0};
  JointVector& q = s.q;
  JointVector& dq = s.dq;
  JointVector q_prev = q, v_cmd(n), a_cmd(n), tau(n);
  Stages k(n);
  JointVector ddq(n);
  const JointVector tau_rate_max = robot.dtau_max * dt;
  const JointVector ddq_step_max = robot.dddq_max * dt;
  EndEffectorTrack end_effector(sim, rd);

  auto finish = [&](RolloutStatus status, int tick) {
    result.status = status;
    result.qf = q;
    result.ticks = tick;
    result.duration = tick * dt;
    return result;
  };

  const int first_tick = start_rollout(sim, ws, samples, resume.from, s, result, end_effector);
  if (first_tick < 0) return finish(result.status, 0);

  const int max_ticks =
      static_cast<int>(std::ceil((profile.duration + sim.options.max_settle_time) / dt));
  if (samples.ticks) reserve_ticks(*samples.ticks, n, profile.duration / dt);
  CheckpointSaver saver(resume, first_tick);
  for (int tick = first_tick; tick < max_ticks; ++tick) {
    if (saver.due(tick)) saver.save(s, result, tick, end_effector.velocity(), samples);
    if (tick == resume.stop_at) {
      result.stopped = true;
      return finish(RolloutStatus::Valid, tick);
    }
    const double t = tick * dt;
    evaluate_command(profile, t, v_cmd.data(), a_cmd.data(), nullptr);

    // Mass matrix, gravity and velocity terms at this tick's state, shared by the controller
    // and the first integration step.
    dynamics_terms(robot, rd, q, dq);
    controller_torque(robot, rd, v_cmd, a_cmd, dq, tau);
    if (!within(tau, robot.tau_max)) return finish(RolloutStatus::TorqueLimit, tick);
    if (!within(tau - s.tau_prev, tau_rate_max))
      return finish(RolloutStatus::TorqueRateLimit, tick);
    s.tau_prev = tau;

    // Stop once at rest after the command.
    if (t >= profile.duration &&
        at_rest(sim, rd, dq, s.ddq_prev, tau, ddq_step_max, tau_rate_max) &&
        end_effector.can_rest()) {
      return finish(end_at_rest(sim, ws, s, v_cmd, samples, sample_every, tick, result), tick);
    }

    if (samples.ticks) push_tick(*samples.ticks, q, dq, s.ddq_prev, v_cmd);
    q_prev = q;
    integrate_period(sim, rd, tau, h, q, dq, ddq, k);
    if (samples.ticks) std::copy(ddq.data(), ddq.data() + n, samples.ticks->end() - 2 * n);
    if (!within(ddq, robot.ddq_max)) return finish(RolloutStatus::AccelerationLimit, tick);
    if (!within(ddq - s.ddq_prev, ddq_step_max)) return finish(RolloutStatus::JerkLimit, tick);
    s.ddq_prev = ddq;
    const RolloutStatus limits = state_limits(robot, q, dq);
    if (limits != RolloutStatus::Valid) return finish(limits, tick + 1);
    const RolloutStatus task = end_effector.step(q, dq, tick == 0);
    if (task != RolloutStatus::Valid) return finish(task, tick + 1);

    result.path_length += (q - q_prev).norm();
    const RolloutStatus c =
        check_motion(sim, ws, q_prev, q, s.moved, k.k1q, result.collision_checks);
    if (c != RolloutStatus::Valid) return finish(c, tick);
    if (sample_every > 0 && (tick + 1) % sample_every == 0) push_sample(samples, q, dq);
  }
  return finish(RolloutStatus::NotSettled, max_ticks);
}

}  // namespace lazyboe
