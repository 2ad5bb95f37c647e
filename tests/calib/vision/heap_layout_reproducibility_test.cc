// Study trials must reproduce bit for bit: a Slurm shard's record must equal the local study's
// (tests/slurm/slurm_study_test.sh). cv::calibrateCamera calls BLAS / LAPACK, and with ATLAS
// (Debian's preferred libblas.so.3 / liblapack.so.3 once libceres3 pulls libatlas3-base in)
// its result depends on where its buffers lie in memory. Measured on study_small trial 4: the
// heap layout the planner's threads leave behind moved the estimated cy by 5.6e-7 px from run
// to run, and the identification then took 31 or 36 iterations and differed in the 3rd digit
// of an ill-determined combination. The build links the reference BLAS / LAPACK by DT_RPATH
// (cmake/ReferenceBlas.cmake); this test checks that the process really gets results that do
// not depend on the memory layout. Under ATLAS it fails (216 of 216 comparisons differed in a
// run with LD_LIBRARY_PATH left alone before the fix; none with the reference libraries).
//
// The corners are the ones the intrinsics stage detected in that trial's rendered images (12
// views of a 3 x 3 inner-corner board, 0.02 m squares), written out as hex floats: the
// rendering and detection are not under test here, the numerical library is. A synthetic
// board of 9 x 6 corners in 8 well-spread views did not show the effect.
#include <alloca.h>

