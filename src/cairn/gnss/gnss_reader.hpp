#pragma once
/// \file
/// GNSS fixes from files: a CSV with a header naming its columns (docs/formats.md, "GNSS fixes
/// (CSV)") and sensor_msgs/NavSatFix from a bag topic. Fixes without a position (status -1, or a
/// NaN latitude, longitude or altitude, as NavSatFix writes for "unknown") are dropped and
/// counted in a `GnssReadReport`; every other defect throws io::ParseError naming the file and
/// line (or the bag, topic and message), what was expected and what was found.

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/gnss/gnss_fix.hpp"

namespace cairn::gnss {

/// What a read kept, dropped and noticed. Nothing is skipped without being counted here.
struct GnssReadReport {
  std::size_t records = 0;              ///< data lines (CSV) or messages (bag) read
  std::size_t fixes = 0;                ///< fixes returned
  std::size_t dropped_no_fix = 0;       ///< status -1
  std::size_t dropped_not_finite = 0;   ///< NaN latitude, longitude or altitude
  /// Bag only: messages whose header stamp does not follow the previous kept fix's (a CSV with
  /// such a line is refused instead: it can be fixed, a recording cannot).
  std::size_t dropped_out_of_order = 0;
  std::size_t covariance_unknown = 0;   ///< kept fixes with covariance_known == false
  /// Bag only: kept fixes whose covariance was declared known (type 1-3) but has a non-finite or
  /// huge (> 1e14 m^2) entry or a zero or negative diagonal entry: kept as unknown covariance.
  std::size_t covariance_invalid = 0;
  std::string first_dropped;            ///< "file:line: why" of the first dropped record, or empty
  std::vector<std::string> warnings;    ///< for the CLI to print (unterminated last line, ...)
};

/// Reads the GNSS CSV at `path` ("-" = standard input). Throws io::ParseError on any defect:
/// no header, an unknown, repeated or missing column, a wrong field count, a number that is not
/// one, latitude / longitude / altitude out of range (is_valid_geodetic), a status other than
/// -1, 0, 1, 2, a standard deviation <= 0, a covariance that is not symmetric positive
/// semi-definite with a positive diagonal, a stamp not after the previous line's, no fix at all
/// kept is not an error (an empty vector, with the report saying why).
std::vector<GnssFix> read_gnss_csv(const std::string& path, GnssReadReport* report = nullptr);

/// Reads sensor_msgs/NavSatFix messages of `topic` in the bag at `bag_path` (any format
/// bag::Bag opens); an empty `topic` means the bag's only NavSatFix topic. Stamps are the
/// messages' header stamps. position_covariance_type 0 gives covariance_known = false; type 2
/// (diagonal known) keeps the diagonal only; types 1 and 3 keep the whole matrix. Throws
/// io::ParseError when the topic is missing or ambiguous, a message does not decode, or a
/// position is out of range.
std::vector<GnssFix> read_gnss_bag(const std::string& bag_path, const std::string& topic = "",
                                   GnssReadReport* report = nullptr);

}  // namespace cairn::gnss
