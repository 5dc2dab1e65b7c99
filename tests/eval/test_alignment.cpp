#include "cairn/eval/alignment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace cairn::eval {
namespace {

using core::SE3;
using core::SO3;

using Poses = std::vector<Matrix4>;

Poses random_poses(std::mt19937_64& rng, std::size_t n) {
  std::normal_distribution<double> g(0.0, 3.0);
  Poses poses;
  for (std::size_t i = 0; i < n; ++i) {
    poses.push_back(SE3(SO3::exp(Vector3(g(rng), g(rng), g(rng)) * 0.3), Vector3(g(rng), g(rng), g(rng))).matrix());
  }
  return poses;
}

// Moves poses by a known similarity: p -> s R p + t, R_body -> R R_body.
Poses transform(const Poses& poses, const SE3& T, double s) {
  Poses out;
  for (const Matrix4& p : poses) {
    Matrix4 q = Matrix4::Identity();
    q.topLeftCorner<3, 3>() = T.rotation_matrix() * p.topLeftCorner<3, 3>();
    q.topRightCorner<3, 1>() = s * (T.rotation_matrix() * p.topRightCorner<3, 1>()) + T.translation();
    out.push_back(q);
  }
  return out;
}

Vector3 position(const Matrix4& T) { return T.topRightCorner<3, 1>(); }
double angle_between(const Matrix4& a, const Matrix4& b) {
  return SO3::from_matrix(a.topLeftCorner<3, 3>().transpose() * b.topLeftCorner<3, 3>()).angle();
}

TEST(Alignment, Se3RecoversAKnownMotionExactly) {
  std::mt19937_64 rng(7);
  const Poses reference = random_poses(rng, 50);
  const SE3 T_estimate_reference(SO3::exp(Vector3(0.3, -1.2, 2.0)), Vector3(5.0, -2.0, 1.0));
  const Poses estimate = transform(reference, T_estimate_reference, 1.0);
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSE3});
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_DOUBLE_EQ(a.scale, 1.0);
  const Poses aligned = apply_alignment(a, estimate);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_LT((position(aligned[i]) - position(reference[i])).norm(), 1e-12);
    EXPECT_LT(angle_between(aligned[i], reference[i]), 1e-12);
  }
}

TEST(Alignment, Sim3RecoversScale) {
  std::mt19937_64 rng(8);
  const Poses reference = random_poses(rng, 30);
  const SE3 T(SO3::exp(Vector3(-0.5, 0.1, 0.9)), Vector3(1.0, 2.0, 3.0));
  const Poses estimate = transform(reference, T, 0.25);
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSim3});
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_NEAR(a.scale, 4.0, 1e-12);
  const Poses aligned = apply_alignment(a, estimate);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_LT((position(aligned[i]) - position(reference[i])).norm(), 1e-11);
  }
  // SE(3) alone cannot undo the scale: a residual remains.
  const Alignment rigid = align(reference, estimate, {.method = AlignmentMethod::kSE3});
  const Poses rigid_aligned = apply_alignment(rigid, estimate);
  double worst = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    worst = std::max(worst, (position(rigid_aligned[i]) - position(reference[i])).norm());
  }
  EXPECT_GT(worst, 0.5);
}

// Umeyama eq. 43: a mirrored point set must still give a rotation (det +1), not a reflection.
TEST(Alignment, MirroredPointsGiveAProperRotation) {
  std::mt19937_64 rng(9);
  Poses reference = random_poses(rng, 20);
  Poses estimate;
  for (const Matrix4& p : reference) {
    Matrix4 q = p;
    q(2, 3) = -q(2, 3);
    estimate.push_back(q);
  }
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSE3});
  ASSERT_TRUE(a.outcome.ok());
  EXPECT_NEAR(a.R.determinant(), 1.0, 1e-12);
}

TEST(Alignment, Se2MovesOnlyInThePlane) {
  std::mt19937_64 rng(10);
  const Poses reference = random_poses(rng, 40);
  const SE3 T(SO3::exp(Vector3(0.0, 0.0, 0.7)), Vector3(3.0, -4.0, 0.0));
  const Poses estimate = transform(reference, T, 1.0);
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSE2});
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_NEAR(a.t.z(), 0.0, 0.0);
  const Poses aligned = apply_alignment(a, estimate);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    EXPECT_LT((position(aligned[i]) - position(reference[i])).norm(), 1e-11);
  }
  // A tilt out of the plane is not removed by SE(2).
  const SE3 tilt(SO3::exp(Vector3(0.2, 0.0, 0.0)), Vector3::Zero());
  const Poses tilted = transform(reference, tilt, 1.0);
  const Poses planar = apply_alignment(align(reference, tilted, {.method = AlignmentMethod::kSE2}), tilted);
  double worst = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    worst = std::max(worst, (position(planar[i]) - position(reference[i])).norm());
  }
  EXPECT_GT(worst, 0.1);
}

TEST(Alignment, FirstPoseMapsTheFirstEstimateOntoTheFirstReference) {
  std::mt19937_64 rng(11);
  const Poses reference = random_poses(rng, 5);
  const Poses estimate = random_poses(rng, 5);
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kFirstPose});
  ASSERT_TRUE(a.outcome.ok());
  const Matrix4 first = a.apply(estimate.front());
  EXPECT_LT((position(first) - position(reference.front())).norm(), 1e-12);
  EXPECT_LT(angle_between(first, reference.front()), 1e-12);
}

TEST(Alignment, NumPosesLimitsThePairsUsed) {
  std::mt19937_64 rng(12);
  const Poses reference = random_poses(rng, 20);
  Poses estimate = transform(reference, SE3(SO3::exp(Vector3(0.1, 0.2, 0.3)), Vector3(1, 1, 1)), 1.0);
  // Corrupt the tail: an alignment from the first 10 pairs must not see it.
  for (std::size_t i = 10; i < 20; ++i) estimate[i](0, 3) += 50.0;
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSE3, .num_poses = 10});
  ASSERT_TRUE(a.outcome.ok());
  EXPECT_EQ(a.pairs_used, 10u);
  EXPECT_LT((position(a.apply(estimate[3])) - position(reference[3])).norm(), 1e-11);
}

TEST(Alignment, CollinearPointsAreDegenerate) {
  Poses reference;
  Poses estimate;
  for (int i = 0; i < 10; ++i) {
    reference.push_back(SE3(SO3(), Vector3(i, 2 * i, 0)).matrix());
    estimate.push_back(SE3(SO3(), Vector3(i, 0, 0)).matrix());
  }
  const Alignment a = align(reference, estimate, {.method = AlignmentMethod::kSE3});
  EXPECT_EQ(a.outcome.status, Status::kDegenerate);
  EXPECT_NE(a.outcome.message.find("line"), std::string::npos) << a.outcome.message;
}

TEST(Alignment, NamesRoundTrip) {
  for (AlignmentMethod m : {AlignmentMethod::kNone, AlignmentMethod::kSE3, AlignmentMethod::kSim3,
                            AlignmentMethod::kSE2, AlignmentMethod::kFirstPose}) {
    EXPECT_EQ(alignment_method_from_name(to_string(m)), m);
  }
  EXPECT_FALSE(alignment_method_from_name("umeyama").has_value());
}

}  // namespace
}  // namespace cairn::eval
