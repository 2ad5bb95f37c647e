// The handclasp procedure (calib/procedures/handclasp_procedure.h) against a kinematic fake Cell whose
// operator makes exact contacts through a known X_B1B2: exact recovery, skipped contacts,
// refusals, and the planner.
#include "calib/procedures/handclasp_procedure.h"

#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "calib/kinematics/forward_kinematics.h"
#include "calib/kinematics/inverse_kinematics.h"
#include "tests/calib/test_models.h"

namespace twin {
namespace {

using testing::ReinovoLikeModel;

Transform FloorFloorLayout() {  // Gan 2014 Table 1, floor-floor, made exactly floor-floor
  Transform X = Transform::Identity();
  X.linear() = RotationFromZyz(Vector3(0, 0, DegToRad(-44.5)));
  X.translation() = Vector3(0.0379, 1.4765, 0.0545);
  return X;
}

std::array<KinematicModel, 2> TipModels() {
  Transform X_FTip = Transform::Identity();
  X_FTip.translation() = Vector3(0, 0, 0.2);
  return {WithTipTool(ReinovoLikeModel(0), X_FTip), WithTipTool(ReinovoLikeModel(1), X_FTip)};
}

// Moves are instantaneous and exact; the operator's contact puts robot 2's tip exactly on
// robot 1's (facing it) by IK; contacts whose call number is in `fail_contacts` fail.
class FakeCell : public Cell {
 public:
  FakeCell(std::array<KinematicModel, 2> models, Transform X_B1B2)
      : models_(std::move(models)), X_B1B2_(X_B1B2) {
    q_[0] = JointVector::Zero(6);
    q_[1] = JointVector::Zero(6);
  }
  MoveResult MoveTo(int robot, const JointVector& q) override {
    q_[robot] = q;
    return {};
  }
  JointVector ReadEncoders(int robot) override { return q_[robot]; }
  cv::Mat GrabImage() override { return {}; }
  MoveResult ExchangeTools() override { return {}; }
  int CameraRobot() override { return 0; }
  MoveResult JogTipToContact(int jogged) override {
    MoveResult r;
    if (fail_contacts.count(calls_++)) {
      r.status = MoveStatus::kCollision;
      r.reason = "fake collision";
      return r;
    }
    EXPECT_EQ(jogged, 1);
    const Transform X_B1Tip1 = EndPose(models_[0], q_[0]);
    // The first roll tried changes from contact to contact, as an operator's would: the
    // relative orientation of the two flanges must vary for both tips to be identifiable.
    for (int k = 0; k < 8; ++k) {
      const int roll = (k + 3 * calls_) % 8;
      Transform X = Transform::Identity();
      X.linear() = FacingTipRotation(X_B1Tip1.linear(), roll * kPi / 4);
      X.translation() = X_B1Tip1.translation();
      IkOptions ik;
      ik.position_tolerance = 1e-12;  // exact contacts: only rounding remains
      ik.orientation_tolerance = 1e-10;
      const IkResult s = SolveIk(models_[1], X_B1B2_.inverse() * X, q_[1], ik);
      if (s.status == IkStatus::kSuccess) {
        q_[1] = s.q;
        return r;
      }
    }
    r.status = MoveStatus::kOutOfLimits;
    r.reason = "fake: unreachable";
    return r;
  }
  std::set<int> fail_contacts;

 private:
  std::array<KinematicModel, 2> models_;
  Transform X_B1B2_;
  std::array<JointVector, 2> q_;
  int calls_ = 0;
};

TaughtPoints Plan() {
  return PlanTaughtPoints(TipModels(), FloorFloorLayout(),
                          {JointVector::Zero(6), JointVector::Zero(6)});
}

TEST(HandclaspPlanner, PlansAWellSpreadCubeReachableByBoth) {
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok) << t.reason;
  EXPECT_GE(t.q1.size(), 6u);
  EXPECT_GE(t.cube_side_m, 0.2);
  const auto m = TipModels();
  for (size_t i = 0; i < t.q1.size(); ++i) {
    // IK tolerance 1e-7 m (IkOptions default); 1e-6 m leaves a margin.
    EXPECT_LT((EndPose(m[0], t.q1[i]).translation() - t.p_B1[i]).norm(), 1e-6);
  }
}

TEST(HandclaspProcedure, RecoversTheBaseFrameExactlyFromExactContacts) {
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok) << t.reason;
  FakeCell cell(TipModels(), FloorFloorLayout());
  HandclaspOptions o;
  o.constraint = BaseConstraint::kFloorFloor;
  std::ostringstream log;
  const HandclaspResult r = RunHandclaspProcedure(cell, TipModels(), t.q1, o, &log);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(r.contacts.size(), t.q1.size());
  // Contacts exact to the fake's IK tolerance (1e-12 m): 1e-6 mm and deg leave a wide margin.
  for (const Transform* X : {&r.calibration.X_B1B2_general, &r.calibration.X_B1B2_constrained}) {
    const BaseFrameError e = CompareBaseFrames(*X, FloorFloorLayout());
    EXPECT_LT(e.e_tran_mm, 1e-6);
    EXPECT_LT(e.e_rot_deg, 1e-6);
  }
}

