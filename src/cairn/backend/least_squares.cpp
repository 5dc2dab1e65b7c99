// The least-squares engine of least_squares.hpp: problem storage, parallel evaluation, the
// reduced (Schur) normal equations, and Levenberg-Marquardt as Ceres' TrustRegionMinimizer with
// its LevenbergMarquardtStrategy (internal/ceres/trust_region_minimizer.cc,
// levenberg_marquardt_strategy.cc): same damping, same radius updates, same stopping rules.

#include "cairn/backend/least_squares.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <sstream>

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define CAIRN_SCHUR_AVX 1
#endif

#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/threads.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {

// ---------------------------------------------------------------------------------------------
// Problem storage

struct VariableEntry {
  double* values = nullptr;
  const Manifold* manifold = nullptr;
  VariableGroup group = VariableGroup::kReduced;
  bool constant = false;
};

struct FactorEntry {
  std::unique_ptr<Factor> factor;
  std::vector<int> variables;
  FactorLoss loss;
  int residual_size = 0;
};

struct LeastSquaresProblem::Impl {
  std::vector<VariableEntry> variables;
  std::vector<FactorEntry> factors;
  int residuals = 0;
};

LeastSquaresProblem::LeastSquaresProblem() : impl_(std::make_unique<Impl>()) {}
LeastSquaresProblem::~LeastSquaresProblem() = default;
LeastSquaresProblem::LeastSquaresProblem(LeastSquaresProblem&&) noexcept = default;
LeastSquaresProblem& LeastSquaresProblem::operator=(LeastSquaresProblem&&) noexcept = default;

int LeastSquaresProblem::add_variable(double* values, const Manifold& manifold, VariableGroup group) {
  CAIRN_ASSERT(values != nullptr, "add_variable: null storage");
  impl_->variables.push_back({values, &manifold, group, false});
  return static_cast<int>(impl_->variables.size()) - 1;
}

void LeastSquaresProblem::set_constant(int variable, bool constant) {
  CAIRN_ASSERT(variable >= 0 && variable < num_variables(), "set_constant: no such variable");
  impl_->variables[variable].constant = constant;
}

bool LeastSquaresProblem::is_constant(int variable) const { return impl_->variables.at(variable).constant; }

int LeastSquaresProblem::add_factor(std::unique_ptr<Factor> factor, std::vector<int> variables, FactorLoss loss) {
  CAIRN_ASSERT(factor != nullptr, "add_factor: null factor");
  CAIRN_ASSERT(!variables.empty(), "add_factor: a factor needs at least one variable");
  for (std::size_t k = 0; k < variables.size(); ++k) {
    CAIRN_ASSERT(variables[k] >= 0 && variables[k] < num_variables(), "add_factor: no such variable");
    for (std::size_t m = 0; m < k; ++m) {
      CAIRN_ASSERT(variables[m] != variables[k], "add_factor: a variable appears twice in one factor");
    }
  }
  CAIRN_ASSERT(loss.kernel == RobustKernel::kNone || loss.scale > 0.0, "add_factor: kernel scale must be > 0");
  const int residual_size = factor->residual_size();
  CAIRN_ASSERT(residual_size >= 1, "add_factor: residual size must be >= 1");
  impl_->residuals += residual_size;
  impl_->factors.push_back({std::move(factor), std::move(variables), loss, residual_size});
  return static_cast<int>(impl_->factors.size()) - 1;
}

int LeastSquaresProblem::num_variables() const { return static_cast<int>(impl_->variables.size()); }
int LeastSquaresProblem::num_factors() const { return static_cast<int>(impl_->factors.size()); }
int LeastSquaresProblem::num_residuals() const { return impl_->residuals; }
const Manifold& LeastSquaresProblem::manifold(int variable) const { return *impl_->variables.at(variable).manifold; }
VariableGroup LeastSquaresProblem::group(int variable) const { return impl_->variables.at(variable).group; }
double* LeastSquaresProblem::values(int variable) const { return impl_->variables.at(variable).values; }
const Factor& LeastSquaresProblem::factor(int index) const { return *impl_->factors.at(index).factor; }
const std::vector<int>& LeastSquaresProblem::factor_variables(int index) const { return impl_->factors.at(index).variables; }
const FactorLoss& LeastSquaresProblem::factor_loss(int index) const { return impl_->factors.at(index).loss; }

std::string_view to_string(LinearSolverType type) {
  switch (type) {
    case LinearSolverType::kSparseNormalCholesky: return "sparse_normal_cholesky";
    case LinearSolverType::kSparseSchur: return "sparse_schur";
    case LinearSolverType::kIterativeSchur: return "iterative_schur";
  }
  return "?";
}

bool LeastSquaresOptions::is_valid(std::string* error) const {
  std::string shared;
  std::ostringstream problems;
  if (!TrustRegionOptions::is_valid(&shared)) problems << shared << "; ";
  if (!(min_diagonal > 0.0 && max_diagonal >= min_diagonal)) problems << "need 0 < min_diagonal <= max_diagonal; ";
  if (!(cg_tolerance > 0.0 && cg_tolerance < 1.0)) problems << "cg_tolerance must be in (0, 1); ";
  if (max_cg_iterations < 1 || min_cg_iterations < 0 || min_cg_iterations > max_cg_iterations) {
    problems << "need 0 <= min_cg_iterations <= max_cg_iterations, max_cg_iterations >= 1; ";
  }
  if (threads < 0) problems << "threads must be >= 0; ";
  if (!(reuse_cg_tolerance > 0.0 && reuse_cg_tolerance < 1.0)) problems << "reuse_cg_tolerance must be in (0, 1); ";
  if (reuse_max_cg_iterations < 0) problems << "reuse_max_cg_iterations must be >= 0; ";
  std::string text = problems.str();
  if (text.empty()) return true;
  if (error != nullptr) *error = text.substr(0, text.size() - 2);
  return false;
}

std::string LeastSquaresSummary::brief_report() const {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), "%s (%s): cost %.6e -> %.6e in %d iterations (%.3f s): %s",
                algorithm == Algorithm::kLevenbergMarquardt ? "LM" : (algorithm == Algorithm::kGaussNewton ? "GN" : "dog-leg"),
                std::string(to_string(linear_solver)).c_str(), initial_cost, final_cost, iterations, total_s,
                message.c_str());
  return buffer;
}

namespace {

using core::Clock;
using core::seconds_since;
// block += A^T B for one pair of a Schur complement with two residuals (bundle adjustment):
// A = J_a (2 x F, row-major), B = M J_b (2 x F, column-major), block F x F column-major, so
// column j gains A.row(0)^T B(0, j) + A.row(1)^T B(1, j), a rank-2 update. The scalar version
// adds each entry's two products, then the sum to the block, in that order; the AVX version does
// the same per lane (target "avx" only, no FMA, so nothing is contracted): bit-identical results.
// This update is most of the Schur complement's flops (162 of ~210 per pair of observations).
template <int F>
void rank2_update_scalar(double* block, const double* A, const double* B) {
  for (int j = 0; j < F; ++j) {
    const double b0 = B[2 * j], b1 = B[2 * j + 1];
    double* column = block + j * F;
    for (int i = 0; i < F; ++i) column[i] += A[i] * b0 + A[F + i] * b1;
  }
}
#if defined(CAIRN_SCHUR_AVX)
template <int F>
__attribute__((target("avx"))) void rank2_update_avx(double* block, const double* A, const double* B) {
  constexpr int kPacked = F / 4 * 4;
  __m256d a0[kPacked / 4 > 0 ? kPacked / 4 : 1], a1[kPacked / 4 > 0 ? kPacked / 4 : 1];
  for (int p = 0; p < kPacked / 4; ++p) {
    a0[p] = _mm256_loadu_pd(A + 4 * p);
    a1[p] = _mm256_loadu_pd(A + F + 4 * p);
  }
  for (int j = 0; j < F; ++j) {
    const double b0 = B[2 * j], b1 = B[2 * j + 1];
    const __m256d v0 = _mm256_set1_pd(b0), v1 = _mm256_set1_pd(b1);
    double* column = block + j * F;
    for (int p = 0; p < kPacked / 4; ++p) {
      const __m256d sum = _mm256_add_pd(_mm256_mul_pd(a0[p], v0), _mm256_mul_pd(a1[p], v1));
      _mm256_storeu_pd(column + 4 * p, _mm256_add_pd(_mm256_loadu_pd(column + 4 * p), sum));
    }
    for (int i = kPacked; i < F; ++i) column[i] += A[i] * b0 + A[F + i] * b1;
  }
}
const bool kHaveAvx = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx") != 0 && std::getenv("CAIRN_NO_AVX") == nullptr;
}();
#endif
template <int F>
void rank2_update(double* block, const double* A, const double* B) {
#if defined(CAIRN_SCHUR_AVX)
  if (kHaveAvx) {
    rank2_update_avx<F>(block, A, B);
    return;
  }
#endif
  rank2_update_scalar<F>(block, A, B);
}

// One reduced variable of a factor on an eliminated block, for the Schur solvers' flat tables.
struct ReducedTerm {
  int jacobian;  ///< offset of J_c in the Jacobian buffer
  int offset;    ///< offset of the block in the reduced vector
  int size;      ///< the block's tangent size
  int block;     ///< the reduced block
};

#if defined(CAIRN_SCHUR_AVX)
// The flat tables schur_product_r2e3_avx reads (the Engine's, see prepare()).
struct SchurProductTables {
  const int* order;            ///< eliminated blocks in visiting order
  const int* entry_start;      ///< eliminated block -> its entries (layout_.eliminated_factor_start)
  const int* term_start;       ///< entry -> its reduced terms
  const ReducedTerm* terms;
  const int* e_jacobian;       ///< entry -> offset of its 2 x 3 J_e
  const double* jacobians;
  const double* v_inverse;     ///< per eliminated block, (V + D/mu)^-1, 3 x 3 column-major
  const int* v_inverse_offset;
};

__attribute__((target("avx"))) inline double horizontal_sum(__m256d v) {
  const __m128d pair = _mm_add_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
  return _mm_cvtsd_f64(_mm_add_sd(pair, _mm_unpackhi_pd(pair, pair)));
}

