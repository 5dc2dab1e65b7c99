#pragma once
/// \file
/// Summary statistics of an error array, defined as evo does (evo/core/metrics.py,
/// PE.get_statistic / get_all_statistics):
///   rmse   = sqrt(mean(e^2))
///   mean   = mean(e)
///   median = numpy.median(e): the middle value, or the mean of the two middle values
///   std    = numpy.std(e) = sqrt(mean((e - mean)^2)): the POPULATION standard deviation
///            (divide by n, not n - 1)
///   min, max
///   sse    = sum(e^2)

#include <cstddef>
#include <span>

namespace cairn::eval {

struct Statistics {
  double rmse = 0;
  double mean = 0;
  double median = 0;
  double std = 0;
  double min = 0;
  double max = 0;
  double sse = 0;
  /// Number of errors summarised.
  std::size_t count = 0;
};

/// All statistics of `errors`. Sums use pairwise summation, as numpy's add.reduce does, so the
/// results agree with evo's to the last few bits. Precondition: errors non-empty (an empty
/// array has no statistics; every metric reports kEmpty/kNoPairs before calling this).
Statistics compute_statistics(std::span<const double> errors);

/// sum(values) by pairwise summation (numpy's scheme: blocks of 8 below 128 elements).
double pairwise_sum(std::span<const double> values);

}  // namespace cairn::eval
