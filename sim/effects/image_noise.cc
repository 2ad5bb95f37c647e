#include "sim/render/camera_image.h"
#include "sim/effects/effects.h"
#include "sim/effects/params.h"

namespace twin::effects {
namespace {

// Sensor noise: every channel of every pixel += N(0, sigma [grey levels]), saturating
// (AddImageNoise), seeded by one draw from the twin's rng per image.
class ImageNoise : public Effect {
 public:
  ImageNoise(const EffectSpec& spec, double sigma) : spec_(spec), sigma_(sigma) {}

  const EffectSpec& spec() const override { return spec_; }

  void ApplyToImage(cv::Mat* image, std::mt19937_64* rng) const override {
    AddImageNoise(image, sigma_, (*rng)());
  }

  bool NeedsCameraAndBoard() const override { return true; }

 private:
  EffectSpec spec_;
  double sigma_;  // [grey levels]
};

}  // namespace

std::unique_ptr<Effect> MakeImageNoise(const EffectSpec& spec) {
  RequireAllRobots(spec, "image noise acts on the camera image, not on a robot");
  RequireAllJoints(spec, "image noise acts on the camera image, not on a joint");
  // At most 64 grey levels: beyond it the noise drowns the board's black-white contrast and
  // nothing can be detected (plausibility limit).
  const Params params(spec, {Required("sigma_levels", kUnitless, PositiveUpTo(64.0))});
  return std::make_unique<ImageNoise>(spec, params.Get("sigma_levels"));
}

}  // namespace twin::effects
