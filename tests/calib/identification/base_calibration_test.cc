#include "calib/identification/base_calibration.h"

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

using Status = BaseCalibrationResult::Status;

// X_B1B2 from a Table 1 row: translation in mm, ZYZ Euler angles in degrees (eq. 31).
Transform FromTableRow(double x, double y, double z, double phi, double theta, double psi) {
  Transform X = Transform::Identity();
  X.linear() = RotationFromZyz(Vector3(DegToRad(phi), DegToRad(theta), DegToRad(psi)));
  X.translation() = Vector3(x, y, z) / 1000.0;
  return X;
}

struct Case {
  const char* name;
  BaseConstraint constraint;
  Transform truth;  // Table 1 true transform (slightly off the ideal installation)
  Transform ideal;  // the same with the middle ZYZ angle exactly 0 / 180 / 90 deg
};

// Paper Table 1, H_tru of the three installations. The measured truths deviate from the ideal
// installation by 0.001 deg (floor-floor, floor-ceiling) and 0.126 deg (floor-wall), which the
// constrained solutions cannot represent; exact-recovery tests therefore use the ideal versions.
std::vector<Case> PaperCases() {
  return {
      {"floor-floor", BaseConstraint::kFloorFloor,
       FromTableRow(37.9, 1476.5, 54.5, -0.001, 0.001, -44.5),
       FromTableRow(37.9, 1476.5, 54.5, 0.0, 0.0, -44.5)},
      {"floor-ceiling", BaseConstraint::kFloorCeiling,
       FromTableRow(1500.1, 500.0, 1499.9, 0.0, 180.001, 0.001),
       FromTableRow(1500.1, 500.0, 1499.9, 0.0, 180.0, 0.001)},
      {"floor-wall", BaseConstraint::kFloorWall,
       FromTableRow(1303.3, -102.3, 1386.3, 180.0, 89.874, -179.997),
       FromTableRow(1303.3, -102.3, 1386.3, 180.0, 90.0, -179.997)},
  };
}

// The paper's recommended contact set (section 3, Fig. 8): a regular triangular pyramid with
// 1 m sides (base triangle P1..P3 horizontal, apex P4 above), then extra contacts inside it.
// Expressed about the pyramid's base centroid; `yaw` turns it about the vertical; a negative
// apex_height means the regular pyramid's, side * sqrt(2/3).
std::vector<Vector3> PyramidContacts(int n, double yaw = 0.0, double side = 1.0,
                                     double apex_height = -1.0) {
  if (apex_height < 0) apex_height = side * std::sqrt(2.0 / 3.0);
  const double r = side / std::sqrt(3.0);  // circumradius of the base triangle
  std::vector<Vector3> p = {
      {r, 0, 0},
      {-r / 2, side / 2, 0},
      {-r / 2, -side / 2, 0},
      {0, 0, apex_height},
      {0.3 * side, 0.3 * side, 0.4 * side},
      {-0.3 * side, 0.2 * side, 0.5 * side},
      {0.1 * side, -0.4 * side, 0.3 * side},
      {0, 0, -0.3 * side},
  };
  p.resize(static_cast<size_t>(n));
  const Matrix3 R = Eigen::AngleAxisd(yaw, Vector3::UnitZ()).toRotationMatrix();
  for (Vector3& q : p) q = R * q;
  return p;
}

