#include "calib/diagnosis/model_discovery.h"

#include <algorithm>
#include <array>
#include <functional>
#include <map>
#include <numeric>
#include <sstream>
#include <utility>

#include "calib/common/cpus.h"
#include "calib/common/errors.h"
#include "calib/diagnosis/candidate_scoring.h"
#include "calib/diagnosis/comparators.h"
#include "calib/diagnosis/cross_validation.h"
#include "calib/diagnosis/discovery_data.h"
#include "calib/diagnosis/discovery_folds.h"
#include "calib/diagnosis/discovery_result.h"
#include "calib/diagnosis/evidence.h"
#include "calib/diagnosis/harmonic_orders.h"
#include "calib/diagnosis/selection.h"
#include "calib/identification/dormant_restart.h"
#include "calib/kinematics/forward_kinematics.h"

// The stages of the search (model_discovery.h, steps 2-4) on any kind of data; the parts live
// beside this file by concept: the data and its noise floor (discovery_data.h), the folds
// (discovery_folds.h), the cross-validation and residual test (cross_validation.h), a
// candidate's scores (candidate_scoring.h), the selection policy (selection.h), the evidence
// (evidence.h) and the verdict (discovery_result.h).
namespace twin {
namespace discovery {
namespace {

// What every stage of the search reads: Discover's arguments and what it derives from them.
struct Search {
  const Data& data;
  const RobotModel& start;
  const std::vector<int>& random;  // each unit's fold of the residual test
  int random_folds;
  const std::vector<int>& region;  // each unit's region fold
  int folds;                       // of the region folds
  const std::string& random_rule;
  const DiscoveryOptions& o;
  std::vector<TermSpec> all_specs;  // the candidates
  int jobs;                         // parallel candidate evaluations
  std::function<void(const std::string&)> say;  // progress lines
};

// The model every fit starts from: `start`, with its declared terms' dormant parameters taken
// from a first all-data fit where that identifies more and fits no worse (KeepRestart, as
// FitCandidate restarts such a candidate).
RobotModel WakeDormantTerms(const Data& data, const RobotModel& start,
                            const std::function<void(const std::string&)>& say) {
  if (!HasDormantTermsAtZero(start)) return start;
  const auto fit = [&](const RobotModel& m, bool restart) {
    return data.FitOn(m, {}, restart ? "declared terms, all data, restarted"
                                     : "declared terms, all data");
  };
  const DormantRestart<Fit> kept = FitWithDormantRestart<Fit>(start, fit, WithDormantTermsWoken);
  if (kept.restarted) {
    say("diagnosis: the declared terms' dormant parameters start from a first fit");
  }
  return kept.model;
}

// Step 2 on the starting model (r->test_before); returns its region cross-validation, the
// base of the first step.
CrossValidation TestStartingModel(const Search& search, const RobotModel& current,
                                  DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  search.say("diagnosis: residual test of the starting model (" +
             std::to_string(search.random_folds) + " folds)");
  r.test_before = RunResidualTest(search.data, current, search.random, search.random_folds,
                                  search.o, search.random_rule, "residual test");
  CrossValidation current_region =
      CrossValidate(search.data, current, search.region, search.folds, "region folds");
  r.heldout_rms_start_m = current_region.Rms();
  return current_region;
}

// The verdict "consistent_with_noise", and with screen_when_noise every candidate fitted on
// all the data beside the model (DiscoveryResult::screened).
void ConcludeConsistentWithNoise(const Search& search, const RobotModel& current,
                                 const CrossValidation& current_region, DiscoveryResult* r) {
  const DiscoveryOptions& o = search.o;
  StateNoiseVerdict(o, r);
  if (!o.screen_when_noise) return;
  const int base_rank = search.data.FitOn(current, {}, "screen base").result.observability.rank;
  r->screened = ScoreAll(search.data, current, base_rank, search.all_specs, search.region,
                         search.folds, current_region, false, o.alpha, search.jobs, search.say,
                         "screen");
  AddScreeningSummary(o, r);
}

// Step `step`'s candidates, each scored beside `current` (ScoreAll) against its region
// cross-validation `current_region`.
DiscoveryStep ScoreStep(const Search& search, const RobotModel& current,
                        const CrossValidation& current_region, int step) {
  const int base_rank = search.data.FitOn(current, {}, "step base").result.observability.rank;
  DiscoveryStep s;
  s.index = step;
  s.heldout_rms_before_m = current_region.Rms();
  s.candidates = ScoreAll(search.data, current, base_rank, search.all_specs, search.region,
                          search.folds, current_region, true, search.o.alpha, search.jobs,
                          search.say,
                          "step " + std::to_string(step));
  return s;
}

// Adds the accepted candidate `best` of step `s` to `current`, records the step and tests the
// extended model (r->test_after); returns whether its residual is still systematic.
bool AcceptTerm(const Search& search, DiscoveryStep s, int best, RobotModel* current,
                CrossValidation* current_region, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const RobotModel& start = search.start;
  const CandidateScore& accepted = s.candidates[best];
  s.accepted = best;
  *current = WithTerm(*current, MakeErrorTerm(accepted.spec, start.chain, start.name()));
  if (accepted.restarted) {
    // Its fits start where its first fit ended (FitCandidate), for the same reason.
    const int added = static_cast<int>(accepted.parameters.size());
    for (int k = 0; k < added; ++k) {
      current->term_values(current->term_values.size() - added + k) =
          accepted.parameters[k].estimated;
    }
  }
  s.model_after = *current;
  *current_region =
      CrossValidate(search.data, *current, search.region, search.folds, "region folds");
  s.heldout_rms_after_m = current_region->Rms();
  r.effects_added.push_back(accepted);
  search.say("diagnosis: step " + std::to_string(s.index) + " added " + accepted.label +
             ", held-out RMS " + Mm(s.heldout_rms_before_m) + " -> " +
             Mm(s.heldout_rms_after_m));
  r.steps.push_back(std::move(s));
  // Once the residual is consistent with the noise there is nothing left to explain: a
  // further term could only fit noise.
  r.test_after = RunResidualTest(search.data, *current, search.random, search.random_folds,
                                 search.o, search.random_rule, "residual test");
  return r.test_after.systematic;
}

// Harmonic orders per joint that the candidates try (harmonic_orders.h): at most this many, the
// strongest in the residual of the model each step starts from. Three: a gear's fundamental
// beside its strongest other orders (an eccentric output and an elliptic wave generator, orders
// 1 and 2, in the commonest case), and a bearing's runout next to both. On the real Motoman wide
// file (right_arm_wide.csv, 8 effects at most) joint 1's axis wobble takes orders 1, 2 and 3;
// with two orders a joint, order 1 was never tried and the region held-out RMS stopped at
// 1.705 mm, with three at 1.594 mm, while the second session (right_arm_cube.csv) went from
// 0.1825 to 0.1978 mm (+- 0.007): better in the region folds, slightly worse on the other
// session. The choice was made on that file. Each further order costs a candidate fit per
// joint and per periodic term (49 candidates a step there, 61 with three; the cube file's
// diagnosis took 1405 s against 832 s, both beside other jobs). Order 1 is tried besides these
// (WithFundamental): on the twin's joint-1 gear error of order 1 (tracker_transmission_j1, 20
// trials at ba06c06) it was named in 18, and the discovered model's mean truth RMS was 2x the
// effect-free one; in a trial it missed, the link-frame spectrum ranked orders 2, 5 and 8 above
// order 1.
constexpr int kOrdersPerJoint = 3;

// The default candidates (CandidateTermSpecs) with each joint's harmonic orders from the
// spectrum of `model`'s residual, fitted on all the data, over that joint's readings.
// Per joint j, each unit's residual (in B) turned into the frame of link j after the joint
// turns, at the fitted model's link angles (stages 1-3; the small deflections of stage 5 left
// out: they turn the frame by ~1e-4 rad).
std::vector<std::vector<Eigen::VectorXd>> ResidualsInLinkFrames(
    const Data& data, const RobotModel& model, const std::vector<Eigen::VectorXd>& e_B) {
  const int n = model.chain.num_joints();
  const Eigen::VectorXd params = GetParameters(model);
  std::vector<std::vector<Eigen::VectorXd>> out(n, e_B);
  std::array<RigidT<double>, kMaxJoints + 2> X;
  for (int i = 0; i < data.size(); ++i) {
    double q[kMaxJoints];
    double s = 1.0;
    LinkAnglesT<double>(model, params.data(), data.context(i), q, &s);
    ChainFramesT<double>(model.chain, params.data(), q, s, X.data());
    for (int j = 0; j < n; ++j) {
      if (e_B[i].size() == 3) out[j][i] = X[j + 1].R.transpose() * Vector3(e_B[i]);
    }
  }
  return out;
}

std::vector<TermSpec> SpectrumCandidates(const Data& data, const RobotModel& model) {
  const Fit fit = data.FitOn(model, {}, "starting model, all data (the residual's spectrum)");
  std::vector<int> all(data.size());
  std::iota(all.begin(), all.end(), 0);
  CrossValidation cv;
  cv.Resize(data.size());
  data.HeldOut(fit, all, &cv);
  std::vector<const MeasurementContext*> contexts(data.size());
  for (int i = 0; i < data.size(); ++i) contexts[i] = &data.context(i);
  const int joints = model.chain.num_joints();
  const std::vector<TermSpec> fixed = CandidateTermSpecs(
      model.chain, WithFundamental(SpectrumOrders(cv.e, contexts, joints, MaxHarmonicOrder(),
                                                  kOrdersPerJoint)));
  std::vector<Eigen::VectorXd> e_B = cv.e;
  if (!data.ResidualsInBase(fit, &e_B)) return fixed;
  // A periodic error of the joint's angle (transmission error) turns the lever arm with it: its
  // order is clean in the link's frame. A periodic tilt of the axis (wobble) is not: its
  // direction is fixed in the parent, and the part of the lever along the axis keeps its order
  // in a fixed frame only (turned into the link's frame every part moves to h - 1 and h + 1).
  // Measured on the twin's tracker scenarios, 20 trials each: a joint-2 gear error of order 3
  // was named 11 of 20 from the fixed frame, 20 of 20 from the link's; a joint-1 wobble of
  // order 2, 20 of 20 from the fixed frame, 11 of 20 from the link's.
  const std::vector<TermSpec> link = CandidateTermSpecs(
      model.chain,
      WithFundamental(SpectrumOrdersPerJoint(ResidualsInLinkFrames(data, fit.result.model, e_B),
                                             contexts, MaxHarmonicOrder(), kOrdersPerJoint)));
  std::vector<TermSpec> out;
  for (const TermSpec& spec : link) {
    const bool periodic = !spec.orders.empty() && spec.joint >= 0;
    if (!periodic || !MakeErrorTerm(spec, model.chain, model.name())->deflects_axes()) {
      out.push_back(spec);
    }
  }
  for (const TermSpec& spec : fixed) {
    const bool periodic = !spec.orders.empty() && spec.joint >= 0;
    if (periodic && MakeErrorTerm(spec, model.chain, model.name())->deflects_axes()) {
      out.push_back(spec);
    }
  }
  return out;
}

// Forward selection (header, step 3): one term per step added to `current`, until none is
// accepted, the residual is consistent with the noise, or max_effects are in. Without a user's
// candidate list, each step's periodic candidates take their orders from the spectrum of the
// residual that step starts from (the previous step's term may have been what dominated it).
void SelectTerms(const Search& search, RobotModel* current, CrossValidation* current_region,
                 DiscoveryResult* r) {
  for (int step = 1; step <= search.o.max_effects; ++step) {
    Search step_search = search;
    if (search.o.candidates.empty() && step > 1) {
      step_search.all_specs = SpectrumCandidates(search.data, *current);
    }
    // Every candidate scored beside the current model.
    DiscoveryStep s = ScoreStep(step_search, *current, *current_region, step);
    // The choice among them, accepted or not.
    const int best =
        ChooseCandidate({search.o, search.region, search.folds, search.start}, &s);
    if (best < 0 || !s.candidates[best].accepted) {
      r->steps.push_back(std::move(s));
      break;
    }
    // The extended model; stop once its residual is noise.
    if (!AcceptTerm(step_search, std::move(s), best, current, current_region, r)) break;
  }
}

// Steps 2-4 of the header on any kind of data; `r` holds the noise floor and the fold rules.
void Discover(const Data& data, const RobotModel& start, const std::vector<int>& random,
              int random_folds, const std::vector<int>& region, int folds,
              const std::string& random_rule,
              const DiscoveryOptions& o, DiscoveryResult* out) {
  DiscoveryResult& r = *out;
  const auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };
  // The starting model, its declared terms' dormant parameters woken where that helps.
  RobotModel current = WakeDormantTerms(data, start, say);
  // The candidates, the parallelism and the rest of what every stage reads.
  const Search search{data, start, random, random_folds, region, folds, random_rule, o,
                      o.candidates.empty() ? SpectrumCandidates(data, current) : o.candidates,
                      o.jobs > 0 ? o.jobs : UsableCpuCount(), say};
  // Step 2: the residual test of the starting model, and its region cross-validation.
  CrossValidation current_region = TestStartingModel(search, current, &r);
  if (!r.test_before.systematic) {
    // Step 4 without a search: consistent with the noise, the candidates screened.
    ConcludeConsistentWithNoise(search, current, current_region, &r);
    // Unless the screen's targeted tests see what the global one missed: then search.
    const ScreenAlarm alarm = StrongestScreenedSize(o, r);
    const double alarm_level = o.screen_alarm_fraction * o.alpha;
    if (o.screen_when_noise && alarm.index >= 0 && alarm.p_adjusted < alarm_level) {
      const CandidateScore& c = r.screened[alarm.index];
      std::ostringstream why;
      why << "the residual test passed (p = " << r.test_before.p_value << "), but the screen "
          << "told the size of " << c.label << " from zero (p = " << c.visible_size_p_value
          << ", Holm-adjusted over " << alarm.family << " screened candidates: "
          << alarm.p_adjusted << " < " << alarm_level << "), so the search ran";
      say("diagnosis: " + why.str());
      const std::string screened_reason = r.reason;
      SelectTerms(search, &current, &current_region, &r);
      if (!r.effects_added.empty()) {
        StateSearchVerdict(current_region.Rms(), &r);
        r.reason = why.str() + "; " + r.reason;
      } else {
        r.reason = screened_reason + "; " + why.str() + " and added nothing (steps[])";
      }
    }
  } else {
    // Step 3: forward selection of terms.
    SelectTerms(search, &current, &current_region, &r);
    // Step 4: the verdict on what the search added.
    StateSearchVerdict(current_region.Rms(), &r);
  }
  // A residual left systematic where the last step accepted nothing: where could its cause
  // hide, beside the model it ends with?
  if (r.verdict != DiscoveryVerdict::kConsistentWithNoise &&
      r.verdict != DiscoveryVerdict::kEffectsAdded && !r.steps.empty() &&
      r.steps.back().accepted < 0) {
    AddHidingPlaces(o, r.steps.back().candidates, "the last step's candidates", &r);
  }
  // The discovered model on all the data, and the residual's evidence.
  const Fit final_fit = data.FitOn(current, {}, "discovered model, all data");
  r.model = final_fit.result.model;
  r.X_TB = final_fit.X_TB;
  Evidence(start, data, current_region, &r);
}

// The samples of the axes with 3 or more (an axis of fewer, the servo having lost the others,
// has no straightness to score held out); `left_out` names the others. Throws InputError for
// a negative axis index.
std::vector<AxisSample> SamplesOfFullAxes(const std::vector<AxisSample>& samples,
                                          const std::string& source, std::string* left_out) {
  std::map<int, int> per_axis;
  for (const AxisSample& s : samples) {
    if (s.axis < 0) {
      throw InputError(source, "model discovery: a sample has axis index " +
                                   std::to_string(s.axis) + "; expected 0 or more");
    }
    ++per_axis[s.axis];
  }
  std::vector<AxisSample> kept;
  for (const AxisSample& s : samples) {
    if (per_axis[s.axis] >= 3) kept.push_back(s);
  }
  for (const auto& [axis, m] : per_axis) {
    if (m >= 3) continue;
    *left_out += (left_out->empty() ? "" : ", ") + std::string("axis ") +
                 std::to_string(axis + 1) + " (" + std::to_string(m) +
                 (m == 1 ? " sample)" : " samples)");
  }
  return kept;
}

}  // namespace
}  // namespace discovery

