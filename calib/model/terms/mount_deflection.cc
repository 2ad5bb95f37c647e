#include "calib/model/terms/terms.h"

namespace twin::terms {
namespace {

// Deflection of the tool or target mount under gravity (a compliant bracket):
//   dp_F += D g_F,  g_F = R_BF^T g_B
// the end point moves in the flange frame F by the diagonal compliance D = diag(d_x, d_y, d_z)
// [m] times the unit gravity direction expressed in F: d_x is how far the point sags along x_F
// when gravity points along +x_F. It needs no context: the flange's orientation follows from
// the configuration. (The tool's orientation is not changed: point measurements do not see it.)
class MountDeflection : public ErrorTermT<MountDeflection> {
 public:
  using ErrorTermT::ErrorTermT;
  bool offsets_tool() const override { return true; }

  template <typename T>
  void OffsetToolT(const T* p, const Mat3T<T>& R_BF, const Vector3& g_B, Vec3T<T>* dp_F) const {
    const Vec3T<T> g_F = R_BF.transpose() * g_B.cast<T>();
    for (int k = 0; k < 3; ++k) (*dp_F)(k) += p[k] * g_F(k);
  }
};

}  // namespace

std::shared_ptr<const ErrorTerm> MakeMountDeflection(const TermInput& in) {
  const std::string prefix = in.robot + ".mount.deflection_";
  return std::make_shared<MountDeflection>(
      in.spec, std::vector<TermParameter>{
                   {prefix + "x", "m", 1.0}, {prefix + "y", "m", 1.0}, {prefix + "z", "m", 1.0}});
}

}  // namespace twin::terms
