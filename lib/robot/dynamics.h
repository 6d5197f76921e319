// Rigid-body dynamics of the chain, tau = M(q) ddq + C(q, dq) dq + g(q) + tau_f(dq), as small
// free functions over (RobotModel, RobotData). Results are written into the data workspace and
// returned by reference; nothing allocates.
#pragma once

#include "lazyboe/robot/kinematics.h"

namespace lazyboe {

// Full inverse dynamics by recursive Newton-Euler, friction included.
const JointVector& inverse_dynamics(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& q, const JointVectorRef& dq,
                                    const JointVectorRef& ddq);

// Recursive Newton-Euler with gravity and friction switchable (for tests and for h(q, dq)).
const JointVector& rnea(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                        const JointVectorRef& dq, const JointVectorRef& ddq, bool with_gravity,
                        bool with_friction);

// Joint-space mass matrix M(q) by the composite-rigid-body algorithm (data.M).
const JointMatrix& mass_matrix(const RobotModel& model, RobotData& data, const JointVectorRef& q);

// Gravity torques g(q) (data.gravity).
const JointVector& gravity_torques(const RobotModel& model, RobotData& data,
                                   const JointVectorRef& q);

// Friction torques tau_f(dq) (data.friction).
const JointVector& friction_torques(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& dq);
double friction_torque(const Friction& friction, double dq);

// Forward dynamics: ddq = M^-1 (tau - C dq - g - tau_f) (data.ddq). Runs dynamics_terms, so
// it also leaves data.M, its factor, data.gravity and data.h at this state.
const JointVector& forward_dynamics(const RobotModel& model, RobotData& data,
                                    const JointVectorRef& q, const JointVectorRef& dq,
                                    const JointVectorRef& tau);

// Everything forward dynamics needs at one state, sharing one pass of joint poses: the mass
// matrix and its Cholesky factor (data.M; data.llt_upper, data.llt_inv_diagonal), gravity torques
// from the composite bodies (data.gravity), and the velocity terms C(q, dq) dq + tau_f(dq)
// (data.h). A simulator tick then gets ddq for its controller torque from
// forward_dynamics_from_terms without a second pass. The velocity terms come from a
// Newton-Euler pass fused with the composite-inertia pass; rnea() and gravity_torques() stay
// the separate reference algorithms.
void dynamics_terms(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                    const JointVectorRef& dq);
const JointVector& forward_dynamics_from_terms(RobotData& data, const JointVectorRef& tau);

double kinetic_energy(const RobotModel& model, RobotData& data, const JointVectorRef& q,
                      const JointVectorRef& dq);
double potential_energy(const RobotModel& model, RobotData& data, const JointVectorRef& q);

}  // namespace lazyboe
