#include "lazyboe/sim/trajectory_check.h"

#include <cmath>
#include <cstdio>

#include "lazyboe/common/error.h"

namespace lazyboe {

const char* trajectory_limit_name(TrajectoryLimit limit) {
  switch (limit) {
    case TrajectoryLimit::Position:
      return "position_limit";
    case TrajectoryLimit::Velocity:
      return "velocity_limit";
    case TrajectoryLimit::Acceleration:
      return "acceleration_limit";
    case TrajectoryLimit::Jerk:
      return "jerk_limit";
    case TrajectoryLimit::Torque:
      return "torque_limit";
    case TrajectoryLimit::TorqueRate:
      return "torque_rate_limit";
    case TrajectoryLimit::StartAtRest:
      return "start_not_at_rest";
    case TrajectoryLimit::EndAtRest:
      return "end_not_at_rest";
    case TrajectoryLimit::SelfCollision:
      return "self_collision";
    case TrajectoryLimit::EnvCollision:
      return "env_collision";
    case TrajectoryLimit::EndEffectorSpeed:
      return "end_effector_speed";
    case TrajectoryLimit::EndEffectorAcceleration:
      return "end_effector_acceleration";
    case TrajectoryLimit::EndEffectorTilt:
      return "end_effector_tilt";
  }
  return "?";
}

TrajectoryChecker::TrajectoryChecker(const RobotModel& robot_model,
                                     const CollisionModel& collision_model,
                                     TrajectoryCheckOptions opts)
    : robot(robot_model),
      collision(collision_model),
      options(opts),
      dt(1.0 / robot_model.control_rate),
      lever_arm(collision_lever_arms(robot_model, collision_model)) {}

TrajectoryCheckWorkspace::TrajectoryCheckWorkspace(const TrajectoryChecker& checker)
    : robot(checker.robot), collision(checker.collision) {}

int first_bad_spacing(const TrajectoryChecker& checker, const TrajectoryView& traj) {
  for (int k = 1; k < traj.samples; ++k) {
    if (!(std::abs(traj.t[k] - traj.t[k - 1] - checker.dt) <= checker.options.time_tolerance))
      return k;
  }
  return -1;
}

namespace {

using Vec = Eigen::Map<const Eigen::VectorXd>;

// One pass over the samples in time order. Per sample k: collision of the motion that led to
// it (the simulator's margin rule: configurations before t_k), then its position, velocity and
// rest, then the control period k -> k+1 (velocity from positions, acceleration, torque) and the
// jerk and torque rate at k (from period k-1; before the first sample and after the last the
// robot holds still at g(q)), then (first sample) its collision. Every estimate is compared with
// its limit plus its rounding allowance.
class Scan {
 public:
  Scan(const TrajectoryChecker& checker, TrajectoryCheckWorkspace& ws, const TrajectoryView& traj)
      : checker_(checker),
        robot_(checker.robot),
        ws_(ws),
        traj_(traj),
        o_(checker.options),
        n_(robot_.dof) {
    result.samples = traj.samples;
    result.duration = traj.t[traj.samples - 1] - traj.t[0];
    a_prev_ = JointVector::Zero(n_);
    a_err_prev_ = JointVector::Zero(n_);
    tau_prev_ = gravity_torques(robot_, ws_.robot, q(0));
    tau_err_prev_ = JointVector::Zero(n_);
  }

  void run() {
    const int last = traj_.samples - 1;
    for (int k = 0; k <= last; ++k) {
      if (k > 0 && o_.check_collision && motion_collides(k)) return;
      if (sample_violates(k)) return;
      if (o_.end_effector.any() && end_effector_violates(k)) return;
      if (period_violates(k)) return;
      if (k == 0 && o_.check_collision && collides_at(0, 0.0, q(0))) return;
    }
    if (o_.check_collision && moved_ > 0 && collides_at(last, 0.0, q(last))) return;
  }

  TrajectoryCheckResult result;

 private:
  Vec q(int k) const { return Vec(traj_.q + static_cast<size_t>(k) * n_, n_); }
  Vec dq(int k) const { return Vec(traj_.dq + static_cast<size_t>(k) * n_, n_); }
  double time(int k) const { return traj_.t[k]; }