#include <cstddef>
#include <memory>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace twin {
namespace {

const std::vector<std::vector<cv::Point2f>> kTrialCorners = {
    {{0x1.b77c3cp+7f, 0x1.e8d994p+7f}, {0x1.c4f132p+7f, 0x1.18384ep+8f}, {0x1.d2aa24p+7f, 0x1.3cd60ep+8f}, {0x1.8fb16p+7f, 0x1.fcbe2p+7f}, {0x1.9c0a9p+7f, 0x1.209894p+8f}, {0x1.a8a8d2p+7f, 0x1.43ac4ep+8f}, {0x1.6b5ac2p+7f, 0x1.0771e2p+8f}, {0x1.76ca08p+7f, 0x1.285084p+8f}, {0x1.826a1cp+7f, 0x1.49ea3cp+8f}},
    {{0x1.b36b7ap+7f, 0x1.4d53eep+7f}, {0x1.e88522p+7f, 0x1.4ef5bcp+7f}, {0x1.0ed53p+8f, 0x1.50476cp+7f}, {0x1.bade3cp+7f, 0x1.7b0734p+7f}, {0x1.ee3a0ep+7f, 0x1.7cb7f2p+7f}, {0x1.10d95cp+8f, 0x1.7defb2p+7f}, {0x1.c1adbap+7f, 0x1.a5d0c6p+7f}, {0x1.f365e4p+7f, 0x1.a73f18p+7f}, {0x1.12bcb6p+8f, 0x1.a8fd8cp+7f}},
    {{0x1.9a3c52p+8f, 0x1.a413e2p+7f}, {0x1.b18544p+8f, 0x1.ab05cap+7f}, {0x1.c7ea86p+8f, 0x1.b1aac6p+7f}, {0x1.942d3p+8f, 0x1.d962ecp+7f}, {0x1.ab565p+8f, 0x1.df4abap+7f}, {0x1.c199b6p+8f, 0x1.e4f81ep+7f}, {0x1.8e3c38p+8f, 0x1.06c91ep+8f}, {0x1.a5417cp+8f, 0x1.094698p+8f}, {0x1.bb6e88p+8f, 0x1.0b904ep+8f}},
    {{0x1.8eb7fap+8f, 0x1.022a06p+8f}, {0x1.a3186cp+8f, 0x1.21558p+8f}, {0x1.b8fbc8p+8f, 0x1.42f6a2p+8f}, {0x1.776682p+8f, 0x1.19ed04p+8f}, {0x1.8a1dd8p+8f, 0x1.38c4c6p+8f}, {0x1.9e2e4ep+8f, 0x1.59d994p+8f}, {0x1.61cb8ep+8f, 0x1.301d9p+8f}, {0x1.731062p+8f, 0x1.4e704p+8f}, {0x1.857d8p+8f, 0x1.6ef0d4p+8f}},
    {{0x1.3faea8p+8f, 0x1.220a42p+7f}, {0x1.649e7ep+8f, 0x1.50e968p+7f}, {0x1.883af2p+8f, 0x1.7e231ep+7f}, {0x1.2dec78p+8f, 0x1.68196cp+7f}, {0x1.547644p+8f, 0x1.9725f8p+7f}, {0x1.797902p+8f, 0x1.c47e84p+7f}, {0x1.1ae01cp+8f, 0x1.b30afcp+7f}, {0x1.432756p+8f, 0x1.e25b2ap+7f}, {0x1.69c0d4p+8f, 0x1.07bb6p+8f}},
    {{0x1.438eap+8f, 0x1.89fd32p+7f}, {0x1.57421ap+8f, 0x1.b6eba2p+7f}, {0x1.69e9fep+8f, 0x1.e196ecp+7f}, {0x1.31d618p+8f, 0x1.b8ab8ep+7f}, {0x1.467938p+8f, 0x1.e570bp+7f}, {0x1.5a0f8p+8f, 0x1.080fb2p+8f}, {0x1.1f4306p+8f, 0x1.e9b678p+7f}, {0x1.34d394p+8f, 0x1.0b3684p+8f}, {0x1.496274p+8f, 0x1.2071dp+8f}},
    {{0x1.28c0e8p+8f, 0x1.ad5e7cp+7f}, {0x1.403a08p+8f, 0x1.c99efp+7f}, {0x1.57f8b2p+8f, 0x1.e6817cp+7f}, {0x1.1ac91cp+8f, 0x1.c72f9ap+7f}, {0x1.331152p+8f, 0x1.e4e898p+7f}, {0x1.4bbc4ap+8f, 0x1.01885cp+8f}, {0x1.0b9cdcp+8f, 0x1.e33472p+7f}, {0x1.24c2e2p+8f, 0x1.01419ap+8f}, {0x1.3e719p+8f, 0x1.11271p+8f}},
    {{0x1.2f074cp+7f, 0x1.f90c74p+6f}, {0x1.664bc2p+7f, 0x1.26e9c4p+7f}, {0x1.990c56p+7f, 0x1.4df432p+7f}, {0x1.2194cep+7f, 0x1.2b3db2p+7f}, {0x1.5b9784p+7f, 0x1.55679ep+7f}, {0x1.90ef6ap+7f, 0x1.7c491ep+7f}, {0x1.12fbp+7f, 0x1.5e67fep+7f}, {0x1.503a4ep+7f, 0x1.882f84p+7f}, {0x1.882b98p+7f, 0x1.ae66c2p+7f}},
    {{0x1.04bc1cp+8f, 0x1.33ae92p+8f}, {0x1.1b185ep+8f, 0x1.3a95cp+8f}, {0x1.2fb4d6p+8f, 0x1.40e9e2p+8f}, {0x1.faa3ep+7f, 0x1.529d48p+8f}, {0x1.143b48p+8f, 0x1.58626p+8f}, {0x1.296902p+8f, 0x1.5d9e44p+8f}, {0x1.eb483ep+7f, 0x1.725e88p+8f}, {0x1.0d35dep+8f, 0x1.76d81p+8f}, {0x1.22de32p+8f, 0x1.7b0fdap+8f}},
    {{0x1.9b3a58p+7f, 0x1.27de02p+8f}, {0x1.da9ef2p+7f, 0x1.257146p+8f}, {0x1.0be802p+8f, 0x1.230f38p+8f}, {0x1.a09aa2p+7f, 0x1.3f4cecp+8f}, {0x1.e2a0eap+7f, 0x1.3c5528p+8f}, {0x1.113f7cp+8f, 0x1.39733ap+8f}, {0x1.a65e18p+7f, 0x1.58e132p+8f}, {0x1.eb41dp+7f, 0x1.555b1cp+8f}, {0x1.16f4f6p+8f, 0x1.51e652p+8f}},
    {{0x1.9455e6p+8f, 0x1.34431cp+6f}, {0x1.ad947cp+8f, 0x1.9ed62ap+6f}, {0x1.c5bc84p+8f, 0x1.02d5fp+7f}, {0x1.7ecp+8f, 0x1.a24dacp+6f}, {0x1.98d52ap+8f, 0x1.0626d4p+7f}, {0x1.b1c7cp+8f, 0x1.3911cp+7f}, {0x1.68a0bap+8f, 0x1.09bdd2p+7f}, {0x1.8383fap+8f, 0x1.3e79eap+7f}, {0x1.9d5628p+8f, 0x1.70c5p+7f}},
    {{0x1.63e5c8p+7f, 0x1.a4430cp+7f}, {0x1.a93644p+7f, 0x1.bc094p+7f}, {0x1.ed2e24p+7f, 0x1.d350acp+7f}, {0x1.55cc8p+7f, 0x1.dba492p+7f}, {0x1.98cd66p+7f, 0x1.f24192p+7f}, {0x1.da7a8ep+7f, 0x1.041f8ap+8f}, {0x1.48be04p+7f, 0x1.07b0dep+8f}, {0x1.8956c6p+7f, 0x1.124faep+8f}, {0x1.c904b4p+7f, 0x1.1c9fa4p+8f}},
};

std::vector<cv::Point3f> BoardCorners() {
  std::vector<cv::Point3f> points;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      points.emplace_back(static_cast<float>(c * 0.02 - 0.02), static_cast<float>(r * 0.02 - 0.02),
                          0.0f);
    }
  }
  return points;
}

