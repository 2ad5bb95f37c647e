#include "calib/cell/cell.h"

#include <gtest/gtest.h>

namespace twin {
namespace {

// A cell whose frames are a gradient (pixel value = column + 3 row, per channel), to check the
// default region grab: a crop of a whole frame, clipped to it.
class GradientCell : public Cell {
 public:
  MoveResult MoveTo(int, const JointVector&) override { return {}; }
  JointVector ReadEncoders(int) override { return JointVector::Zero(6); }
  cv::Mat GrabImage() override {
    ++frames;
    cv::Mat m(48, 64, CV_8UC3);
    for (int r = 0; r < m.rows; ++r) {
      for (int c = 0; c < m.cols; ++c) m.at<cv::Vec3b>(r, c) = cv::Vec3b(c, 3 * r, c + r);
    }
    return m;
  }
  MoveResult ExchangeTools() override { return {}; }
  int CameraRobot() override { return 0; }
  int frames = 0;
};

TEST(CellTest, DefaultRegionGrabIsAClippedCropOfAFrame) {
  GradientCell cell;
  const cv::Mat r = cell.GrabImageRegion(cv::Rect(10, 20, 5, 4));
  ASSERT_EQ(r.size(), cv::Size(5, 4));
  EXPECT_EQ(r.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 60, 30));  // frame pixel (10, 20)
  EXPECT_EQ(r.at<cv::Vec3b>(3, 4), cv::Vec3b(14, 69, 37));
  const cv::Mat clipped = cell.GrabImageRegion(cv::Rect(60, -2, 10, 5));
  ASSERT_EQ(clipped.size(), cv::Size(4, 3));  // columns 60..63, rows 0..2
  EXPECT_EQ(clipped.at<cv::Vec3b>(0, 0), cv::Vec3b(60, 0, 60));
  EXPECT_TRUE(cell.GrabImageRegion(cv::Rect(100, 100, 5, 5)).empty());
  EXPECT_EQ(cell.frames, 3);  // one frame per region grab
}

TEST(CellTest, DefaultCellHasTheFeatureBoardOnly) {
  GradientCell cell;
  const MoveResult board = cell.MountTarget(BracketTarget::kFeatureBoard);
  EXPECT_EQ(board.status, MoveStatus::kSettled);
  EXPECT_TRUE(board.reason.empty()) << board.reason;
  const MoveResult target = cell.MountTarget(BracketTarget::kIntrinsicsTarget);
  EXPECT_EQ(target.status, MoveStatus::kInvalidInput);
  EXPECT_NE(target.reason.find("no intrinsics target"), std::string::npos) << target.reason;
  EXPECT_STREQ(ToString(BracketTarget::kIntrinsicsTarget), "intrinsics_target");
  EXPECT_STREQ(ToString(BracketTarget::kFeatureBoard), "feature_board");
  EXPECT_EQ(cell.frames, 0);
}

}  // namespace
}  // namespace twin
