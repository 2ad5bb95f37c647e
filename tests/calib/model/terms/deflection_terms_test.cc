// The stage-5 terms (axis deflections): lateral compliance, the lumped-mass joint compliance of
// a model without masses, and axis wobble. Their Jacobians against central finite differences,
// their formulas against the test's own rotations of the chain, and the lumped compliance's
// recovery of compliance times weight on synthetic data.
#include <cmath>
#include <random>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "calib/kinematics/forward_kinematics.h"
#include "calib/model/end_point_jacobian.h"
#include "calib/model/error_term.h"
#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"
#include "calib/model/terms/terms.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::RandomJoints;
using testing::ReinovoLikeModel;

KinematicModel Massless(KinematicModel m) {
  for (Link& l : m.links) {
    l.inertia.mass = 0.0;
    l.inertia.p_LiCom.setZero();
  }
  return m;
}

MeasurementContext Context(const JointVector& q) {
  MeasurementContext c;
  c.q = q;
  return c;
}

// The end point of `chain` at readings q with the rotation `w` [rad, in frame X_BL[joint]]
// inserted before joint `joint` turns: the test's own composition of the chain (Eigen's
// AngleAxis, ForwardKinematics' frames).
Vector3 RotatedAt(const KinematicModel& chain, const JointVector& q, int joint, const Vector3& w) {
  const FrameSet f = ForwardKinematics(chain, q);
  const Transform& X = f.X_BL[joint];
  Transform R = Transform::Identity();
  if (w.norm() > 0) R.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  // Everything beyond X_BL[joint] turns about its origin, in its axes.
  return (X * R * X.inverse() * f.X_BE).translation();
}

TEST(DeflectionTerms, AutodiffMatchesCentralFiniteDifferencesWithAndWithoutMasses) {
  std::mt19937_64 rng(7);
  for (const bool masses : {true, false}) {
    KinematicModel chain = testing::Perturbed(ReinovoLikeModel(), rng, 0.002, 0.003);
    if (!masses) chain = Massless(chain);
    RobotModel model = MakeRobotModel(chain);
    std::vector<TermSpec> specs = {{"lateral_compliance", 0, {}},
                                   {"lateral_compliance", 3, {}},
                                   {"axis_wobble", 3, {1, 3}}};
    // With masses joint compliance is stage 3's (the autodiff way); without, stage 5's.
    if (!masses) specs.push_back({"joint_compliance", 1, {}});
    for (const TermSpec& s : specs) model = WithTerm(model, MakeErrorTerm(s, chain, "r1"));
    // Realistic sizes: a tilt of order 1e-4 rad from every parameter.
    const ParameterLayout layout(model);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < model.term_values.size(); ++k) {
      model.term_values(k) = 1e-4 * u(rng) * layout[layout.geometry_size() + k].scale;
    }
    const Eigen::VectorXd p0 = GetParameters(model);
    const int n = layout.size();
    for (int trial = 0; trial < 6; ++trial) {
      const MeasurementContext c = Context(RandomJoints(chain, rng));
      Vector3 p, p_fast;
      PointJacobian J, J_fast;
      EndPointJacobianAutodiff(model, p0.data(), c, &p, &J);
      EndPointJacobian(model, p0.data(), c, &p_fast, &J_fast);
      ASSERT_TRUE(DeflectedEndPointJacobian(model));
      EXPECT_EQ(p_fast, p);
      for (int k = 0; k < n; ++k) {
        const double h = 1e-6 * layout[k].scale;
        Eigen::VectorXd pp = p0, pm = p0;
        pp(k) += h;
        pm(k) -= h;
        const Vector3 fd = (RobotEndPoseT<double>(model, pp.data(), c).p -
                            RobotEndPoseT<double>(model, pm.data(), c).p) /
                           (2 * h);
        // Per scaled unit the derivative is O(1 m); the central difference errs by about
        // 1e-10 of rounding and 1e-12 of curvature: 1e-7 is a wide margin, far below a wrong
        // derivative (O(0.01 m) and more).
        EXPECT_LT((J.col(k) - fd).norm() * layout[k].scale, 1e-7)
            << layout[k].name << (masses ? " (masses)" : " (lumped)");
        if (k >= layout.geometry_size()) {
          // The fast way's term columns are the same autodiff.
          EXPECT_LT((J_fast.col(k) - J.col(k)).norm() * layout[k].scale, 1e-12) << layout[k].name;
        } else {
          // Its geometric columns hold the deflections (|w| ~ 1e-4 rad here) fixed: they miss
          // the deflections' change with the geometry, about |w| times a lever of ~1 m per
          // scaled unit; 1e-3 bounds that with a margin and is far below a wrong column (O(1)).
          EXPECT_LT((J_fast.col(k) - J.col(k)).norm() * layout[k].scale, 1e-3) << layout[k].name;
        }
      }
      // Every term parameter moves the point (a term column of zero would be a wiring error).
      for (int k = layout.geometry_size(); k < n; ++k) {
        EXPECT_GT(J.col(k).norm() * layout[k].scale, 1e-6) << layout[k].name;
      }
    }
  }
}

