#pragma once
/// \file
/// Pure localisation in a saved 2D map (saved_map.hpp, map_file.hpp): scans go in one at a time
/// as into Slam2d::add_scan (an io::LaserScan with its odometry in T_odom_laser); each returns the
/// laser's pose in the map frame, a health state and a confidence. The map is never changed.
///
/// States:
///  - Searching (health `lost`; no pose is given): at the start ("not localised yet") and after
///    tracking failed ("lost"). Global relocalisation (Hess et al. ICRA 2016, sec. V-C:
///    branch-and-bound over a submap's precomputation grids): every scan searches
///    `global_searches_per_scan` submaps over their whole area (the path the map was built along
///    plus `global_search_margin_m`, every heading; place_search.hpp's global_window). Which
///    submaps: those whose max-pooled coarse grids score the scan best (one coarse branch and
///    bound per submap, the multi-resolution idea of Olson, ICRA 2009, applied across submaps;
///    at most one submap per place), plus `round_robin_searches_per_scan` in turn, nearest first
///    when there is a prior (the last pose before being lost, carried on by odometry), otherwise
///    in farthest-point order. A result counts only once it passed search_and_verify's
///    verification (ICP inliers and residual, every direction constrained, no other pose in the
///    submap nearly as good) with the stricter `verification_*` thresholds, and put almost no
///    scan point where the submap saw empty space (`verification_max_free_fraction`).
///  - Hypotheses: a verified match that agrees with no hypothesis starts one, the
///    map-from-odometry transform T_map_odom = T_map_laser * T_odom_laser^-1. On every following
///    scan each hypothesis is (a) followed as the tracking state tracks (ICP against the map from
///    its odometry prediction; `matching.lost_after_scans` scans in a row that do not fit there,
///    or a place that explains clearly less than the best one over the last scans
///    (`hypothesis_drop_*`), drop it) and (b) checked by a windowed search around its pose: a
///    verified match there is support. A hypothesis is accepted when verified matches on
///    `confirmations` distinct scans support it, one of them the current scan, no other
///    hypothesis is alive, and no other place of the scan's coarse ranking fits as well (refined
///    and matched by ICP against the whole map: per-submap verification cannot see a look-alike
///    in another submap), nor a partly mapped place as far as the map observed it, and the pose
///    puts no more scan points in any submap's empty space than verification allows
///    (`look_alike_*`). Zero wrong relocalisations matters more than speed: while two places
///    both explain the scans (a half-turn-symmetric building) the localiser stays `lost`.
///  - Tracking (health `ok` or `degraded`): prediction by odometry, point-to-line ICP (icp.hpp)
///    against one point map of every submap's points in the map frame, with the prediction as
///    a prior, as Slam2d's local matching. `degraded` when the inlier fraction is below
///    `ok_min_inlier_fraction`, the geometry is degenerate, the scan has too few returns, or a
///    match since the last verified one put scan points where the map saw empty space; a
///    match below `tracking_min_inlier_fraction` is a failure (the pose follows odometry:
///    `degraded`, `dead_reckoning`), and `matching.lost_after_scans` failures in a row make it
///    `lost` and start the search. A robot carried elsewhere is caught this way when its scans
///    stop matching where odometry says it is; when they still fit there (Intel's corridors
///    look alike), by the tracking check: every `check_every_n_scans` scans one submap is
///    searched over its whole area (the next in turn, or the best by coarse score when the scan
///    matches poorly); a verified match that disagrees with the tracked pose becomes a rival
///    hypothesis, followed as above. Once the rival is confirmed, the tracked pose is judged by
///    this scan's tracking match against the whole map with the verification thresholds (no
///    ambiguity test: continuity has already chosen between look-alike places): if it passes,
///    the rival is refuted and not followed again; if not, tracking ends (`lost`) with the
///    tracked pose kept as a hypothesis without support, so the rival is accepted only once the
///    scans stop fitting the tracked pose.
///
/// Every search is bounded: per scan one coarse ranking, at most `max_hypotheses` windowed
/// searches and ICP matches, and `global_searches_per_scan` whole-submap searches (one while
/// tracking), so no scan costs more than that (Intel, 96 submaps: at most 0.32 s per scan,
/// 0.155 s on average while searching, 8 ms while tracking).

