#include "cairn/vision/vocabulary.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <unordered_set>

#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/threads.hpp"
#include "cairn/io/compressed_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::vision {

namespace {

using Descriptor = std::array<std::uint64_t, 4>;
constexpr int kDescriptorBytes = 32;
constexpr std::string_view kMagic = "CAIRN_BOW_VOCABULARY";
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::size_t kHeaderBytes = 8 * 4;
constexpr std::size_t kNodeRecordBytes = 4 + 4 + 32 + 8;
// Largest node weight a vocabulary may hold. An idf weight is log(images / images with the word),
// below 23 for 2^32 images; far larger weights are corrupt, and near DBL_MAX they make transform()
// sum to infinity and return NaN weights.
constexpr double kMaxNodeWeight = 1e6;

int distance(const Descriptor& a, const Descriptor& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

Descriptor row_descriptor(const cv::Mat& m, int row) {
  Descriptor d;
  std::memcpy(d.data(), m.ptr(row), kDescriptorBytes);
  return d;
}

const unsigned char* bytes_of(const Descriptor& d) { return reinterpret_cast<const unsigned char*>(d.data()); }

std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Byte v -> a 64-bit word whose byte j is bit j of v: adding these counts the eight bits of a
// byte in eight 8-bit lanes at once (flushed before a lane can overflow).
constexpr std::array<std::uint64_t, 256> make_spread() {
  std::array<std::uint64_t, 256> t{};
  for (std::uint64_t v = 0; v < 256; ++v) {
    for (std::uint64_t j = 0; j < 8; ++j) t[v] |= ((v >> j) & 1u) << (8 * j);
  }
  return t;
}
constexpr std::array<std::uint64_t, 256> kSpread = make_spread();

// Runs body(begin, end) over [0, n), in parallel when n is large. Every index is processed
// independently, so the result does not depend on the partition.
template <class Body>
void for_range(std::size_t n, const Body& body) {
  if (n < 8192) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

void check_descriptor_matrix(const cv::Mat& m, const std::string& what) {
  if (m.empty()) return;
  if (m.type() != CV_8U || m.cols != kDescriptorBytes || m.dims != 2) {
    throw std::invalid_argument(what + ": expected N x 32 CV_8U ORB descriptors, found " + std::to_string(m.rows) + " x " +
                                std::to_string(m.cols) + " of type " + std::to_string(m.type()));
  }
}

std::string weighting_name(BowWeighting w) {
  switch (w) {
    case BowWeighting::kTfIdf: return "tf-idf";
    case BowWeighting::kTf: return "tf";
    case BowWeighting::kIdf: return "idf";
    case BowWeighting::kBinary: return "binary";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// Number parsing for the loaders.

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::optional<std::int64_t> to_integer(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty()) return std::nullopt;
  return v;
}

std::optional<double> to_finite(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || s.empty() || !std::isfinite(v)) return std::nullopt;
  return v;
}

// 32 decimal bytes separated by blanks (DBoW2 FORB::toString / fromString); nullopt with a reason.
std::optional<Descriptor> parse_descriptor_bytes(const std::vector<std::string_view>& tokens, std::string* why) {
  if (tokens.size() != kDescriptorBytes) {
    *why = "expected 32 descriptor bytes (only ORB vocabularies, 256-bit descriptors, are supported), found " +
           std::to_string(tokens.size()) + " values";
    return std::nullopt;
  }
  std::array<unsigned char, kDescriptorBytes> bytes{};
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const auto v = to_integer(tokens[i]);
    if (!v || *v < 0 || *v > 255) {
      *why = "expected descriptor byte " + std::to_string(i) + " to be an integer in [0, 255] (only ORB vocabularies are supported), found " +
             io::quote_token(tokens[i]);
      return std::nullopt;
    }
    bytes[i] = static_cast<unsigned char>(*v);
  }
  Descriptor d;
  std::memcpy(d.data(), bytes.data(), kDescriptorBytes);
  return d;
}

// ---------------------------------------------------------------------------------------------
// CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320; the value of zlib's crc32()).

constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int j = 0; j < 8; ++j) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    t[i] = c;
  }
  return t;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

std::uint32_t crc32(std::string_view data) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (const char ch : data) c = kCrcTable[(c ^ static_cast<unsigned char>(ch)) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
std::uint32_t get_u32(std::string_view s, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + i])) << (8 * i);
  return v;
}
std::uint64_t get_u64(std::string_view s, std::size_t at) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(static_cast<unsigned char>(s[at + i])) << (8 * i);
  return v;
}

struct Cluster {
  Descriptor centre{};
  std::vector<std::uint32_t> members;
};

