#include "cairn/eval/status.hpp"

namespace cairn::eval {

std::string_view to_string(Status status) {
  switch (status) {
    case Status::kOk: return "ok";
    case Status::kInvalidOptions: return "invalid options";
    case Status::kEmpty: return "empty trajectory";
    case Status::kSizeMismatch: return "size mismatch";
    case Status::kMissingStamps: return "missing timestamps";
    case Status::kUnsortedStamps: return "unsorted timestamps";
    case Status::kNoOverlap: return "no overlapping timestamps";
    case Status::kNotFinite: return "not finite";
    case Status::kDegenerate: return "degenerate";
    case Status::kNoPairs: return "no pairs";
    case Status::kMissingPoses: return "missing poses";
  }
  return "unknown";
}

}  // namespace cairn::eval
