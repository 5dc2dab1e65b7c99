// The Freiburg relations metric (relations.hpp; Kuemmerle et al., Autonomous Robots 27(4), 2009)
// on the real ACES relations file with an estimate built so that every relation's error is known
// before the metric runs.
//
// Construction. The 1279 relations of aces.relations join 1218 distinct scan times; 74 of them
// close a cycle (their two ends are already connected by earlier relations). The others form a
// spanning forest. Walking the relations in file order, each forest relation k from t_i to t_j
// fixes the pose at t_j as
//     X_j = X_i * SE2(x_k + dx_k, y_k + dy_k, yaw_k + dyaw_k)
// (when t_j already belongs to another tree, that whole tree is moved rigidly so that this
// holds; a rigid motion on the left leaves its internal relative poses unchanged). So the estimated
// relative pose of relation k is the reference's with (dx_k, dy_k, dyaw_k) added, and the metric
// must give translational error hypot(dx_k, dy_k) and rotational error |dyaw_k| for it, whatever
// happens to the 74 cycle relations. The expected statistics are plain sums over those chosen
// offsets.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "cairn/eval/relations.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::eval {
namespace {

constexpr const char* kAces = "laser2d/aces/aces.relations";

struct Planar {
  double x = 0;
  double y = 0;
  double yaw = 0;
};

Planar compose(const Planar& a, const Planar& b) {
  const double c = std::cos(a.yaw);
  const double s = std::sin(a.yaw);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, a.yaw + b.yaw};
}

Planar inverse(const Planar& a) {
  const double c = std::cos(a.yaw);
  const double s = std::sin(a.yaw);
  return {-(c * a.x + s * a.y), s * a.x - c * a.y, -a.yaw};
}

Matrix4 to_matrix(const Planar& p) {
  Matrix4 T = Matrix4::Identity();
  T(0, 0) = std::cos(p.yaw);
  T(0, 1) = -std::sin(p.yaw);
  T(1, 0) = std::sin(p.yaw);
  T(1, 1) = std::cos(p.yaw);
  T(0, 3) = p.x;
  T(1, 3) = p.y;
  return T;
}

// The offsets given to relation k (forest relations only): 2..4 cm in x, 0..3 cm in y,
// +-(0.5, 0.75, 1.0) degrees in yaw.
Planar offset(std::size_t k) {
  const double dx = 0.02 + 0.01 * static_cast<double>(k % 3);
  const double dy = 0.01 * static_cast<double>(k % 4);
  const double sign = (k % 2 == 0) ? 1.0 : -1.0;
  const double dyaw_deg = sign * (0.5 + 0.25 * static_cast<double>(k % 3));
  return {dx, dy, dyaw_deg * std::numbers::pi / 180.0};
}

struct Construction {
  MatrixTrajectory estimate;
  std::vector<bool> in_forest;  // per relation
};

Construction construct(const std::vector<Relation>& relations) {
  std::map<std::int64_t, Planar> pose;       // by time stamp (ns)
  std::map<std::int64_t, std::int64_t> tree;  // stamp -> tree id
  std::map<std::int64_t, std::vector<std::int64_t>> members;
  Construction c;
  for (std::size_t k = 0; k < relations.size(); ++k) {
    const Relation& r = relations[k];
    const std::int64_t a = r.from.nanoseconds();
    const std::int64_t b = r.to.nanoseconds();
    if (!tree.contains(a)) {
      tree[a] = a;
      members[a] = {a};
      pose[a] = {};
    }
    if (tree.contains(b) && tree[a] == tree[b]) {
      c.in_forest.push_back(false);
      continue;
    }
    const Planar reference{r.translation_m.x(), r.translation_m.y(), r.roll_pitch_yaw_rad.z()};
    const Planar d = offset(k);
    const Planar wanted_b = compose(pose[a], {reference.x + d.x, reference.y + d.y, reference.yaw + d.yaw});
    if (!tree.contains(b)) {
      tree[b] = tree[a];
      members[tree[a]].push_back(b);
      pose[b] = wanted_b;
    } else {
      // Move b's whole tree rigidly: M = wanted_b * X_b^-1 on the left, then merge it into a's.
      const Planar M = compose(wanted_b, inverse(pose[b]));
      const std::int64_t old_tree = tree[b];
      for (std::int64_t m : members[old_tree]) {
        pose[m] = compose(M, pose[m]);
        tree[m] = tree[a];
        members[tree[a]].push_back(m);
      }
      members.erase(old_tree);
    }
    c.in_forest.push_back(true);
  }
  for (const auto& [stamp, p] : pose) {  // std::map: increasing stamps
    c.estimate.stamps.push_back(core::Timestamp::from_nanoseconds(stamp));
    c.estimate.poses.push_back(to_matrix(p));
  }
  return c;
}