// One k-means++ clustering of `members` (indices into `data`) into at most k clusters with
// bitwise-majority centres. Returns no clusters when the members cannot be split (fewer than 2
// distinct descriptors), which makes the node a leaf.
std::vector<Cluster> cluster_node(const std::vector<Descriptor>& data, const std::vector<std::uint32_t>& members, int k,
                                  int iterations, std::uint64_t seed) {
  const std::size_t n = members.size();
  if (n < 2) return {};
  std::uint64_t rng = seed;
  // k-means++ seeding (Arthur & Vassilvitskii, SODA 2007): the next centre is drawn with
  // probability proportional to the squared distance to the nearest centre so far. (DBoW2's
  // initiateClustersKMpp draws proportional to the plain distance.)
  std::vector<Descriptor> centres;
  centres.push_back(data[members[splitmix64(rng) % n]]);
  std::vector<std::uint32_t> d2(n);
  for_range(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto d = static_cast<std::uint32_t>(distance(data[members[i]], centres[0]));
      d2[i] = d * d;
    }
  });
  while (centres.size() < static_cast<std::size_t>(k)) {
    std::uint64_t sum = 0;
    for (const std::uint32_t v : d2) sum += v;
    if (sum == 0) break;  // every member equals a centre
    const std::uint64_t r = splitmix64(rng) % sum;
    std::uint64_t cumulative = 0;
    std::size_t pick = 0;
    for (; pick < n; ++pick) {
      cumulative += d2[pick];
      if (cumulative > r) break;
    }
    centres.push_back(data[members[pick]]);
    const Descriptor& c = centres.back();
    for_range(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const auto d = static_cast<std::uint32_t>(distance(data[members[i]], c));
        d2[i] = std::min(d2[i], d * d);
      }
    });
  }
  const std::size_t m = centres.size();
  if (m < 2) return {};

  std::vector<std::uint32_t> assignment(n, 0xFFFFFFFFu);
  // Nearest centre of every member (first on ties, as DBoW2); true when any assignment changed.
  auto assign = [&]() {
    std::vector<unsigned char> changed_in_block((n + 4095) / 4096, 0);
    for_range(n, [&](std::size_t b, std::size_t e) {
      bool changed = false;
      for (std::size_t i = b; i < e; ++i) {
        const Descriptor& x = data[members[i]];
        std::uint32_t best = 0;
        int best_d = distance(x, centres[0]);
        for (std::size_t c = 1; c < m; ++c) {
          const int d = distance(x, centres[c]);
          if (d < best_d) {
            best_d = d;
            best = static_cast<std::uint32_t>(c);
          }
        }
        if (assignment[i] != best) {
          assignment[i] = best;
          changed = true;
        }
      }
      if (changed) changed_in_block[b / 4096] = 1;
    });
    return std::any_of(changed_in_block.begin(), changed_in_block.end(), [](unsigned char c) { return c != 0; });
  };
  // Centres = bitwise majority of their members (DBoW2 FORB::meanValue: a bit is set when at
  // least ceil(N/2) members have it). Bits are counted per fixed block of members and summed;
  // integer sums, so the result does not depend on the threads. An empty cluster keeps its centre.
  auto update_centres = [&]() {
    constexpr std::size_t kBlock = 16384;
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<std::vector<std::uint32_t>> counts(blocks);
    std::vector<std::vector<std::uint32_t>> sizes(blocks);
    auto count_block = [&](std::size_t block) {
      std::vector<std::uint32_t>& cnt = counts[block];
      std::vector<std::uint32_t>& size = sizes[block];
      cnt.assign(m * 256, 0);
      size.assign(m, 0);
      std::vector<std::uint64_t> lanes(m * kDescriptorBytes, 0);
      std::vector<std::uint32_t> pending(m, 0);
      auto flush = [&](std::size_t c) {
        for (std::size_t b = 0; b < kDescriptorBytes; ++b) {
          const std::uint64_t lane = lanes[c * kDescriptorBytes + b];
          for (std::size_t j = 0; j < 8; ++j) cnt[c * 256 + b * 8 + j] += static_cast<std::uint32_t>((lane >> (8 * j)) & 0xFFu);
          lanes[c * kDescriptorBytes + b] = 0;
        }
        pending[c] = 0;
      };
      const std::size_t end = std::min(n, (block + 1) * kBlock);
      for (std::size_t i = block * kBlock; i < end; ++i) {
        const std::size_t c = assignment[i];
        const unsigned char* bytes = bytes_of(data[members[i]]);
        std::uint64_t* lane = &lanes[c * kDescriptorBytes];
        for (std::size_t b = 0; b < kDescriptorBytes; ++b) lane[b] += kSpread[bytes[b]];
        ++size[c];
        if (++pending[c] == 255) flush(c);
      }
      for (std::size_t c = 0; c < m; ++c) flush(c);
    };
    if (blocks == 1) {
      count_block(0);
    } else {
      tbb::parallel_for(std::size_t{0}, blocks, count_block);
    }
    for (std::size_t c = 0; c < m; ++c) {
      std::uint64_t size = 0;
      for (std::size_t blk = 0; blk < blocks; ++blk) size += sizes[blk][c];
      if (size == 0) continue;
      std::array<unsigned char, kDescriptorBytes> out{};
      for (std::size_t bit = 0; bit < 256; ++bit) {
        std::uint64_t total = 0;
        for (std::size_t blk = 0; blk < blocks; ++blk) total += counts[blk][c * 256 + bit];
        if (2 * total >= size) out[bit / 8] = static_cast<unsigned char>(out[bit / 8] | (1u << (bit % 8)));
      }
      std::memcpy(centres[c].data(), out.data(), kDescriptorBytes);
    }
  };

  assign();
  for (int iteration = 0; iteration < iterations; ++iteration) {
    update_centres();
    if (!assign()) break;  // converged: the centres are the majorities of the final clusters
    if (iteration + 1 == iterations) update_centres();  // capped: centres of the final clusters
  }

  std::vector<Cluster> clusters(m);
  for (std::size_t c = 0; c < m; ++c) clusters[c].centre = centres[c];
  for (std::size_t i = 0; i < n; ++i) clusters[assignment[i]].members.push_back(members[i]);
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(), [](const Cluster& c) { return c.members.empty(); }),
                 clusters.end());
  if (clusters.size() < 2) return {};
  return clusters;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Construction and checks shared by training and the three loaders.

class VocabularyBuilder {
 public:
  struct Problem {
    std::uint32_t node;
    std::string message;
  };

  // Links the tree and checks it: parents in range, every node reachable from the root (no
  // cycle), at most k children, depth at most L, words exactly on the leaves, word ids 0..W-1
  // each once, weights finite and >= 0. Returns the first problem.
  static std::optional<Problem> link_and_check(Vocabulary& v) {
    const std::size_t n = v.parent_.size();
    if (n < 2) return Problem{0, "the vocabulary has no nodes below the root"};
    for (std::uint32_t i = 1; i < n; ++i) {
      if (v.parent_[i] >= n || v.parent_[i] == i) {
        return Problem{i, "node " + std::to_string(i) + " has parent " + std::to_string(v.parent_[i]) +
                              ", expected another node id in [0, " + std::to_string(n - 1) + "]"};
      }
      if (!(v.weight_[i] >= 0.0) || !std::isfinite(v.weight_[i])) {
        return Problem{i, "node " + std::to_string(i) + " has weight " + std::to_string(v.weight_[i]) + ", expected a finite number >= 0"};
      }
      if (v.weight_[i] > kMaxNodeWeight) {
        char weight[32];
        std::snprintf(weight, sizeof weight, "%g", v.weight_[i]);
        return Problem{i, "node " + std::to_string(i) + " has weight " + weight + ", expected at most 1e6 (an idf weight, log(images / images with the word))"};
      }
    }
    v.link_children();
    // Breadth-first from the root: depth of every node.
    std::vector<int> level(n, -1);
    level[0] = 0;
    std::vector<std::uint32_t> queue{0};
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const std::uint32_t node = queue[q];
      const std::uint32_t count = v.first_child_[node + 1] - v.first_child_[node];
      if (count > static_cast<std::uint32_t>(v.k_)) {
        return Problem{node, "node " + std::to_string(node) + " has " + std::to_string(count) + " children, expected at most k = " +
                                 std::to_string(v.k_)};
      }
      for (std::uint32_t c = v.first_child_[node]; c < v.first_child_[node + 1]; ++c) {
        const std::uint32_t child = v.children_[c];
        level[child] = level[node] + 1;
        if (level[child] > v.L_) {
          return Problem{child, "node " + std::to_string(child) + " is at depth " + std::to_string(level[child]) +
                                    ", expected at most L = " + std::to_string(v.L_)};
        }
        queue.push_back(child);
      }
    }
    for (std::uint32_t i = 1; i < n; ++i) {
      if (level[i] < 0) return Problem{i, "node " + std::to_string(i) + " is not connected to the root (its parents form a cycle)"};
    }
    std::size_t leaves = 0;
    for (std::uint32_t i = 1; i < n; ++i) {
      const bool leaf = v.first_child_[i] == v.first_child_[i + 1];
      leaves += leaf ? 1 : 0;
      if (leaf && v.word_of_node_[i] == Vocabulary::kNoWord) return Problem{i, "leaf node " + std::to_string(i) + " has no word"};
      if (!leaf && v.word_of_node_[i] != Vocabulary::kNoWord) {
        return Problem{i, "node " + std::to_string(i) + " has children but is word " + std::to_string(v.word_of_node_[i]) +
                              " (words must be leaves)"};
      }
    }
    if (v.word_of_node_[0] != Vocabulary::kNoWord) return Problem{0, "the root cannot be a word"};
    v.node_of_word_.assign(leaves, Vocabulary::kNoWord);
    for (std::uint32_t i = 1; i < n; ++i) {
      const std::uint32_t w = v.word_of_node_[i];
      if (w == Vocabulary::kNoWord) continue;
      if (w >= leaves) {
        return Problem{i, "node " + std::to_string(i) + " is word " + std::to_string(w) + ", expected word ids 0.." +
                              std::to_string(leaves - 1) + " (one per leaf)"};
      }
      if (v.node_of_word_[w] != Vocabulary::kNoWord) {
        return Problem{i, "word " + std::to_string(w) + " is given to nodes " + std::to_string(v.node_of_word_[w]) + " and " +
                              std::to_string(i)};
      }
      v.node_of_word_[w] = i;
    }
    return std::nullopt;
  }

  static void resize(Vocabulary& v, std::size_t nodes) {
    v.parent_.assign(nodes, 0);
    v.descriptor_.assign(nodes, Descriptor{});
    v.weight_.assign(nodes, 0.0);
    v.word_of_node_.assign(nodes, Vocabulary::kNoWord);
  }

  static Vocabulary train(const std::vector<cv::Mat>& images, const VocabularyOptions& options);
  static Vocabulary parse_cairn(const std::string& path, const std::string& content);
  static Vocabulary parse_dbow2_text(const std::string& path, const std::string& content);
  static Vocabulary parse_dbow2_yaml(const std::string& path, const std::string& content);
};

