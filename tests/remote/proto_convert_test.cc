// remote/proto_convert: what crosses the wire comes back bit for bit (issue 40: a remote run
// must see what an in-process run sees), and a malformed message is refused, not misread.
#include "remote/proto_convert.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace twin::remote {
namespace {

cv::Mat RandomImage(int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  return image;
}

// Both encodings are lossless: every pixel of a random image (the hardest case for PNG) back.
TEST(ProtoConvert, ImagesComeBackPixelForPixelInBothEncodings) {
  cv::theRNG().state = 7;
  const cv::Mat image = RandomImage(37, 23);
  for (const std::string encoding : {"png", "rgb8"}) {
    pb::GrabImageResponse response;
    EncodeImage(image, 5, 9, &response, encoding);
    EXPECT_EQ(response.encoding(), encoding);
    EXPECT_EQ(response.width_px(), 37u);
    EXPECT_EQ(response.height_px(), 23u);
    EXPECT_EQ(response.x_px(), 5);
    EXPECT_EQ(response.y_px(), 9);
    const cv::Mat back = DecodeImage(response);
    ASSERT_EQ(back.type(), CV_8UC3) << encoding;
    ASSERT_EQ(back.size(), image.size()) << encoding;
    EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0) << encoding;
  }
}

// rgb8 is RGB in rows from the top without padding, whatever OpenCV's BGR order is.
TEST(ProtoConvert, Rgb8IsRgbRowsFromTheTop) {
  cv::Mat image(2, 3, CV_8UC3, cv::Scalar(0, 0, 0));
  image.at<cv::Vec3b>(0, 0) = cv::Vec3b(10, 20, 30);  // B, G, R
  image.at<cv::Vec3b>(1, 2) = cv::Vec3b(40, 50, 60);
  pb::GrabImageResponse response;
  EncodeImage(image, 0, 0, &response, "rgb8");
  ASSERT_EQ(response.data().size(), 18u);
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(response.data()[i]); };
  EXPECT_EQ(byte(0), 30);  // R of the top-left pixel first
  EXPECT_EQ(byte(1), 20);
  EXPECT_EQ(byte(2), 10);
  EXPECT_EQ(byte(15), 60);  // the last pixel: row 1, column 2
  EXPECT_EQ(byte(17), 40);
}

TEST(ProtoConvert, MalformedImagesAreRefused) {
  pb::GrabImageResponse rgb8;
  rgb8.set_encoding("rgb8");
  rgb8.set_width_px(4);
  rgb8.set_height_px(4);
  rgb8.set_data(std::string(47, '\0'));  // one byte short of 4 x 4 x 3
  EXPECT_THROW(DecodeImage(rgb8), ProtocolError);
  pb::GrabImageResponse png;
  png.set_encoding("png");
  png.set_width_px(4);
  png.set_height_px(4);
  png.set_data("not a png");
  EXPECT_THROW(DecodeImage(png), ProtocolError);
  pb::GrabImageResponse other;
  other.set_encoding("jpeg");
  other.set_data("x");
  EXPECT_THROW(DecodeImage(other), ProtocolError);
  // A PNG whose stated size is not its own.
  pb::GrabImageResponse lying;
  EncodeImage(cv::Mat(3, 5, CV_8UC3, cv::Scalar::all(1)), 0, 0, &lying);
  lying.set_width_px(6);
  EXPECT_THROW(DecodeImage(lying), ProtocolError);
}

TEST(ProtoConvert, StoppedMovesAreMovesThatDidNotSettle) {
  pb::MoveResult stopped;
  stopped.set_status(pb::MOVE_STATUS_STOPPED);
  stopped.set_reason("the session ended");
  const MoveResult r = FromProto(stopped);
  EXPECT_EQ(r.status, MoveStatus::kNotSettled);
  EXPECT_EQ(r.reason, "stopped: the session ended");
  pb::MoveResult unknown;
  unknown.set_status(static_cast<pb::MoveStatus>(42));
  EXPECT_THROW(FromProto(unknown), ProtocolError);
  EXPECT_THROW(FromProto(pb::MOVE_STATUS_UNSPECIFIED), ProtocolError);
}