// y += (A - W V^-1 W^T) x over the eliminated blocks order[begin..end), for factors with two
// residuals on a 3-dimensional eliminated block and F-dimensional reduced blocks (bundle
// adjustment): the steps of Engine::schur_product_block, with J_c x and J_c^T t four lanes at a
// time (target "avx", no FMA). Sums are grouped differently from Eigen's SSE2 products, so the
// result differs from schur_product_block's in the last bits. `z`: 2 doubles per entry.
template <int F>
__attribute__((target("avx"))) void schur_product_r2e3_avx(const SchurProductTables& T, int begin, int end,
                                                             const double* x, double* y, double* z) {
  constexpr int kPacks = F / 4;
  for (int i = begin; i < end; ++i) {
    const int e = T.order[i];
    const int first = T.entry_start[e];
    const int last = T.entry_start[e + 1];
    double w0 = 0.0, w1 = 0.0, w2 = 0.0;
    for (int index = first; index < last; ++index) {
      __m256d sum0 = _mm256_setzero_pd(), sum1 = _mm256_setzero_pd();
      double tail0 = 0.0, tail1 = 0.0;
      for (int t = T.term_start[index]; t < T.term_start[index + 1]; ++t) {
        const double* J = T.jacobians + T.terms[t].jacobian;  // 2 x F, row-major
        const double* x_c = x + T.terms[t].offset;
        for (int p = 0; p < kPacks; ++p) {
          const __m256d x_p = _mm256_loadu_pd(x_c + 4 * p);
          sum0 = _mm256_add_pd(sum0, _mm256_mul_pd(_mm256_loadu_pd(J + 4 * p), x_p));
          sum1 = _mm256_add_pd(sum1, _mm256_mul_pd(_mm256_loadu_pd(J + F + 4 * p), x_p));
        }
        for (int k = 4 * kPacks; k < F; ++k) {
          tail0 += J[k] * x_c[k];
          tail1 += J[F + k] * x_c[k];
        }
      }
      const double z0 = horizontal_sum(sum0) + tail0;
      const double z1 = horizontal_sum(sum1) + tail1;
      z[2 * (index - first)] = z0;
      z[2 * (index - first) + 1] = z1;
      const double* J_e = T.jacobians + T.e_jacobian[index];  // 2 x 3, row-major
      w0 += J_e[0] * z0 + J_e[3] * z1;
      w1 += J_e[1] * z0 + J_e[4] * z1;
      w2 += J_e[2] * z0 + J_e[5] * z1;
    }
    const double* V = T.v_inverse + T.v_inverse_offset[e];
    const double u0 = V[0] * w0 + V[3] * w1 + V[6] * w2;
    const double u1 = V[1] * w0 + V[4] * w1 + V[7] * w2;
    const double u2 = V[2] * w0 + V[5] * w1 + V[8] * w2;
    for (int index = first; index < last; ++index) {
      const double* J_e = T.jacobians + T.e_jacobian[index];
      const double t0 = z[2 * (index - first)] - (J_e[0] * u0 + J_e[1] * u1 + J_e[2] * u2);
      const double t1 = z[2 * (index - first) + 1] - (J_e[3] * u0 + J_e[4] * u1 + J_e[5] * u2);
      const __m256d v0 = _mm256_set1_pd(t0), v1 = _mm256_set1_pd(t1);
      for (int t = T.term_start[index]; t < T.term_start[index + 1]; ++t) {
        const double* J = T.jacobians + T.terms[t].jacobian;
        double* y_c = y + T.terms[t].offset;
        for (int p = 0; p < kPacks; ++p) {
          const __m256d sum = _mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(J + 4 * p), v0),
                                            _mm256_mul_pd(_mm256_loadu_pd(J + F + 4 * p), v1));
          _mm256_storeu_pd(y_c + 4 * p, _mm256_add_pd(_mm256_loadu_pd(y_c + 4 * p), sum));
        }
        for (int k = 4 * kPacks; k < F; ++k) y_c[k] += J[k] * t0 + J[F + k] * t1;
      }
    }
  }
}
#endif


/// Row-major matrix type that stays valid for one column (Eigen forbids row-major column vectors;
/// their memory layout is the same).
template <int Rows, int Cols>
using RowMajor = Eigen::Matrix<double, Rows, Cols, (Cols == 1 && Rows != 1) ? Eigen::ColMajor : Eigen::RowMajor>;
template <int Rows, int Cols>
using ConstMap = Eigen::Map<const RowMajor<Rows, Cols>>;
template <int Rows>
using VectorMap = Eigen::Map<Eigen::Matrix<double, Rows, 1>>;
template <int Rows>
using ConstVectorMap = Eigen::Map<const Eigen::Matrix<double, Rows, 1>>;

// ---------------------------------------------------------------------------------------------
// The layout of one solve: which variables are free, where their blocks sit in the reduced and
// eliminated unknowns, where each factor's residual and Jacobians are stored.

struct Layout {
  int reduced_dim = 0;
  int eliminated_dim = 0;
  std::vector<int> block_of;           ///< variable -> reduced block or eliminated block, -1 if constant
  std::vector<char> eliminated;        ///< variable -> 1 when in the eliminated group (and free)
  std::vector<int> reduced_variable;   ///< reduced block -> variable
  std::vector<int> reduced_offset;     ///< reduced block -> offset in the reduced vector
  std::vector<int> eliminated_variable;
  std::vector<int> eliminated_offset;
  std::vector<int> residual_offset;    ///< factor -> offset in the residual buffer
  std::vector<int> slot_start;         ///< factor -> first slot (one slot per factor variable)
  std::vector<int> jacobian_offset;    ///< slot -> offset in the Jacobian buffer, -1 if constant
  std::vector<int> factor_eliminated;  ///< factor -> eliminated block or -1
  std::vector<int> factor_eliminated_slot;  ///< factor -> slot of its eliminated variable or -1
  std::vector<int> eliminated_factor_start;  ///< CSR: eliminated block -> its factors
  std::vector<int> eliminated_factors;
  std::vector<int> plain_factors;      ///< factors with no eliminated variable
  std::size_t jacobian_size = 0;
  int residual_size = 0;
  int ambient_free = 0;
};

// ---------------------------------------------------------------------------------------------
// The reduced matrix: upper triangle of a symmetric block matrix with blocks of any sizes, in
// CHOLMOD's compressed-column form, with direct block addressing.

class ReducedMatrix {
 public:
  /// `pairs`: coupled blocks (r, c), any order, duplicates allowed; the diagonal is always present.
  ReducedMatrix(const std::vector<int>& block_size, std::vector<std::pair<int, int>> pairs) {
    const int blocks = static_cast<int>(block_size.size());
    offset_.assign(blocks + 1, 0);
    for (int b = 0; b < blocks; ++b) offset_[b + 1] = offset_[b] + block_size[b];
    for (auto& [r, c] : pairs) {
      if (r > c) std::swap(r, c);
    }
    for (int b = 0; b < blocks; ++b) pairs.emplace_back(b, b);
    std::sort(pairs.begin(), pairs.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second < b.second : a.first < b.first;
    });
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    column_rows_.assign(blocks, {});
    for (const auto& [r, c] : pairs) column_rows_[c].push_back(r);
    const int n = offset_[blocks];
    csc_.size = n;
    csc_.column_start.assign(n + 1, 0);
    for (int c = 0; c < blocks; ++c) {
      int prefix = 0;
      for (const int r : column_rows_[c]) {
        prefix += block_size[r];
      }
      // Column j of block c holds every row of the blocks above c, then rows 0..j of block c.
      const int above = prefix - block_size[c];
      for (int j = 0; j < block_size[c]; ++j) {
        const int column = offset_[c] + j;
        csc_.column_start[column + 1] = csc_.column_start[column] + above + j + 1;
      }
    }
    csc_.row.resize(csc_.column_start[n]);
    csc_.value.assign(csc_.column_start[n], 0.0);
    // Dense column-major storage of every stored block (r <= c; diagonal blocks whole).
    column_block_offset_.assign(blocks, {});
    std::size_t block_values = 0;
    for (int c = 0; c < blocks; ++c) {
      for (const int r : column_rows_[c]) {
        column_block_offset_[c].push_back(block_values);
        block_values += static_cast<std::size_t>(block_size[r]) * block_size[c];
      }
    }
    block_values_ = block_values;
    // Direct addressing of every block when the table is small beside the blocks it addresses
    // (an eighth of their storage or less: S of bundle adjustment, dense or nearly, over a few
    // hundred cameras); sparse patterns over many blocks search the column instead.
    if (static_cast<std::size_t>(blocks) * blocks * 8 <= block_values && block_values < kNoBlock) {
      dense_blocks_ = blocks;
      dense_offset_.assign(static_cast<std::size_t>(blocks) * blocks, kNoBlock);
      for (int c = 0; c < blocks; ++c) {
        for (std::size_t k = 0; k < column_rows_[c].size(); ++k) {
          dense_offset_[static_cast<std::size_t>(column_rows_[c][k]) * blocks + c] =
              static_cast<std::uint32_t>(column_block_offset_[c][k]);
        }
      }
    }
    for (int c = 0; c < blocks; ++c) {
      for (int j = 0; j < block_size[c]; ++j) {
        int k = csc_.column_start[offset_[c] + j];
        for (const int r : column_rows_[c]) {
          const int rows = r == c ? j + 1 : block_size[r];
          for (int i = 0; i < rows; ++i) csc_.row[k++] = offset_[r] + i;
        }
      }
    }
  }

  const UpperCsc& matrix() const { return csc_; }
  UpperCsc& matrix() { return csc_; }
  int offset(int block) const { return offset_[block]; }
  int size(int block) const { return offset_[block + 1] - offset_[block]; }

  /// Values of the block storage (blocks_size() doubles) that add() accumulates into:
  /// every stored block (r, c), r <= c, dense and column-major, so that one update touches
  /// contiguous memory (Ceres' BlockRandomAccessSparseMatrix keeps its cells dense likewise).
  std::size_t blocks_size() const { return block_values_; }

  /// blocks += M at block (r, c), M size(r) x size(c). For r > c, M^T is added at (c, r).
  /// Diagonal blocks are accumulated whole (to_csc reads their upper triangle).
  template <class Matrix>
  void add(int r, int c, const Matrix& M, double* blocks) const {
    if (r > c) {
      add_upper(c, r, M.transpose(), blocks);
    } else {
      add_upper(r, c, M, blocks);
    }
  }

  /// Start of stored block (r, c), r <= c, in the block storage (column-major, size(r) rows).
  std::size_t block_offset(int r, int c) const {
    if (dense_blocks_ > 0) {
      const std::uint32_t offset = dense_offset_[static_cast<std::size_t>(r) * dense_blocks_ + c];
      CAIRN_ASSERT(offset != kNoBlock, "ReducedMatrix: block outside the pattern");
      return offset;
    }
    const auto& rows = column_rows_[c];
    const auto it = std::lower_bound(rows.begin(), rows.end(), r);
    CAIRN_ASSERT(it != rows.end() && *it == r, "ReducedMatrix: block outside the pattern");
    return column_block_offset_[c][it - rows.begin()];
  }

  /// y += S x over the block storage (S's upper blocks; diagonal blocks whole), every block
  /// F x F: the product PCG on the previous factorisation needs, without the CSC's row indices
  /// (a third of its memory traffic) and with fixed-size products instead of one scattered
  /// update per value.
  template <int F>
  void multiply(const double* blocks, const double* x, double* y) const {
    using Block = Eigen::Map<const Eigen::Matrix<double, F, F>>;
    using Vector = Eigen::Map<Eigen::Matrix<double, F, 1>>;
    using ConstVector = Eigen::Map<const Eigen::Matrix<double, F, 1>>;
    const int block_count = static_cast<int>(column_rows_.size());
    for (int c = 0; c < block_count; ++c) {
      const ConstVector x_c(x + offset_[c]);
      Eigen::Matrix<double, F, 1> y_c = Eigen::Matrix<double, F, 1>::Zero();
      for (std::size_t k = 0; k < column_rows_[c].size(); ++k) {
        const int r = column_rows_[c][k];
        const Block B(blocks + column_block_offset_[c][k]);
        if (r == c) {
          y_c.noalias() += B * x_c;
        } else {
          Vector(y + offset_[r]).noalias() += B * x_c;
          y_c.noalias() += B.transpose() * ConstVector(x + offset_[r]);
        }
      }
      Vector(y + offset_[c]) += y_c;
    }
  }

  /// Writes the upper triangle of the block storage into the CSC values (same pattern).
  void to_csc(const double* blocks, double* values) const {
    const int block_count = static_cast<int>(column_rows_.size());
    for (int c = 0; c < block_count; ++c) {
      const int columns = size(c);
      for (int j = 0; j < columns; ++j) {
        double* out = values + csc_.column_start[offset_[c] + j];
        for (std::size_t k = 0; k < column_rows_[c].size(); ++k) {
          const int r = column_rows_[c][k];
          const int rows = r == c ? j + 1 : size(r);
          const double* in = blocks + column_block_offset_[c][k] + static_cast<std::size_t>(j) * size(r);
          out = std::copy(in, in + rows, out);
        }
      }
    }
  }

  /// Adds `amount` to the diagonal entry of scalar column `column`.
  void add_diagonal(int column, double amount, double* values) const {
    values[csc_.column_start[column + 1] - 1] += amount;
  }

 private:
  template <class Matrix>
  void add_upper(int r, int c, const Matrix& M, double* blocks) const {
    double* block = blocks + block_offset(r, c);
    const int block_rows = size(r);
    const int columns = size(c);
    for (int j = 0; j < columns; ++j) {
      for (int i = 0; i < block_rows; ++i) block[i + j * block_rows] += M(i, j);
    }
  }

  std::vector<int> offset_;
  std::vector<std::vector<int>> column_rows_;
  std::vector<std::vector<std::size_t>> column_block_offset_;
  std::size_t block_values_ = 0;
  static constexpr std::uint32_t kNoBlock = std::numeric_limits<std::uint32_t>::max();
  int dense_blocks_ = 0;                    ///< > 0: dense_offset_ addresses every (r, c)
  std::vector<std::uint32_t> dense_offset_;  ///< r * dense_blocks_ + c -> block start or kNoBlock
  UpperCsc csc_;
};