void Vocabulary::link_children() {
  const std::size_t n = parent_.size();
  first_child_.assign(n + 1, 0);
  for (std::size_t i = 1; i < n; ++i) ++first_child_[parent_[i] + 1];
  for (std::size_t i = 0; i < n; ++i) first_child_[i + 1] += first_child_[i];
  children_.assign(n > 0 ? n - 1 : 0, 0);
  std::vector<std::uint32_t> fill(first_child_.begin(), first_child_.end() - 1);
  for (std::uint32_t i = 1; i < n; ++i) children_[fill[parent_[i]]++] = i;  // increasing id per parent
}

std::uint32_t Vocabulary::descend(const Descriptor& d, int node_level, std::uint32_t* node_at_level) const {
  // DBoW2 TemplatedVocabulary::transform: from the root, the child of least Hamming distance
  // (the first on ties) at every level until a leaf.
  std::uint32_t node = 0;
  int level = 0;
  if (node_at_level != nullptr) *node_at_level = 0;
  while (first_child_[node] != first_child_[node + 1]) {
    ++level;
    const std::uint32_t begin = first_child_[node], end = first_child_[node + 1];
    std::uint32_t best = children_[begin];
    int best_d = distance(d, descriptor_[best]);
    for (std::uint32_t c = begin + 1; c < end; ++c) {
      const int dist = distance(d, descriptor_[children_[c]]);
      if (dist < best_d) {
        best_d = dist;
        best = children_[c];
      }
    }
    node = best;
    if (node_at_level != nullptr && level == node_level) *node_at_level = node;
  }
  if (node_at_level != nullptr && node_level > level) *node_at_level = node;
  return node;
}

// ---------------------------------------------------------------------------------------------
// Training.

bool VocabularyOptions::is_valid(std::string* why) const {
  core::Problems problems;
  auto add = [&](const std::string& p) { problems.add(p); };
  if (branching < 2 || branching > 64) add("branching must be in [2, 64]");
  if (depth < 1 || depth > 12) add("depth must be in [1, 12]");
  if (branching >= 2 && branching <= 64 && depth >= 1 && depth <= 12 &&
      std::pow(static_cast<double>(branching), static_cast<double>(depth)) >= 2147483648.0) {
    add("branching^depth must be below 2^31 words");
  }
  if (kmeans_iterations < 1 || kmeans_iterations > 1000) add("kmeans_iterations must be in [1, 1000]");
  if (max_threads < 0) add("max_threads must be >= 0 (0 = all)");
  return problems.report(why);
}

Vocabulary VocabularyBuilder::train(const std::vector<cv::Mat>& images, const VocabularyOptions& options) {
  std::vector<Descriptor> data;
  std::size_t total = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    check_descriptor_matrix(images[i], "vocabulary training image " + std::to_string(i));
    total += images[i].empty() ? 0 : static_cast<std::size_t>(images[i].rows);
  }
  if (total >= 0xFFFFFFFFu) throw std::invalid_argument("vocabulary training: too many descriptors (at most 2^32 - 2)");
  data.reserve(total);
  for (const cv::Mat& m : images) {
    for (int r = 0; !m.empty() && r < m.rows; ++r) data.push_back(row_descriptor(m, r));
  }

  Vocabulary v;
  v.k_ = options.branching;
  v.L_ = options.depth;
  v.weighting_ = BowWeighting::kTfIdf;
  v.scoring_ = 0;
  v.training_images_ = images.size();
  v.origin_ = "trained";
  resize(v, 1);

  // Level by level: the nodes of a level are clustered in parallel (each with its own seed from
  // the option's seed and its node id); their children get ids in (parent, cluster) order, so the
  // tree is the same whatever the threads.
  struct Pending {
    std::uint32_t node;
    std::vector<std::uint32_t> members;
  };
  std::vector<std::uint32_t> everything;
  everything.reserve(data.size());
  for (std::size_t i = 0; i < data.size(); ++i) everything.push_back(static_cast<std::uint32_t>(i));
  std::vector<Pending> current;
  current.push_back({0, std::move(everything)});
  for (int level = 0; level < options.depth && !current.empty(); ++level) {
    std::vector<std::vector<Cluster>> results(current.size());
    tbb::parallel_for(std::size_t{0}, current.size(), [&](std::size_t i) {
      std::uint64_t state = options.seed ^ (0xD1B54A32D192ED03ull * (static_cast<std::uint64_t>(current[i].node) + 1));
      const std::uint64_t node_seed = splitmix64(state);
      results[i] = cluster_node(data, current[i].members, options.branching, options.kmeans_iterations, node_seed);
    });
    std::vector<Pending> next;
    for (std::size_t i = 0; i < current.size(); ++i) {
      for (Cluster& c : results[i]) {
        const auto id = static_cast<std::uint32_t>(v.parent_.size());
        v.parent_.push_back(current[i].node);
        v.descriptor_.push_back(c.centre);
        v.weight_.push_back(0.0);
        v.word_of_node_.push_back(Vocabulary::kNoWord);
        if (level + 1 < options.depth && c.members.size() > 1) next.push_back({id, std::move(c.members)});
      }
    }
    current = std::move(next);
  }
  if (v.parent_.size() < 2) {
    throw std::invalid_argument("vocabulary training needs at least 2 distinct descriptors, found " + std::to_string(data.size()) +
                                " descriptors, all equal");
  }
  v.link_children();
  std::uint32_t words = 0;
  for (std::uint32_t i = 1; i < v.parent_.size(); ++i) {
    if (v.first_child_[i] == v.first_child_[i + 1]) v.word_of_node_[i] = words++;
  }
  const auto problem = link_and_check(v);
  CAIRN_ASSERT(!problem, "vocabulary training built an inconsistent tree");

  // idf (paper eq. (1), DBoW2 setNodeWeights for TF_IDF): N_i = training images with word i.
  std::vector<std::vector<std::uint32_t>> words_of_image(images.size());
  tbb::parallel_for(std::size_t{0}, images.size(), [&](std::size_t i) {
    const cv::Mat& m = images[i];
    std::vector<std::uint32_t>& w = words_of_image[i];
    for (int r = 0; !m.empty() && r < m.rows; ++r) w.push_back(v.word_of_node_[v.descend(row_descriptor(m, r), 0, nullptr)]);
    std::sort(w.begin(), w.end());
    w.erase(std::unique(w.begin(), w.end()), w.end());
  });
  std::vector<std::uint32_t> images_with(words, 0);
  for (const auto& w : words_of_image) {
    for (const std::uint32_t word : w) ++images_with[word];
  }
  const auto n_images = static_cast<double>(images.size());
  for (std::uint32_t w = 0; w < words; ++w) {
    if (images_with[w] > 0) v.weight_[v.node_of_word_[w]] = std::log(n_images / static_cast<double>(images_with[w]));
  }
  return v;
}