TEST(DeflectionTerms, AWobbleTurnsTheChainAtItsJointByTheHarmonicOfItsReading) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel model = MakeRobotModel(chain);
  model = WithTerm(model, MakeErrorTerm({"axis_wobble", 1, {3}}, chain, "r1"));
  model.term_values << 2e-4, -1e-4, 5e-5, 3e-4;  // x sin, x cos, y sin, y cos
  const JointVector q = (JointVector(6) << 0.2, -0.7, 0.5, 1.0, -0.4, 0.3).finished();
  const double s3 = std::sin(3 * q(1)), c3 = std::cos(3 * q(1));
  const Vector3 w(2e-4 * s3 - 1e-4 * c3, 5e-5 * s3 + 3e-4 * c3, 0.0);
  // 1e-12 m: the same rotation composed two ways, rounding of metre-sized coordinates.
  EXPECT_LT((EndPose(model, Context(q)).translation() - RotatedAt(chain, q, 1, w)).norm(), 1e-12);
}

TEST(DeflectionTerms, LateralComplianceTiltsItsAxisByComplianceTimesTheNominalMoment) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel model = MakeRobotModel(chain);
  // Joint 1: its axis is vertical, so the arm's whole gravity moment bends it.
  model = WithTerm(model, MakeErrorTerm({"lateral_compliance", 0, {}}, chain, "r1"));
  const double cx = 3e-6, cy = -2e-6;  // [rad/(N m)], an anisotropic base: e = cy - cx
  model.term_values << cx, cy - cx, 0.0, 0.0;  // no gravity tilt
  const JointVector q = (JointVector(6) << 0.4, 0.3, -0.6, 0.8, 0.9, -0.2).finished();
  // The test's own moment about the origin of X_BL[0] of links 1..6 and the tool, each at its
  // centre of mass, in X_BL[0]'s axes.
  const FrameSet f = ForwardKinematics(chain, q);
  Vector3 moment = Vector3::Zero();
  for (int j = 0; j <= 6; ++j) {
    const Vector3 com = f.X_BL[j + 1] * chain.links[j].inertia.p_LiCom;
    moment += (com - f.X_BL[0].translation())
                  .cross(chain.links[j].inertia.mass * kStandardGravity * -Vector3::UnitZ());
  }
  const Vector3 m_L = f.X_BL[0].linear().transpose() * moment;
  const Vector3 w(cx * m_L.x(), cy * m_L.y(), 0.0);
  EXPECT_GT(w.norm(), 1e-5);  // the case tilts the axis measurably
  // 1e-12 m: as above.
  EXPECT_LT((EndPose(model, Context(q)).translation() - RotatedAt(chain, q, 0, w)).norm(), 1e-12);
}

// Gravity tilted against the model's g_B = -z of B by gamma_1 about e_1 = x of B and gamma_2
// about e_2 = g_B x e_1 = -y: the term with one compliance c and u_k = c gamma_k tilts joint
// 2's axis by c times the bending moment under the tilted gravity, which the test computes
// itself. Joint 2 carries its drive torque along its axis, so a tilt of 0.2 deg changes the
// moment across it by a large part of that moment.
TEST(DeflectionTerms, LateralComplianceTakesTheTiltOfGravityAgainstTheBase) {
  const KinematicModel chain = ReinovoLikeModel();
  RobotModel model = MakeRobotModel(chain);
  model = WithTerm(model, MakeErrorTerm({"lateral_compliance", 1, {}}, chain, "r1"));
  ASSERT_EQ(model.term_values.size(), 4);
  const double c = 5e-4, gamma1 = 3.5e-3, gamma2 = -2e-3;  // [rad/(N m)], [rad]
  model.term_values << c, 0.0, c * gamma1, c * gamma2;  // a bearing: the same c both ways
  const JointVector q = (JointVector(6) << 0.4, 0.3, -0.6, 0.8, 0.9, -0.2).finished();
  const Vector3 g =
      kStandardGravity * (-Vector3::UnitZ() + gamma1 * Vector3::UnitX() - gamma2 * Vector3::UnitY());
  const FrameSet f = ForwardKinematics(chain, q);
  const auto across = [&](const Vector3& gravity) {
    Vector3 moment = Vector3::Zero();
    for (int j = 1; j <= 6; ++j) {
      const Vector3 com = f.X_BL[j + 1] * chain.links[j].inertia.p_LiCom;
      moment += (com - f.X_BL[1].translation()).cross(chain.links[j].inertia.mass * gravity);
    }
    const Vector3 m_L = f.X_BL[1].linear().transpose() * moment;
    return Vector3(m_L.x(), m_L.y(), 0.0);
  };
  const Vector3 w = c * across(g);
  const Vector3 w_level = c * across(-kStandardGravity * Vector3::UnitZ());
  // The tilt matters here: it moves the end point by far more than the tolerance below.
  EXPECT_GT((RotatedAt(chain, q, 1, w) - RotatedAt(chain, q, 1, w_level)).norm(), 1e-6);
  // 1e-12 m: as above.
  EXPECT_LT((EndPose(model, Context(q)).translation() - RotatedAt(chain, q, 1, w)).norm(), 1e-12);
}

