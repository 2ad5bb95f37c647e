#include "calib/diagnosis/selection.h"

#include <cmath>
#include <sstream>

#include "calib/common/errors.h"
#include "calib/diagnosis/candidate_scoring.h"
#include "calib/diagnosis/statistics.h"

namespace twin::discovery {

const char* ToString(Refusal refusal) {
  switch (refusal) {
    case Refusal::kNone: return "none";
    case Refusal::kNotApplicable: return "not_applicable";
    case Refusal::kNotIdentifiable: return "not_identifiable";
    case Refusal::kNotTested: return "not_tested";
    case Refusal::kSizeNotShown: return "size_not_shown";
    case Refusal::kNotSignificant: return "not_significant";
    case Refusal::kGainTooSmall: return "gain_too_small";
    case Refusal::kGeometryDisguise: return "geometry_disguise";
  }
  return "?";
}

Refusal Judge(const CandidateScore& c, const DiscoveryOptions& o) {
  if (!c.applicable) return Refusal::kNotApplicable;
  if (!c.identifiable) return Refusal::kNotIdentifiable;
  if (!c.tested) return Refusal::kNotTested;
  // The size first: a candidate whose size the data cannot tell from zero is not even
  // eligible as the step's leader (SelectLargestGain); the others only refuse the choice.
  if (c.size_p_value >= o.alpha) return Refusal::kSizeNotShown;
  if (c.p_adjusted >= o.alpha) return Refusal::kNotSignificant;
  if (c.gain_percent < o.min_gain_percent) return Refusal::kGainTooSmall;
  // Per direction: refused only where every direction it adds is the geometry's. One that
  // also adds a direction of its own is judged by its held-out gain; its directions that are
  // the geometry's trade with it (noted by SelectLargestGain).
  if (c.min_geometry_correlation >= o.correlation_limit) return Refusal::kGeometryDisguise;
  return Refusal::kNone;
}

std::string RefusalText(Refusal refusal, const CandidateScore& c, const DiscoveryOptions& o,
                        int family) {
  std::ostringstream why;
  switch (refusal) {
    case Refusal::kNone:
      break;
    case Refusal::kNotApplicable:
      why << "not applicable to the data";
      break;
    case Refusal::kNotIdentifiable:
      why << "unidentifiable from the data";
      break;
    case Refusal::kNotTested:
      why << "not tested held out";
      break;
    case Refusal::kSizeNotShown:
      why << "its size is not told from zero: Wald chi-square " << c.size_statistic << " on "
          << c.size_dof << " dof, p = " << c.size_p_value << " >= " << o.alpha;
      break;
    case Refusal::kNotSignificant:
      why << "not significant: Holm-adjusted p = " << c.p_adjusted << " >= " << o.alpha
          << " over " << family << " candidates";
      break;
    case Refusal::kGainTooSmall:
      why << c.gain_percent << " % < the " << o.min_gain_percent << " % worth a term";
      break;
    case Refusal::kGeometryDisguise:
      why << "a disguise of the geometry: each of its " << c.geometry_correlations.size()
          << " direction(s) moves the measurements as a geometric correction does (|rho| >= "
          << c.min_geometry_correlation << ", the nearest " << c.correlated_with << ")";
      break;
  }
  return why.str();
}

namespace {

// Appends `text` to the candidate's note ("; " between).
void AddNote(const std::string& text, CandidateScore* c) {
  c->note = c->note.empty() ? text : c->note + "; " + text;
}

// A term with some but not all of its directions the geometry's: those combinations of its
// parameters trade with the geometric ones (their values are not the term's own).
void NotePartlyGeometry(const DiscoveryOptions& o, CandidateScore* c) {
  int disguised = 0;
  for (double r : c->geometry_correlations) disguised += r >= o.correlation_limit ? 1 : 0;
  if (disguised == 0 || disguised == static_cast<int>(c->geometry_correlations.size())) return;
  std::ostringstream why;
  why << disguised << " of its " << c->geometry_correlations.size()
      << " directions move the measurements as the geometry does (|rho| = "
      << c->max_geometry_correlation << " with " << c->correlated_with
      << "): those combinations trade with the geometry";
  AddNote(why.str(), c);
}

}  // namespace

const char* DriverText(TermDriver d) {
  switch (d) {
    case TermDriver::kMeasured: return "a measured quantity";
    case TermDriver::kClockLevelling: return "the clock, levelling off";
    case TermDriver::kClockUnbounded: return "the clock, without bound";
  }
  return "?";
}

double ChangeCosine(const CandidateScore& a, const CandidateScore& b) {
  if (a.heldout_change.empty() || a.heldout_change.size() != b.heldout_change.size()) {
    return 0.0;
  }
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.heldout_change.size(); ++i) {
    ab += a.heldout_change[i] * b.heldout_change[i];
    aa += a.heldout_change[i] * a.heldout_change[i];
    bb += b.heldout_change[i] * b.heldout_change[i];
  }
  return aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0.0;
}