// ---------------------------------------------------------------------------------------------
// The solver state of one solve().

class Engine final : public TrustRegionModel {
 public:
  Engine(LeastSquaresProblem& problem, const LeastSquaresOptions& options)
      : problem_(problem.impl()),
        options_(options),
        arena_(core::arena_concurrency(options.threads)) {}

  LeastSquaresSummary run();
  VariableCovariances covariances(const std::vector<int>& variables);

 private:
  // Setup
  bool build_layout(std::string* error);
  /// The reduced pattern (block-AMD numbered), elimination order and buffers; after build_layout.
  void prepare();
  void choose_kernels();
  // Evaluation. Returns false when a factor could not be evaluated or gave a non-finite value.
  bool evaluate(bool jacobians, double& cost) { return evaluate(jacobians, cost, residuals_, jacobians_); }
  bool evaluate(bool jacobians, double& cost, std::vector<double>& residual_buffer, std::vector<double>& jacobian_buffer);
  // Gradient g = J^T r over the free variables (reduced part, eliminated part).
  void compute_gradient();
  // Builds and solves the system damped by D * mu_inverse (0: undamped) for the step into
  // step_reduced_ / step_eliminated_; false on a numerical failure. *inexact: the step came
  // from PCG on an earlier factorisation.
  bool solve_system(double mu_inverse, int& cg_iterations, bool* inexact);
  // r^T J dx and ||J dx||^2 over all factors, dx split as the steps are.
  void jacobian_products(const double* dx_reduced, const double* dx_eliminated, double* r_dot, double* squared) const;
  void save_values();
  void restore_values();
  void apply_step();
  // Ceres' gradient norm at the current point (computed after compute_gradient()).
  double compute_gradient_max_norm();
  // The step in TrustRegionModel's layout: [reduced; eliminated], both ways.
  void join_step(Eigen::VectorXd& step) const;
  void split_step(const Eigen::VectorXd& step);

 public:
  // TrustRegionModel (trust_region.hpp).
  bool start(double* cost, std::string* error) override;
  double gradient_max_norm() override { return gradient_max_norm_; }
  double values_norm() override;
  StepQuality compute_step(double lambda, Eigen::VectorXd& step, double* predicted, TrustRegionIteration& it) override;
  const Eigen::VectorXd& gradient() override;
  double curvature(const Eigen::VectorXd& v) override;
  double model_decrease(const Eigen::VectorXd& step) override;
  bool evaluate_trial(const Eigen::VectorXd& step, double* cost, TrustRegionIteration& it) override;
  void accept_trial(double old_cost, double new_cost, bool final, TrustRegionIteration& it) override;
  void reject_trial(StepQuality quality) override;

 private:

  template <int R, int E, int F>
  void eliminate(int e, double mu_inverse, double* matrix_values, double* rhs, double* diagonal, bool diagonal_only);
  template <int R, int F>
  void add_plain_factor(int f, double* matrix_values, double* rhs, double* diagonal, bool diagonal_only);
  template <int R, int F>
  Eigen::Matrix<double, R, 1> reduced_times(int f, const double* x) const;
  template <int R, int F>
  void add_reduced_transpose_times(int f, const Eigen::Matrix<double, R, 1>& z, double* y) const;
  template <int R, int E, int F>
  void back_substitute(int e);
  template <int R, int E, int F>
  void schur_product_block(int e, const double* x, double* y) const;
  template <int R, int F>
  void plain_product(int f, const double* x, double* y) const;
  void schur_product(const Eigen::VectorXd& x, Eigen::VectorXd& y);
  bool solve_iterative(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, int& cg_iterations);
  bool solve_with_previous_factor(const UpperCsc& S, const Eigen::VectorXd& rhs, int& cg_iterations);

  template <class Body>
  void parallel(int n, int grain, const Body& body) {
    arena_.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, grain), [&](const tbb::blocked_range<int>& range) {
        for (int i = range.begin(); i < range.end(); ++i) body(i);
      });
    });
  }

  /// As parallel(), with the body called once per chunk, body(begin, end): thread-local state
  /// (tbb::enumerable_thread_specific::local() hashes the thread id) is then looked up once per
  /// chunk, not once per item (per item it took 3 % of a one-thread BA solve of problem-49, perf).
  template <class Body>
  void parallel_chunks(int n, int grain, const Body& body) {
    arena_.execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, grain),
                        [&](const tbb::blocked_range<int>& range) { body(range.begin(), range.end()); });
    });
  }

  const double* jacobian(int f, int k) const {
    const int offset = layout_.jacobian_offset[layout_.slot_start[f] + k];
    return offset < 0 ? nullptr : jacobians_.data() + offset;
  }
  /// The Jacobian of a slot known to hold a free variable.
  const double* free_jacobian(int f, int k) const {
    return jacobians_.data() + layout_.jacobian_offset[layout_.slot_start[f] + k];
  }

  LeastSquaresProblem::Impl& problem_;
  const LeastSquaresOptions& options_;
  tbb::task_arena arena_;
  Layout layout_;
  std::unique_ptr<ReducedMatrix> reduced_;
  SparseCholesky cholesky_;
  bool analyzed_ = false;

  // Kernel selection: fixed sizes when every factor on an eliminated block has R residuals, the
  // eliminated blocks E and every reduced block F tangent dimensions (bundle adjustment).
  int fixed_r_ = 0, fixed_e_ = 0, fixed_f_ = 0;
  // Likewise for the factors without an eliminated variable (pose graphs: (3, 3) and (6, 6)
  // geodesic, (6, 3) and (12, 6) chordal).
  int plain_r_ = 0, plain_f_ = 0;

  std::vector<double> residuals_;
  std::vector<double> jacobians_;
  /// The trial point's residuals and Jacobians (LeastSquaresOptions::jacobians_with_trial_cost),
  /// swapped with the above when the step is accepted.
  std::vector<double> trial_residuals_;
  std::vector<double> trial_jacobians_;
  std::vector<double> saved_values_;
  Eigen::VectorXd gradient_reduced_;
  Eigen::VectorXd gradient_eliminated_;
  Eigen::VectorXd step_reduced_;
  Eigen::VectorXd step_eliminated_;
  std::vector<double> v_inverse_;        ///< per eliminated block, (V + D/mu)^-1, column-major
  std::vector<int> v_inverse_offset_;
  std::vector<double> block_values_;  ///< S in ReducedMatrix's block storage
  std::vector<std::vector<double>> partial_pool_;  ///< the other threads' sums of S's blocks
  /// Eliminated blocks in the order the Schur complement visits them: by the first reduced
  /// block they touch, so that consecutive blocks update nearby parts of S (cache locality).
  std::vector<int> elimination_order_;
  std::vector<double> damping_reduced_;  ///< D / mu on the reduced unknowns for this step
  // Iterative Schur: the block-diagonal preconditioner's inverse blocks.
  std::vector<Eigen::MatrixXd> preconditioner_;
  // Schur solvers: per entry of layout_.eliminated_factors (same index), its residual size and
  // offset, the offset of its eliminated Jacobian and its range of reduced terms, so that forming
  // S and the product with the implicit Schur complement read flat arrays instead of walking
  // factor, variable and slot tables, a cache miss each (prepare()).
  int max_entries_per_block_ = 0;  ///< most factors on one eliminated block
  std::vector<int> schur_residual_size_;
  std::vector<int> schur_residual_offset_;
  std::vector<int> schur_e_jacobian_;
  std::vector<int> schur_term_start_;
  std::vector<ReducedTerm> schur_terms_;
  LeastSquaresSummary* summary_ = nullptr;
  // Trust-region state: the current point's gradient (max-norm, and joined for dog-leg); an
  // accepted point whose Jacobians could not be evaluated (jacobians_with_trial_cost off) fails
  // the next step.
  double gradient_max_norm_ = 0.0;
  Eigen::VectorXd gradient_joined_;
  bool linearization_failed_ = false;
};

bool Engine::build_layout(std::string* error) {
  Layout& L = layout_;
  const int variables = static_cast<int>(problem_.variables.size());
  const bool schur = options_.linear_solver != LinearSolverType::kSparseNormalCholesky;
  L.block_of.assign(variables, -1);
  L.eliminated.assign(variables, 0);
  for (int v = 0; v < variables; ++v) {
    const VariableEntry& variable = problem_.variables[v];
    if (variable.constant) continue;
    const int tangent = variable.manifold->tangent_size();
    L.ambient_free += variable.manifold->ambient_size();
    if (schur && variable.group == VariableGroup::kEliminate) {
      L.eliminated[v] = 1;
      L.block_of[v] = static_cast<int>(L.eliminated_variable.size());
      L.eliminated_variable.push_back(v);
      L.eliminated_offset.push_back(L.eliminated_dim);
      L.eliminated_dim += tangent;
    } else {
      L.block_of[v] = static_cast<int>(L.reduced_variable.size());
      L.reduced_variable.push_back(v);
      L.reduced_offset.push_back(L.reduced_dim);
      L.reduced_dim += tangent;
    }
  }
  const int factors = static_cast<int>(problem_.factors.size());
  L.residual_offset.resize(factors);
  L.slot_start.resize(factors + 1);
  L.factor_eliminated.assign(factors, -1);
  L.factor_eliminated_slot.assign(factors, -1);
  std::vector<int> eliminated_count(L.eliminated_variable.size(), 0);
  std::size_t jacobian_size = 0;
  int residual_size = 0;
  for (int f = 0; f < factors; ++f) {
    const FactorEntry& factor = problem_.factors[f];
    L.residual_offset[f] = residual_size;
    residual_size += factor.residual_size;
    L.slot_start[f] = static_cast<int>(L.jacobian_offset.size());
    for (const int v : factor.variables) {
      if (L.block_of[v] < 0) {
        L.jacobian_offset.push_back(-1);
        continue;
      }
      L.jacobian_offset.push_back(static_cast<int>(jacobian_size));
      jacobian_size += static_cast<std::size_t>(factor.residual_size) * problem_.variables[v].manifold->tangent_size();
      if (L.eliminated[v]) {
        if (L.factor_eliminated[f] >= 0) {
          if (error) *error = "factor " + std::to_string(f) + " touches two eliminated variables (Schur solvers allow one)";
          return false;
        }
        L.factor_eliminated[f] = L.block_of[v];
        L.factor_eliminated_slot[f] = static_cast<int>(L.jacobian_offset.size()) - 1 - L.slot_start[f];
        ++eliminated_count[L.block_of[v]];
      }
    }
    if (L.factor_eliminated[f] < 0) L.plain_factors.push_back(f);
  }
  L.slot_start[factors] = static_cast<int>(L.jacobian_offset.size());
  if (jacobian_size > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    if (error) *error = "the Jacobian has more than 2^31 entries";
    return false;
  }
  L.jacobian_size = jacobian_size;
  L.residual_size = residual_size;
  L.eliminated_factor_start.assign(L.eliminated_variable.size() + 1, 0);
  for (std::size_t e = 0; e < eliminated_count.size(); ++e) {
    L.eliminated_factor_start[e + 1] = L.eliminated_factor_start[e] + eliminated_count[e];
  }
  L.eliminated_factors.resize(L.eliminated_factor_start.back());
  std::vector<int> fill(L.eliminated_factor_start.begin(), L.eliminated_factor_start.end() - 1);
  for (int f = 0; f < factors; ++f) {
    if (L.factor_eliminated[f] >= 0) L.eliminated_factors[fill[L.factor_eliminated[f]]++] = f;
  }
  if (L.reduced_dim == 0 && L.eliminated_dim == 0) {
    if (error) *error = "no free variables";
    return false;
  }
  return true;
}

