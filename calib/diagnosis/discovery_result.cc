#include "calib/diagnosis/discovery_result.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "calib/diagnosis/selection.h"

namespace twin {

const char* ToString(DiscoveryVerdict verdict) {
  switch (verdict) {
    case DiscoveryVerdict::kConsistentWithNoise: return "consistent_with_noise";
    case DiscoveryVerdict::kEffectsAdded: return "effects_added";
    case DiscoveryVerdict::kUnexplained: return "unexplained";
    case DiscoveryVerdict::kPartlyExplained: return "partly_explained";
  }
  return "?";
}

const char* ToString(DiscoveryData data) {
  switch (data) {
    case DiscoveryData::kTrackerPoints: return "tracker_points";
    case DiscoveryData::kOpticalAxes: return "optical_axes";
  }
  return "?";
}

namespace discovery {

std::string Mm(double m) {
  std::ostringstream os;
  os.precision(4);
  os << 1e3 * m << " mm";
  return os.str();
}

void StateNoiseVerdict(const DiscoveryOptions& o, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  r.verdict = DiscoveryVerdict::kConsistentWithNoise;
  std::ostringstream os;
  os << "the residuals of the residual test (RMS " << Mm(r.test_before.rms_m)
     << ") are consistent with the noise floor (sigma " << Mm(r.noise.sigma_m)
     << " per coordinate): p = "
     << r.test_before.p_value << " >= alpha = " << o.alpha << "; no effect searched";
  r.reason = os.str();
  r.test_after = r.test_before;
  r.heldout_rms_discovered_m = r.heldout_rms_start_m;
}

void AddScreeningSummary(const DiscoveryOptions& o, DiscoveryResult* r) {
  int seen = 0, unseen = 0;
  for (const CandidateScore& c : r->screened) {
    const Refusal j = Judge(c, o);
    seen += j != Refusal::kNotApplicable && j != Refusal::kNotIdentifiable;
    unseen += j == Refusal::kNotIdentifiable;
  }
  r->reason += "; of " + std::to_string(r->screened.size()) +
               " candidates fitted beside the model the data could see " + std::to_string(seen) +
               ", " + std::to_string(unseen) + " are unidentifiable from them (screened[])";
  AddHidingPlaces(o, r->screened, "", r);
}

void AddHidingPlaces(const DiscoveryOptions& o, const std::vector<CandidateScore>& candidates,
                     const std::string& which, DiscoveryResult* r) {
  // The ones an effect could hide in: blind to a combination of them, or a detection limit
  // above the stated multiple of the noise floor.
  const double limit = o.could_hide_noise_multiple * r->noise.sigma_m;
  std::vector<const CandidateScore*> room;
  for (const CandidateScore& c : candidates) {
    if (c.detection_limit_m > limit) room.push_back(&c);  // NaN: not computed, never named
  }
  std::stable_sort(room.begin(), room.end(), [](const CandidateScore* a, const CandidateScore* b) {
    return a->detection_limit_m > b->detection_limit_m;
  });
  r->could_hide.clear();
  std::ostringstream os;
  for (const CandidateScore* c : room) {
    r->could_hide.push_back(c->label);
    os << (os.tellp() > 0 ? ", " : "") << c->label << " ("
       << (std::isinf(c->detection_limit_m) ? "unidentifiable: blind to a combination that "
                                              "moves the end point"
                                            : "up to " + Mm(c->detection_limit_m))
       << ")";
  }
  if (!room.empty()) {
    std::ostringstream k;
    k << o.could_hide_noise_multiple;
    r->reason += "; an effect of " + std::to_string(room.size()) + " of " +
                 (which.empty() ? "them" : which) +
                 " could be there unseen, moving the end point by more than " + Mm(limit) +
                 " RMS (" + k.str() + " x the noise floor's sigma; the size a test " +
                 "finds with 80 % power): " + os.str();
  }
}

ScreenAlarm StrongestScreenedSize(const DiscoveryOptions& o, const DiscoveryResult& r) {
  ScreenAlarm a;
  double smallest = 1.0;
  for (std::size_t k = 0; k < r.screened.size(); ++k) {
    const CandidateScore& c = r.screened[k];
    const Refusal j = Judge(c, o);
    if (j == Refusal::kNotApplicable || j == Refusal::kNotIdentifiable ||
        j == Refusal::kGeometryDisguise || c.visible_size_dof <= 0) {
      continue;
    }
    ++a.family;
    if (a.index < 0 || c.visible_size_p_value < smallest) {
      a.index = static_cast<int>(k);
      smallest = c.visible_size_p_value;
    }
  }
  a.p_adjusted = std::min(1.0, smallest * a.family);
  return a;
}

void StateSearchVerdict(double heldout_rms_discovered_m, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  r.heldout_rms_discovered_m = heldout_rms_discovered_m;
  if (r.effects_added.empty()) {
    r.test_after = r.test_before;
    r.verdict = DiscoveryVerdict::kUnexplained;
    std::ostringstream os;
    os << "the residuals of the residual test (RMS " << Mm(r.test_before.rms_m)
       << ") are systematic (p = " << r.test_before.p_value << " against sigma "
       << Mm(r.noise.sigma_m) << " per coordinate) and no candidate effect passes";
    r.reason = os.str();
  } else {
    r.verdict = r.test_after.systematic ? DiscoveryVerdict::kPartlyExplained
                                        : DiscoveryVerdict::kEffectsAdded;
    std::ostringstream os;
    os << r.effects_added.size() << " effect(s) added; region-disjoint held-out RMS "
       << Mm(r.heldout_rms_start_m) << " -> " << Mm(r.heldout_rms_discovered_m)
       << "; the residual is then " << (r.test_after.systematic ? "still systematic" :
                                                                  "consistent with noise")
       << " (p = " << r.test_after.p_value << ")";
    for (const CandidateScore& c : r.effects_added) {
      if (c.indistinguishable_from.empty()) continue;
      os << "; " << c.label;
      for (const std::string& other : c.indistinguishable_from) os << " and " << other;
      os << " are indistinguishable on these data";
    }
    r.reason = os.str();
  }
}

}  // namespace discovery

namespace {

// "0.0123 mm": a length for the terminal lines (4 decimals of a mm) [m in].
std::string FixedMm(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f mm", 1e3 * m);
  return buf;
}

// The step's line: its tested count and its best tested candidate.
std::string StepLine(const DiscoveryStep& s) {
  std::ostringstream os;
  int tested = 0;
  for (const CandidateScore& c : s.candidates) tested += c.tested ? 1 : 0;
  os << "  step " << s.index << ": " << tested << " of " << s.candidates.size()
     << " candidates tested; ";
  const CandidateScore* best = nullptr;
  for (const CandidateScore& c : s.candidates) {
    if (c.tested && (!best || c.gain_percent > best->gain_percent)) best = &c;
  }
  if (best) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "best %s, held-out gain %.1f %%, Holm p = %.3g: %s",
                  best->label.c_str(), best->gain_percent, best->p_adjusted,
                  best->accepted ? "ACCEPTED" : "rejected");
    os << buf;
  } else {
    os << "none testable";
  }
  for (const CandidateScore& c : s.candidates) {
    if (!c.accepted || c.indistinguishable_from.empty()) continue;
    os << " (" << (best != &c ? c.label + " accepted; " : std::string())
       << "indistinguishable on these data from";
    for (std::size_t k = 0; k < c.indistinguishable_from.size(); ++k) {
      os << (k == 0 ? " " : ", ") << c.indistinguishable_from[k];
    }
    os << ")";
  }
  os << "; region held-out RMS " << FixedMm(s.heldout_rms_before_m) << " -> "
     << FixedMm(s.heldout_rms_after_m) << "\n";
  return os.str();
}

