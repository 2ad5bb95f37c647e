// Model discovery (issue 15): after the identification, decide whether the residual is noise or
// systematic, trace it to a physical effect the model lacks, add that effect and report the
// held-out error before and after. Two kinds of data: laser-tracker points
// (DiscoverTrackerModel) and optical-axis samples (DiscoverOpticalAxisModel, the line
// constraint of Zhu et al. 2019, eq. 13-15, with the depth scale measurement). Estimator side
// only: the measurements, their stated noise and the nominal model; never a true value.
//
// The steps below are written for tracker points; what differs for optical axes is at the end.
// The implementation, one concept a file (internal headers, namespace twin::discovery): the
// data and its noise floor (discovery_data.h), the folds (discovery_folds.h), the
// cross-validation and residual test (cross_validation.h), a candidate's scores
// (candidate_scoring.h), the selection policy with its one acceptability rule, Judge
// (selection.h), the evidence (evidence.h) and the verdict (discovery_result.h); the
// dormant-term restart is calib/identification/dormant_restart.h.
//
// 1. Noise floor: the points' stated sigmas (the file's sigma column), else the set's default,
//    plus the joint readings' noise when the engineer states it (joint_sigma_rad, an encoder's
//    datasheet value) carried to the point through the model: per point the covariance
//    Sigma_i = sigma_i^2 I + sigma_q^2 J_i J_i^T, J_i the point's position Jacobian in the joint
//    angles (central differences of the starting model). Where the data has repeated poses
//    (the same joint readings to 1e-6 rad) their spread is reported beside it.
// 2. Residual test: random K-fold cross-validation of the current model; the held-out
//    residuals' chi-square sum(e_i^T Sigma_i^-1 e_i) over 3 n coordinates, divided by the
//    expected inflation of prediction errors 1 + u / (3 n_train) (u the unknowns of the fit:
//    a held-out point also carries the parameters' estimation error, on average u / n_train of
//    the noise variance), against chi-square(3 n). p < alpha: "systematic".
// 3. Candidate search by forward selection: every registered error term at every joint and
//    order it applies to (CandidateTermSpecs) is added in turn and scored by region-disjoint
//    cross-validation (K workspace blocks from k-means on the measured points: each block is
//    predicted by a model that never saw its region). A candidate is tested only when its
//    context is in the data (time stamps, temperatures, approach directions) and its
//    parameters are identifiable (the rank rises; by less than its parameter count: partly,
//    the engine then moves only the combinations the data sees) and not a disguise
//    of the geometry (the largest canonical correlation of its rank-raising Jacobian directions
//    with the geometric columns below correlation_limit: TermGeometryDependence). The
//    paired test is Wilcoxon's signed rank on per-point differences of held-out squared error
//    (base minus candidate, one-sided), Holm-corrected over the candidates tested in the
//    step. The candidate with the largest held-out gain among those whose size the data tell
//    from zero (Wald's test of its size on the all-data fit, p below alpha: the size
//    test) is accepted only if its adjusted p is below alpha and its gain at least
//    min_gain_percent. A leader driven by the session's clock (ErrorTerm::driver: a warm-up,
//    a drift linear in time) gives way to an acceptable candidate with a driver earlier in
//    TermDriver's order (a measured quantity before a warm-up that levels off, before a drift
//    that grows without end) that the held-out data cannot tell from it (the leader's
//    held-out loss below the other's, summed per region fold, one-sided sign-flip test over
//    the folds: p >= alpha); of several, the earliest driver, then the largest gain. The
//    region folds are parts of one session and cannot test how a clock-driven model carries
//    over to the later times it is used at. A choice whose shape parameter (a warm-up's time
//    constant) stayed at the value its search started from, the data not identifying it
//    there, gives way to the same term with its shape estimated from another start where that
//    one would be accepted and the region folds do not tell the two apart (the same
//    sign-flip test): the start is the search's assumption, not the data's. Then the next
//    step starts from the extended model, until none passes, the residual test of the
//    extended model finds it consistent with the noise (nothing left to explain), or
//    max_effects are in.
// 4. Verdict (DiscoveryVerdict): "consistent_with_noise" (step 2 passes: nothing searched;
//    every candidate is still fitted on all the data and reported, DiscoveryResult::screened),
//    "effects_added", or "unexplained" (systematic and no candidate passes), with the
//    residual's strongest correlations (joint angles, gravity torques, time, temperature,
//    acquisition order) and binned residual maps as evidence.
// 5. Comparators beside the verdict (issue 39), tracker points only; neither decides anything
//    nor enters the model. With a second session (DiscoveryOptions::session, another tracker
//    session of the arm, its tracker pose unknown): the starting model, the model after each
//    step and the discovered one, each fitted on every point of the first session, scored on
//    it over seeded random halvings (session_scoring.h: pose refitted on one half, the other
//    scored); a step whose term makes the session worse is flagged and warned of. And a black
//    box (black_box.h): kernel ridge regression of the starting model's residual over the
//    joint readings, scored on the same region folds and on the second session.
//
// Optical axes (DiscoverOpticalAxisModel). A unit of data is one aligned pose (AxisSample).
// - Noise floor: each sample's own sigmas where it states them (AxisSample::sigma_offset,
//   sigma_depth: the board pose's covariance, i.e. the corner noise the intrinsics step
//   measured carried through the camera model, optical_axis_procedure.cc), else the stated
//   ones (OpticalAxisSetOptions: sigma_perpendicular, the camera's measurement of the servo's
//   residual offset; sigma_depth, the depth from the board pose); plus the stated joint reading
//   noise through the model's Jacobian, projected on (n1, n2, line direction). Every
//   identification of the diagnosis weights each sample by its own sigmas.
// - Residual test: the adjustment's global test, not a held-out one: every sample fitted with
//   those weights (no re-estimation), chi-square of the whitened residuals against
//   chi-square(redundancy), the rows less every unknown (the geometry's rank, 4 + 1 per line).
//   A held-out sample of few, short axes is predicted against a line trained on a handful of
//   its neighbours (leverages up to near 1): its chi-square is heavy-tailed, and on synthetic
//   geometric truths the held-out test called 4 to 7 of 10 clean seeds systematic; the global
//   test's null distribution is exact for a linear model and called 0 of 10.
// - Candidates: region folds of whole axes (consecutive plan axes together, K = min(folds,
//   axes)): the axis's own line is a nuisance, so a held-out axis is scored by the straightness
//   of its predicted points p_i = p_BE(q_i) - o_i: the total-least-squares line through them
//   (FitLine) gives each sample's perpendicular offset in a basis (n1, n2) of the plane normal
//   to the line and, with depths, its along-line position less the measured depth less their
//   mean offset (eq. 13-15 and the scale measurement of nonlinear_identification.h). Gains and
//   the paired test compare whitened squared residuals (the depth is noisier and would
//   otherwise dominate); RMS figures are of the perpendicular distance, the paper's
//   misaligned error.
// A term the line constraint cannot see (the compliance of a joint gravity has no torque
// about, a scale without depths, a tool offset along the camera axis) does not raise the rank:
// the report names it unidentifiable, it is never tested or added.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "calib/diagnosis/black_box.h"
#include "calib/diagnosis/session_scoring.h"
#include "calib/identification/engine.h"
#include "calib/measurements/optical_axis_set.h"
#include "calib/measurements/tracker_set.h"
#include "calib/model/error_term.h"
#include "calib/model/robot_model.h"

