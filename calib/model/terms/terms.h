// Factories of the registered error terms, one per file in calib/model/terms/, listed in the
// registry table (registry.cc). Adding a term: one file defining its class and factory, one
// declaration here, one line in the registry table.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "calib/model/error_term.h"

namespace twin::terms {

/// Everything a factory gets: the spec (joint and orders already checked against the chain),
/// the nominal chain and the robot's name (prefix of the parameter names).
struct TermInput {
  const TermSpec& spec;
  const KinematicModel& nominal;
  const std::string& robot;
  const std::string& where;  ///< for messages
};

std::shared_ptr<const ErrorTerm> MakeJointCompliance(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeTransmissionError(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeBacklash(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeThermalGrowth(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeThermalDrift(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeThermalWarmup(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeMountDeflection(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeLateralCompliance(const TermInput& in);
std::shared_ptr<const ErrorTerm> MakeAxisWobble(const TermInput& in);

/// "r1.joint2" for joint index 1 (0-based) of robot r1.
std::string JointPrefix(const std::string& robot, int joint);

/// Reach of the nominal arm, sum over links of |d| + |a| [m] (at least 0.1 m): the lever arm
/// used to size parameter scales.
double NominalReach(const KinematicModel& nominal);

/// True when the nominal chain carries mass properties (some link's mass > 0).
bool HasMasses(const KinematicModel& nominal);

/// Lumped masses for a chain without mass properties (lumped_masses.cc): the points that carry
/// the weight joint `joint` (0-based) holds, as indices into the stage-5 frames (1..N+1: the
/// origin of X_BL[k]; N+2: the end point), with readable names.
struct Lumps {
  std::vector<int> points;
  std::vector<std::string> names;  ///< "U" (the origin of link U's frame) or "end"
};
Lumps LumpsBeyond(const KinematicModel& nominal, int joint);

/// The point `index` of Lumps::points in B.
template <typename T>
const Vec3T<T>& LumpPoint(const DeflectionInputT<T>& in, int index, int num_joints) {
  return index == num_joints + 2 ? in.p_BE : in.X_BL[index].p;
}

/// The gravity moment about the origin of X_BL[joint] [N m], in that frame's axes, of the
/// nominal masses of the links joint turns (links joint..N, each at its centre of mass; the
/// tool link's with the flange link, as GravityTorquesT), under the acceleration `g_B`
/// [m/s^2, in B] (the moment is linear in it).
template <typename T>
Vec3T<T> NominalGravityMoment(const KinematicModel& chain, const DeflectionInputT<T>& in,
                              int joint, const Vector3& g_B) {
  const int n = chain.num_joints();
  const RigidT<T>& X = in.X_BL[joint];
  const Vec3T<T> g = g_B.template cast<T>();
  Vec3T<T> moment = Vec3T<T>::Zero();
  for (int j = joint; j <= n; ++j) {
    const Vec3T<T> com = in.X_BL[j + 1] * chain.links[j].inertia.p_LiCom.template cast<T>();
    moment += (com - X.p).cross(g * T(chain.links[j].inertia.mass));
  }
  return X.R.transpose() * moment;
}

/// NominalGravityMoment under the model's gravity (in.gravity times in.g_B).
template <typename T>
Vec3T<T> NominalGravityMoment(const KinematicModel& chain, const DeflectionInputT<T>& in,
                              int joint) {
  return NominalGravityMoment(chain, in, joint, Vector3(in.gravity * in.g_B));
}

}  // namespace twin::terms
