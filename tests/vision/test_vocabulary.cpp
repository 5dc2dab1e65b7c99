// Bag-of-words vocabulary (DBoW2, Galvez-Lopez & Tardos, T-RO 2012): training on synthetic binary
// descriptors with known clusters, tf-idf weights and L1 scores checked against values worked out
// by hand, the three file formats (round trip, a real DBoW2 YAML vocabulary, hand-written DBoW2
// text and YAML files, corrupt files), the inverted-index database, and place recognition on real
// images (trained on KITTI, evaluated on TUM: never the same images).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "cairn/io/parse_error.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/vocabulary.hpp"
#include "test_data.hpp"

namespace cairn::vision {
namespace {

namespace fs = std::filesystem;
using Bytes = std::array<unsigned char, 32>;
const char* kToy = "visual/vocab_dbow2_orb_toy/small_voc.yml.gz";

fs::path temp_dir() {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_vocabulary_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary);
  out << s;
}

Bytes random_bytes(std::mt19937_64& rng) {
  Bytes b;
  for (auto& x : b) x = static_cast<unsigned char>(rng() & 0xFFu);
  return b;
}

// `bits` distinct bits flipped.
Bytes flip(Bytes b, int bits, std::mt19937_64& rng) {
  std::set<std::size_t> done;
  while (static_cast<int>(done.size()) < bits) {
    const std::size_t bit = rng() % 256;
    if (!done.insert(bit).second) continue;
    b[bit / 8] = static_cast<unsigned char>(b[bit / 8] ^ (1u << (bit % 8)));
  }
  return b;
}

cv::Mat to_mat(const std::vector<Bytes>& rows) {
  cv::Mat m(static_cast<int>(rows.size()), 32, CV_8U);
  for (std::size_t i = 0; i < rows.size(); ++i) std::memcpy(m.ptr(static_cast<int>(i)), rows[i].data(), 32);
  return m;
}

int hamming(const Bytes& a, const Bytes& b) { return descriptor_distance(a.data(), b.data()); }

// A synthetic world of landmark descriptors; an image sees some landmarks, each with a few bits
// of noise (what a re-observed ORB feature looks like).
struct World {
  std::vector<Bytes> landmarks;
  explicit World(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    for (std::size_t i = 0; i < n; ++i) landmarks.push_back(random_bytes(rng));
  }
  std::vector<std::size_t> pick(std::size_t count, std::mt19937_64& rng) const {
    std::vector<std::size_t> ids;
    for (std::size_t i = 0; i < count; ++i) ids.push_back(rng() % landmarks.size());
    return ids;
  }
  cv::Mat observe(const std::vector<std::size_t>& ids, int noise_bits, std::mt19937_64& rng) const {
    std::vector<Bytes> rows;
    for (const std::size_t id : ids) rows.push_back(flip(landmarks[id], noise_bits, rng));
    return to_mat(rows);
  }
};

void expect_normalised(const BowVector& v) {
  double sum = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    EXPECT_GT(v[i].second, 0.0);
    if (i > 0) {
      EXPECT_LT(v[i - 1].first, v[i].first);
    }
    sum += v[i].second;
  }
  if (!v.empty()) {
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
}

// ---------------------------------------------------------------------------------------------

TEST(Vocabulary, OptionsReportEveryProblem) {
  std::string none;
  EXPECT_TRUE(VocabularyOptions{}.is_valid(&none));
  EXPECT_EQ(none, "");
  VocabularyOptions bad;
  bad.branching = 1;
  bad.depth = 0;
  bad.kmeans_iterations = 0;
  std::string p;
  EXPECT_FALSE(bad.is_valid(&p));
  EXPECT_NE(p.find("branching"), std::string::npos);
  EXPECT_NE(p.find("depth"), std::string::npos);
  EXPECT_NE(p.find("kmeans_iterations"), std::string::npos);
  EXPECT_THROW(Vocabulary::train({}, bad), std::invalid_argument);
  const cv::Mat floats(3, 32, CV_32F, cv::Scalar(0));
  EXPECT_THROW(Vocabulary::train({floats}, VocabularyOptions{}), std::invalid_argument);
  const cv::Mat same(5, 32, CV_8U, cv::Scalar(7));
  EXPECT_THROW(Vocabulary::train({same}, VocabularyOptions{}), std::invalid_argument);  // one distinct descriptor
}

TEST(Vocabulary, WordsSeparateKnownClusters) {
  // 6 cluster centres (random, so ~128 bits apart), members within 6 bits of their centre.
  std::mt19937_64 rng(11);
  std::vector<Bytes> centres;
  for (int c = 0; c < 6; ++c) centres.push_back(random_bytes(rng));
  for (int a = 0; a < 6; ++a) {
    for (int b = a + 1; b < 6; ++b) ASSERT_GT(hamming(centres[static_cast<std::size_t>(a)], centres[static_cast<std::size_t>(b)]), 80);
  }
  std::vector<cv::Mat> images;
  std::vector<std::vector<int>> cluster_of_row;
  for (int image = 0; image < 20; ++image) {
    std::vector<Bytes> rows;
    std::vector<int> labels;
    for (int c = 0; c < 6; ++c) {
      for (int j = 0; j < 15; ++j) {
        rows.push_back(flip(centres[static_cast<std::size_t>(c)], static_cast<int>(rng() % 7), rng));
        labels.push_back(c);
      }
    }
    images.push_back(to_mat(rows));
    cluster_of_row.push_back(labels);
  }

  // k = number of clusters, one level: the words are the clusters, one each.
  VocabularyOptions one_level;
  one_level.branching = 6;
  one_level.depth = 1;
  const Vocabulary flat = Vocabulary::train(images, one_level);
  ASSERT_EQ(flat.words(), 6u);
  std::map<std::uint32_t, std::set<int>> clusters_of_word;
  std::map<int, std::set<std::uint32_t>> words_of_cluster;
  for (std::size_t i = 0; i < images.size(); ++i) {
    std::vector<std::uint32_t> words;
    flat.transform(images[i], &words);
    ASSERT_EQ(words.size(), cluster_of_row[i].size());
    for (std::size_t r = 0; r < words.size(); ++r) {
      clusters_of_word[words[r]].insert(cluster_of_row[i][r]);
      words_of_cluster[cluster_of_row[i][r]].insert(words[r]);
    }
  }
  for (const auto& [word, clusters] : clusters_of_word) EXPECT_EQ(clusters.size(), 1u) << "word " << word;
  for (const auto& [cluster, words] : words_of_cluster) EXPECT_EQ(words.size(), 1u) << "cluster " << cluster;

  // A deeper tree (k = 10 > 6 clusters, so some clusters are split already at level 1) never
  // mixes clusters: every word and every level-1 node holds members of one cluster only, and
  // fresh members of a cluster pass through one of that cluster's level-1 nodes.
  VocabularyOptions deep;
  deep.branching = 10;
  deep.depth = 3;
  const Vocabulary tree = Vocabulary::train(images, deep);
  EXPECT_GT(tree.words(), 6u);
  EXPECT_EQ(tree.branching(), 10);
  EXPECT_EQ(tree.depth(), 3);
  clusters_of_word.clear();
  std::map<int, std::set<std::uint32_t>> level1_of_cluster;
  std::map<std::uint32_t, std::set<int>> clusters_of_level1;
  for (std::size_t i = 0; i < images.size(); ++i) {
    std::vector<std::uint32_t> words, level1;
    tree.transform(images[i], &words, &level1, 2);  // node at depth L - 2 = 1
    for (std::size_t r = 0; r < words.size(); ++r) {
      clusters_of_word[words[r]].insert(cluster_of_row[i][r]);
      level1_of_cluster[cluster_of_row[i][r]].insert(level1[r]);
      clusters_of_level1[level1[r]].insert(cluster_of_row[i][r]);
      // The level-1 node is the word's ancestor whose parent is the root.
      std::uint32_t node = tree.word_node(words[r]);
      while (tree.parent_node(node) != 0) node = tree.parent_node(node);
      EXPECT_EQ(node, level1[r]);
    }
  }
  for (const auto& [word, clusters] : clusters_of_word) EXPECT_EQ(clusters.size(), 1u) << "word " << word;
  for (const auto& [node, clusters] : clusters_of_level1) EXPECT_EQ(clusters.size(), 1u) << "level-1 node " << node;
  EXPECT_EQ(level1_of_cluster.size(), 6u);
  for (int c = 0; c < 6; ++c) {
    std::vector<Bytes> fresh;
    for (int j = 0; j < 10; ++j) fresh.push_back(flip(centres[static_cast<std::size_t>(c)], 5, rng));
    std::vector<std::uint32_t> words, level1;
    tree.transform(to_mat(fresh), &words, &level1, 2);
    for (const std::uint32_t n : level1) EXPECT_EQ(level1_of_cluster[c].count(n), 1u) << "cluster " << c;
  }
}

TEST(Vocabulary, IdfWeightsAndTfIdfVectorsMatchHandValues) {
  // 4 clusters over 4 images: cluster 0 in every image, 1 in two, 2 in one, 3 in three.
  std::mt19937_64 rng(5);
  std::vector<Bytes> centres;
  for (int c = 0; c < 4; ++c) centres.push_back(random_bytes(rng));
  const std::vector<std::vector<int>> present = {{0, 1, 2, 3}, {0, 1, 3}, {0, 3}, {0}};
  std::vector<cv::Mat> images;
  for (const auto& clusters : present) {
    std::vector<Bytes> rows;
    for (const int c : clusters) {
      for (int j = 0; j < 8; ++j) rows.push_back(flip(centres[static_cast<std::size_t>(c)], 3, rng));
    }
    images.push_back(to_mat(rows));
  }
  VocabularyOptions options;
  options.branching = 4;
  options.depth = 1;
  const Vocabulary v = Vocabulary::train(images, options);
  ASSERT_EQ(v.words(), 4u);
  EXPECT_EQ(v.training_images(), 4u);
  EXPECT_EQ(v.weighting(), BowWeighting::kTfIdf);
  std::vector<std::uint32_t> word(4);
  for (int c = 0; c < 4; ++c) {
    std::vector<std::uint32_t> w;
    v.transform(to_mat({centres[static_cast<std::size_t>(c)]}), &w);
    word[static_cast<std::size_t>(c)] = w[0];
  }
  // idf = log(N / N_i), N = 4 images.
  EXPECT_NEAR(v.word_weight(word[0]), 0.0, 1e-15);
  EXPECT_NEAR(v.word_weight(word[1]), std::log(2.0), 1e-12);
  EXPECT_NEAR(v.word_weight(word[2]), std::log(4.0), 1e-12);
  EXPECT_NEAR(v.word_weight(word[3]), std::log(4.0 / 3.0), 1e-12);
  // 5 features of cluster 0 (weight 0: left out), 2 of cluster 1, 1 of cluster 2:
  // tf-idf 2 ln 2 and ln 4 = 2 ln 2, so 1/2 each after normalisation.
  std::vector<Bytes> rows;
  for (int j = 0; j < 5; ++j) rows.push_back(flip(centres[0], 2, rng));
  for (int j = 0; j < 2; ++j) rows.push_back(flip(centres[1], 2, rng));
  rows.push_back(flip(centres[2], 2, rng));
  const BowVector bow = v.transform(to_mat(rows));
  ASSERT_EQ(bow.size(), 2u);
  const std::map<std::uint32_t, double> m(bow.begin(), bow.end());
  EXPECT_NEAR(m.at(word[1]), 0.5, 1e-12);
  EXPECT_NEAR(m.at(word[2]), 0.5, 1e-12);
  EXPECT_TRUE(v.transform(cv::Mat()).empty());
}

TEST(Vocabulary, ScoreIsDBoW2L1Score) {
  const BowVector a = {{1, 0.5}, {2, 0.5}};
  const BowVector b = {{3, 1.0}};
  const BowVector c = {{1, 0.5}, {3, 0.5}};
  const BowVector d = {{1, 0.25}, {2, 0.25}, {7, 0.5}};
  EXPECT_NEAR(Vocabulary::score(a, a), 1.0, 1e-15);
  EXPECT_NEAR(Vocabulary::score(a, b), 0.0, 1e-15);  // no common word
  EXPECT_NEAR(Vocabulary::score(a, c), 0.5, 1e-15);  // |a - c|_1 = 0 + 0.5 + 0.5
  EXPECT_NEAR(Vocabulary::score(a, d), 0.5, 1e-15);  // |a - d|_1 = 0.25 + 0.25 + 0.5
  EXPECT_NEAR(Vocabulary::score(d, a), 0.5, 1e-15);
  // An empty vector (an image without features) shares no word: 0, also with itself (DBoW2).
  EXPECT_EQ(Vocabulary::score({}, a), 0.0);
  EXPECT_EQ(Vocabulary::score({}, {}), 0.0);
}

struct WorldFixture {
  World world{3000, 42};
  std::vector<cv::Mat> training;
  WorldFixture() {
    std::mt19937_64 rng(7);
    for (int i = 0; i < 60; ++i) training.push_back(world.observe(world.pick(300, rng), 4, rng));
  }
};

TEST(Vocabulary, TransformScoresAnImageHighestWithItsPerturbedCopy) {
  const WorldFixture f;
  VocabularyOptions options;
  options.branching = 10;
  options.depth = 3;
  const Vocabulary v = Vocabulary::train(f.training, options);
  EXPECT_EQ(v.description().rfind("k=10 L=3 ", 0), 0u) << v.description();
  EXPECT_NE(v.description().find("trained on 60 images"), std::string::npos) << v.description();
  std::mt19937_64 rng(99);
  double worst_margin = 1.0;
  for (int trial = 0; trial < 10; ++trial) {
    auto ids = f.world.pick(300, rng);
    const BowVector a = v.transform(f.world.observe(ids, 4, rng));
    // The same place seen again: new noise on every descriptor, 20 % of the landmarks replaced.
    auto again = ids;
    for (std::size_t i = 0; i < again.size(); i += 5) again[i] = rng() % f.world.landmarks.size();
    const BowVector a2 = v.transform(f.world.observe(again, 4, rng));
    const BowVector b = v.transform(f.world.observe(f.world.pick(300, rng), 4, rng));
    expect_normalised(a);
    expect_normalised(a2);
    expect_normalised(b);
    EXPECT_NEAR(Vocabulary::score(a, a), 1.0, 1e-12);
    EXPECT_NEAR(Vocabulary::score(a, a2), Vocabulary::score(a2, a), 1e-12);
    const double same = Vocabulary::score(a, a2), other = Vocabulary::score(a, b);
    EXPECT_GT(same, other) << "trial " << trial;
    EXPECT_GE(other, 0.0);
    EXPECT_LE(same, 1.0);
    worst_margin = std::min(worst_margin, same - other);
  }
  EXPECT_GT(worst_margin, 0.2);
}

TEST(Vocabulary, TrainingIsDeterministicAndIndependentOfThreads) {
  // ~200k descriptors, k = 10, L = 5: the size the brief asks to train in seconds.
  const World world(20000, 3);
  std::mt19937_64 rng(8);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 200; ++i) images.push_back(world.observe(world.pick(1000, rng), 5, rng));
  VocabularyOptions options;  // k = 10, L = 5
  options.max_threads = 1;
  const auto t0 = std::chrono::steady_clock::now();
  const Vocabulary one = Vocabulary::train(images, options);
  const auto t1 = std::chrono::steady_clock::now();
  options.max_threads = 0;
  const Vocabulary all = Vocabulary::train(images, options);
  const auto t2 = std::chrono::steady_clock::now();
  std::cout << "200000 descriptors, k=10 L=5: " << one.description() << "; 1 thread "
            << std::chrono::duration<double>(t1 - t0).count() << " s, all threads " << std::chrono::duration<double>(t2 - t1).count()
            << " s\n";
  EXPECT_GT(one.words(), 10000u);
  const fs::path dir = temp_dir();
  one.save((dir / "one.voc").string());
  all.save((dir / "all.voc").string());
  EXPECT_EQ(read_bytes(dir / "one.voc"), read_bytes(dir / "all.voc"));
  fs::remove_all(dir);
}

