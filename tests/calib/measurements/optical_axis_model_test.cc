#include "calib/measurements/optical_axis_model.h"

#include <random>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "optical_axis_synthetic.h"
#include "test_models.h"

namespace twin {
namespace {

using testing::MakeOpticalAxisScenario;
using testing::RandomJoints;
using testing::ReinovoLikeModel;

TEST(OpticalAxisModel, ErrorJacobianMatchesCentralDifferences) {
  std::mt19937_64 rng(11);
  const KinematicModel model = ReinovoLikeModel();
  const ParameterVector phi = GetParameters(model);
  const Vector3 mu = Vector3(0.3, -0.5, 0.8).normalized();
  for (int trial = 0; trial < 3; ++trial) {
    const JointVector qi = RandomJoints(model, rng), qj = RandomJoints(model, rng);
    const auto J = ErrorJacobian(model, mu, qi, qj);
    const double h = 1e-6;
    for (int c = 0; c < 35; ++c) {
      ParameterVector plus = phi, minus = phi;
      plus(c) += h;
      minus(c) -= h;
      const KinematicModel mp = WithParameters(model, plus), mm = WithParameters(model, minus);
      const Vector3 Ep = MisalignedError(mu, EndPose(mp, qi).translation(),
                                         EndPose(mp, qj).translation());
      const Vector3 Em = MisalignedError(mu, EndPose(mm, qi).translation(),
                                         EndPose(mm, qj).translation());
      // Eq. 20: E(nominal) = J (true - nominal), so J = -dE/dphi with mu fixed. Tolerance:
      // central-difference truncation ~h^2 * |d3p| ~ 1e-12 plus round-off ~1e-16 / h ~ 1e-10,
      // for entries of order 0.1-1; 1e-8 leaves margin.
      const Vector3 fd = -(Ep - Em) / (2 * h);
      EXPECT_LT((J.col(c) - fd).norm(), 1e-8) << ParameterName("r1", c);
    }
  }
}

TEST(OpticalAxisModel, FitLineRecoversKnownLineExactly) {
  const Vector3 c(0.4, -0.2, 0.3), d = Vector3(1.0, 2.0, -0.5).normalized();
  std::vector<Vector3> pts;
  for (double t : {-0.1, -0.03, 0.0, 0.05, 0.12, 0.2}) pts.push_back(c + t * d);
  const Line3 l = FitLine(pts);
  // Noise-free points: exact up to round-off of ~1e-16 relative; 1e-12 is generous.
  EXPECT_NEAR(l.direction.norm(), 1.0, 1e-12);
  EXPECT_LT(l.direction.cross(d).norm(), 1e-12);
  EXPECT_GT(l.direction.dot(d), 0.0);  // oriented from the first point to the last
  EXPECT_LT(d.cross(l.point - c).norm(), 1e-12);  // the fitted point lies on the line
}

TEST(OpticalAxisModel, FitLineEq45AgreesWhenAxisIsNotPerpendicularToZ) {
  const Vector3 c(0.5, 0.1, 0.2), d = Vector3(0.3, -0.4, -0.9).normalized();
  std::vector<Vector3> pts;
  for (int i = 0; i < 10; ++i) pts.push_back(c + 0.02 * i * d);
  const Line3 tls = FitLine(pts), eq45 = FitLineEq45(pts);
  // Both are exact for noise-free points; 1e-10 covers eq. 45's normal-equation round-off.
  EXPECT_LT(tls.direction.cross(eq45.direction).norm(), 1e-10);
  EXPECT_GT(tls.direction.dot(eq45.direction), 0.0);
  EXPECT_LT(d.cross(eq45.point - c).norm(), 1e-10);

  // An axis in the base x-y plane: eq. 45 breaks down, TLS does not.
  std::vector<Vector3> flat;
  for (int i = 0; i < 10; ++i) flat.push_back(c + 0.02 * i * Vector3(0.6, 0.8, 0.0));
  EXPECT_THROW(FitLineEq45(flat), InputError);
  EXPECT_LT(FitLine(flat).direction.cross(Vector3(0.6, 0.8, 0.0)).norm(), 1e-12);
}

TEST(OpticalAxisModel, FitLineRejectsTooFewPoints) {
  try {
    FitLine({Vector3::Zero()});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 2 points"), std::string::npos);
  }
}

TEST(OpticalAxisModel, StackIsConsistentWithPairwiseFunctions) {
  const auto s = MakeOpticalAxisScenario(3);
  std::vector<Vector3> dirs;
  for (const Line3& l : FitAxes(s.nominal, s.samples)) dirs.push_back(l.direction);
  const MisalignedErrorStack st = StackMisalignedErrors(s.nominal, s.samples, dirs);
  ASSERT_EQ(st.num_pairs, 5 * 45);
  ASSERT_EQ(st.E.size(), 3 * 5 * 45);
  // First pair of axis 1 (samples 10 and 11) sits at row 3 * 45.
  const int r = 3 * 45;
  const Vector3 pi = EndPose(s.nominal, s.samples[10].q).translation();
  const Vector3 pj = EndPose(s.nominal, s.samples[11].q).translation();
  EXPECT_LT((st.E.segment<3>(r) - MisalignedError(dirs[1], pi, pj)).norm(), 1e-15);
  EXPECT_LT((st.Phi.block<3, 35>(r, 0) -
             ErrorJacobian(s.nominal, dirs[1], s.samples[10].q, s.samples[11].q))
                .norm(),
            1e-13);
  // Positions are homogeneous of degree 1 in the lengths, so Phi s = [mu x](p_i - p_j) = -E
  // exactly for s = the current lengths (why scale is a gauge of line data). Round-off only.
  ParameterVector scale = ParameterVector::Zero(35);
  const ParameterVector phi = GetParameters(s.nominal);
  for (int i = 0; i < 35; ++i) scale(i) = IsLengthParameter(i) ? phi(i) : 0.0;
  EXPECT_LT((st.Phi * scale + st.E).norm(), 1e-12);
}

TEST(OpticalAxisModel, MeanMisalignedErrorVanishesForTheTrueModel) {
  const auto s = MakeOpticalAxisScenario(3);
  // The synthetic IK solves to 1e-7 m, so the true model's points are collinear to ~1e-7 m.
  EXPECT_LT(MeanMisalignedErrorNorm(s.truth, s.samples), 1e-6);
  // mm-level parameter errors give mm-level misalignment with the nominal model.
  EXPECT_GT(MeanMisalignedErrorNorm(s.nominal, s.samples), 3e-4);
}

}  // namespace
}  // namespace twin
