// `cairn vslam` end to end: the files it writes, the report's facts, clear errors for folders
// that are not sequences or lack a calibration.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "test_data.hpp"

namespace {

namespace fs = std::filesystem;
using Result = cairn::test::CliResult;
using cairn::test::slurp;

fs::path scratch() { return cairn::test::scratch_folder("vslam_cli"); }
Result run(const std::string& args) { return cairn::test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }
std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

TEST(VslamCli, KittiStereoWritesEveryOutput) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const fs::path out = scratch() / "kitti";
  fs::remove_all(out);
  const Result r = run("vslam " + quoted(cairn::test::data_path("visual/kitti_extract_seq2")) + " --max-frames 12 --out " + quoted(out));
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* name : {"trajectory.tum", "trajectory.kitti", "keyframes.tum", "map_points.ply", "frames.csv", "report.json",
                           "trajectory.png", "features.png"}) {
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["input"]["frames_processed"], 12);
  EXPECT_EQ(report["summary"]["lost"], 0);
  EXPECT_GT(report["summary"]["map_points"].get<int>(), 500);
  ASSERT_TRUE(report["evaluation"].is_object());
  EXPECT_LT(report["evaluation"]["rpe_1_frame_rotation_deg"]["rmse"].get<double>(), 0.3);
  EXPECT_NE(r.err.find("no times.txt"), std::string::npos) << r.err;
  // Refused without --overwrite, before any work.
  const Result again = run("vslam " + quoted(cairn::test::data_path("visual/kitti_extract_seq2")) + " --max-frames 2 --out " + quoted(out));
  EXPECT_EQ(again.status, 1);
  EXPECT_NE(again.err.find("--overwrite"), std::string::npos) << again.err;
}

