#include "cairn/lidar3d/scan_context.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <nanoflann.hpp>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"

namespace cairn::lidar3d {

bool ScanContextOptions::is_valid(std::string* error) const {
  core::Problems problems;
  auto check = [&](bool ok, const char* message) {
    if (!ok) problems.add(message);
  };
  check(rings > 0, "rings must be > 0");
  check(sectors > 0, "sectors must be > 0");
  check(max_radius_m > 0.0 && std::isfinite(max_radius_m), "max_radius_m must be > 0");
  check(sensor_height_m >= 0.0 && std::isfinite(sensor_height_m), "sensor_height_m must be >= 0");
  check(candidates > 0, "candidates must be > 0");
  check(search_ratio >= 0.0 && search_ratio <= 1.0, "search_ratio must be in [0, 1]");
  check(exclude_recent >= 0, "exclude_recent must be >= 0");
  check(max_distance >= 0.0 && max_distance <= 2.0, "max_distance must be in [0, 2]");
  check(tree_rebuild_period > 0, "tree_rebuild_period must be > 0");
  check(std::all_of(lateral_offsets_m.begin(), lateral_offsets_m.end(),
                    [](double offset) { return std::isfinite(offset) && offset != 0.0; }),
        "lateral_offsets_m must be finite and non-zero (the scan's own viewpoint is always used)");
  return problems.report(error);
}

namespace {

// Bins start at 0, the value of an empty bin, so max() also applies the clamp of negative heights
// documented in the header (eq. 3: phi(P_ij) = max z over the bin).
void add_point(ScanContext& context, double x, double y, double height, const ScanContextOptions& options) {
  const double range_m = std::hypot(x, y);
  if (range_m > options.max_radius_m) return;
  double theta = std::atan2(y, x);
  if (theta < 0.0) theta += 2.0 * std::numbers::pi;
  const int ring = std::min(options.rings - 1, static_cast<int>(range_m * options.rings / options.max_radius_m));
  const int sector = std::min(options.sectors - 1, static_cast<int>(theta * options.sectors / (2.0 * std::numbers::pi)));
  float& bin = context.descriptor(ring, sector);
  bin = std::max(bin, static_cast<float>(height));
}

void finish_keys(ScanContext& context) {
  context.ring_key = context.descriptor.rowwise().mean();
  context.sector_key = context.descriptor.colwise().mean().transpose();
}

}  // namespace

ScanContext make_scan_context(const std::vector<Eigen::Vector3d>& points_sensor, const ScanContextOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "make_scan_context: invalid ScanContextOptions (check is_valid first)");
  ScanContext context;
  context.descriptor = Eigen::MatrixXf::Zero(options.rings, options.sectors);
  for (const double offset : options.lateral_offsets_m) {
    ScanContext view;
    view.lateral_offset_m = offset;
    view.descriptor = Eigen::MatrixXf::Zero(options.rings, options.sectors);
    context.lateral_views.push_back(std::move(view));
  }
  for (const Eigen::Vector3d& p : points_sensor) {
    if (!p.allFinite()) continue;
    const double height = p.z() + options.sensor_height_m;
    add_point(context, p.x(), p.y(), height, options);
    // The viewpoint (0, o) sees p at (x, y - o).
    for (ScanContext& view : context.lateral_views) add_point(view, p.x(), p.y() - view.lateral_offset_m, height, options);
  }
  finish_keys(context);
  for (ScanContext& view : context.lateral_views) finish_keys(view);
  return context;
}

ScanContext scan_context_from_descriptor(Eigen::MatrixXf descriptor) {
  ScanContext context;
  context.descriptor = std::move(descriptor);
  finish_keys(context);
  return context;
}

