// The slam2d YAML configuration: every key has a default, files may set any subset, and
// mistakes are errors naming the file and line.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/config.hpp"

namespace cairn::slam2d {
namespace {

namespace fs = std::filesystem;

fs::path write_temp(const std::string& name, const std::string& text) {
  const fs::path path = fs::temp_directory_path() / ("cairn-config-" + std::to_string(::getpid()) + "-" + name);
  std::ofstream(path) << text;
  return path;
}

TEST(Slam2dConfig, FileOverridesOnlyTheKeysItNames) {
  const fs::path path = write_temp("ok.yaml", "front_end:\n  keyframe_distance_m: 0.5\nloop_closure:\n  min_score: 0.7\n  max_submaps_per_search: 2\n");
  Slam2dOptions options;
  load_config(path.string(), options);
  EXPECT_DOUBLE_EQ(options.keyframe_distance_m, 0.5);
  EXPECT_DOUBLE_EQ(options.loop_min_score, 0.7);
  EXPECT_EQ(options.loop_max_submaps_per_search, 2);
  EXPECT_DOUBLE_EQ(options.keyframe_angle_rad, Slam2dOptions{}.keyframe_angle_rad);
  fs::remove(path);
}

TEST(Slam2dConfig, UnknownKeyNamesFileAndLine) {
  const fs::path path = write_temp("unknown.yaml", "front_end:\n  keyframe_distance_m: 0.5\n  keyframe_distanse_m: 0.3\n");
  Slam2dOptions options;
  try {
    load_config(path.string(), options);
    ADD_FAILURE() << "an unknown key must be refused";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 3u);
    EXPECT_NE(std::string(e.what()).find("front_end.keyframe_distanse_m"), std::string::npos) << e.what();
  }
  fs::remove(path);
}

TEST(Slam2dConfig, WrongTypeAndSyntaxErrorsNameTheLine) {
  const fs::path typed = write_temp("type.yaml", "loop_closure:\n  min_score: high\n");
  Slam2dOptions options;
  try {
    load_config(typed.string(), options);
    ADD_FAILURE();
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 2u);
    EXPECT_NE(std::string(e.what()).find("a finite number"), std::string::npos) << e.what();
  }
  const fs::path broken = write_temp("syntax.yaml", "loop_closure:\n  min_score: [0.5\n");
  EXPECT_THROW(load_config(broken.string(), options), io::ParseError);
  EXPECT_THROW(load_config("/nonexistent/cairn.yaml", options), io::ParseError);
  fs::remove(typed);
  fs::remove(broken);
}

TEST(Slam2dConfig, SettingsAndPrintedConfigRoundTrip) {
  Slam2dOptions options;
  apply_setting("icp.point_sigma_m=0.03", options);
  EXPECT_DOUBLE_EQ(options.icp.point_sigma_m, 0.03);
  EXPECT_THROW(apply_setting("icp.point_sigma_m=nan", options), std::invalid_argument);
  EXPECT_THROW(apply_setting("icp.nothing=1", options), std::invalid_argument);
  EXPECT_THROW(apply_setting("no-equals-sign", options), std::invalid_argument);
  // What --print-config prints reads back to the same options.
  const fs::path path = write_temp("printed.yaml", config_to_yaml(options));
  Slam2dOptions reread;
  reread.icp.point_sigma_m = 1.0;
  load_config(path.string(), reread);
  EXPECT_EQ(config_to_yaml(reread), config_to_yaml(options));
  fs::remove(path);
  EXPECT_THROW(preset_options("velodyne"), std::invalid_argument);
}

}  // namespace
}  // namespace cairn::slam2d