void Engine::choose_kernels() {
  // One (R, E, F) for the whole problem when the sizes allow it: BAL (2, 3, 9), pinhole
  // monocular (2, 3, 6), stereo (3, 3, 6).
  int r = 0, e = 0, f = 0;
  bool uniform = true;
  for (const int v : layout_.reduced_variable) {
    const int size = problem_.variables[v].manifold->tangent_size();
    if (f == 0) f = size;
    uniform = uniform && size == f;
  }
  for (const int v : layout_.eliminated_variable) {
    const int size = problem_.variables[v].manifold->tangent_size();
    if (e == 0) e = size;
    uniform = uniform && size == e;
  }
  int plain_r = 0;
  bool plain_uniform = true;
  for (const int factor : layout_.plain_factors) {
    const int size = problem_.factors[factor].residual_size;
    if (plain_r == 0) plain_r = size;
    plain_uniform = plain_uniform && size == plain_r;
  }
  const bool reduced_uniform = uniform;  // every reduced block has size f
  if (plain_uniform && reduced_uniform) {
    const auto plain_is = [&](int rr, int ff) { return plain_r == rr && f == ff; };
    if (plain_is(3, 3) || plain_is(6, 6) || plain_is(6, 3) || plain_is(12, 6)) {
      plain_r_ = plain_r;
      plain_f_ = f;
    }
  }
  for (const int factor : layout_.eliminated_factors) {
    const int size = problem_.factors[factor].residual_size;
    if (r == 0) r = size;
    uniform = uniform && size == r;
  }
  if (!uniform) return;
  const auto is = [&](int rr, int ee, int ff) { return r == rr && e == ee && f == ff; };
  if (is(2, 3, 9) || is(2, 3, 6) || is(3, 3, 6) || is(2, 2, 3)) {
    fixed_r_ = r;
    fixed_e_ = e;
    fixed_f_ = f;
  }
}

bool Engine::evaluate(bool with_jacobians, double& cost, std::vector<double>& residual_buffer,
                      std::vector<double>& jacobian_buffer) {
  const int factors = static_cast<int>(problem_.factors.size());
  tbb::enumerable_thread_specific<double> partial(0.0);
  std::atomic<bool> ok{true};
  tbb::enumerable_thread_specific<std::vector<const double*>> value_pointers;
  tbb::enumerable_thread_specific<std::vector<double*>> jacobian_pointers;
  const auto evaluate_factor = [&](int f, std::vector<const double*>& values, std::vector<double*>& jacobians, double& sum) {
    const FactorEntry& factor = problem_.factors[f];
    const std::size_t n = factor.variables.size();
    values.resize(n);
    jacobians.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      values[k] = problem_.variables[factor.variables[k]].values;
      const int offset = layout_.jacobian_offset[layout_.slot_start[f] + static_cast<int>(k)];
      jacobians[k] = offset < 0 ? nullptr : jacobian_buffer.data() + offset;
    }
    double* residual = residual_buffer.data() + layout_.residual_offset[f];
    const int m = factor.residual_size;
    if (!factor.factor->evaluate(values.data(), residual, with_jacobians ? jacobians.data() : nullptr)) {
      ok = false;
      return;
    }
    double squared = 0.0;
    for (int i = 0; i < m; ++i) squared += residual[i] * residual[i];
    if (!std::isfinite(squared)) {
      ok = false;
      return;
    }
    if (factor.loss.kernel == RobustKernel::kNone) {
      sum += 0.5 * squared;
    } else {
      // Ceres' Corrector (internal/ceres/corrector.cc) with rho'' <= 0 (Huber outside its core,
      // Cauchy, Geman-McClure): r and J scaled by sqrt(rho'); our kernels never have rho'' > 0.
      const KernelValue kernel = evaluate_kernel(factor.loss.kernel, factor.loss.scale, squared);
      sum += 0.5 * kernel.rho;
      const double scale = std::sqrt(kernel.weight);
      if (scale != 1.0) {
        for (int i = 0; i < m; ++i) residual[i] *= scale;
        if (with_jacobians) {
          for (std::size_t k = 0; k < n; ++k) {
            if (jacobians[k] == nullptr) continue;
            const int size = m * problem_.variables[factor.variables[k]].manifold->tangent_size();
            for (int i = 0; i < size; ++i) jacobians[k][i] *= scale;
          }
        }
      }
    }
    if (with_jacobians) {
      for (std::size_t k = 0; k < n; ++k) {
        if (jacobians[k] == nullptr) continue;
        const int size = m * problem_.variables[factor.variables[k]].manifold->tangent_size();
        for (int i = 0; i < size; ++i) {
          if (!std::isfinite(jacobians[k][i])) {
            ok = false;
            return;
          }
        }
      }
    }
  };
  parallel_chunks(factors, 256, [&](int begin, int end) {
    auto& values = value_pointers.local();
    auto& jacobians = jacobian_pointers.local();
    double& sum = partial.local();
    for (int f = begin; f < end; ++f) evaluate_factor(f, values, jacobians, sum);
  });
  cost = partial.combine(std::plus<>());
  return ok.load() && std::isfinite(cost);
}

void Engine::compute_gradient() {
  gradient_eliminated_.setZero(layout_.eliminated_dim);
  const int n = layout_.reduced_dim;
  tbb::enumerable_thread_specific<Eigen::VectorXd> partial([n] { return Eigen::VectorXd::Zero(n); });
  // g += J_k^T r for factor f's free variables: eliminated parts in place (one task owns each
  // eliminated block), reduced parts into the task's partial sum.
  const auto add_factor = [&](int f, double* reduced) {
    const FactorEntry& factor = problem_.factors[f];
    const int m = factor.residual_size;
    const double* r = residuals_.data() + layout_.residual_offset[f];
    for (std::size_t k = 0; k < factor.variables.size(); ++k) {
      const double* J = jacobian(f, static_cast<int>(k));
      if (J == nullptr) continue;
      const int v = factor.variables[k];
      const int size = problem_.variables[v].manifold->tangent_size();
      double* g = layout_.eliminated[v] ? gradient_eliminated_.data() + layout_.eliminated_offset[layout_.block_of[v]]
                                        : reduced + layout_.reduced_offset[layout_.block_of[v]];
      for (int i = 0; i < m; ++i) {
        for (int j = 0; j < size; ++j) g[j] += J[i * size + j] * r[i];
      }
    }
  };
  parallel_chunks(static_cast<int>(layout_.eliminated_variable.size()), 256, [&](int begin, int end) {
    double* reduced = partial.local().data();
    for (int e = begin; e < end; ++e) {
      for (int index = layout_.eliminated_factor_start[e]; index < layout_.eliminated_factor_start[e + 1]; ++index) {
        add_factor(layout_.eliminated_factors[index], reduced);
      }
    }
  });
  parallel_chunks(static_cast<int>(layout_.plain_factors.size()), 512, [&](int begin, int end) {
    double* reduced = partial.local().data();
    for (int i = begin; i < end; ++i) add_factor(layout_.plain_factors[i], reduced);
  });
  gradient_reduced_.setZero(n);
  for (const auto& part : partial) gradient_reduced_ += part;
}

// Per eliminated block e with factors f_1..f_m: V = sum J_e^T J_e + D_e / mu and
// g_e = sum J_e^T r; then, with P_f = J_ef V^-1 (R x E) for each factor, every pair of
// (factor, reduced variable) items a = (f, c), b = (f', c') adds to S(c, c')
//     J_c^T (I - P_f J_ef^T) J_c'   when f = f' (A's J^T J and the Schur term together),
//    -J_c^T (P_f J_ef'^T) J_c'       otherwise,
// which is A - W V^-1 W^T with W = J_e^T J_c written through the R x R matrices between the
// residuals: with R = 2 < E = 3 (bundle adjustment) the inner products are over 2, not 3, and A
// needs no separate pass (40 % fewer flops than forming W_a^T V^-1 W_b per pair). And
// rhs(c) += J_c^T (r_f - P_f g_e), i.e. g_c - W V^-1 g_e.
template <int R, int E, int F>
void Engine::eliminate(int e, double mu_inverse, double* matrix_values, double* rhs, double* diagonal,
                       bool diagonal_only) {
  using MatrixEE = Eigen::Matrix<double, E, E>;
  using MatrixRE = Eigen::Matrix<double, R, E>;
  using MatrixRR = Eigen::Matrix<double, R, R>;
  using MatrixRF = Eigen::Matrix<double, R, F>;
  using VectorE = Eigen::Matrix<double, E, 1>;
  const int e_variable = layout_.eliminated_variable[e];
  const int e_size = E != Eigen::Dynamic ? E : problem_.variables[e_variable].manifold->tangent_size();
  MatrixEE V = MatrixEE::Zero(e_size, e_size);
  VectorE g_e = VectorE::Zero(e_size);

  struct Item {
    int block;        ///< reduced block of the variable
    int factor_item;  ///< index into `factors` below
    const double* J_c;
    int f_size;
  };
  struct FactorItem {
    const double* J_e;
    const double* r;
    int m;
    MatrixRE P;  ///< J_e V^-1
  };
  thread_local std::vector<Item> items;
  thread_local std::vector<FactorItem> factors;
  items.clear();
  factors.clear();
  const int begin = layout_.eliminated_factor_start[e];
  const int end = layout_.eliminated_factor_start[e + 1];
  const double* jacobians = jacobians_.data();
  for (int index = begin; index < end; ++index) {
    const auto entry = static_cast<std::size_t>(index);
    const int m = R != Eigen::Dynamic ? R : schur_residual_size_[entry];
    const double* r = residuals_.data() + schur_residual_offset_[entry];
    const double* J_e_data = jacobians + schur_e_jacobian_[entry];
    const ConstMap<R, E> J_e(J_e_data, m, e_size);
    V.noalias() += J_e.transpose().lazyProduct(J_e);
    g_e.noalias() += J_e.transpose() * ConstVectorMap<R>(r, m);
    const int factor_item = static_cast<int>(factors.size());
    factors.push_back({J_e_data, r, m, MatrixRE::Zero(m, e_size)});
    for (int t = schur_term_start_[entry]; t < schur_term_start_[entry + 1]; ++t) {
      const ReducedTerm& term = schur_terms_[static_cast<std::size_t>(t)];
      const int f_size = F != Eigen::Dynamic ? F : term.size;
      const double* J_c = jacobians + term.jacobian;
      items.push_back({term.block, factor_item, J_c, f_size});
      // diag(J_c^T J_c): the LM damping's D on the reduced unknowns.
      const ConstMap<R, F> J(J_c, m, f_size);
      double* d = diagonal + term.offset;
      for (int i = 0; i < f_size; ++i) d[i] += J.col(i).squaredNorm();
    }
  }
  for (int i = 0; i < e_size; ++i) {
    const double d = std::clamp(V(i, i), options_.min_diagonal, options_.max_diagonal);
    V(i, i) += d * mu_inverse;
  }
  const Eigen::LLT<MatrixEE> llt(V);
  MatrixEE V_inverse = MatrixEE::Identity(e_size, e_size);
  if (llt.info() == Eigen::Success) {
    llt.solveInPlace(V_inverse);
  } else {
    V_inverse = V.completeOrthogonalDecomposition().pseudoInverse();
  }
  Eigen::Map<MatrixEE>(v_inverse_.data() + v_inverse_offset_[e], e_size, e_size) = V_inverse;
  for (FactorItem& item : factors) {
    item.P.noalias() = ConstMap<R, E>(item.J_e, item.m, e_size).lazyProduct(V_inverse);
  }
  for (const Item& a : items) {
    const FactorItem& fa = factors[a.factor_item];
    const Eigen::Matrix<double, R, 1> corrected = ConstVectorMap<R>(fa.r, fa.m) - fa.P * g_e;
    VectorMap<F>(rhs + reduced_->offset(a.block), a.f_size).noalias() +=
        ConstMap<R, F>(a.J_c, fa.m, a.f_size).transpose() * corrected;
  }
  thread_local std::vector<double*> destination;
  if constexpr (F != Eigen::Dynamic) {
    // The destination blocks are scattered over S (33 MB for 318 cameras): find them all and
    // ask for their cache lines before the products, which then overlap the misses.
    destination.clear();
    for (const Item& a : items) {
      for (const Item& b : items) {
        if (b.block < a.block || (diagonal_only && b.block != a.block)) continue;
        double* block = matrix_values + reduced_->block_offset(a.block, b.block);
        destination.push_back(block);
        for (int line = 0; line < F * F; line += 8) __builtin_prefetch(block + line, 1);
      }
    }
  }
  std::size_t pair = 0;
  for (const Item& a : items) {
    const FactorItem& fa = factors[a.factor_item];
    const ConstMap<R, F> J_a(a.J_c, fa.m, a.f_size);
    for (const Item& b : items) {
      if (b.block < a.block || (diagonal_only && b.block != a.block)) continue;
      const FactorItem& fb = factors[b.factor_item];
      MatrixRR M = -fa.P.lazyProduct(ConstMap<R, E>(fb.J_e, fb.m, e_size).transpose());
      if (a.factor_item == b.factor_item) M.diagonal().array() += 1.0;
      const MatrixRF M_J_b = M.lazyProduct(ConstMap<R, F>(b.J_c, fb.m, b.f_size));
      if constexpr (R == 2 && F != Eigen::Dynamic) {
        // b.block >= a.block: the block is stored as is, F x F column-major.
        rank2_update<F>(destination[pair++], a.J_c, M_J_b.data());
      } else if constexpr (F != Eigen::Dynamic) {
        Eigen::Map<Eigen::Matrix<double, F, F>>(destination[pair++]) += J_a.transpose().lazyProduct(M_J_b);
      } else {
        reduced_->add(a.block, b.block, Eigen::MatrixXd(J_a.transpose().lazyProduct(M_J_b)), matrix_values);
      }
    }
  }
}

