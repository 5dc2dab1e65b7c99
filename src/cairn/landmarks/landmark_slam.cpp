#include "cairn/landmarks/landmark_slam.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/filter/nees.hpp"
#include "cairn/filter/range_bearing.hpp"

namespace cairn::landmarks {
namespace {

using core::Clock;
using core::seconds_since;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();


struct Step {
  core::Timestamp time;
  Vector3 odometry = Vector3::Zero();        // T_odom_body at this step
  // Motion since the previous step (body frame of the previous step) and its covariance.
  Vector3 u = Vector3::Zero();
  Matrix3 Q = Matrix3::Zero();
  std::vector<std::size_t> observations;      // indices into run.observations
};

// The motion between times a < b and its covariance, composed record by record so that a long
// gap between observations (a turn with no landmark in view) gets the covariance of the path
// actually driven, not of the chord: U <- U (+) u_i, Sigma <- J_U Sigma J_U^T + J_u Q(u_i) J_u^T
// (Smith, Self & Cheeseman 1990, compounding with first-order covariance propagation).
void preintegrate(const std::vector<TimedPose>& odometry, const OdometryNoiseModel& model, core::Timestamp a,
                  core::Timestamp b, Step* step) {
  std::vector<Vector3> path;
  path.push_back(*odometry_at(odometry, a));
  auto it = std::upper_bound(odometry.begin(), odometry.end(), a,
                             [](core::Timestamp t, const TimedPose& p) { return t < p.time; });
  for (; it != odometry.end() && it->time < b; ++it) path.push_back(it->pose);
  path.push_back(*odometry_at(odometry, b));
  Vector3 U = Vector3::Zero();
  Matrix3 Sigma = Matrix3::Zero();
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Vector3 u = filter::between(path[i - 1], path[i]);
    Matrix3 J_U;
    Matrix3 J_u;
    U = filter::compose(U, u, &J_U, &J_u);
    Sigma = J_U * Sigma * J_U.transpose() + J_u * model.covariance(u) * J_u.transpose();
  }
  step->u = U;
  step->Q = Sigma;
}

std::vector<Step> make_steps(const LandmarkRun& run, const OdometryNoiseModel& model) {
  std::vector<Step> steps;
  Step first;
  first.time = run.odometry.front().time;
  first.odometry = run.odometry.front().pose;
  steps.push_back(first);
  for (std::size_t i = 0; i < run.observations.size(); ++i) {
    const Observation& o = run.observations[i];
    if (!(steps.back().time == o.time)) {
      const std::optional<Vector3> odometry = odometry_at(run.odometry, o.time);
      CAIRN_ASSERT(odometry.has_value(), "make_steps: observation outside the odometry span (the reader checks this)");
      Step s;
      s.time = o.time;
      s.odometry = *odometry;
      preintegrate(run.odometry, model, steps.back().time, o.time, &s);
      steps.push_back(s);
    }
    steps.back().observations.push_back(i);
  }
  return steps;
}

// Ground truth by exact time stamp.
class Truth {
 public:
  explicit Truth(const LandmarkRun& run) : landmarks_(run.true_landmarks) {
    for (const TimedPose& p : run.ground_truth) poses_.emplace(p.time.nanoseconds(), p.pose);
  }
  std::optional<Vector3> pose(core::Timestamp t) const {
    const auto it = poses_.find(t.nanoseconds());
    if (it == poses_.end()) return std::nullopt;
    return it->second;
  }
  const Vector2* landmark(std::int64_t id) const {
    const auto it = landmarks_.find(id);
    return it == landmarks_.end() ? nullptr : &it->second;
  }

 private:
  std::map<std::int64_t, Vector3> poses_;
  const std::map<std::int64_t, Vector2>& landmarks_;
};

Vector2 measurement(const Observation& o) { return {o.range_m, o.bearing_rad}; }

std::vector<std::size_t> checkpoint_steps(std::size_t step_count, int checkpoints) {
  std::vector<std::size_t> out;
  for (int c = 1; c <= checkpoints; ++c) {
    const auto s = static_cast<std::size_t>(
        std::llround(static_cast<double>(c) * static_cast<double>(step_count - 1) / static_cast<double>(checkpoints)));
    if (out.empty() || out.back() != s) out.push_back(s);
  }
  return out;
}

// Mean 2-dof NEES of the landmarks that have a true position.
template <typename Get>
std::pair<double, std::size_t> landmark_nees_mean(const Truth& truth, const std::vector<std::int64_t>& labels, Get get) {
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const Vector2* p_true = truth.landmark(labels[l]);
    if (p_true == nullptr) continue;
    const auto [p, covariance] = get(l);
    const std::optional<double> value = filter::nees(Eigen::VectorXd(p - *p_true), Eigen::MatrixXd(covariance));
    if (!value) continue;
    sum += *value;
    ++count;
  }
  return {count == 0 ? kNaN : sum / static_cast<double>(count), count};
}

