#pragma once
/// \file
/// Bag-of-binary-words place recognition for ORB descriptors, as DBoW2: D. Galvez-Lopez and
/// J. D. Tardos, "Bags of Binary Words for Fast Place Recognition in Image Sequences", IEEE T-RO
/// 28(5), 2012 (below "the paper").
///
/// * Vocabulary (paper Sec. III): a tree of k branches and L levels below the root built by
///   hierarchical k-means++ over binary descriptors; a node's descriptor is the bitwise majority of
///   its members (DBoW2 FORB::meanValue); the leaves are the words. A descriptor becomes a word by
///   descending from the root to the child of least Hamming distance at each level (k L
///   distances). Word weights are tf-idf, eq. (1): v_i = (n_id / n_d) log(N / N_i); the idf
///   log(N / N_i) is stored in the word, the tf part is counted when an image is transformed.
/// * Score (paper eq. (2), DBoW2 L1Scoring): s(v1, v2) = 1 - 1/2 | v1/|v1| - v2/|v2| |_1 in [0, 1].
/// * Direct index (paper Sec. IV, DBoW2 FeatureVector): the node `levels_up` levels above the
///   leaves that each feature passes through, to restrict matching to features in the same node.
/// * Inverted index (paper Sec. IV): BowDatabase, word -> (entry, weight), so a query visits only
///   the entries that share a word with it.
///
/// Files: cairn's own binary format (docs/formats.md, "BoW vocabulary"), DBoW2's text format
/// (ORB-SLAM2's ORBvoc.txt, TemplatedVocabulary::loadFromTextFile) and DBoW2's OpenCV-FileStorage
/// YAML (TemplatedVocabulary::save, optionally gzipped).

#include <opencv2/core.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace cairn::vision {

struct VocabularyOptions {
  int branching = 10;         ///< k, children per node, in [2, 64]
  int depth = 5;              ///< L, levels below the root, in [1, 12]; k^L must stay below 2^31
  int kmeans_iterations = 10; ///< cap on Lloyd iterations per node (stops earlier when no
                              ///< assignment changes), in [1, 1000]
  std::uint64_t seed = 1;     ///< k-means++ seeding; the tree depends only on the data and this
  int max_threads = 0;        ///< worker threads for training; 0 = all (TBB's default). The
                              ///< result does not depend on it.
  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

/// Sparse bag-of-words vector: (word id, weight) sorted by word id, weights > 0, L1-normalised
/// (weights sum to 1); empty when no descriptor reached a word of positive weight.
using BowVector = std::vector<std::pair<std::uint32_t, double>>;

/// Word weighting, numbered as DBoW2's WeightingType (the numbers are stored in files).
enum class BowWeighting : int { kTfIdf = 0, kTf = 1, kIdf = 2, kBinary = 3 };

class Vocabulary {
 public:
  static constexpr std::uint32_t kNoWord = 0xFFFFFFFFu;

  /// An empty vocabulary (no words); transform() must not be called on it.
  Vocabulary() = default;

  /// Hierarchical k-means++ (Arthur & Vassilvitskii 2007, D^2 seeding) over the rows of every
  /// matrix (N x 32 CV_8U, one matrix per training image; empty matrices allowed), as DBoW2's
  /// TemplatedVocabulary::create / HKmeansStep: a node with more than one distinct descriptor is
  /// split into at most k clusters until depth L; centres are bitwise majorities (a bit is set when
  /// at least half of the members have it, DBoW2 FORB::meanValue); leaves are words, numbered in
  /// node order. Word weight = idf = log(N_images / N_images containing the word) (DBoW2
  /// TF_IDF; 0 for a word no training image reaches). Deterministic for a seed, independent of
  /// the thread count. Throws std::invalid_argument for bad options, a matrix that is not
  /// N x 32 CV_8U, or fewer than 2 distinct descriptors in all.
  static Vocabulary train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularyOptions& options);

  /// Reads cairn's format, DBoW2's text format or DBoW2's YAML, told apart by content (gzip,
  /// bzip2 and xz are decompressed first). Throws io::ParseError naming the file, the line (text
  /// formats) or byte offset (cairn's binary format), what was expected and what was found.
  /// Only ORB vocabularies (32-byte descriptors) are supported; any DBoW2 weighting and scoring
  /// type is accepted (the scoring type is kept, but score() is always L1).
  static Vocabulary load(const std::string& path);
  /// Writes cairn's format (whole or not at all, io::write_output). Throws io::ParseError.
  void save(const std::string& path) const;

