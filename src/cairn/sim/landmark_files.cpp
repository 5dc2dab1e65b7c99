#include "cairn/sim/landmark_files.hpp"

#include "cairn/io/landmark_csv.hpp"

namespace cairn::sim {

void write_landmark_map(const std::string& path, const std::vector<Landmark>& landmarks) {
  std::vector<io::LandmarkPosition> records;
  records.reserve(landmarks.size());
  for (const Landmark& landmark : landmarks) records.push_back({landmark.id, landmark.position.x(), landmark.position.y()});
  io::write_landmark_map(path, records);
}

void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations) {
  std::vector<io::LandmarkObservation> records;
  records.reserve(observations.size());
  for (const LandmarkObservation& o : observations) records.push_back({o.stamp, o.landmark_id, o.range_m, o.bearing_rad, 0});
  io::write_landmark_observations(path, records);
}

}  // namespace cairn::sim
