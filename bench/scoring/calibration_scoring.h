// Scoring of an optical-axis calibration against the twin's truth, after the procedure ended
// (the only place estimates meet truth, DESIGN.md). Feature-point position errors over random
// joint configurations in three gauges: raw; after the best rigid transform (what a base-frame
// calibration would absorb); after the best similarity transform (additionally the uniform
// scale that the collinearity constraint alone cannot see).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calib/kinematics/kinematic_model.h"
#include "calib/identification/observability.h"

namespace twin {

/// RMS and largest feature-point position error [m].
struct PositionErrorStats {
  double rms = 0.0;
  double max = 0.0;
};

/// Position errors of one model against the truth in the three gauges.
struct GaugeErrors {
  PositionErrorStats raw, rigid, similarity;
};

/// One parameter's deviation from nominal: identified and true [m or rad].
struct ParameterComparison {
  std::string name;
  bool length = false;
  double estimated = 0.0;
  double truth = 0.0;
};

/// Truth scores of one robot.
struct RobotScore {
  int configurations = 0;
  GaugeErrors before, after;     ///< nominal / identified model against truth
  double scale_estimated = 1.0;  ///< similarity scale identified / nominal positions [-]
  double scale_true = 1.0;       ///< similarity scale true / nominal positions [-]
  std::vector<ParameterComparison> parameters;
  /// Identifiable combinations (coordinates in the identifiable basis, scaled units: m for a
  /// 1 m characteristic length, rad; each basis vector signed so that its largest entry is
  /// positive): identified, true, and their differences.
  std::vector<double> combination_estimated, combination_true;
  double combination_rms_error = 0.0, combination_max_error = 0.0;
};

/// Scores `identified` and `nominal` (passive-robot models with the board as link 7) against
/// `truth` over `configurations` joint vectors drawn uniformly inside the joint limits less
/// 10 deg (seeded). `observability` is the identification's (for the combinations).
/// `n` joint vectors drawn uniformly inside `model`'s limits less `margin` [rad] per side,
/// from a std::mt19937_64 seeded with `seed` (joint by joint, configuration by
/// configuration): the configurations of the truth metrics.
std::vector<JointVector> RandomJointConfigurations(const KinematicModel& model, int n,
                                                   std::uint64_t seed, double margin);

/// The joint-space region a calibration covered: per joint the smallest and largest angle
/// over its poses [rad].
struct JointBox {
  JointVector lower, upper;
};

/// The per-joint bounding box of `poses` (at least one; all of one arm's joint count).
JointBox CoveredJointBox(const std::vector<JointVector>& poses);

/// `n` joint vectors drawn uniformly inside `box` (seeded as RandomJointConfigurations).
std::vector<JointVector> RandomJointConfigurationsIn(const JointBox& box, int n,
                                                     std::uint64_t seed);

/// Position errors of `nominal` and `identified` against `truth` over `n` configurations drawn
/// inside `box` (the region the calibration poses covered), in the three gauges, each gauge
/// fitted over these configurations alone.
struct RegionScore {
  int configurations = 0;
  GaugeErrors before, after;
};
RegionScore ScoreRegion(const KinematicModel& nominal, const KinematicModel& identified,
                        const KinematicModel& truth, const JointBox& box, int n,
                        std::uint64_t seed);

RobotScore ScoreRobot(const KinematicModel& nominal, const KinematicModel& identified,
                      const KinematicModel& truth, const ObservabilityReport& observability,
                      int configurations, std::uint64_t seed);

/// The estimates alone, for a cell without truth (a real cell): the parameters' and the
/// identifiable combinations' estimates and the estimated scale as ScoreRobot gives them, and
/// NaN for every figure against truth (the gauges, the true values, their differences).
RobotScore EstimatesWithoutTruth(const KinematicModel& nominal, const KinematicModel& identified,
                                 const ObservabilityReport& observability, int configurations,
                                 std::uint64_t seed);

/// Errors after the best rigid (with_scale false) or similarity transform mapping `model`
/// points onto `truth` points (Umeyama), and raw; also returns the fitted scale.
GaugeErrors CompareInGauges(const std::vector<Vector3>& model, const std::vector<Vector3>& truth,
                            double* similarity_scale = nullptr);

}  // namespace twin