struct Candidate {
  Vector2 p_world = Vector2::Zero();
  double first_time_s = 0.0;
  std::size_t last_step = 0;
  int support = 0;  // unpaired observations, at most one per step
};

// The EKF pass: the EKF-SLAM estimate, and for unknown association the front end whose
// associations graph SLAM reuses.
struct EkfPass {
  std::vector<Vector3> poses;
  std::vector<std::optional<std::size_t>> landmark_of_observation;  // includes the creating observation
  std::vector<std::int64_t> labels;                                  // per EKF landmark
  std::vector<std::size_t> landmark_observations;
  std::vector<NeesPoint> nees;
  double mean_pose_nees = kNaN;
  AssociationCounts counts;
  filter::EkfSlamCounters counters;
  std::vector<LandmarkEstimate> landmarks;
  double time_s = 0.0;
  double mean_step_s = 0.0;
  double max_step_s = 0.0;
  std::size_t steps_done = 0;  // < steps.size() when should_stop ended the pass
};

// The EKF pass one step at a time (run_ekf): the filter and the association state kept between
// steps, and the stages of a step. What it reports goes into `pass`.
class EkfSteps {
 public:
  EkfSteps(const LandmarkRun& run, const LandmarkSlamOptions& options, const Truth& truth,
           const std::vector<std::size_t>& checkpoints, const Vector3& first_pose, EkfPass& pass)
      : run_(run),
        options_(options),
        truth_(truth),
        checkpoints_(checkpoints),
        pass_(pass),
        ekf_(first_pose, Matrix3::Zero(), options.sensor) {}

  // Predict: the motion since the previous step (Step::u with its covariance Step::Q).
  void predict(const Step& step) { ekf_.predict(step.u, step.Q); }
  std::vector<std::size_t> valid_observations(const Step& step);
  void update_known_association(const std::vector<std::size_t>& valid);
  void update_unknown_association(const Step& step, std::size_t k, const std::vector<std::size_t>& valid);
  void record_step(const Step& step, std::size_t k);
  void finish();

 private:
  std::vector<std::size_t> update_known(const std::vector<std::size_t>& valid);
  void augment_known(const std::vector<std::size_t>& new_ones);
  filter::AssociationResult associate(const std::vector<Vector2>& zs);
  std::vector<std::size_t> update_paired(const std::vector<std::size_t>& valid, const std::vector<Vector2>& zs,
                                         const filter::AssociationResult& result);
  void expire_candidates(double now_s);
  void augment_from_unpaired(std::size_t i, std::size_t k, double now_s);
  void add_landmark(const Vector2& z, std::int64_t label, std::size_t observation);
  void label_landmarks_by_truth();
  void score_pairings();
  void count_landmark_origins();
  void count_spurious_rejected();
  void output_landmarks();

  const LandmarkRun& run_;
  const LandmarkSlamOptions& options_;
  const Truth& truth_;
  const std::vector<std::size_t>& checkpoints_;
  EkfPass& pass_;
  filter::EkfSlam ekf_;
  std::map<std::int64_t, std::size_t> index_of_id_;  // known association
  std::vector<Candidate> candidates_;                // unknown association
  std::vector<std::pair<std::size_t, std::size_t>> pairings_;  // (observation, landmark), unknown association
  std::size_t next_checkpoint_ = 0;
  double nees_sum_ = 0.0;
  std::size_t nees_count_ = 0;
};

// The EKF pass: per step predict, associate and update, augment the map, record; then the
// scoring of the associations.
EkfPass run_ekf(const LandmarkRun& run, const std::vector<Step>& steps, const LandmarkSlamOptions& options,
                const Truth& truth, const std::vector<std::size_t>& checkpoints) {
  EkfPass pass;
  pass.landmark_of_observation.assign(run.observations.size(), std::nullopt);
  EkfSteps ekf(run, options, truth, checkpoints, steps.front().odometry, pass);
  const auto run_start = Clock::now();

  pass.steps_done = steps.size();
  for (std::size_t k = 0; k < steps.size(); ++k) {
    if (k > 0 && options.should_stop && options.should_stop()) {
      pass.steps_done = k;
      break;
    }
    const Step& step = steps[k];
    const auto step_start = Clock::now();
    if (k > 0) {
      ekf.predict(step);
    }
    const std::vector<std::size_t> valid = ekf.valid_observations(step);
    if (options.association == Association::kKnown) {
      ekf.update_known_association(valid);
    } else {
      ekf.update_unknown_association(step, k, valid);
    }
    const double step_s = seconds_since(step_start);
    pass.max_step_s = std::max(pass.max_step_s, step_s);
    ekf.record_step(step, k);
  }
  pass.time_s = seconds_since(run_start);
  pass.mean_step_s = pass.time_s / static_cast<double>(pass.steps_done);
  ekf.finish();
  return pass;
}