double FoldSignFlipP(const CandidateScore& c, const CandidateScore& better,
                     const std::vector<int>& region, int folds) {
  TWIN_REQUIRE(c.heldout_loss.size() == region.size() &&
                   better.heldout_loss.size() == region.size(),
               "FoldSignFlipP: held-out losses of " + std::to_string(c.heldout_loss.size()) +
                   " and " + std::to_string(better.heldout_loss.size()) + " units, " +
                   std::to_string(region.size()) + " in the folds");
  std::vector<double> d(folds, 0.0);
  for (std::size_t i = 0; i < region.size(); ++i) {
    d[region[i]] += c.heldout_loss[i] - better.heldout_loss[i];
  }
  return stats::SignFlipTestGreater(d);
}

Selection SelectLargestGain(const DiscoveryOptions& o, DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  Selection sel;
  // Holm over the tested candidates: every tested candidate is in the family.
  std::vector<double> p;
  for (int k = 0; k < static_cast<int>(s.candidates.size()); ++k) {
    if (s.candidates[k].tested) {
      sel.tested.push_back(k);
      p.push_back(s.candidates[k].p_value);
    }
  }
  const std::vector<double> adjusted = stats::HolmAdjust(p);
  const int family = static_cast<int>(sel.tested.size());
  for (int t = 0; t < family; ++t) {
    CandidateScore& c = s.candidates[sel.tested[t]];
    c.p_adjusted = adjusted[t];
    // One whose size the data cannot tell from zero (SizeTest) is not eligible.
    if (Judge(c, o) == Refusal::kSizeNotShown) {
      AddNote(RefusalText(Refusal::kSizeNotShown, c, o, family), &c);
      continue;
    }
    if (sel.best < 0 || c.gain_percent > s.candidates[sel.best].gain_percent) {
      sel.best = sel.tested[t];
    }
  }
  return sel;
}


