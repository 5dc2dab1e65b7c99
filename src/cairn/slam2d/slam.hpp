#pragma once
/// \file
/// The streaming 2D LiDAR SLAM pipeline. One scan (with the odometry pose the robot reported for
/// it) at a time goes in; `add_scan` returns the scan's pose and health at once, so a live robot
/// drives it exactly as `cairn slam2d` does with a log.
///
/// Structure (after Cartographer, Hess et al. ICRA 2016, with a point-to-line front end):
///  - Local SLAM: each scan is preprocessed (range_scan.hpp), predicted by odometry and aligned
///    to a local map made of the last `local_map_keyframes` keyframes by point-to-line ICP with
///    the odometry prediction as prior (icp.hpp). Local poses T_local_laser drift slowly.
///  - Keyframes (graph nodes): a scan becomes a keyframe when the motion since the last one
///    exceeds `keyframe_distance_m` or `keyframe_angle_rad`; every other scan keeps its pose
///    relative to the keyframe before it. Consecutive keyframes are joined by the local match.
///  - Submaps: `submap_keyframes` consecutive keyframes, a new one started every half of that
///    (two overlapping submaps are active, as in Cartographer), rendered into a probability grid
///    in the frame of their first keyframe (the anchor) once finished.
///  - Loop closure: every `loop_search_every_n_keyframes`-th keyframe is searched against every
///    finished submap within `loop_max_distance_m` by branch-and-bound (branch_and_bound.hpp),
///    in a window growing with the path travelled since the submap (the drift it may have);
///    a candidate above `loop_min_score` is refined by ICP against the submap's points and
///    verified: enough inliers, small residual, and unambiguous (no other pose farther than
///    `loop_ambiguity_distance_m` scores within `loop_ambiguity_margin` of it). Accepted loops
///    become graph edges; the back end's GNC (Yang et al. 2020) has the last word at the end.
///  - Back end: the pose graph of keyframes, optimised (Levenberg-Marquardt) whenever new loop
///    closures have arrived and `optimize_every_n_keyframes` keyframes have passed.
///  - Health: per scan, the match's inlier fraction and degeneracy (icp.hpp). `degraded` when the
///    scan constrains the pose poorly (the odometry prior then carries the unobservable
///    direction), `lost` after `lost_after_scans` consecutive failed matches.
///  - Map segments (ORB-SLAM3's Atlas, Campos et al. T-RO 2021, sec. III; Cartographer's new
///    trajectory per session): being lost never lasts. The scan that makes the state `lost`
///    seeds a new map segment: the local map and the submaps restart from it, so the robot keeps
///    mapping wherever there is structure. The seed is on probation (still `lost`) until
///    `segment_confirm_scans` scans in a row match it; one that does not is dropped and the next
///    scan seeds again (a burst of garbage never becomes a map). The segment hangs from the
///    previous one by odometry with an inflated covariance (`segment_link_*_sigma`), so the graph
///    stays connected; its placement is odometry only until it is merged.
///  - Merging: segments not joined by a loop closure (groups) are searched for each other. A
///    verified match across groups proposes a placement (the rigid move of the keyframe's group
///    onto the matched one); later keyframes test it where it puts them. A placement is merged
///    after `merge_confirmations` agreeing verified matches from distinct keyframes supporting
///    `merge_min_spread_corroborated_m` of path when it agrees with a trusted odometry link
///    (moves the keyframe less than `merge_odometry_radius_m` / `merge_odometry_angle_rad`, and
///    every segment link between the two is SegmentInfo::odometry_link_trusted), or
///    `merge_min_spread_m` when it does not (the path between consecutive supporting keyframes,
///    each gap counted up to `merge_support_gap_m`), and then only if no other supported
///    placement of the same groups competes (for a corroborated one: no other near the odometry
///    link) and, when not corroborated, the scan is unique over the whole map (no submap of
///    another group scores within the ambiguity margin elsewhere, every heading). A placement
///    not found again where
///    it says `merge_max_misses_in_a_row` times is dropped; for a placement far from the
///    odometry link, a search that finds nothing counts against it only where the other group's
///    robot passed (`merge_miss_coverage_m`), so a kidnapping's right placement survives the
///    stretches the other map never saw. The merged group moves
///    rigidly onto the other, the matches become loop-closure edges, the graph is solved, and
///    GNC still has the last word at the end. A wrong merge is as bad as a wrong loop: a kidnapped
///    robot in an unmapped twin of a mapped room (a floor plan symmetric under a half turn) sees
///    exactly what it would see in the twin, which is why the placements odometry does not
///    support need a long path of consistent evidence.
///  - Search budget (no log can make the search quadratic): every keyframe adds
///    `search_budget_per_keyframe` tokens to a bucket holding at most `search_budget_burst`; a
///    windowed search costs one. Priority within a keyframe: tests of pending placements, merge
///    searches around the estimate, then loop searches within the group (nearest first). While
///    other groups exist, one search over a whole submap of another group (every heading, points
///    within `global_search_max_range_m`) every `global_search_every_n_keyframes` keyframes,
///    round-robin over them. What the budget skipped is counted.
///  - Threads: a keyframe's searches run as one background job while the front end goes on; it
///    is joined, and its results taken in a fixed order, when the next keyframe is made (or at
///    finish()). The submaps a keyframe fills are built in another background job and installed
///    `submap_install_delay_keyframes` keyframes later (or when a segment closes, or at
///    finish()). Both join at fixed keyframes, so the results never depend on timing. Each
///    keyframe's rays go into its active submaps' grids in the background as it comes (a
///    low-priority arena, waited for only by a build or a change to the keyframes), so a build
///    adds the last keyframes and computes the precomputation grids (on huge pages).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/health.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/pose_graph.hpp"
#include "cairn/slam2d/branch_and_bound.hpp"
#include "cairn/slam2d/icp.hpp"
#include "cairn/slam2d/point_map.hpp"
#include "cairn/slam2d/probability_grid.hpp"
#include "cairn/slam2d/range_scan.hpp"
#include "cairn/slam2d/saved_map.hpp"