// Contacts placed between the two robots: the pyramid centred half-way along X_B1B2's
// translation, given in B1 and, through the true transform, in B2.
void MakeContacts(const Transform& X_B1B2, const std::vector<Vector3>& pyramid,
                  std::vector<Vector3>* p_B1, std::vector<Vector3>* p_B2) {
  const Vector3 centre_B1 = 0.5 * X_B1B2.translation();
  const Transform X_B2B1 = X_B1B2.inverse();
  p_B1->clear();
  p_B2->clear();
  for (const Vector3& q : pyramid) {
    p_B1->push_back(centre_B1 + q);
    p_B2->push_back(X_B2B1 * (centre_B1 + q));
  }
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// ---------------------------------------------------------------- ZYZ Euler angles (eq. 31-32)

TEST(Zyz, RotationFromZyzMatchesEquation31) {
  const double phi = 0.3, theta = 1.1, psi = -2.0;
  const Matrix3 R = RotationFromZyz(Vector3(phi, theta, psi));
  // Third column and third row of eq. 31; 1e-15: a few ulps of products of unit numbers.
  EXPECT_NEAR(R(0, 2), std::cos(phi) * std::sin(theta), 1e-15);
  EXPECT_NEAR(R(1, 2), std::sin(phi) * std::sin(theta), 1e-15);
  EXPECT_NEAR(R(2, 2), std::cos(theta), 1e-15);
  EXPECT_NEAR(R(2, 0), -std::sin(theta) * std::cos(psi), 1e-15);
  EXPECT_NEAR(R(2, 1), std::sin(theta) * std::sin(psi), 1e-15);
}

TEST(Zyz, AnglesRoundTripAwayFromTheDegeneracy) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-kPi + 1e-6, kPi);
  std::uniform_real_distribution<double> middle(1e-3, kPi - 1e-3);
  for (int i = 0; i < 1000; ++i) {
    const Vector3 zyz(angle(rng), middle(rng), angle(rng));
    const Vector3 back = ZyzFromRotation(RotationFromZyz(zyz));
    // 1e-9 rad: atan2 of entries with rounding errors ~1e-16, divided by sin(theta) >= 1e-3.
    EXPECT_LT((back - zyz).cwiseAbs().maxCoeff(), 1e-9) << zyz.transpose();
  }
}