// A plain folder (left/ + right/, or images alone) with a calibration YAML: the first 12 KITTI
// frames laid out that way give the same trajectory, to the last digit, as the KITTI folder.
TEST(VslamCli, PlainFoldersWithACalibrationRunLikeTheirDataset) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const fs::path kitti = cairn::test::data_path("visual/kitti_extract_seq2");
  const fs::path plain = scratch() / "plain";
  fs::remove_all(plain);
  fs::create_directories(plain / "left");
  fs::create_directories(plain / "right");
  fs::create_directories(plain / "mono");
  std::vector<fs::path> left;
  for (const auto& entry : fs::directory_iterator(kitti / "image_l")) left.push_back(entry.path());
  std::sort(left.begin(), left.end());
  for (std::size_t k = 0; k < left.size(); ++k) {
    // Monocular initialisation on this stretch needs 19 frames: the mono folder gets them all.
    fs::create_symlink(left[k], plain / "mono" / left[k].filename());
    if (k >= 12) continue;
    fs::create_symlink(left[k], plain / "left" / left[k].filename());
    fs::create_symlink(kitti / "image_r" / left[k].filename(), plain / "right" / left[k].filename());
  }
  // calib.txt's P0 and P1: fx = fy = 718.856, (cx, cy) = (607.1928, 185.2157), baseline 386.1448 / fx.
  const fs::path calib = scratch() / "kitti_calib.yaml";
  {
    std::ofstream yaml(calib);
    yaml.precision(17);
    yaml << "fx: " << 718.856 << "\nfy: " << 718.856 << "\ncx: " << 607.1928 << "\ncy: " << 185.2157
         << "\nbaseline_m: " << 386.1448 / 718.856 << "\n";
  }
  const fs::path out_kitti = scratch() / "plain_ref", out_plain = scratch() / "plain_out", out_mono = scratch() / "plain_mono";
  for (const fs::path& out : {out_kitti, out_plain, out_mono}) fs::remove_all(out);
  Result r = run("vslam " + quoted(kitti) + " --max-frames 12 -q --out " + quoted(out_kitti));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run("vslam " + quoted(plain) + " --calib " + quoted(calib) + " --features 2000 -q --out " + quoted(out_plain));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(out_plain / "trajectory.tum"), slurp(out_kitti / "trajectory.tum"));
  const nlohmann::json report = nlohmann::json::parse(slurp(out_plain / "report.json"));
  EXPECT_EQ(report["input"]["layout"], "folder");

  // Images alone are monocular.
  r = run("vslam " + quoted(plain / "mono") + " --calib " + quoted(calib) + " --features 2000 --progress --out " + quoted(out_mono));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("folder monocular"), std::string::npos) << r.err;
  const nlohmann::json mono = nlohmann::json::parse(slurp(out_mono / "report.json"));
  EXPECT_GT(mono["summary"]["ok"].get<int>(), 20) << mono["summary"].dump();  // initialised at frame 19, then tracked
  // Without a calibration, or stereo without a baseline: refused, naming what is missing.
  r = run("vslam " + quoted(plain) + " --out " + quoted(scratch() / "none"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("a plain image folder has no calibration: give --calib"), std::string::npos) << r.err;
  const fs::path no_baseline = scratch() / "no_baseline.yaml";
  std::ofstream(no_baseline) << "fx: 718.856\nfy: 718.856\ncx: 607.1928\ncy: 185.2157\n";
  r = run("vslam " + quoted(plain) + " --calib " + quoted(no_baseline) + " --out " + quoted(scratch() / "none"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("baseline_m"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "none"));
}

TEST(VslamCli, FoldersThatAreNotSequencesOrLackACalibrationAreRefused) {
  const fs::path empty = scratch() / "empty";
  fs::create_directories(empty);
  Result r = run("vslam " + quoted(empty) + " --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("not a known image sequence"), std::string::npos) << r.err;
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  r = run("vslam " + quoted(cairn::test::data_path("visual/tum_fr1_desk_every4th")) + " --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--camera tum-fr1"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "x"));
  const fs::path calib = scratch() / "calib.yaml";
  std::ofstream(calib) << "fx: 500\nfy: 500\ncx: 320\ncy: abc\n";
  r = run("vslam " + quoted(cairn::test::data_path("visual/tum_fr1_desk_every4th")) + " --calib " + quoted(calib) + " --out " +
          quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("calib.yaml:4: \"cy\" must be a number"), std::string::npos) << r.err;
}

// --print-config, --config and --set (vslam/config.hpp): without a FOLDER the defaults are printed
// and nothing runs; every key is listed, and the printed file read back prints the same text.
TEST(VslamCli, PrintConfigListsEveryKeyAndRoundTrips) {
  const Result printed = run("vslam --print-config");
  ASSERT_EQ(printed.status, 0) << printed.err;
  std::size_t keys = 0;
  std::istringstream lines(printed.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  ", 0) == 0 && line.find(": ") != std::string::npos && line.find("  # ") != std::string::npos) ++keys;
  }
  EXPECT_EQ(keys, 71u) << printed.out;  // VisualSlamOptions with its OrbOptions, StereoOptions and VisualInertialOptions' rules, but the vocabulary
  for (const char* key : {"orb:\n  features: 2000  #", "  scale_factor: 1.2  #", "stereo:\n  max_descriptor_distance: 75  #",
                          "tracking:\n", "health:\n", "keyframes:\n  close_depth_baselines: 35  #", "local_mapping:\n  local_ba: true  #",
                          "loop_closure:\n  enabled: true  #", "inertial:\n  initialisation_window_s: 2  #", "maps:\n"}) {
    EXPECT_NE(printed.out.find(key), std::string::npos) << key;
  }
  const fs::path config = scratch() / "vslam_config.yaml";
  std::ofstream(config) << printed.out;
  const Result again = run("vslam --print-config --config " + quoted(config));
  ASSERT_EQ(again.status, 0) << again.err;
  EXPECT_EQ(again.out, printed.out);
  // --set over --config; --features and --no-local-ba win over both.
  std::ofstream(config) << "orb:\n  levels: 6\n  features: 1500\n";
  const Result changed = run("vslam --print-config --config " + quoted(config) +
                             " --set orb.levels=7 --set local_mapping.keyframe_culling=false --features 1200 --no-local-ba");
  ASSERT_EQ(changed.status, 0) << changed.err;
  for (const char* value : {"  levels: 7  #", "  features: 1200  #", "  keyframe_culling: false  #", "  local_ba: false  #"}) {
    EXPECT_NE(changed.out.find(value), std::string::npos) << value << "\n" << changed.out;
  }
}

TEST(VslamCli, BadSettingsAreRefusedNamingTheKey) {
  for (const auto& [set, expected] : std::vector<std::pair<std::string, std::string>>{
           {"orb.bogus=1", "--set: unknown key 'orb.bogus'"},
           {"orb.features=many", "--set orb.features: expected an integer, got 'many'"},
           {"local_mapping.local_ba=yes", "--set local_mapping.local_ba: expected true or false"}}) {
    const Result r = run("vslam --print-config --set " + set);
    EXPECT_EQ(r.status, 2) << set;
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "") << set;
  }
  // Well-typed values the pipeline cannot use: its validation, every problem at once.
  Result r = run("vslam --print-config --set orb.levels=0 --set stereo.search_half_range=-1 --set inertial.max_scale_drift=2");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("invalid configuration: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("levels must be in [1, 16]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stereo.search_half_range must be in [1, 50]"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("inertial.max_scale_drift must be in (0, 1)"), std::string::npos) << r.err;
  // A file: its line (a bad input file, exit status 1 as every other).
  const fs::path config = scratch() / "bad_vslam_config.yaml";
  std::ofstream(config) << "orb:\n  features: 1500\n  bogus: 1\n";
  r = run("vslam --print-config --config " + quoted(config));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad_vslam_config.yaml:3: unknown key 'orb.bogus'"), std::string::npos) << r.err;
  // Before any work on a sequence.
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const fs::path out = scratch() / "bad_set";
  r = run("vslam " + quoted(cairn::test::data_path("visual/kitti_extract_seq2")) + " --max-frames 2 --set orb.features=0 --out " +
          quoted(out));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("features must be in [10, 100000]"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// With a FOLDER, the dataset's settings come first (1000 features and close points within 40
// baselines for TUM RGB-D), and report.json's "options" are the keys in effect.
TEST(VslamCli, ReportOptionsAreTheConfigurationInEffect) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  const Result tum = run("vslam " + quoted(cairn::test::data_path("visual/tum_fr1_desk_every4th")) + " --camera tum-fr1 --print-config -q");
  EXPECT_NE(tum.out.find("  features: 1000  #"), std::string::npos) << tum.out;
  EXPECT_NE(tum.out.find("  close_depth_baselines: 40  #"), std::string::npos) << tum.out;
  EXPECT_EQ(tum.status, 1);  // printed, then the run needs --out (as slam2d)
  EXPECT_NE(tum.err.find("--out DIR is required"), std::string::npos) << tum.err;

  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const fs::path out = scratch() / "configured";
  fs::remove_all(out);
  const Result r = run("vslam " + quoted(cairn::test::data_path("visual/kitti_extract_seq2")) +
                       " --max-frames 3 -q --set loop_closure.drift_floor_m=0.75 --set local_mapping.keyframe_culling=false"
                       " --set orb.features=1500 --features 1800 --out " + quoted(out));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  const nlohmann::json& options = report["options"];
  // Every section of `cairn vslam --print-config`, and nothing else.
  std::vector<std::string> sections;
  for (const auto& [name, keys] : options.items()) sections.push_back(name);
  EXPECT_EQ(sections, (std::vector<std::string>{"health", "inertial", "keyframes", "local_mapping", "loop_closure", "maps",
                                                "orb", "stereo", "tracking"}))
      << options.dump();
  EXPECT_EQ(options["loop_closure"]["drift_floor_m"], 0.75);
  EXPECT_EQ(options["local_mapping"]["keyframe_culling"], false);
  EXPECT_EQ(options["orb"]["features"], 1800);  // --features wins over --set
  EXPECT_EQ(options["orb"]["levels"], 8);
  EXPECT_EQ(options["keyframes"]["close_depth_baselines"], 35.0);  // KITTI stereo
  EXPECT_EQ(options["inertial"]["max_carried_s"], 1.5);  // the rules' defaults, though this run has no IMU
  EXPECT_EQ(report["input"]["frames_processed"], 3);
}

TEST(VocabularyCli, TrainDescribeAndUseAVocabulary) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l");
  const fs::path voc = scratch() / "kitti.voc";
  Result r = run("vocabulary train " + quoted(cairn::test::data_path("visual/kitti_extract_seq2/image_l")) + " --every 5 -L 3 --out " +
                 quoted(voc));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("trained on 11 images"), std::string::npos) << r.out;  // images 0, 5, ..., 50
  r = run("vocabulary info " + quoted(voc));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("k=10 L=3"), std::string::npos) << r.out;
  // A flipped byte: the checksum says so.
  std::string bytes = slurp(voc);
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  const fs::path bad = scratch() / "bad.voc";
  std::ofstream(bad, std::ios::binary) << bytes;
  r = run("vocabulary info " + quoted(bad));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("bad.voc"), std::string::npos) << r.err;
  // Used by vslam on TUM (other images than it was trained on): the report says so.
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  const fs::path out = scratch() / "tum";
  fs::remove_all(out);
  r = run("vslam " + quoted(cairn::test::data_path("visual/tum_fr1_desk_every4th")) + " --camera tum-fr1 --vocabulary " + quoted(voc) +
          " --max-frames 20 --out " + quoted(out) + " -q");
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["place_recognition"]["vocabulary"], voc.string());
  EXPECT_NE(report["place_recognition"]["vocabulary_description"].get<std::string>().find("trained on 11 images"), std::string::npos);
}

