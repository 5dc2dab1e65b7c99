#include "cairn/backend/sparse_cholesky.hpp"

#include <dlfcn.h>

#include <amd.h>
#include <cholmod.h>
#include <omp.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "cairn/core/assert.hpp"

namespace cairn::backend {
namespace {

// CHOLMOD and AMD fail only for want of memory or when a factor outgrows their 32-bit indices (a
// problem too large for this machine, which a user's file can be): an error, not an assertion.
[[noreturn]] void resources_exhausted(const std::string& what, int status) {
  throw std::runtime_error(what + " failed (status " + std::to_string(status) +
                           "): out of memory, or the problem is too large for 32-bit sparse indices");
}

}  // namespace

BlockPattern::BlockPattern(int blocks, int block_size, const std::vector<std::pair<int, int>>& pairs)
    : blocks_(blocks), block_size_(block_size), column_block_rows_(static_cast<std::size_t>(blocks)) {
  for (const auto& [a, b] : pairs) {
    CAIRN_ASSERT(a != b && a >= 0 && b >= 0 && a < blocks && b < blocks, "block pair out of range");
    column_block_rows_[static_cast<std::size_t>(std::max(a, b))].push_back(std::min(a, b));
  }
  for (auto& rows : column_block_rows_) {
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  }
  const int B = block_size;
  csc_.size = blocks * B;
  csc_.column_start.assign(static_cast<std::size_t>(csc_.size) + 1, 0);
  for (int c = 0; c < blocks; ++c) {
    const int off = static_cast<int>(column_block_rows_[static_cast<std::size_t>(c)].size()) * B;
    for (int k = 0; k < B; ++k) {
      const int col = c * B + k;
      csc_.column_start[static_cast<std::size_t>(col) + 1] = csc_.column_start[static_cast<std::size_t>(col)] + off + k + 1;
    }
  }
  csc_.row.resize(static_cast<std::size_t>(csc_.column_start.back()));
  csc_.value.assign(csc_.row.size(), 0.0);
  for (int c = 0; c < blocks; ++c) {
    for (int k = 0; k < B; ++k) {
      int pos = csc_.column_start[static_cast<std::size_t>(c * B + k)];
      for (const int r : column_block_rows_[static_cast<std::size_t>(c)]) {
        for (int a = 0; a < B; ++a) csc_.row[static_cast<std::size_t>(pos++)] = r * B + a;
      }
      for (int a = 0; a <= k; ++a) csc_.row[static_cast<std::size_t>(pos++)] = c * B + a;
    }
  }
}

int BlockPattern::rank_of(int r, int c) const {
  const auto& rows = column_block_rows_[static_cast<std::size_t>(c)];
  const auto it = std::lower_bound(rows.begin(), rows.end(), r);
  CAIRN_ASSERT(it != rows.end() && *it == r, "block not in pattern");
  return static_cast<int>(it - rows.begin());
}

void BlockPattern::add_off_diagonal(int r, int c, const double* M) {
  const int B = block_size_;
  const int base = rank_of(r, c) * B;
  for (int k = 0; k < B; ++k) {
    double* column = csc_.value.data() + csc_.column_start[static_cast<std::size_t>(c * B + k)] + base;
    for (int a = 0; a < B; ++a) column[a] += M[a * B + k];
  }
}

void BlockPattern::add_diagonal(int c, const double* M) {
  const int B = block_size_;
  const int base = static_cast<int>(column_block_rows_[static_cast<std::size_t>(c)].size()) * B;
  for (int k = 0; k < B; ++k) {
    double* column = csc_.value.data() + csc_.column_start[static_cast<std::size_t>(c * B + k)] + base;
    for (int a = 0; a <= k; ++a) column[a] += M[a * B + k];
  }
}

void BlockPattern::add_diagonal_packed(int c, const double* upper) {
  const int B = block_size_;
  const int base = static_cast<int>(column_block_rows_[static_cast<std::size_t>(c)].size()) * B;
  for (int k = 0; k < B; ++k) {
    double* column = csc_.value.data() + csc_.column_start[static_cast<std::size_t>(c * B + k)] + base;
    for (int a = 0; a <= k; ++a) column[a] += *upper++;
  }
}

std::vector<int> BlockPattern::block_amd_ordering() const {
  // Upper-triangular block pattern (diagonal included) in compressed-column form.
  std::vector<int> start(static_cast<std::size_t>(blocks_) + 1, 0);
  std::vector<int> rows;
  for (int c = 0; c < blocks_; ++c) {
    for (const int r : column_block_rows_[static_cast<std::size_t>(c)]) rows.push_back(r);
    rows.push_back(c);
    start[static_cast<std::size_t>(c) + 1] = static_cast<int>(rows.size());
  }
  std::vector<int> block_order(static_cast<std::size_t>(blocks_));
  const int status = amd_order(blocks_, start.data(), rows.data(), block_order.data(), nullptr, nullptr);
  if (status != AMD_OK && status != AMD_OK_BUT_JUMBLED) resources_exhausted("AMD ordering", status);
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(blocks_ * block_size_));
  for (const int b : block_order) {
    for (int k = 0; k < block_size_; ++k) order.push_back(b * block_size_ + k);
  }
  return order;
}