TEST(Vocabulary, SaveLoadRoundTripGivesIdenticalTransforms) {
  const WorldFixture f;
  VocabularyOptions options;
  options.branching = 8;
  options.depth = 3;
  const Vocabulary v = Vocabulary::train(f.training, options);
  const fs::path dir = temp_dir();
  const std::string path = (dir / "world.voc").string();
  v.save(path);
  // Size as documented: magic line, 32-byte header, 48 bytes per node but the root, CRC-32.
  const std::string bytes = read_bytes(path);
  EXPECT_EQ(bytes.size(), std::string("CAIRN_BOW_VOCABULARY 1\n").size() + 32 + 48 * (v.nodes() - 1) + 4);
  EXPECT_EQ(bytes.rfind("CAIRN_BOW_VOCABULARY 1\n", 0), 0u);
  const Vocabulary loaded = Vocabulary::load(path);
  EXPECT_EQ(loaded.words(), v.words());
  EXPECT_EQ(loaded.nodes(), v.nodes());
  EXPECT_EQ(loaded.branching(), 8);
  EXPECT_EQ(loaded.depth(), 3);
  EXPECT_EQ(loaded.training_images(), 60u);
  std::mt19937_64 rng(4);
  for (int i = 0; i < 5; ++i) {
    const cv::Mat d = f.world.observe(f.world.pick(300, rng), 6, rng);
    std::vector<std::uint32_t> w1, w2, n1, n2;
    const BowVector a = v.transform(d, &w1, &n1, 1);
    const BowVector b = loaded.transform(d, &w2, &n2, 1);
    EXPECT_EQ(a, b);
    EXPECT_EQ(w1, w2);
    EXPECT_EQ(n1, n2);
  }
  fs::remove_all(dir);
}