  // Records the peak and, when |value| exceeds bound + allowance, the violation.
  bool over(TrajectoryLimit limit, int k, int joint, double value, double bound, double allowance) {
    const int l = static_cast<int>(limit);
    if (l < kJointLimitCount && std::abs(value) / bound > result.peak_fraction[l]) {
      result.peak_fraction[l] = std::abs(value) / bound;
      result.peak_joint[l] = joint;
    }
    if (std::abs(value) <= bound + allowance) return false;
    violate(limit, k, time(k), joint, value, bound);
    return true;
  }

  void violate(TrajectoryLimit limit, int k, double t, int joint, double value, double bound) {
    result.valid = false;
    TrajectoryViolation& v = result.violation;
    v.limit = limit;
    v.sample = k;
    v.time = t;
    v.joint = joint;
    v.value = value;
    v.bound = bound;
  }

  bool sample_violates(int k) {
    const double u = o_.sample_precision;
    const Vec qk = q(k), dqk = dq(k);
    for (int i = 0; i < n_; ++i) {
      // Strictly inside the range, as the simulator requires.
      const double mid = 0.5 * (robot_.q_min[i] + robot_.q_max[i]);
      const double half = 0.5 * (robot_.q_max[i] - robot_.q_min[i]);
      const double off = qk[i] - mid, slack = u * std::abs(qk[i]);
      if (std::abs(off) / half > result.peak_fraction[0]) {
        result.peak_fraction[0] = std::abs(off) / half;
        result.peak_joint[0] = i;
      }
      if (!(std::abs(off) < half + slack)) {
        violate(TrajectoryLimit::Position, k, time(k), i, qk[i],
                off > 0 ? robot_.q_max[i] : robot_.q_min[i]);
        return true;
      }
    }
    for (int i = 0; i < n_; ++i) {
      if (over(TrajectoryLimit::Velocity, k, i, dqk[i], robot_.dq_max[i], u * std::abs(dqk[i])))
        return true;
    }
    const bool first = k == 0, last = k == traj_.samples - 1;
    if (first || last) {
      const TrajectoryLimit rest =
          first ? TrajectoryLimit::StartAtRest : TrajectoryLimit::EndAtRest;
      for (int i = 0; i < n_; ++i) {
        if (over(rest, k, i, dqk[i], o_.rest_velocity, 0)) return true;
      }
    }
    return false;
  }

  // The torque held over period k: inverse dynamics, friction included, at the period's
  // midpoint state with its mean acceleration a (second-order accurate for a torque held
  // over the period); `err` gets |M| a_err, the part of its rounding error that matters.
  void period_torque(int k, const JointVector& a, const JointVector& a_err, JointVector& tau,
                     JointVector& err) {
    mid_q_ = 0.5 * (q(k) + q(k + 1));
    mid_dq_ = 0.5 * (dq(k) + dq(k + 1));
    RobotData& rd = ws_.robot;
    dynamics_terms(robot_, rd, mid_q_, mid_dq_);
    tau.noalias() = rd.M * a;
    tau += rd.h + rd.gravity;
    err.noalias() = rd.M.cwiseAbs() * a_err;
  }

  bool period_violates(int k) {
    const double u = o_.sample_precision, dt = checker_.dt;
    const bool last = k == traj_.samples - 1;
    JointVector a(n_), a_err(n_), tau(n_), tau_err(n_);
    if (last) {  // held still afterwards
      a.setZero();
      a_err.setZero();
      tau = gravity_torques(robot_, ws_.robot, q(k));
      tau_err.setZero();
    } else {
      const Vec q0 = q(k), q1 = q(k + 1), dq0 = dq(k), dq1 = dq(k + 1);
      for (int i = 0; i < n_; ++i) {
        const double v = (q1[i] - q0[i]) / dt;
        const double v_err = u * (std::abs(q1[i]) + std::abs(q0[i])) / dt;
        if (over(TrajectoryLimit::Velocity, k, i, v, robot_.dq_max[i], v_err)) return true;
      }
      a = (dq1 - dq0) / dt;
      a_err = u * (dq1.cwiseAbs() + dq0.cwiseAbs()) / dt;
      for (int i = 0; i < n_; ++i) {
        if (over(TrajectoryLimit::Acceleration, k, i, a[i], robot_.ddq_max[i], a_err[i]))
          return true;
      }
    }
    for (int i = 0; i < n_; ++i) {
      const double jerk = (a[i] - a_prev_[i]) / dt;
      if (over(TrajectoryLimit::Jerk, k, i, jerk, robot_.dddq_max[i],
               (a_err[i] + a_err_prev_[i]) / dt))
        return true;
    }
    if (!last) {
      period_torque(k, a, a_err, tau, tau_err);
      for (int i = 0; i < n_; ++i) {
        if (over(TrajectoryLimit::Torque, k, i, tau[i], robot_.tau_max[i], tau_err[i])) return true;
      }
    }
    for (int i = 0; i < n_; ++i) {
      const double rate = (tau[i] - tau_prev_[i]) / dt;
      if (over(TrajectoryLimit::TorqueRate, k, i, rate, robot_.dtau_max[i],
               (tau_err[i] + tau_err_prev_[i]) / dt))
        return true;
    }
    a_prev_ = a;
    a_err_prev_ = a_err;
    tau_prev_ = tau;
    tau_err_prev_ = tau_err;
    return false;
  }