namespace cairn::slam2d {

struct Slam2dOptions {
  ScanFilterOptions filter;
  PointMapOptions map_points;          ///< local map and submap point maps
  IcpOptions icp;                      ///< local matching (scan to local map)
  ProbabilityGridOptions grid;         ///< submap grids and the final map

  double keyframe_distance_m = 0.2;    ///< motion that makes a keyframe; > 0
  double keyframe_angle_rad = 0.1;     ///< (5.7 degrees); > 0
  int local_map_keyframes = 8;         ///< keyframes in the local map; >= 1
  int submap_keyframes = 40;           ///< keyframes per submap; >= 2

  /// Windows are the largest the search may use; the angle step from the 90th percentile of the
  /// ranges (measured: half the loop-search time on ACES and Intel, relations equal to 4 digits).
  BranchAndBoundOptions loop_search = {7.0, 0.5236, 7, 0.1, 0.9};
  int loop_search_every_n_keyframes = 2;
  double loop_max_distance_m = 15.0;   ///< keyframe to submap centre, current estimate
  int loop_max_submaps_per_search = 4; ///< the nearest finished submaps searched per keyframe
  /// A full submap is built in the background and becomes searchable this many keyframes later;
  /// >= 1. 10 made MIT CSAIL 1.2x faster but accepted 3 false loop closures (10.4 m off) in the
  /// simulated building yard, seed 10, where 1 accepts none: the newest submap searchable later
  /// means fewer loops and wider drift windows (docs/benchmarks.md, 2026-11-30). Keep 1.
  int submap_install_delay_keyframes = 1;
  /// Search window = base + drift_per_metre * d, clamped to loop_search's windows, where d is
  /// the path length between submap and keyframe or since the last accepted loop closure,
  /// whichever is shorter (the drift the estimate may have).
  double loop_window_base_m = 0.5;
  double loop_window_drift_per_m = 0.03;
  double loop_angle_window_base_rad = 0.1;
  double loop_angle_window_drift_per_m = 0.003;
  double loop_min_score = 0.6;         ///< branch-and-bound score (mean probability)
  /// Relocalisation (while matching fails) accepts a lower search score: the scan may see space the
  /// map does not hold yet. The ICP and ambiguity verification are the same as for loops.
  double relocalisation_min_score = 0.5;
  double loop_min_inlier_fraction = 0.8;  ///< ICP verification against the submap points
  double loop_max_rms_m = 0.03;
  double loop_min_degeneracy = 0.1;    ///< verification: the match constrains every direction
  /// Verification: at least this many of the scan's points within inlier distance of the map. A
  /// match of a few posts (10-20 returns) has no redundancy against a submap the drift of a
  /// sparse stretch distorted: on issue 41's sparse open stretch such closures were up to 0.5 m
  /// off at inlier fraction 1.0 (docs/slam2d.md, Known limits).
  int loop_min_inliers = 30;
  /// The ambiguity search spans at least this half-width, whatever the match window (repeated
  /// structure such as identical doors lies farther away than a small match window reaches).
  double loop_ambiguity_window_m = 3.0;
  /// The ambiguity search also spans the drift the estimate may have (window base + drift per
  /// metre of path, uncapped by the search window) up to this half-width.
  double loop_ambiguity_max_window_m = 30.0;
  double loop_ambiguity_distance_m = 0.6;
  double loop_ambiguity_angle_rad = 0.15;
  double loop_ambiguity_margin = 0.06;  ///< best score - best elsewhere must exceed this