// Invalid observations are refused by the filter and counted; the rest are associated (known
// association: not those without an identity).
std::vector<std::size_t> EkfSteps::valid_observations(const Step& step) {
  std::vector<std::size_t> valid;
  for (const std::size_t i : step.observations) {
    const Observation& o = run_.observations[i];
    ++pass_.counts.observations;
    if (o.landmark_id == kSpuriousId) ++pass_.counts.spurious_observations;
    if (!ekf_.is_valid_observation(measurement(o))) {
      ++pass_.counts.rejected_invalid;
      continue;
    }
    if (options_.association == Association::kKnown && o.landmark_id == kSpuriousId) {
      continue;  // no identity: known association cannot use it (counted as spurious_rejected below)
    }
    valid.push_back(i);
  }
  return valid;
}

// Known association: the observations of mapped ids update the filter, the others add landmarks.
void EkfSteps::update_known_association(const std::vector<std::size_t>& valid) {
  const std::vector<std::size_t> new_ones = update_known(valid);
  augment_known(new_ones);
}

// Update (known association): each observation of an id already in the map; returns the others.
std::vector<std::size_t> EkfSteps::update_known(const std::vector<std::size_t>& valid) {
  std::vector<std::size_t> new_ones;
  for (const std::size_t i : valid) {
    const Observation& o = run_.observations[i];
    const auto it = index_of_id_.find(o.landmark_id);
    if (it == index_of_id_.end()) {
      new_ones.push_back(i);
      continue;
    }
    if (ekf_.update(it->second, measurement(o))) {
      pass_.landmark_of_observation[i] = it->second;
      ++pass_.landmark_observations[it->second];
      ++pass_.counts.paired_correct;
    } else {
      ++pass_.counts.rejected_invalid;
    }
  }
  return new_ones;
}

// Augment (known association): a landmark per new id, initialised from its first observation.
void EkfSteps::augment_known(const std::vector<std::size_t>& new_ones) {
  for (const std::size_t i : new_ones) {
    const Observation& o = run_.observations[i];
    if (index_of_id_.count(o.landmark_id) != 0) {
      // The same id twice in one step: the second is an ordinary update.
      if (ekf_.update(index_of_id_[o.landmark_id], measurement(o))) {
        pass_.landmark_of_observation[i] = index_of_id_[o.landmark_id];
        ++pass_.landmark_observations[index_of_id_[o.landmark_id]];
        ++pass_.counts.paired_correct;
      }
      continue;
    }
    const std::size_t before = ekf_.landmark_count();
    add_landmark(measurement(o), o.landmark_id, i);
    if (ekf_.landmark_count() > before) index_of_id_[o.landmark_id] = before;
  }
}

// Unknown association: associate (NN or JCBB), update with the pairings, then the unpaired
// observations support tentative landmarks, which enter the map once confirmed.
void EkfSteps::update_unknown_association(const Step& step, std::size_t k, const std::vector<std::size_t>& valid) {
  std::vector<Vector2> zs;
  for (const std::size_t i : valid) zs.push_back(measurement(run_.observations[i]));
  const filter::AssociationResult result = associate(zs);
  // Apply the pairings (sequential updates of a jointly compatible set)...
  const std::vector<std::size_t> unpaired = update_paired(valid, zs, result);
  // Tentative landmarks: expire, then match or start.
  const double now_s = step.time.seconds();
  expire_candidates(now_s);
  for (const std::size_t i : unpaired) augment_from_unpaired(i, k, now_s);
}

// Associate: the step's observations with the map's landmarks, by JCBB or nearest neighbour.
filter::AssociationResult EkfSteps::associate(const std::vector<Vector2>& zs) {
  const filter::AssociationResult result = options_.association == Association::kJcbb
                                               ? filter::associate_jcbb(ekf_, zs, options_.gating)
                                               : filter::associate_nearest_neighbour(ekf_, zs, options_.gating);
  pass_.counts.jcbb_nodes += result.nodes;
  if (result.search_truncated) ++pass_.counts.jcbb_truncated_searches;
  return result;
}

// Update: one sequential update per pairing (scored at the end); returns the unpaired observations.
std::vector<std::size_t> EkfSteps::update_paired(const std::vector<std::size_t>& valid, const std::vector<Vector2>& zs,
                                                 const filter::AssociationResult& result) {
  std::vector<std::size_t> unpaired;
  for (std::size_t a = 0; a < valid.size(); ++a) {
    const std::size_t i = valid[a];
    const auto& landmark = result.landmark_of_observation[a];
    if (!landmark) {
      unpaired.push_back(i);
      continue;
    }
    pairings_.emplace_back(i, *landmark);  // scored at the end, against the final map
    if (ekf_.update(*landmark, zs[a])) {
      pass_.landmark_of_observation[i] = *landmark;
      ++pass_.landmark_observations[*landmark];
    }
  }
  return unpaired;
}