std::vector<int> block_amd_labels(int blocks, const std::vector<std::pair<int, int>>& pairs) {
  std::vector<int> label(static_cast<std::size_t>(blocks));
  if (blocks == 0) return label;
  const std::vector<int> order = BlockPattern(blocks, 1, pairs).block_amd_ordering();
  for (int k = 0; k < blocks; ++k) label[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])] = k;
  return label;
}

const std::vector<int>& block_amd_labels(int blocks, const std::vector<std::pair<int, int>>& pairs,
                                         BlockOrderCache& cache) {
  // splitmix64's finaliser (Steele, Lea & Flood 2014) folded over the block count and the pairs.
  auto mix = [](std::uint64_t h, std::uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    h ^= h >> 30;
    h *= 0xbf58476d1ce4e5b9ULL;
    h ^= h >> 27;
    h *= 0x94d049bb133111ebULL;
    return h ^ (h >> 31);
  };
  std::uint64_t digest = mix(0, static_cast<std::uint64_t>(blocks));
  for (const auto& [a, b] : pairs) digest = mix(digest, (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b));
  if (digest != cache.digest || cache.label.size() != static_cast<std::size_t>(blocks)) {
    cache.label = block_amd_labels(blocks, pairs);
    cache.digest = digest;
  }
  return cache.label;
}

void apply_block_labels(const std::vector<int>& label, std::vector<int>& variable,
                        std::vector<std::pair<int, int>>& pairs) {
  for (int& v : variable) {
    if (v >= 0) v = label[static_cast<std::size_t>(v)];
  }
  for (auto& [a, b] : pairs) {
    a = label[static_cast<std::size_t>(a)];
    b = label[static_cast<std::size_t>(b)];
  }
}

void BlockPattern::set_zero() { std::fill(csc_.value.begin(), csc_.value.end(), 0.0); }

void symmetric_multiply(const UpperCsc& A, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  CAIRN_ASSERT(x.size() == A.size && &x != &y, "symmetric_multiply: x must have A's size and differ from y");
  y.setZero(A.size);
  const int* row = A.row.data();
  const double* value = A.value.data();
  for (int c = 0; c < A.size; ++c) {
    int p = A.column_start[static_cast<std::size_t>(c)];
    int end = A.column_start[static_cast<std::size_t>(c) + 1];
    const double xc = x[c];
    double yc = 0.0;
    // Rows are sorted, so a stored diagonal entry is the column's last: the loop over the strict
    // upper part needs no test per entry.
    if (end > p && row[end - 1] == c) {
      --end;
      yc = value[end] * xc;
    }
    for (; p < end; ++p) {
      const int r = row[p];
      y[r] += value[p] * xc;
      yc += value[p] * x[r];
    }
    y[c] += yc;
  }
}

Eigen::VectorXd symmetric_multiply(const UpperCsc& A, const Eigen::VectorXd& x) {
  Eigen::VectorXd y;
  symmetric_multiply(A, x, y);
  return y;
}

