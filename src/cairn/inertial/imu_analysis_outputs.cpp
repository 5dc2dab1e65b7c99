#include "cairn/inertial/imu_analysis_outputs.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "cairn/io/json_text.hpp"
#include "cairn/viz/figure.hpp"
#include "cairn/viz/render.hpp"

namespace cairn::inertial {
namespace {

/// One panel: log10 of the Allan deviation against log10 tau for three axes, and the fitted
/// white-noise lines N / sqrt(tau) (dashed). Log axes as base-10 exponents (viz has linear axes).
viz::Axes allan_panel(const std::array<std::vector<AllanPoint>, 3>& curves, const std::array<AllanFit, 3>& fits,
                      const std::string& title, const std::string& unit) {
  viz::Axes axes;
  axes.title = title;
  axes.x_label = "log10 tau [s]";
  axes.y_label = "log10 Allan deviation [" + unit + "]";
  const char* names[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    viz::Series series;
    series.label = names[axis];
    series.color = viz::categorical(axis);
    for (const AllanPoint& p : curves[static_cast<std::size_t>(axis)]) {
      if (!(p.deviation > 0.0)) continue;
      series.x.push_back(std::log10(p.tau_s));
      series.y.push_back(std::log10(p.deviation));
    }
    const AllanFit& fit = fits[static_cast<std::size_t>(axis)];
    if (fit.white_noise_found && !series.x.empty()) {
      viz::Series line;
      line.color = series.color;
      line.dashed = true;
      line.width_px = 1.0;
      for (const double lt : {series.x.front(), series.x.back()}) {
        line.x.push_back(lt);
        line.y.push_back(std::log10(fit.white_noise_density) - 0.5 * lt);
      }
      axes.series.push_back(std::move(line));
    }
    axes.series.push_back(std::move(series));
  }
  return axes;
}

viz::Figure allan_figure(const ImuAllanReport& report) {
  viz::Figure figure;
  figure.title = "Allan deviation (dashed: white noise N / sqrt(tau) fitted)";
  figure.width_px = 1400;
  figure.height_px = 600;
  figure.columns = 2;
  figure.panels.push_back(allan_panel(report.gyro, report.gyro_fit, "gyroscope", "rad/s"));
  figure.panels.push_back(allan_panel(report.accel, report.accel_fit, "accelerometer", "m/s^2"));
  return figure;
}

viz::Axes window_panel(const PreintegrationCheck& check, double WindowError::*field, const std::string& title,
                       const std::string& label, double median) {
  viz::Axes axes;
  axes.title = title;
  axes.x_label = "window start [s from the first]";
  axes.y_label = label;
  axes.y_from_zero = true;
  axes.legend = false;
  viz::Series series;
  series.style = viz::SeriesStyle::kPoints;
  series.width_px = 2.0;
  const double t0 = check.windows.empty() ? 0.0 : check.windows.front().start_s;
  for (const WindowError& w : check.windows) {
    series.x.push_back(w.start_s - t0);
    series.y.push_back(w.*field);
  }
  axes.series.push_back(std::move(series));
  axes.horizontal_lines.push_back({"median", median, viz::kBlack, true});
  return axes;
}

viz::Figure check_figure(const PreintegrationCheck& check) {
  viz::Figure figure;
  figure.title = "Preintegration against ground truth, per window";
  figure.width_px = 1200;
  figure.height_px = 1000;
  figure.panels.push_back(window_panel(check, &WindowError::rotation_error_deg, "rotation error", "[deg]",
                                       check.rotation_deg.median));
  figure.panels.push_back(window_panel(check, &WindowError::position_error_m, "position error", "[m]",
                                       check.position_m.median));
  figure.panels.push_back(window_panel(check, &WindowError::nees, "NEES (9 dof; 9 expected)", "[-]", check.nees.median));
  return figure;
}

void write_png(io::OutputDirectory& out, const std::string& name, const viz::Figure& figure) {
  const viz::RenderResult png = viz::render(figure, viz::ImageFormat::kPng);
  if (!png.ok) throw std::runtime_error("cannot draw " + name + ": " + png.message);
  io::write_output(out.staging_path(name), [&](std::ostream& o) { o << png.bytes; });
}

}  // namespace

std::vector<std::string> write_imu_analysis_outputs(io::OutputDirectory& out, const ImuAnalysis& analysis,
                                                    const nlohmann::json& inputs) {
  std::vector<std::string> names;
  nlohmann::json report = to_json(analysis);
  report["inputs"] = inputs;
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  names.push_back("report.json");
  if (analysis.allan) {
    write_png(out, "allan.png", allan_figure(*analysis.allan));
    names.push_back("allan.png");
  }
  if (analysis.check && !analysis.check->windows.empty()) {
    write_png(out, "preintegration.png", check_figure(*analysis.check));
    names.push_back("preintegration.png");
  }
  return names;
}

}  // namespace cairn::inertial