namespace twin {

struct DiscoveryOptions {
  double alpha = 0.05;             ///< level of the residual test and family-wise level of a step
  /// Smallest held-out gain worth a term: reduction of the held-out sum of squares [%]. A
  /// significant but tiny gain (many points) is not worth a new parameter block.
  double min_gain_percent = 5.0;
  /// At most this many effects added. The search ends on its tests (step 3), not on a count:
  /// a real arm has several effects at once (the Motoman wide file's search accepts six and
  /// stops on its own, docs/results/real_data_discovery.md); the bound is the largest
  /// ValidateDiscoveryOptions takes, a limit on run time (each step scores every candidate).
  int max_effects = 10;
  int folds = 5;                   ///< K of both cross-validations (>= 2)
  std::uint64_t seed = 1;          ///< of the random folds of the residual test
  /// Canonical correlation of a term's rank-raising Jacobian directions with the geometric
  /// columns (TermGeometryDependence) from which the term counts as a disguise of the geometry
  /// and is not accepted [-]. 0.99999: less than 0.45 % of the term's effect (sqrt(1 - R^2))
  /// lies outside what a geometric correction does. The held-out gain decides whether a term
  /// is real; this only refuses one that is the geometry to within that. A canonical
  /// correlation is at least every pairwise one: on the paper cell a compliance of joint 2
  /// that the optical axes see with 99.7 % held-out gain has R = 0.991-0.9994 (20 trials).
  double correlation_limit = 0.99999;
  /// Cosine between two acceptable candidates' held-out changes of the residual (what each
  /// moves, stacked over every unit of the region folds: CandidateScore::heldout_change) from
  /// which they count as explaining the residual in the same direction, indistinguishable on
  /// these data whatever their gains [-]. 0.99: less than 14 % (sqrt(1 - 0.99^2)) of either's
  /// change lies outside the other's direction.
  double parallel_limit = 0.99;
  /// Candidates to try; empty: every registered term at every joint / order it applies to.
  std::vector<TermSpec> candidates;
  /// Noise of each joint reading (encoder), per joint [rad]; 0: not stated, the floor is the
  /// tracker's alone.
  double joint_sigma_rad = 0.0;
  /// Parallel candidate evaluations; 0: the CPUs this process may use (UsableCpuCount). The
  /// result does not depend on it.
  int jobs = 0;
  /// When the residual is consistent with the noise nothing is searched; still fit every
  /// candidate on all the data (no cross-validation, nothing added) and report it
  /// (DiscoveryResult::screened): whether the data could see it at all, and its size with
  /// 1 sigma, i.e. how large an effect the data leave room for.
  bool screen_when_noise = true;
  /// A screened candidate whose detection limit at the end point
  /// (CandidateScore::detection_limit_m) exceeds this multiple of the noise floor's sigma, or
  /// that has a combination the data cannot see at all, is named in the verdict's reason and
  /// in DiscoveryResult::could_hide: the residual is consistent with the noise, yet an effect
  /// of that term could be there, larger than this, unseen [-] (> 0).
  double could_hide_noise_multiple = 3.0;
  /// Level of the screen's alarm (StrongestScreenedSize's Holm-adjusted p below it starts the
  /// search where the residual test passed) as a fraction of alpha [-] (in (0, 1]). It
  /// overrides a test that has already passed, on the same data, and its chi-square assumes
  /// independent noise, which samples along one optical axis do not have (their residual test
  /// reads p ~ 1): 0.1 asks ten times the evidence. At 1, 3 of 20 clean optical-axis trials of
  /// the twin raised it (adjusted p 0.02-0.034) and 2 added a term.
  double screen_alarm_fraction = 0.1;
  IdentificationOptions engine;    ///< of every identification
  TrackerSetOptions set;           ///< default sigma, source for messages (tracker points)
  /// Optical axes: the stated noise (sigma_perpendicular, sigma_depth), the use of depths and
  /// the Huber threshold of every identification.
  OpticalAxisSetOptions axis_set;
  std::string axis_source = "optical-axis samples";  ///< origin, for messages (optical axes)
  /// Called with a line of progress (step, candidate k of m); may be empty.
  std::function<void(const std::string&)> progress;
  /// Tracker points: a second session of the same arm (its tracker pose unknown); empty:
  /// none. The starting model, each step's model and the discovered one, trained on the first
  /// session, are scored on it (session_scoring.h); it never trains or decides anything.
  std::vector<TrackerPoint> session;
  SessionScoringOptions session_scoring;  ///< the halvings of the second session
  /// Tracker points: fit the black-box comparator (black_box.h) beside the verdict.
  bool black_box = true;
  KernelRidgeOptions kernel_ridge;        ///< its hyperparameter grid
};

/// Throws InputError naming the bad field.
void ValidateDiscoveryOptions(const DiscoveryOptions& options);

struct NoiseFloor {
  /// Tracker: RMS over the points of the per-axis noise sqrt(trace(Sigma_i) / 3); optical
  /// axes: of the perpendicular noise per coordinate, joint noise included [m]
  double sigma_m = 0;
  /// RMS of the points' stated (or default) sigmas; optical axes: sigma_perpendicular [m]
  double tracker_sigma_m = 0;
  double depth_sigma_m = -1;   ///< optical axes with depths: sigma_depth [m]; -1 none
  double joint_sigma_rad = 0;  ///< the readings' stated noise carried through the model [rad]
  std::string source;     ///< "stated per point", "the set's default", ...
  int repeated_groups = 0;       ///< groups of points at the same joint readings
  double repeat_sigma_m = -1;    ///< per-axis spread within those groups [m]; -1 none
};

struct ResidualTest {
  std::string held_out;   ///< how the held-out residuals were obtained
  int points = 0;
  double rms_m = 0;       ///< held-out residual RMS (distance) [m]
  double statistic = 0;   ///< chi-square / inflation
  double dof = 0;
  double inflation = 1;   ///< expected prediction-error inflation divided out
  double p_value = 1;
  bool systematic = false;
};

/// One term parameter's estimate.
struct DiscoveredParameter {
  std::string name, unit;
  double estimated = 0, sigma = 0;  ///< [SI]
};

struct CandidateScore {
  TermSpec spec;
  std::string label;                ///< TermLabel
  bool applicable = true;           ///< the data has the context the term needs
  bool identifiable = true;         ///< its parameters raise the rank
  std::string note;                 ///< why not applicable / identifiable / accepted
  /// Largest canonical correlation of its rank-raising directions with the geometric columns
  /// [-]: 1, one combination of its parameters moves the measurements as a geometric
  /// correction does (it trades with the geometry, its parameters are not its own there).
  double max_geometry_correlation = 0;
  std::string correlated_with;      ///< the geometric parameter most aligned with that direction
  /// Smallest canonical correlation of its rank-raising directions [-]: the direction least
  /// like the geometry. The term is a disguise of the geometry (refused) only where this is at
  /// least DiscoveryOptions::correlation_limit: every direction it adds is the geometry's.
  double min_geometry_correlation = 0;
  /// The canonical correlations of its rank-raising directions, descending [-].
  std::vector<double> geometry_correlations;
  double heldout_rms_m = 0;         ///< region-disjoint held-out RMS with the term [m]
  double gain_percent = 0;          ///< held-out sum-of-squares reduction vs the step's base [%]
  double p_value = 1, p_adjusted = 1;  ///< Wilcoxon one-sided, and after Holm
  /// Size test: Wald's chi-square of the term's size measures s (ErrorTerm::SizeMeasures: its
  /// amplitudes; a warm-up's growth by the data's latest time stamp) against zero on the
  /// all-data fit, s' (J C J')^+ s over the rank of their covariance (size_dof; C the term's
  /// covariance block, J the measures' Jacobian), and its p-value. A candidate whose size the
  /// data do not tell from zero (size_p_value >= alpha) is not accepted, whatever its held-out
  /// gain.
  double size_statistic = 0;
  int size_dof = 0;
  double size_p_value = 1;
  /// Detection limit at the end point [m]: the largest RMS over the data's poses of the end
  /// point's displacement that an effect of this term could cause, with every other parameter
  /// refitted to it, while a test of its size at level alpha would find it with probability
  /// below 0.8 (Baarda's minimal detectable bias: the effect's non-centrality on the weighted
  /// residuals, theta' V theta with V TermGeometryDependence::visible_information, at most
  /// (z(1 - alpha / 2) + z(0.8))^2; 7.85 at alpha 0.05). +inf: a combination of its
  /// parameters the data cannot see at all moves the end point (unidentifiable there, at any
  /// size). NaN: not computed (not applicable, or its fit refused the data). Over the term's
  /// amplitudes, its shape parameters held as fitted. The displacement is the model's end
  /// point (EndPose), in the base frame, beside the other parameters' least-squares response
  /// to the effect in the measurements (TermGeometryDependence::compensation), less the best
  /// rigid motion of all the points (what a tracker's pose or the cell's frame takes up, and
  /// what the rigid scores leave out).
  double detection_limit_m = std::numeric_limits<double>::quiet_NaN();
  /// The size test on what the measurements see of the term (the screen's alarm,
  /// StrongestScreenedSize): theta' V theta / sigma0^2 over V's seen eigen-directions (those
  /// detection_limit_m keeps), theta the term's fitted amplitudes, sigma0 the fit's a
  /// posteriori factor, against chi-square(visible_size_dof). Unlike size_p_value it leaves
  /// out the combinations the data cannot tell from the geometry, where a partly identifiable
  /// term's marginal covariance says nothing. dof 0, p 1: not computed.
  double visible_size_statistic = 0;
  int visible_size_dof = 0;
  double visible_size_p_value = 1;
  bool tested = false;              ///< applicable, identifiable, and entered the correction
  /// ErrorTerm::driver: a measured quantity, or the session's clock (levelling off or not)
  TermDriver driver = TermDriver::kMeasured;
  /// Per unit of data (a point, an axis sample), its held-out loss in the region folds, in the
  /// units' order; what the paired tests compare.
  std::vector<double> heldout_loss;
  /// Per unit, its residual's held-out change against the step's base (base minus candidate),
  /// the units' components stacked in their order [m]: the direction in which it explains
  /// the residual (DiscoveryOptions::parallel_limit).
  std::vector<double> heldout_change;
  /// The driver preference (header, step 3). Where the step's leader is clock-driven and this
  /// candidate, with a driver earlier in TermDriver's order, would be accepted on its own: the
  /// one-sided sign-flip p (stats::SignFlipTestGreater) of the leader's held-out loss being
  /// below this one's, summed per region fold; NaN where not compared.
  double versus_leader_p_value = std::numeric_limits<double>::quiet_NaN();
  /// Accepted in place of that leader (versus_leader_p_value >= alpha): the leader's label.
  std::string preferred_over;
  /// Its fits started from its first all-data fit's term values rather than zero: a term with
  /// dormant parameters (ErrorTerm::has_dormant_parameters: a time constant while the
  /// amplitude is zero) that became identifiable there; an accepted term keeps that start in
  /// the later steps.
  bool restarted = false;
  bool accepted = false;
  /// Of the accepted candidate: the other candidates of its step that would be accepted on
  /// their own (Judge) and either whose held-out loss the region folds do not tell from its
  /// own (one-sided sign-flip p of its being lower, summed per fold, >= alpha) or whose
  /// held-out change is nearly parallel to its own (cosine >= parallel_limit): the data
  /// explain the residual about equally well with any of them, and the verdict names them
  /// together.
  std::vector<std::string> indistinguishable_from;
  std::vector<DiscoveredParameter> parameters;  ///< identified on every point
};

struct DiscoveryStep {
  int index = 1;
  double heldout_rms_before_m = 0;  ///< the step's base model, region-disjoint held-out [m]
  double heldout_rms_after_m = 0;   ///< after the accepted term (= before when none) [m]
  std::vector<CandidateScore> candidates;
  int accepted = -1;                ///< index into candidates, -1 none
  /// The step's base model with its accepted term, as the later steps start from it (not yet
  /// fitted); the default model when none was accepted.
  RobotModel model_after;
  /// The second session's score after the step's accepted term (its base's when none was
  /// accepted), the model fitted on every point of the first session; empty without a second
  /// session (DiscoveryOptions::session).
  std::optional<SessionScore> session;
  /// The accepted term made the second session worse than the step's base (a larger mean RMS
  /// over the same halvings); DiscoveryResult::warnings names it.
  bool session_worse = false;
  int session_worse_halvings = 0;   ///< halvings on which it was worse
};

struct ResidualCorrelation {
  std::string quantity;   ///< "q3", "tau2", "time", "temperature", "order"
  /// "x", "y", "z" (tracker frame) or "norm"; optical axes "distance" (perpendicular) or
  /// "depth" (along-line, signed)
  std::string component;
  double r = 0;           ///< Pearson correlation over the held-out residuals [-]
};

struct ResidualMap {
  std::string quantity;           ///< as above
  std::string unit;
  std::vector<double> bin_centre;
  std::vector<double> rms_m;      ///< residual RMS in each bin [m]
  std::vector<int> count;
};

/// The diagnosis's verdict (header, step 4).
enum class DiscoveryVerdict {
  kConsistentWithNoise,  ///< the residual test passes: nothing searched
  kEffectsAdded,         ///< one or more terms accepted, and the residual is then noise
  kUnexplained,          ///< systematic, and no candidate passes
  /// one or more terms accepted, and the residual after the last accepted step is still
  /// systematic (its test and evidence say how much is left)
  kPartlyExplained,
};

/// "consistent_with_noise", "effects_added", "unexplained", "partly_explained" (the report's
/// words).
const char* ToString(DiscoveryVerdict verdict);

/// The kind of data diagnosed.
enum class DiscoveryData {
  kTrackerPoints,  ///< DiscoverTrackerModel
  kOpticalAxes,    ///< DiscoverOpticalAxisModel
};

/// "tracker_points", "optical_axes" (the report's words).
const char* ToString(DiscoveryData data);

struct DiscoveryResult {
  DiscoveryData data = DiscoveryData::kTrackerPoints;
  std::string data_note;          ///< units of data left out and why; empty: none
  DiscoveryVerdict verdict = DiscoveryVerdict::kConsistentWithNoise;
  std::string reason;             ///< one sentence for the report
  NoiseFloor noise;
  ResidualTest test_before;       ///< of the starting model
  ResidualTest test_after;        ///< of the discovered model (= before when nothing added)
  double heldout_rms_start_m = 0;      ///< region-disjoint, starting model [m]
  double heldout_rms_discovered_m = 0; ///< region-disjoint, discovered model [m]
  std::string region_rule;        ///< how the workspace blocks were made
  std::vector<DiscoveryStep> steps;
  std::vector<CandidateScore> effects_added;
  /// consistent_with_noise with DiscoveryOptions::screen_when_noise: every candidate fitted on
  /// all the data beside the starting model, none tested or added (tested false): applicable,
  /// identifiable (by name when not), its parameters with 1-sigma, its disguise of the geometry.
  std::vector<CandidateScore> screened;
  /// Of the screened candidates, those the data leave room for (detection limit above
  /// DiscoveryOptions::could_hide_noise_multiple times the noise floor's sigma, or blind to a
  /// combination of it): their labels, largest limit first, the blind ones first of all. After
  /// unexplained, or partly_explained with a last step that accepted nothing, the same of
  /// that step's candidates.
  std::vector<std::string> could_hide;
  RobotModel model;               ///< the discovered model, identified on every point
  Transform X_TB = Transform::Identity();  ///< tracker points: the tracker pose
  std::vector<ResidualCorrelation> evidence;  ///< strongest |r| first (at most 8)
  std::vector<ResidualMap> maps;  ///< residual vs each joint angle, gravity torque, order
  /// The second session's scores (DiscoveryOptions::session) of the starting model and of the
  /// discovered one, each fitted on every point of the first; empty without one.
  std::optional<SessionScore> session_start, session_discovered;
  /// The black-box comparator (never part of `model`); not computed for optical axes.
  BlackBoxResult black_box;
  /// E.g. a term that made the second session worse, named.
  std::vector<std::string> warnings;

