#include "calib/identification/observability.h"

#include <algorithm>
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/identification/linearized_identification.h"
#include "calib/measurements/optical_axis_model.h"
#include "optical_axis_synthetic.h"

namespace twin {
namespace {

// A six-axis chain named r2 (the names prefix the parameters).
KinematicModel R2() {
  KinematicModel m;
  m.name = "r2";
  return m;
}

using testing::MakeOpticalAxisScenario;

bool Contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

MisalignedErrorStack StackAt(const KinematicModel& model, const std::vector<AxisSample>& samples) {
  std::vector<Vector3> dirs;
  for (const Line3& l : FitAxes(model, samples)) dirs.push_back(l.direction);
  return StackMisalignedErrors(model, samples, dirs);
}

// At the true model the data are exactly collinear (to the 1e-7 m IK tolerance), so theory's
// invariants must appear in the null space by themselves, with no hint.
TEST(Observability, TheoryInvariantsAreInTheNullSpaceOfConsistentData) {
  const auto s = MakeOpticalAxisScenario(42);
  const MisalignedErrorStack st = StackAt(s.truth, s.samples);
  const Eigen::MatrixXd Phi = ProfiledPhi(st);
  const ObservabilityReport rep = AnalyseObservability(Phi, R2(), 1e-6);
  std::cout << "rank " << rep.rank << "; unidentifiable combinations (truth):\n";
  for (const auto& n : rep.unidentifiable) std::cout << "  " << n << "\n";
  // Rotation about base z and translation along it lie in the null space: their projection onto
  // it is 1 up to the ~1e-7 inconsistency the IK tolerance leaves (names then carry ~1e-6
  // residue terms, e.g. "1 r2.link1.theta + 2.5e-06 r2.link2.d ...", so check the subspace).
  for (int idx : {ParameterIndex(1, DhParameter::kTheta), ParameterIndex(1, DhParameter::kD)}) {
    EXPECT_GT(rep.null_basis.row(idx).norm(), 1.0 - 1e-9) << ParameterName("r2", idx);
  }
  EXPECT_NE(rep.unidentifiable[0].find("r2.link1.theta"), std::string::npos);
  EXPECT_TRUE(Contains(rep.unidentifiable, "r2.link1.d"));
  EXPECT_EQ(rep.rank, 20);
  // Uniform scale: |Phi s| / |s| ~ 0. Relative to sigma_max, the 1e-7 m IK tolerance on a
  // ~0.5 m arm leaves ~1e-7; 1e-6 is the rank cut used above.
  const auto inv = LineConstraintInvariants(s.truth);
  const double sigma_max = rep.singular_values[0];
  for (const ParameterVector& v : inv) {
    EXPECT_LT((Phi * v).norm() / v.norm(), 1e-6 * sigma_max);
    EXPECT_LT((rep.identifiable_basis.transpose() * v.normalized()).norm(), 1e-5);
  }
  // With mu held fixed (the paper's Phi) scale is null too, but rotation is not: a rotated
  // point set no longer fits the old direction. Hence the profiling of the refitted mu_k.
  EXPECT_LT((st.Phi * inv[2]).norm() / inv[2].norm(), 1e-6 * sigma_max);
  EXPECT_GT((st.Phi * inv[0]).norm(), 1e-2 * sigma_max);
}

TEST(Observability, NominalModelWithKnownInvariants) {
  const auto s = MakeOpticalAxisScenario(42);
  const KinematicModel& m = s.nominal;
  const Eigen::MatrixXd Phi = ProfiledPhi(StackAt(m, s.samples));
  const auto inv = LineConstraintInvariants(m);
  const ObservabilityReport rep = AnalyseObservability(Phi, R2(), 1e-6, inv);
  std::cout << "rank " << rep.rank << "; unidentifiable combinations (nominal):\n";
  for (const auto& n : rep.unidentifiable) std::cout << "  " << n << "\n";
  EXPECT_EQ(rep.rank, 20);
  EXPECT_EQ(rep.unidentifiable.size(), 15u);
  EXPECT_TRUE(Contains(rep.unidentifiable, "r2.link1.theta"));
  EXPECT_TRUE(Contains(rep.unidentifiable, "r2.link1.d"));
  EXPECT_TRUE(Contains(rep.unidentifiable, "0.707 r2.link2.d - 0.707 r2.link3.d"));
  EXPECT_TRUE(Contains(rep.unidentifiable, "r2.link7.alpha"));  // orientation-only parameters
  EXPECT_TRUE(Contains(rep.unidentifiable, "r2.link7.beta"));
  // Bases: orthonormal and complementary (round-off level, 1e-10).
  const Eigen::MatrixXd& V = rep.identifiable_basis;
  const Eigen::MatrixXd& N = rep.null_basis;
  EXPECT_LT((V.transpose() * V - Eigen::MatrixXd::Identity(V.cols(), V.cols())).norm(), 1e-10);
  EXPECT_LT((V.transpose() * N).norm(), 1e-10);
  for (const ParameterVector& v : inv) {
    EXPECT_LT((V.transpose() * v.normalized()).norm(), 1e-10);
  }
  const std::vector<double> id(rep.singular_values.begin(),
                               rep.singular_values.begin() + rep.rank);
  EXPECT_GT(ObservabilityIndexO1(id), 0.0);
  std::cout << "O1 (identifiable) = " << ObservabilityIndexO1(id) << "\n";
}

TEST(Observability, IndexO1) {
  EXPECT_NEAR(ObservabilityIndexO1({4.0, 1.0}), 2.0 / std::sqrt(2.0), 1e-14);
  EXPECT_EQ(ObservabilityIndexO1({4.0, 0.0}), 0.0);  // why only identifiable values are passed
  EXPECT_EQ(ObservabilityIndexO1({}), 0.0);
}

TEST(Observability, NamesCombinations) {
  ParameterVector v = ParameterVector::Zero(35);
  v(ParameterIndex(2, DhParameter::kD)) = 2.0;
  v(ParameterIndex(3, DhParameter::kD)) = -2.0;
  EXPECT_EQ(NameCombination(v, ParameterNames(R2())), "0.707 r2.link2.d - 0.707 r2.link3.d");
  v.setZero();
  v(ParameterIndex(1, DhParameter::kTheta)) = -3.0;
  EXPECT_EQ(NameCombination(v, ParameterNames(R2())), "r2.link1.theta");
}

// Phi, its names and scales and the tolerance all come from our own code: a mismatch is a
// broken precondition.
TEST(Observability, RejectsBrokenPreconditions) {
  try {
    AnalyseObservability(Eigen::MatrixXd::Zero(6, 34), R2(), 1e-6);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("34 columns"), std::string::npos);
  }
  try {
    AnalyseObservability(Eigen::MatrixXd::Ones(6, 35), R2(), 1.5);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("relative_tolerance"), std::string::npos);
  }
}

}  // namespace
}  // namespace twin
