// The parameter layout of a robot model (DESIGN.md, convention 8): every parameter's name,
// unit, nominal value, block and observability scale, and the one map between names and the
// flat vector. Order: the geometric block (parameters.h: link-major, theta, d, a, alpha, beta),
// then each error term's block in the model's term order.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "calib/model/robot_model.h"

namespace twin {

/// One parameter of the layout.
struct ParameterInfo {
  std::string name;    ///< e.g. "r1.link3.alpha", "r1.joint2.compliance"
  std::string unit;    ///< SI unit: "m", "rad", "rad/(N m)", "1/K", ...
  std::string block;   ///< "geometry" or the term's label, e.g. "joint_compliance (joint 2)"
  double nominal = 0;  ///< value in the model the layout was made from [SI]
  double scale = 1;    ///< observability column scale (TermParameter::scale; 1 m or 1 rad)
  int term = -1;       ///< index of its term in RobotModel::terms, -1 for geometry
  bool length = false; ///< a geometric length (d, a)
};

/// A contiguous block of the flat vector.
struct ParameterBlock {
  std::string name;  ///< as ParameterInfo::block
  int begin = 0;     ///< first index
  int size = 0;      ///< number of parameters
};

/// The layout of one model. Cheap to copy.
class ParameterLayout {
 public:
  explicit ParameterLayout(const RobotModel& model);

  int size() const { return static_cast<int>(info_.size()); }
  const ParameterInfo& operator[](int i) const { return info_[i]; }
  const std::vector<ParameterInfo>& parameters() const { return info_; }
  const std::vector<ParameterBlock>& blocks() const { return blocks_; }
  /// Size of the geometric block (5 (N + 1)).
  int geometry_size() const { return geometry_size_; }
  /// Index of a name. Precondition: the name is one of this model's (callers build their names
  /// from the layout); else PreconditionError naming it and listing the form of valid names.
  int Find(const std::string& name) const;
  /// All names in flat order.
  std::vector<std::string> names() const;
  /// Column scales for AnalyseObservability, in flat order.
  Eigen::VectorXd scales() const;

 private:
  /// The block names, comma-separated (for Find's message).
  std::string BlockNames() const;

  std::vector<ParameterInfo> info_;
  std::vector<ParameterBlock> blocks_;
  int geometry_size_ = 0;
};

}  // namespace twin