#include <Eigen/Core>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/slam2d/saved_map.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::slam2d {

struct Localizer2dOptions {
  /// Matching and verification shared with Slam2d, with Slam2d's defaults (one place for them):
  /// `icp` (tracking, with the odometry prior), `loop_search` (precomputation depth, unknown
  /// probability; the windows are set per search), `loop_min_score` (branch-and-bound score
  /// every search must reach), `loop_max_rms_m`, `loop_ambiguity_*` (verification of every
  /// search), `degraded_min_degeneracy`, `min_matching_points`, `lost_after_scans` (health). The
  /// map's own settings replace `filter`, `map_points` and `grid` (scans must be matched as the
  /// map was built). The other fields are unused.
  Slam2dOptions matching;

  /// Tracking health. The map holds the whole place, so a right match explains most of a scan
  /// (on Intel's second half half of the tracked scans have an inlier fraction >= 0.9); a
  /// kidnapped robot matched 25 m away still explained 50-60 % of its scans in Intel's ring
  /// corridor. Inlier fraction below `ok_min_inlier_fraction`: degraded; below
  /// `tracking_min_inlier_fraction`: the match failed (odometry carries the pose, degraded;
  /// `matching.lost_after_scans` failures in a row: lost). In [0, 1], tracking <= ok.
  double tracking_min_inlier_fraction = 0.35;
  double ok_min_inlier_fraction = 0.7;

  /// Verification: the fraction of the scan's points within the ICP inlier distance of the
  /// submap's points, in [0, 1]. Replaces matching.loop_min_inlier_fraction (0.8): a robot in a
  /// room the map lacks sees one like it elsewhere (Intel's offices). Measured on 60 scans spread
  /// over Intel's second half, every submap of the first half's map searched, verified with 0.7:
  /// the 7 wrong matches had 0.70-0.85, 42 of the 52 right ones >= 0.9; with 0.9 a right match
  /// was found for 30 of 60 scans that lie on the map (37 with 0.85, 38 with 0.8). With 0.8 the
  /// second half had one wrong relocalisation (inlier fraction 0.83, a mirrored room 21 m away).
  double verification_min_inlier_fraction = 0.9;
  /// Verification: the match must constrain every direction at least this much (icp.hpp's
  /// degeneracy), in [0, 0.5]. Replaces matching.loop_min_degeneracy (0.1, for loop closures,
  /// which have no second scan to confirm them). Measured on 60 scans of Intel's second half in
  /// the map of its first half, every submap searched: 29 / 38 / 43 scans had a verified right
  /// match with 0.1 / 0.05 / 0.03, none a verified wrong one.
  double verification_min_degeneracy = 0.05;
  /// Verification: at most this fraction of the scan's matching points may lie where the
  /// matched submap saw empty space, in [0, 1]: in a cell whose 3 x 3 neighbourhood is observed
  /// and below occupancy 0.4. The inlier fraction cannot tell a place the map holds poorly from
  /// a look-alike the map holds well (what the map lacks and what contradicts it are both
  /// outliers); free space can: a point where the map saw through contradicts the match, a point
  /// where the map knows nothing does not. Measured: every right verified match in the
  /// simulated office 0 (static world), on Intel's second half <= 0.0075 (15 matches); the
  /// wrong ones that made a simulated kidnapping relocalise in a look-alike room 0.028-0.067.
  /// Tracking uses it too: a tracked match above it makes the pose `degraded` until a scan
  /// verifies it again (right tracked matches on Intel reach 0.15 where the map is poor, so it
  /// does not make a match fail).
  double verification_max_free_fraction = 0.02;
  /// Acceptance against the whole map, when a pose is about to be accepted (after the
  /// look-alike test of the coarse ranking):
  ///  1. the scan at the pose may put at most verification_max_free_fraction of its points
  ///     where any submap of the matched submap's segment saw empty space (verification checks
  ///     only the matched submap; an unmerged segment is placed by odometry alone, so other
  ///     segments are left out);
  ///  2. no partly mapped place may explain the scan as far as the map observed it: a place
  ///     whose sensor position lies in a cell some submap observed, where at least
  ///     `look_alike_min_observed_fraction` of the scan's points land in observed cells (or near
  ///     a map point), at least verification_min_inlier_fraction of those lie within the ICP
  ///     inlier distance of a map point, and at most verification_max_free_fraction of all of
  ///     them in observed empty space. Unobserved space is no evidence against a place: a robot
  ///     in a room the map saw only through its door sees what it would see in a twin room the
  ///     map holds whole, and the map's partial view of the true room fits it too. The sensor's
  ///     cell must be observed, or a corridor is refused for a place outside the building's
  ///     outer wall, where the map holds only that wall (measured: up to 30 scans' delay).
  ///     Candidates: the `look_alike_places` best places of the coarse ranking of the whole
  ///     scan, and half as many for each of two overlapping sectors (the first and the last two
  ///     thirds of the scan by bearing), since a partly mapped place scores low for the whole
  ///     scan (its unobserved part scores as unknown); each is refined (branch and bound in its
  ///     coarse cell, ICP against the whole map without a prior). A look-alike found is
  ///     followed (re-checked from its odometry prediction on the next attempts) and nothing is
  ///     accepted while it fits. Measured in simulation
  ///     (LocalizationSimulation.KidnappedIntoRoomsTenSeeds: a robot put down in a room the map
  ///     saw through its door): 6 of 10 seeds relocalised 7-21 m away without these tests, 1
  ///     with them but ranking the whole scan only (the true room, half observed, was not among
  ///     the ranked places), 0 with the sectors. At the true place 50-92 % of the points lay in
  ///     observed cells, none in observed empty space. `look_alike_min_observed_fraction` in
  ///     (0, 1]; `look_alike_places` >= 0, 0 disables test 2.
  double look_alike_min_observed_fraction = 0.5;
  int look_alike_places = 40;