  // The end-effector limits at sample k: its speed and tilt, and its velocity change since the
  // previous sample (from rest before the first) and, after the last, back to rest. The
  // allowance: how far rounding of dq by the sample precision moves the velocity.
  bool end_effector_violates(int k) {
    const EndEffectorLimits& e = o_.end_effector;
    const double u = o_.sample_precision, dt = checker_.dt;
    RobotData& rd = ws_.robot;
    forward_kinematics(robot_, rd, q(k));
    const Eigen::Vector3d v = link_linear_velocity(robot_, rd, e.link, dq(k));
    const double v_err = u * checker_.lever_arm.dot(dq(k).cwiseAbs());
    if (end_effector_over(TrajectoryLimit::EndEffectorSpeed, k, v.norm(), e.max_linear_speed,
                          v_err) ||
        end_effector_over(TrajectoryLimit::EndEffectorAcceleration, k, (v - v_prev_).norm() / dt,
                          e.max_linear_acceleration, (v_err + v_err_prev_) / dt) ||
        end_effector_over(TrajectoryLimit::EndEffectorTilt, k, end_effector_tilt(robot_, rd, e),
                          e.max_tilt, u * q(k).cwiseAbs().sum()))
      return true;
    v_prev_ = v;
    v_err_prev_ = v_err;
    return k == traj_.samples - 1 &&
           end_effector_over(TrajectoryLimit::EndEffectorAcceleration, k, v.norm() / dt,
                             e.max_linear_acceleration, v_err / dt);
  }

  bool end_effector_over(TrajectoryLimit limit, int k, double value, double bound,
                         double allowance) {
    if (value <= bound + allowance) return false;
    violate(limit, k, time(k), -1, value, bound);
    return true;
  }

  // Collision of configuration x, checked at time t(k) + dt_after.
  bool collides_at(int k, double dt_after, const JointVectorRef& x) {
    ++result.collision_checks;
    forward_kinematics(robot_, ws_.robot, x);
    update_collision_transforms(checker_.collision, ws_.collision, ws_.robot);
    if (!in_collision(checker_.collision, ws_.collision)) return false;
    const CollisionReport report = check_collision(checker_.collision, ws_.collision);
    const DistanceReport distance = min_distance(checker_.collision, ws_.collision);
    const bool env = report.env_collision;
    violate(env ? TrajectoryLimit::EnvCollision : TrajectoryLimit::SelfCollision, k,
            time(k) + dt_after, -1, env ? distance.env_distance : distance.self_distance,
            checker_.collision.margin);
    result.violation.shape_a = report.first_a;
    result.violation.shape_b = report.first_b;
    return true;
  }

  // The simulator's rule (check_motion in simulator.cpp): `moved_` bounds the path length of
  // any robot point since the last check; a check is made before it would pass the margin, and
  // a motion longer than the margin between two samples is checked in between as well.
  bool motion_collides(int k) {
    const double margin = checker_.collision.margin;
    const Vec q0 = q(k - 1), q1 = q(k);
    const double step = checker_.lever_arm.dot((q1 - q0).cwiseAbs());
    if (!(moved_ + step > margin)) {
      moved_ += step;
      return false;
    }
    if (moved_ > 0 && collides_at(k - 1, 0.0, q0)) return true;
    moved_ = step;
    if (step > margin) {
      const int pieces = static_cast<int>(std::ceil(step / margin));
      for (int j = 1; j < pieces; ++j) {
        const double s = static_cast<double>(j) / pieces;
        between_ = q0 + s * (q1 - q0);
        if (collides_at(k - 1, s * (time(k) - time(k - 1)), between_)) return true;
      }
      moved_ = step / pieces;
    }
    return false;
  }