namespace {

// d of eq. 5 for query column j against candidate column (j + shift) mod N_s, over the columns
// occupied in both (the reference's distDirectSC); 1 when there is none.
double shifted_distance(const ScanContext& query, const ScanContext& candidate, const Eigen::VectorXf& query_norms,
                        const Eigen::VectorXf& candidate_norms, int shift) {
  const int sectors = static_cast<int>(query.descriptor.cols());
  double similarity_sum = 0.0;
  int columns = 0;
  for (int j = 0; j < sectors; ++j) {
    const int c = (j + shift) % sectors;
    if (query_norms[j] == 0.0f || candidate_norms[c] == 0.0f) continue;
    similarity_sum += static_cast<double>(query.descriptor.col(j).dot(candidate.descriptor.col(c))) /
                      (static_cast<double>(query_norms[j]) * static_cast<double>(candidate_norms[c]));
    ++columns;
  }
  // Rounding can push a cosine a hair above 1; the distance stays >= 0.
  return columns == 0 ? 1.0 : std::max(0.0, 1.0 - similarity_sum / columns);
}

// The shift whose sector keys differ least in the L2 norm (the reference's fastAlignUsingVkey).
int align_sector_keys(const Eigen::VectorXf& query_key, const Eigen::VectorXf& candidate_key) {
  const int sectors = static_cast<int>(query_key.size());
  int best_shift = 0;
  double best = std::numeric_limits<double>::infinity();
  for (int shift = 0; shift < sectors; ++shift) {
    double sum = 0.0;
    for (int j = 0; j < sectors; ++j) {
      const double difference = static_cast<double>(query_key[j] - candidate_key[(j + shift) % sectors]);
      sum += difference * difference;
    }
    if (sum < best) {
      best = sum;
      best_shift = shift;
    }
  }
  return best_shift;
}

}  // namespace

namespace {

ScanContextMatch compare_view(const ScanContext& query, const ScanContext& candidate, const ScanContextOptions& options) {
  CAIRN_ASSERT(query.descriptor.rows() == options.rings && query.descriptor.cols() == options.sectors &&
                   candidate.descriptor.rows() == options.rings && candidate.descriptor.cols() == options.sectors,
               "compare: descriptors must be rings x sectors of these options");
  const int sectors = options.sectors;
  const Eigen::VectorXf query_norms = query.descriptor.colwise().norm().transpose();
  const Eigen::VectorXf candidate_norms = candidate.descriptor.colwise().norm().transpose();

  // Shifts to try: all of them (eq. 6), or a window around the sector-key alignment (reference:
  // half-width round(SEARCH_RATIO N_s / 2)), nearest first so ties keep the key's choice.
  std::vector<int> shifts;
  const int half_width = static_cast<int>(std::lround(0.5 * options.search_ratio * sectors));
  if (options.search_ratio <= 0.0 || options.search_ratio >= 1.0 || 2 * half_width + 1 >= sectors) {
    for (int shift = 0; shift < sectors; ++shift) shifts.push_back(shift);
  } else {
    const int center = align_sector_keys(query.sector_key, candidate.sector_key);
    shifts.push_back(center);
    for (int offset = 1; offset <= half_width; ++offset) {
      shifts.push_back((center + offset) % sectors);
      shifts.push_back((center - offset + sectors) % sectors);
    }
  }

  ScanContextMatch match;
  match.distance = std::numeric_limits<double>::infinity();
  for (const int shift : shifts) {
    const double distance = shifted_distance(query, candidate, query_norms, candidate_norms, shift);
    if (distance < match.distance) {
      match.distance = distance;
      match.shift_sectors = shift;
    }
  }
  // eq. 7: n* gives the yaw; query azimuth theta <-> candidate azimuth theta + n* 2 pi / N_s.
  double yaw = match.shift_sectors * 2.0 * std::numbers::pi / sectors;
  if (yaw > std::numbers::pi) yaw -= 2.0 * std::numbers::pi;
  match.yaw_rad = yaw;
  // T_candidate_query = T_candidate_view T_view_query with T_candidate_view ~ (Rz(yaw), 0) and
  // T_view_query = (I, -(0, o, 0)).
  match.lateral_offset_m = query.lateral_offset_m;
  match.t_candidate_query = -(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(0.0, query.lateral_offset_m, 0.0));
  return match;
}

}  // namespace

