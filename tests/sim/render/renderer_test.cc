// Rendering accuracy: chessboard corners detected in rendered images against the analytic
// projection of the board's inner corners with the true camera pose and intrinsics.
#include "sim/render/renderer.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib/common/text_format.h"
#include "sim/world/board_mjcf.h"
#include "sim/render/camera_image.h"
#include "sim/world/mujoco_handles.h"

namespace twin {
namespace {

// Detection errors of a rendered board are about 0.05 px RMS (DESIGN.md, measured); 0.1 px
// leaves room for pose-to-pose spread while still catching a half-pixel convention slip
// (0.7 px) or an fx/fy mix-up (several px).
constexpr double kMaxRmsPx = 0.1;
constexpr int kPoses = 50;

std::string Num(double v) { return ShortestNumber(v); }

// The world: a light, a fixed camera whose optical frame is R_WC at p_WC, the board on a mocap
// body. Returns MJCF text.
std::string SceneMjcf(const BoardSpec& board, const Matrix3& R_WC, const Vector3& p_WC,
                      int offwidth, int offheight) {
  const Vector3 x = R_WC.col(0), y = -R_WC.col(1), z = R_WC.col(2);  // MuJoCo: y up, looks -z
  auto v3 = [](const Vector3& v) { return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()); };
  return "<mujoco model=\"render_test\">\n"
         "<visual><global offwidth=\"" + std::to_string(offwidth) + "\" offheight=\"" +
         std::to_string(offheight) + "\"/><quality offsamples=\"4\"/></visual>\n"
         "<asset>\n" + BoardAssetsMjcf(board) + "</asset>\n"
         "<worldbody>\n"
         "<light directional=\"true\" castshadow=\"false\" diffuse=\"0.5 0.5 0.5\" pos=\"" +
         v3(p_WC) + "\" dir=\"" + v3(z) + "\"/>\n"
         "<camera name=\"cam\" pos=\"" + v3(p_WC) + "\" xyaxes=\"" + v3(x) + " " + v3(y) +
         "\"/>\n"
         "<body name=\"board\" mocap=\"true\">\n" + BoardGeomsMjcf(board, "board_") +
         "</body>\n</worldbody>\n</mujoco>\n";
}

struct Scene {
  MjModelPtr model;
  MjDataPtr data;
  int camera = -1;
  int mocap = -1;
  Transform X_WC;  // true camera optical frame, from MuJoCo
};

// A tilted, off-axis camera so that no frame conversion can pass by symmetry.
Scene MakeScene(const BoardSpec& board, int offwidth, int offheight) {
  InstallMujocoErrorHandlers();
  Matrix3 R_look;  // optical z down the world -z, x along world x
  R_look << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Matrix3 R_WC = Eigen::AngleAxisd(0.4, Vector3(1, 2, 3).normalized()) * R_look;
  Scene s;
  s.model = LoadMjcfFromString(SceneMjcf(board, R_WC, Vector3(0.2, -0.1, 1.2), offwidth,
                                         offheight));
  s.data.reset(mj_makeData(s.model.get()));
  s.camera = mj_name2id(s.model.get(), mjOBJ_CAMERA, "cam");
  s.mocap = s.model->body_mocapid[mj_name2id(s.model.get(), mjOBJ_BODY, "board")];
  mj_forward(s.model.get(), s.data.get());
  // MuJoCo camera frame (x right, y up, looking along -z) to the optical frame (y down, z fwd).
  Matrix3 R_mj;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R_mj(r, c) = s.data->cam_xmat[9 * s.camera + 3 * r + c];
  }
  s.X_WC.setIdentity();
  s.X_WC.linear() = R_mj * Vector3(1, -1, -1).asDiagonal();
  s.X_WC.translation() = Vector3(s.data->cam_xpos + 3 * s.camera);
  return s;
}

void PlaceBoard(Scene* s, const Transform& X_CT) {
  const Transform X_WT = s->X_WC * X_CT;
  const Eigen::Quaterniond q(X_WT.rotation());
  for (int i = 0; i < 3; ++i) s->data->mocap_pos[3 * s->mocap + i] = X_WT.translation()[i];
  const double wxyz[4] = {q.w(), q.x(), q.y(), q.z()};
  for (int i = 0; i < 4; ++i) s->data->mocap_quat[4 * s->mocap + i] = wxyz[i];
  mj_forward(s->model.get(), s->data.get());
}

