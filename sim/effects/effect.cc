#include "sim/effects/effect.h"

#include <cassert>

namespace twin {

// The do-nothing defaults: an effect overrides only the hooks it acts through.
void Effect::ApplyToGeometry(int, KinematicModel*, std::mt19937_64*) const {}
bool Effect::DriftsLengths(int) const { return false; }
double Effect::LengthScaleAt(int, double) const { return 1.0; }
double Effect::TemperatureDeltaAt(int, double) const { return 0.0; }
void Effect::ApplyToDrive(int, std::vector<JointDrive>*) const {}
void Effect::ApplyToMount(int, MountCompliance*) const {}
void Effect::ApplyToStructure(int, StructureCompliance*) const {}
bool Effect::TiltsAxes(int) const { return false; }
void Effect::AddAxisTilt(int, const JointVector&, std::vector<Eigen::Vector2d>*) const {}
void Effect::ApplyToTransmission(int, const JointVector&, const JointVector&,
                                 JointVector*) const {}
void Effect::ApplyToEncoder(int, JointVector*, std::mt19937_64*) const {}
void Effect::ApplyToImage(cv::Mat*, std::mt19937_64*) const {}
bool Effect::NeedsCameraAndBoard() const { return false; }

bool Effect::Applies(int robot) const {
  assert(robot >= 0 && robot < kMaxRobots);
  return spec().robot == -1 || spec().robot == robot;
}

bool Effect::Applies(int robot, int joint) const {
  assert(joint >= 0 && joint < kMaxJoints);
  return Applies(robot) && (spec().joint == -1 || spec().joint == joint);
}

}  // namespace twin