void ValidateDiscoveryOptions(const DiscoveryOptions& o) {
  const auto fail = [](const std::string& field, const std::string& why) {
    throw InputError("diagnosis." + field, why);
  };
  if (!(o.alpha > 0.0 && o.alpha < 0.5)) fail("alpha", "must be in (0, 0.5)");
  if (!(o.min_gain_percent >= 0.0 && o.min_gain_percent < 100.0)) {
    fail("min_gain_percent", "must be in [0, 100)");
  }
  if (o.max_effects < 0 || o.max_effects > 10) fail("max_effects", "must be from 0 to 10");
  if (o.folds < 2 || o.folds > 20) fail("folds", "must be from 2 to 20");
  if (!(o.correlation_limit > 0.0 && o.correlation_limit <= 1.0)) {
    fail("correlation_limit", "must be in (0, 1]");
  }
  if (o.jobs < 0) fail("jobs", "must be >= 0");
  if (!(o.screen_alarm_fraction > 0.0 && o.screen_alarm_fraction <= 1.0)) {
    fail("screen_alarm_fraction", "must be in (0, 1]");
  }
  if (!(o.could_hide_noise_multiple > 0.0 && std::isfinite(o.could_hide_noise_multiple))) {
    fail("could_hide_noise_multiple", "must be a finite number > 0");
  }
  if (!(o.joint_sigma_rad >= 0.0 && o.joint_sigma_rad <= 0.01)) {
    fail("joint_sigma", "must be from 0 to 0.01 rad (0.57 deg)");
  }
  ValidateIdentificationOptions(o.engine);
  ValidateSessionScoringOptions(o.session_scoring, "diagnosis.session_scoring");
  ValidateKernelRidgeOptions(o.kernel_ridge, "diagnosis.kernel_ridge");
}

