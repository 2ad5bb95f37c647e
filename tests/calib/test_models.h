// Models for calib/ tests, built in code so calib tests need no file loading. The numbers are
// those of models/reinovo_r1.yaml (bench tests check that the file loads to the same model).
#pragma once

#include <random>

#include "calib/kinematic_model.h"

namespace twin::testing {

inline KinematicModel ReinovoLikeModel() {
  KinematicModel m;
  m.name = "r1";
  struct Row { double th, d, a, al, lo, hi; };
  const Row rows[kNumLinks] = {{0, 0.1365, 0.100, 90, -170, 170}, {90, 0, 0.290, 0, -120, 120},
                               {0, 0, 0.121, 90, -140, 140},     {0, 0.310, 0, -90, -180, 180},
                               {-90, 0, 0, 90, -120, 120},       {0, 0.1215, 0, 0, -270, 270},
                               {-90, 0, 0.060, 0, 0, 0}};
  for (int i = 0; i < kNumLinks; ++i) {
    Link& l = m.links[i];
    l.name = i < kNumJoints ? "link" + std::to_string(i + 1) : "tool";
    l.dh = {DegToRad(rows[i].th), rows[i].d, rows[i].a, DegToRad(rows[i].al), 0.0};
    l.limits = {DegToRad(rows[i].lo), DegToRad(rows[i].hi)};
  }
  return m;
}

/// Uniform random joint vector inside the limits.
inline JointVector RandomJoints(const KinematicModel& m, std::mt19937_64& rng) {
  JointVector q;
  for (int i = 0; i < kNumJoints; ++i) {
    q(i) = std::uniform_real_distribution<double>(m.links[i].limits.lower,
                                                   m.links[i].limits.upper)(rng);
  }
  return q;
}

/// A random rigid transform (translation up to `reach` m per axis).
inline Transform RandomTransform(std::mt19937_64& rng, double reach) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Transform X = Transform::Identity();
  X.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  X.translation() = reach * Vector3(u(rng), u(rng), u(rng));
  return X;
}

/// The model with every one of its 35 parameters perturbed (lengths by up to `len` m,
/// angles by up to `ang` rad), and non-identity base and end transforms.
inline KinematicModel Perturbed(KinematicModel m, std::mt19937_64& rng, double len, double ang) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Link& l : m.links) {
    l.dh.theta_offset += ang * u(rng);
    l.dh.d += len * u(rng);
    l.dh.a += len * u(rng);
    l.dh.alpha += ang * u(rng);
    l.dh.beta += ang * u(rng);
  }
  m.X_BL0 = RandomTransform(rng, 0.2);
  m.X_L7E = RandomTransform(rng, 0.1);
  return m;
}

}  // namespace twin::testing
