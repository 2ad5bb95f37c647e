// Identification from laser-tracker points with honest held-out scoring (no ground truth
// needed): the model is identified on a training part of the points and scored on the part it
// never saw, before (the nominal model with only the tracker pose and the reflector offset
// fitted) and after (the whole identifiable geometry). Two splits:
//   random: a seeded random fraction of the points is held out;
//   region: the held-out points are those farthest along the measured cloud's principal axis
//           (a workspace region the training points do not cover), or a separate file (from
//           another session: each model's tracker pose is refitted to its points, 6 of their
//           3 n coordinates, before they are scored).
// With a separate file, the nominal and the delivered model are also scored on it as a second
// session: the pose refitted on a random half of it, the other half scored, over seeded
// halvings (calib/diagnosis/session_scoring.h).
// A calibrated model worse than the nominal one on a held-out part is flagged (worse = true)
// and said in the result's warnings, never averaged away. Estimator side: points and the
// nominal model only.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "calib/diagnosis/session_scoring.h"
#include "calib/identification/engine.h"
#include "calib/measurements/tracker_set.h"

namespace twin {

struct TrackerCalibrationOptions {
  double holdout_fraction = 0.2;   ///< part of the points held out by each split, in (0, 0.5]
  std::uint64_t seed = 1;          ///< of the random split
  IdentificationOptions engine;    ///< of every identification
  TrackerSetOptions set;           ///< default sigma, told tracker pose
  /// The halvings of the second session (the validation file): the nominal and the delivered
  /// model are scored on it as well (session_scoring.h).
  SessionScoringOptions session;
};

/// Distance statistics of predicted vs measured points [m].
struct PointErrors {
  int poses = 0;
  double rms = 0, mean = 0, max = 0;
};

/// One split's scores.
struct HeldOutSplit {
  std::string name;        ///< "random" or "region"
  std::string rule;        ///< how the held-out points were chosen, for the report
  int training = 0;        ///< points identified on
  PointErrors before;      ///< held-out, nominal model (tracker pose and reflector fitted)
  PointErrors after;       ///< held-out, identified model
  PointErrors training_after;  ///< the training points, identified model
  bool worse = false;      ///< after.rms > before.rms: the calibration hurts on this part
};

struct TrackerCalibrationResult {
  IdentificationResult identified;  ///< on every point: the delivered model
  Transform X_TB = Transform::Identity();  ///< the tracker pose identified with it
  PointErrors all_before, all_after;  ///< every point, nominal (pose + reflector) and delivered
  std::vector<HeldOutSplit> splits;   ///< random, region
  std::vector<std::string> warnings;  ///< e.g. a held-out part where the calibration is worse
  /// With a validation file (a second session): the nominal model (its reflector offset fitted
  /// on every point, as all_before) and the delivered model scored on it, the tracker pose
  /// refitted on half its poses and the other half scored, over the halvings
  /// (session_scoring.h); empty without one.
  std::optional<SessionScore> session_nominal, session_geometric;
};

/// The parameters "before" keeps free: the reflector offset (the tool link's theta, d, a),
/// the tracker pose being the set's nuisance.
std::vector<std::string> ReflectorParameterNames(const RobotModel& model);

/// Distances between the model's predicted points (through X_TB) and the measured ones.
PointErrors ScorePoints(const RobotModel& model, const Transform& X_TB,
                        const std::vector<TrackerPoint>& points);

/// Identifies `nominal` from `points`, with the random and the region split (the region's
/// held-out points are `validation` when it is not empty). Throws PreconditionError for bad
/// options (bounded where the user's values are read), InputError for too few points for the
/// unknowns (3 coordinates a point against the geometry and the tracker pose) or a failed
/// identification.
TrackerCalibrationResult CalibrateFromTracker(const RobotModel& nominal,
                                              const std::vector<TrackerPoint>& points,
                                              const std::vector<TrackerPoint>& validation,
                                              const TrackerCalibrationOptions& options = {});

}  // namespace twin