  /// A few lines for the terminal (as Ceres' Solver::Summary::BriefReport): the verdict and
  /// reason, the noise floor, the residual test, one line per step (its best tested candidate
  /// and whether it was accepted), the screened candidates the data cannot see, and for an
  /// unexplained residual its strongest correlations. Lengths in mm.
  std::string BriefReport() const;
  /// BriefReport, then every candidate of every step (and every screened one) with its
  /// scores and note, the effects added with their parameters, and the evidence.
  std::string FullReport() const;
};

/// Runs the diagnosis from `start` (the geometric model plus any declared terms). Throws
/// InputError for bad options or too few points for the folds.
DiscoveryResult DiscoverTrackerModel(const RobotModel& start,
                                     const std::vector<TrackerPoint>& points,
                                     const DiscoveryOptions& options = {});

/// The diagnosis on one robot's optical-axis samples (header, "Optical axes"); `start` is the
/// board robot's model (BoardRobotModel: end point the feature point) plus any declared terms;
/// sample axis indices may have gaps (plan axes); axes of fewer than 3 samples are left out
/// (DiscoveryResult::data_note). Throws InputError for bad options, a negative axis index,
/// fewer than 3 axes with 3 or more samples, or samples the set refuses.
DiscoveryResult DiscoverOpticalAxisModel(const RobotModel& start,
                                         const std::vector<AxisSample>& samples,
                                         const DiscoveryOptions& options = {});

}  // namespace twin