TEST(Zyz, RotationsRoundTripIncludingTheDegenerateOnes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int i = 0; i < 300; ++i) {
    const double theta = (i % 3 == 0) ? 0.0 : (i % 3 == 1) ? kPi : std::abs(angle(rng));
    const Matrix3 R = RotationFromZyz(Vector3(angle(rng), theta, angle(rng)));
    // 1e-12: rounding of a product of three rotations and a few trig calls.
    EXPECT_LT((RotationFromZyz(ZyzFromRotation(R)) - R).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(Zyz, DegenerateMiddleAngleFollowsThePaper) {
  // eq. 32 with theta = 0: only phi + psi is defined, the paper sets phi = 0.
  Vector3 zyz = ZyzFromRotation(RotationFromZyz(Vector3(0.3, 0.0, 0.4)));
  EXPECT_NEAR(zyz(0), 0.0, 1e-15);  // exactly the convention, up to rounding
  EXPECT_NEAR(zyz(1), 0.0, 1e-15);
  EXPECT_NEAR(zyz(2), 0.7, 1e-12);
  // theta = 180 deg: Rz(phi) Ry(pi) Rz(psi) = Ry(pi) Rz(psi - phi).
  zyz = ZyzFromRotation(RotationFromZyz(Vector3(0.3, kPi, 0.4)));
  EXPECT_NEAR(zyz(0), 0.0, 1e-15);
  EXPECT_NEAR(std::abs(zyz(1)), kPi, 1e-12);
  EXPECT_NEAR(zyz(2), 0.1, 1e-12);
}

// ------------------------------------------------------------------- orthonormalization (eq. 3)

TEST(NearestRotation, IsAProperRotationAndKeepsRotations) {
  const Matrix3 R = RotationFromZyz(Vector3(0.2, 0.7, -1.3));
  EXPECT_LT((NearestRotation(R) - R).norm(), 1e-14);  // rounding only
  Matrix3 M = 1.02 * R;
  M(0, 1) += 0.01;
  const Matrix3 Q = NearestRotation(M);
  EXPECT_LT((Q.transpose() * Q - Matrix3::Identity()).norm(), 1e-14);
  EXPECT_NEAR(Q.determinant(), 1.0, 1e-14);
  // A reflection still gives det +1 (the det fix of the SVD solution).
  EXPECT_NEAR(NearestRotation(Vector3(1, 1, -1).asDiagonal()).determinant(), 1.0, 1e-14);
}

// --------------------------------------------------------------- accuracy measures (eq. 32-34)

TEST(CompareBaseFrames, KnownDifferences) {
  const Transform truth = FromTableRow(100, 200, 300, 30, 60, -45);
  Transform est = FromTableRow(101, 197, 302, 30, 60, -44.5);
  BaseFrameError e = CompareBaseFrames(est, truth);
  EXPECT_NEAR(e.e_tran_mm, 3.0, 1e-9);  // infinity norm of (1, -3, 2) mm
  EXPECT_NEAR(e.e_rot_deg, 0.5, 1e-9);  // psi differs by 0.5 deg
  // Differences are wrapped: 179.9 vs -179.9 deg is 0.2 deg apart.
  e = CompareBaseFrames(FromTableRow(100, 200, 300, -179.9, 60, -45),
                        FromTableRow(100, 200, 300, 179.9, 60, -45));
  EXPECT_NEAR(e.e_tran_mm, 0.0, 1e-9);
  EXPECT_NEAR(e.e_rot_deg, 0.2, 1e-9);
}

TEST(CompareBaseFrames, DegenerateMiddleAngleDoesNotCountTheUndefinedSplit) {
  // Both near theta = 0: (10, 0, -54.5) is the same rotation as (0, 0, -44.5); the truth
  // differs from it by 0.001 deg in theta and ~0.001 deg in phi + psi.
  const Transform truth = FromTableRow(0, 0, 0, -0.001, 0.001, -44.5);
  BaseFrameError e = CompareBaseFrames(FromTableRow(0, 0, 0, 10, 0, -54.5), truth);
  EXPECT_LT(e.e_rot_deg, 0.002);  // 0.001 deg true difference plus rounding
  // Near theta = 180 deg only psi - phi is defined.
  e = CompareBaseFrames(FromTableRow(0, 0, 0, 5, 180, 5.001),
                        FromTableRow(0, 0, 0, 0, 180.001, 0.001));
  EXPECT_LT(e.e_rot_deg, 0.002);
}

TEST(CompareBaseFrames, ReproducesThePapersTable1Errors) {
  // Rows of Table 1 (H_tru against H_calib1 / H_calib2, with the paper's e_tran and e_rot).
  // Tolerances: Table 1 rounds translations to 0.1 mm and angles to 0.001 deg, so e_tran can
  // differ by 0.1 mm and e_rot by 0.002 deg.
  struct Row {
    Transform truth, estimate;
    double e_tran_mm, e_rot_deg;
  };
  const Transform ff = FromTableRow(37.9, 1476.5, 54.5, -0.001, 0.001, -44.500);
  const Transform fc = FromTableRow(1500.1, 500.0, 1499.9, 0, 180.001, 0.001);
  const Transform fw = FromTableRow(1303.3, -102.3, 1386.3, 180, 89.874, -179.997);
  const std::vector<Row> rows = {
      {ff, FromTableRow(43.6, 1475.4, 58.8, 0, -0.167, -44.593), 5.7, 0.167},
      {ff, FromTableRow(43.8, 1475.6, 58.2, 0, 0, -44.593), 5.9, 0.093},
      {fc, FromTableRow(1501.4, 508.6, 1496.2, 0, -179.941, -0.312), 8.6, 0.312},
      {fc, FromTableRow(1500.4, 506.3, 1498.4, 0, 180, -0.312), 6.3, 0.312},
      {fw, FromTableRow(1305.2, -101.2, 1384.0, -179.952, 89.753, 179.890), 2.3, 0.121},
      {fw, FromTableRow(1301.5, -101.2, 1387.0, -179.952, 90, 179.890), 1.8, 0.126},
  };
  for (const Row& row : rows) {
    const BaseFrameError e = CompareBaseFrames(row.estimate, row.truth);
    EXPECT_NEAR(e.e_tran_mm, row.e_tran_mm, 0.1 + 1e-9);
    EXPECT_NEAR(e.e_rot_deg, row.e_rot_deg, 0.002);
  }
}

// ------------------------------------------------------------------------------ calibration

TEST(CalibrateBaseFrame, RecoversIdealInstallationsExactlyWithoutNoise) {
  for (const Case& c : PaperCases()) {
    for (int n = 4; n <= 8; ++n) {
      std::vector<Vector3> p_B1, p_B2;
      MakeContacts(c.ideal, PyramidContacts(n, 0.4), &p_B1, &p_B2);
      const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, c.constraint);
      ASSERT_EQ(r.status, Status::kSuccess) << c.name << " n=" << n << ": " << r.reason;
      EXPECT_TRUE(r.warnings.empty()) << c.name << ": " << r.warnings.front();
      // 1e-6 mm and 1e-6 deg: noise-free data, so only rounding (~1e-12 relative) and the LM's
      // tolerance (floor-wall, ~1e-10 rad) remain, far below these bounds.
      for (const Transform* X : {&r.X_B1B2_general, &r.X_B1B2_constrained}) {
        const BaseFrameError e = CompareBaseFrames(*X, c.ideal);
        EXPECT_LT(e.e_tran_mm, 1e-6) << c.name << " n=" << n;
        EXPECT_LT(e.e_rot_deg, 1e-6) << c.name << " n=" << n;
      }
      EXPECT_LT(r.rms_residual_general_m, 1e-9);  // metres; rounding only
      EXPECT_LT(r.rms_residual_constrained_m, 1e-9);
    }
  }
}

TEST(CalibrateBaseFrame, GeneralConstraintReturnsTheGeneralSolution) {
  const Case c = PaperCases()[2];
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(c.truth, PyramidContacts(5), &p_B1, &p_B2);
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kGeneral);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_TRUE(r.X_B1B2_general.isApprox(r.X_B1B2_constrained, 1e-15));
  // The general solution recovers even the non-ideal truth (1e-6: rounding, see above).
  EXPECT_LT(CompareBaseFrames(r.X_B1B2_general, c.truth).e_rot_deg, 1e-6);
}

