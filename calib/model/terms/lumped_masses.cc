// Lumped masses (terms.h): where a chain without mass properties carries its weight.
#include <cmath>

#include "calib/model/terms/terms.h"

namespace twin::terms {

bool HasMasses(const KinematicModel& nominal) {
  for (const Link& l : nominal.links) {
    if (l.inertia.mass > 0.0) return true;
  }
  return false;
}

// The weight beyond a joint is lumped at frame origins along the chain, from the end point
// inwards, keeping a point only when it lies at least kLumpSpacing of the arm's reach (measured
// along the chain, sum of sqrt(d^2 + a^2) of the links between) from the last point kept: two
// masses closer than that move almost together and the data cannot tell their weights apart.
// A six-axis arm then gets three lumps beyond its shoulder: the elbow, the wrist, the tool.
constexpr double kLumpSpacing = 0.1;

Lumps LumpsBeyond(const KinematicModel& nominal, int joint) {
  const int n = nominal.num_joints();
  const double spacing = kLumpSpacing * NominalReach(nominal);
  Lumps lumps;
  lumps.points.push_back(n + 2);
  lumps.names.push_back("end");
  // From the end point to the tool link's frame: X_LtE's offset.
  double along = nominal.X_LtE.translation().norm();
  // Frame X_BL[k] (k = 1..N+1) is the far end of link k-1; link k's d and a lead to X_BL[k+1].
  for (int k = n + 1; k >= joint + 1; --k) {
    if (along >= spacing) {
      lumps.points.push_back(k);
      lumps.names.push_back(nominal.links[k - 1].name);
      along = 0.0;
    }
    const DhParameters& dh = nominal.links[k - 1].dh;
    along += std::hypot(dh.d, dh.a);
  }
  return lumps;
}

}  // namespace twin::terms
