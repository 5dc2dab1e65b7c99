#pragma once
/// \file
/// How an evaluation ended. Bad data handed to a metric (mismatched lengths, no common
/// timestamps, unsorted times, a NaN) is an expected failure, not a programmer error: every
/// computation returns its result with a Status and a message saying what was wrong and where
/// (STYLE.md section 3), and never throws for it. Files are different: the relations reader
/// throws io::ParseError like every other reader.

#include <string>
#include <string_view>

namespace cairn::eval {

enum class Status {
  kOk,
  /// Invalid options (negative tolerance, zero delta, ...); the message lists every problem.
  kInvalidOptions,
  /// A trajectory has no poses, or fewer than the computation needs.
  kEmpty,
  /// Pairing by index needs equal lengths; the lengths differ.
  kSizeMismatch,
  /// One trajectory has timestamps and the other has none, and they cannot be paired by index.
  kMissingStamps,
  /// Timestamps do not strictly increase.
  kUnsortedStamps,
  /// No timestamp of one trajectory lies within the allowed difference of the other's.
  kNoOverlap,
  /// A pose holds a NaN or infinity.
  kNotFinite,
  /// The alignment is not determined (points collinear or coincident).
  kDegenerate,
  /// The pair selection (RPE delta, KITTI segments) found no pair.
  kNoPairs,
  /// Relations metric: a relation's time has no estimated pose close enough.
  kMissingPoses,
};

std::string_view to_string(Status status);

/// Status and explanation shared by every result struct.
struct Outcome {
  Status status = Status::kOk;
  /// Empty when status is kOk; otherwise what went wrong, with counts and indices.
  std::string message;

  bool ok() const { return status == Status::kOk; }
};

}  // namespace cairn::eval
