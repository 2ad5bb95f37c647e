// Synthetic optical-axis data for tests (Zhu et al. 2019, section V): the passive robot's true
// model differs from the nominal one in its 35 link parameters; for q = 5 camera axes through a
// fixed camera point and p = 10 positions 20 mm apart on each, joint angles are solved with the
// TRUE model so that the true feature point lies exactly on the axis (a perfect servo).
#pragma once

#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "calib/kinematics/inverse_kinematics.h"
#include "calib/measurements/optical_axis_model.h"
#include "calib/model/robot_model.h"
#include "test_models.h"

namespace twin::testing {

struct OpticalAxisScenario {
  KinematicModel nominal;          ///< what the estimator starts from
  KinematicModel truth;            ///< nominal with perturbed parameters (X_BL0, X_LtE identity)
  std::vector<AxisSample> samples; ///< recorded joint angles, axis-major
  std::vector<Line3> axes;         ///< the true camera axes in B
};

/// Builds the scenario. Parameter errors are uniform up to `len_error` m and `ang_error` rad
/// (paper's Table 3: ~1-5 mm, ~0.1-0.5 deg); `joint_noise` (rad, Gaussian sigma) is added to
/// the recorded q after the IK solve. Throws std::runtime_error if a position is unreachable.
/// With `point_on_last_axis`, the nominal tool link puts the feature point 40 mm out on the
/// last joint's axis (the paper scenario's board mount), where the last joint's rotation
/// cannot move it: a symmetry of the nominal model that the perturbed truth breaks.
inline OpticalAxisScenario MakeOpticalAxisScenario(std::uint64_t seed, double joint_noise = 0.0,
                                                   double len_error = 0.003,
                                                   double ang_error = DegToRad(0.3),
                                                   bool point_on_last_axis = false) {
  std::mt19937_64 rng(seed);
  OpticalAxisScenario s;
  s.nominal = ReinovoLikeModel();
  s.nominal.name = "r2";
  if (point_on_last_axis) s.nominal.links[6].dh = {0.0, 0.040, 0.0, 0.0, 0.0};
  s.truth = Perturbed(s.nominal, rng, len_error, ang_error);
  s.truth.X_BL0 = Transform::Identity();  // nominal and truth differ only in the 35 parameters
  s.truth.X_LtE = Transform::Identity();

  const Vector3 camera(0.35, -0.45, 0.75);  // fixed camera point in B [m]
  const Vector3 centre(0.45, 0.0, 0.30);    // middle of the passive robot's working region
  const Vector3 offsets[5] = {{0, 0, 0}, {0.12, 0.10, 0}, {-0.12, 0.10, 0.05},
                              {0.10, -0.08, -0.10}, {-0.10, -0.05, 0.10}};
  constexpr int kPositions = 10;
  constexpr double kStep = 0.020;  // D_step [m]
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  IkOptions ik;
  ik.random_restarts = 40;
  JointVector seed_q = MidRange(s.truth);
  for (int k = 0; k < 5; ++k) {
    const Vector3 mu = (centre + offsets[k] - camera).normalized();
    const double s0 = (centre + offsets[k] - camera).norm() - 0.5 * (kPositions - 1) * kStep;
    s.axes.push_back({camera, mu});
    Matrix3 facing;  // a rotation whose z axis is -mu
    facing.col(2) = -mu;
    facing.col(0) = mu.cross(Vector3::UnitZ()).normalized();
    facing.col(1) = facing.col(2).cross(facing.col(0));
    for (int i = 0; i < kPositions; ++i) {
      const Vector3 p = camera + (s0 + i * kStep) * mu;
      IkResult best;
      for (int attempt = 0; attempt < 20 && best.status != IkStatus::kSuccess; ++attempt) {
        // Board normal (E's z) roughly back along the axis: random roll, tilt up to 25 deg.
        const Vector3 tilt_axis = mu.cross(Vector3(u(rng), u(rng), u(rng))).normalized();
        const Matrix3 R = Eigen::AngleAxisd(DegToRad(25.0) * u(rng), tilt_axis) *
                          Eigen::AngleAxisd(kPi * u(rng), mu) * facing;
        Transform X = Transform::Identity();
        X.linear() = R;
        X.translation() = p;
        ik.seed = seed + 7919u * (10u * k + i) + attempt;
        best = SolveIk(s.truth, X, seed_q, ik);
      }
      if (best.status != IkStatus::kSuccess) {
        throw std::runtime_error("synthetic axis " + std::to_string(k) + " position " +
                                 std::to_string(i) + " unreachable: " + best.reason);
      }
      seed_q = best.q;
      AxisSample sample;
      sample.axis = k;
      sample.q = best.q;
      for (int j = 0; j < 6; ++j) sample.q(j) += joint_noise * noise(rng);
      s.samples.push_back(sample);
    }
  }
  return s;
}

/// Samples of `scenario`'s poses as a servo with a residual would record them when the arm also
/// has the effects of `truth` (the scenario's true chain plus error terms; at zero term values
/// exactly the scenario): the feature point p = EndPose(truth, q) is off the true axis by its
/// perpendicular part, which the camera measures (AxisSample::offset, plus Gaussian noise of
/// `sigma_perpendicular` per coordinate), and its distance along the axis from the camera is
/// the depth (plus noise of `sigma_depth`). With a right model p_BE(q) - offset lies on a line.
inline std::vector<AxisSample> SamplesWithEffects(const OpticalAxisScenario& scenario,
                                                  const RobotModel& truth, std::uint64_t seed,
                                                  double sigma_perpendicular,
                                                  double sigma_depth) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<AxisSample> out;
  for (const AxisSample& s : scenario.samples) {
    const Line3& axis = scenario.axes[s.axis];
    const Vector3 p = EndPose(truth, s.context()).translation();
    const Vector3 d = p - axis.point;
    const double along = axis.direction.dot(d);
    Vector3 perpendicular = d - along * axis.direction;
    const Vector3 n1 = axis.direction.unitOrthogonal();
    const Vector3 n2 = axis.direction.cross(n1);
    perpendicular += sigma_perpendicular * (noise(rng) * n1 + noise(rng) * n2);
    AxisSample r = s;
    r.offset = perpendicular;
    r.depth = along + sigma_depth * noise(rng);
    out.push_back(r);
  }
  return out;
}

}  // namespace twin::testing