// The intrinsics stage's call (calib/vision/intrinsics_calibration.cc): k3 held at 0.
std::vector<double> Calibrate(const std::vector<std::vector<cv::Point3f>>& object,
                              const std::vector<std::vector<cv::Point2f>>& image) {
  cv::Mat K, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  const double rms = cv::calibrateCamera(
      object, image, cv::Size(640, 480), K, dist, rvecs, tvecs, cv::CALIB_FIX_K3,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  std::vector<double> out{rms};
  K.convertTo(K, CV_64F);
  dist.convertTo(dist, CV_64F);
  for (int i = 0; i < 9; ++i) out.push_back(K.at<double>(i / 3, i % 3));
  for (int i = 0; i < static_cast<int>(dist.total()); ++i) out.push_back(dist.at<double>(i));
  return out;
}

// Calibrate with the stack pointer moved down by 16 * shift bytes.
__attribute__((noinline)) std::vector<double> CalibrateWithStackShift(
    const std::vector<std::vector<cv::Point3f>>& object,
    const std::vector<std::vector<cv::Point2f>>& image, int shift) {
  volatile char* pad = static_cast<volatile char*>(alloca(16 * static_cast<std::size_t>(shift)));
  pad[0] = 1;
  return Calibrate(object, image);
}

TEST(HeapLayoutReproducibility, CalibrateCameraGivesTheSameBitsWhereverItsBuffersLie) {
  const std::vector<std::vector<cv::Point3f>> object(kTrialCorners.size(), BoardCorners());
  const std::vector<double> first = Calibrate(object, kTrialCorners);
  ASSERT_GT(first.size(), 10u);
  for (int layout = 1; layout <= 24; ++layout) {
    // Hold blocks of odd sizes and free every other one, leaving holes, so that the buffers
    // calibrateCamera allocates start elsewhere; copy the inputs to new addresses too.
    std::vector<std::unique_ptr<char[]>> held;
    for (int i = 0; i < layout; ++i) {
      held.emplace_back(new char[static_cast<std::size_t>(8 * (layout + 3 * i) + 8)]);
      held.back()[0] = static_cast<char>(i);
    }
    for (std::size_t i = 0; i < held.size(); i += 2) held[i].reset();
    const auto object_copy = object;
    const auto image_copy = kTrialCorners;
    const std::vector<double> again = CalibrateWithStackShift(object_copy, image_copy, layout);
    ASSERT_EQ(again.size(), first.size());
    for (std::size_t i = 0; i < first.size(); ++i) {
      // Exact equality on purpose: the property under test is bitwise reproducibility.
      EXPECT_EQ(again[i], first[i]) << "value " << i << " under memory layout " << layout;
    }
  }
}

}  // namespace
}  // namespace twin
