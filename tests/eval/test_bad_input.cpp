// Bad data handed to every metric: mismatched lengths, no overlapping timestamps, unsorted
// timestamps, a NaN. Each gives a failed outcome with a message that says what and where; none
// throws or aborts. Files: the relations reader names file and line.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::eval {
namespace {

Matrix4 at_x(double x) {
  Matrix4 T = Matrix4::Identity();
  T(0, 3) = x;
  T(1, 3) = 0.1 * x * x;  // not collinear, so SE(3) alignment is defined
  return T;
}

MatrixTrajectory line(std::size_t n, double t0_s, bool stamps) {
  MatrixTrajectory t;
  for (std::size_t i = 0; i < n; ++i) {
    t.poses.push_back(at_x(static_cast<double>(i)));
    if (stamps) t.stamps.push_back(core::Timestamp::from_seconds(t0_s + 0.1 * static_cast<double>(i)));
  }
  return t;
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// One failing outcome per metric for the same pair of trajectories.
struct Outcomes {
  Outcome ape, rpe, kitti;
};

Outcomes run_all(const MatrixTrajectory& reference, const MatrixTrajectory& estimate) {
  ApeOptions ape;
  ape.alignment.method = AlignmentMethod::kSE3;
  return {evaluate_ape(reference, estimate, ape).outcome, evaluate_rpe(reference, estimate).outcome,
          evaluate_kitti(reference, estimate).outcome};
}

TEST(BadInput, MismatchedLengthsWithoutStamps) {
  const Outcomes o = run_all(line(10, 0, false), line(9, 0, false));
  for (const Outcome* out : {&o.ape, &o.rpe, &o.kitti}) {
    EXPECT_EQ(out->status, Status::kSizeMismatch);
    EXPECT_TRUE(has(out->message, "10") && has(out->message, "9")) << out->message;
  }
}

TEST(BadInput, NoOverlappingTimestamps) {
  const Outcomes o = run_all(line(10, 0, true), line(10, 100, true));
  for (const Outcome* out : {&o.ape, &o.rpe, &o.kitti}) {
    EXPECT_EQ(out->status, Status::kNoOverlap) << out->message;
    EXPECT_FALSE(out->message.empty());
  }
}

TEST(BadInput, UnsortedTimestamps) {
  MatrixTrajectory est = line(10, 0, true);
  std::swap(est.stamps[4], est.stamps[5]);
  const Outcomes o = run_all(line(10, 0, true), est);
  for (const Outcome* out : {&o.ape, &o.rpe, &o.kitti}) {
    EXPECT_EQ(out->status, Status::kUnsortedStamps);
    EXPECT_TRUE(has(out->message, "estimate") && has(out->message, "pose 5")) << out->message;
  }
}

TEST(BadInput, NaNInAPose) {
  MatrixTrajectory est = line(10, 0, false);
  est.poses[7](1, 3) = std::numeric_limits<double>::quiet_NaN();
  const Outcomes o = run_all(line(10, 0, false), est);
  for (const Outcome* out : {&o.ape, &o.rpe, &o.kitti}) {
    EXPECT_EQ(out->status, Status::kNotFinite);
    EXPECT_TRUE(has(out->message, "estimate pose 7")) << out->message;
  }
  // In the reference too.
  const Outcomes r = run_all(est, line(10, 0, false));
  EXPECT_EQ(r.ape.status, Status::kNotFinite);
  EXPECT_TRUE(has(r.ape.message, "reference pose 7")) << r.ape.message;
}

TEST(BadInput, EmptyTrajectory) {
  const Outcomes o = run_all(line(10, 0, false), MatrixTrajectory{});
  for (const Outcome* out : {&o.ape, &o.rpe, &o.kitti}) EXPECT_EQ(out->status, Status::kEmpty) << out->message;
}

Relation relation(double from_s, double to_s) {
  Relation r;
  r.from = core::Timestamp::from_seconds(from_s);
  r.to = core::Timestamp::from_seconds(to_s);
  r.translation_m = Vector3(0.1, 0, 0);
  r.line = 3;
  return r;
}

TEST(BadInput, RelationsMetric) {
  const std::vector<Relation> relations = {relation(0.1, 0.2), relation(0.2, 0.5)};
  // No stamps at all.
  EXPECT_EQ(evaluate_relations(relations, line(10, 0, false)).outcome.status, Status::kMissingStamps);
  // No overlap: every relation time is far from every pose.
  const RelationsResult far = evaluate_relations(relations, line(10, 100, true));
  EXPECT_EQ(far.outcome.status, Status::kMissingPoses);
  EXPECT_TRUE(has(far.outcome.message, "line 3")) << far.outcome.message;
  MatrixTrajectory unsorted = line(10, 0, true);
  std::swap(unsorted.stamps[2], unsorted.stamps[3]);
  EXPECT_EQ(evaluate_relations(relations, unsorted).outcome.status, Status::kUnsortedStamps);
  MatrixTrajectory nan = line(10, 0, true);
  nan.poses[1](0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(evaluate_relations(relations, nan).outcome.status, Status::kNotFinite);
  EXPECT_EQ(evaluate_relations({}, line(10, 0, true)).outcome.status, Status::kEmpty);
  EXPECT_TRUE(evaluate_relations(relations, line(10, 0, true)).outcome.ok());
}

std::string write(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("cairn_eval_bad_" + std::to_string(::getpid()) + name);
  std::ofstream(path) << text;
  return path.string();
}

void expect_parse_error(const std::string& text, const std::string& where, const std::string& what) {
  const std::string path = write("relations.txt", text);
  try {
    (void)read_relations(path);
    ADD_FAILURE() << "no error for:\n" << text;
  } catch (const io::ParseError& e) {
    const std::string message = e.what();
    EXPECT_TRUE(has(message, path + ":" + where)) << message;
    EXPECT_TRUE(has(message, what)) << message;
  }
  std::filesystem::remove(path);
}

TEST(BadInput, RelationsFileErrorsNameFileAndLine) {
  expect_parse_error("# comment\n1.0 2.0 0.1 0 0 0 0 0.01\n2.0 3.0 0.1 0 0 0 0\n", "3", "8");
  expect_parse_error("1.0 2.0 0.1 0 0 0 0 nan\n", "1", "");
  expect_parse_error("# only a comment\n", "", "no relation");
}

}  // namespace
}  // namespace cairn::eval
