// The comparators run after the search (internal to calib/diagnosis; issue 39, items 6 and
// 7): the scores on a second session of the models the search went through, and the black
// box beside the verdict. Neither changes the verdict or the discovered model.
#pragma once

#include <vector>

#include "calib/diagnosis/discovery_data.h"

namespace twin::discovery {

/// With a second session (o.session not empty): the starting model fitted on every point of
/// the first, each step's model (DiscoveryStep::model_after) fitted the same way, scored on
/// the second session over the same halvings (session_scoring.h): r->session_start, each
/// step's session score and whether its term made the session worse (with a warning naming
/// the term), r->session_discovered. `start`: the model the search started from.
void ScoreOnSecondSession(const TrackerData& data, const RobotModel& start,
                          const DiscoveryOptions& o, DiscoveryResult* r);

/// The black box (black_box.h) on the starting model's residual: held out in the region folds
/// `region` (each point's fold, 0..folds-1), and on the second session when there is one.
BlackBoxResult TrackerBlackBox(const TrackerData& data, const RobotModel& start,
                               const std::vector<int>& region, int folds,
                               const DiscoveryOptions& o);

}  // namespace twin::discovery