// Every number of the truth comes back to the bit: random values in every field that the
// bench's scoring reads.
TEST(ProtoConvert, TheTruthComesBackBitForBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const auto random_transform = [&] {
    Transform X = Transform::Identity();
    X.linear() = Eigen::AngleAxisd(u(rng), Vector3(u(rng), u(rng), u(rng)).normalized())
                     .toRotationMatrix();
    X.translation() = Vector3(u(rng), u(rng), u(rng));
    return X;
  };
  TwinTruth t;
  t.num_robots = 2;
  for (int r = 0; r < kMaxRobots; ++r) {
    KinematicModel m(r == 0 ? 6 : 7);
    m.name = "robot" + std::to_string(r);
    m.X_BL0 = random_transform();
    m.X_LtE = random_transform();
    for (Link& l : m.links) {
      l.dh = DhParameters{u(rng), u(rng), u(rng), u(rng), u(rng)};
      l.limits = JointLimits{-3 + u(rng) * 0.1, 3 + u(rng) * 0.1};
      l.inertia.mass = 1 + u(rng) * 0.1;
      l.inertia.p_LiCom = Vector3(u(rng), u(rng), u(rng));
      l.inertia.I_Com = Matrix3::Random();
      l.joint_name = "j" + std::to_string(r);
    }
    t.models[r] = m;
    t.length_scale[r] = 1 + u(rng) * 1e-6;
    t.X_WB[r] = random_transform();
    t.X_WF[r] = random_transform();
    t.X_FTip[r] = random_transform();
    t.q_link[r] = JointVector::Random(m.num_joints());
    t.q_motor[r] = JointVector::Random(m.num_joints());
    t.p_WTip[r] = Vector3(u(rng), u(rng), u(rng));
  }
  t.time_s = 12.345678901234567;
  t.X_WC = random_transform();
  t.X_WT = random_transform();
  t.camera.robot = 1;
  t.camera.X_FC = random_transform();
  t.camera.intrinsics.fx = 834.31 + u(rng);
  t.camera.distortion.k1 = u(rng) * 0.01;
  t.camera.msaa_samples = 2;
  t.camera.skybox = !CameraSpec{}.skybox;  // not the default, so a dropped field shows
  t.board.robot = 0;
  t.board.X_FT = random_transform();
  t.board.square_m = 0.0123456789;
  t.tracker.present = true;
  t.tracker.X_WT = random_transform();
  t.tracker.p_FR = Vector3(u(rng), u(rng), u(rng));
  t.tracker.drift_m_per_s = Vector3(u(rng), u(rng), u(rng)) * 1e-9;

  bpb::TwinTruth message;
  ToProto(t, &message);
  const TwinTruth b = FromProto(message);
  const auto same = [](const Transform& x, const Transform& y) {
    return x.matrix() == y.matrix();
  };
  EXPECT_EQ(b.num_robots, 2);
  for (int r = 0; r < kMaxRobots; ++r) {
    const KinematicModel &x = t.models[r], &y = b.models[r];
    ASSERT_EQ(x.num_links(), y.num_links());
    EXPECT_EQ(x.name, y.name);
    EXPECT_TRUE(same(x.X_BL0, y.X_BL0) && same(x.X_LtE, y.X_LtE));
    for (int i = 0; i < x.num_links(); ++i) {
      const Link &p = x.links[i], &q = y.links[i];
      EXPECT_EQ(p.dh.theta_offset, q.dh.theta_offset);
      EXPECT_EQ(p.dh.d, q.dh.d);
      EXPECT_EQ(p.dh.a, q.dh.a);
      EXPECT_EQ(p.dh.alpha, q.dh.alpha);
      EXPECT_EQ(p.dh.beta, q.dh.beta);
      EXPECT_EQ(p.limits.lower, q.limits.lower);
      EXPECT_EQ(p.limits.upper, q.limits.upper);
      EXPECT_EQ(p.inertia.mass, q.inertia.mass);
      EXPECT_EQ(p.inertia.p_LiCom, q.inertia.p_LiCom);
      EXPECT_EQ(p.inertia.I_Com, q.inertia.I_Com);
      EXPECT_EQ(p.joint_name, q.joint_name);
    }
    EXPECT_EQ(t.length_scale[r], b.length_scale[r]);
    EXPECT_TRUE(same(t.X_WB[r], b.X_WB[r]) && same(t.X_WF[r], b.X_WF[r]));
    EXPECT_TRUE(same(t.X_FTip[r], b.X_FTip[r]));
    EXPECT_EQ(t.q_link[r], b.q_link[r]);
    EXPECT_EQ(t.q_motor[r], b.q_motor[r]);
    EXPECT_EQ(t.p_WTip[r], b.p_WTip[r]);
  }
  EXPECT_EQ(t.time_s, b.time_s);
  EXPECT_TRUE(same(t.X_WC, b.X_WC) && same(t.X_WT, b.X_WT));
  EXPECT_EQ(b.camera.robot, 1);
  EXPECT_TRUE(same(t.camera.X_FC, b.camera.X_FC));
  EXPECT_EQ(t.camera.intrinsics.fx, b.camera.intrinsics.fx);
  EXPECT_EQ(t.camera.distortion.k1, b.camera.distortion.k1);
  EXPECT_EQ(b.camera.msaa_samples, 2);
  EXPECT_EQ(b.camera.skybox, t.camera.skybox);
  EXPECT_EQ(b.board.robot, 0);
  EXPECT_TRUE(same(t.board.X_FT, b.board.X_FT));
  EXPECT_EQ(t.board.square_m, b.board.square_m);
  EXPECT_TRUE(b.tracker.present);
  EXPECT_TRUE(same(t.tracker.X_WT, b.tracker.X_WT));
  EXPECT_EQ(t.tracker.p_FR, b.tracker.p_FR);
  EXPECT_EQ(t.tracker.drift_m_per_s, b.tracker.drift_m_per_s);

  // A truth from before camera.skybox: its images were rendered with the sky.
  bpb::TwinTruth without_skybox = message;
  without_skybox.mutable_camera()->clear_skybox();
  EXPECT_TRUE(FromProto(without_skybox).camera.skybox);
  without_skybox.mutable_camera()->set_skybox(false);
  EXPECT_FALSE(FromProto(without_skybox).camera.skybox);

  // A truth of the wrong shape is refused.
  bpb::TwinTruth short_of_a_robot = message;
  short_of_a_robot.mutable_models()->RemoveLast();
  EXPECT_THROW(FromProto(short_of_a_robot), ProtocolError);
  bpb::TwinTruth bad_rotation = message;
  bad_rotation.mutable_world_to_camera()->mutable_rotation()->RemoveLast();
  EXPECT_THROW(FromProto(bad_rotation), ProtocolError);
  // A truth from before flange_to_tip (an older serve-cell or recording) is read, with its tips
  // NaN, so that what is scored with them is null rather than wrong; one tip of two is refused.
  bpb::TwinTruth without_tips = message;
  without_tips.clear_flange_to_tip();
  const TwinTruth old = FromProto(without_tips);
  EXPECT_TRUE(std::isnan(old.X_FTip[0].translation().x()));
  EXPECT_TRUE(std::isnan(old.X_FTip[1].translation().z()));
  EXPECT_TRUE(same(t.X_WF[0], old.X_WF[0]));
  bpb::TwinTruth one_tip = message;
  one_tip.mutable_flange_to_tip()->RemoveLast();
  EXPECT_THROW(FromProto(one_tip), ProtocolError);
}

}  // namespace
}  // namespace twin::remote