template <int R, int F>
void Engine::add_plain_factor(int f, double* matrix_values, double* rhs, double* diagonal, bool diagonal_only) {
  const FactorEntry& factor = problem_.factors[f];
  const int m = R != Eigen::Dynamic ? R : factor.residual_size;
  const ConstVectorMap<R> r(residuals_.data() + layout_.residual_offset[f], m);
  for (std::size_t k = 0; k < factor.variables.size(); ++k) {
    const int v = factor.variables[k];
    const int block = layout_.block_of[v];
    if (block < 0) continue;
    const int f_size = F != Eigen::Dynamic ? F : problem_.variables[v].manifold->tangent_size();
    const ConstMap<R, F> J_c(free_jacobian(f, static_cast<int>(k)), m, f_size);
    VectorMap<F>(rhs + reduced_->offset(block), f_size).noalias() += J_c.transpose() * r;
    for (std::size_t k2 = 0; k2 < factor.variables.size(); ++k2) {
      const int v2 = factor.variables[k2];
      const int block2 = layout_.block_of[v2];
      if (block2 < 0 || block2 < block || (diagonal_only && block2 != block)) continue;
      const int f2_size = F != Eigen::Dynamic ? F : problem_.variables[v2].manifold->tangent_size();
      const ConstMap<R, F> J_c2(free_jacobian(f, static_cast<int>(k2)), m, f2_size);
      const Eigen::Matrix<double, F, F> product = J_c.transpose().lazyProduct(J_c2);
      reduced_->add(block, block2, product, matrix_values);
      if (block2 == block) {
        for (int i = 0; i < f_size; ++i) diagonal[reduced_->offset(block) + i] += product(i, i);
      }
    }
  }
}

// J_r x_r of factor f: the sum over its free reduced variables c of J_c x_c.
template <int R, int F>
Eigen::Matrix<double, R, 1> Engine::reduced_times(int f, const double* x) const {
  const FactorEntry& factor = problem_.factors[f];
  const int m = R != Eigen::Dynamic ? R : factor.residual_size;
  Eigen::Matrix<double, R, 1> z = Eigen::Matrix<double, R, 1>::Zero(m);
  for (std::size_t k = 0; k < factor.variables.size(); ++k) {
    const int v = factor.variables[k];
    const int block = layout_.block_of[v];
    if (block < 0 || layout_.eliminated[v]) continue;
    const int f_size = F != Eigen::Dynamic ? F : problem_.variables[v].manifold->tangent_size();
    const ConstMap<R, F> J_c(free_jacobian(f, static_cast<int>(k)), m, f_size);
    z.noalias() += J_c * ConstVectorMap<F>(x + layout_.reduced_offset[block], f_size);
  }
  return z;
}

// y_c += J_c^T z for the free reduced variables c of factor f.
template <int R, int F>
void Engine::add_reduced_transpose_times(int f, const Eigen::Matrix<double, R, 1>& z, double* y) const {
  const FactorEntry& factor = problem_.factors[f];
  const int m = static_cast<int>(z.size());
  for (std::size_t k = 0; k < factor.variables.size(); ++k) {
    const int v = factor.variables[k];
    const int block = layout_.block_of[v];
    if (block < 0 || layout_.eliminated[v]) continue;
    const int f_size = F != Eigen::Dynamic ? F : problem_.variables[v].manifold->tangent_size();
    const ConstMap<R, F> J_c(free_jacobian(f, static_cast<int>(k)), m, f_size);
    VectorMap<F>(y + layout_.reduced_offset[block], f_size).noalias() += J_c.transpose() * z;
  }
}

// dx_e = -V^-1 (g_e + sum_f J_e^T (J_r dx_r)).
template <int R, int E, int F>
void Engine::back_substitute(int e) {
  using VectorE = Eigen::Matrix<double, E, 1>;
  const int e_size = E != Eigen::Dynamic ? E : problem_.variables[layout_.eliminated_variable[e]].manifold->tangent_size();
  const int e_offset = layout_.eliminated_offset[e];
  VectorE sum = gradient_eliminated_.segment(e_offset, e_size);
  const double* jacobians = jacobians_.data();
  for (int index = layout_.eliminated_factor_start[e]; index < layout_.eliminated_factor_start[e + 1]; ++index) {
    const auto entry = static_cast<std::size_t>(index);
    const int m = R != Eigen::Dynamic ? R : schur_residual_size_[entry];
    // J_r dx_r over the factor's free reduced variables, in the factor's order.
    Eigen::Matrix<double, R, 1> J_dx = Eigen::Matrix<double, R, 1>::Zero(m);
    for (int t = schur_term_start_[entry]; t < schur_term_start_[entry + 1]; ++t) {
      const ReducedTerm& term = schur_terms_[static_cast<std::size_t>(t)];
      const int f_size = F != Eigen::Dynamic ? F : term.size;
      J_dx.noalias() += ConstMap<R, F>(jacobians + term.jacobian, m, f_size) * ConstVectorMap<F>(step_reduced_.data() + term.offset, f_size);
    }
    const ConstMap<R, E> J_e(jacobians + schur_e_jacobian_[entry], m, e_size);
    sum.noalias() += J_e.transpose() * J_dx;
  }
  const Eigen::Map<const Eigen::Matrix<double, E, E>> V_inverse(v_inverse_.data() + v_inverse_offset_[e], e_size, e_size);
  step_eliminated_.segment(e_offset, e_size).noalias() = -(V_inverse * sum);
}

// y += (A - W V^-1 W^T) x restricted to eliminated block e's factors (A's part from them):
// z_f = J_r x for each factor, u = V^-1 sum_f J_e^T z_f, then y += J_r^T (z_f - J_e u) factor by
// factor (one transposed product per factor instead of two).
template <int R, int E, int F>
void Engine::schur_product_block(int e, const double* x, double* y) const {
  using VectorE = Eigen::Matrix<double, E, 1>;
  using VectorR = Eigen::Matrix<double, R, 1>;
  const int e_size = E != Eigen::Dynamic ? E : problem_.variables[layout_.eliminated_variable[e]].manifold->tangent_size();
  const int begin = layout_.eliminated_factor_start[e];
  const int end = layout_.eliminated_factor_start[e + 1];
  const double* jacobians = jacobians_.data();
  thread_local std::vector<VectorR> z;
  z.resize(static_cast<std::size_t>(end - begin));
  VectorE w = VectorE::Zero(e_size);
  for (int index = begin; index < end; ++index) {
    const int m = R != Eigen::Dynamic ? R : schur_residual_size_[static_cast<std::size_t>(index)];
    VectorR& z_f = z[static_cast<std::size_t>(index - begin)];
    z_f.setZero(m);
    for (int t = schur_term_start_[static_cast<std::size_t>(index)]; t < schur_term_start_[static_cast<std::size_t>(index) + 1]; ++t) {
      const ReducedTerm& term = schur_terms_[static_cast<std::size_t>(t)];
      const int f_size = F != Eigen::Dynamic ? F : term.size;
      z_f.noalias() += ConstMap<R, F>(jacobians + term.jacobian, m, f_size) * ConstVectorMap<F>(x + term.offset, f_size);
    }
    w.noalias() += ConstMap<R, E>(jacobians + schur_e_jacobian_[static_cast<std::size_t>(index)], m, e_size).transpose() * z_f;
  }
  const Eigen::Map<const Eigen::Matrix<double, E, E>> V_inverse(v_inverse_.data() + v_inverse_offset_[e], e_size, e_size);
  const VectorE u = V_inverse * w;
  for (int index = begin; index < end; ++index) {
    const int m = R != Eigen::Dynamic ? R : schur_residual_size_[static_cast<std::size_t>(index)];
    const VectorR t_f = z[static_cast<std::size_t>(index - begin)] -
                        ConstMap<R, E>(jacobians + schur_e_jacobian_[static_cast<std::size_t>(index)], m, e_size) * u;
    for (int t = schur_term_start_[static_cast<std::size_t>(index)]; t < schur_term_start_[static_cast<std::size_t>(index) + 1]; ++t) {
      const ReducedTerm& term = schur_terms_[static_cast<std::size_t>(t)];
      const int f_size = F != Eigen::Dynamic ? F : term.size;
      VectorMap<F>(y + term.offset, f_size).noalias() += ConstMap<R, F>(jacobians + term.jacobian, m, f_size).transpose() * t_f;
    }
  }
}

template <int R, int F>
void Engine::plain_product(int f, const double* x, double* y) const {
  add_reduced_transpose_times<R, F>(f, reduced_times<R, F>(f, x), y);
}

#define CAIRN_DISPATCH_RFE(CALL_FIXED, CALL_DYNAMIC)                       \
  if (fixed_r_ == 2 && fixed_e_ == 3 && fixed_f_ == 9) { CALL_FIXED(2, 3, 9); } \
  else if (fixed_r_ == 2 && fixed_e_ == 3 && fixed_f_ == 6) { CALL_FIXED(2, 3, 6); } \
  else if (fixed_r_ == 3 && fixed_e_ == 3 && fixed_f_ == 6) { CALL_FIXED(3, 3, 6); } \
  else if (fixed_r_ == 2 && fixed_e_ == 2 && fixed_f_ == 3) { CALL_FIXED(2, 2, 3); } \
  else { CALL_DYNAMIC; }

