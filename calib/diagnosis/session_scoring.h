// Scores on a second session (issue 39, item 6): a model trained on one tracker session is
// scored on the points of another session of the same arm, whose tracker pose is unknown. Per
// halving, the tracker pose (6 dof, rigid least squares) is fitted on a random half of the
// session's poses and the other half is scored (RMS of the 3-D point distance); the score is
// the mean of that RMS over seeded random halvings, the same halvings for every model, so
// that two models' scores are a paired comparison. The model's geometry and terms stay as
// trained on the first session: only the pose is refitted, on points the score never sees.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "calib/measurements/tracker_set.h"
#include "calib/model/robot_model.h"

namespace twin {

struct SessionScoringOptions {
  int halvings = 20;       ///< random halvings of the session's poses, 1 to 1000
  std::uint64_t seed = 1;  ///< of the halvings (one stream, the same halvings for every model)
};

/// Throws InputError naming the bad field (`where`.halvings).
void ValidateSessionScoringOptions(const SessionScoringOptions& options, const std::string& where);

/// One halving: the points the tracker pose is fitted on and the points scored (indices into
/// the session's points; disjoint, together every point).
struct SessionHalving {
  std::vector<int> fit, scored;
};

/// The halvings of `session`: its poses (PoseGroups: repeats of a pose stay together) in a
/// seeded shuffle, the first floor(poses / 2) fit the pose and the rest are scored. Requires
/// valid options; throws InputError (naming `source`) for fewer than 6 poses (3 to fit a pose
/// on, 3 to score).
std::vector<SessionHalving> SessionHalvings(const std::vector<TrackerPoint>& session,
                                            const SessionScoringOptions& options,
                                            const std::string& source);

/// A model's score on the second session over the halvings.
struct SessionScore {
  int points = 0;       ///< the session's points
  int halvings = 0;     ///< halvings scored
  double rms_m = 0;     ///< mean over the halvings of the scored half's RMS distance [m]
  double rms_sd_m = 0;  ///< sample standard deviation of that RMS over the halvings [m]
  double rms_min_m = 0, rms_max_m = 0;  ///< its smallest and largest [m]
  std::vector<double> rms_per_halving_m;  ///< in the halvings' order [m]
};

/// Scores predicted points `p_B` (one per session point, in the robot's base frame) against
/// the session's measured points p_T: per halving, X_TB fitted (FitRigid) on the fit half,
/// the RMS of |X_TB p_B - p_T| over the scored half. Throws InputError (naming `source`)
/// where a fit half is collinear.
SessionScore ScorePredictionsOnSession(const std::vector<Vector3>& p_B,
                                       const std::vector<TrackerPoint>& session,
                                       const std::vector<SessionHalving>& halvings,
                                       const std::string& source);

/// ScorePredictionsOnSession of the model's end points at the session's joint readings.
SessionScore ScoreModelOnSession(const RobotModel& model, const std::vector<TrackerPoint>& session,
                                 const std::vector<SessionHalving>& halvings,
                                 const std::string& source);

/// Halvings on which `after` scores worse (a larger RMS) than `before` (the same halvings).
int WorseHalvings(const SessionScore& after, const SessionScore& before);

}  // namespace twin
