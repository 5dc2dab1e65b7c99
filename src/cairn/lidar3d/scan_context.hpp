#pragma once
/// \file
/// Scan Context place recognition: Kim & Kim, "Scan Context: Egocentric Spatial Descriptor for
/// Place Recognition within 3D Point Cloud Map", IROS 2018, as its authors' reference code does it
/// (github.com/gisbi-kim/scancontext and SC-A-LOAM `include/scancontext/Scancontext.cpp`: the
/// "variant key" fast alignment and the periodic k-d tree are theirs, not in the paper).
///
/// Descriptor (Sec. III-A): the plane around the sensor is cut into N_r rings of width
/// L_max / N_r and N_s sectors of 2 pi / N_s; bin (i, j) holds the highest z + h of the points that
/// fall in it (0 when empty), h = `sensor_height_m`, so the matrix is indexed
/// ring i = floor(r / (L_max / N_r)), r = sqrt(x^2 + y^2) < L_max (r = L_max joins the last ring),
/// sector j = floor(theta / (2 pi / N_s)), theta = atan2(y, x) in [0, 2 pi) counter-clockwise from
/// the sensor's x axis (forward). The reference's ceil(...) - 1 puts exact bin boundaries in the
/// bin below instead; nothing else depends on it.
///
/// Distance (Sec. III-B, eq. 5-7): d = 1 - mean over sectors j of the cosine similarity of query
/// column j and candidate column j + k (mod N_s); columns empty in either scan are left out of the
/// mean, as the reference does (the paper divides by N_s). D = min over the shift k, and the
/// minimising k gives the relative yaw (ScanContextMatch).
///
/// Search (Sec. III-C): a rotation-invariant "ring key" per scan (here the mean of each ring's
/// row, as the reference; the paper's ring key is each ring's occupancy ratio) is searched in a
/// k-d tree (nanoflann) for the `candidates` nearest previous scans, and each candidate is scored
/// with D. The candidates are only candidates: the distance says "these scans look alike", never
/// "these are the same place"; the caller verifies geometry (ICP from T_candidate_query =
/// (Rz(yaw_rad), t_candidate_query), ScanContextMatch) before it adds a loop closure.
///
/// Lateral offsets: the polar bins are centred on the sensor, so a revisit with a lateral offset
/// (another lane, above all a reverse revisit on the opposite lane) moves every near structure to
/// other rings and sectors and the distance grows quickly with the offset, while a yaw change alone
/// at the same place (even 180 degrees) costs nothing. `lateral_offsets_m` adds descriptors of the
/// query seen from virtual viewpoints beside the sensor and keeps the best: the lateral
/// augmentation ("root shifting") of Scan Context++ (Kim, Choi, Jo & Kim, T-RO 2021), applied here
/// to the query only and to the polar descriptor only. Measured on the simulated street (sim/
/// street_world.hpp, a 64-ring sensor; test_scan_context.cpp): a reverse revisit from the opposite
/// lane, 3.5 m across, scored 0.61-0.66 at its true yaw without views and 0.10-0.15 with offsets
/// {-4, -2, 2, 4} m (a side experiment at three places of that street; 0.118 in the test); without
/// them the best candidate in the test was the street's own symmetry instead, at a wrong yaw of 0
/// (0.162). On real KITTI scans the views left the
/// distances between different places unchanged (smallest 0.300 either way).

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace cairn::lidar3d {

struct ScanContextOptions {
  /// N_r, rings (> 0). Paper and reference: 20.
  int rings = 20;
  /// N_s, sectors (> 0): yaw resolution 2 pi / N_s (6 degrees at 60). Paper and reference: 60.
  int sectors = 60;
  /// L_max, radius of the descriptor, metres (> 0); farther points are ignored. Reference: 80.
  double max_radius_m = 80.0;
  /// h, added to every point's z before the bin maximum (the reference's LIDAR_HEIGHT = 2.0), so
  /// the ground seen from a sensor up to h above it gives positive heights; metres (>= 0). A bin
  /// whose highest z + h is still negative holds 0, like an empty one (the reference would store the
  /// negative number). 0 when the points are already in a frame on the ground.
  double sensor_height_m = 2.0;
  /// Nearest ring keys taken from the k-d tree and scored with the full distance (> 0). Paper and
  /// reference: 10.
  int candidates = 10;
  /// Fraction of the N_s column shifts tried, in [0, 1]: shifts within
  /// round(search_ratio N_s / 2) of the best alignment of the sector keys (the column means), as
  /// the reference's fastAlignUsingVkey/SEARCH_RATIO = 0.1 (7 of 60 shifts). 0 or 1: every shift
  /// (the paper's exhaustive eq. 6).
  double search_ratio = 0.1;
  /// Database entries whose id differs from the query's by less than this are not candidates
  /// (the reference's NUM_EXCLUDE_RECENT = 50: recent scans of the same pass always look alike);
  /// >= 0, in units of the ids given to add().
  int exclude_recent = 50;
  /// A candidate whose distance D is at most this is flagged `below_threshold`, in [0, 2]. The
  /// reference suggests 0.1-0.2 for 20 x 60 descriptors (0.2 in SC-A-LOAM). Measured on the 110
  /// real KITTI 00 HDL-64E key frames, which hold no revisit (tests/lidar3d/test_scan_context.cpp):
  /// scans more than 50 frames (>= 62 m) apart score 0.300 at least (median 0.49), scans 5 or more
  /// frames (~9 m) apart 0.217 at least, so 0.2 admits none of them; the same place seen from
  /// 1.8 m on (the next key frame) scores 0.11-0.28, median 0.17 (77% within 0.2), from 3.5 m on
  /// 0.19-0.41 (5% within). A pure yaw change costs up to 0.14 when it falls half a sector off the
  /// grid (0 at a whole number of sectors). So below 0.2 means "the same place within a few
  /// metres, or an aliased one": verify.
  double max_distance = 0.2;
  /// The k-d tree is rebuilt when this many entries have been added since it was last built
  /// (> 0). Entries not yet in the tree are compared by brute force, so none is missed; the period
  /// only trades rebuild time against the linear scan (the reference rebuilds every 30 to 50
  /// frames and does not see the newest ones meanwhile).
  int tree_rebuild_period = 50;
  /// Virtual viewpoints of the query, metres along the sensor's y axis (left), each non-zero and
  /// finite; empty: the scan's own viewpoint only (the paper and reference). Each offset costs one
  /// more descriptor per scan, one more ring-key search and up to `candidates` more comparisons
  /// per query. {-4, -2, 2, 4} finds reverse revisits on the opposite lane of a two-lane street
  /// (see the file comment) at no measured cost in distinctiveness on KITTI.
  std::vector<double> lateral_offsets_m;

  /// False with every problem, one per line, when an option is out of range.
  bool is_valid(std::string* error) const;
};

/// One scan's descriptor and keys. Invariant: descriptor is rings x sectors, entries >= 0;
/// ring_key has `rings` entries, sector_key `sectors`.
struct ScanContext {
  /// The viewpoint the descriptor was made from: the sensor moved by this along its y axis,
  /// metres (0 for the scan's own).
  double lateral_offset_m = 0.0;
  /// I = (a_ij), highest z + h per bin (paper eq. 4), 0 where empty.
  Eigen::MatrixXf descriptor;
  /// Mean of each row of `descriptor`: invariant to yaw (reference's makeRingkeyFromScancontext).
  Eigen::VectorXf ring_key;
  /// Mean of each column: turns with the sensor (reference's makeSectorkeyFromScancontext).
  Eigen::VectorXf sector_key;
  /// The same scan seen from options.lateral_offsets_m, in that order (each without views of its
  /// own); used only when this context is the query.
  std::vector<ScanContext> lateral_views;
};

/// The descriptor of `points_sensor`, points in the sensor frame (x forward, y left, z up, metres),
/// ideally one full revolution. Non-finite points and points at a horizontal range > max_radius_m
/// (from the viewpoint) are ignored. Fills lateral_views for options.lateral_offsets_m.
/// Precondition: options.is_valid().
ScanContext make_scan_context(const std::vector<Eigen::Vector3d>& points_sensor, const ScanContextOptions& options);

/// The context of a stored descriptor (a saved map's keyframe, saved_map.hpp): the descriptor with
/// its ring and sector keys recomputed exactly as make_scan_context computes them, no lateral views.
/// Precondition: entries finite and >= 0.
ScanContext scan_context_from_descriptor(Eigen::MatrixXf descriptor);

/// Best column alignment of two descriptors.
///
/// Sign convention: query column j lines up with candidate column (j + shift_sectors) mod N_s,
/// i.e. what the query sees at azimuth theta the candidate saw at theta + yaw_rad. So
/// yaw_rad is the rotation about z taking query-frame directions to candidate-frame directions,
/// R_candidate_query = Rz(yaw_rad), and a verifier starts ICP (aligning the query scan to the
/// candidate's) from T_candidate_query = (Rz(yaw_rad), t_candidate_query). The SC-A-LOAM reference
/// returns the opposite sign (its column shift moves the candidate the other way).
///
/// When a lateral view of the query matched best (lateral_offset_m = o != 0), the candidate's
/// sensor is taken to stand at the virtual viewpoint t_query_view = (0, o, 0), so
/// T_candidate_query = T_candidate_view T_view_query = (Rz(yaw), -Rz(yaw) (0, o, 0)): within about
/// half the spacing of the offsets (and the key-frame spacing along the road) of the truth.
struct ScanContextMatch {
  /// D of eq. 6, in [0, 1] for non-negative descriptors: 0 = identical up to the shift; 1 when no
  /// sector is occupied in both.
  double distance = 1.0;
  /// In [0, N_s).
  int shift_sectors = 0;
  /// shift_sectors * 2 pi / N_s, wrapped to (-pi, pi]. The true yaw lies within about one sector
  /// of it (bins quantise the azimuth).
  double yaw_rad = 0.0;
  /// The query view that matched: 0 (the scan itself) or one of options.lateral_offsets_m.
  double lateral_offset_m = 0.0;
  /// Initial guess of the candidate-frame position of the query's sensor, metres: zero unless a
  /// lateral view matched (see above).
  Eigen::Vector3d t_candidate_query = Eigen::Vector3d::Zero();
};

/// D(query, candidate) and its alignment (eq. 5-7), with the shift search narrowed by the sector
/// keys unless search_ratio is 0 or 1; the smallest over the query and its lateral views (the
/// candidate's views are not used). Precondition: both made with these options' rings and sectors.
ScanContextMatch compare(const ScanContext& query, const ScanContext& candidate, const ScanContextOptions& options);

/// One candidate returned by ScanContextDatabase::query.
struct LoopCandidate {
  int id = -1;
  /// Euclidean distance of the ring keys, metres of height (the first, coarse phase).
  double ring_key_distance = 0.0;
  ScanContextMatch match;
  /// match.distance <= options.max_distance.
  bool below_threshold = false;
};

/// The scans seen so far, searchable by descriptor (paper Sec. III-C, two-phase search). Not
/// thread-safe: query() may rebuild the tree.
class ScanContextDatabase {
 public:
  /// Throws std::invalid_argument, listing every problem, if the options are invalid.
  explicit ScanContextDatabase(const ScanContextOptions& options = {});
  ~ScanContextDatabase();
  ScanContextDatabase(ScanContextDatabase&&) noexcept;
  ScanContextDatabase& operator=(ScanContextDatabase&&) noexcept;
  ScanContextDatabase(const ScanContextDatabase&) = delete;
  ScanContextDatabase& operator=(const ScanContextDatabase&) = delete;

  /// Stores `context` under `id` (e.g. the key-frame index), without its lateral views (stored
  /// scans are compared from their own viewpoint). Preconditions: made with these options' rings
  /// and sectors; `id` not stored yet.
  void add(int id, ScanContext context);

  /// Up to `candidates` stored scans nearest to `query` by ring key (to the query's own ring key or
  /// any of its lateral views'), leaving out ids with |id - query_id| < exclude_recent, each scored
  /// with compare() and sorted by increasing match.distance (ties by id); with lateral views, the
  /// `candidates` best of the union. All of them are returned, below the threshold or not, so the
  /// caller can test the best against the second best (uniqueness) before verifying the best with
  /// ICP. Empty when nothing is eligible. `query` need not have been added.
  std::vector<LoopCandidate> query(const ScanContext& query, int query_id);

  std::size_t size() const { return ids_.size(); }
  const ScanContextOptions& options() const { return options_; }
  /// The stored context of `id`, or nullptr.
  const ScanContext* find(int id) const;

 private:
  struct Tree;
  void rebuild_tree();
  /// Appends the up to `candidates` eligible entries nearest to `key` as (squared distance, entry).
  void nearest_ring_keys(const Eigen::VectorXf& key, const std::function<bool(std::size_t)>& eligible,
                         std::vector<std::pair<float, std::size_t>>& nearest) const;

  ScanContextOptions options_;
  std::vector<int> ids_;
  std::vector<ScanContext> contexts_;
  /// Ring keys one after another (rings floats per entry), the tree's data.
  std::vector<float> ring_keys_;
  std::unique_ptr<Tree> tree_;
  /// Entries [0, tree_entries_) are in the tree, the rest are scanned.
  std::size_t tree_entries_ = 0;
};

}  // namespace cairn::lidar3d