// One candidate in full: its scores and note.
std::string CandidateLine(const CandidateScore& c) {
  std::ostringstream os;
  os << "    " << c.label << ":";
  if (!c.applicable) {
    os << " not applicable";
  } else if (!c.identifiable) {
    os << " unidentifiable";
  } else if (c.tested) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  " held-out RMS %.4f mm, gain %.1f %%, p = %.3g, Holm p = %.3g, size p = "
                  "%.3g, |rho| geometry %.5f-%.5f",
                  1e3 * c.heldout_rms_m, c.gain_percent, c.p_value, c.p_adjusted,
                  c.size_p_value, c.min_geometry_correlation, c.max_geometry_correlation);
    os << buf;
  } else {
    char buf[120];
    std::snprintf(buf, sizeof buf, " not tested, size p = %.3g, |rho| geometry %.5f-%.5f",
                  c.size_p_value, c.min_geometry_correlation, c.max_geometry_correlation);
    os << buf;
  }
  os << (c.accepted ? " [accepted]" : "") << "\n";
  for (const DiscoveredParameter& p : c.parameters) {
    os << "      " << p.name << " = " << p.estimated << " +- " << p.sigma << " " << p.unit
       << "\n";
  }
  if (!c.note.empty()) os << "      " << c.note << "\n";
  return os.str();
}

