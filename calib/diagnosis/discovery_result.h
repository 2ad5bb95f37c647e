// The verdict of model discovery and its reason (internal to calib/diagnosis;
// model_discovery.h, step 4). DiscoveryResult's ToString, BriefReport and FullReport are
// defined beside them (discovery_result.cc).
#pragma once

#include <string>
#include <vector>

#include "calib/diagnosis/model_discovery.h"

namespace twin::discovery {

/// "0.01234 mm": a length for a reason sentence (4 significant digits) [m in].
std::string Mm(double m);

/// The verdict without a search: consistent with the noise (r->test_before passed, p >=
/// alpha); the discovered model is the start (test_after, heldout_rms_discovered_m).
void StateNoiseVerdict(const DiscoveryOptions& o, DiscoveryResult* r);

/// Appends to r->reason how many screened candidates the data could see and how many are
/// unidentifiable (Judge: applicable, and identifiable or not), then AddHidingPlaces of them.
void AddScreeningSummary(const DiscoveryOptions& o, DiscoveryResult* r);

/// Sets r->could_hide to the labels of `candidates` whose detection limit exceeds
/// DiscoveryOptions::could_hide_noise_multiple times the noise floor's sigma (infinite: blind
/// to a combination that moves the end point), largest first, and names them with their limits
/// in r->reason; `which` names the candidates there ("" for "them", after a sentence about
/// them).
void AddHidingPlaces(const DiscoveryOptions& o, const std::vector<CandidateScore>& candidates,
                     const std::string& which, DiscoveryResult* r);

/// The screen's targeted evidence: among the screened candidates the data can see (Judge
/// does not refuse them as not applicable, not identifiable or a disguise of the geometry,
/// and they have a visible size test), the one whose visible size test
/// (CandidateScore::visible_size_p_value) is smallest, with that p Holm-adjusted over them
/// (for the smallest, times their number).
struct ScreenAlarm {
  int index = -1;           ///< into DiscoveryResult::screened; -1: no candidate qualifies
  double p_adjusted = 1.0;  ///< [-]
  int family = 0;           ///< candidates adjusted over
};
ScreenAlarm StrongestScreenedSize(const DiscoveryOptions& o, const DiscoveryResult& r);

/// The verdict after a search: effects_added, or unexplained where none was added (then
/// test_after is test_before); `heldout_rms_discovered_m` of the discovered model [m].
void StateSearchVerdict(double heldout_rms_discovered_m, DiscoveryResult* r);

}  // namespace twin::discovery
