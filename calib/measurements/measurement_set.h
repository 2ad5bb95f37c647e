// A set of measurements of one kind, as the identification engine (calib/identification/
// engine.h) sees it: it adds its residual blocks and its nuisance parameters (what the
// measurement needs besides the robot model: the lines of optical axes, a tracker's pose) to a
// Ceres problem, names the parameter directions it can never see, and groups its residuals for
// the estimation of their weights. One kind per file: optical_axis_set.h, tracker_set.h.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "calib/model/parameter_layout.h"
#include "calib/model/robot_model.h"

namespace twin {

/// A nuisance parameter block of a set (owned by the set).
struct NuisanceBlock {
  double* data = nullptr;  ///< the block's values
  int size = 0;            ///< ambient size
  int tangent_size = 0;    ///< tangent size (its manifold's, else its size)
  std::string name;        ///< for reports, e.g. "axis 3 direction", "tracker rotation"
};

/// Residuals that share one noise level (variance component): their weight is 1 / sigma, and
/// the engine may re-estimate sigma from their sum of squares after a first solve.
struct ResidualGroup {
  std::string name;                           ///< e.g. "perpendicular", "depth", "tracker"
  std::vector<ceres::ResidualBlockId> blocks; ///< the residual blocks holding the group's rows
  int first_row = 0;                          ///< its rows in each block: first_row ..
  int num_rows = -1;                          ///< .. first_row + num_rows - 1 (-1: to the end)
  double* weight = nullptr;                   ///< 1 / sigma [1/m], read by the group's functors
  /// Degrees of freedom of the group: its independent residual rows minus the nuisance
  /// parameters it alone determines (the model's are shared and neglected).
  int redundancy = 0;
};

/// The interface of a measurement set.
class MeasurementSet {
 public:
  virtual ~MeasurementSet() = default;
  /// Kind of measurement, e.g. "optical_axis", "tracker_point".
  virtual std::string kind() const = 0;
  /// Number of measurements (samples or points).
  virtual int size() const = 0;
  /// Throws InputError naming the measurement when it does not fit `model` (joint counts, a
  /// context an error term needs, too few measurements).
  virtual void Validate(const RobotModel& model) const = 0;
  /// Starting values of the nuisance parameters for `model`.
  virtual void Initialize(const RobotModel& model) = 0;
  /// Adds the residual blocks (and the nuisance blocks' manifolds) to `problem`; `params` is the
  /// model's flat parameter vector the residuals read (ParameterLayout order).
  virtual void AddResiduals(const RobotModel& model, double* params, ceres::Problem* problem) = 0;
  /// The nuisance blocks added by AddResiduals.
  virtual std::vector<NuisanceBlock> nuisance() = 0;
  /// The residual groups added by AddResiduals.
  virtual std::vector<ResidualGroup> groups() = 0;
  /// Directions of the model's parameter space (SI, flat order of `layout`) this kind of
  /// measurement can never see at all, which noisy data would otherwise give a small non-zero
  /// singular value (e.g. a uniform scale for lines without depth).
  virtual std::vector<Eigen::VectorXd> Invariants(const RobotModel& model,
                                                  const ParameterLayout& layout) const = 0;
  /// RMS of the unweighted residuals of each measurement at the current nuisance values for
  /// `model` [m] (one entry per measurement; for a multi-row residual, the norm).
  virtual std::vector<double> ResidualNorms(const RobotModel& model) const = 0;
};

}  // namespace twin
