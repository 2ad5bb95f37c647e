// The selection policy of model discovery (internal to calib/diagnosis; model_discovery.h,
// step 3): whether a scored candidate is acceptable is decided in one place, Judge, which
// names the first reason it is not (Refusal); the step's choice (the largest held-out gain
// among the candidates with a size, then the driver and the shape preferences) asks Judge
// wherever it needs to know.
#pragma once

#include <string>
#include <vector>

#include "calib/diagnosis/model_discovery.h"

namespace twin::discovery {

/// Why a candidate is not acceptable, in the order Judge checks; kNone: acceptable.
enum class Refusal {
  kNone,
  kNotApplicable,     ///< the term cannot be made, or the data lacks its context
  kNotIdentifiable,   ///< the rank does not rise, or its identification failed
  kNotTested,         ///< fitted on all the data only (screening): no held-out evidence
  kSizeNotShown,      ///< Wald's size test does not tell it from zero (p >= alpha)
  kNotSignificant,    ///< Holm-adjusted paired p >= alpha
  kGainTooSmall,      ///< held-out gain below min_gain_percent
  kGeometryDisguise,  ///< canonical correlation with the geometry >= correlation_limit
};

/// "none", "not_applicable", ... (for messages and tests).
const char* ToString(Refusal refusal);

/// The one acceptability rule: the first refusal of `c` under `o`, kNone where it would be
/// accepted on its own. A tested candidate's p_adjusted must be set (Holm over its step).
Refusal Judge(const CandidateScore& c, const DiscoveryOptions& o);

/// The refusal in words for the candidate's note: the figures that decided it; `family` the
/// number of candidates Holm corrected over. Empty for kNone.
std::string RefusalText(Refusal refusal, const CandidateScore& c, const DiscoveryOptions& o,
                        int family);

/// TermDriver in words, for the notes.
const char* DriverText(TermDriver d);

/// Cosine between two candidates' held-out changes of the residual (heldout_change); 0 where
/// either is empty or zero, or their sizes differ.
double ChangeCosine(const CandidateScore& a, const CandidateScore& b);

/// The one-sided sign-flip p (stats::SignFlipTestGreater) of `better`'s region-fold held-out
/// loss being below `c`'s: their loss differences summed per fold (`region`: each unit's
/// fold, 0..folds-1). Requires both losses of region's size.
double FoldSignFlipP(const CandidateScore& c, const CandidateScore& better,
                     const std::vector<int>& region, int folds);

/// What the policy reads besides the scores.
struct SelectionContext {
  const DiscoveryOptions& o;
  const std::vector<int>& region;  ///< each unit's region fold
  int folds;                       ///< of the region folds
  const RobotModel& start;         ///< the chain the candidates' terms are made for
};

/// The step's tested candidates (indices) and the one of largest gain among them whose size
/// the data tell from zero (-1 none).
struct Selection {
  std::vector<int> tested;
  int best = -1;
};

/// Holm over the tested candidates (sets p_adjusted) and the largest gain among those that
/// pass the size test; the others' notes say why they are not eligible.
Selection SelectLargestGain(const DiscoveryOptions& o, DiscoveryStep* step);

/// The driver preference (model_discovery.h, step 3): a clock-driven acceptable leader `best`
/// gives way to an acceptable candidate with an earlier driver that the region folds cannot
/// tell from it. Returns the choice, `best` where nothing is preferred; notes both.
int PreferEarlierDriver(const SelectionContext& x, const std::vector<int>& tested, int best,
                        DiscoveryStep* step);

/// A shape held at its start (model_discovery.h, step 3): an acceptable `best` whose dormant
/// shape stayed where its search started gives way to the same term restarted (its shape
/// estimated) where that is acceptable and the region folds cannot tell the two apart.
/// Returns the choice, `best` where nothing changed; `shape_choice` says why it changed.
int PreferEstimatedShape(const SelectionContext& x, const std::vector<int>& tested, int best,
                         DiscoveryStep* step, std::string* shape_choice);

/// Accepts the chosen candidate `best` (CandidateScore::accepted) unless Judge refuses it, and
/// notes why either way; nothing where best < 0.
void DecideOnChoice(const DiscoveryOptions& o, const std::vector<int>& tested, int best,
                    const std::string& shape_choice, DiscoveryStep* step);

/// The step's choice among its scored candidates: the index of the chosen one, -1 none; it is
/// accepted only where its CandidateScore::accepted says so. Sets heldout_rms_after_m to
/// before (AcceptTerm updates it).
int ChooseCandidate(const SelectionContext& x, DiscoveryStep* step);

}  // namespace twin::discovery
