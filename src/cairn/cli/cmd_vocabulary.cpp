// `cairn vocabulary train IMAGES... --out FILE` and `cairn vocabulary info FILE`: the bag-of-words
// vocabulary of place recognition (vision/vocabulary.hpp), trained by hierarchical k-means++ on
// ORB descriptors as DBoW2 trains it. Train on images other than the ones it will be used on.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"

namespace cairn::cli {
namespace {

namespace fs = std::filesystem;

struct VocabularyFlags {
  std::vector<std::string> inputs;
  std::string out;
  std::string file;
  int branching = 10;
  int levels = 5;
  int features = 1000;
  int every = 1;
  unsigned long seed = 1;
  bool quiet = false;
};

// Folders give their images (sorted, not recursive); files are taken as they are.
std::vector<std::string> list_images(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (fs::is_directory(input, ec)) {
      const std::vector<std::string> here = io::image_files_in(input);
      out.insert(out.end(), here.begin(), here.end());
    } else {
      out.push_back(input);
    }
  }
  return out;
}

int train_command(const VocabularyFlags& flags) {
  if (flags.out.empty()) throw std::invalid_argument("--out FILE is required");
  if (flags.every < 1) throw std::invalid_argument("--every must be >= 1");
  vision::VocabularyOptions options;
  options.branching = flags.branching;
  options.depth = flags.levels;
  options.seed = flags.seed;
  if (std::string p; !options.is_valid(&p)) throw std::invalid_argument("vocabulary options: " + p);
  vision::OrbOptions orb_options;
  orb_options.features = flags.features;
  const vision::OrbExtractor orb(orb_options);
  const std::vector<std::string> all = list_images(flags.inputs);
  std::vector<std::string> used;
  for (std::size_t i = 0; i < all.size(); i += static_cast<std::size_t>(flags.every)) used.push_back(all[i]);
  const bool tty = !flags.quiet && isatty(fileno(stderr));
  const auto start = core::Clock::now();
  std::vector<cv::Mat> descriptors;
  std::size_t total = 0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    const vision::Features f = orb.extract(vision::read_gray_image(used[i]));
    total += static_cast<std::size_t>(f.descriptors.rows);
    descriptors.push_back(f.descriptors);
    if (tty && (i % 20 == 0 || i + 1 == used.size())) {
      std::fprintf(stderr, "\rcairn vocabulary: features of image %zu / %zu", i + 1, used.size());
      std::fflush(stderr);
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  const double features_s = core::seconds_since(start);
  const vision::Vocabulary vocabulary = vision::Vocabulary::train(descriptors, options);
  const double total_s = core::seconds_since(start);
  vocabulary.save(flags.out);
  if (!flags.quiet) {
    std::printf("%s: %s; %zu images (%s%s), %zu descriptors; features %.1f s, k-means %.1f s\n", flags.out.c_str(),
                vocabulary.description().c_str(), used.size(), used.front().c_str(), used.size() > 1 ? " ..." : "", total, features_s,
                total_s - features_s);
  }
  return 0;
}

int info_command(const VocabularyFlags& flags) {
  const vision::Vocabulary vocabulary = vision::Vocabulary::load(flags.file);
  std::printf("%s: %s\n", flags.file.c_str(), vocabulary.description().c_str());
  return 0;
}

}  // namespace

Runner register_vocabulary(CLI::App& app) {
  auto flags = std::make_shared<VocabularyFlags>();
  app.require_subcommand(1);
  CLI::App* train = app.add_subcommand("train", "Train a vocabulary on images (folders or files): hierarchical k-means++ on ORB descriptors, tf-idf");
  train->add_option("images", flags->inputs, "Image folders or files; never the images the vocabulary will be evaluated on")->required();
  train->add_option("--out", flags->out, "Vocabulary file to write (cairn's format, docs/formats.md)");
  train->add_option("-k,--branching", flags->branching, "Children per node, 2 to 64 (default 10, as ORB-SLAM's vocabulary)")
      ->check(checks::whole_range(2, 64));
  train->add_option("-L,--levels", flags->levels, "Levels below the root, 1 to 12 (default 5)")->check(checks::whole_range(1, 12));
  train->add_option("--features", flags->features, "ORB features per image (default 1000)")->check(checks::whole_range(10, 100000));
  train->add_option("--every", flags->every, "Take every Nth image (default 1)")->check(checks::count());
  train->add_option("--seed", flags->seed, "k-means++ seed (default 1)");
  train->add_flag("-q,--quiet", flags->quiet, "No progress or summary");
  CLI::App* info = app.add_subcommand("info", "Describe a vocabulary file (cairn's, or DBoW2's .txt / .yml)");
  info->add_option("file", flags->file, "Vocabulary file")->required();
  return [flags, train] { return train->parsed() ? train_command(*flags) : info_command(*flags); };
}

}  // namespace cairn::cli
