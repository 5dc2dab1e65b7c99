#pragma once
/// \file
/// Sparse Cholesky of a symmetric block-sparse matrix through SuiteSparse CHOLMOD: the symbolic
/// analysis (fill-reducing ordering, supernodes) runs once per sparsity pattern, the numeric
/// factorisation once per solver iteration, as in Ceres' SPARSE_NORMAL_CHOLESKY
/// (internal/ceres/suitesparse.cc) and g2o's LinearSolverCholmod.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace cairn::backend {

/// Upper triangle of a symmetric matrix in compressed-column form (CHOLMOD's stype = 1).
struct UpperCsc {
  int size = 0;
  std::vector<int> column_start;  ///< size + 1 entries
  std::vector<int> row;           ///< row of each stored value, sorted within a column
  std::vector<double> value;
};

/// Pattern of the normal equations H of a graph with `blocks` block variables of size
/// `block_size` and block couplings `pairs` (i, j), i != j, in any order (duplicates allowed).
/// `block_offset(c, r)` gives the position in `value` of scalar entry (r*B + 0, c*B + k) minus
/// column_start[c*B + k], for r <= c, so a block can be scattered without searching.
class BlockPattern {
 public:
  BlockPattern(int blocks, int block_size, const std::vector<std::pair<int, int>>& pairs);

  const UpperCsc& matrix() const { return csc_; }
  UpperCsc& matrix() { return csc_; }
  int block_size() const { return block_size_; }
  int blocks() const { return blocks_; }

  /// Adds the B x B block `M` at block (r, c), r < c (only the strictly upper block).
  void add_off_diagonal(int r, int c, const double* M_row_major_r_by_c);
  /// Adds the upper triangle of the symmetric B x B block `M` at (c, c).
  void add_diagonal(int c, const double* M_row_major);
  /// Same, from the upper triangle packed column by column: (0,0), (0,1), (1,1), (0,2), ...
  /// (B (B + 1) / 2 values).
  void add_diagonal_packed(int c, const double* upper_by_columns);
  void set_zero();
  /// Fill-reducing ordering of the block graph (AMD, Amestoy, Davis & Duff 1996), expanded to
  /// the scalar variables: a block's variables stay together, as Ceres orders its parameter
  /// blocks before CHOLMOD sees them.
  std::vector<int> block_amd_ordering() const;
  /// Index into value of the diagonal entry of scalar column k.
  int diagonal_index(int scalar_column) const { return csc_.column_start[scalar_column + 1] - 1; }

 private:
  int blocks_;
  int block_size_;
  UpperCsc csc_;
  /// For block column c: the off-diagonal block rows (sorted) and, via lookup, their rank.
  std::vector<std::vector<int>> column_block_rows_;
  int rank_of(int r, int c) const;
};

/// Fill-reducing relabelling of the blocks of a block graph with `blocks` blocks and couplings
/// `pairs` (as BlockPattern's): label[b] is the position at which block b is eliminated under
/// AMD on the block graph (Amestoy, Davis & Duff 1996). A BlockPattern built with the relabelled
/// pairs is already in elimination order, so SparseCholesky::analyze_in_stored_order() factorises
/// it without permuting it (see there).
std::vector<int> block_amd_labels(int blocks, const std::vector<std::pair<int, int>>& pairs);

/// A block_amd_labels result kept with a digest (64 bits) of the block graph it was computed
/// for, so that solves of one structure (the chordal initialisation and the optimiser, on the
/// same edges) order it once.
struct BlockOrderCache {
  std::uint64_t digest = 0;
  std::vector<int> label;
};

/// block_amd_labels through `cache`: computed only when the digest of (blocks, pairs in order)
/// differs from the cached one. A digest collision could only cost fill, never correctness: any
/// permutation of the blocks is a valid elimination order.
const std::vector<int>& block_amd_labels(int blocks, const std::vector<std::pair<int, int>>& pairs,
                                         BlockOrderCache& cache);

/// Renumbers blocks by `label` (block_amd_labels): each non-negative entry of `variable` (a
/// pose -> block map, -1 for fixed poses) and both blocks of every pair, so that a BlockPattern
/// of `pairs` is in elimination order.
void apply_block_labels(const std::vector<int>& label, std::vector<int>& variable,
                        std::vector<std::pair<int, int>>& pairs);

/// Limits the threads of the BLAS that CHOLMOD's supernodal factorisation calls, when that BLAS
/// is OpenBLAS (found at run time with dlsym; other BLAS libraries are left alone). Debian's
/// OpenBLAS starts one thread per core and its idle threads spin in sched_yield after each
/// call: with a single-threaded solve they took 37 % of the samples on the second core while
/// bundle-adjusting problem-16-22106 (perf, 2026-11-24). Process-wide. Returns false when no
/// OpenBLAS is loaded.
bool set_blas_threads(int threads);
/// OpenBLAS's current thread count, or 0 when no OpenBLAS is loaded.
int blas_threads();