Vocabulary Vocabulary::train(const std::vector<cv::Mat>& descriptors_per_image, const VocabularyOptions& options) {
  if (std::string p; !options.is_valid(&p)) throw std::invalid_argument("vocabulary options: " + p);
  if (options.max_threads > 0) {
    tbb::task_arena arena(core::arena_concurrency(options.max_threads));
    return arena.execute([&] { return VocabularyBuilder::train(descriptors_per_image, options); });
  }
  return VocabularyBuilder::train(descriptors_per_image, options);
}

// ---------------------------------------------------------------------------------------------
// Use.

BowVector Vocabulary::transform(const cv::Mat& descriptors, std::vector<std::uint32_t>* word_of_feature,
                                std::vector<std::uint32_t>* node_of_feature, int levels_up) const {
  CAIRN_ASSERT(!node_of_word_.empty(), "Vocabulary::transform on an empty vocabulary (train or load one first)");
  CAIRN_ASSERT(descriptors.empty() || (descriptors.type() == CV_8U && descriptors.cols == kDescriptorBytes),
               "Vocabulary::transform expects N x 32 CV_8U ORB descriptors");
  const int rows = descriptors.empty() ? 0 : descriptors.rows;
  if (word_of_feature != nullptr) word_of_feature->assign(static_cast<std::size_t>(rows), kNoWord);
  if (node_of_feature != nullptr) node_of_feature->assign(static_cast<std::size_t>(rows), 0);
  const int node_level = L_ - levels_up;
  std::vector<std::pair<std::uint32_t, double>> hits;
  hits.reserve(static_cast<std::size_t>(rows));
  for (int r = 0; r < rows; ++r) {
    std::uint32_t node_at_level = 0;
    const std::uint32_t leaf = descend(row_descriptor(descriptors, r), node_level, node_of_feature != nullptr ? &node_at_level : nullptr);
    const std::uint32_t word = word_of_node_[leaf];
    if (word_of_feature != nullptr) (*word_of_feature)[static_cast<std::size_t>(r)] = word;
    if (node_of_feature != nullptr) (*node_of_feature)[static_cast<std::size_t>(r)] = node_at_level;
    if (weight_[leaf] > 0.0) hits.emplace_back(word, weight_[leaf]);  // DBoW2 skips weight-0 words
  }
  std::sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // tf-idf / tf: the word weight summed over the word's features (tf = n_id / n_d, eq. (1); the
  // 1 / n_d cancels in the normalisation). idf / binary: once per word (DBoW2 addIfNotExist).
  const bool per_feature = weighting_ == BowWeighting::kTfIdf || weighting_ == BowWeighting::kTf;
  BowVector v;
  for (const auto& [word, weight] : hits) {
    if (!v.empty() && v.back().first == word) {
      if (per_feature) v.back().second += weight;
    } else {
      v.emplace_back(word, weight);
    }
  }
  double sum = 0.0;
  for (const auto& entry : v) sum += entry.second;
  if (sum > 0.0) {
    for (auto& entry : v) entry.second /= sum;
  }
  return v;
}

double Vocabulary::score(const BowVector& a, const BowVector& b) {
  // Paper eq. (2), s = 1 - 1/2 |a - b|_1, computed as DBoW2's L1Scoring::score over the common
  // words only: |a - b|_1 = |a|_1 + |b|_1 + sum_common (|a_i - b_i| - |a_i| - |b_i|) = 2 + sum_common
  // (...) for L1-normalised a and b, so s = -1/2 sum_common (|a_i - b_i| - |a_i| - |b_i|). Equal to
  // eq. (2) for normalised vectors; 0 (not 1) when either vector is empty.
  double sum = 0.0;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i].first < b[j].first) {
      ++i;
    } else if (b[j].first < a[i].first) {
      ++j;
    } else {
      sum += std::abs(a[i].second - b[j].second) - std::abs(a[i].second) - std::abs(b[j].second);
      ++i;
      ++j;
    }
  }
  return -0.5 * sum;
}

double Vocabulary::word_weight(std::uint32_t word) const {
  CAIRN_ASSERT(word < node_of_word_.size(), "word id out of range");
  return weight_[node_of_word_[word]];
}

std::uint32_t Vocabulary::word_node(std::uint32_t word) const {
  CAIRN_ASSERT(word < node_of_word_.size(), "word id out of range");
  return node_of_word_[word];
}

std::uint32_t Vocabulary::parent_node(std::uint32_t node) const {
  CAIRN_ASSERT(node > 0 && node < parent_.size(), "node id out of range (the root has no parent)");
  return parent_[node];
}

std::string Vocabulary::description() const {
  std::string out = "k=" + std::to_string(k_) + " L=" + std::to_string(L_) + " " + std::to_string(words()) + " words (" +
                    weighting_name(weighting_) + ")";
  if (training_images_ > 0) out += ", trained on " + std::to_string(training_images_) + " images";
  if (!origin_.empty() && origin_ != "trained") out += ", from " + origin_;
  return out;
}

// ---------------------------------------------------------------------------------------------
// cairn's binary format, version 1 (docs/formats.md, "BoW vocabulary"). Little endian.
//   offset 0   23 bytes  the line "CAIRN_BOW_VOCABULARY 1\n" (ASCII)
//   23         u32 k, u32 L, u32 weighting (DBoW2 WeightingType 0..3), u32 scoring (DBoW2
//              ScoringType 0..5), u32 descriptor bytes (32), u32 training images (0 = unknown),
//              u32 node count N (root included), u32 word count W
//   55 + 48 (i - 1), for node i = 1 .. N-1 (the root, node 0, has no record):
//              u32 parent, u32 word id (0xFFFFFFFF for an inner node), 32 bytes descriptor,
//              f64 weight (IEEE 754; the idf of a word, 0 for inner nodes)
//   55 + 48 (N - 1)  u32 CRC-32 (ISO-HDLC, zlib's crc32) of every byte before it
// Total size 59 + 48 (N - 1) bytes. Children are ordered by increasing node id.

