#pragma once
/// \file
/// A TF tree from a bag's /tf_static and /tf (tf2_msgs/TFMessage), for looking up sensor
/// extrinsics by frame id as tf2's BufferCore::lookupTransform does (REP 105 frames: each
/// transform is T_parent_child, header.frame_id the parent). Static transforms hold at every
/// time; dynamic ones are interpolated between the two samples around the asked time (linear in
/// translation, slerp in rotation) and are not extrapolated beyond their first or last sample.

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cairn/bag/sensor_messages.hpp"

namespace cairn::bag {

class TfTree {
 public:
  void add(const TransformStamped& transform, bool is_static);

  /// T_target_source (maps points in `source` into `target`) at `time_ns`, or nothing when the
  /// two frames are not connected or a dynamic link has no sample around that time. `why` says
  /// which link is missing.
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& source, std::int64_t time_ns,
                                          std::string* why = nullptr) const;
  /// Every frame id seen, sorted.
  std::vector<std::string> frames() const;
  bool empty() const { return links_.empty(); }

 private:
  struct Sample {
    std::int64_t time_ns = 0;
    Eigen::Isometry3d T_parent_child = Eigen::Isometry3d::Identity();
  };
  struct Link {
    std::string parent;
    bool is_static = false;
    std::vector<Sample> samples;  ///< by time
  };
  /// T_parent_child of `child`'s link at `time_ns`.
  std::optional<Eigen::Isometry3d> link_at(const Link& link, std::int64_t time_ns) const;
  /// T_root_frame and the path's root, walking parents from `frame`.
  std::optional<Eigen::Isometry3d> to_ancestor(const std::string& frame, const std::string& ancestor,
                                               std::int64_t time_ns, std::string* why) const;
  std::vector<std::string> ancestors(const std::string& frame) const;

  std::map<std::string, Link> links_;  ///< by child frame
};

}  // namespace cairn::bag