std::vector<cv::Point2d> Project(const Intrinsics& K, const Transform& X_CT,
                                 const std::vector<Vector3>& p_T) {
  std::vector<cv::Point2d> uv;
  for (const Vector3& p : p_T) {
    const Vector3 c = X_CT * p;
    uv.emplace_back(K.fx * c.x() / c.z() + K.cx, K.fy * c.y() / c.z() + K.cy);
  }
  return uv;
}

// The board's outline (a square beyond the squares on every side: covers margin and strips).
std::vector<Vector3> Outline(const BoardSpec& b) {
  const double m = std::max(b.margin_m, b.square_m);
  const double x0 = -(b.squares_x / 2) * b.square_m - m;
  const double x1 = (b.squares_x - b.squares_x / 2) * b.square_m + m;
  const double y0 = -(b.squares_y / 2) * b.square_m - m;
  const double y1 = (b.squares_y - b.squares_y / 2) * b.square_m + m;
  return {Vector3(x0, y0, 0), Vector3(x1, y0, 0), Vector3(x1, y1, 0), Vector3(x0, y1, 0)};
}

// A board pose 0.3-0.6 m in front of the camera, tilted up to 30 deg about a random axis in
// its plane, any rotation about its normal, fully in view with 10 px to spare.
Transform RandomBoardPose(std::mt19937* rng, const Intrinsics& K, const BoardSpec& board) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (;;) {
    const double depth = 0.3 + 0.3 * unit(*rng);
    const double tilt = DegToRad(30) * unit(*rng);
    const double axis_angle = 2 * kPi * unit(*rng);
    const double spin = 2 * kPi * unit(*rng);
    const Vector3 u((unit(*rng) * K.width - K.cx) / K.fx, (unit(*rng) * K.height - K.cy) / K.fy,
                    1);
    Transform X_CT = Transform::Identity();
    X_CT.linear() = Matrix3(Eigen::AngleAxisd(kPi, Vector3::UnitX())) *  // face the camera
                    Eigen::AngleAxisd(tilt, Vector3(std::cos(axis_angle),
                                                    std::sin(axis_angle), 0)) *
                    Eigen::AngleAxisd(spin, Vector3::UnitZ());
    X_CT.translation() = depth * u;
    bool inside = true;
    for (const cv::Point2d& p : Project(K, X_CT, Outline(board))) {
      inside = inside && p.x > 10 && p.y > 10 && p.x < K.width - 11 && p.y < K.height - 11;
    }
    if (inside) return X_CT;
  }
}

// findChessboardCorners + cornerSubPix (DESIGN.md: SB mislocks on a 4x4 board).
bool Detect(const cv::Mat& bgr, const BoardSpec& board, std::vector<cv::Point2f>* corners) {
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  const cv::Size pattern(board.squares_x - 1, board.squares_y - 1);
  if (!cv::findChessboardCorners(gray, pattern, *corners,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    return false;
  }
  // 11 x 11 window: smaller than a square at 0.6 m and 30 deg tilt (about 24 px).
  cv::cornerSubPix(gray, *corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 100, 1e-4));
  return true;
}

struct ErrorStats {
  double sum_sq = 0, max = 0;
  int n = 0, poses = 0, missed = 0;
  // The least-squares scale s of detected - projected = s (projected - principal point): how
  // much larger the rendered picture is than K says (a focal-length error of the twin).
  double radial_num = 0, radial_den = 0;
  double Rms() const { return n ? std::sqrt(sum_sq / n) : 0.0; }
  double Scale() const { return radial_den > 0 ? radial_num / radial_den : 0.0; }
  void Print(const char* what) const {
    std::printf("[ measured ] %s: RMS %.4f px, max %.4f px over %d corners in %d poses "
                "(%d not detected)\n", what, Rms(), max, n, poses, missed);
  }
};

// Matches each detected corner to its nearest projected one (OpenCV's order is not the
// board's) and accumulates the distances; the match must be one-to-one and within 2 px.
void AddMatched(const std::vector<cv::Point2d>& detected,
                const std::vector<cv::Point2d>& projected, const cv::Point2d& centre,
                ErrorStats* stats) {
  ASSERT_EQ(detected.size(), projected.size());
  std::vector<bool> used(projected.size(), false);
  for (const cv::Point2d& d : detected) {
    size_t best = 0;
    for (size_t j = 1; j < projected.size(); ++j) {
      if (cv::norm(projected[j] - d) < cv::norm(projected[best] - d)) best = j;
    }
    const double e = cv::norm(projected[best] - d);
    EXPECT_FALSE(used[best]) << "two detections share a corner";
    EXPECT_LT(e, 2.0) << "detection far from every projected corner";  // squares are >20 px
    used[best] = true;
    const cv::Point2d r = projected[best] - centre;
    stats->radial_num += (d - projected[best]).dot(r);
    stats->radial_den += r.dot(r);
    stats->sum_sq += e * e;
    stats->max = std::max(stats->max, e);
    ++stats->n;
  }
}