  /// Bag of words of the descriptors (N x 32 CV_8U, or empty): per feature its word; weights as
  /// DBoW2 transform: tf-idf and tf sum the word weight over the features, idf and binary count a
  /// word once; words of weight 0 are left out; then L1-normalised. `word_of_feature` (optional)
  /// gets each row's word id. `node_of_feature` (optional) gets each row's node at depth
  /// L - levels_up on its path from the root (the root, 0, when that is <= 0; the leaf when the
  /// path ends above that depth): DBoW2's FeatureVector direct index.
  BowVector transform(const cv::Mat& descriptors, std::vector<std::uint32_t>* word_of_feature = nullptr,
                      std::vector<std::uint32_t>* node_of_feature = nullptr, int levels_up = 4) const;

  /// DBoW2 L1 score: 1 - 0.5 | a - b |_1 (paper eq. (2)) for L1-normalised vectors, in [0, 1]:
  /// 1 for equal vectors, 0 for vectors without a common word. Computed over the common words as
  /// DBoW2's L1Scoring (so an empty vector scores 0 with anything, itself included).
  static double score(const BowVector& a, const BowVector& b);

  std::size_t words() const { return node_of_word_.size(); }
  /// Nodes including the root (node 0).
  std::size_t nodes() const { return parent_.size(); }
  int branching() const { return k_; }
  int depth() const { return L_; }
  BowWeighting weighting() const { return weighting_; }
  /// DBoW2 ScoringType of the file (0 = L1 for everything cairn trains).
  int scoring_type() const { return scoring_; }
  /// Images the vocabulary was trained on; 0 when unknown (DBoW2 files do not say).
  std::size_t training_images() const { return training_images_; }
  double word_weight(std::uint32_t word) const;
  std::uint32_t word_node(std::uint32_t word) const;
  /// Parent of a node other than the root.
  std::uint32_t parent_node(std::uint32_t node) const;
  /// e.g. "k=10 L=5 4312 words (tf-idf), trained on 102 images".
  std::string description() const;
  /// 64-bit FNV-1a hash of what transform() depends on (k, L, weighting, the tree, every node's
  /// descriptor and weight): equal for the same vocabulary however it was stored (cairn's format,
  /// DBoW2's text or YAML), different for another one in all practical cases. A saved visual map
  /// records it (vslam/saved_map.hpp) so that it is only reused with the vocabulary it was made with.
  std::uint64_t fingerprint() const;

 private:
  using Descriptor = std::array<std::uint64_t, 4>;
  friend class VocabularyBuilder;

  /// Builds the children lists (in increasing id order) from parent_ and checks the tree.
  void link_children();
  std::uint32_t descend(const Descriptor& d, int node_level, std::uint32_t* node_at_level) const;

  int k_ = 0;
  int L_ = 0;
  BowWeighting weighting_ = BowWeighting::kTfIdf;
  int scoring_ = 0;
  std::size_t training_images_ = 0;
  std::string origin_;
  std::vector<std::uint32_t> parent_;        // per node; parent_[0] = 0 (root)
  std::vector<Descriptor> descriptor_;       // per node (root: zeros)
  std::vector<double> weight_;               // per node (only words' weights are used)
  std::vector<std::uint32_t> word_of_node_;  // kNoWord for inner nodes
  std::vector<std::uint32_t> first_child_;   // children of n: children_[first_child_[n] .. first_child_[n + 1])
  std::vector<std::uint32_t> children_;
  std::vector<std::uint32_t> node_of_word_;
};

/// Inverted-index database of keyframe BoW vectors (paper Sec. IV).
class BowDatabase {
 public:
  /// Adds (or replaces) entry `id`. `v` should be L1-normalised (Vocabulary::transform).
  void add(std::uint32_t id, const BowVector& v);
  /// Removes entry `id`; nothing happens when it is absent.
  void erase(std::uint32_t id);

  struct Result {
    std::uint32_t id;
    double score;      ///< Vocabulary::score of the query and the entry
    int common_words;  ///< words both have
  };
  /// Entries sharing at least one word with `v`, best score first (ties: lower id first), at
  /// most max_results; `exclude` ids are skipped. Visits only the posting lists of v's words; the
  /// L1 score is accumulated over the common words as sum of min(a_i, b_i), which equals
  /// 1 - 0.5 |a - b|_1 for L1-normalised vectors (DBoW2 L1Scoring::score).
  std::vector<Result> query(const BowVector& v, std::size_t max_results,
                            const std::vector<std::uint32_t>& exclude = {}) const;
  std::size_t size() const { return entries_.size(); }

 private:
  struct Posting {
    std::uint32_t id;
    double weight;
  };
  std::unordered_map<std::uint32_t, std::vector<Posting>> index_;  // word -> entries
  std::unordered_map<std::uint32_t, BowVector> entries_;
};

}  // namespace cairn::vision