/// set_blas_threads(threads) for its lifetime, then the caller's count again; threads <= 0 or
/// equal to the current count: nothing changes. For a solve asked to use `threads` threads
/// (OptimizerOptions::threads, LeastSquaresOptions::threads), so that `--threads 1` means one
/// core for CHOLMOD's BLAS too. Process-wide, like set_blas_threads.
class ScopedBlasThreads {
 public:
  explicit ScopedBlasThreads(int threads);
  ~ScopedBlasThreads();
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

 private:
  int restore_ = 0;  ///< the caller's count to restore, 0: nothing was changed
};

enum class FactorizationStatus { kSuccess, kNotPositiveDefinite, kFailure };

/// y = A x for a symmetric matrix stored as its upper triangle.
Eigen::VectorXd symmetric_multiply(const UpperCsc& A, const Eigen::VectorXd& x);
/// Same into `y` (resized; its storage reused when it has A's size already; not x itself).
void symmetric_multiply(const UpperCsc& A, const Eigen::VectorXd& x, Eigen::VectorXd& y);

/// Sparse Cholesky factorisation through CHOLMOD (supernodal, OpenBLAS for the dense blocks).
/// CHOLMOD's own OpenMP regions run on the calling thread (why: sparse_cholesky.cpp); the
/// caller's OpenMP setting (max-active-levels) is restored after every call.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// Always an LL^T factorisation (supernodal), so that factorize() reports
  /// kNotPositiveDefinite for every matrix that is not positive definite: CHOLMOD's simplicial
  /// LDL^T, which it picks for small or very sparse matrices, factorises indefinite ones too.
  /// For positive-definiteness tests (the certificate). Call before analyze().
  void require_ll();
  /// Symbolic analysis of the pattern of `A` (values ignored). Call again when the pattern changes.
  /// With `ordering` (a permutation of the scalar variables), CHOLMOD uses it as given;
  /// otherwise it chooses (AMD, and METIS when AMD fills in badly).
  void analyze(const UpperCsc& A, const std::vector<int>* ordering = nullptr);
  /// Symbolic analysis of `A` in the order it is stored (no fill-reducing permutation: the
  /// caller has built A in one, block_amd_labels). CHOLMOD then factorises A itself instead of
  /// a permuted copy PAP^T that it would assemble (two transposes per simplicial factorisation,
  /// cholmod_factorize.c) at every numeric factorisation.
  void analyze_in_stored_order(const UpperCsc& A);
  /// Numeric factorisation of A (same pattern as analyzed).
  FactorizationStatus factorize(const UpperCsc& A);
  /// Solves A x = b with the last successful factorisation.
  Eigen::VectorXd solve(const Eigen::VectorXd& b);
  /// Solves for several right-hand sides at once (columns of B).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& B);
  /// Columns `columns` of A^-1 (for marginal covariances), via solves with unit vectors.
  Eigen::MatrixXd inverse_columns(const std::vector<int>& columns);
  /// Solves A x = b into `x` (size n) reusing CHOLMOD's workspace between calls (cholmod_solve2),
  /// for iterative methods that solve with the same factor many times.
  void solve_in_place(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  /// Forward substitution for a sparse right-hand side: y = L^-1 b with A = L L^T, where b is
  /// non-zero only in the rows `rows` (b, of full length, is read only there). Only the rows of y
  /// that can be non-zero are computed, those reachable from `rows` in the elimination tree
  /// (Gilbert & Peierls 1988; CHOLMOD's cholmod_solve2 with Bset), and returned in `y_rows`; the
  /// result (full length, defined at y_rows only) lives until the next call. Then
  /// b^T A^-1 c = y_b^T y_c: selected entries of the inverse, such as J A^-1 J^T for a
  /// measurement Jacobian J, at the cost of a few elimination-tree paths instead of full solves.
  /// Needs analyze_in_stored_order(). The first call turns the factor into a simplicial LL^T
  /// (solve() still works; a later factorize() is then simplicial too).
  const double* solve_lower_sparse(const std::vector<int>& rows, const Eigen::VectorXd& b, std::vector<int>& y_rows);
  /// True when the last factorize() succeeded (solves are valid).
  bool has_factor() const;
  /// Non-zeros of the factor L (fill-in), after analyze.
  std::size_t factor_nonzeros() const;
  /// Floating-point operations of one numeric factorisation, after analyze (CHOLMOD's estimate).
  double factor_flops() const;
  /// Peak memory CHOLMOD reported, bytes.
  std::size_t peak_memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cairn::backend