ScanContextMatch compare(const ScanContext& query, const ScanContext& candidate, const ScanContextOptions& options) {
  ScanContextMatch best = compare_view(query, candidate, options);
  for (const ScanContext& view : query.lateral_views) {
    const ScanContextMatch match = compare_view(view, candidate, options);
    if (match.distance < best.distance) best = match;
  }
  return best;
}

/// The k-d tree owns a copy of the keys it indexes, so it stays valid while the database grows or
/// moves (nanoflann keeps a reference to its dataset).
struct ScanContextDatabase::Tree {
  struct Keys {
    std::vector<float> values;
    std::size_t dimension = 0;
    std::size_t kdtree_get_point_count() const { return values.size() / dimension; }
    float kdtree_get_pt(std::size_t index, std::size_t d) const { return values[index * dimension + d]; }
    template <class BoundingBox>
    bool kdtree_get_bbox(BoundingBox& /*box*/) const {
      return false;
    }
  };
  using Index = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Keys>, Keys, -1, std::uint32_t>;

  Keys keys;
  std::unique_ptr<Index> index;
};

ScanContextDatabase::ScanContextDatabase(const ScanContextOptions& options) : options_(options) {
  std::string error;
  if (!options_.is_valid(&error)) throw std::invalid_argument("ScanContextOptions: " + error);
}

ScanContextDatabase::~ScanContextDatabase() = default;
ScanContextDatabase::ScanContextDatabase(ScanContextDatabase&&) noexcept = default;
ScanContextDatabase& ScanContextDatabase::operator=(ScanContextDatabase&&) noexcept = default;

void ScanContextDatabase::add(int id, ScanContext context) {
  CAIRN_ASSERT(context.descriptor.rows() == options_.rings && context.descriptor.cols() == options_.sectors &&
                   context.ring_key.size() == options_.rings && context.sector_key.size() == options_.sectors,
               "ScanContextDatabase::add: context not made with this database's rings and sectors");
  CAIRN_ASSERT(find(id) == nullptr, "ScanContextDatabase::add: id already stored");
  context.lateral_views.clear();  // only a query uses them
  ids_.push_back(id);
  ring_keys_.insert(ring_keys_.end(), context.ring_key.data(), context.ring_key.data() + context.ring_key.size());
  contexts_.push_back(std::move(context));
}

const ScanContext* ScanContextDatabase::find(int id) const {
  const auto it = std::find(ids_.begin(), ids_.end(), id);
  return it == ids_.end() ? nullptr : &contexts_[static_cast<std::size_t>(it - ids_.begin())];
}

// GCC 12 reports a null dereference inside nanoflann's std::vector<uint32_t>::resize once it is
// inlined here (a false positive: the vector is never null); the pragma scopes the exemption to
// this function.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
void ScanContextDatabase::rebuild_tree() {
  auto tree = std::make_unique<Tree>();
  tree->keys.dimension = static_cast<std::size_t>(options_.rings);
  tree->keys.values = ring_keys_;
  tree->index = std::make_unique<Tree::Index>(options_.rings, tree->keys,
                                              nanoflann::KDTreeSingleIndexAdaptorParams(10 /* leaf size */));
  tree_ = std::move(tree);
  tree_entries_ = ids_.size();
}
#pragma GCC diagnostic pop