// The black box's line: its region held-out RMS beside the physics', and its second-session
// score beside the discovered model's.
std::string BlackBoxLine(const DiscoveryResult& r) {
  const BlackBoxResult& b = r.black_box;
  std::ostringstream os;
  os << "  black box (kernel ridge on the starting model's residual; a comparator, not in the "
        "model): region held-out RMS "
     << FixedMm(b.heldout_rms_m) << " against discovered " << FixedMm(r.heldout_rms_discovered_m);
  if (b.session && r.session_discovered) {
    os << "; second session " << FixedMm(b.session->rms_m) << " against discovered "
       << FixedMm(r.session_discovered->rms_m);
  }
  os << "\n";
  return os.str();
}

}  // namespace

std::string DiscoveryResult::BriefReport() const {
  std::ostringstream os;
  os << "diagnosis: " << ToString(verdict) << ": " << reason << "\n";
  os << "  noise floor " << FixedMm(noise.sigma_m) << " per coordinate (" << noise.source << ")";
  if (noise.repeat_sigma_m >= 0) {
    os << "; repeated poses (" << noise.repeated_groups << " groups) spread "
       << FixedMm(noise.repeat_sigma_m);
  }
  os << "\n  residual test ("
     << (data == DiscoveryData::kOpticalAxes ? "in sample, global" : "held out")
     << "): RMS " << FixedMm(test_before.rms_m) << ", p = " << test_before.p_value << " ("
     << (test_before.systematic ? "systematic" : "noise") << ")\n";
  for (const DiscoveryStep& s : steps) os << StepLine(s);
  if (!screened.empty()) {
    std::string unseen;
    for (const CandidateScore& c : screened) {
      if (c.applicable && !c.identifiable) unseen += (unseen.empty() ? "" : ", ") + c.label;
    }
    os << "  screened " << screened.size() << " candidates on all the data (none tested)"
       << (unseen.empty() ? std::string("; every applicable one identifiable")
                          : "; unidentifiable from the data: " + unseen)
       << "\n";
  }
  if ((verdict == DiscoveryVerdict::kUnexplained ||
       verdict == DiscoveryVerdict::kPartlyExplained) &&
      !evidence.empty()) {
    os << "  strongest residual correlations:";
    for (std::size_t k = 0; k < evidence.size() && k < 4; ++k) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " %s/%s r = %.2f", evidence[k].quantity.c_str(),
                    evidence[k].component.c_str(), evidence[k].r);
      os << (k ? "," : "") << buf;
    }
    os << "\n";
  }
  if (black_box.computed) os << BlackBoxLine(*this);
  return os.str();
}

std::string DiscoveryResult::FullReport() const {
  std::ostringstream os;
  os << BriefReport();
  os << "  data: " << ToString(data) << (data_note.empty() ? "" : " (" + data_note + ")")
     << "\n  region folds: " << region_rule << "\n  residual test of the discovered model: RMS "
     << FixedMm(test_after.rms_m) << ", p = " << test_after.p_value << "\n";
  os << "  region-disjoint held-out RMS " << FixedMm(heldout_rms_start_m) << " -> "
     << FixedMm(heldout_rms_discovered_m) << "\n";
  for (const DiscoveryStep& s : steps) {
    os << "  step " << s.index << " candidates:\n";
    for (const CandidateScore& c : s.candidates) os << CandidateLine(c);
  }
  if (!screened.empty()) {
    os << "  screened candidates:\n";
    for (const CandidateScore& c : screened) os << CandidateLine(c);
  }
  if (!effects_added.empty()) {
    os << "  effects added:\n";
    for (const CandidateScore& c : effects_added) os << CandidateLine(c);
  }
  if (!evidence.empty()) {
    os << "  residual correlations:";
    for (const ResidualCorrelation& e : evidence) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " %s/%s %.2f", e.quantity.c_str(), e.component.c_str(),
                    e.r);
      os << buf;
    }
    os << "\n";
  }
  return os.str();
}

}  // namespace twin