#define CAIRN_DISPATCH_PLAIN(CALL_FIXED, CALL_DYNAMIC)                        \
  if (plain_r_ == 3 && plain_f_ == 3) { CALL_FIXED(3, 3); }                  \
  else if (plain_r_ == 6 && plain_f_ == 6) { CALL_FIXED(6, 6); }             \
  else if (plain_r_ == 6 && plain_f_ == 3) { CALL_FIXED(6, 3); }             \
  else if (plain_r_ == 12 && plain_f_ == 6) { CALL_FIXED(12, 6); }           \
  else { CALL_DYNAMIC; }

void Engine::schur_product(const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  const int n = layout_.reduced_dim;
  tbb::enumerable_thread_specific<Eigen::VectorXd> partial([n] { return Eigen::VectorXd::Zero(n); });
  const int blocks = static_cast<int>(layout_.eliminated_variable.size());
#if defined(CAIRN_SCHUR_AVX)
  const bool avx = kHaveAvx && fixed_r_ == 2 && fixed_e_ == 3 && (fixed_f_ == 9 || fixed_f_ == 6);
  const SchurProductTables tables{elimination_order_.data(), layout_.eliminated_factor_start.data(), schur_term_start_.data(),
                                  schur_terms_.data(), schur_e_jacobian_.data(), jacobians_.data(),
                                  v_inverse_.data(), v_inverse_offset_.data()};
#endif
  parallel_chunks(blocks, 64, [&](int begin, int end) {
    double* out = partial.local().data();
#if defined(CAIRN_SCHUR_AVX)
    if (avx) {
      thread_local std::vector<double> z;
      z.resize(2 * static_cast<std::size_t>(max_entries_per_block_));
      if (fixed_f_ == 9) {
        schur_product_r2e3_avx<9>(tables, begin, end, x.data(), out, z.data());
      } else {
        schur_product_r2e3_avx<6>(tables, begin, end, x.data(), out, z.data());
      }
      return;
    }
#endif
    for (int i = begin; i < end; ++i) {
      const int e = elimination_order_[i];
#define CAIRN_CALL(R, E, F) schur_product_block<R, E, F>(e, x.data(), out)
      CAIRN_DISPATCH_RFE(CAIRN_CALL, (schur_product_block<Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic>(e, x.data(), out)))
#undef CAIRN_CALL
    }
  });
  y = Eigen::Map<const Eigen::VectorXd>(damping_reduced_.data(), n).cwiseProduct(x);
  for (const int f : layout_.plain_factors) plain_product<Eigen::Dynamic, Eigen::Dynamic>(f, x.data(), y.data());
  for (const auto& part : partial) y += part;
}