// Tentative landmarks older than candidate_lifetime_s are dropped, and counted.
void EkfSteps::expire_candidates(double now_s) {
  const auto expired = std::remove_if(candidates_.begin(), candidates_.end(), [&](const Candidate& c) {
    return now_s - c.first_time_s > options_.candidate_lifetime_s;
  });
  pass_.counts.candidates_expired += static_cast<std::size_t>(candidates_.end() - expired);
  candidates_.erase(expired, candidates_.end());
}

// Augment (unknown association): unpaired observation i supports the nearest tentative landmark
// within candidate_match_distance_m (or starts one); confirmed, it becomes a landmark.
void EkfSteps::augment_from_unpaired(std::size_t i, std::size_t k, double now_s) {
  const Observation& o = run_.observations[i];
  if (o.landmark_id != kSpuriousId) ++pass_.counts.true_unpaired;
  const Vector2 p_world = filter::landmark_from_range_bearing(ekf_.pose(), measurement(o));
  auto best = candidates_.end();
  double best_distance = options_.candidate_match_distance_m;
  for (auto it = candidates_.begin(); it != candidates_.end(); ++it) {
    if (it->last_step == k) continue;  // one observation per step and candidate
    const double distance = (it->p_world - p_world).norm();
    if (distance <= best_distance) {
      best = it;
      best_distance = distance;
    }
  }
  if (best == candidates_.end()) {
    candidates_.push_back({p_world, now_s, k, 1});
    best = candidates_.end() - 1;
  } else {
    ++best->support;
    best->last_step = k;
    best->p_world = p_world;
  }
  if (best->support >= options_.confirmations_to_create) {
    // Its position comes from this observation, so it stands for this observation's landmark.
    add_landmark(measurement(o), o.landmark_id, i);
    candidates_.erase(best);
  }
}

// A new landmark from observation z (unless the filter refuses it), labelled `label`.
void EkfSteps::add_landmark(const Vector2& z, std::int64_t label, std::size_t observation) {
  const std::optional<std::size_t> index = ekf_.add_landmark(z);
  if (!index) return;
  pass_.labels.push_back(label);
  pass_.landmark_observations.push_back(1);
  pass_.landmark_of_observation[observation] = *index;
  ++pass_.counts.landmarks_created;
}

// Record: the step's pose, its NEES against ground truth, and at a checkpoint the landmarks' NEES.
void EkfSteps::record_step(const Step& step, std::size_t k) {
  pass_.poses.push_back(ekf_.pose());

  const std::optional<Vector3> true_pose = truth_.pose(step.time);
  double pose_nees = kNaN;
  if (true_pose && k > 0) {
    if (const auto value = filter::pose_nees(ekf_.pose(), *true_pose, ekf_.pose_covariance())) {
      pose_nees = *value;
      nees_sum_ += pose_nees;
      ++nees_count_;
    }
  }
  if (next_checkpoint_ < checkpoints_.size() && checkpoints_[next_checkpoint_] == k) {
    ++next_checkpoint_;
    NeesPoint point;
    point.step = k;
    point.time_s = step.time.seconds();
    point.pose_nees = pose_nees;
    const auto [mean, count] = landmark_nees_mean(truth_, pass_.labels, [&](std::size_t l) {
      return std::make_pair(ekf_.landmark(l), ekf_.landmark_covariance(l));
    });
    point.landmark_nees_mean = mean;
    point.landmarks_evaluated = count;
    pass_.nees.push_back(point);
  }
}

// After the last step: mean NEES, the filter's counters, the scoring of the associations and
// the landmarks.
void EkfSteps::finish() {
  pass_.mean_pose_nees = nees_count_ == 0 ? kNaN : nees_sum_ / static_cast<double>(nees_count_);
  pass_.counters = ekf_.counters();
  if (options_.association != Association::kKnown) {
    label_landmarks_by_truth();
    score_pairings();
  }
  count_landmark_origins();
  count_spurious_rejected();
  output_landmarks();
}

// Scoring (unknown association): each estimated landmark stands for the true landmark nearest
// to its final estimate, if one lies within kLabelDistanceM (else it is counted as made from
// clutter); a pairing is correct when the observation came from that true landmark. Without a
// true map, the id of the creating observation is kept.
void EkfSteps::label_landmarks_by_truth() {
  constexpr double kLabelDistanceM = 1.0;
  if (!run_.true_landmarks.empty()) {
    for (std::size_t l = 0; l < ekf_.landmark_count(); ++l) {
      std::int64_t nearest = kSpuriousId;
      double nearest_distance = kLabelDistanceM;
      for (const auto& [id, p_true] : run_.true_landmarks) {
        const double distance = (ekf_.landmark(l) - p_true).norm();
        if (distance <= nearest_distance) {
          nearest = id;
          nearest_distance = distance;
        }
      }
      pass_.labels[l] = nearest;
    }
  }
}