DiscoveryResult DiscoverTrackerModel(const RobotModel& start,
                                     const std::vector<TrackerPoint>& points,
                                     const DiscoveryOptions& o) {
  ValidateDiscoveryOptions(o);
  const int n = static_cast<int>(points.size());
  const int per_fold_train = n - (n + o.folds - 1) / o.folds;
  if (3 * per_fold_train <= start.num_parameters() + 6) {
    throw InputError(o.set.source, "model discovery: " + std::to_string(n) + " points leave " +
                                       std::to_string(per_fold_train) +
                                       " to train on in a fold of " + std::to_string(o.folds) +
                                       ", too few for the model's " +
                                       std::to_string(start.num_parameters()) +
                                       " parameters and the tracker pose");
  }
  // Step 1: the data and its noise floor.
  const discovery::TrackerData data(start, points, o);
  DiscoveryResult r;
  r.data = DiscoveryData::kTrackerPoints;
  r.noise = discovery::TrackerNoise(data, o);
  // The folds: random for the residual test, workspace blocks for the candidates.
  const std::vector<int> random = discovery::RandomFolds(n, o.folds, o.seed);
  const std::vector<int> region = discovery::RegionFolds(points, o.folds, &r.region_rule);
  const std::string random_rule = std::to_string(o.folds) + "-fold cross-validation, points "
                                  "assigned to folds at random (seed " + std::to_string(o.seed) +
                                  ")";
  // Steps 2-4.
  discovery::Discover(data, start, random, o.folds, region, o.folds, random_rule, o, &r);
  // The comparators beside the verdict (issue 39): the second session, the black box. They
  // start where the search started: the declared terms' dormant parameters woken.
  const RobotModel woken = discovery::WakeDormantTerms(data, start, [](const std::string&) {});
  if (!o.session.empty()) discovery::ScoreOnSecondSession(data, woken, o, &r);
  if (o.black_box) r.black_box = discovery::TrackerBlackBox(data, woken, region, o.folds, o);
  return r;
}

