#include "cairn/sim/world_file.hpp"

#include <initializer_list>

#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"

namespace cairn::sim {

void write_world_file(const std::string& path, const World& world) {
  io::write_output(path, [&](std::ostream& out) {
    out << "# cairn world '" << world.name << "': WALL ax ay bx by | GLASS ax ay bx by | CIRCLE cx cy radius | "
        << "LANDMARK id x y | WALKER from_x from_y to_x to_y speed_mps radius_m phase_s (metres, seconds, world frame)\n";
    std::string line;
    auto emit = [&](const char* tag, std::initializer_list<double> values) {
      line = tag;
      for (double v : values) {
        line += ' ';
        io::append_number(line, v);
      }
      line += '\n';
      out << line;
    };
    for (const auto& w : world.walls) emit(w.glass ? "GLASS" : "WALL", {w.a.x(), w.a.y(), w.b.x(), w.b.y()});
    for (const auto& c : world.circles) emit("CIRCLE", {c.center.x(), c.center.y(), c.radius_m});
    for (const auto& l : world.landmarks) {
      line = "LANDMARK " + std::to_string(l.id) + ' ';
      io::append_number(line, l.position.x());
      line += ' ';
      io::append_number(line, l.position.y());
      line += '\n';
      out << line;
    }
    for (const auto& w : world.walkers) {
      emit("WALKER", {w.from.x(), w.from.y(), w.to.x(), w.to.y(), w.speed_mps, w.radius_m, w.phase_s});
    }
  });
}

}  // namespace cairn::sim