// A pairing is correct when its observation came from the true landmark its landmark stands for.
void EkfSteps::score_pairings() {
  for (const auto& [i, l] : pairings_) {
    const std::int64_t id = run_.observations[i].landmark_id;
    if (id != kSpuriousId && pass_.labels[l] == id) {
      ++pass_.counts.paired_correct;
    } else {
      ++pass_.counts.paired_wrong;
      if (id == kSpuriousId) ++pass_.counts.spurious_paired;
    }
  }
}

// Landmarks made from clutter, and second (third...) landmarks for one true landmark.
void EkfSteps::count_landmark_origins() {
  std::set<std::int64_t> seen;
  for (const std::int64_t label : pass_.labels) {
    if (label == kSpuriousId) {
      ++pass_.counts.landmarks_from_spurious;
    } else if (!seen.insert(label).second) {
      ++pass_.counts.landmarks_duplicated;
    }
  }
}

// Clutter that never became (or updated) a landmark.
void EkfSteps::count_spurious_rejected() {
  for (std::size_t i = 0; i < run_.observations.size(); ++i) {
    if (run_.observations[i].landmark_id == kSpuriousId && !pass_.landmark_of_observation[i]) {
      ++pass_.counts.spurious_rejected;
    }
  }
}

// The filter's landmarks with their labels, covariances and observation counts.
void EkfSteps::output_landmarks() {
  for (std::size_t l = 0; l < ekf_.landmark_count(); ++l) {
    pass_.landmarks.push_back({pass_.labels[l], ekf_.landmark(l), ekf_.landmark_covariance(l), pass_.landmark_observations[l]});
  }
}

struct GraphPass {
  std::vector<Vector3> poses;
  std::vector<LandmarkEstimate> landmarks;
  std::vector<NeesPoint> nees;
  backend::LandmarkGraphSummary summary;
  double time_s = 0.0;
  double final_solve_s = 0.0;
  std::size_t solves = 0;  // every optimize() call: checkpoints and graph_solve_every_steps
  std::size_t steps_done = 0;  // < steps.size() when should_stop ended the pass
};

// The growing graph of run_graph: the variables and factors of the steps added so far, and the
// landmark variable of each association key (made at the key's first observation).
struct GraphBuild {
  GraphBuild(std::size_t keys, const LandmarkSlamOptions& options)
      : variable_of_key(keys), R(options.sensor.measurement_covariance()), R_information(R.inverse()) {}

  backend::LandmarkGraph2D graph;
  std::vector<std::optional<std::size_t>> variable_of_key;
  std::vector<std::int64_t> variable_labels;
  std::vector<std::size_t> variable_observations;
  Matrix2 R;
  Matrix2 R_information;
};

// Step `built` joins the graph: its pose (dead-reckoned from the last) with the odometry factor,
// then a range-bearing factor per associated observation, a landmark variable at a key's first.
void add_step_to_graph(const LandmarkRun& run, const Step& step, std::size_t built,
                       const std::vector<std::optional<std::size_t>>& landmark_key_of_observation,
                       const std::vector<std::int64_t>& key_labels, GraphBuild& build) {
  backend::LandmarkGraph2D& graph = build.graph;
  if (built == 0) {
    graph.poses.push_back(step.odometry);
  } else {
    graph.poses.push_back(filter::compose(graph.poses.back(), step.u));
    backend::OdometryFactor2D factor;
    factor.from = built - 1;
    factor.to = built;
    factor.u = step.u;
    factor.information = step.Q.inverse();
    graph.odometry.push_back(factor);
  }
  for (const std::size_t i : step.observations) {
    const auto& key = landmark_key_of_observation[i];
    if (!key) continue;
    const Vector2 z = measurement(run.observations[i]);
    if (!build.variable_of_key[*key]) {
      build.variable_of_key[*key] = graph.landmarks.size();
      graph.landmarks.push_back(filter::landmark_from_range_bearing(graph.poses.back(), z));
      build.variable_labels.push_back(key_labels[*key]);
      build.variable_observations.push_back(0);
    }
    backend::RangeBearingFactor2D factor;
    factor.pose = built;
    factor.landmark = *build.variable_of_key[*key];
    factor.z = z;
    factor.information = build.R_information;
    graph.observations.push_back(factor);
    ++build.variable_observations[factor.landmark];
  }
}