// Renders `board` at one pose and adds its corner errors: ideal pinhole K, or, with `mapper`,
// a distorted image whose detections are undistorted with K and D before comparing.
void MeasurePose(Scene* scene, OffscreenRenderer* renderer, const BoardSpec& board,
                 const Intrinsics& K, const Transform& X_CT, const DistortionMapper* mapper,
                 const Distortion& D, ErrorStats* stats, const char* save_as = nullptr) {
  PlaceBoard(scene, X_CT);
  cv::Mat image = renderer->RenderPinhole(scene->model.get(), scene->data.get(), scene->camera,
                                          mapper ? mapper->canvas() : K);
  if (mapper) image = mapper->Apply(image);
  if (save_as) cv::imwrite(save_as, image);
  ++stats->poses;
  std::vector<cv::Point2f> found;
  if (!Detect(image, board, &found)) {
    ++stats->missed;
    return;
  }
  std::vector<cv::Point2d> detected(found.begin(), found.end());
  if (mapper) {
    const cv::Matx33d Km(K.fx, 0, K.cx, 0, K.fy, K.cy, 0, 0, 1);
    const cv::Vec<double, 5> Dv(D.k1, D.k2, D.p1, D.p2, D.k3);
    // undistortPoints stops after 5 fixed-point iterations (about 0.05 px off at the image
    // corners for k1 = -0.12); iterate to convergence instead.
    cv::undistortPoints(std::vector<cv::Point2d>(detected), detected, Km, Dv, cv::noArray(), Km,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100,
                                         1e-12));
  }
  AddMatched(detected, Project(K, X_CT, BoardInnerCorners(board)), cv::Point2d(K.cx, K.cy),
             stats);
}

ErrorStats MeasureRandomPoses(const Intrinsics& K, const BoardSpec& board, int poses,
                              unsigned seed, const Distortion& D = Distortion(),
                              const char* save_first_as = nullptr) {
  const DistortionMapper mapper(K, D);
  const Intrinsics& canvas = mapper.canvas();
  Scene scene = MakeScene(board, canvas.width, canvas.height);
  OffscreenRenderer renderer(scene.model.get(), canvas.width, canvas.height, 4);
  renderer.SetClipPlanes(0.02, 5.0);
  std::mt19937 rng(seed);
  ErrorStats stats;
  for (int i = 0; i < poses; ++i) {
    MeasurePose(&scene, &renderer, board, K, RandomBoardPose(&rng, K, board),
                D.Any() ? &mapper : nullptr, D, &stats, i == 0 ? save_first_as : nullptr);
  }
  EXPECT_EQ(WarningCount(scene.data.get()), 0);
  return stats;
}

Intrinsics PaperIntrinsics() { return Intrinsics(); }  // Zhu et al. 2019, VI.A

// Strongly anisotropic, off-centre: an fx/fy swap or a wrong principal point shows at once.
Intrinsics AnisotropicIntrinsics() {
  Intrinsics K;
  K.fx = 850;
  K.fy = 820;
  K.cx = 530.3;
  K.cy = 390.7;
  return K;
}

TEST(OffscreenRenderer, PaperIntrinsicsMatchAnalyticProjection) {
  // TWIN_RENDER_TEST_IMAGE=/tmp/board_view.png saves the first view for a look.
  const ErrorStats s = MeasureRandomPoses(PaperIntrinsics(), BoardSpec(), kPoses, 11,
                                          Distortion(), std::getenv("TWIN_RENDER_TEST_IMAGE"));
  s.Print("paper intrinsics, 4x4 board");
  EXPECT_EQ(s.missed, 0);  // the board is fully in view and at most 30 deg tilted
  EXPECT_LE(s.Rms(), kMaxRmsPx);
}

TEST(OffscreenRenderer, AnisotropicOffCentreIntrinsicsMatchAnalyticProjection) {
  const ErrorStats s = MeasureRandomPoses(AnisotropicIntrinsics(), BoardSpec(), kPoses, 12);
  s.Print("fx 850, fy 820, cx 530.3, cy 390.7, 4x4 board");
  EXPECT_EQ(s.missed, 0);
  EXPECT_LE(s.Rms(), kMaxRmsPx);
}

