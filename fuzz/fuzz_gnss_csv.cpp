// libFuzzer entry point for the GNSS CSV reader (gnss/gnss_reader). Any input must end in fixes
// or a cairn::io::ParseError: another exception, a crash, a hang or a sanitizer report is a bug.
// What the reader accepts must hold its promises: stamps strictly increasing, positions on Earth
// (is_valid_geodetic), no no-fix status, a known covariance symmetric with a positive diagonal,
// the counts of the report adding up, and every fix finite in the ENU frame of the first. Run
// with `make fuzz` (clang); the corpus in fuzz/corpus/gnss_csv runs in `make test`.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>
#include <vector>

#include "cairn/gnss/gnss_reader.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

std::string scratch_path() {
  static const std::string path = [] {
    static const std::string p =
        (std::filesystem::temp_directory_path() / ("cairn_fuzz_gnss_csv_" + std::to_string(::getpid()) + ".csv")).string();
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove(p, ignored);
    });
    return p;
  }();
  return path;
}

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_gnss_csv: invariant broken: %s\n", what);
  std::abort();
}

void check_invariants(const std::vector<cairn::gnss::GnssFix>& fixes, const cairn::gnss::GnssReadReport& report) {
  check(report.fixes == fixes.size(), "the report counts the fixes returned");
  check(report.records == fixes.size() + report.dropped_no_fix + report.dropped_not_finite, "every record is kept or counted");
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    const cairn::gnss::GnssFix& fix = fixes[i];
    check(i == 0 || fixes[i - 1].stamp < fix.stamp, "stamps increase");
    check(cairn::gnss::is_valid_geodetic({fix.latitude_deg, fix.longitude_deg, fix.altitude_m}, nullptr), "position on Earth");
    check(fix.status >= cairn::gnss::kStatusFix && fix.status <= cairn::gnss::kStatusGbasFix, "status of a fix");
    if (fix.covariance_known) {
      check(fix.covariance_enu_m2.allFinite(), "finite covariance");
      check(fix.covariance_enu_m2.isApprox(fix.covariance_enu_m2.transpose(), 0.0), "symmetric covariance");
      check(fix.covariance_enu_m2.diagonal().minCoeff() > 0.0, "positive variances");
    }
  }
  if (fixes.empty()) return;
  const cairn::gnss::LocalFrame frame({fixes[0].latitude_deg, fixes[0].longitude_deg, fixes[0].altitude_m});
  for (const cairn::gnss::GnssFix& fix : fixes) check(frame.forward(fix).allFinite(), "finite ENU position");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = scratch_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) {
      std::fprintf(stderr, "fuzz_gnss_csv: cannot write scratch file %s\n", path.c_str());
      std::abort();
    }
  }
  cairn::gnss::GnssReadReport report;
  std::vector<cairn::gnss::GnssFix> fixes;
  try {
    fixes = cairn::gnss::read_gnss_csv(path, &report);
  } catch (const cairn::io::ParseError&) {
    return 0;  // expected for malformed input
  }
  check_invariants(fixes, report);
  return 0;
}
