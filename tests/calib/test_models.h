// Models for calib/ and sim/ tests, built in code so these tests need no file loading. The
// numbers are those of models/reinovo_r1.yaml and reinovo_r2.yaml.
#pragma once

#include <random>

#include "calib/kinematics/kinematic_model.h"

namespace twin::testing {

/// Reinovo-like arm `robot` (0: r1, 1: r2; they differ only in d6 and link 6's mass data).
inline KinematicModel ReinovoLikeModel(int robot = 0) {
  KinematicModel m;
  m.name = robot == 0 ? "r1" : "r2";
  struct Row {
    double th, d, a, al, lo, hi, mass, cx, cy, cz, ixx, iyy, izz, ixy, ixz, iyz;
  };
  const double d6 = robot == 0 ? 0.1215 : 0.131;
  const double c6 = robot == 0 ? -0.0607 : -0.0655;
  const double i6 = robot == 0 ? 0.00065 : 0.00073;
  const Row rows[7] = {
      {0, 0.1365, 0.100, 90, -170, 170, 7.0, -0.05, -0.0683, 0, 0.02598, 0.02432, 0.0279,
       -0.00262, 0, 0},
      {90, 0, 0.290, 0, -120, 120, 7.5, -0.145, 0, 0, 0.01838, 0.06175, 0.06175, 0, 0, 0},
      {0, 0, 0.121, 90, -140, 140, 4.5, -0.0605, 0, 0, 0.0081, 0.00954, 0.00954, 0, 0, 0},
      {0, 0.310, 0, -90, -180, 180, 2.5, 0, 0.155, 0, 0.02158, 0.00313, 0.02158, 0, 0, 0},
      {-90, 0, 0, 90, -120, 120, 1.5, 0, 0, 0, 0.00177, 0.00177, 0.00152, 0, 0, 0},
      {0, d6, 0, 0, -270, 270, 0.4, 0, 0, c6, i6, i6, 0.00032, 0, 0, 0},
      {-90, 0, 0.060, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}};
  for (int i = 0; i < 7; ++i) {
    const Row& r = rows[i];
    Link& l = m.links[i];
    l.name = i < 6 ? "link" + std::to_string(i + 1) : "tool";
    l.dh = {DegToRad(r.th), r.d, r.a, DegToRad(r.al), 0.0};
    if (i < 6) l.limits = {DegToRad(r.lo), DegToRad(r.hi)};
    l.inertia.mass = r.mass;
    l.inertia.p_LiCom = Vector3(r.cx, r.cy, r.cz);
    l.inertia.I_Com << r.ixx, r.ixy, r.ixz, r.ixy, r.iyy, r.iyz, r.ixz, r.iyz, r.izz;
  }
  return m;
}

/// A redundant 7-joint arm (KUKA LBR iiwa 7-like standard DH: a = 0, d = 0.36, 0, 0.42, 0,
/// 0.4, 0, 0.126 m, alternating +-90 deg twists), with plausible masses; tool link identity.
inline KinematicModel SevenJointModel() {
  KinematicModel m(7);
  m.name = "iiwa";
  const double d[7] = {0.36, 0, 0.42, 0, 0.4, 0, 0.126};
  const double alpha[7] = {-90, 90, 90, -90, -90, 90, 0};
  const double limit[7] = {170, 120, 170, 120, 170, 120, 175};
  const double mass[7] = {4.0, 4.0, 3.0, 2.7, 1.7, 1.8, 0.3};
  for (int i = 0; i < 7; ++i) {
    Link& l = m.links[i];
    l.dh = {0.0, d[i], 0.0, DegToRad(alpha[i]), 0.0};
    l.limits = {DegToRad(-limit[i]), DegToRad(limit[i])};
    l.inertia.mass = mass[i];
    l.inertia.p_LiCom = Vector3(0.0, -0.03, 0.02);
    l.inertia.I_Com = 0.02 * Matrix3::Identity();
  }
  return m;
}

/// Uniform random joint vector inside the limits.
inline JointVector RandomJoints(const KinematicModel& m, std::mt19937_64& rng) {
  JointVector q(m.num_joints());
  for (int i = 0; i < m.num_joints(); ++i) {
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
  m.X_LtE = RandomTransform(rng, 0.1);
  return m;
}

}  // namespace twin::testing