TEST(OffscreenRenderer, DistortedImageUndistortsToAnalyticProjection) {
  Distortion D;
  D.k1 = -0.12;
  D.k2 = 0.05;
  D.p1 = 0.0005;
  D.p2 = -0.0003;
  const ErrorStats s = MeasureRandomPoses(PaperIntrinsics(), BoardSpec(), kPoses, 13, D);
  s.Print("paper intrinsics with distortion, 4x4 board");
  EXPECT_EQ(s.missed, 0);
  // Same budget as without distortion: the remap adds interpolation blur, not bias.
  EXPECT_LE(s.Rms(), kMaxRmsPx);
}

// The rendered picture has the scale K says: a twin whose images were 1e-4 larger than its
// true fx would bias every depth the estimator measures by as much. Detected corners of a
// 10 x 8 target of 12 mm squares (63 corners per view over much of the image) against the
// analytic projection, fitted as detected - projected = s (projected - principal point). The
// bound: 3e-5 is a tenth of the fx errors Zhang's method showed on the twin (1e-4..3.5e-4),
// so a scale error of the twin that size would be seen, and it is 4x above the fit's own
// spread (0.05 px RMS corner errors over ~3000 corners at ~250 px radius: about 1e-5 per
// 50 poses when the errors are independent).
TEST(OffscreenRenderer, RenderedPictureHasTheScaleOfK) {
  BoardSpec target;
  target.squares_x = 10;
  target.squares_y = 8;
  target.square_m = 0.012;
  for (const Intrinsics& K : {PaperIntrinsics(), AnisotropicIntrinsics()}) {
    const ErrorStats s = MeasureRandomPoses(K, target, kPoses, 31);
    s.Print("10x8 target");
    std::printf("[ measured ] radial scale of the detections: %.2e\n", s.Scale());
    EXPECT_EQ(s.missed, 0);
    EXPECT_LT(std::abs(s.Scale()), 3e-5);
  }
}

TEST(OffscreenRenderer, OddAndNonSquareBoards) {
  for (const auto& [nx, ny] : {std::pair{5, 4}, std::pair{4, 5}, std::pair{5, 5}}) {
    BoardSpec board;
    board.squares_x = nx;
    board.squares_y = ny;
    const ErrorStats s = MeasureRandomPoses(AnisotropicIntrinsics(), board, 10, 20 + nx * ny);
    s.Print((std::to_string(nx) + "x" + std::to_string(ny) + " board").c_str());
    EXPECT_EQ(s.missed, 0);
    EXPECT_LE(s.Rms(), kMaxRmsPx);
  }
}

// Grey level of the rendered image at board point p_T.
int GreyAt(const cv::Mat& bgr, const Intrinsics& K, const Transform& X_CT, const Vector3& p_T) {
  const cv::Point2d uv = Project(K, X_CT, {p_T})[0];
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  return gray.at<unsigned char>(cvRound(uv.y), cvRound(uv.x));
}