  const TrajectoryChecker& checker_;
  const RobotModel& robot_;
  TrajectoryCheckWorkspace& ws_;
  const TrajectoryView& traj_;
  const TrajectoryCheckOptions& o_;
  const int n_;
  JointVector a_prev_, a_err_prev_, tau_prev_, tau_err_prev_;
  JointVector mid_q_, mid_dq_, between_;
  double moved_ = 0;
  Eigen::Vector3d v_prev_ = Eigen::Vector3d::Zero();  // end-effector velocity, previous sample
  double v_err_prev_ = 0;
};

}  // namespace

TrajectoryCheckResult check_trajectory(const TrajectoryChecker& checker,
                                       TrajectoryCheckWorkspace& ws, const TrajectoryView& traj) {
  if (traj.dof != checker.robot.dof) {
    fail("trajectory",
         std::to_string(traj.dof) + " joints, the robot has " + std::to_string(checker.robot.dof));
  }
  if (traj.samples < 2) fail("trajectory", "fewer than two samples");
  const int bad = first_bad_spacing(checker, traj);
  if (bad >= 0) {
    char what[160];
    std::snprintf(what, sizeof what,
                  "samples %d and %d are %.9g s apart, not the control period %g s", bad - 1, bad,
                  traj.t[bad] - traj.t[bad - 1], checker.dt);
    fail("trajectory", what);
  }
  Scan scan(checker, ws, traj);
  scan.run();
  return scan.result;
}

namespace {

const char* unit(TrajectoryLimit limit) {
  switch (limit) {
    case TrajectoryLimit::Position:
      return "rad";
    case TrajectoryLimit::Velocity:
    case TrajectoryLimit::StartAtRest:
    case TrajectoryLimit::EndAtRest:
      return "rad/s";
    case TrajectoryLimit::Acceleration:
      return "rad/s^2";
    case TrajectoryLimit::Jerk:
      return "rad/s^3";
    case TrajectoryLimit::Torque:
      return "Nm";
    case TrajectoryLimit::TorqueRate:
      return "Nm/s";
    case TrajectoryLimit::EndEffectorSpeed:
      return "m/s";
    case TrajectoryLimit::EndEffectorAcceleration:
      return "m/s^2";
    case TrajectoryLimit::EndEffectorTilt:
      return "rad from the vertical";
    default:
      return "m";
  }
}

}  // namespace

std::string describe_violation(const TrajectoryChecker& checker, const TrajectoryViolation& v) {
  char head[128];
  std::snprintf(head, sizeof head, "%s at t = %.6g s (sample %d): ", trajectory_limit_name(v.limit),
                v.time, v.sample);
  char tail[192];
  const bool collision =
      v.limit == TrajectoryLimit::SelfCollision || v.limit == TrajectoryLimit::EnvCollision;
  if (v.joint < 0 && !collision) {  // an end-effector limit
    std::snprintf(tail, sizeof tail, "%s %.6g %s, limit %.6g",
                  checker.robot.links[checker.options.end_effector.link].name.c_str(), v.value,
                  unit(v.limit), v.bound);
    return std::string(head) + tail;
  }
  if (!collision) {
    std::snprintf(tail, sizeof tail, "joint %d (%s) %.6g %s, limit %.6g", v.joint + 1,
                  checker.robot.joints[v.joint].name.c_str(), v.value, unit(v.limit), v.bound);
    return std::string(head) + tail;
  }
  const CollisionModel& cm = checker.collision;
  const std::string a = checker.robot.links[cm.robot[v.shape_a].link].name;
  const std::string b = v.limit == TrajectoryLimit::EnvCollision
                            ? "obstacle '" + cm.obstacles[v.shape_b].name + "'"
                            : checker.robot.links[cm.robot[v.shape_b].link].name;
  std::snprintf(tail, sizeof tail, "%s and %s, distance %.4g m, margin %.4g m", a.c_str(),
                b.c_str(), v.value, v.bound);
  return std::string(head) + tail;
}

}  // namespace lazyboe