struct Expected {
  double mean = 0;
  double std = 0;
};

Expected mean_std(const std::vector<double>& v) {
  const double n = static_cast<double>(v.size());
  const double mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double sq = 0;
  for (double e : v) sq += (e - mean) * (e - mean);
  return {mean, std::sqrt(sq / n)};  // population std, as relations.hpp states
}

TEST(Relations, AcesWithAConstructedEstimateGivesTheConstructedErrors) {
  CAIRN_REQUIRE_DATA(kAces);
  const std::vector<Relation> relations = read_relations(test::data_path(kAces).string());
  ASSERT_EQ(relations.size(), 1279u);
  const Construction c = construct(relations);
  EXPECT_EQ(c.estimate.size(), 1218u);
  EXPECT_EQ(std::count(c.in_forest.begin(), c.in_forest.end(), false), 74);

  // Every relation of the file: the forest ones must carry exactly their offsets.
  const RelationsResult all = evaluate_relations(relations, c.estimate);
  ASSERT_TRUE(all.outcome.ok()) << all.outcome.message;
  ASSERT_EQ(all.translation_errors_m.size(), relations.size());
  for (std::size_t k = 0; k < relations.size(); ++k) {
    if (!c.in_forest[k]) continue;
    const Planar d = offset(k);
    ASSERT_NEAR(all.translation_errors_m[k], std::hypot(d.x, d.y), 1e-9) << "relation line " << relations[k].line;
    ASSERT_NEAR(all.rotation_errors_rad[k], std::abs(d.yaw), 1e-9) << "relation line " << relations[k].line;
  }

  // Only the forest relations: the four mean +- std rows of Hess et al. 2016, Table II.
  std::vector<Relation> forest;
  std::vector<double> t_abs, t_sq, r_abs, r_sq;
  for (std::size_t k = 0; k < relations.size(); ++k) {
    if (!c.in_forest[k]) continue;
    forest.push_back(relations[k]);
    const Planar d = offset(k);
    const double t = std::hypot(d.x, d.y);
    const double r = std::abs(d.yaw) * 180.0 / std::numbers::pi;
    t_abs.push_back(t);
    t_sq.push_back(t * t);
    r_abs.push_back(r);
    r_sq.push_back(r * r);
  }
  const RelationsResult sub = evaluate_relations(forest, c.estimate);
  ASSERT_TRUE(sub.outcome.ok()) << sub.outcome.message;
  const Expected et = mean_std(t_abs), et2 = mean_std(t_sq), er = mean_std(r_abs), er2 = mean_std(r_sq);
  EXPECT_NEAR(sub.translation_absolute_m.mean, et.mean, 1e-10);
  EXPECT_NEAR(sub.translation_absolute_m.std, et.std, 1e-10);
  EXPECT_NEAR(sub.translation_squared_m2.mean, et2.mean, 1e-10);
  EXPECT_NEAR(sub.translation_squared_m2.std, et2.std, 1e-10);
  EXPECT_NEAR(sub.rotation_absolute_deg.mean, er.mean, 1e-7);
  EXPECT_NEAR(sub.rotation_absolute_deg.std, er.std, 1e-7);
  EXPECT_NEAR(sub.rotation_squared_deg2.mean, er2.mean, 1e-7);
  EXPECT_NEAR(sub.rotation_squared_deg2.std, er2.std, 1e-7);
  EXPECT_NEAR(sub.translation_absolute_m.min, 0.02, 1e-10);
  EXPECT_NEAR(sub.rotation_absolute_deg.max, 1.0, 1e-7);
}

TEST(Relations, EstimateMissingARelationTimeIsAnErrorNamingIt) {
  CAIRN_REQUIRE_DATA(kAces);
  const std::vector<Relation> relations = read_relations(test::data_path(kAces).string());
  Construction c = construct(relations);
  // Drop the pose at the first relation's first time: the nearest other pose is 0.48 s away.
  c.estimate.stamps.erase(c.estimate.stamps.begin());
  c.estimate.poses.erase(c.estimate.poses.begin());
  const RelationsResult r = evaluate_relations(relations, c.estimate);
  EXPECT_EQ(r.outcome.status, Status::kMissingPoses);
  EXPECT_NE(r.outcome.message.find("90.2395"), std::string::npos) << r.outcome.message;
}

}  // namespace
}  // namespace cairn::eval