// --save-map then --localize-in (issue 42): the map of the first 16 KITTI frames, frames 8-15
// localised in it. The accuracy on frames the map did not see is tests/vslam/test_vslam_map_reuse's
// (TUM fr1/desk); this checks the command: what it writes, what it says, what it refuses.
std::size_t lines_in(const fs::path& path) {
  std::ifstream in(path);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) n += !line.empty() && line[0] != '#' ? 1 : 0;
  return n;
}

TEST(VslamCli, SaveAMapThenLocaliseInItWithoutChangingIt) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const std::string kitti = quoted(cairn::test::data_path("visual/kitti_extract_seq2"));
  const fs::path map = scratch() / "kitti16.cvsm";
  fs::remove_all(scratch() / "map_run");
  fs::remove(map);
  Result r = run("vslam " + kitti + " --max-frames 16 --save-map " + quoted(map) + " --out " + quoted(scratch() / "map_run"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("wrote the map for reuse"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(map));
  const std::string map_bytes = slurp(map);
  const nlohmann::json mapped = nlohmann::json::parse(slurp(scratch() / "map_run" / "report.json"));

  const fs::path out = scratch() / "localised";
  fs::remove_all(out);
  r = run("vslam " + kitti + " --first-frame 8 --max-frames 8 --localize-in " + quoted(map) + " --out " + quoted(out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("localising in"), std::string::npos) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(out / "report.json"));
  ASSERT_TRUE(report["localization"].is_object()) << report.dump();
  EXPECT_EQ(report["localization"]["frames"], 8);
  EXPECT_EQ(report["input"]["first_frame"], 8);
  EXPECT_EQ(report["localization"]["frames_localised"], 8);  // frames the map was made from
  EXPECT_EQ(report["summary"]["keyframes"], 0);             // nothing added
  EXPECT_EQ(report["localization"]["map_keyframes"].get<std::size_t>(), lines_in(scratch() / "map_run" / "keyframes.tum"));
  EXPECT_EQ(lines_in(out / "keyframes.tum"), lines_in(scratch() / "map_run" / "keyframes.tum"));  // the map's keyframes
  EXPECT_EQ(lines_in(out / "trajectory.tum"), 8u);
  EXPECT_EQ(report["localization"]["map_points"], mapped["summary"]["map_points"]);
  EXPECT_EQ(slurp(map), map_bytes);

  // What it refuses: both flags; a map of other images; a damaged map; --first-frame past the end.
  r = run("vslam " + kitti + " --save-map " + quoted(scratch() / "again.cvsm") + " --localize-in " + quoted(map) + " --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("exclude each other"), std::string::npos) << r.err;
  r = run("vslam " + kitti + " --mono --max-frames 2 --localize-in " + quoted(map) + " --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("made from stereo images, these are monocular"), std::string::npos) << r.err;
  const fs::path cut = scratch() / "cut.cvsm";
  std::ofstream(cut, std::ios::binary) << map_bytes.substr(0, map_bytes.size() / 2);
  r = run("vslam " + kitti + " --max-frames 2 --localize-in " + quoted(cut) + " --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("cut.cvsm"), std::string::npos) << r.err;
  r = run("vslam " + kitti + " --first-frame 51 --out " + quoted(scratch() / "x"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--first-frame 51: the sequence has 51 frames"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "x"));
}

}  // namespace