TEST(HandclaspProcedure, IdentifiesBothTipsAndTheBaseFrameFromVariedOrientations) {
  // The physical tips differ from the pendant's: robot 1's across its axis (the along-axis
  // share is the gauge of tip_refinement.h), robot 2's in all three directions.
  const Vector3 dt1(0.0010, -0.0015, 0.0), dt2(0.0008, 0.0005, -0.0010);
  std::array<KinematicModel, 2> physical = TipModels();
  physical[0].X_LtE.translation() += dt1;
  physical[1].X_LtE.translation() += dt2;
  TeachOptions teach;
  teach.orientations_per_point = 4;
  const TaughtPoints t = PlanTaughtPoints(TipModels(), FloorFloorLayout(),
                                          {JointVector::Zero(6), JointVector::Zero(6)}, teach);
  ASSERT_TRUE(t.ok) << t.reason;
  EXPECT_GT(static_cast<int>(t.q1.size()), t.points);  // extra orientations were teachable
  FakeCell cell(physical, FloorFloorLayout());
  HandclaspOptions o;
  o.identify_tips = true;
  std::ostringstream log;
  const HandclaspResult r = RunHandclaspProcedure(cell, TipModels(), t.q1, o, &log);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_TRUE(r.tips.ok) << r.tips.reason;
  // Gan's solution with the pendant tips suffers from the millimetre tip errors...
  const BaseFrameError gan = CompareBaseFrames(r.calibration.X_B1B2_general, FloorFloorLayout());
  EXPECT_GT(gan.e_tran_mm, 0.1);
  // ...the joint refinement does not (exact contacts to 1e-12 m: 1e-6 mm / deg leave margin).
  const BaseFrameError e = CompareBaseFrames(r.tips.X_B1B2, FloorFloorLayout());
  EXPECT_LT(e.e_tran_mm, 1e-6);
  EXPECT_LT(e.e_rot_deg, 1e-6);
  EXPECT_LT((r.tips.dt1_F1 - dt1).norm(), 1e-9);
  EXPECT_LT((r.tips.dt2_F2 - dt2).norm(), 1e-9);
  EXPECT_NE(log.str().find("tips identified"), std::string::npos) << log.str();
}

TEST(HandclaspProcedure, TipIdentificationWithOneOrientationPerPointIsRefusedWithAWarning) {
  // Robot 1's tip points at robot 2's shoulder from every corner and the fake's roll choice
  // follows, so with one orientation per point the rotations vary too little (or just
  // enough); either way the Gan estimate stands and nothing is half-done.
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok) << t.reason;
  EXPECT_EQ(static_cast<int>(t.q1.size()), t.points);
  FakeCell cell(TipModels(), FloorFloorLayout());
  HandclaspOptions o;
  o.identify_tips = true;
  o.tips.min_relative_singular_value = 0.5;  // stricter than any real spread: forces refusal
  const HandclaspResult r = RunHandclaspProcedure(cell, TipModels(), t.q1, o, nullptr);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_FALSE(r.tips.ok);
  ASSERT_FALSE(r.calibration.warnings.empty());
  EXPECT_NE(r.calibration.warnings.back().find("tip identification"), std::string::npos);
  const BaseFrameError e = CompareBaseFrames(r.calibration.X_B1B2_general, FloorFloorLayout());
  EXPECT_LT(e.e_tran_mm, 1e-6);
}