TEST(DeflectionTerms, LumpsAreTheElbowWristAndEndOfASixAxisArm) {
  // Motoman-like spacing: links of 0.614, 0.2, 0.64, 0.03, 0.2 m and a 0.25 m tool; lumps
  // 0.1 of the reach (3.5 m) apart keep the end, the wrist and the elbow.
  KinematicModel m = Massless(ReinovoLikeModel());
  const double d[7] = {1.4159, 0, 0, -0.64, 0, 0.2, 0.245};
  const double a[7] = {0.15, 0.614, 0.2, 0, 0.03, 0, 0.045};
  for (int i = 0; i < 7; ++i) {
    m.links[i].dh.d = d[i];
    m.links[i].dh.a = a[i];
  }
  const terms::Lumps lumps = terms::LumpsBeyond(m, 1);
  ASSERT_EQ(lumps.points.size(), 3u);
  EXPECT_EQ(lumps.points[0], 8);  // the end point (N + 2)
  EXPECT_EQ(lumps.points[1], 5);  // X_BL[5]: past link 5's 0.03 m, the wrist
  EXPECT_EQ(lumps.points[2], 3);  // X_BL[3]: the elbow, 0.2 m past joint 3
  EXPECT_EQ(lumps.names[0], "end");
  // From the base, the shoulder is a lump too.
  EXPECT_EQ(terms::LumpsBeyond(m, 0).points.size(), 4u);
}

// Synthetic data: a compliant joint 2 of stiffness k under masses that sit exactly at the
// lump points; the model without masses, fitted with its lumped compliance by linear least
// squares on the truth's sag, recovers each lump's weight over the stiffness, m_k g / k.
TEST(DeflectionTerms, LumpedComplianceRecoversComplianceTimesEachLumpsWeight) {
  KinematicModel massless = Massless(ReinovoLikeModel());
  const terms::Lumps lumps = terms::LumpsBeyond(massless, 1);
  ASSERT_GE(lumps.points.size(), 2u);
  // The truth: masses at the lump points (link k-1's frame is X_BL[k]; the end point is the
  // tool link's X_LtE origin).
  KinematicModel massive = massless;
  const double lump_mass[kMaxJoints + 2] = {3.0, 5.0, 8.0, 4.0, 6.0, 2.0, 7.0, 1.0, 9.0};
  const int n = massless.num_joints();
  for (size_t k = 0; k < lumps.points.size(); ++k) {
    const int pt = lumps.points[k];
    Link& l = pt == n + 2 ? massive.links[n] : massive.links[pt - 1];
    l.inertia.mass = lump_mass[k];
    l.inertia.p_LiCom = pt == n + 2 ? Vector3(massless.X_LtE.translation()) : Vector3::Zero();
  }
  const double compliance = 2e-5;  // [rad/(N m)]: k = 5e4 N m/rad
  RobotModel truth = MakeRobotModel(massive);
  truth = WithTerm(truth, MakeErrorTerm({"joint_compliance", 1, {}}, massive, "r1"));
  truth.term_values << compliance;
  RobotModel model = MakeRobotModel(massless);
  model = WithTerm(model, MakeErrorTerm({"joint_compliance", 1, {}}, massless, "r1"));
  ASSERT_EQ(model.term_values.size(), static_cast<int>(lumps.points.size()));
  // Rows: the truth's sag at 40 poses; columns: the lumped term's Jacobian at zero.
  std::mt19937_64 rng(3);
  const int poses = 40, m = static_cast<int>(lumps.points.size());
  Eigen::MatrixXd A(3 * poses, m);
  Eigen::VectorXd b(3 * poses);
  const Eigen::VectorXd p0 = GetParameters(model);
  for (int i = 0; i < poses; ++i) {
    const MeasurementContext c = Context(RandomJoints(massless, rng));
    Vector3 p;
    PointJacobian J;
    EndPointJacobian(model, p0.data(), c, &p, &J);
    A.middleRows(3 * i, 3) = J.rightCols(m);
    b.segment(3 * i, 3) = EndPose(truth, c).translation() - p;
  }
  const Eigen::VectorXd a = A.colPivHouseholderQr().solve(b);
  for (int k = 0; k < m; ++k) {
    const double expected = compliance * lump_mass[k] * kStandardGravity;
    // 2 %: the truth's sag is solved with the torque it changes (stage 3's iteration), the
    // lumped term in one pass; the difference, c dtau/dq ~ 1e-3 of the sag, and the
    // linearisation (sags of 1e-3 rad) stay well inside it. A wrong lever or sign is 100 %.
    EXPECT_NEAR(a(k), expected, 0.02 * expected) << lumps.names[k];
  }
}

}  // namespace
}  // namespace twin