namespace {

// Debian 12's CHOLMOD (SuiteSparse 5.12) is compiled with OpenMP and opens parallel regions with a
// fixed team of CHOLMOD_OMP_NUM_THREADS = 4 threads (cholmod_core.h) around the supernodal
// factorisation's memory clears and assembly loops (t_cholmod_super_numeric.c, `if (n > 128)`),
// while the dense work of the same factorisation runs in OpenBLAS' own thread pool. On a machine
// with fewer than 4 + OpenBLAS' threads worth of cores the two pools preempt each other (spinning
// OpenMP workers against spinning OpenBLAS workers): on the 2-core machine of docs/benchmarks.md
// the numeric factorisation took 2.4x longer on sphere_bignoise and 1.9x on sphere2500 than with
// those regions serialised (OMP_MAX_ACTIVE_LEVELS=0; median of 30 solves, 2026-11-24). The
// loops they parallelise are memory-bound and short, so every CHOLMOD call here runs them on
// the calling thread: the max-active-levels ICV is 0 for the call and restored after it
// (OpenMP 5.1, "Determining the Number of Threads for a parallel Region": a region that would
// exceed max-active-levels active levels gets a team of one thread). GCC 12's libgomp keeps that
// setting per thread (checked: set to 0 in one std::thread, it stays 1 in main), so OpenMP
// regions in other threads are untouched.
// docs/backend.md, "Sparse Cholesky and threads".
class SerialOpenMpRegions {
 public:
  SerialOpenMpRegions() : saved_(omp_get_max_active_levels()) { omp_set_max_active_levels(0); }
  ~SerialOpenMpRegions() { omp_set_max_active_levels(saved_); }
  SerialOpenMpRegions(const SerialOpenMpRegions&) = delete;
  SerialOpenMpRegions& operator=(const SerialOpenMpRegions&) = delete;

 private:
  int saved_;
};

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  int size = 0;
  bool factorized = false;
  double flops = 0.0;
  // cholmod_solve2 workspace, kept between solves.
  cholmod_dense* solve_x = nullptr;
  cholmod_dense* solve_y = nullptr;
  cholmod_dense* solve_e = nullptr;
  cholmod_sparse* solve_xset = nullptr;  // solve_lower_sparse's reach