// Solves the graph at a checkpoint, with the marginals of its last pose and every landmark, and
// records the NEES there; at the last checkpoint (or when stopping) also the landmarks.
void solve_checkpoint(const std::vector<Step>& steps, const LandmarkSlamOptions& options, const Truth& truth,
                      std::size_t checkpoint, bool last, bool stopping, GraphBuild& build, GraphPass& pass) {
  backend::LandmarkGraph2D& graph = build.graph;
  const auto solve_start = Clock::now();
  pass.summary = backend::optimize(graph, options.graph);
  ++pass.solves;
  std::vector<std::size_t> all_landmarks(graph.landmarks.size());
  for (std::size_t l = 0; l < all_landmarks.size(); ++l) all_landmarks[l] = l;
  const backend::LandmarkGraphMarginals marginals =
      backend::marginal_covariances(graph, {graph.poses.size() - 1}, all_landmarks);
  pass.final_solve_s = seconds_since(solve_start);

  NeesPoint point;
  point.step = checkpoint;
  point.time_s = steps[checkpoint].time.seconds();
  point.pose_nees = kNaN;
  const std::optional<Vector3> true_pose = truth.pose(steps[checkpoint].time);
  if (true_pose && marginals.ok && checkpoint > 0) {
    if (const auto value = filter::pose_nees(graph.poses.back(), *true_pose, marginals.poses[0])) point.pose_nees = *value;
  }
  const auto [mean, count] = landmark_nees_mean(truth, build.variable_labels, [&](std::size_t l) {
    return std::make_pair(graph.landmarks[l], marginals.landmarks[l]);
  });
  point.landmark_nees_mean = marginals.ok ? mean : kNaN;
  point.landmarks_evaluated = marginals.ok ? count : 0;
  if (stopping && !pass.nees.empty() && pass.nees.back().step == checkpoint) pass.nees.pop_back();  // solved again
  pass.nees.push_back(point);
  if (last || stopping) {
    for (std::size_t l = 0; l < graph.landmarks.size(); ++l) {
      pass.landmarks.push_back({build.variable_labels[l], graph.landmarks[l], marginals.landmarks[l], build.variable_observations[l]});
    }
  }
}

// Graph SLAM over growing prefixes of the run, warm-started from the previous prefix.
GraphPass run_graph(const LandmarkRun& run, const std::vector<Step>& steps, const LandmarkSlamOptions& options,
                    const Truth& truth, const std::vector<std::size_t>& checkpoints,
                    const std::vector<std::optional<std::size_t>>& landmark_key_of_observation,
                    const std::vector<std::int64_t>& key_labels) {
  GraphPass pass;
  GraphBuild build(key_labels.size(), options);
  std::size_t built = 0;  // steps already in the graph
  const auto start = Clock::now();
  bool stopping = false;
  for (std::size_t checkpoint : checkpoints) {
    for (; built <= checkpoint; ++built) {
      if (built > 0 && options.should_stop && options.should_stop()) {
        // Interrupted: the graph built so far is solved as the last checkpoint.
        stopping = true;
        checkpoint = built - 1;
        break;
      }
      add_step_to_graph(run, steps[built], built, landmark_key_of_observation, key_labels, build);
      const int every = options.graph_solve_every_steps;
      if (every > 0 && built > 0 && built < checkpoint && built % static_cast<std::size_t>(every) == 0) {
        backend::optimize(build.graph, options.graph);
        ++pass.solves;
      }
    }
    solve_checkpoint(steps, options, truth, checkpoint, checkpoint == checkpoints.back(), stopping, build, pass);
    if (stopping) break;
  }
  pass.poses = build.graph.poses;
  pass.steps_done = build.graph.poses.size();
  pass.time_s = seconds_since(start);
  return pass;
}

// Interrupted (options.should_stop): what follows sees the run up to the last step processed.
void truncate_run(std::size_t done, std::vector<Step>& steps, std::vector<std::size_t>& checkpoints) {
  if (done >= steps.size()) return;
  steps.resize(done);
  while (!checkpoints.empty() && checkpoints.back() >= done) checkpoints.pop_back();
  if (checkpoints.empty() || checkpoints.back() != done - 1) checkpoints.push_back(done - 1);
}

// Graph SLAM's result: its poses and landmarks, and its part of the report.
void take_graph_pass(const GraphPass& graph, std::vector<Step>& steps, std::vector<std::size_t>& checkpoints,
                     std::vector<Vector3>& poses, LandmarkSlamResult& result) {
  LandmarkSlamReport& report = result.report;
  poses = graph.poses;
  truncate_run(graph.steps_done, steps, checkpoints);
  result.landmarks = graph.landmarks;
  report.nees = graph.nees;
  report.graph_summary = graph.summary;
  report.graph_time_s = graph.time_s;
  report.graph_final_solve_s = graph.final_solve_s;
  report.graph_solves = graph.solves;
  report.mean_pose_nees_all_steps = kNaN;
}

// The EKF, as the estimate (EKF method) or as the association front end of graph SLAM with
// unknown association.
void run_with_ekf(const LandmarkRun& run, const LandmarkSlamOptions& options, const Truth& truth,
                  std::vector<Step>& steps, std::vector<std::size_t>& checkpoints, std::size_t steps_in_run,
                  std::vector<Vector3>& poses, LandmarkSlamResult& result) {
  LandmarkSlamReport& report = result.report;
  EkfPass ekf = run_ekf(run, steps, options, truth, checkpoints);
  truncate_run(ekf.steps_done, steps, checkpoints);
  report.association_counts = ekf.counts;
  report.ekf_counters = ekf.counters;
  report.ekf_time_s = ekf.time_s;
  report.ekf_mean_step_s = ekf.mean_step_s;
  report.ekf_max_step_s = ekf.max_step_s;
  if (options.method == Method::kEkf) {
    poses = ekf.poses;
    result.landmarks = ekf.landmarks;
    report.nees = ekf.nees;
    report.mean_pose_nees_all_steps = ekf.mean_pose_nees;
  } else {
    // The EKF (the association front end) already stopped: the graph takes all it associated.
    LandmarkSlamOptions graph_options = options;
    if (steps.size() < steps_in_run) graph_options.should_stop = nullptr;
    const GraphPass graph =
        run_graph(run, steps, graph_options, truth, checkpoints, ekf.landmark_of_observation, ekf.labels);
    take_graph_pass(graph, steps, checkpoints, poses, result);
  }
}

