// Synthetic laser-tracker data for tests: a robot model (the truth, with or without error
// terms) measured at random configurations inside the joint limits by a tracker at a fixed pose,
// with optional Gaussian noise. The readings' contexts carry random approach directions, time
// stamps and temperature changes, so that every error term has what it needs.
#pragma once

#include <random>
#include <vector>

#include "calib/measurements/tracker_set.h"
#include "calib/model/robot_model.h"
#include "test_models.h"

namespace twin::testing {

/// A tracker 2 m in front of the robot, turned 30 deg about z and tilted 5 deg.
inline Transform TrackerPose() {
  Transform X = Transform::Identity();
  X.linear() = (Eigen::AngleAxisd(DegToRad(30.0), Vector3::UnitZ()) *
                Eigen::AngleAxisd(DegToRad(5.0), Vector3::UnitX()))
                   .toRotationMatrix();
  X.translation() = Vector3(-2.0, 0.4, -0.3);
  return X;
}

/// `count` points of `truth` seen by a tracker at X_TB with noise `sigma` [m] per axis.
inline std::vector<TrackerPoint> SyntheticTrackerPoints(const RobotModel& truth, int count,
                                                        std::uint64_t seed, double sigma = 0.0,
                                                        const Transform& X_TB = TrackerPose()) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::bernoulli_distribution coin(0.5);
  std::vector<TrackerPoint> points;
  const double margin = DegToRad(10.0);
  for (int k = 0; k < count; ++k) {
    TrackerPoint p;
    p.row = k + 2;
    p.context.q = JointVector(truth.chain.num_joints());
    p.context.approach = JointVector(truth.chain.num_joints());
    for (int i = 0; i < truth.chain.num_joints(); ++i) {
      const JointLimits& l = truth.chain.links[i].limits;
      p.context.q(i) = std::uniform_real_distribution<double>(l.lower + margin, l.upper - margin)(rng);
      p.context.approach(i) = coin(rng) ? 1.0 : -1.0;
    }
    p.context.time_s = 3600.0 * k / count;
    p.context.temperature_delta_K = std::uniform_real_distribution<double>(-5.0, 15.0)(rng);
    p.p_T = X_TB * EndPose(truth, p.context).translation();
    if (sigma > 0.0) {
      for (int a = 0; a < 3; ++a) p.p_T(a) += sigma * noise(rng);
      p.sigma = sigma;
    }
    points.push_back(p);
  }
  return points;
}

}  // namespace twin::testing