// The driver preference (model_discovery.h, step 3): the region folds are parts of one session, so
// they cannot test how a clock-driven term carries over to later times. Where the leader
// is clock-driven and an acceptable candidate with an earlier driver (TermDriver) is not
// told apart from it (the leader's held-out loss below the other's, summed per region
// fold, by the sign-flip test: p >= alpha), that candidate is taken instead: of several,
// the earliest driver, then the largest gain. The folds are the independent units here,
// not the points: a fold's points share the error of the model fitted without them, and
// between two near-equal models that shared error is the whole difference. Per point,
// Wilcoxon called a 0.14-point gain difference (a time-linear growth against the same
// growth read by a 0.03 K sensor, synthetic tracker data) significant at p = 0.0007.
int PreferEarlierDriver(const SelectionContext& x, const std::vector<int>& tested, int best,
                        DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  const DiscoveryOptions& o = x.o;
  if (!(best >= 0 && s.candidates[best].driver != TermDriver::kMeasured &&
        Judge(s.candidates[best], o) == Refusal::kNone)) {
    return best;
  }
  const CandidateScore& lead = s.candidates[best];
  int preferred = -1;
  for (int k : tested) {
    CandidateScore& c = s.candidates[k];
    if (c.driver >= lead.driver || Judge(c, o) != Refusal::kNone) continue;
    if (c.heldout_loss.size() != lead.heldout_loss.size() ||
        x.region.size() != lead.heldout_loss.size()) {
      continue;
    }
    c.versus_leader_p_value = FoldSignFlipP(c, lead, x.region, x.folds);
    if (c.versus_leader_p_value < o.alpha) {
      std::ostringstream why;
      why << "not preferred for its driver (" << DriverText(c.driver) << "): "
          << lead.label << " (" << DriverText(lead.driver)
          << ") is better in the region folds (sign-flip p = " << c.versus_leader_p_value
          << " < " << o.alpha << ")";
      AddNote(why.str(), &c);
      continue;
    }
    const CandidateScore* q = preferred >= 0 ? &s.candidates[preferred] : nullptr;
    if (!q || c.driver < q->driver ||
        (c.driver == q->driver && c.gain_percent > q->gain_percent)) {
      preferred = k;
    }
  }
  if (preferred >= 0) {
    CandidateScore& leader = s.candidates[best];
    CandidateScore& c = s.candidates[preferred];
    c.preferred_over = leader.label;
    std::ostringstream why;
    why << "largest held-out gain (" << leader.gain_percent << " %), but driven by "
        << DriverText(leader.driver) << " and not told apart from " << c.label << " ("
        << c.gain_percent << " %, sign-flip p over the region folds = "
        << c.versus_leader_p_value << " >= " << o.alpha << "), driven by "
        << DriverText(c.driver);
    AddNote(why.str(), &leader);
    best = preferred;
  }
  return best;
}

// A shape held at its start: a term whose shape (a warm-up's time constant) the data left at
// the value its search started from is that start's assumption, not the data's.
int PreferEstimatedShape(const SelectionContext& x, const std::vector<int>& tested, int best,
                         DiscoveryStep* step, std::string* shape_choice) {
  DiscoveryStep& s = *step;
  const DiscoveryOptions& o = x.o;
  if (!(best >= 0 && !s.candidates[best].restarted &&
        Judge(s.candidates[best], o) == Refusal::kNone &&
        s.candidates[best].heldout_loss.size() == x.region.size() &&
        HasDormantParameters(s.candidates[best].spec, x.start))) {
    return best;
  }
  const CandidateScore& held = s.candidates[best];
  int estimated = -1;
  double estimated_p = 1.0;
  for (int k : tested) {
    const CandidateScore& c = s.candidates[k];
    if (k == best || c.spec.type != held.spec.type || !c.restarted ||
        Judge(c, o) != Refusal::kNone || c.heldout_loss.size() != x.region.size()) {
      continue;
    }
    const double p_fold = FoldSignFlipP(c, held, x.region, x.folds);
    if (p_fold < o.alpha) continue;
    if (estimated < 0 || c.gain_percent > s.candidates[estimated].gain_percent) {
      estimated = k;
      estimated_p = p_fold;
    }
  }
  if (estimated >= 0) {
    CandidateScore& was = s.candidates[best];
    CandidateScore& c = s.candidates[estimated];
    std::ostringstream why;
    why << "its shape stayed at the start of its search (the data did not identify it "
           "there), and "
        << c.label << " estimates it with a held-out loss the region folds do not tell "
        << "apart (sign-flip p = " << estimated_p << " >= " << o.alpha << ")";
    AddNote(why.str(), &was);
    std::ostringstream accepted_why;
    accepted_why << "accepted in place of " << was.label
                 << ", whose shape stayed at the start of its search: this one estimates "
                    "it, and the region folds do not tell the two apart (sign-flip p = "
                 << estimated_p << ")";
    *shape_choice = accepted_why.str();
    c.preferred_over = was.label;
    best = estimated;
  }
  return best;
}