void ScanContextDatabase::nearest_ring_keys(const Eigen::VectorXf& key, const std::function<bool(std::size_t)>& eligible,
                                            std::vector<std::pair<float, std::size_t>>& nearest) const {
  const std::size_t wanted = static_cast<std::size_t>(options_.candidates);
  std::vector<std::pair<float, std::size_t>> found_here;
  // The tree does not know the exclusion, so ask it for more neighbours until enough eligible
  // ones come back or it has none left.
  if (tree_entries_ > 0) {
    std::size_t k = std::min(wanted, tree_entries_);
    std::vector<std::uint32_t> indices;
    std::vector<float> distances_sq;
    while (true) {
      indices.resize(k);
      distances_sq.resize(k);
      const std::size_t found = tree_->index->knnSearch(key.data(), k, indices.data(), distances_sq.data());
      found_here.clear();
      for (std::size_t i = 0; i < found; ++i) {
        if (eligible(indices[i])) found_here.emplace_back(distances_sq[i], indices[i]);
      }
      if (found_here.size() >= wanted || k >= tree_entries_) break;
      k = std::min(2 * k, tree_entries_);
    }
  }
  // Entries added since the last rebuild: brute force.
  const std::size_t rings = static_cast<std::size_t>(options_.rings);
  for (std::size_t entry = tree_entries_; entry < ids_.size(); ++entry) {
    if (!eligible(entry)) continue;
    const Eigen::Map<const Eigen::VectorXf> stored(ring_keys_.data() + entry * rings, options_.rings);
    found_here.emplace_back((stored - key).squaredNorm(), entry);
  }
  const auto by_key_distance = [&](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : ids_[a.second] < ids_[b.second];
  };
  if (found_here.size() > wanted) {
    std::partial_sort(found_here.begin(), found_here.begin() + static_cast<std::ptrdiff_t>(wanted), found_here.end(),
                      by_key_distance);
    found_here.resize(wanted);
  }
  nearest.insert(nearest.end(), found_here.begin(), found_here.end());
}

std::vector<LoopCandidate> ScanContextDatabase::query(const ScanContext& query, int query_id) {
  CAIRN_ASSERT(query.ring_key.size() == options_.rings, "ScanContextDatabase::query: ring key size != rings");
  if (ids_.size() - tree_entries_ >= static_cast<std::size_t>(options_.tree_rebuild_period)) rebuild_tree();

  const std::function<bool(std::size_t)> eligible = [&](std::size_t entry) {
    return std::abs(static_cast<long long>(ids_[entry]) - query_id) >= options_.exclude_recent;
  };
  // Phase 1 (Sec. III-C): nearest ring keys, to the query's and to each lateral view's.
  std::vector<std::pair<float, std::size_t>> nearest;  // (squared ring-key distance, entry)
  nearest_ring_keys(query.ring_key, eligible, nearest);
  for (const ScanContext& view : query.lateral_views) nearest_ring_keys(view.ring_key, eligible, nearest);
  // One entry per stored scan, at its smallest key distance.
  std::sort(nearest.begin(), nearest.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second < b.second : a.first < b.first;
  });
  nearest.erase(std::unique(nearest.begin(), nearest.end(), [](const auto& a, const auto& b) { return a.second == b.second; }),
                nearest.end());

  // Phase 2: the full distance D (eq. 6) for each.
  std::vector<LoopCandidate> candidates;
  candidates.reserve(nearest.size());
  for (const auto& [distance_sq, entry] : nearest) {
    LoopCandidate candidate;
    candidate.id = ids_[entry];
    candidate.ring_key_distance = std::sqrt(static_cast<double>(distance_sq));
    candidate.match = compare(query, contexts_[entry], options_);
    candidate.below_threshold = candidate.match.distance <= options_.max_distance;
    candidates.push_back(candidate);
  }
  std::sort(candidates.begin(), candidates.end(), [](const LoopCandidate& a, const LoopCandidate& b) {
    return a.match.distance != b.match.distance ? a.match.distance < b.match.distance : a.id < b.id;
  });
  if (candidates.size() > static_cast<std::size_t>(options_.candidates)) {
    candidates.resize(static_cast<std::size_t>(options_.candidates));
  }
  return candidates;
}

}  // namespace cairn::lidar3d