TEST(CalibrateBaseFrame, ConstrainedRotationsSatisfyTheirInstallationUnderNoise) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (const Case& c : PaperCases()) {
    std::vector<Vector3> p_B1, p_B2;
    MakeContacts(c.truth, PyramidContacts(6), &p_B1, &p_B2);
    for (size_t i = 0; i < p_B1.size(); ++i) {
      p_B1[i] += Vector3(noise(rng), noise(rng), noise(rng));
      p_B2[i] += Vector3(noise(rng), noise(rng), noise(rng));
    }
    const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, c.constraint);
    ASSERT_TRUE(r.ok()) << r.reason;
    const Matrix3 R = r.X_B1B2_constrained.linear();
    EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-12);  // rounding only
    const double z_expected = c.constraint == BaseConstraint::kFloorFloor     ? 1.0
                              : c.constraint == BaseConstraint::kFloorCeiling ? -1.0
                                                                              : 0.0;
    EXPECT_NEAR(R(2, 2), z_expected, 1e-12) << c.name;  // z_B2 . z_B1, exact by construction
  }
}

// Operator error level: the paper states none, but Table 1's general-solution errors with 4
// contacts average e_tran1 = 6.1 / 7.5 / 4.7 mm and e_rot1 = 0.18 / 0.26 / 0.30 deg (floor-floor /
// floor-ceiling / floor-wall). An independent Gaussian error of 3 mm per axis on each robot's
// reading of each contact (operator misalignment of the tips plus the robots' absolute
// positioning error) gives the same level with the 1 m pyramid placed between the robots.
constexpr double kContactSigmaM = 0.003;
constexpr int kTrials = 200;