  /// Edge noise of the pose graph (standard deviations).
  double odometry_translation_sigma_m = 0.02;
  double odometry_rotation_sigma_rad = 0.005;
  double loop_translation_sigma_m = 0.05;
  double loop_rotation_sigma_rad = 0.01;
  int optimize_every_n_keyframes = 20;
  bool final_gnc = true;               ///< GNC over loop closures at finish()
  /// Keyframe edges: covariance = odometry sigmas^2 + the covariance of the keyframe's match,
  /// (H_scan + H_prior)^-1 (Censi 2007 first-order estimate, with the ICP prior), rotated into the
  /// edge's frame. Where the match is degenerate (a corridor) the edge is weak along the
  /// unobservable direction, so loop closures can move the chain along it. false: odometry sigmas only.
  bool edge_covariance_from_matcher = true;
  double output_map_resolution_m = 0.05;  ///< cell of the written map (PGM, PNG); > 0

  double degraded_min_inlier_fraction = 0.5;
  double degraded_min_degeneracy = 0.03;
  int min_matching_points = 10;        ///< fewer returns: no match, degraded, odometry only
  int lost_after_scans = 5;            ///< consecutive matches below lost_inlier_fraction
  double lost_inlier_fraction = 0.25;
  /// A failed match (below lost_inlier_fraction) where at most this share of the scan's rays,
  /// cast from the odometry prediction (returns, and no-returns up to the filter's
  /// missing_ray_length_m), pass through a point of the local map sees structure the local map
  /// does not hold and contradicts nothing it does: newly visible posts in open space, not a
  /// kidnapping (whose rays cross mapped walls). Such a scan is `degraded`, placed by odometry,
  /// its points enter the map, and it does not count towards lost_after_scans. Negative: every
  /// failed match counts (the behaviour before issue 41).
  double new_space_max_rays_through = 0.05;

  /// Map segments and merging (see the file comment).
  double segment_link_translation_sigma_m = 10.0;  ///< the weak edge joining a new segment
  double segment_link_rotation_sigma_rad = 3.0;
  /// A segment lost with fewer keyframes than this is restarted in place (no new segment).
  int min_segment_keyframes = 3;
  /// A (re)started segment is on probation (still `lost`) until this many scans in a row match
  /// its map with at least degraded_min_inlier_fraction; a failure drops the seed and reseeds.
  int segment_confirm_scans = 3;
  /// A new segment's odometry link is trusted (SegmentInfo::odometry_link_trusted) when the
  /// failed matches that declared it lost explained at least this share of their scans at the
  /// predicted pose on average (the map fits poorly where the robot is), or once a seed of it is
  /// dropped on probation (garbage); otherwise the robot may have been carried.
  double segment_trusted_link_min_inlier_fraction = 0.1;
  int merge_searches_per_keyframe = 2;       ///< windowed merge searches, nearest submaps first
  double merge_max_distance_m = 30.0;        ///< windowed merge searches: submap centre distance
  /// While other groups exist, one whole-submap search every this many keyframes (outside the
  /// token budget: a fixed cadence bounds it).
  int global_search_every_n_keyframes = 8;
  double merge_agreement_m = 0.5;            ///< two matches agree on the relative placement ...
  double merge_agreement_rad = 0.1;          ///< ... within these
  int merge_confirmations = 3;               ///< agreeing matches (distinct keyframes) to merge ...
  double merge_min_spread_m = 40.0;          ///< ... supporting at least this much path, or ...
  double merge_min_spread_corroborated_m = 2.0;  ///< ... this much when odometry agrees:
  double merge_odometry_radius_m = 3.0;      ///< the merge moves the keyframe less than this ...
  double merge_odometry_angle_rad = 0.3;     ///< ... and turns it less than this
  int merge_max_misses_in_a_row = 10;        ///< a placement not found this often in a row is dropped
  /// The path a placement's support covers: the path between consecutive supporting keyframes,
  /// each gap counted up to this (a stretch where the other map found nothing supports nothing).
  double merge_support_gap_m = 3.0;
  /// A test that finds nothing where a placement far from the odometry link puts the keyframe
  /// counts against it only when a keyframe of the other group lies within this of that pose
  /// (its robot was there).
  double merge_miss_coverage_m = 2.0;
  /// Global searches and the merge's map-wide uniqueness test use the scan's points within this
  /// range (a coarser angle step); verification always uses all of them.
  double global_search_max_range_m = 10.0;
  /// Search budget (see the file comment).
  double search_budget_per_keyframe = 2.5;
  double search_budget_burst = 40.0;