TEST(Vocabulary, CorruptCairnFilesAreRejected) {
  const WorldFixture f;
  VocabularyOptions options;
  options.branching = 4;
  options.depth = 2;
  const Vocabulary v = Vocabulary::train(f.training, options);
  const fs::path dir = temp_dir();
  const std::string path = (dir / "good.voc").string();
  v.save(path);
  const std::string good = read_bytes(path);
  auto expect_error = [&](const std::string& name, const std::string& content, std::size_t line, const std::string& says) {
    const std::string p = (dir / name).string();
    write_bytes(p, content);
    try {
      Vocabulary::load(p);
      ADD_FAILURE() << name << " loaded";
    } catch (const io::ParseError& e) {
      EXPECT_EQ(e.file(), p);
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_NE(e.detail().find(says), std::string::npos) << e.what();
    }
  };
  std::string flipped = good;
  flipped[good.size() / 2] = static_cast<char>(flipped[good.size() / 2] ^ 0x10);
  expect_error("flipped.voc", flipped, 0, "checksum");
  expect_error("truncated.voc", good.substr(0, good.size() - 30), 0, "truncated");
  expect_error("header_only.voc", good.substr(0, 40), 0, "truncated");
  std::string version = good;
  version[21] = '2';  // "CAIRN_BOW_VOCABULARY 2"
  expect_error("version.voc", version, 1, "unsupported version");
  expect_error("empty.voc", "", 0, "empty");
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// DBoW2 formats.

std::string bytes_text(int value) {
  std::string s;
  for (int i = 0; i < 32; ++i) s += std::to_string(value) + " ";
  return s;
}

TEST(Vocabulary, LoadsHandWrittenDBoW2TextAndYaml) {
  const fs::path dir = temp_dir();
  // k = 2, L = 1: word 0 = all bits clear (weight 0.5), word 1 = all bits set (weight 1.5).
  const std::string text = "2 1  0 0\n0 1 " + bytes_text(0) + "0.5\n0 1 " + bytes_text(255) + "1.5\n";
  write_bytes(dir / "two.txt", text);
  const Vocabulary t = Vocabulary::load((dir / "two.txt").string());
  EXPECT_EQ(t.branching(), 2);
  EXPECT_EQ(t.depth(), 1);
  EXPECT_EQ(t.words(), 2u);
  EXPECT_EQ(t.weighting(), BowWeighting::kTfIdf);
  Bytes few{}, many{}, zero{};
  few[0] = 0x0F;  // 4 bits set: nearest all-clear
  many.fill(0xFF);
  many[3] = 0;  // 248 bits set: nearest all-set
  const cv::Mat d = to_mat({few, many, zero});
  std::vector<std::uint32_t> words;
  const BowVector tv = t.transform(d, &words);
  EXPECT_EQ(words, (std::vector<std::uint32_t>{0, 1, 0}));
  // tf-idf: word 0 twice (2 x 0.5 = 1.0), word 1 once (1.5): 0.4 and 0.6.
  ASSERT_EQ(tv.size(), 2u);
  EXPECT_NEAR(tv[0].second, 0.4, 1e-12);
  EXPECT_NEAR(tv[1].second, 0.6, 1e-12);

  // The same tree as DBoW2 YAML with binary weighting (each word once: 0.5 and 1.5 -> 0.25,
  // 0.75), with and without blanks after the colons as OpenCV writes them.
  const std::string yaml = "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 3\n   nodes:\n"
                           "      - { nodeId:1, parentId:0, weight:5.0000000000000000e-01,\n          descriptor:\"" +
                           bytes_text(0) + "\" }\n      - { nodeId: 2, parentId: 0, weight: 1.5, descriptor: \"" + bytes_text(255) +
                           "\" }\n   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:2 }\n";
  write_bytes(dir / "two.yml", yaml);
  const Vocabulary y = Vocabulary::load((dir / "two.yml").string());
  EXPECT_EQ(y.weighting(), BowWeighting::kBinary);
  const BowVector yv = y.transform(d);
  ASSERT_EQ(yv.size(), 2u);
  EXPECT_NEAR(yv[0].second, 0.25, 1e-12);
  EXPECT_NEAR(yv[1].second, 0.75, 1e-12);
  fs::remove_all(dir);
}

TEST(Vocabulary, LoadsTheToyDBoW2Vocabulary) {
  CAIRN_REQUIRE_DATA(kToy);
  const std::string path = test::data_path(kToy).string();
  const Vocabulary v = Vocabulary::load(path);
  // SOURCE.txt: k 9, L 3, 781 nodes below the root (9 children of the root), 692 words, tf-idf.
  // Word weights: idf over 4 training images, so 0, ln(4/3), ln 2 or ln 4. Counted in the file
  // with zcat | grep -o 'weight:[^,]*' | sort | uniq -c: 172 x 0 (89 inner nodes + 83 words),
  // 77 x ln(4/3), 143 x ln 2, 389 x ln 4. (SOURCE.txt omits ln(4/3).)
  EXPECT_EQ(v.branching(), 9);
  EXPECT_EQ(v.depth(), 3);
  EXPECT_EQ(v.words(), 692u);
  EXPECT_EQ(v.nodes(), 782u);
  EXPECT_EQ(v.weighting(), BowWeighting::kTfIdf);
  EXPECT_EQ(v.scoring_type(), 0);
  int root_children = 0;
  for (std::uint32_t n = 1; n < v.nodes(); ++n) root_children += v.parent_node(n) == 0 ? 1 : 0;
  EXPECT_EQ(root_children, 9);
  std::map<std::string, int> weight_kinds;
  for (std::uint32_t w = 0; w < v.words(); ++w) {
    const double x = v.word_weight(w);
    if (std::abs(x) < 1e-9) {
      ++weight_kinds["0"];
    } else if (std::abs(x - std::log(4.0 / 3.0)) < 1e-9) {
      ++weight_kinds["ln 4/3"];
    } else if (std::abs(x - std::log(2.0)) < 1e-9) {
      ++weight_kinds["ln 2"];
    } else if (std::abs(x - std::log(4.0)) < 1e-9) {
      ++weight_kinds["ln 4"];
    } else {
      ADD_FAILURE() << "word " << w << " has weight " << x;
    }
  }
  EXPECT_EQ(weight_kinds, (std::map<std::string, int>{{"0", 83}, {"ln 4/3", 77}, {"ln 2", 143}, {"ln 4", 389}}));
  // The file's first word (wordId 0) is node 19 (from the file's words list).
  EXPECT_EQ(v.word_node(0), 19u);
  EXPECT_EQ(v.word_node(691), 781u);

  // It transforms real ORB features, and survives a round trip through cairn's format.
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l/000000.png");
  const Features features = OrbExtractor{}.extract(read_gray_image(test::data_path("visual/kitti_extract_seq2/image_l/000000.png").string()));
  const BowVector bow = v.transform(features.descriptors);
  EXPECT_GT(bow.size(), 20u);
  expect_normalised(bow);
  EXPECT_NEAR(Vocabulary::score(bow, bow), 1.0, 1e-12);
  const fs::path dir = temp_dir();
  v.save((dir / "toy.voc").string());
  const Vocabulary again = Vocabulary::load((dir / "toy.voc").string());
  std::vector<std::uint32_t> n1, n2;
  EXPECT_EQ(again.transform(features.descriptors, nullptr, &n2, 2), v.transform(features.descriptors, nullptr, &n1, 2));
  EXPECT_EQ(n1, n2);
  fs::remove_all(dir);
}

TEST(Vocabulary, MalformedDBoW2FilesNameFileAndLine) {
  const fs::path dir = temp_dir();
  auto expect_error = [&](const std::string& name, const std::string& content, std::size_t line, const std::string& says) {
    const std::string p = (dir / name).string();
    write_bytes(p, content);
    try {
      Vocabulary::load(p);
      ADD_FAILURE() << name << " loaded";
    } catch (const io::ParseError& e) {
      EXPECT_EQ(e.file(), p);
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_NE(e.detail().find(says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos);
    }
  };
  const std::string node0 = "0 1 " + bytes_text(0) + "0.5\n";
  const std::string node1 = "0 1 " + bytes_text(255) + "1.5\n";
  // Text format.
  expect_error("fields.txt", "2 1 0 0\n" + node0 + "0 1 1 2 3 0.5\n", 3, "expected 35 fields");
  expect_error("byte.txt", "2 1 0 0\n0 1 300 " + bytes_text(0).substr(2) + "0.5\n" + node1, 2, "[0, 255]");
  expect_error("weighting.txt", "2 1 0 7\n" + node0 + node1, 1, "weighting");
  expect_error("parent.txt", "2 1 0 0\n5 1 " + bytes_text(0) + "0.5\n" + node1, 2, "parent");
  expect_error("inner.txt", "2 1 0 0\n" + node0 + "0 0 " + bytes_text(255) + "0\n", 3, "no node has it as parent");
  expect_error("weight.txt", "2 1 0 0\n" + node0 + "0 1 " + bytes_text(255) + "nan\n", 3, "weight");
  // Not a vocabulary at all.
  expect_error("graph.g2o", "VERTEX_SE2 0 0 0 0\n", 1, "not a vocabulary");
  expect_error("binary.bin", std::string("\x89PNG\r\n\x1a\n\0\0\0", 12), 1, "not a vocabulary");
  // YAML.
  const std::string head = "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 1\n   scoringType: 0\n   weightingType: 0\n   nodes:\n";
  const std::string words = "   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:2 }\n";
  const std::string y1 = "      - { nodeId:1, parentId:0, weight:0.5, descriptor:\"" + bytes_text(0) + "\" }\n";
  const std::string y2 = "      - { nodeId:2, parentId:0, weight:1.5, descriptor:\"" + bytes_text(255) + "\" }\n";
  expect_error("short.yml", head + y1 + "      - { nodeId:2, parentId:0, weight:1.5, descriptor:\"1 2 3\" }\n" + words, 10,
               "expected 32 descriptor bytes");
  std::string surf;
  for (int i = 0; i < 64; ++i) surf += "0.125 ";
  expect_error("surf.yml", head + y1 + "      - { nodeId:2, parentId:0, weight:1.5, descriptor:\"" + surf + "\" }\n" + words, 10,
               "only ORB");
  std::string bad_weighting = head;
  bad_weighting.replace(bad_weighting.find("weightingType: 0"), 16, "weightingType: 9");
  expect_error("weighting.yml", bad_weighting + y1 + y2 + words, 7, "weightingType");
  expect_error("nowords.yml", head + y1 + y2, 10, "words");
  expect_error("duplicate.yml", head + y1 + y1 + words, 10, "listed twice");
  expect_error("key.yml", head + y1 + "      - { nodeId:2, parent:0, weight:1.5, descriptor:\"" + bytes_text(255) + "\" }\n" + words, 10,
               "unexpected key 'parent'");
  expect_error("wordnode.yml", head + y1 + y2 + "   words:\n      - { wordId:0, nodeId:1 }\n      - { wordId:1, nodeId:1 }\n", 13,
               "given words");
  fs::remove_all(dir);
}

TEST(Vocabulary, TruncatedToyVocabularyIsRejected) {
  CAIRN_REQUIRE_DATA(kToy);
  const std::string gz = read_bytes(test::data_path(kToy));
  const fs::path dir = temp_dir();
  // The gzip stream cut in half: the decompressor reports it (the whole file, line 0).
  const std::string cut_gz = (dir / "cut.yml.gz").string();
  write_bytes(cut_gz, gz.substr(0, gz.size() / 2));
  try {
    Vocabulary::load(cut_gz);
    ADD_FAILURE() << "a truncated gzip file loaded";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.file(), cut_gz);
    EXPECT_EQ(e.line(), 0u) << e.what();  // the compressed stream, not a line, is at fault
  }
  fs::remove_all(dir);
}

TEST(Vocabulary, YamlCutInsideANodeNamesItsLine) {
  // Built here, not decompressed from the toy file: a 3-node tree cut inside node 3's mapping.
  const std::string head = "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 2\n   scoringType: 0\n   weightingType: 0\n   nodes:\n";
  const std::string content = head + "      - { nodeId:1, parentId:0, weight:0.5,\n          descriptor:\"" + bytes_text(0) +
                              "\" }\n      - { nodeId:2, parentId:0, weight:0.5,\n          descriptor:\"" + bytes_text(255) +
                              "\" }\n      - { nodeId:3, parentId:1, weight:0.5,\n          descr";
  const fs::path dir = temp_dir();
  write_bytes(dir / "cut.yml", content);
  try {
    Vocabulary::load((dir / "cut.yml").string());
    ADD_FAILURE() << "a cut YAML file loaded";
  } catch (const io::ParseError& e) {
    EXPECT_EQ(e.line(), 13u) << e.what();  // "- { nodeId:3, ..." is line 13
    EXPECT_NE(e.detail().find("unterminated"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------

TEST(BowDatabase, QueryRanksByL1ScoreOverCommonWords) {
  BowDatabase db;
  db.add(1, {{1, 0.5}, {2, 0.5}});
  db.add(2, {{2, 0.25}, {3, 0.75}});
  db.add(3, {{4, 1.0}});
  EXPECT_EQ(db.size(), 3u);
  const BowVector q = {{2, 0.5}, {3, 0.5}};
  // By hand: entry 2 shares words 2 and 3 (min 0.25 + min 0.5 = 0.75), entry 1 word 2 (0.5),
  // entry 3 nothing.
  auto r = db.query(q, 10);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].id, 2u);
  EXPECT_NEAR(r[0].score, 0.75, 1e-12);
  EXPECT_EQ(r[0].common_words, 2);
  EXPECT_EQ(r[1].id, 1u);
  EXPECT_NEAR(r[1].score, 0.5, 1e-12);
  EXPECT_EQ(r[1].common_words, 1);
  EXPECT_EQ(db.query(q, 1).size(), 1u);
  r = db.query(q, 10, {2});
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 1u);
  db.erase(2);
  db.erase(77);  // absent: nothing happens
  EXPECT_EQ(db.size(), 2u);
  r = db.query(q, 10);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 1u);
  db.add(1, {{4, 1.0}});  // replaces entry 1
  EXPECT_TRUE(db.query(q, 10).empty());
}

TEST(BowDatabase, FindsTheRevisitedPlaceAmongManyAndAgreesWithScore) {
  const WorldFixture f;
  VocabularyOptions options;
  options.branching = 10;
  options.depth = 3;
  const Vocabulary v = Vocabulary::train(f.training, options);
  std::mt19937_64 rng(21);
  std::vector<std::vector<std::size_t>> places;
  std::vector<BowVector> vectors;
  BowDatabase db;
  for (std::uint32_t id = 0; id < 40; ++id) {
    places.push_back(f.world.pick(300, rng));
    vectors.push_back(v.transform(f.world.observe(places.back(), 4, rng)));
    db.add(id, vectors.back());
  }
  for (const std::uint32_t revisit : {3u, 17u, 39u}) {
    const BowVector q = v.transform(f.world.observe(places[revisit], 4, rng));
    const auto r = db.query(q, 5);
    ASSERT_FALSE(r.empty());
    EXPECT_EQ(r[0].id, revisit);
    for (std::size_t i = 0; i < r.size(); ++i) {
      // Fast path against brute force: the accumulated score equals the full L1 score.
      EXPECT_NEAR(r[i].score, Vocabulary::score(q, vectors[r[i].id]), 1e-9);
      if (i > 0) {
        EXPECT_GE(r[i - 1].score, r[i].score);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Real images: trained on the 51 KITTI left images, evaluated on TUM fr1/desk.

TEST(VocabularyRealImages, TumRevisitScoresAboveDistantFrames) {
  const std::string kitti = "visual/kitti_extract_seq2/image_l";
  const std::string tum = "visual/tum_fr1_desk_every4th";
  CAIRN_REQUIRE_DATA(kitti);
  CAIRN_REQUIRE_DATA(tum + "/rgb.txt");
  const OrbExtractor orb;
  std::vector<fs::path> kitti_images;
  for (const auto& e : fs::directory_iterator(test::data_path(kitti))) {
    if (e.path().extension() == ".png") kitti_images.push_back(e.path());
  }
  std::sort(kitti_images.begin(), kitti_images.end());
  ASSERT_EQ(kitti_images.size(), 51u);
  std::vector<cv::Mat> training(kitti_images.size());
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < kitti_images.size(); ++i) training[i] = orb.extract(read_gray_image(kitti_images[i].string())).descriptors;
  const auto t1 = std::chrono::steady_clock::now();
  VocabularyOptions options;
  options.depth = 4;  // ~100k descriptors: k^L = 10^4 words keeps ~10 descriptors per word
  const Vocabulary v = Vocabulary::train(training, options);
  const auto t2 = std::chrono::steady_clock::now();
  std::cout << "KITTI: ORB " << std::chrono::duration<double>(t1 - t0).count() << " s, training "
            << std::chrono::duration<double>(t2 - t1).count() << " s: " << v.description() << "\n";

  std::vector<std::string> frames;
  std::ifstream list(test::data_path(tum + "/rgb.txt"));
  for (std::string line; std::getline(list, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string stamp, file;
    fields >> stamp >> file;
    frames.push_back(file);
  }
  ASSERT_GT(frames.size(), 122u);
  std::vector<BowVector> bows(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    bows[k] = v.transform(orb.extract(read_gray_image(test::data_path(tum + "/" + frames[k]).string())).descriptors);
  }
  const BowVector& query = bows[122];
  const double revisit = Vocabulary::score(query, bows[13]);
  std::cout << "TUM s(122, 13) = " << revisit << "; s(122, k) for k = 60..70:";
  double best_far = 0.0;
  for (std::size_t k = 60; k <= 70; ++k) {
    const double s = Vocabulary::score(query, bows[k]);
    std::cout << " " << s;
    EXPECT_GT(revisit, s) << "frame " << k;
    best_far = std::max(best_far, s);
  }
  std::cout << "\n";
  EXPECT_GT(revisit, best_far);
  // The database over every frame more than 10 frames (~1.3 s) away from 122: its best match is
  // in the revisited stretch around frame 13 (the camera passes that part of the desk at frames
  // ~10-20 and again at ~122).
  BowDatabase db;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (k + 10 < 122 || k > 132) db.add(static_cast<std::uint32_t>(k), bows[k]);
  }
  const auto best = db.query(query, 3);
  ASSERT_EQ(best.size(), 3u);
  std::cout << "TUM database query of frame 122: " << best[0].id << " (" << best[0].score << "), " << best[1].id << " ("
            << best[1].score << "), " << best[2].id << " (" << best[2].score << ")\n";
  EXPECT_GE(best[0].id, 8u);
  EXPECT_LE(best[0].id, 20u);
}

}  // namespace
}  // namespace cairn::vision
