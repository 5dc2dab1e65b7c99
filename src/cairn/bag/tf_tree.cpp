#include "cairn/bag/tf_tree.hpp"

#include <algorithm>
#include <set>

namespace cairn::bag {

void TfTree::add(const TransformStamped& transform, bool is_static) {
  Link& link = links_[transform.child_frame_id];
  link.parent = transform.header.frame_id;
  link.is_static = is_static;
  Sample sample;
  sample.time_ns = transform.header.stamp_ns;
  sample.T_parent_child.linear() = transform.rotation.normalized().toRotationMatrix();
  sample.T_parent_child.translation() = transform.translation;
  if (is_static) {
    link.samples.assign(1, sample);
    return;
  }
  const auto after = std::upper_bound(link.samples.begin(), link.samples.end(), sample.time_ns,
                                      [](std::int64_t t, const Sample& s) { return t < s.time_ns; });
  link.samples.insert(after, sample);
}

std::optional<Eigen::Isometry3d> TfTree::link_at(const Link& link, std::int64_t time_ns) const {
  if (link.samples.empty()) return std::nullopt;
  if (link.is_static || link.samples.size() == 1) {
    if (link.is_static || link.samples.front().time_ns == time_ns) return link.samples.front().T_parent_child;
    return std::nullopt;
  }
  const auto after = std::lower_bound(link.samples.begin(), link.samples.end(), time_ns,
                                      [](const Sample& s, std::int64_t t) { return s.time_ns < t; });
  if (after == link.samples.end()) return std::nullopt;
  if (after->time_ns == time_ns) return after->T_parent_child;
  if (after == link.samples.begin()) return std::nullopt;
  const Sample& a = *std::prev(after);
  const Sample& b = *after;
  const double s = static_cast<double>(time_ns - a.time_ns) / static_cast<double>(b.time_ns - a.time_ns);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(a.T_parent_child.linear())
                   .slerp(s, Eigen::Quaterniond(b.T_parent_child.linear()))
                   .toRotationMatrix();
  T.translation() = (1 - s) * a.T_parent_child.translation() + s * b.T_parent_child.translation();
  return T;
}

std::vector<std::string> TfTree::ancestors(const std::string& frame) const {
  std::vector<std::string> chain{frame};
  std::set<std::string> seen{frame};
  for (auto it = links_.find(frame); it != links_.end(); it = links_.find(it->second.parent)) {
    if (!seen.insert(it->second.parent).second) break;  // a cycle: stop
    chain.push_back(it->second.parent);
  }
  return chain;
}

std::optional<Eigen::Isometry3d> TfTree::to_ancestor(const std::string& frame, const std::string& ancestor,
                                                     std::int64_t time_ns, std::string* why) const {
  Eigen::Isometry3d T_ancestor_frame = Eigen::Isometry3d::Identity();
  for (std::string current = frame; current != ancestor;) {
    const Link& link = links_.at(current);
    const auto T_parent_current = link_at(link, time_ns);
    if (!T_parent_current) {
      if (why != nullptr) *why = "no transform " + link.parent + " <- " + current + " at that time";
      return std::nullopt;
    }
    T_ancestor_frame = *T_parent_current * T_ancestor_frame;
    current = link.parent;
  }
  return T_ancestor_frame;
}

std::optional<Eigen::Isometry3d> TfTree::lookup(const std::string& target, const std::string& source,
                                                std::int64_t time_ns, std::string* why) const {
  const std::vector<std::string> up_from_source = ancestors(source);
  const std::vector<std::string> up_from_target = ancestors(target);
  const auto common = std::find_first_of(up_from_source.begin(), up_from_source.end(), up_from_target.begin(),
                                         up_from_target.end());
  if (common == up_from_source.end()) {
    if (why != nullptr) *why = "frames '" + target + "' and '" + source + "' are not connected";
    return std::nullopt;
  }
  const auto T_common_source = to_ancestor(source, *common, time_ns, why);
  const auto T_common_target = to_ancestor(target, *common, time_ns, why);
  if (!T_common_source || !T_common_target) return std::nullopt;
  return T_common_target->inverse() * *T_common_source;
}

std::vector<std::string> TfTree::frames() const {
  std::set<std::string> all;
  for (const auto& [child, link] : links_) {
    all.insert(child);
    all.insert(link.parent);
  }
  return {all.begin(), all.end()};
}

}  // namespace cairn::bag