TEST(CalibrateBaseFrame, ConstrainedIsNotWorseThanGeneralAtThePapersErrorLevel) {
  std::mt19937 rng(2014);
  std::normal_distribution<double> noise(0.0, kContactSigmaM);
  std::uniform_real_distribution<double> yaw(-kPi, kPi);
  for (const Case& c : PaperCases()) {
    double tran_general = 0, rot_general = 0, tran_constrained = 0, rot_constrained = 0;
    for (int t = 0; t < kTrials; ++t) {
      std::vector<Vector3> p_B1, p_B2;
      MakeContacts(c.truth, PyramidContacts(4, yaw(rng)), &p_B1, &p_B2);  // the paper's 4
      for (size_t i = 0; i < p_B1.size(); ++i) {
        p_B1[i] += Vector3(noise(rng), noise(rng), noise(rng));
        p_B2[i] += Vector3(noise(rng), noise(rng), noise(rng));
      }
      const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, c.constraint);
      ASSERT_TRUE(r.ok()) << r.reason;
      const BaseFrameError g = CompareBaseFrames(r.X_B1B2_general, c.truth);
      const BaseFrameError k = CompareBaseFrames(r.X_B1B2_constrained, c.truth);
      tran_general += g.e_tran_mm / kTrials;
      rot_general += g.e_rot_deg / kTrials;
      tran_constrained += k.e_tran_mm / kTrials;
      rot_constrained += k.e_rot_deg / kTrials;
    }
    std::printf("[ means    ] %-13s sigma %.0f mm, %d trials: general e_tran %.2f mm e_rot %.3f "
                "deg | constrained e_tran %.2f mm e_rot %.3f deg\n",
                c.name, kContactSigmaM * 1e3, kTrials, tran_general, rot_general,
                tran_constrained, rot_constrained);
    // The claim of the paper (Table 1, Fig. 11-12): the installation constraint does not hurt.
    EXPECT_LE(tran_constrained, tran_general) << c.name;
    EXPECT_LE(rot_constrained, rot_general) << c.name;
    // Sanity against Table 1's level: the paper's worst errors are 11.9 mm and 0.45 deg.
    EXPECT_LT(tran_general, 12.0) << c.name;
    EXPECT_LT(rot_general, 0.5) << c.name;
  }
}

TEST(CalibrateBaseFrame, FloorWallReportsAnLmThatDidNotConverge) {
  const Case c = PaperCases()[2];
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(c.truth, PyramidContacts(4), &p_B1, &p_B2);
  p_B1[0] += Vector3(0.01, -0.01, 0.01);  // noise, so the start is not already the optimum
  BaseCalibrationOptions options;
  options.lm_max_iterations = 1;
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, c.constraint, options);
  EXPECT_EQ(r.status, Status::kNotConverged);
  EXPECT_TRUE(Contains(r.reason, "did not converge")) << r.reason;
  // The general solution is still delivered; 0.5 deg: a 1.7 cm error on one of 4 contacts
  // ~1 m apart tilts the fit by about 0.01 rad.
  EXPECT_LT(CompareBaseFrames(r.X_B1B2_general, c.truth).e_rot_deg, 0.5);
}

// --------------------------------------------------------------------- refusals and warnings

TEST(CalibrateBaseFrame, RefusesFewerThanFourContacts) {
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(PaperCases()[0].ideal, PyramidContacts(3), &p_B1, &p_B2);
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kFloorFloor);
  EXPECT_EQ(r.status, Status::kTooFewPoints);
  EXPECT_TRUE(Contains(r.reason, "at least 4")) << r.reason;
  EXPECT_TRUE(Contains(r.reason, "got 3")) << r.reason;
}

TEST(CalibrateBaseFrame, RefusesCollinearContactsNamingTheSingularValues) {
  std::vector<Vector3> line;
  for (int i = 0; i < 5; ++i) line.push_back(Vector3(0.3 * i, 0.1 * i, 0.05 * i));
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(PaperCases()[0].ideal, line, &p_B1, &p_B2);
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kFloorFloor);
  EXPECT_EQ(r.status, Status::kDegenerate);
  EXPECT_TRUE(Contains(r.reason, "collinear")) << r.reason;
  EXPECT_TRUE(Contains(r.reason, "singular values")) << r.reason;
  EXPECT_TRUE(Contains(r.reason, "collinear_ratio_min")) << r.reason;
}