// Preconditioned conjugate gradients on S x = rhs with the block-Jacobi preconditioner of S
// (Ceres' SCHUR_JACOBI). Stopping rule: the truncated-Newton test of Nash & Sofer (1990) on the
// quadratic model Q(x) = 1/2 x^T S x - rhs^T x, stop when i (Q_i - Q_{i-1}) / Q_i < eta after
// at least min_cg_iterations -- the rule Ceres' LevenbergMarquardtStrategy gives its CG
// (q_tolerance = eta, no residual test; internal/ceres/conjugate_gradients_solver.cc).
bool Engine::solve_iterative(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, int& cg_iterations) {
  const int n = layout_.reduced_dim;
  x.setZero(n);
  Eigen::VectorXd r = rhs;
  cg_iterations = 0;
  if (rhs.squaredNorm() == 0.0) return true;
  const auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    out.resize(n);
    for (std::size_t b = 0; b < preconditioner_.size(); ++b) {
      const int offset = layout_.reduced_offset[b];
      const int size = static_cast<int>(preconditioner_[b].rows());
      out.segment(offset, size).noalias() = preconditioner_[b] * in.segment(offset, size);
    }
  };
  Eigen::VectorXd z, p, q;
  precondition(r, z);
  p = z;
  double rz = r.dot(z);
  double Q_previous = 0.0;  // Q(0)
  for (int k = 0; k < options_.max_cg_iterations; ++k) {
    schur_product(p, q);
    const double pq = p.dot(q);
    if (!(pq > 0.0)) return k > 0;  // S is positive definite; stop on breakdown
    const double alpha = rz / pq;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * q;
    cg_iterations = k + 1;
    // Q(x) = 1/2 x^T S x - rhs^T x = -1/2 x^T (rhs + r), with r = rhs - S x.
    const double Q = -0.5 * x.dot(rhs + r);
    const double zeta = cg_iterations * (Q - Q_previous) / Q;
    Q_previous = Q;
    if (cg_iterations >= options_.min_cg_iterations && zeta < options_.cg_tolerance) return true;
    precondition(r, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return true;
}

// kSparseSchur with reuse_factorization: S x = rhs by conjugate gradients preconditioned with
// the last numeric factorisation (of the previous iteration's S) instead of a new one, as the
// pose-graph optimiser does (optimizer.hpp, reuse_factorization; an inexact LM step, Wright &
// Holt 1985). Tried only where a factorisation costs at least kReuseMinFlopRatio PCG iterations,
// so a failed attempt (reuse_max_cg_iterations without reaching the forcing term) costs at most
// a small fraction of the factorisation it tried to save. False: factorise.
bool Engine::solve_with_previous_factor(const UpperCsc& S, const Eigen::VectorXd& rhs, int& cg_iterations) {
  constexpr double kReuseMinFlopRatio = 50.0;
  if (!options_.reuse_factorization || !cholesky_.has_factor()) return false;
  const double pcg_flops = 4.0 * static_cast<double>(cholesky_.factor_nonzeros()) + 4.0 * static_cast<double>(S.value.size());
  if (cholesky_.factor_flops() < kReuseMinFlopRatio * pcg_flops) return false;
  const int n = S.size;
  Eigen::VectorXd& x = step_reduced_;
  x.setZero(n);
  Eigen::VectorXd r = rhs, z(n), p, q;
  const double rhs_norm = rhs.norm();
  if (rhs_norm == 0.0) return true;
  cholesky_.solve_in_place(r, z);
  p = z;
  double rz = r.dot(z);
  // S p: from the block storage where every reduced block has one fixed size (bundle
  // adjustment's cameras), else from the CSC values (which hold the damping already).
  const auto multiply = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    if (fixed_f_ == 9 || fixed_f_ == 6) {
      out = Eigen::Map<const Eigen::VectorXd>(damping_reduced_.data(), n).cwiseProduct(in);
      if (fixed_f_ == 9) {
        reduced_->multiply<9>(block_values_.data(), in.data(), out.data());
      } else {
        reduced_->multiply<6>(block_values_.data(), in.data(), out.data());
      }
    } else {
      symmetric_multiply(S, in, out);
    }
  };
  for (int k = 0; k < options_.reuse_max_cg_iterations; ++k) {
    multiply(p, q);
    const double pq = p.dot(q);
    if (!(pq > 0.0)) break;
    const double alpha = rz / pq;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * q;
    ++cg_iterations;
    if (r.norm() <= options_.reuse_cg_tolerance * rhs_norm) {
      ++summary_->reused_factorizations;
      return true;
    }
    cholesky_.solve_in_place(r, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return false;
}

bool Engine::solve_system(double mu_inverse, int& cg_iterations, bool* inexact) {
  *inexact = false;
  const bool iterative = options_.linear_solver == LinearSolverType::kIterativeSchur;
  UpperCsc& S = reduced_->matrix();
  const int n = layout_.reduced_dim;
  const int blocks = static_cast<int>(layout_.eliminated_variable.size());
  const auto system_start = Clock::now();
  // Per-thread partial sums of S's blocks, the rhs and diag(J^T J). The first thread to start
  // accumulates into block_values_ itself, so a single-threaded solve copies nothing (S of the
  // 318-camera BAL problem is dense, 4.1 million values).
  // The other threads' block sums live in partial_pool_, kept from one iteration to the next:
  // allocating 33 MB per thread and iteration cost page faults on every iteration.
  struct Partial {
    double* values = nullptr;
    bool own = false;  ///< values is one of partial_pool_'s buffers
    Eigen::VectorXd rhs;
    Eigen::VectorXd diagonal;
  };
  const std::size_t nonzeros = reduced_->blocks_size();
  block_values_.assign(nonzeros, 0.0);
  const std::size_t max_threads = static_cast<std::size_t>(std::max(1, arena_.max_concurrency()));
  if (partial_pool_.size() < max_threads - 1) partial_pool_.resize(max_threads - 1);
  std::atomic<bool> claimed{false};
  std::atomic<std::size_t> next_buffer{0};
  tbb::enumerable_thread_specific<Partial> partial([&] {
    Partial p{nullptr, false, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
    if (!claimed.exchange(true)) {
      p.values = block_values_.data();
    } else {
      const std::size_t k = next_buffer++;
      CAIRN_ASSERT(k < partial_pool_.size(), "Engine: more threads than the arena's concurrency");
      partial_pool_[k].assign(nonzeros, 0.0);
      p.values = partial_pool_[k].data();
      p.own = true;
    }
    return p;
  });
  parallel_chunks(blocks, 32, [&](int begin, int end) {
    Partial& mine = partial.local();
    for (int i = begin; i < end; ++i) {
      const int e = elimination_order_[i];
#define CAIRN_CALL(R, E, F) eliminate<R, E, F>(e, mu_inverse, mine.values, mine.rhs.data(), mine.diagonal.data(), iterative)
      CAIRN_DISPATCH_RFE(CAIRN_CALL, (eliminate<Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic>(
                                          e, mu_inverse, mine.values, mine.rhs.data(), mine.diagonal.data(), iterative)))
#undef CAIRN_CALL
    }
  });
  // Plain factors (no eliminated variable: all of a pose graph's) into the same partial sums.
  parallel_chunks(static_cast<int>(layout_.plain_factors.size()), 256, [&](int begin, int end) {
    Partial& mine = partial.local();
    for (int i = begin; i < end; ++i) {
      const int f = layout_.plain_factors[i];
#define CAIRN_CALL(R, F) add_plain_factor<R, F>(f, mine.values, mine.rhs.data(), mine.diagonal.data(), iterative)
      CAIRN_DISPATCH_PLAIN(CAIRN_CALL, (add_plain_factor<Eigen::Dynamic, Eigen::Dynamic>(
                                           f, mine.values, mine.rhs.data(), mine.diagonal.data(), iterative)))
#undef CAIRN_CALL
    }
  });
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd diagonal = Eigen::VectorXd::Zero(n);
  std::vector<const double*> others;
  for (const Partial& part : partial) {
    if (part.own) others.push_back(part.values);
    rhs += part.rhs;
    diagonal += part.diagonal;
  }
  if (!others.empty()) {
    // The sum over threads in the same order as before (block_values_ + each other thread's),
    // split over ranges of the storage.
    constexpr int kRange = 1 << 16;
    const int ranges = static_cast<int>((nonzeros + kRange - 1) / kRange);
    parallel(ranges, 1, [&](int range) {
      const std::size_t begin = static_cast<std::size_t>(range) * kRange;
      const std::size_t end = std::min(nonzeros, begin + kRange);
      for (const double* other : others) {
        for (std::size_t i = begin; i < end; ++i) block_values_[i] += other[i];
      }
    });
  }
  reduced_->to_csc(block_values_.data(), S.value.data());
  // LM damping D / mu on the reduced unknowns, D = diag(J^T J) clamped (Ceres).
  damping_reduced_.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    damping_reduced_[i] = std::clamp(diagonal[i], options_.min_diagonal, options_.max_diagonal) * mu_inverse;
    reduced_->add_diagonal(i, damping_reduced_[i], S.value.data());
  }
  summary_->linear_system_s += seconds_since(system_start);

  const auto solve_start = Clock::now();
  Eigen::VectorXd minus_rhs = -rhs;
  cg_iterations = 0;
  if (n > 0) {
    if (iterative) {
      // S's diagonal blocks (formed above, diagonal_only) -> inverses for the preconditioner.
      preconditioner_.resize(layout_.reduced_variable.size());
      for (std::size_t b = 0; b < layout_.reduced_variable.size(); ++b) {
        const int size = reduced_->size(static_cast<int>(b));
        const int offset = reduced_->offset(static_cast<int>(b));
        Eigen::MatrixXd block(size, size);
        for (int j = 0; j < size; ++j) {
          const int start = S.column_start[offset + j];
          for (int i = 0; i <= j; ++i) block(i, j) = block(j, i) = S.value[start + i];
        }
        Eigen::LLT<Eigen::MatrixXd> llt(block);
        if (llt.info() != Eigen::Success) return false;
        preconditioner_[b] = llt.solve(Eigen::MatrixXd::Identity(size, size));
      }
      if (!solve_iterative(minus_rhs, step_reduced_, cg_iterations)) return false;
    } else {
      if (!analyzed_) {
        const auto analyze_start = Clock::now();
        cholesky_.analyze_in_stored_order(S);
        summary_->analyze_s += seconds_since(analyze_start);
        summary_->factor_nonzeros = cholesky_.factor_nonzeros();
        analyzed_ = true;
      }
      if (solve_with_previous_factor(S, minus_rhs, cg_iterations)) {
        *inexact = true;
      } else {
        if (cholesky_.factorize(S) != FactorizationStatus::kSuccess) return false;
        ++summary_->factorizations;
        step_reduced_ = cholesky_.solve(minus_rhs);
      }
    }
  } else {
    step_reduced_.resize(0);
  }
  if (!step_reduced_.allFinite()) return false;
  summary_->linear_solve_s += seconds_since(solve_start);

  const auto back_start = Clock::now();
  step_eliminated_.setZero(layout_.eliminated_dim);
  parallel(blocks, 256, [&](int e) {
#define CAIRN_CALL(R, E, F) back_substitute<R, E, F>(e)
    CAIRN_DISPATCH_RFE(CAIRN_CALL, (back_substitute<Eigen::Dynamic, Eigen::Dynamic, Eigen::Dynamic>(e)))
#undef CAIRN_CALL
  });
  summary_->linear_solve_s += seconds_since(back_start);
  return step_eliminated_.allFinite();
}

// r^T J dx and ||J dx||^2, factor by factor: the model cost change of a step is
// 1/2 ||r||^2 - 1/2 ||r + J dx||^2 = -(r . J dx) - 1/2 ||J dx||^2 (Ceres' model cost change).
void Engine::jacobian_products(const double* dx_reduced, const double* dx_eliminated, double* r_dot,
                               double* squared) const {
  const int factors = static_cast<int>(problem_.factors.size());
  double dot = 0.0;
  double norm = 0.0;
  std::vector<double> large;
  for (int f = 0; f < factors; ++f) {
    const FactorEntry& factor = problem_.factors[f];
    const int m = factor.residual_size;
    const double* r = residuals_.data() + layout_.residual_offset[f];
    double J_dx[16];
    double* product = J_dx;
    if (m > 16) {
      large.assign(m, 0.0);
      product = large.data();
    } else {
      std::fill(J_dx, J_dx + m, 0.0);
    }
    for (std::size_t k = 0; k < factor.variables.size(); ++k) {
      const double* J = jacobian(f, static_cast<int>(k));
      if (J == nullptr) continue;
      const int v = factor.variables[k];
      const int n = problem_.variables[v].manifold->tangent_size();
      const int block = layout_.block_of[v];
      const double* dx = layout_.eliminated[v] ? dx_eliminated + layout_.eliminated_offset[block]
                                               : dx_reduced + layout_.reduced_offset[block];
      for (int i = 0; i < m; ++i) {
        double sum = 0.0;
        for (int j = 0; j < n; ++j) sum += J[i * n + j] * dx[j];
        product[i] += sum;
      }
    }
    for (int i = 0; i < m; ++i) {
      dot += r[i] * product[i];
      norm += product[i] * product[i];
    }
  }
  *r_dot = dot;
  *squared = norm;
}

void Engine::join_step(Eigen::VectorXd& step) const {
  step.resize(step_reduced_.size() + step_eliminated_.size());
  step.head(step_reduced_.size()) = step_reduced_;
  step.tail(step_eliminated_.size()) = step_eliminated_;
}

void Engine::split_step(const Eigen::VectorXd& step) {
  step_reduced_ = step.head(layout_.reduced_dim);
  step_eliminated_ = step.tail(layout_.eliminated_dim);
}

void Engine::save_values() {
  saved_values_.resize(layout_.ambient_free);
  int k = 0;
  for (const auto& list : {&layout_.reduced_variable, &layout_.eliminated_variable}) {
    for (const int v : *list) {
      const VariableEntry& variable = problem_.variables[v];
      const int size = variable.manifold->ambient_size();
      std::copy(variable.values, variable.values + size, saved_values_.begin() + k);
      k += size;
    }
  }
}

void Engine::restore_values() {
  int k = 0;
  for (const auto& list : {&layout_.reduced_variable, &layout_.eliminated_variable}) {
    for (const int v : *list) {
      const VariableEntry& variable = problem_.variables[v];
      const int size = variable.manifold->ambient_size();
      std::copy(saved_values_.begin() + k, saved_values_.begin() + k + size, variable.values);
      k += size;
    }
  }
}

void Engine::apply_step() {
  for (std::size_t b = 0; b < layout_.reduced_variable.size(); ++b) {
    const VariableEntry& variable = problem_.variables[layout_.reduced_variable[b]];
    variable.manifold->plus(variable.values, step_reduced_.data() + layout_.reduced_offset[b], variable.values);
  }
  const int blocks = static_cast<int>(layout_.eliminated_variable.size());
  parallel(blocks, 1024, [&](int e) {
    const VariableEntry& variable = problem_.variables[layout_.eliminated_variable[e]];
    variable.manifold->plus(variable.values, step_eliminated_.data() + layout_.eliminated_offset[e], variable.values);
  });
}

double Engine::values_norm() {
  double squared = 0.0;
  for (const auto& list : {&layout_.reduced_variable, &layout_.eliminated_variable}) {
    for (const int v : *list) {
      const VariableEntry& variable = problem_.variables[v];
      const int size = variable.manifold->ambient_size();  // one virtual call per variable, not per value
      for (int i = 0; i < size; ++i) squared += variable.values[i] * variable.values[i];
    }
  }
  return std::sqrt(squared);
}

// Ceres' gradient norm: max_i |x_i - (x [+] -g)_i| (for R^n: max |g_i|).
double Engine::compute_gradient_max_norm() {
  double norm = 0.0;
  std::vector<double> minus_g, moved;
  const auto visit = [&](int v, const double* g) {
    const VariableEntry& variable = problem_.variables[v];
    const int tangent = variable.manifold->tangent_size();
    const int ambient = variable.manifold->ambient_size();
    minus_g.assign(g, g + tangent);
    for (double& value : minus_g) value = -value;
    moved.resize(ambient);
    variable.manifold->plus(variable.values, minus_g.data(), moved.data());
    for (int i = 0; i < ambient; ++i) norm = std::max(norm, std::abs(variable.values[i] - moved[i]));
  };
  for (std::size_t b = 0; b < layout_.reduced_variable.size(); ++b) {
    visit(layout_.reduced_variable[b], gradient_reduced_.data() + layout_.reduced_offset[b]);
  }
  for (std::size_t e = 0; e < layout_.eliminated_variable.size(); ++e) {
    visit(layout_.eliminated_variable[e], gradient_eliminated_.data() + layout_.eliminated_offset[e]);
  }
  return norm;
}

void Engine::prepare() {
  // The reduced pattern: reduced blocks coupled by a factor, or through an eliminated block.
  std::vector<int> block_size;
  for (const int v : layout_.reduced_variable) block_size.push_back(problem_.variables[v].manifold->tangent_size());
  std::vector<std::pair<int, int>> pairs;
  const bool iterative = options_.linear_solver == LinearSolverType::kIterativeSchur;
  if (!iterative) {
    std::vector<int> blocks_of_factor;
    for (const int f : layout_.plain_factors) {
      blocks_of_factor.clear();
      for (const int v : problem_.factors[f].variables) {
        if (layout_.block_of[v] >= 0) blocks_of_factor.push_back(layout_.block_of[v]);
      }
      for (std::size_t a = 0; a < blocks_of_factor.size(); ++a) {
        for (std::size_t b = a + 1; b < blocks_of_factor.size(); ++b) pairs.emplace_back(blocks_of_factor[a], blocks_of_factor[b]);
      }
    }
    for (std::size_t e = 0; e < layout_.eliminated_variable.size(); ++e) {
      blocks_of_factor.clear();
      for (int index = layout_.eliminated_factor_start[e]; index < layout_.eliminated_factor_start[e + 1]; ++index) {
        for (const int v : problem_.factors[layout_.eliminated_factors[index]].variables) {
          if (layout_.block_of[v] >= 0 && !layout_.eliminated[v]) blocks_of_factor.push_back(layout_.block_of[v]);
        }
      }
      std::sort(blocks_of_factor.begin(), blocks_of_factor.end());
      blocks_of_factor.erase(std::unique(blocks_of_factor.begin(), blocks_of_factor.end()), blocks_of_factor.end());
      for (std::size_t a = 0; a < blocks_of_factor.size(); ++a) {
        for (std::size_t b = a + 1; b < blocks_of_factor.size(); ++b) pairs.emplace_back(blocks_of_factor[a], blocks_of_factor[b]);
      }
    }
  }
  if (!iterative && !pairs.empty()) {
    // Fill-reducing order of the reduced blocks (AMD on the block graph, as Ceres' use_block_amd),
    // applied by renumbering the blocks, so that CHOLMOD factorises S in the order it is stored
    // and never assembles a permuted copy (SparseCholesky::analyze_in_stored_order).
    const int blocks = static_cast<int>(layout_.reduced_variable.size());
    const std::vector<int> label = block_amd_labels(blocks, pairs);
    std::vector<int> relabelled(blocks);
    for (int b = 0; b < blocks; ++b) relabelled[label[b]] = layout_.reduced_variable[b];
    layout_.reduced_variable = relabelled;
    int offset = 0;
    for (int b = 0; b < blocks; ++b) {
      const int v = layout_.reduced_variable[b];
      layout_.block_of[v] = b;
      layout_.reduced_offset[b] = offset;
      block_size[b] = problem_.variables[v].manifold->tangent_size();
      offset += block_size[b];
    }
    for (auto& [a, b] : pairs) {
      a = label[a];
      b = label[b];
    }
  }
  reduced_ = std::make_unique<ReducedMatrix>(block_size, std::move(pairs));
  {
    const int blocks = static_cast<int>(layout_.eliminated_variable.size());
    std::vector<int> first_block(blocks, std::numeric_limits<int>::max());
    for (int e = 0; e < blocks; ++e) {
      for (int index = layout_.eliminated_factor_start[e]; index < layout_.eliminated_factor_start[e + 1]; ++index) {
        for (const int v : problem_.factors[layout_.eliminated_factors[index]].variables) {
          if (layout_.block_of[v] >= 0 && !layout_.eliminated[v]) first_block[e] = std::min(first_block[e], layout_.block_of[v]);
        }
      }
    }
    elimination_order_.resize(blocks);
    for (int e = 0; e < blocks; ++e) elimination_order_[e] = e;
    std::stable_sort(elimination_order_.begin(), elimination_order_.end(),
                     [&](int a, int b) { return first_block[a] < first_block[b]; });
  }
  // Storage order of residuals and Jacobians: each eliminated block's factors together, blocks in
  // elimination order, then the plain factors (Ceres keeps an E-block's rows together likewise),
  // so that forming S and its products read the Jacobians as a stream instead of one cache miss
  // per factor (BAL files list observations by camera, their points scattered). Only where
  // values live changes: every sum keeps its order.
  {
    int residual = 0;
    std::size_t jacobian = 0;
    const auto place = [&](int f) {
      const FactorEntry& factor = problem_.factors[f];
      layout_.residual_offset[f] = residual;
      residual += factor.residual_size;
      for (std::size_t k = 0; k < factor.variables.size(); ++k) {
        int& offset = layout_.jacobian_offset[layout_.slot_start[f] + static_cast<int>(k)];
        if (offset < 0) continue;
        offset = static_cast<int>(jacobian);
        jacobian += static_cast<std::size_t>(factor.residual_size) * problem_.variables[factor.variables[k]].manifold->tangent_size();
      }
    };
    for (const int e : elimination_order_) {
      for (int index = layout_.eliminated_factor_start[e]; index < layout_.eliminated_factor_start[e + 1]; ++index) {
        place(layout_.eliminated_factors[index]);
      }
    }
    for (const int f : layout_.plain_factors) place(f);
    CAIRN_ASSERT(residual == layout_.residual_size && jacobian == layout_.jacobian_size, "Engine: storage order lost a factor");
  }
  v_inverse_offset_.resize(layout_.eliminated_variable.size() + 1);
  v_inverse_offset_[0] = 0;
  for (std::size_t e = 0; e < layout_.eliminated_variable.size(); ++e) {
    const int size = problem_.variables[layout_.eliminated_variable[e]].manifold->tangent_size();
    v_inverse_offset_[e + 1] = v_inverse_offset_[e] + size * size;
  }
  v_inverse_.assign(v_inverse_offset_.back(), 0.0);
  residuals_.assign(layout_.residual_size, 0.0);
  jacobians_.assign(layout_.jacobian_size, 0.0);
  {
    const std::size_t count = layout_.eliminated_factors.size();
    schur_residual_size_.resize(count);
    schur_residual_offset_.resize(count);
    schur_e_jacobian_.resize(count);
    schur_term_start_.assign(1, 0);
    schur_terms_.clear();
    for (std::size_t index = 0; index < count; ++index) {
      const int f = layout_.eliminated_factors[index];
      const FactorEntry& factor = problem_.factors[f];
      schur_residual_size_[index] = factor.residual_size;
      schur_residual_offset_[index] = layout_.residual_offset[f];
      schur_e_jacobian_[index] = layout_.jacobian_offset[layout_.slot_start[f] + layout_.factor_eliminated_slot[f]];
      for (std::size_t k = 0; k < factor.variables.size(); ++k) {
        const int v = factor.variables[k];
        const int block = layout_.block_of[v];
        if (block < 0 || layout_.eliminated[v]) continue;
        schur_terms_.push_back({layout_.jacobian_offset[layout_.slot_start[f] + static_cast<int>(k)], layout_.reduced_offset[block],
                                problem_.variables[v].manifold->tangent_size(), block});
      }
      schur_term_start_.push_back(static_cast<int>(schur_terms_.size()));
    }
    max_entries_per_block_ = 0;
    for (std::size_t e = 0; e < layout_.eliminated_variable.size(); ++e) {
      max_entries_per_block_ = std::max(max_entries_per_block_, layout_.eliminated_factor_start[e + 1] - layout_.eliminated_factor_start[e]);
    }
  }

}

LeastSquaresSummary Engine::run() {
  const auto start = Clock::now();
  LeastSquaresSummary summary;
  summary_ = &summary;
  summary.linear_solver = options_.linear_solver;
  summary.algorithm = options_.algorithm;
  summary.threads = arena_.max_concurrency();
  // CHOLMOD's BLAS gets the solve's threads, not one per core spinning beside TBB's workers;
  // the caller's setting is restored when the solve ends.
  const ScopedBlasThreads blas(summary.threads);
  summary.factors = static_cast<int>(problem_.factors.size());
  summary.residuals = problem_.residuals;
  const auto finish = [&](LeastSquaresTermination termination, std::string message) {
    summary.termination = termination;
    summary.message = std::move(message);
    summary.total_s = seconds_since(start);
    return summary;
  };
  std::string error;
  if (!options_.is_valid(&error)) return finish(LeastSquaresTermination::kFailure, "invalid options: " + error);
  if (!build_layout(&error)) return finish(LeastSquaresTermination::kFailure, error);
  choose_kernels();
  summary.variables = static_cast<int>(layout_.reduced_variable.size() + layout_.eliminated_variable.size());
  summary.eliminated_variables = static_cast<int>(layout_.eliminated_variable.size());
  summary.reduced_size = layout_.reduced_dim;

  prepare();

  static_cast<TrustRegionResult&>(summary) = minimize(*this, options_);
  return finish(summary.termination, summary.message);
}

bool Engine::start(double* cost, std::string* error) {
  const auto phase = Clock::now();
  if (!evaluate(true, *cost)) {
    summary_->jacobian_s += seconds_since(phase);
    *error = "a factor could not be evaluated at the initial values (NaN or infinite residual or Jacobian)";
    return false;
  }
  compute_gradient();
  gradient_max_norm_ = compute_gradient_max_norm();
  summary_->jacobian_s += seconds_since(phase);
  return true;
}

StepQuality Engine::compute_step(double lambda, Eigen::VectorXd& step, double* predicted, TrustRegionIteration& it) {
  if (linearization_failed_) return StepQuality::kFailed;
  int cg_iterations = 0;
  bool inexact = false;
  const bool ok = solve_system(lambda, cg_iterations, &inexact);
  it.cg_iterations = cg_iterations;
  it.reused_factorization = inexact;
  summary_->cg_iterations += cg_iterations;
  if (!ok) return StepQuality::kFailed;
  double r_dot = 0.0;
  double squared = 0.0;
  jacobian_products(step_reduced_.data(), step_eliminated_.data(), &r_dot, &squared);
  *predicted = -r_dot - 0.5 * squared;
  join_step(step);
  // A PCG step on the last factorisation counts as exact: when it is rejected the radius shrinks
  // as for any other step (the engine's rule before the minimiser was shared). Retrying it from
  // a fresh factorisation with the same radius (StepQuality::kInexact, the pose graph's rule) cost
  // problem-318-41628 3 more iterations (17 instead of 14, 4.4 s instead of about 3.7 s).
  return StepQuality::kExact;
}

const Eigen::VectorXd& Engine::gradient() {
  gradient_joined_.resize(gradient_reduced_.size() + gradient_eliminated_.size());
  gradient_joined_.head(gradient_reduced_.size()) = gradient_reduced_;
  gradient_joined_.tail(gradient_eliminated_.size()) = gradient_eliminated_;
  return gradient_joined_;
}

double Engine::curvature(const Eigen::VectorXd& v) {
  double r_dot = 0.0;
  double squared = 0.0;
  jacobian_products(v.data(), v.data() + layout_.reduced_dim, &r_dot, &squared);
  return squared;
}

double Engine::model_decrease(const Eigen::VectorXd& step) {
  double r_dot = 0.0;
  double squared = 0.0;
  jacobian_products(step.data(), step.data() + layout_.reduced_dim, &r_dot, &squared);
  return -r_dot - 0.5 * squared;
}

bool Engine::evaluate_trial(const Eigen::VectorXd& step, double* cost, TrustRegionIteration& it) {
  split_step(step);
  save_values();
  apply_step();
  const auto phase = Clock::now();
  // The trial point's residuals go to their own buffer: a rejected step must leave the current
  // point's residuals (the next step's right-hand side) untouched.
  const bool with_jacobians = options_.jacobians_with_trial_cost;
  if (trial_residuals_.size() != residuals_.size()) trial_residuals_.assign(residuals_.size(), 0.0);
  if (with_jacobians && trial_jacobians_.size() != jacobians_.size()) trial_jacobians_.assign(jacobians_.size(), 0.0);
  const bool ok = evaluate(with_jacobians, *cost, trial_residuals_, with_jacobians ? trial_jacobians_ : jacobians_);
  const double seconds = seconds_since(phase);
  summary_->residual_s += seconds;
  it.linearize_s += seconds;
  return ok;
}

void Engine::accept_trial(double /*old_cost*/, double /*new_cost*/, bool final, TrustRegionIteration& it) {
  if (final) return;  // the values are in place; nothing is solved from here
  const auto phase = Clock::now();
  if (options_.jacobians_with_trial_cost) {
    std::swap(residuals_, trial_residuals_);
    std::swap(jacobians_, trial_jacobians_);
  } else {
    double relinearized = 0.0;
    linearization_failed_ = !evaluate(true, relinearized);
  }
  compute_gradient();
  gradient_max_norm_ = compute_gradient_max_norm();
  const double seconds = seconds_since(phase);
  summary_->jacobian_s += seconds;
  it.linearize_s += seconds;
}

void Engine::reject_trial(StepQuality /*quality*/) { restore_values(); }

VariableCovariances Engine::covariances(const std::vector<int>& variables) {
  VariableCovariances result;
  LeastSquaresSummary summary;
  summary_ = &summary;
  std::string error;
  if (!build_layout(&error)) {
    result.message = error;
    return result;
  }
  for (const int v : variables) {
    if (v < 0 || v >= static_cast<int>(problem_.variables.size())) {
      result.message = "no variable " + std::to_string(v);
      return result;
    }
  }
  choose_kernels();
  prepare();
  double cost = 0.0;
  if (!evaluate(true, cost)) {
    result.message = "a factor could not be evaluated at the current values";
    return result;
  }
  compute_gradient();
  // The undamped normal equations J^T J (radius infinite: no LM damping), factorised.
  int cg_iterations = 0;
  bool inexact = false;
  if (!solve_system(0.0, cg_iterations, &inexact) || !cholesky_.has_factor()) {
    result.message = "J^T J is singular at the current values (is the gauge fixed by a constant variable?)";
    return result;
  }
  std::vector<int> columns;
  for (const int v : variables) {
    const int block = layout_.block_of[v];
    if (block < 0) continue;
    const int size = problem_.variables[v].manifold->tangent_size();
    for (int i = 0; i < size; ++i) columns.push_back(layout_.reduced_offset[block] + i);
  }
  const Eigen::MatrixXd inverse = columns.empty() ? Eigen::MatrixXd() : cholesky_.inverse_columns(columns);
  int column = 0;
  for (const int v : variables) {
    const int size = problem_.variables[v].manifold->tangent_size();
    const int block = layout_.block_of[v];
    if (block < 0) {
      result.blocks.push_back(Eigen::MatrixXd::Zero(size, size));
      continue;
    }
    result.blocks.push_back(inverse.block(layout_.reduced_offset[block], column, size, size));
    column += size;
  }
  result.ok = true;
  return result;
}

}  // namespace

VariableCovariances marginal_covariances(LeastSquaresProblem& problem, const std::vector<int>& variables, int threads) {
  LeastSquaresOptions options;
  options.linear_solver = LinearSolverType::kSparseNormalCholesky;
  options.reuse_factorization = false;
  options.threads = threads;
  Engine engine(problem, options);
  return engine.covariances(variables);
}

LeastSquaresSummary solve(LeastSquaresProblem& problem, const LeastSquaresOptions& options) {
  Engine engine(problem, options);
  return engine.run();
}

bool schur_kernels_use_avx() {
#if defined(CAIRN_SCHUR_AVX)
  return kHaveAvx;
#else
  return false;
#endif
}

double evaluate_cost(const LeastSquaresProblem& problem) {
  const auto& impl = problem.impl();
  double cost = 0.0;
  std::vector<const double*> values;
  std::vector<double> residual;
  for (const FactorEntry& factor : impl.factors) {
    values.clear();
    for (const int v : factor.variables) values.push_back(impl.variables[v].values);
    residual.assign(factor.residual_size, 0.0);
    if (!factor.factor->evaluate(values.data(), residual.data(), nullptr)) return std::numeric_limits<double>::quiet_NaN();
    double squared = 0.0;
    for (const double value : residual) squared += value * value;
    cost += factor.loss.kernel == RobustKernel::kNone ? 0.5 * squared
                                                     : 0.5 * evaluate_kernel(factor.loss.kernel, factor.loss.scale, squared).rho;
  }
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace cairn::backend