void DecideOnChoice(const DiscoveryOptions& o, const std::vector<int>& tested, int best,
                    const std::string& shape_choice, DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  if (best < 0) return;
  CandidateScore& c = s.candidates[best];
  const Refusal refused = Judge(c, o);
  std::ostringstream why;
  if (refused != Refusal::kNone) {
    why << "largest held-out gain, but "
        << RefusalText(refused, c, o, static_cast<int>(tested.size()));
  } else if (!shape_choice.empty()) {
    c.accepted = true;
    why << shape_choice << "; held-out gain " << c.gain_percent
        << " %, Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  } else if (!c.preferred_over.empty()) {
    c.accepted = true;
    why << "accepted in place of " << c.preferred_over << " (driven by "
        << DriverText(c.driver) << ", fold p = "
        << c.versus_leader_p_value << "): held-out gain " << c.gain_percent
        << " %, Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  } else {
    c.accepted = true;
    why << "accepted: largest held-out gain (" << c.gain_percent
        << " %), Holm-adjusted p = " << c.p_adjusted << " over " << tested.size()
        << " candidates";
  }
  AddNote(why.str(), &c);
  if (c.accepted) NotePartlyGeometry(o, &c);
}

// Honest names (model_discovery.h, CandidateScore::indistinguishable_from): the accepted term
// and every other acceptable candidate the region folds do not tell from it.
void NameIndistinguishable(const SelectionContext& x, const std::vector<int>& tested, int best,
                           DiscoveryStep* step) {
  DiscoveryStep& s = *step;
  if (best < 0 || !s.candidates[best].accepted) return;
  CandidateScore& chosen = s.candidates[best];
  if (chosen.heldout_loss.size() != x.region.size()) return;
  for (int k : tested) {
    CandidateScore& c = s.candidates[k];
    if (k == best || Judge(c, x.o) != Refusal::kNone ||
        c.heldout_loss.size() != x.region.size()) {
      continue;
    }
    const double p = FoldSignFlipP(c, chosen, x.region, x.folds);
    const double cosine = ChangeCosine(c, chosen);
    const bool parallel = cosine >= x.o.parallel_limit;
    if (p < x.o.alpha && !parallel) continue;
    chosen.indistinguishable_from.push_back(c.label);
    std::ostringstream why;
    why << "indistinguishable on these data from the accepted " << chosen.label
        << " (held-out gain " << c.gain_percent << " % against " << chosen.gain_percent
        << " %, sign-flip p over the region folds = " << p
        << (p >= x.o.alpha ? " >= " : " < ") << x.o.alpha;
    if (parallel) {
      why << "; their held-out changes of the residual are nearly parallel: cosine " << cosine
          << " >= " << x.o.parallel_limit;
    }
    why << ")";
    AddNote(why.str(), &c);
  }
  if (!chosen.indistinguishable_from.empty()) {
    std::string names;
    for (const std::string& n : chosen.indistinguishable_from) {
      names += (names.empty() ? "" : ", ") + n;
    }
    AddNote("the region folds do not tell it from " + names +
                ": the data explain the residual about equally well with either",
            &chosen);
  }
}

int ChooseCandidate(const SelectionContext& x, DiscoveryStep* step) {
  // Holm-adjusted p-values, and the largest gain among those with a size.
  const Selection sel = SelectLargestGain(x.o, step);
  step->heldout_rms_after_m = step->heldout_rms_before_m;
  // A clock-driven leader gives way to an earlier driver the folds cannot tell from it.
  int best = PreferEarlierDriver(x, sel.tested, sel.best, step);
  // A shape left at its start gives way to the same term with its shape estimated.
  std::string shape_choice;  // why this rule changed the choice
  best = PreferEstimatedShape(x, sel.tested, best, step, &shape_choice);
  // Accepted or refused, with the reason.
  DecideOnChoice(x.o, sel.tested, best, shape_choice, step);
  // The others the data cannot tell from it, named with it.
  NameIndistinguishable(x, sel.tested, best, step);
  return best;
}

}  // namespace twin::discovery
