#pragma once
/// \file
/// The one validation convention of cairn's options and settings structs: `bool is_valid(std::string*
/// why) const` checks every value and reports every problem at once (joined by "; "), not only the
/// first, so a user fixing a configuration sees all of it in one run. Problems collects them:
///
///   bool Options::is_valid(std::string* why) const {
///     core::Problems problems;
///     if (!(voxel_size_m > 0.0)) problems.add("voxel_size_m must be > 0");
///     return problems.report(why);
///   }

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace cairn::core {

class Problems {
 public:
  void add(std::string problem) { list_.push_back(std::move(problem)); }
  /// A nested struct's problems (its is_valid's text), each prefixed with `prefix`.
  void add_all(const std::string& prefix, const std::string& joined) {
    if (!joined.empty()) add(prefix + joined);
  }
  /// "<name> must be finite and > 0" unless `value` is.
  void require_positive(double value, const char* name) {
    if (!(std::isfinite(value) && value > 0.0)) add(std::string(name) + " must be finite and > 0");
  }
  bool empty() const { return list_.empty(); }
  const std::vector<std::string>& list() const { return list_; }
  /// Every problem joined by "; " (empty when none).
  std::string text() const {
    std::string out;
    for (const std::string& p : list_) out += (out.empty() ? "" : "; ") + p;
    return out;
  }
  /// True when there is none; otherwise false, with text() in *why when why is given.
  bool report(std::string* why) const {
    if (list_.empty()) return true;
    if (why != nullptr) *why = text();
    return false;
  }

 private:
  std::vector<std::string> list_;
};

}  // namespace cairn::core