void Vocabulary::save(const std::string& path) const {
  CAIRN_ASSERT(!node_of_word_.empty(), "Vocabulary::save on an empty vocabulary");
  std::string body;
  body.reserve(kHeaderBytes + kNodeRecordBytes * parent_.size() + 4);
  put_u32(body, static_cast<std::uint32_t>(k_));
  put_u32(body, static_cast<std::uint32_t>(L_));
  put_u32(body, static_cast<std::uint32_t>(weighting_));
  put_u32(body, static_cast<std::uint32_t>(scoring_));
  put_u32(body, kDescriptorBytes);
  put_u32(body, static_cast<std::uint32_t>(std::min<std::size_t>(training_images_, 0xFFFFFFFFu)));
  put_u32(body, static_cast<std::uint32_t>(parent_.size()));
  put_u32(body, static_cast<std::uint32_t>(node_of_word_.size()));
  for (std::size_t i = 1; i < parent_.size(); ++i) {
    put_u32(body, parent_[i]);
    put_u32(body, word_of_node_[i]);
    body.append(reinterpret_cast<const char*>(bytes_of(descriptor_[i])), kDescriptorBytes);
    put_u64(body, std::bit_cast<std::uint64_t>(weight_[i]));
  }
  const std::string magic_line = std::string(kMagic) + " " + std::to_string(kFormatVersion) + "\n";
  put_u32(body, crc32(magic_line + body));  // CRC-32 of every byte before it
  io::write_output(path, [&](std::ostream& out) {
    out.write(magic_line.data(), static_cast<std::streamsize>(magic_line.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

Vocabulary VocabularyBuilder::parse_cairn(const std::string& path, const std::string& content) {
  const std::size_t newline = content.find('\n');
  const std::string_view first(content.data(), std::min(newline, std::min<std::size_t>(content.size(), 64)));
  const std::string expected_line = std::string(kMagic) + " " + std::to_string(kFormatVersion);
  if (newline == std::string::npos || first != expected_line) {
    throw io::ParseError(path, 1, "expected the line '" + expected_line + "', found " + io::quote_token(first) +
                                      (first.substr(0, kMagic.size()) == kMagic ? " (unsupported version of cairn's vocabulary format)" : ""));
  }
  const std::size_t start = newline + 1;
  const std::string_view body(content.data() + start, content.size() - start);
  auto fail = [&](std::size_t offset, const std::string& what) -> void {
    throw io::ParseError(path, 0, "byte " + std::to_string(start + offset) + ": " + what);
  };
  if (body.size() < kHeaderBytes + 4) {
    fail(body.size(), "truncated: expected a 32-byte header and a 4-byte checksum, the file ends after " +
                          std::to_string(content.size()) + " bytes");
  }
  const std::uint32_t k = get_u32(body, 0), L = get_u32(body, 4), weighting = get_u32(body, 8), scoring = get_u32(body, 12);
  const std::uint32_t descriptor_bytes = get_u32(body, 16), images = get_u32(body, 20), nodes = get_u32(body, 24),
                      words = get_u32(body, 28);
  if (nodes < 2) fail(24, "expected at least 2 nodes (the root and a word), found " + std::to_string(nodes));
  const std::uint64_t expected_size = kHeaderBytes + std::uint64_t{kNodeRecordBytes} * (nodes - 1) + 4;
  if (body.size() != expected_size) {
    fail(body.size() < expected_size ? body.size() : expected_size,
         std::string(body.size() < expected_size ? "truncated" : "trailing bytes") + ": " + std::to_string(nodes) +
             " nodes need " + std::to_string(start + expected_size) + " bytes, the file has " + std::to_string(content.size()));
  }
  const std::uint32_t stored_crc = get_u32(body, body.size() - 4);
  const std::uint32_t crc = crc32(std::string_view(content.data(), content.size() - 4));
  if (stored_crc != crc) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "stored %08x, computed %08x", stored_crc, crc);
    fail(body.size() - 4, std::string("checksum mismatch (the file is corrupt): ") + buffer);
  }
  if (k < 2 || k > 64) fail(0, "expected branching k in [2, 64], found " + std::to_string(k));
  if (L < 1 || L > 12) fail(4, "expected depth L in [1, 12], found " + std::to_string(L));
  if (weighting > 3) fail(8, "expected weighting 0..3 (tf-idf, tf, idf, binary), found " + std::to_string(weighting));
  if (scoring > 5) fail(12, "expected a DBoW2 scoring type 0..5, found " + std::to_string(scoring));
  if (descriptor_bytes != kDescriptorBytes) {
    fail(16, "only ORB vocabularies (32-byte descriptors) are supported, found " + std::to_string(descriptor_bytes) + "-byte descriptors");
  }
  Vocabulary v;
  v.k_ = static_cast<int>(k);
  v.L_ = static_cast<int>(L);
  v.weighting_ = static_cast<BowWeighting>(weighting);
  v.scoring_ = static_cast<int>(scoring);
  v.training_images_ = images;
  v.origin_ = "cairn";
  resize(v, nodes);
  for (std::uint32_t i = 1; i < nodes; ++i) {
    const std::size_t at = kHeaderBytes + kNodeRecordBytes * (i - 1);
    v.parent_[i] = get_u32(body, at);
    v.word_of_node_[i] = get_u32(body, at + 4);
    std::memcpy(v.descriptor_[i].data(), body.data() + at + 8, kDescriptorBytes);
    v.weight_[i] = std::bit_cast<double>(get_u64(body, at + 40));
  }
  if (const auto problem = link_and_check(v)) {
    fail(problem->node == 0 ? 0 : kHeaderBytes + kNodeRecordBytes * (problem->node - 1), problem->message);
  }
  if (v.node_of_word_.size() != words) {
    fail(28, "the header says " + std::to_string(words) + " words, the tree has " + std::to_string(v.node_of_word_.size()) + " leaves");
  }
  return v;
}

// ---------------------------------------------------------------------------------------------
// DBoW2's text format (ORB-SLAM2 TemplatedVocabulary::loadFromTextFile / saveToTextFile):
//   line 1: "k L scoring weighting"
//   line n + 1 (node n = 1, 2, ...): "parent is_leaf b0 ... b31 weight"
// Leaves become words in line order.

namespace {

struct Line {
  std::size_t number;
  std::string_view text;
};

std::vector<Line> split_lines(const std::string& content) {
  std::vector<Line> lines;
  std::size_t pos = 0, number = 1;
  while (pos < content.size()) {
    std::size_t end = content.find('\n', pos);
    if (end == std::string::npos) end = content.size();
    std::string_view text(content.data() + pos, end - pos);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    lines.push_back({number++, text});
    pos = end + 1;
  }
  return lines;
}

}  // namespace

Vocabulary VocabularyBuilder::parse_dbow2_text(const std::string& path, const std::string& content) {
  const std::vector<Line> lines = split_lines(content);
  CAIRN_ASSERT(!lines.empty(), "parse_dbow2_text called on empty content");
  const auto header = io::split_whitespace(lines[0].text);
  auto fail = [&](std::size_t line, const std::string& what) -> void { throw io::ParseError(path, line, what); };
  std::array<std::int64_t, 4> h{};
  if (header.size() != 4) {
    fail(1, "expected the DBoW2 text header 'k L scoring weighting' (4 integers), found " + std::to_string(header.size()) + " fields");
  }
  for (std::size_t i = 0; i < 4; ++i) {
    const auto value = to_integer(header[i]);
    if (!value) fail(1, "expected an integer in the header 'k L scoring weighting', found " + io::quote_token(header[i]));
    h[i] = *value;
  }
  if (h[0] < 2 || h[0] > 64) fail(1, "expected branching k in [2, 64], found " + std::to_string(h[0]));
  if (h[1] < 1 || h[1] > 12) fail(1, "expected depth L in [1, 12], found " + std::to_string(h[1]));
  if (h[2] < 0 || h[2] > 5) fail(1, "expected a DBoW2 scoring type 0..5, found " + std::to_string(h[2]));
  if (h[3] < 0 || h[3] > 3) fail(1, "expected a DBoW2 weighting type 0..3 (tf-idf, tf, idf, binary), found " + std::to_string(h[3]));

  Vocabulary v;
  v.k_ = static_cast<int>(h[0]);
  v.L_ = static_cast<int>(h[1]);
  v.scoring_ = static_cast<int>(h[2]);
  v.weighting_ = static_cast<BowWeighting>(h[3]);
  v.origin_ = "DBoW2 text";
  resize(v, 1);
  std::vector<std::size_t> line_of_node{1};
  std::vector<unsigned char> marked_leaf{0};
  std::uint32_t words = 0;
  std::size_t last = lines.size();
  while (last > 1 && trim(lines[last - 1].text).empty()) --last;  // trailing blank lines
  for (std::size_t li = 1; li < last; ++li) {
    const Line& line = lines[li];
    const auto fields = io::split_whitespace(line.text);
    const auto id = static_cast<std::uint32_t>(v.parent_.size());
    if (fields.size() != 35) {
      fail(line.number, "expected 35 fields for node " + std::to_string(id) +
                            " (parent, is-leaf flag, 32 descriptor bytes, weight; only ORB vocabularies are supported), found " +
                            std::to_string(fields.size()));
    }
    const auto parent = to_integer(fields[0]);
    if (!parent || *parent < 0 || *parent >= id) {
      fail(line.number, "expected the parent of node " + std::to_string(id) + " to be an earlier node id in [0, " +
                            std::to_string(id - 1) + "], found " + io::quote_token(fields[0]));
    }
    const auto leaf = to_integer(fields[1]);
    if (!leaf || (*leaf != 0 && *leaf != 1)) fail(line.number, "expected the is-leaf flag 0 or 1, found " + io::quote_token(fields[1]));
    const auto p = static_cast<std::uint32_t>(*parent);
    if (marked_leaf[p] != 0) {
      fail(line.number, "node " + std::to_string(id) + " has parent " + std::to_string(p) + ", which line " +
                            std::to_string(line_of_node[p]) + " marks as a leaf");
    }
    std::string why;
    const auto descriptor = parse_descriptor_bytes(std::vector<std::string_view>(fields.begin() + 2, fields.begin() + 34), &why);
    if (!descriptor) fail(line.number, why);
    const auto weight = to_finite(fields[34]);
    if (!weight || *weight < 0.0) fail(line.number, "expected the node weight to be a finite number >= 0, found " + io::quote_token(fields[34]));
    v.parent_.push_back(p);
    v.descriptor_.push_back(*descriptor);
    v.weight_.push_back(*weight);
    v.word_of_node_.push_back(*leaf == 1 ? words++ : Vocabulary::kNoWord);
    marked_leaf.push_back(*leaf == 1 ? 1 : 0);
    line_of_node.push_back(line.number);
  }
  if (v.parent_.size() < 2) fail(lines.size(), "expected node lines after the header, found none");
  if (const auto problem = link_and_check(v)) {
    std::string message = problem->message;
    // (first_child_ is empty when the check stopped before linking, e.g. at a weight)
    if (problem->node != 0 && problem->node + 1 < v.first_child_.size() && v.word_of_node_[problem->node] == Vocabulary::kNoWord &&
        v.first_child_[problem->node] == v.first_child_[problem->node + 1]) {
      message = "node " + std::to_string(problem->node) + " is marked as inner (is-leaf 0) but no node has it as parent";
    }
    fail(line_of_node[problem->node], message);
  }
  return v;
}

// ---------------------------------------------------------------------------------------------
// DBoW2's YAML (TemplatedVocabulary::save(cv::FileStorage&), OpenCV FileStorage):
//   %YAML:1.0
//   ---
//   vocabulary:
//      k: 9
//      L: 3
//      scoringType: 0
//      weightingType: 0
//      nodes:
//         - { nodeId:1, parentId:0, weight:0.,
//             descriptor:"212 176 ... 34 " }
//      words:
//         - { wordId:0, nodeId:19 }
// Parsed by hand: OpenCV writes "key:value" without a blank inside flow mappings, which a YAML
// parser reads as a single plain scalar. Top-level keys after "vocabulary" (a DBoW2 Database file
// also holds "database") are ignored.

namespace {

// One "{ key: value, ... }" mapping that may span lines; text joined with '\n'.
struct FlowField {
  std::string key;
  std::string value;
  std::size_t line;
};

std::vector<FlowField> parse_flow_mapping(const std::string& path, std::string_view s, std::size_t first_line) {
  std::vector<FlowField> out;
  std::size_t pos = 0;
  auto line_at = [&](std::size_t p) { return first_line + static_cast<std::size_t>(std::count(s.begin(), s.begin() + static_cast<std::ptrdiff_t>(p), '\n')); };
  auto fail = [&](std::size_t p, const std::string& what) -> void { throw io::ParseError(path, line_at(p), what); };
  auto skip_blank = [&]() {
    while (pos < s.size() && (s[pos] == ' ' || s[pos] == '\t' || s[pos] == '\n' || s[pos] == '\r')) ++pos;
  };
  skip_blank();
  if (pos >= s.size() || s[pos] != '{') fail(pos, "expected a '{ key:value, ... }' mapping");
  ++pos;
  while (true) {
    skip_blank();
    if (pos < s.size() && s[pos] == '}') {
      ++pos;
      break;
    }
    const std::size_t key_start = pos;
    while (pos < s.size() && s[pos] != ':' && s[pos] != ',' && s[pos] != '}' && s[pos] != '\n') ++pos;
    if (pos >= s.size() || s[pos] != ':') fail(key_start, "expected 'key:value' in the mapping, found " + io::quote_token(s.substr(key_start, pos - key_start)));
    FlowField field;
    field.key = std::string(trim(s.substr(key_start, pos - key_start)));
    field.line = line_at(key_start);
    ++pos;
    skip_blank();
    if (pos < s.size() && s[pos] == '"') {
      const std::size_t close = s.find('"', pos + 1);
      if (close == std::string_view::npos) fail(pos, "unterminated quoted string for '" + field.key + "'");
      field.value = std::string(s.substr(pos + 1, close - pos - 1));
      pos = close + 1;
    } else {
      const std::size_t value_start = pos;
      while (pos < s.size() && s[pos] != ',' && s[pos] != '}' && s[pos] != '\n') ++pos;
      field.value = std::string(trim(s.substr(value_start, pos - value_start)));
    }
    out.push_back(std::move(field));
    skip_blank();
    if (pos < s.size() && s[pos] == ',') {
      ++pos;
      continue;
    }
    if (pos < s.size() && s[pos] == '}') {
      ++pos;
      break;
    }
    fail(pos, "expected ',' or '}' in the mapping");
  }
  skip_blank();
  if (pos != s.size()) fail(pos, "unexpected text after the mapping's '}': " + io::quote_token(s.substr(pos)));
  return out;
}

std::size_t indentation(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return i;
}

}  // namespace

Vocabulary VocabularyBuilder::parse_dbow2_yaml(const std::string& path, const std::string& content) {
  const std::vector<Line> lines = split_lines(content);
  auto fail = [&](std::size_t line, const std::string& what) -> void { throw io::ParseError(path, line, what); };
  auto blank = [](std::string_view t) {
    t = trim(t);
    return t.empty() || t.front() == '#';
  };
  std::size_t i = 0;
  while (i < lines.size() && blank(lines[i].text)) ++i;
  if (i < lines.size() && lines[i].text.substr(0, 5) == "%YAML") ++i;
  while (i < lines.size() && blank(lines[i].text)) ++i;
  if (i < lines.size() && trim(lines[i].text) == "---") ++i;
  while (i < lines.size() && blank(lines[i].text)) ++i;
  if (i >= lines.size() || trim(lines[i].text) != "vocabulary:" || indentation(lines[i].text) != 0) {
    fail(i < lines.size() ? lines[i].number : lines.size(),
         "expected the DBoW2 YAML key 'vocabulary:', found " + (i < lines.size() ? io::quote_token(trim(lines[i].text)) : "the end of the file"));
  }
  const std::size_t vocabulary_line = lines[i].number;
  ++i;

  struct NodeItem {
    std::int64_t id = -1, parent = -1;
    double weight = 0.0;
    Descriptor descriptor{};
    std::size_t line = 0;
  };
  struct WordItem {
    std::int64_t word = -1, node = -1;
    std::size_t line = 0;
  };
  std::vector<NodeItem> node_items;
  std::vector<WordItem> word_items;
  std::optional<std::int64_t> k, L, scoring, weighting;
  bool saw_nodes = false, saw_words = false;

  auto parse_int = [&](const std::string& value, std::size_t line, const std::string& what) {
    const auto v = to_integer(value);
    if (!v) fail(line, "expected an integer for " + what + ", found " + io::quote_token(value));
    return *v;
  };

  while (i < lines.size()) {
    const Line& line = lines[i];
    if (blank(line.text)) {
      ++i;
      continue;
    }
    if (indentation(line.text) == 0) break;  // the next top-level key: the vocabulary ends
    const std::string_view t = trim(line.text);
    const std::size_t colon = t.find(':');
    if (colon == std::string_view::npos) fail(line.number, "expected 'key: value' inside 'vocabulary:', found " + io::quote_token(t));
    const std::string key(trim(t.substr(0, colon)));
    const std::string value(trim(t.substr(colon + 1)));
    ++i;
    if (key == "k" || key == "L" || key == "scoringType" || key == "weightingType") {
      const std::int64_t v = parse_int(value, line.number, "'" + key + "'");
      (key == "k" ? k : key == "L" ? L : key == "scoringType" ? scoring : weighting) = v;
      if (key == "k" && (v < 2 || v > 64)) fail(line.number, "expected branching k in [2, 64], found " + value);
      if (key == "L" && (v < 1 || v > 12)) fail(line.number, "expected depth L in [1, 12], found " + value);
      if (key == "scoringType" && (v < 0 || v > 5)) fail(line.number, "expected a DBoW2 scoringType 0..5, found " + value);
      if (key == "weightingType" && (v < 0 || v > 3)) {
        fail(line.number, "expected a DBoW2 weightingType 0..3 (tf-idf, tf, idf, binary), found " + value);
      }
      continue;
    }
    if (key != "nodes" && key != "words") {
      fail(line.number, "unexpected key '" + key + "' in 'vocabulary:' (expected k, L, scoringType, weightingType, nodes, words)");
    }
    const bool nodes = key == "nodes";
    (nodes ? saw_nodes : saw_words) = true;
    if (!value.empty()) fail(line.number, "expected a list of " + key + " on the following lines, found " + io::quote_token(value));
    // Items: "- { ... }", possibly continued over several lines until the braces close.
    while (i < lines.size()) {
      if (blank(lines[i].text)) {
        ++i;
        continue;
      }
      const std::string_view item = trim(lines[i].text);
      if (item.empty() || item.front() != '-') break;
      const std::size_t item_line = lines[i].number;
      std::string text(trim(item.substr(1)));
      int depth = 0;
      bool quoted = false;
      auto scan = [&](std::string_view s) {
        for (const char c : s) {
          if (c == '"') quoted = !quoted;
          if (!quoted && c == '{') ++depth;
          if (!quoted && c == '}') --depth;
        }
      };
      scan(text);
      ++i;
      while (depth > 0 && i < lines.size()) {
        text += '\n';
        text += std::string(lines[i].text);
        scan(lines[i].text);
        ++i;
      }
      if (depth > 0) fail(item_line, "unterminated '{' in the " + key + " list (truncated file?)");
      const auto fields = parse_flow_mapping(path, text, item_line);
      if (nodes) {
        NodeItem n;
        n.line = item_line;
        bool has_id = false, has_parent = false, has_weight = false, has_descriptor = false;
        for (const FlowField& f : fields) {
          if (f.key == "nodeId") {
            n.id = parse_int(f.value, f.line, "nodeId");
            has_id = true;
          } else if (f.key == "parentId") {
            n.parent = parse_int(f.value, f.line, "parentId");
            has_parent = true;
          } else if (f.key == "weight") {
            const auto w = to_finite(f.value);
            if (!w || *w < 0.0) fail(f.line, "expected the weight to be a finite number >= 0, found " + io::quote_token(f.value));
            n.weight = *w;
            has_weight = true;
          } else if (f.key == "descriptor") {
            std::string why;
            const auto d = parse_descriptor_bytes(io::split_whitespace(f.value), &why);
            if (!d) fail(f.line, why);
            n.descriptor = *d;
            has_descriptor = true;
          } else {
            fail(f.line, "unexpected key '" + f.key + "' in a node (expected nodeId, parentId, weight, descriptor)");
          }
        }
        if (!has_id || !has_parent || !has_weight || !has_descriptor) {
          fail(item_line, "expected a node with nodeId, parentId, weight and descriptor; missing " +
                              std::string(!has_id ? "nodeId" : !has_parent ? "parentId" : !has_weight ? "weight" : "descriptor"));
        }
        node_items.push_back(n);
      } else {
        WordItem w;
        w.line = item_line;
        bool has_word = false, has_node = false;
        for (const FlowField& f : fields) {
          if (f.key == "wordId") {
            w.word = parse_int(f.value, f.line, "wordId");
            has_word = true;
          } else if (f.key == "nodeId") {
            w.node = parse_int(f.value, f.line, "nodeId");
            has_node = true;
          } else {
            fail(f.line, "unexpected key '" + f.key + "' in a word (expected wordId, nodeId)");
          }
        }
        if (!has_word || !has_node) fail(item_line, std::string("expected a word with wordId and nodeId; missing ") + (!has_word ? "wordId" : "nodeId"));
        word_items.push_back(w);
      }
    }
  }
  const std::size_t end_line = lines.empty() ? 0 : lines.back().number;
  if (!k || !L || !scoring || !weighting) {
    fail(vocabulary_line, std::string("'vocabulary:' lacks '") + (!k ? "k" : !L ? "L" : !scoring ? "scoringType" : "weightingType") + "'");
  }
  if (!saw_nodes || node_items.empty()) {
    fail(saw_nodes ? vocabulary_line : end_line, "expected a non-empty 'nodes:' list in 'vocabulary:'" +
                                                     std::string(saw_nodes ? "" : ", found the end of the file (truncated?)"));
  }
  if (!saw_words || word_items.empty()) {
    fail(saw_words ? vocabulary_line : end_line, "expected a non-empty 'words:' list in 'vocabulary:'" +
                                                     std::string(saw_words ? "" : ", found the end of the file (truncated?)"));
  }

  Vocabulary v;
  v.k_ = static_cast<int>(*k);
  v.L_ = static_cast<int>(*L);
  v.scoring_ = static_cast<int>(*scoring);
  v.weighting_ = static_cast<BowWeighting>(*weighting);
  v.origin_ = "DBoW2 YAML";
  const std::size_t n = node_items.size() + 1;
  resize(v, n);
  std::vector<std::size_t> line_of_node(n, vocabulary_line);
  for (const NodeItem& item : node_items) {
    if (item.id < 1 || static_cast<std::size_t>(item.id) >= n) {
      fail(item.line, "expected nodeId in [1, " + std::to_string(n - 1) + "] (the file lists " + std::to_string(n - 1) +
                          " nodes), found " + std::to_string(item.id));
    }
    const auto id = static_cast<std::size_t>(item.id);
    if (line_of_node[id] != vocabulary_line) fail(item.line, "nodeId " + std::to_string(id) + " is listed twice (also on line " + std::to_string(line_of_node[id]) + ")");
    if (item.parent < 0 || static_cast<std::size_t>(item.parent) >= n) {
      fail(item.line, "expected parentId in [0, " + std::to_string(n - 1) + "], found " + std::to_string(item.parent));
    }
    line_of_node[id] = item.line;
    v.parent_[id] = static_cast<std::uint32_t>(item.parent);
    v.weight_[id] = item.weight;
    v.descriptor_[id] = item.descriptor;
  }
  std::vector<std::size_t> line_of_word(word_items.size(), 0);
  for (const WordItem& item : word_items) {
    if (item.word < 0 || static_cast<std::size_t>(item.word) >= word_items.size()) {
      fail(item.line, "expected wordId in [0, " + std::to_string(word_items.size() - 1) + "] (the file lists " +
                          std::to_string(word_items.size()) + " words), found " + std::to_string(item.word));
    }
    if (item.node < 1 || static_cast<std::size_t>(item.node) >= n) {
      fail(item.line, "expected the nodeId of word " + std::to_string(item.word) + " in [1, " + std::to_string(n - 1) + "], found " +
                          std::to_string(item.node));
    }
    const auto w = static_cast<std::size_t>(item.word);
    const auto node = static_cast<std::size_t>(item.node);
    if (line_of_word[w] != 0) fail(item.line, "wordId " + std::to_string(w) + " is listed twice (also on line " + std::to_string(line_of_word[w]) + ")");
    if (v.word_of_node_[node] != Vocabulary::kNoWord) {
      fail(item.line, "node " + std::to_string(node) + " is given words " + std::to_string(v.word_of_node_[node]) + " and " + std::to_string(w));
    }
    line_of_word[w] = item.line;
    v.word_of_node_[node] = static_cast<std::uint32_t>(w);
  }
  if (const auto problem = link_and_check(v)) fail(line_of_node[problem->node], problem->message);
  return v;
}

Vocabulary Vocabulary::load(const std::string& path) {
  const std::string content = io::read_maybe_compressed(path);
  if (content.empty()) throw io::ParseError(path, 0, "the file is empty, expected a vocabulary");
  if (content.compare(0, kMagic.size(), kMagic) == 0) return VocabularyBuilder::parse_cairn(path, content);
  // The first line that is not blank or a comment tells the text formats apart.
  std::size_t pos = 0;
  std::string_view first;
  while (pos < content.size()) {
    std::size_t end = content.find('\n', pos);
    if (end == std::string::npos) end = content.size();
    first = trim(std::string_view(content.data() + pos, end - pos));
    if (!first.empty() && first.front() != '#') break;
    pos = end + 1;
  }
  if (first.substr(0, 5) == "%YAML" || first == "---" || first == "vocabulary:") {
    return VocabularyBuilder::parse_dbow2_yaml(path, content);
  }
  const auto fields = io::split_whitespace(first);
  if (fields.size() == 4 && std::all_of(fields.begin(), fields.end(), [](std::string_view f) { return to_integer(f).has_value(); })) {
    return VocabularyBuilder::parse_dbow2_text(path, content);
  }
  const std::size_t line = static_cast<std::size_t>(std::count(content.begin(), content.begin() + static_cast<std::ptrdiff_t>(std::min(pos, content.size())), '\n')) + 1;
  throw io::ParseError(path, line,
                       "not a vocabulary: expected cairn's '" + std::string(kMagic) + " 1' line, DBoW2 YAML ('%YAML:1.0' / 'vocabulary:') or "
                       "DBoW2 text ('k L scoring weighting'), found " + io::quote_token(first) +
                           " (DBoW3, FBoW and ORBvoc.bin binary vocabularies are not supported)");
}

// ---------------------------------------------------------------------------------------------
// Database.

void BowDatabase::add(std::uint32_t id, const BowVector& v) {
  erase(id);
  for (const auto& [word, weight] : v) index_[word].push_back({id, weight});
  entries_.emplace(id, v);
}

void BowDatabase::erase(std::uint32_t id) {
  const auto it = entries_.find(id);
  if (it == entries_.end()) return;
  for (const auto& entry : it->second) {
    auto list = index_.find(entry.first);
    if (list == index_.end()) continue;
    auto& postings = list->second;
    postings.erase(std::remove_if(postings.begin(), postings.end(), [&](const Posting& p) { return p.id == id; }), postings.end());
    if (postings.empty()) index_.erase(list);
  }
  entries_.erase(it);
}

std::vector<BowDatabase::Result> BowDatabase::query(const BowVector& v, std::size_t max_results,
                                                    const std::vector<std::uint32_t>& exclude) const {
  const std::unordered_set<std::uint32_t> skip(exclude.begin(), exclude.end());
  // For L1-normalised non-negative a, b: |a - b|_1 = 2 - sum over common words of
  // (a_i + b_i - |a_i - b_i|) = 2 - 2 sum min(a_i, b_i), so s = 1 - |a - b|_1 / 2 = sum min(a_i, b_i)
  // (DBoW2 L1Scoring::score accumulates the same terms).
  std::unordered_map<std::uint32_t, Result> accumulated;
  for (const auto& [word, weight] : v) {
    const auto list = index_.find(word);
    if (list == index_.end()) continue;
    for (const Posting& p : list->second) {
      if (skip.count(p.id) != 0) continue;
      auto [it, inserted] = accumulated.try_emplace(p.id, Result{p.id, 0.0, 0});
      it->second.score += std::min(weight, p.weight);
      ++it->second.common_words;
    }
  }
  std::vector<Result> out;
  out.reserve(accumulated.size());
  for (const auto& entry : accumulated) out.push_back(entry.second);
  std::sort(out.begin(), out.end(), [](const Result& a, const Result& b) { return a.score != b.score ? a.score > b.score : a.id < b.id; });
  if (out.size() > max_results) out.resize(max_results);
  return out;
}

std::uint64_t Vocabulary::fingerprint() const {
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64 (Fowler, Noll, Vo)
  const auto mix = [&h](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) {
      h ^= bytes[i];
      h *= 1099511628211ull;
    }
  };
  const auto mix_u64 = [&mix](std::uint64_t v) {
    unsigned char le[8];
    for (int b = 0; b < 8; ++b) le[b] = static_cast<unsigned char>(v >> (8 * b));
    mix(le, 8);
  };
  mix_u64(static_cast<std::uint64_t>(k_));
  mix_u64(static_cast<std::uint64_t>(L_));
  mix_u64(static_cast<std::uint64_t>(weighting_));
  mix_u64(parent_.size());
  for (std::size_t n = 0; n < parent_.size(); ++n) {
    mix_u64(parent_[n]);
    for (const std::uint64_t word : descriptor_[n]) mix_u64(word);
    std::uint64_t weight_bits = 0;
    std::memcpy(&weight_bits, &weight_[n], sizeof weight_bits);
    mix_u64(weight_bits);
    mix_u64(word_of_node_[n]);
  }
  return h;
}

}  // namespace cairn::vision
