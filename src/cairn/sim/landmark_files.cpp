#include "cairn/sim/landmark_files.hpp"

#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/sim/carmen_log.hpp"

namespace cairn::sim {

void write_landmark_map(const std::string& path, const std::vector<Landmark>& landmarks) {
  io::write_output(path, [&](std::ostream& out) {
    out << "id,x_m,y_m\n";
    std::string line;
    for (const auto& landmark : landmarks) {
      line = std::to_string(landmark.id);
      line += ',';
      io::append_number(line, landmark.position.x());
      line += ',';
      io::append_number(line, landmark.position.y());
      line += '\n';
      out << line;
    }
  });
}

void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations) {
  io::write_output(path, [&](std::ostream& out) {
    out << "time_s,landmark_id,range_m,bearing_rad\n";
    std::string line;
    for (const auto& o : observations) {
      line = format_carmen_time(o.stamp);
      line += ',';
      line += std::to_string(o.landmark_id);
      line += ',';
      io::append_number(line, o.range_m);
      line += ',';
      io::append_number(line, o.bearing_rad);
      line += '\n';
      out << line;
    }
  });
}

}  // namespace cairn::sim