  /// Searching: whole-submap searches per scan at full resolution; >= 1. Of these,
  /// `round_robin_searches_per_scan` take the next submaps in turn (nearest first with a prior,
  /// else farthest-point order), so every submap is searched in the end; the others take the
  /// submaps whose max-pooled grids score the scan best (branch and bound over every submap at
  /// `coarse_cell_factor` times the cell size, which costs about as much as one full search).
  /// Measured on 30 scans of Intel's second half: whenever a submap gave a verified right
  /// match, one of the three best by coarse score did (rank 0 for 8 of 10 scans, at most 3).
  int global_searches_per_scan = 3;
  int round_robin_searches_per_scan = 1;  ///< in [0, global_searches_per_scan]
  int coarse_cell_factor = 8;             ///< max-pooled cell = this x the map's cell (0.4 m); in [1, 64]
  int coarse_depth = 5;                   ///< precomputation grids of the coarse search; in [1, 12]
  /// A global search spans the path the map was built along in the submap (its keyframes'
  /// box) plus this margin, clamped to the submap's observed extent, every heading; metres,
  /// >= 0. Farther from the path the submap holds little of what a scan there sees.
  double global_search_margin_m = 3.0;
  /// Tracking check: every this many scans one whole-submap search runs while tracking (the next
  /// submap in turn; the best by coarse score when the inlier fraction is below
  /// ok_min_inlier_fraction); a verified match elsewhere that is confirmed (`confirmations`)
  /// while the tracked pose fails the verification thresholds ends tracking (a kidnapped robot
  /// whose scans still fit where it was). >= 1; a large value disables it in practice.
  int check_every_n_scans = 5;
  /// Distinct scans whose verified matches must agree before a pose is accepted; >= 1.
  int confirmations = 2;
  /// Two matches agree when the poses they give for the same scan (through the odometry)
  /// differ by at most these; > 0.
  double agreement_m = 0.3;
  double agreement_rad = 0.1;
  /// Confirmation search around a hypothesis' prediction: half-widths, >= 0 (the ambiguity
  /// test still spans matching.loop_ambiguity_window_m).
  double confirmation_window_m = 0.5;
  double confirmation_window_rad = 0.2;
  /// Among several hypotheses, one whose ICP inlier fraction falls short of the best one's by
  /// `hypothesis_drop_deficit` or more, summed over the last `hypothesis_drop_window_scans`
  /// scans, is dropped: its place explains clearly less of what the robot sees (the pillar that
  /// breaks a building's symmetry, seen through a door for 10 scans, is about 0.5). The sum of
  /// noise between two places that fit equally stays near 0.2 over 20 scans. > 0; >= 1.
  double hypothesis_drop_deficit = 0.5;
  int hypothesis_drop_window_scans = 20;
  /// Live hypotheses at most; a verified match that would start one more is ignored (no
  /// hypothesis is dropped to make room: that could leave a wrong one alone); >= 1.
  int max_hypotheses = 4;