// The documented layout: the (-x, -y) corner square is black, its neighbours white, a white
// border all round, and the extra print column/row of an odd count hidden.
TEST(OffscreenRenderer, BoardLayoutMatchesDocumentation) {
  for (const auto& [nx, ny] : {std::pair{4, 4}, std::pair{5, 4}, std::pair{4, 5},
                               std::pair{5, 5}, std::pair{6, 3}}) {
    SCOPED_TRACE(std::to_string(nx) + "x" + std::to_string(ny));
    BoardSpec b;
    b.squares_x = nx;
    b.squares_y = ny;
    const Intrinsics K = PaperIntrinsics();
    Scene scene = MakeScene(b, K.width, K.height);
    OffscreenRenderer renderer(scene.model.get(), K.width, K.height, 4);
    Transform X_CT = Transform::Identity();
    X_CT.linear() = Matrix3(Eigen::AngleAxisd(kPi, Vector3::UnitX()));
    X_CT.translation() = Vector3(0, 0, 0.4);
    PlaceBoard(&scene, X_CT);
    const cv::Mat image = renderer.RenderPinhole(scene.model.get(), scene.data.get(),
                                                 scene.camera, K);
    const double s = b.square_m, x0 = -(nx / 2) * s, y0 = -(ny / 2) * s;
    const double x1 = x0 + nx * s, y1 = y0 + ny * s, m = b.margin_m / 2;
    auto grey = [&](double x, double y) { return GreyAt(image, K, X_CT, Vector3(x, y, 0)); };
    // Lit white is above 150 and black below 60 (ambient + diffuse; black reflects nothing).
    EXPECT_LT(grey(x0 + s / 2, y0 + s / 2), 60);
    EXPECT_GT(grey(x0 + 1.5 * s, y0 + s / 2), 150);
    EXPECT_GT(grey(x0 + s / 2, y0 + 1.5 * s), 150);
    EXPECT_EQ(grey(x1 - s / 2, y0 + s / 2) < 60, nx % 2 == 1);  // square (nx-1, 0)
    EXPECT_EQ(grey(x0 + s / 2, y1 - s / 2) < 60, ny % 2 == 1);  // square (0, ny-1)
    EXPECT_EQ(grey(x1 - s / 2, y1 - s / 2) < 60, (nx + ny) % 2 == 0);
    for (double t : {0.25, 0.5, 0.75}) {  // white border on all four sides
      EXPECT_GT(grey(x0 - m, y0 + t * (y1 - y0)), 150);
      EXPECT_GT(grey(x1 + m, y0 + t * (y1 - y0)), 150);
      EXPECT_GT(grey(x0 + t * (x1 - x0), y0 - m), 150);
      EXPECT_GT(grey(x0 + t * (x1 - x0), y1 + m), 150);
      // An odd count's extra print column / row is covered white.
      if (nx % 2 == 1) {
        EXPECT_GT(grey(x1 + s / 2, y0 + t * (y1 - y0)), 150);
      }
      if (ny % 2 == 1) {
        EXPECT_GT(grey(x0 + t * (x1 - x0), y1 + s / 2), 150);
      }
    }
    EXPECT_EQ(WarningCount(scene.data.get()), 0);
  }
}

// Two renderers in one process, different models and sizes, called alternately.
TEST(OffscreenRenderer, TwoRenderersAlternate) {
  const Intrinsics Ka = PaperIntrinsics();
  Intrinsics Kb = AnisotropicIntrinsics();
  Kb.width = 800;
  Kb.height = 600;
  Kb.cx = 410.2;
  Kb.cy = 290.9;
  BoardSpec board_b;
  board_b.squares_x = 5;
  Scene a = MakeScene(BoardSpec(), Ka.width, Ka.height);
  OffscreenRenderer ra(a.model.get(), Ka.width, Ka.height, 4);
  Scene b = MakeScene(board_b, Kb.width, Kb.height);
  OffscreenRenderer rb(b.model.get(), Kb.width, Kb.height, 4);
  std::mt19937 rng(31);
  ErrorStats sa, sb;
  for (int i = 0; i < 10; ++i) {
    MeasurePose(&a, &ra, BoardSpec(), Ka, RandomBoardPose(&rng, Ka, BoardSpec()), nullptr,
                Distortion(), &sa);
    MeasurePose(&b, &rb, board_b, Kb, RandomBoardPose(&rng, Kb, board_b), nullptr,
                Distortion(), &sb);
  }
  sa.Print("renderer A of two (1024x768)");
  sb.Print("renderer B of two (800x600, 5x4 board)");
  EXPECT_EQ(sa.missed + sb.missed, 0);
  EXPECT_LE(sa.Rms(), kMaxRmsPx);
  EXPECT_LE(sb.Rms(), kMaxRmsPx);
  EXPECT_EQ(WarningCount(a.data.get()) + WarningCount(b.data.get()), 0);
}

TEST(OffscreenRenderer, FreeAndBareRenders) {
  const Intrinsics K = PaperIntrinsics();
  Scene scene = MakeScene(BoardSpec(), 320, 240);
  OffscreenRenderer renderer(scene.model.get(), 320, 240, 0);
  EXPECT_EQ(renderer.width(), 320);
  EXPECT_EQ(renderer.height(), 240);
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.lookat[0] = 0.2;
  cam.lookat[1] = -0.1;
  cam.lookat[2] = 0.8;
  cam.distance = 1.5;
  const cv::Mat free = renderer.RenderFree(scene.model.get(), scene.data.get(), cam);
  EXPECT_EQ(free.size(), cv::Size(320, 240));
  EXPECT_EQ(free.type(), CV_8UC3);
  renderer.RenderBare(scene.model.get(), scene.data.get(), scene.camera);
  EXPECT_THROW(renderer.RenderPinhole(scene.model.get(), scene.data.get(), scene.camera, K),
               std::invalid_argument);  // K is 1024x768, the renderer 320x240
  EXPECT_THROW(renderer.SetClipPlanes(0.5, 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace twin
