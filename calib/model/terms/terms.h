// Factories of the registered error terms, one per file in calib/model/terms/, listed in the
// registry table (registry.cc). Adding a term: one file defining its class and factory, one
// declaration here, one line in the registry table.
#pragma once

#include <memory>
#include <string>

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

/// "r1.joint2" for joint index 1 (0-based) of robot r1.
std::string JointPrefix(const std::string& robot, int joint);

/// Reach of the nominal arm, sum over links of |d| + |a| [m] (at least 0.1 m): the lever arm
/// used to size parameter scales.
double NominalReach(const KinematicModel& nominal);

}  // namespace twin::terms