  /// False with every problem when an option is out of range.
  bool is_valid(std::string* error) const;
};

/// Searching: no pose, the global search runs. Tracking: matched against the map.
enum class LocalizationState { kSearching, kTracking };
std::string_view to_string(LocalizationState state);

struct LocalizationResult {
  core::Timestamp time;
  LocalizationState state = LocalizationState::kSearching;
  Health health = Health::kLost;
  /// Whether T_map_laser holds a pose (tracking); false while searching: the localiser does not
  /// guess.
  bool localised = false;
  core::SE2 T_map_laser;
  /// The pose comes from odometry alone (tracking, but this scan's match failed or the scan
  /// had too few returns; health degraded): carried on, not measured.
  bool dead_reckoning = false;
  /// Fraction of the scan's matching points within the ICP inlier distance of the map (0 when
  /// not localised): how much of the scan the map explains.
  double confidence = 0.0;
  double degeneracy = 0.0;   ///< of the match (icp.hpp); < degraded_min_degeneracy: a corridor
  double rms_m = 0.0;        ///< point-to-line RMS of the inliers
  /// Tracking: fraction of the scan's matching points where the map saw empty space (the submap
  /// holding the pose; Localizer2dOptions::verification_max_free_fraction); above that maximum
  /// the pose is not `ok`.
  double free_space_fraction = 0.0;
  /// Covariance of the match, (x, y, theta), inverse ICP Hessian (Censi 2007; optimistic);
  /// zero when not localised or not invertible.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  bool relocalised = false;  ///< this scan accepted a relocalisation
  int matching_points = 0;
};

/// A verified match found while searching (the evidence of a relocalisation).
struct LocalizationMatch {
  std::size_t scan = 0;
  core::Timestamp time;
  int submap = 0;
  bool global = false;           ///< whole-submap search (else a confirmation search)
  double score = 0.0;            ///< branch-and-bound score
  double second_score = 0.0;     ///< best score elsewhere (ambiguity test)
  double inlier_fraction = 0.0;  ///< ICP verification
  double rms_m = 0.0;
  double degeneracy = 0.0;
  /// Fraction of the scan's matching points in space the submap saw empty (Localizer2dOptions::
  /// verification_max_free_fraction).
  double free_space_fraction = 0.0;
  core::SE2 T_map_laser;         ///< the verified pose of the scan
};

struct Relocalisation {
  std::size_t scan = 0;          ///< the scan that accepted it
  core::Timestamp time;
  core::SE2 T_map_laser;
  std::size_t searching_since_scan = 0;  ///< first scan of the search that ended here
  bool had_prior = false;        ///< searched nearest first from a pose before being lost
  std::vector<LocalizationMatch> evidence;  ///< the agreeing matches, oldest first
  std::size_t rival_hypotheses = 0;         ///< other hypotheses that died during the search
};