// Known association: the landmark key is the id, numbered in order of first sight; invalid and
// unidentified observations get none.
void known_association_keys(const LandmarkRun& run, const LandmarkSlamOptions& options,
                            std::vector<std::optional<std::size_t>>& key_of_observation,
                            std::vector<std::int64_t>& labels, AssociationCounts& counts) {
  std::map<std::int64_t, std::size_t> key_of_id;
  for (std::size_t i = 0; i < run.observations.size(); ++i) {
    const Observation& o = run.observations[i];
    ++counts.observations;
    if (o.landmark_id == kSpuriousId) ++counts.spurious_observations;
    if (!(std::isfinite(o.range_m) && std::isfinite(o.bearing_rad) && o.range_m > options.sensor.min_range_m)) {
      ++counts.rejected_invalid;
      continue;
    }
    if (o.landmark_id == kSpuriousId) {
      ++counts.spurious_rejected;  // no identity: known association cannot use it
      continue;
    }
    const auto [it, inserted] = key_of_id.emplace(o.landmark_id, labels.size());
    if (inserted) {
      labels.push_back(o.landmark_id);
      ++counts.landmarks_created;
    } else {
      ++counts.paired_correct;
    }
    key_of_observation[i] = it->second;
  }
}

// Graph SLAM with known association.
void run_graph_known(const LandmarkRun& run, const LandmarkSlamOptions& options, const Truth& truth,
                     std::vector<Step>& steps, std::vector<std::size_t>& checkpoints, std::vector<Vector3>& poses,
                     LandmarkSlamResult& result) {
  std::vector<std::int64_t> labels;
  std::vector<std::optional<std::size_t>> key_of_observation(run.observations.size());
  known_association_keys(run, options, key_of_observation, labels, result.report.association_counts);
  const GraphPass graph = run_graph(run, steps, options, truth, checkpoints, key_of_observation, labels);
  take_graph_pass(graph, steps, checkpoints, poses, result);
}

// Errors of the trajectory against ground truth, no alignment (both in the world frame).
void score_trajectory(const Truth& truth, LandmarkSlamResult& result) {
  LandmarkSlamReport& report = result.report;
  double sum_squared = 0.0;
  report.ate_max_m = 0.0;
  report.final_position_error_m = kNaN;
  report.final_heading_error_rad = kNaN;
  for (const TimedPose& estimate : result.trajectory) {
    const std::optional<Vector3> true_pose = truth.pose(estimate.time);
    if (!true_pose) continue;
    const double error = (estimate.pose.head<2>() - true_pose->head<2>()).norm();
    sum_squared += error * error;
    report.ate_max_m = std::max(report.ate_max_m, error);
    ++report.ate_poses;
    report.final_position_error_m = error;
    report.final_heading_error_rad = std::abs(core::wrap_angle(estimate.pose.z() - true_pose->z()));
  }
  report.ate_rmse_m = report.ate_poses == 0 ? kNaN : std::sqrt(sum_squared / static_cast<double>(report.ate_poses));
  if (report.ate_poses == 0) report.ate_max_m = kNaN;
}

// RMS error of the landmarks that stand for a true landmark.
void score_landmarks(const Truth& truth, LandmarkSlamResult& result) {
  LandmarkSlamReport& report = result.report;
  double landmark_sum = 0.0;
  std::size_t landmark_count = 0;
  for (const LandmarkEstimate& l : result.landmarks) {
    const Vector2* p_true = truth.landmark(l.id);
    if (p_true == nullptr) continue;
    landmark_sum += (l.p_world - *p_true).squaredNorm();
    ++landmark_count;
  }
  report.landmark_rmse_m = landmark_count == 0 ? kNaN : std::sqrt(landmark_sum / static_cast<double>(landmark_count));
}

}  // namespace

std::string_view to_string(Method method) { return method == Method::kEkf ? "ekf" : "graph"; }

std::string_view to_string(Association association) {
  switch (association) {
    case Association::kKnown: return "known";
    case Association::kNearestNeighbour: return "nn";
    case Association::kJcbb: return "jcbb";
  }
  return "?";
}