DiscoveryResult DiscoverOpticalAxisModel(const RobotModel& start,
                                         const std::vector<AxisSample>& samples,
                                         const DiscoveryOptions& o) {
  ValidateDiscoveryOptions(o);
  // The axes with 3 samples or more; the others are named.
  std::string left_out;
  const std::vector<AxisSample> kept = discovery::SamplesOfFullAxes(samples, o.axis_source,
                                                                    &left_out);
  const discovery::OpticalData data(start, kept, o);
  const int q = static_cast<int>(data.axes().size());
  if (q < 3) {
    throw InputError(o.axis_source, "model discovery: " + std::to_string(q) +
                                        " optical axes; held-out scoring by whole axes needs 3 "
                                        "or more (2 to train on in every fold)");
  }
  // Step 1: the noise floor.
  DiscoveryResult r;
  r.data = DiscoveryData::kOpticalAxes;
  if (!left_out.empty()) r.data_note = "left out, fewer than 3 samples: " + left_out;
  r.noise = discovery::OpticalNoise(data, o);
  // The folds: whole axes, for the candidates; the residual test is the global one.
  const int folds = std::min(o.folds, q);
  std::vector<int> sample_axes;
  for (const AxisSample& s : kept) sample_axes.push_back(s.axis);
  const std::vector<int> region = discovery::AxisFolds(sample_axes, folds, &r.region_rule);
  const std::string global_rule =
      "in sample: the adjustment's global test, every sample fitted with the stated sigmas, "
      "chi-square over the redundancy (rows less the unknowns, lines included); held-out "
      "samples of few short axes have leverages up to near 1 and a heavy-tailed chi-square";
  // Steps 2-4.
  discovery::Discover(data, start, region, folds, region, folds, global_rule, o, &r);
  r.black_box.note = "not computed for optical axes: a held-out axis is scored by the "
                     "straightness of its points against its own line, not by points a "
                     "residual model could be added to";
  return r;
}

}  // namespace twin