  Impl() {
    cholmod_start(&common);
    common.print = 0;  // library code never prints; failures come back as status
    common.supernodal = CHOLMOD_AUTO;
  }
  ~Impl() {
    cholmod_free_dense(&solve_x, &common);
    cholmod_free_dense(&solve_y, &common);
    cholmod_free_dense(&solve_e, &common);
    cholmod_free_sparse(&solve_xset, &common);
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  // A view of a vector as a one-column cholmod_dense (no copy).
  static cholmod_dense view(const Eigen::VectorXd& b) {
    cholmod_dense B{};
    B.nrow = static_cast<std::size_t>(b.size());
    B.ncol = 1;
    B.nzmax = B.nrow;
    B.d = B.nrow;
    B.x = const_cast<double*>(b.data());
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    return B;
  }

  // A view of our arrays as a cholmod_sparse (no copy).
  static cholmod_sparse view(const UpperCsc& A) {
    cholmod_sparse S{};
    S.nrow = static_cast<std::size_t>(A.size);
    S.ncol = static_cast<std::size_t>(A.size);
    S.nzmax = A.value.size();
    S.p = const_cast<int*>(A.column_start.data());
    S.i = const_cast<int*>(A.row.data());
    S.x = const_cast<double*>(A.value.data());
    S.stype = 1;
    S.itype = CHOLMOD_INT;
    S.xtype = CHOLMOD_REAL;
    S.dtype = CHOLMOD_DOUBLE;
    S.sorted = 1;
    S.packed = 1;
    return S;
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::analyze(const UpperCsc& A, const std::vector<int>* ordering) {
  const SerialOpenMpRegions serial;
  if (impl_->factor != nullptr) cholmod_free_factor(&impl_->factor, &impl_->common);
  cholmod_sparse S = Impl::view(A);
  if (ordering != nullptr) {
    CAIRN_ASSERT(static_cast<int>(ordering->size()) == A.size, "ordering must permute every variable");
    impl_->common.nmethods = 1;
    impl_->common.method[0].ordering = CHOLMOD_GIVEN;
    impl_->common.postorder = 1;
    impl_->factor = cholmod_analyze_p(&S, const_cast<int*>(ordering->data()), nullptr, 0, &impl_->common);
  } else {
    impl_->common.nmethods = 0;
    impl_->factor = cholmod_analyze(&S, &impl_->common);
  }
  impl_->size = A.size;
  impl_->factorized = false;
  if (impl_->factor == nullptr) resources_exhausted("CHOLMOD analysis", impl_->common.status);
  impl_->flops = impl_->common.fl;
}

void SparseCholesky::analyze_in_stored_order(const UpperCsc& A) {
  const SerialOpenMpRegions serial;
  if (impl_->factor != nullptr) cholmod_free_factor(&impl_->factor, &impl_->common);
  cholmod_sparse S = Impl::view(A);
  impl_->common.nmethods = 1;
  impl_->common.method[0].ordering = CHOLMOD_NATURAL;
  // No postorder: it would permute A again (cholmod_analyze.c turns a postordered natural
  // ordering into a permutation). AMD's order is already a postorder of its assembly tree.
  impl_->common.postorder = 0;
  impl_->factor = cholmod_analyze(&S, &impl_->common);
  impl_->common.postorder = 1;
  impl_->size = A.size;
  impl_->factorized = false;
  if (impl_->factor == nullptr) resources_exhausted("CHOLMOD analysis", impl_->common.status);
  impl_->flops = impl_->common.fl;
}

void SparseCholesky::require_ll() {
  impl_->common.supernodal = CHOLMOD_SUPERNODAL;
  impl_->common.final_ll = 1;
}

FactorizationStatus SparseCholesky::factorize(const UpperCsc& A) {
  const SerialOpenMpRegions serial;
  CAIRN_ASSERT(impl_->factor != nullptr && A.size == impl_->size, "factorize() before analyze()");
  cholmod_sparse S = Impl::view(A);
  const int ok = cholmod_factorize(&S, impl_->factor, &impl_->common);
  impl_->factorized = false;
  if (impl_->common.status == CHOLMOD_NOT_POSDEF || impl_->factor->minor < impl_->factor->n) {
    return FactorizationStatus::kNotPositiveDefinite;
  }
  if (ok == 0 || impl_->common.status != CHOLMOD_OK) return FactorizationStatus::kFailure;
  impl_->factorized = true;
  return FactorizationStatus::kSuccess;
}

Eigen::MatrixXd SparseCholesky::solve(const Eigen::MatrixXd& B) {
  const SerialOpenMpRegions serial;
  cholmod_dense* rhs = cholmod_allocate_dense(static_cast<std::size_t>(B.rows()), static_cast<std::size_t>(B.cols()),
                                              static_cast<std::size_t>(B.rows()), CHOLMOD_REAL, &impl_->common);
  if (rhs == nullptr) resources_exhausted("CHOLMOD's right-hand side", impl_->common.status);
  std::memcpy(rhs->x, B.data(), sizeof(double) * static_cast<std::size_t>(B.size()));
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, impl_->factor, rhs, &impl_->common);
  if (x == nullptr) resources_exhausted("CHOLMOD solve", impl_->common.status);
  Eigen::MatrixXd X(B.rows(), B.cols());
  std::memcpy(X.data(), x->x, sizeof(double) * static_cast<std::size_t>(X.size()));
  cholmod_free_dense(&x, &impl_->common);
  cholmod_free_dense(&rhs, &impl_->common);
  return X;
}

Eigen::VectorXd SparseCholesky::solve(const Eigen::VectorXd& b) {
  const Eigen::MatrixXd B = b;
  return solve(B).col(0);
}

Eigen::MatrixXd SparseCholesky::inverse_columns(const std::vector<int>& columns) {
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(impl_->size, static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) E(columns[k], static_cast<Eigen::Index>(k)) = 1.0;
  return solve(E);
}

void SparseCholesky::solve_in_place(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const SerialOpenMpRegions serial;
  CAIRN_ASSERT(impl_->factorized && b.size() == impl_->size, "solve_in_place() needs a factorisation of the right size");
  cholmod_dense B = Impl::view(b);
  const int ok = cholmod_solve2(CHOLMOD_A, impl_->factor, &B, nullptr, &impl_->solve_x, nullptr, &impl_->solve_y,
                                &impl_->solve_e, &impl_->common);
  if (ok == 0 || impl_->solve_x == nullptr) resources_exhausted("CHOLMOD solve", impl_->common.status);
  x.resize(b.size());
  std::memcpy(x.data(), impl_->solve_x->x, sizeof(double) * static_cast<std::size_t>(b.size()));
}

const double* SparseCholesky::solve_lower_sparse(const std::vector<int>& rows, const Eigen::VectorXd& b,
                                                 std::vector<int>& y_rows) {
  const SerialOpenMpRegions serial;
  CAIRN_ASSERT(impl_->factorized && b.size() == impl_->size, "solve_lower_sparse() needs a factorisation of the right size");
  cholmod_factor* L = impl_->factor;
  CAIRN_ASSERT(L->ordering == CHOLMOD_NATURAL, "solve_lower_sparse() needs analyze_in_stored_order()");
  for (const int row : rows) CAIRN_ASSERT(row >= 0 && row < impl_->size, "solve_lower_sparse(): row out of range");
  if (L->is_super || !L->is_ll) {
    // Bset solves run on a simplicial factor; LL^T so that L^-1 b needs no D.
    const int changed = cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/0, /*to_packed=*/1,
                                              /*to_monotonic=*/1, L, &impl_->common);
    if (changed == 0) resources_exhausted("CHOLMOD's conversion to a simplicial LL^T factor", impl_->common.status);
  }
  int set_start[2] = {0, static_cast<int>(rows.size())};
  cholmod_sparse Bset{};
  Bset.nrow = static_cast<std::size_t>(impl_->size);
  Bset.ncol = 1;
  Bset.nzmax = std::max<std::size_t>(rows.size(), 1);
  Bset.p = set_start;
  Bset.i = const_cast<int*>(rows.data());
  Bset.stype = 0;
  Bset.itype = CHOLMOD_INT;
  Bset.xtype = CHOLMOD_PATTERN;
  Bset.dtype = CHOLMOD_DOUBLE;
  Bset.sorted = 0;
  Bset.packed = 1;
  cholmod_dense B = Impl::view(b);
  const int ok = cholmod_solve2(CHOLMOD_L, L, &B, &Bset, &impl_->solve_x, &impl_->solve_xset, &impl_->solve_y,
                                &impl_->solve_e, &impl_->common);
  if (ok == 0 || impl_->solve_x == nullptr || impl_->solve_xset == nullptr) {
    resources_exhausted("CHOLMOD sparse solve", impl_->common.status);
  }
  const cholmod_sparse* X_set = impl_->solve_xset;
  const int* set_rows = static_cast<const int*>(X_set->i);
  y_rows.assign(set_rows, set_rows + static_cast<const int*>(X_set->p)[1]);
  return static_cast<const double*>(impl_->solve_x->x);
}

bool SparseCholesky::has_factor() const { return impl_->factorized; }

double SparseCholesky::factor_flops() const { return impl_->flops; }

std::size_t SparseCholesky::factor_nonzeros() const {
  return impl_->factor == nullptr ? 0 : static_cast<std::size_t>(impl_->common.lnz);
}

std::size_t SparseCholesky::peak_memory_bytes() const { return impl_->common.memory_usage; }

int blas_threads() {
  using GetThreads = int (*)();
  static const auto get = reinterpret_cast<GetThreads>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get == nullptr ? 0 : get();
}

bool set_blas_threads(int threads) {
  using SetThreads = void (*)(int);
  static const auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (set == nullptr) return false;
  set(threads > 0 ? threads : 1);
  return true;
}

ScopedBlasThreads::ScopedBlasThreads(int threads) {
  const int current = blas_threads();
  if (threads <= 0 || current <= 0 || current == threads) return;
  if (set_blas_threads(threads)) restore_ = current;
}

ScopedBlasThreads::~ScopedBlasThreads() {
  if (restore_ > 0) set_blas_threads(restore_);
}

}  // namespace cairn::backend