std::optional<Method> method_from_name(std::string_view name) {
  if (name == "ekf") return Method::kEkf;
  if (name == "graph") return Method::kGraph;
  return std::nullopt;
}

std::optional<Association> association_from_name(std::string_view name) {
  if (name == "known") return Association::kKnown;
  if (name == "nn") return Association::kNearestNeighbour;
  if (name == "jcbb") return Association::kJcbb;
  return std::nullopt;
}

Matrix3 OdometryNoiseModel::covariance(const Vector3& u) const {
  const double d = u.head<2>().norm();
  const double a = std::abs(u.z());
  const double floor = floor_sigma * floor_sigma;
  Matrix3 Q = Matrix3::Zero();
  Q(0, 0) = inflation * forward_sigma_m_per_sqrt_m * forward_sigma_m_per_sqrt_m * d + floor;
  Q(1, 1) = inflation * lateral_sigma_m_per_sqrt_m * lateral_sigma_m_per_sqrt_m * d + floor;
  Q(2, 2) = inflation * (yaw_sigma_rad_per_sqrt_rad * yaw_sigma_rad_per_sqrt_rad * a +
                         yaw_sigma_rad_per_sqrt_m * yaw_sigma_rad_per_sqrt_m * d) +
            floor;
  return Q;
}

bool OdometryNoiseModel::is_valid(std::string* why) const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  for (const double sigma : {forward_sigma_m_per_sqrt_m, lateral_sigma_m_per_sqrt_m, yaw_sigma_rad_per_sqrt_rad,
                             yaw_sigma_rad_per_sqrt_m}) {
    if (!(sigma >= 0.0 && std::isfinite(sigma))) {
      add("odometry noise sigmas must be >= 0");
      break;
    }
  }
  // Beyond 1e6 the predicted covariance overflows within a few steps (a filter that knows
  // nothing of its motion is no filter).
  if (!(inflation > 0.0 && inflation <= 1e6)) add("odometry inflation must be in (0, 1e6]");
  if (!(floor_sigma > 0.0 && std::isfinite(floor_sigma))) add("odometry floor_sigma must be > 0");
  if (why != nullptr) *why = problems;
  return problems.empty();
}

bool LandmarkSlamOptions::is_valid(std::string* why) const {
  std::string problems;
  const auto add = [&](const std::string& p) {
    if (!p.empty()) problems += (problems.empty() ? "" : "; ") + p;
  };
  std::string text;
  if (!odometry.is_valid(&text)) add(text);
  if (!sensor.is_valid(&text)) add(text);
  if (!graph.is_valid(&text)) add(text);
  if (!(gating.gate_probability > 0.0 && gating.gate_probability < 1.0)) add("gate probability must be in (0, 1)");
  if (gating.max_jcbb_nodes < 1) add("max_jcbb_nodes must be >= 1");
  if (confirmations_to_create < 1) add("confirmations_to_create must be >= 1");
  if (!(candidate_match_distance_m > 0.0)) add("candidate_match_distance_m must be > 0");
  if (!(candidate_lifetime_s > 0.0)) add("candidate_lifetime_s must be > 0");
  if (nees_checkpoints < 1) add("nees_checkpoints must be >= 1");
  if (graph_solve_every_steps < 0) add("graph_solve_every_steps must be >= 0");
  if (why != nullptr) *why = problems;
  return problems.empty();
}

LandmarkSlamResult run_landmark_slam(const LandmarkRun& run, const LandmarkSlamOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "run_landmark_slam: invalid options (check LandmarkSlamOptions::is_valid)");
  CAIRN_ASSERT(!run.odometry.empty(), "run_landmark_slam: the run has no odometry");
  const auto start = Clock::now();
  std::vector<Step> steps = make_steps(run, options.odometry);
  const Truth truth(run);
  std::vector<std::size_t> checkpoints = checkpoint_steps(steps.size(), options.nees_checkpoints);
  const std::size_t steps_in_run = steps.size();

  LandmarkSlamResult result;
  LandmarkSlamReport& report = result.report;
  report.method = std::string(to_string(options.method));
  report.association = std::string(to_string(options.association));
  report.source = run.source;

  std::vector<Vector3> poses;
  // The EKF runs for the EKF method, and as the association front end for graph SLAM with
  // unknown association.
  if (options.method == Method::kEkf || options.association != Association::kKnown) {
    run_with_ekf(run, options, truth, steps, checkpoints, steps_in_run, poses, result);
  } else {
    run_graph_known(run, options, truth, steps, checkpoints, poses, result);
  }

  report.steps = steps.size();
  report.steps_in_run = steps_in_run;
  report.interrupted = steps.size() < steps_in_run;
  for (std::size_t k = 0; k < steps.size(); ++k) result.trajectory.push_back({steps[k].time, poses[k]});
  report.landmarks = result.landmarks.size();
  score_trajectory(truth, result);
  score_landmarks(truth, result);
  report.total_time_s = seconds_since(start);
  return result;
}

}  // namespace cairn::landmarks