TEST(HandclaspProcedure, SkipsAndLogsFailedContacts) {
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok);
  FakeCell cell(TipModels(), FloorFloorLayout());
  cell.fail_contacts = {1};
  std::ostringstream log;
  const HandclaspResult r = RunHandclaspProcedure(cell, TipModels(), t.q1, {}, &log);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_NE(r.skipped[0].find("point 1: contact collision: fake collision"), std::string::npos)
      << r.skipped[0];
  EXPECT_NE(log.str().find("skipped point 1"), std::string::npos) << log.str();
  EXPECT_EQ(r.contacts.size(), t.q1.size() - 1);
}

TEST(HandclaspProcedure, RefusesWhenTooFewContactsRemain) {
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok);
  FakeCell cell(TipModels(), FloorFloorLayout());
  for (int i = 0; i < static_cast<int>(t.q1.size()) - 3; ++i) cell.fail_contacts.insert(i);
  const HandclaspResult r = RunHandclaspProcedure(cell, TipModels(), t.q1, {}, nullptr);
  EXPECT_EQ(r.status, HandclaspResult::Status::kTooFewContacts);
  EXPECT_NE(r.reason.find("only 3 of"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("need 4"), std::string::npos) << r.reason;
}

TEST(HandclaspProcedure, RefusesCollinearContactsWithAClearMessage) {
  // Robot 1 taught along one line: joint 1 fixed, the tip moved along its own axis.
  const auto m = TipModels();
  const TaughtPoints t = Plan();
  ASSERT_TRUE(t.ok);
  const Transform X0 = EndPose(m[0], t.q1[0]);
  std::vector<JointVector> line;
  for (int i = 0; i < 5; ++i) {
    Transform X = X0;
    X.translation() += (0.03 * i) * X0.linear().col(2);
    const IkResult s = SolveIk(m[0], X, t.q1[0]);
    ASSERT_EQ(s.status, IkStatus::kSuccess) << s.reason;
    line.push_back(s.q);
  }
  FakeCell cell(m, FloorFloorLayout());
  const HandclaspResult r = RunHandclaspProcedure(cell, m, line, {}, nullptr);
  EXPECT_EQ(r.status, HandclaspResult::Status::kCalibrationFailed);
  EXPECT_NE(r.reason.find("collinear"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("triangle"), std::string::npos) << r.reason;
}

// The taught angles are IK solutions and no user sets the options: a non-finite angle or a
// bad option is a broken precondition, naming what was wrong.
TEST(HandclaspProcedure, BrokenPreconditionsArePreconditionErrors) {
  FakeCell cell(TipModels(), FloorFloorLayout());
  JointVector bad = JointVector::Zero(6);
  bad(2) = std::nan("");
  EXPECT_THROW(RunHandclaspProcedure(cell, TipModels(), {bad}, {}, nullptr), PreconditionError);
  HandclaspOptions o;
  o.retract_m = -1;
  try {
    RunHandclaspProcedure(cell, TipModels(), {}, o, nullptr);
    ADD_FAILURE();
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("retract_m must be >= 0"), std::string::npos)
        << e.what();
  }
}

TEST(HandclaspProcedure, ACellWithoutTipsRefusesTheHandclasp) {
  struct Plain : Cell {
    MoveResult MoveTo(int, const JointVector&) override { return {}; }
    JointVector ReadEncoders(int) override { return JointVector::Zero(6); }
    cv::Mat GrabImage() override { return {}; }
    MoveResult ExchangeTools() override { return {}; }
    int CameraRobot() override { return 0; }
  } plain;
  const MoveResult r = plain.JogTipToContact(1);
  EXPECT_EQ(r.status, MoveStatus::kInvalidInput);
  EXPECT_NE(r.reason.find("no handclasp"), std::string::npos);
}

TEST(HandclaspTools, TipToolPutsTheEndFrameAtTheTip) {
  const KinematicModel flange = ReinovoLikeModel(0);
  Transform X_FTip = Transform::Identity();
  X_FTip.translation() = Vector3(0.01, -0.02, 0.3);
  const KinematicModel tip = WithTipTool(flange, X_FTip);
  const JointVector q = (JointVector(6) << 0.1, 0.2, -0.3, 0.4, 0.5, 0.6).finished();
  const Transform expected = ForwardKinematics(flange, q).flange() * X_FTip;
  EXPECT_LT((EndPose(tip, q).matrix() - expected.matrix()).norm(), 1e-12);  // rounding only
  const Matrix3 R = FacingTipRotation(Matrix3::Identity(), 0.3);
  EXPECT_LT((R.col(2) + Vector3::UnitZ()).norm(), 1e-12);
}

}  // namespace
}  // namespace twin