  /// Polled before every pose-graph optimisation and by its solver (not a configuration key):
  /// true skips the optimisation, or ends it at its last accepted step; a GNC solve cut short
  /// changes nothing. The CLI stops on SIGINT/SIGTERM this way. May be empty.
  std::function<bool()> should_stop;

  /// False with the reason when an option is out of range.
  bool is_valid(std::string* error) const;
};

using core::Health;  // ok / degraded / lost (core/health.hpp)
using core::to_string;

struct ScanResult {
  core::Timestamp time;
  core::SE2 T_world_laser;     ///< current global estimate (changes after optimisations)
  Health health = Health::kOk;
  double inlier_fraction = 0.0;
  double degeneracy = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< of the local match, (x, y, theta)
  bool keyframe = false;
  int segment = 0;             ///< map segment (Slam2dSummary::segments)
};

struct LoopCandidate {
  int keyframe = 0;
  int submap = 0;
  int anchor_keyframe = 0;
  core::Timestamp time;          ///< of the keyframe's scan
  core::Timestamp anchor_time;   ///< of the submap anchor's scan
  double search_window_m = 0.0;
  double score = 0.0;             ///< branch-and-bound score, 0 when nothing above min_score
  double second_score = 0.0;      ///< best score away from the match (ambiguity)
  double inlier_fraction = 0.0;   ///< ICP verification
  double rms_m = 0.0;
  double degeneracy = 0.0;        ///< of the ICP verification (icp.hpp)
  core::SE2 T_anchor_keyframe;    ///< the verified relative pose (when found)
  bool accepted = false;          ///< passed verification and became an edge
  bool rejected_by_gnc = false;   ///< an accepted edge the back end rejected at finish()
  bool relocalisation = false;
  bool merge = false;             ///< searched across map segments (merge search)
  bool global = false;            ///< searched over the whole submap and every heading
  std::string reason;             ///< why rejected, or "accepted"
  /// For a match across map segments (its keyframe's group and its submap's differ when it was
  /// found), what became of it as merge evidence: "failed verification", "awaiting support",
  /// "competing placement", "awaiting the uniqueness test", "ambiguous", "merged" (it confirmed
  /// a merge) or "superseded" (a merge earlier in the same batch joined the groups and it
  /// disagrees); "" for a match within one segment group.
  std::string merge_decision;
};

/// One map segment: a stretch of the run mapped on its own after the previous one was lost.
struct SegmentInfo {
  int id = 0;
  std::size_t first_scan = 0;
  std::size_t scans = 0;
  int first_keyframe = 0;
  int keyframes = 0;
  double path_length_m = 0.0;
  std::string started_because;    ///< empty for the first segment
  /// Whether the odometry across the loss that started it may place it: true when the failed
  /// matches that declared it lost still explained part of their scans at the predicted pose
  /// (Slam2dOptions::segment_trusted_link_min_inlier_fraction: the map fits poorly where the
  /// robot is), or when a seed of it was dropped on probation (the failed scans did not even
  /// match each other: a sensor fault while the wheels went on); false when the scans matched
  /// nothing at the prediction yet formed a consistent view (the robot may have been carried).
  /// Only a trusted chain of segment links lets odometry corroborate a merge. Always true for
  /// the first segment.
  bool odometry_link_trusted = true;
  /// The segment it ended up joined with (the lowest id of its group; itself when unmerged
  /// with any lower segment). Filled at finish() and by merges.
  int merged_with = 0;
  /// Merge searches (windowed and whole-submap) its keyframes made into other segments' submaps.
  std::size_t merge_searches = 0;
  /// For a segment not joined with segment 0 at finish(): why, from what its keyframes' merge
  /// searches found (LoopCandidate::merge_decision), the first that applies: "no merge search
  /// ...", "no candidate ...", "ambiguous ...", "not enough support ...", "failed verification
  /// ..."; empty for a segment joined with segment 0.
  std::string why_not_merged;
  Eigen::Vector2d min_world = Eigen::Vector2d::Zero();  ///< keyframe extent, current estimate
  Eigen::Vector2d max_world = Eigen::Vector2d::Zero();
};

/// Two groups of segments joined by confirmed matches.
struct MergeEvent {
  core::Timestamp time;
  std::size_t scan = 0;
  int segment_a = 0;  ///< the group of the matched submap
  int segment_b = 0;  ///< the group of the searching keyframe
  std::vector<int> candidates;  ///< indices into Slam2dSummary::candidates (the evidence)
  double moved_m = 0.0;         ///< how far the merged group's newest keyframe moved
};

struct HealthEvent {
  core::Timestamp time;
  std::size_t scan = 0;
  Health from = Health::kOk;
  Health to = Health::kOk;
  std::string reason;
};

struct StageTimes {
  double preprocess_s = 0.0;
  double local_match_s = 0.0;
  double local_map_s = 0.0;
  double submap_s = 0.0;
  double loop_search_s = 0.0;  ///< loop, merge and global searches with their verification
  double global_search_s = 0.0;  ///< of which whole-submap searches (CPU time, summed over threads)
  double optimize_s = 0.0;
};

struct Slam2dSummary {
  std::size_t scans = 0;
  std::size_t keyframes = 0;
  std::size_t submaps = 0;
  std::size_t optimizations = 0;
  std::size_t loop_searches = 0;
  std::size_t loops_accepted = 0;
  std::size_t loops_rejected_by_gnc = 0;
  std::size_t scans_ok = 0, scans_degraded = 0, scans_lost = 0;
  std::size_t relocalisations = 0;
  /// Failed matches that saw only new structure (Slam2dOptions::new_space_max_rays_through).
  std::size_t scans_new_space = 0;
  std::size_t merge_searches = 0;
  std::size_t global_searches = 0;
  std::size_t searches_skipped_by_budget = 0;
  std::size_t uniqueness_searches = 0;       ///< submaps searched by merges' uniqueness tests
  std::size_t merges_refused_as_ambiguous = 0;
  std::vector<SegmentInfo> segments;
  std::vector<MergeEvent> merges;
  std::vector<LoopCandidate> candidates;  ///< every verified-or-rejected candidate above min score
  std::vector<HealthEvent> health_events;
  StageTimes times;
  double total_s = 0.0;
};

class Slam2d {
 public:
  explicit Slam2d(const Slam2dOptions& options = {});
  ~Slam2d();
  Slam2d(const Slam2d&) = delete;
  Slam2d& operator=(const Slam2d&) = delete;

  /// Processes one scan; `scan.T_odom_laser` is the odometry prediction (raw CARMEN logs carry
  /// odometry there).
  ScanResult add_scan(const io::LaserScan& scan);
  /// Final optimisation (GNC over loop closures if enabled). Further scans may still be added.
  void finish();

  /// Global poses of every scan added, in input order.
  std::vector<ScanResult> trajectory() const;
  /// The keyframe pose graph with current estimates (vertex id = keyframe index).
  io::PoseGraph2D pose_graph() const;
  /// Probability grid of all keyframes at their current global poses.
  ProbabilityGrid render_map(const ProbabilityGridOptions& options) const;
  /// The map for reuse (saved_map.hpp): every submap with keyframes that carry points, rendered
  /// at the current global poses.
  SavedMap2D export_map() const;
  const Slam2dSummary& summary() const { return summary_; }
  Health health() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Slam2dSummary summary_;
};

}  // namespace cairn::slam2d