TEST(CalibrateBaseFrame, RefusesCoplanarContactsNamingTheSingularValues) {
  // The pyramid's apex pulled into the base plane, up to 1e-5 m: sigma3/sigma1 ~ 1e-5 < 1e-3.
  std::vector<Vector3> flat = PyramidContacts(4);
  flat[3].z() = 1e-5;
  flat.push_back(Vector3(0.1, 0.1, 0.0));
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(PaperCases()[1].ideal, flat, &p_B1, &p_B2);
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kFloorCeiling);
  EXPECT_EQ(r.status, Status::kDegenerate);
  EXPECT_TRUE(Contains(r.reason, "coplanar")) << r.reason;
  EXPECT_TRUE(Contains(r.reason, "singular values")) << r.reason;
  EXPECT_NEAR(r.singular_values_m(2), 0.0, 1e-4);  // reported: ~1e-5 m out of plane
}

TEST(CalibrateBaseFrame, WarnsWhenFarFromTheRecommendedPyramid) {
  const Case c = PaperCases()[0];
  std::vector<Vector3> p_B1, p_B2;
  // 0.2 m sides: well formed, but far below the paper's ~1 m.
  MakeContacts(c.ideal, PyramidContacts(4, 0.0, 0.2), &p_B1, &p_B2);
  BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, c.constraint);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(Contains(r.warnings[0], "span only")) << r.warnings[0];
  // 1 m base with the apex only 5 cm above it: solvable but flat.
  MakeContacts(c.ideal, PyramidContacts(4, 0.0, 1.0, 0.05), &p_B1, &p_B2);
  r = CalibrateBaseFrame(p_B1, p_B2, c.constraint);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(Contains(r.warnings[0], "far from a triangular pyramid")) << r.warnings[0];
}

TEST(CalibrateBaseFrame, WarnsWhenTheDeclaredInstallationDoesNotFit) {
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(PaperCases()[2].truth, PyramidContacts(4), &p_B1, &p_B2);  // a wall robot
  const BaseCalibrationResult r = CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kFloorFloor);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_TRUE(Contains(r.warnings[0], "check the declared installation")) << r.warnings[0];
}

// The contacts are forward kinematics of encoder readings (never a user's numbers): unequal
// counts or a non-finite coordinate are a caller's bug.
TEST(CalibrateBaseFrame, MalformedInputIsAPreconditionError) {
  std::vector<Vector3> p_B1, p_B2;
  MakeContacts(PaperCases()[0].ideal, PyramidContacts(4), &p_B1, &p_B2);
  std::vector<Vector3> short_B2(p_B2.begin(), p_B2.end() - 1);
  try {
    CalibrateBaseFrame(p_B1, short_B2, BaseConstraint::kFloorFloor);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "got 4 and 3")) << e.what();
  }
  p_B2[1].y() = std::nan("");
  try {
    CalibrateBaseFrame(p_B1, p_B2, BaseConstraint::kFloorFloor);
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "p_B2[1]")) << e.what();
  }
}

TEST(BaseCalibrationOptions, ValidateNamesTheBadField) {
  EXPECT_NO_THROW(BaseCalibrationOptions{}.Validate());
  BaseCalibrationOptions options;
  options.coplanar_ratio_min = 1.5;
  try {
    options.Validate();
    FAIL() << "expected PreconditionError";  // no user sets these options
  } catch (const PreconditionError& e) {
    EXPECT_TRUE(Contains(e.what(), "BaseCalibrationOptions.coplanar_ratio_min")) << e.what();
    EXPECT_TRUE(Contains(e.what(), "1.5")) << e.what();
  }
  options = BaseCalibrationOptions{};
  options.lm_max_iterations = 0;
  EXPECT_THROW(options.Validate(), PreconditionError);
}

}  // namespace
}  // namespace twin