struct LocalizationTimes {
  double preprocess_s = 0.0;
  double tracking_s = 0.0;
  double global_search_s = 0.0;        ///< whole-submap searches with their verification
  double ranking_s = 0.0;              ///< coarse rankings of the submaps
  double confirmation_search_s = 0.0;  ///< following hypotheses: ICP and windowed searches
  double setup_s = 0.0;                ///< precomputation grids and point maps of the map
};

struct Localizer2dSummary {
  std::size_t scans = 0;
  std::size_t scans_ok = 0, scans_degraded = 0, scans_lost = 0;
  std::size_t scans_localised = 0;
  std::optional<std::size_t> first_localised_scan;
  std::size_t global_searches = 0;
  std::size_t rankings = 0;               ///< coarse rankings of every submap
  std::size_t confirmation_searches = 0;
  std::size_t verified_matches = 0;       ///< matches that passed verification
  std::size_t rejected_matches = 0;       ///< found by branch and bound, failed verification
  std::map<std::string, std::size_t> rejected_by_reason;  ///< place_search.hpp's reasons
  std::size_t hypotheses = 0;             ///< created
  std::size_t hypotheses_dropped = 0;     ///< the scans stopped fitting them (or merged with another)
  std::size_t hypotheses_ignored = 0;     ///< verified matches not followed: max_hypotheses alive
  std::size_t scans_ambiguous = 0;        ///< a hypothesis was confirmed but another place fits too
  std::size_t uniqueness_tests = 0;       ///< other places tested before accepting a pose
  std::size_t look_alikes = 0;            ///< ... that fitted as well (then followed as rivals)
  /// Acceptances refused because the pose put scan points where another submap saw empty space
  /// (Localizer2dOptions::look_alike_places, test 1).
  std::size_t refused_empty_space_elsewhere = 0;
  /// Acceptances refused because a partly mapped place explained what the map observed of the
  /// scan there (Localizer2dOptions::look_alike_places, test 2; counted in scans_ambiguous too).
  std::size_t partly_mapped_look_alikes = 0;
  std::size_t tracking_failures = 0;      ///< tracking matches below tracking_min_inlier_fraction
  std::size_t tracking_checks = 0;        ///< whole-submap searches while tracking
  std::size_t tracking_checks_agreeing = 0;  ///< ... whose verified match agreed with the tracked pose
  std::size_t tracking_contradicted = 0;  ///< tracking ended by a confirmed match elsewhere
  std::size_t rivals_refuted = 0;         ///< confirmed matches elsewhere while the tracked pose verified
  std::vector<Relocalisation> relocalisations;
  std::vector<HealthEvent> health_events;
  LocalizationTimes times;
  double total_s = 0.0;
  double max_scan_s = 0.0;          ///< slowest scan (setup excluded)
  double max_global_search_s = 0.0; ///< slowest single whole-submap search
  /// The map: submaps, points of the tracking map, memory of the precomputation grids.
  std::size_t map_submaps = 0;
  std::size_t map_points = 0;
  std::size_t precomputation_bytes = 0;
};

class Localizer2d {
 public:
  /// Builds the search structures of `map` (precomputation grids and point maps per submap, one
  /// point map of the whole map for tracking). Throws std::invalid_argument for invalid options
  /// or a map without any submap holding points. The map is copied and never changed.
  explicit Localizer2d(SavedMap2D map, const Localizer2dOptions& options = {});
  ~Localizer2d();
  Localizer2d(const Localizer2d&) = delete;
  Localizer2d& operator=(const Localizer2d&) = delete;

  /// Localises one scan; `scan.T_odom_laser` is its odometry (any frame, continuous).
  LocalizationResult add_scan(const io::LaserScan& scan);
  /// Optional: a prior for the search (where the robot was told it starts); the search then
  /// goes nearest first from there. It is not trusted: the pose is accepted only as any other
  /// (verified and confirmed).
  void set_prior(const core::SE2& T_map_laser_guess, const core::SE2& T_odom_laser);

  const SavedMap2D& map() const;
  const Localizer2dSummary& summary() const { return summary_; }
  LocalizationState state() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Localizer2dSummary summary_;
};

}  // namespace cairn::slam2d
