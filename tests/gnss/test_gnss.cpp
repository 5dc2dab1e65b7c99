// Tests of cairn::gnss: the local ENU frame against a hand-written ECEF -> ENU computation, the
// CSV and bag readers (strictness, drops counted, the real Husky bag against python3-rosbag's
// count), the position factor's Jacobians against numeric ones, the chi-square(3) gate against
// published quantiles, the outlier and dropout report, and the yaw alignment on synthetic data.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/gnss/gnss_factor.hpp"
#include "cairn/gnss/gnss_outliers.hpp"
#include "cairn/gnss/gnss_reader.hpp"
#include "cairn/gnss/gnss_yaw.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::gnss {
namespace {

constexpr double kPi = 3.14159265358979323846;

// WGS84 geodetic -> ECEF, written out here independently of GeographicLib (NIMA TR8350.2,
// eq. 4-14/4-15: a = 6378137 m, 1/f = 298.257223563, N = a / sqrt(1 - e^2 sin^2 lat)).
Vector3 ecef(double lat_deg, double lon_deg, double h_m) {
  const double a = 6378137.0;
  const double f = 1.0 / 298.257223563;
  const double e2 = f * (2.0 - f);
  const double lat = lat_deg * kPi / 180.0;
  const double lon = lon_deg * kPi / 180.0;
  const double n = a / std::sqrt(1.0 - e2 * std::sin(lat) * std::sin(lat));
  return {(n + h_m) * std::cos(lat) * std::cos(lon), (n + h_m) * std::cos(lat) * std::sin(lon),
          (n * (1.0 - e2) + h_m) * std::sin(lat)};
}

// ECEF -> ENU at an origin: the rows of R are east, north, up in ECEF.
Vector3 enu_by_hand(double lat0_deg, double lon0_deg, double h0_m, double lat_deg, double lon_deg, double h_m) {
  const double lat0 = lat0_deg * kPi / 180.0;
  const double lon0 = lon0_deg * kPi / 180.0;
  Matrix3 R;
  R << -std::sin(lon0), std::cos(lon0), 0.0,
       -std::sin(lat0) * std::cos(lon0), -std::sin(lat0) * std::sin(lon0), std::cos(lat0),
       std::cos(lat0) * std::cos(lon0), std::cos(lat0) * std::sin(lon0), std::sin(lat0);
  return R * (ecef(lat_deg, lon_deg, h_m) - ecef(lat0_deg, lon0_deg, h0_m));
}

TEST(LocalFrame, MatchesHandWrittenEcefToEnu) {
  struct Case { double lat0, lon0, h0, lat, lon, h; };
  const std::vector<Case> cases = {
      {42.375812, -71.14739466666667, 7.3, 42.376, -71.147, 2.0},   // the Husky bag's first fix, ~50 m away
      {47.3769, 8.5417, 408.0, 47.4, 8.6, 500.0},                   // Zurich, ~5 km
      {-33.8688, 151.2093, 20.0, -33.9, 151.1, -10.0},              // Sydney, southern hemisphere, ~11 km
      {0.0, 179.99, 0.0, 0.01, -179.99, 100.0},                     // across the antimeridian
      {89.9, 45.0, 0.0, 89.9, -135.0, 0.0},                         // across the pole
  };
  for (const Case& c : cases) {
    const LocalFrame frame({c.lat0, c.lon0, c.h0});
    const Vector3 expected = enu_by_hand(c.lat0, c.lon0, c.h0, c.lat, c.lon, c.h);
    const Vector3 got = frame.forward(GeodeticPosition{c.lat, c.lon, c.h});
    EXPECT_LT((got - expected).norm(), 1e-6) << "at " << c.lat << ", " << c.lon << ": " << got.transpose() << " vs "
                                             << expected.transpose();
    const GeodeticPosition back = frame.reverse(got);
    EXPECT_NEAR(back.latitude_deg, c.lat, 1e-10);
    EXPECT_NEAR(std::remainder(back.longitude_deg - c.lon, 360.0), 0.0, 1e-10);
    EXPECT_NEAR(back.altitude_m, c.h, 1e-6);
  }
  // The origin itself is (0, 0, 0); 1e-5 deg of latitude at 47 N is 1.1119 km / 100 (the meridian arc).
  const LocalFrame zurich({47.3769, 8.5417, 408.0});
  EXPECT_LT(zurich.forward(GeodeticPosition{47.3769, 8.5417, 408.0}).norm(), 1e-9);
}

TEST(LocalFrame, OriginIsTheFirstValidFix) {
  EXPECT_FALSE(LocalFrame::at_first_fix({}).has_value());
  GnssFix no_fix;
  no_fix.status = kStatusNoFix;
  no_fix.latitude_deg = 10.0;
  GnssFix good;
  good.latitude_deg = 20.0;
  good.longitude_deg = 30.0;
  const auto frame = LocalFrame::at_first_fix({no_fix, good});
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->origin().latitude_deg, 20.0);
  std::string why;
  EXPECT_FALSE(is_valid_geodetic({91.0, 0.0, 0.0}, &why));
  EXPECT_NE(why.find("latitude"), std::string::npos);
}

// ---- CSV reader ----

std::string write_file(const std::string& name, const std::string& text) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / ("cairn_test_gnss_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

TEST(GnssCsv, ReadsColumnsInAnyOrderAndCountsDrops) {
  const std::string path = write_file("valid.csv",
                                      "# a comment\n"
                                      "status, alt_m, lat_deg, lon_deg, time_s, std_north_m, std_east_m, std_up_m\n"
                                      "1, 7.3, 42.375812, -71.147394, 1432235498.039089918, 0.9, 0.8, 1.8\n"
                                      "-1, 7.3, 42.375812, -71.147394, 1432235498.4, 0.9, 0.8, 1.8\n"
                                      "\n"
                                      "0, nan, 42.375812, -71.147394, 1432235498.8, 0.9, 0.8, 1.8\n"
                                      "2, -5.5, 42.3759, -71.1474, 1432235499.2, 0.1, 0.2, 0.3\n");
  GnssReadReport report;
  const std::vector<GnssFix> fixes = read_gnss_csv(path, &report);
  ASSERT_EQ(fixes.size(), 2u);
  EXPECT_EQ(report.records, 4u);
  EXPECT_EQ(report.fixes, 2u);
  EXPECT_EQ(report.dropped_no_fix, 1u);
  EXPECT_EQ(report.dropped_not_finite, 1u);
  EXPECT_NE(report.first_dropped.find("valid.csv:4: status -1"), std::string::npos) << report.first_dropped;
  EXPECT_EQ(fixes[0].stamp.nanoseconds(), 1432235498039089918);
  EXPECT_EQ(fixes[0].status, 1);
  EXPECT_DOUBLE_EQ(fixes[0].latitude_deg, 42.375812);
  EXPECT_DOUBLE_EQ(fixes[0].altitude_m, 7.3);
  EXPECT_TRUE(fixes[0].covariance_known);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(0, 0), 0.8 * 0.8);  // east
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(1, 1), 0.9 * 0.9);  // north
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(2, 2), 1.8 * 1.8);
  EXPECT_EQ(fixes[1].status, 2);
}

TEST(GnssCsv, CovarianceColumnsAndNanosecondsAndNoCovariance) {
  const std::string with_cov = write_file("cov.csv",
                                          "time_ns,lat_deg,lon_deg,alt_m,cov_ee_m2,cov_en_m2,cov_eu_m2,cov_nn_m2,cov_nu_m2,cov_uu_m2\n"
                                          "100,1.0,2.0,3.0,4.0,0.5,0.1,2.0,0.2,9.0\n");
  const std::vector<GnssFix> fixes = read_gnss_csv(with_cov);
  ASSERT_EQ(fixes.size(), 1u);
  EXPECT_EQ(fixes[0].stamp.nanoseconds(), 100);
  EXPECT_EQ(fixes[0].status, kStatusFix);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(1, 0), 0.5);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(2, 1), 0.2);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(2, 2), 9.0);
  GnssReadReport report;
  const std::vector<GnssFix> plain = read_gnss_csv(write_file("plain.csv", "time_s,lat_deg,lon_deg,alt_m\n1,1,2,3\n2,1,2,3"), &report);
  ASSERT_EQ(plain.size(), 2u);
  EXPECT_FALSE(plain[0].covariance_known);
  EXPECT_EQ(report.covariance_unknown, 2u);
  EXPECT_EQ(report.warnings.size(), 1u);  // unterminated last line
}

// Every defect throws a ParseError naming file:line, what was expected and what was found.
TEST(GnssCsv, RefusesBadInputNamingTheLine) {
  struct Case { std::string name, text, line, words; };
  const std::string header = "time_s,lat_deg,lon_deg,alt_m\n";
  const std::vector<Case> cases = {
      {"empty", "", ": ", "file is empty"},  // line 0: the whole file
      {"unknown_column", "time_s,lat_deg,lon_deg,alt_m,speed\n", ":1:", "found 'speed'"},
      {"repeated_column", "time_s,lat_deg,lat_deg,alt_m\n", ":1:", "twice"},
      {"no_time", "lat_deg,lon_deg,alt_m\n", ":1:", "neither"},
      {"two_times", "time_s,time_ns,lat_deg,lon_deg,alt_m\n", ":1:", "both"},
      {"missing_alt", "time_s,lat_deg,lon_deg\n", ":1:", "alt_m"},
      {"partial_std", "time_s,lat_deg,lon_deg,alt_m,std_east_m\n", ":1:", "only some"},
      {"fields", header + "1,2,3\n", ":2:", "expected 4 comma-separated fields"},
      {"not_number", header + "1,abc,3,4\n", ":2:", "lat_deg"},
      {"infinite", header + "1,2,inf,4\n", ":2:", "lon_deg"},
      {"latitude_range", header + "1,95,3,4\n", ":2:", "latitude"},
      {"longitude_range", header + "1,45,-181,4\n", ":2:", "longitude"},
      {"time", header + "1x,45,3,4\n", ":2:", "time_s"},
      {"order", header + "2,45,3,4\n2,45,3,4\n", ":3:", "after the previous"},
      {"order_of_dropped", header + "2,45,3,4\n1,nan,3,4\n", ":3:", "after the previous"},
      {"status", "time_s,lat_deg,lon_deg,alt_m,status\n1,45,3,4,3\n", ":2:", "status"},
      {"sigma", "time_s,lat_deg,lon_deg,alt_m,std_east_m,std_north_m,std_up_m\n1,45,3,4,1,0,1\n", ":2:", "standard deviation in (0, 1e7]"},
      {"covariance", "time_s,lat_deg,lon_deg,alt_m,cov_ee_m2,cov_en_m2,cov_eu_m2,cov_nn_m2,cov_nu_m2,cov_uu_m2\n"
                     "1,45,3,4,1,5,0,1,0,1\n", ":2:", "positive semi-definite"},
      {"binary", std::string("time_s,lat_deg\0,lon", 19) + "\n", ":1:", ""},
  };
  for (const Case& c : cases) {
    const std::string path = write_file("bad_" + c.name + ".csv", c.text);
    try {
      read_gnss_csv(path);
      ADD_FAILURE() << c.name << ": accepted";
    } catch (const io::ParseError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path + c.line), std::string::npos) << c.name << ": " << what;
      EXPECT_NE(what.find(c.words), std::string::npos) << c.name << ": " << what;
    }
  }
  EXPECT_THROW(read_gnss_csv("/nonexistent/cairn/gnss.csv"), io::ParseError);
}

// ---- the real Husky bag ----

TEST(GnssBag, ReadsEveryFixOfTheHuskyBag) {
  CAIRN_REQUIRE_DATA("bags/robot_localization_test1.bag");
  const std::string path = test::data_path("bags/robot_localization_test1.bag").string();
  GnssReadReport report;
  const std::vector<GnssFix> fixes = read_gnss_bag(path, "", &report);
  // 989 messages on /fix, counted independently with python3-rosbag:
  //   /usr/bin/python3 -c "import rosbag; print(sum(1 for _ in rosbag.Bag('robot_localization_test1.bag')
  //                        .read_messages(topics=['/fix'])))"  -> 989
  // The same script saw status 1 and position_covariance_type 1 on all of them, strictly increasing
  // header stamps, no NaN, and the first message: stamp 1432235498.039089918, latitude 42.375812,
  // longitude -71.14739466666667, altitude 7.299999999999997, covariance diag(0.81, 0.81, 3.24).
  EXPECT_EQ(report.records, 989u);
  ASSERT_EQ(fixes.size(), 989u);
  EXPECT_EQ(report.dropped_no_fix + report.dropped_not_finite + report.dropped_out_of_order, 0u);
  EXPECT_EQ(report.covariance_unknown, 0u);
  EXPECT_EQ(fixes[0].stamp.nanoseconds(), 1432235498039089918);
  EXPECT_EQ(fixes[0].status, kStatusSbasFix);
  EXPECT_DOUBLE_EQ(fixes[0].latitude_deg, 42.375812);
  EXPECT_DOUBLE_EQ(fixes[0].longitude_deg, -71.14739466666667);
  EXPECT_DOUBLE_EQ(fixes[0].altitude_m, 7.299999999999997);
  EXPECT_TRUE(fixes[0].covariance_known);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(0, 0), 0.81);
  EXPECT_DOUBLE_EQ(fixes[0].covariance_enu_m2(2, 2), 3.24);
  EXPECT_THROW(read_gnss_bag(path, "/imu/data"), io::ParseError);  // a topic of another type
}

// ---- the factor ----

core::SE3 random_pose(std::mt19937_64& rng, double translation_m) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  const Vector3 axis = Vector3(normal(rng), normal(rng), normal(rng)).normalized();
  return core::SE3(core::SO3::exp(angle(rng) * axis),
                   translation_m * Vector3(normal(rng), normal(rng), normal(rng)));
}

TEST(GnssFactor, AnalyticJacobiansMatchNumericOnes) {
  std::mt19937_64 rng(38);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> sigma(0.05, 5.0);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    const core::SE3 T_world_body = random_pose(rng, 100.0);
    const core::SE3 T_enu_world = trial % 2 == 0 ? core::SE3() : random_pose(rng, 1000.0);
    const Vector3 lever(normal(rng), normal(rng), normal(rng));
    const Eigen::Matrix3d A = Eigen::Matrix3d::NullaryExpr([&]() { return normal(rng); });
    const Matrix3 covariance = A * A.transpose() * sigma(rng) + 0.01 * Matrix3::Identity();
    const GnssPositionFactor factor(100.0 * Vector3(normal(rng), normal(rng), normal(rng)), covariance, lever, T_enu_world);
    std::array<double, 7> x{};
    backend::se3_to_values(T_world_body, x.data());
    const double* values[] = {x.data()};
    Vector3 r;
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J;
    double* jacobians[] = {J.data()};
    ASSERT_TRUE(factor.evaluate(values, r.data(), jacobians));
    Eigen::Matrix<double, 3, 6> numeric;
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      std::array<double, 6> delta{};
      std::array<double, 7> plus{}, minus{};
      delta[k] = h;
      backend::se3_manifold().plus(x.data(), delta.data(), plus.data());
      delta[k] = -h;
      backend::se3_manifold().plus(x.data(), delta.data(), minus.data());
      Vector3 r_plus, r_minus;
      const double* vp[] = {plus.data()};
      const double* vm[] = {minus.data()};
      factor.evaluate(vp, r_plus.data(), nullptr);
      factor.evaluate(vm, r_minus.data(), nullptr);
      numeric.col(k) = (r_plus - r_minus) / (2.0 * h);
    }
    worst = std::max(worst, (J - numeric).cwiseAbs().maxCoeff() / std::max(1.0, J.cwiseAbs().maxCoeff()));
    // The whitening: ||r||^2 = e^T Sigma^-1 e.
    const Vector3 e = factor.error_enu_m(T_world_body);
    EXPECT_NEAR(r.squaredNorm(), e.dot(covariance.inverse() * e), 1e-8 * std::max(1.0, r.squaredNorm()));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST(GnssFactor, CovarianceDefaultsAndFloor) {
  GnssFactorOptions options;
  GnssFix fix;
  Matrix3 c = factor_covariance_enu(fix, options);
  EXPECT_NEAR(c(0, 0), 2.5 * 2.5, 1e-12);
  EXPECT_NEAR(c(2, 2), 5.0 * 5.0, 1e-12);
  fix.covariance_known = true;
  fix.covariance_enu_m2 = Matrix3::Zero();
  fix.covariance_enu_m2(0, 0) = 4.0;
  c = factor_covariance_enu(fix, options);
  EXPECT_NEAR(c(0, 0), 4.0, 1e-12);
  EXPECT_NEAR(c(1, 1), 1e-4, 1e-15);  // floored at min_sigma_m^2
  std::string why;
  options.min_sigma_m = 0.0;
  options.default_sigma_vertical_m = -1.0;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_NE(why.find("min_sigma_m"), std::string::npos);
  EXPECT_NE(why.find("default_sigma_vertical_m"), std::string::npos);
}

// 60 fixes of a still antenna, 6 of them jumps of 10-50 m: least squares is dragged off, the
// recommended Cauchy kernel is not.
TEST(GnssFactor, CauchyKernelIgnoresJumps) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  const core::SE3 truth(core::SO3::exp(Vector3(0.1, -0.2, 0.7)), Vector3(12.0, -3.0, 1.5));
  const Vector3 lever(0.3, 0.0, 0.8);
  const Vector3 antenna = truth * lever;
  const double sigma_m = 0.5;
  std::vector<Vector3> measured;
  for (int i = 0; i < 60; ++i) {
    Vector3 p = antenna + sigma_m * Vector3(normal(rng), normal(rng), normal(rng));
    if (i % 10 == 3) p += (10.0 + 40.0 * (i / 60.0)) * Vector3(normal(rng), normal(rng), 0.3 * normal(rng)).normalized();
    measured.push_back(p);
  }
  const auto solve_with = [&](backend::FactorLoss loss) {
    std::array<double, 7> x{};
    backend::se3_to_values(core::SE3(truth.so3(), truth.translation() + Vector3(3.0, -2.0, 1.0)), x.data());
    backend::LeastSquaresProblem problem;
    const int pose = problem.add_variable(x.data(), backend::se3_manifold());
    for (const Vector3& p : measured) {
      problem.add_factor(std::make_unique<GnssPositionFactor>(p, sigma_m * sigma_m * Matrix3::Identity(), lever), {pose}, loss);
    }
    backend::LeastSquaresOptions options;
    options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
    options.threads = 1;
    backend::solve(problem, options);
    return (backend::se3_from_values(x.data()) * lever - antenna).norm();
  };
  const double plain_m = solve_with({});
  const double cauchy_m = solve_with(GnssFactorOptions{}.loss);
  EXPECT_GT(plain_m, 1.0);
  EXPECT_LT(cauchy_m, 0.3);
}

// ---- chi-square gate, outliers, dropouts ----

TEST(GnssOutliers, ChiSquareThreeMatchesPublishedValues) {
  // Quantiles of chi^2(3) from NIST/SEMATECH e-Handbook of Statistical Methods, table 1.3.6.7.4
  // (upper critical values: 7.815 at 0.05, 11.345 at 0.01, 16.266 at 0.001); more digits from R's
  // qchisq(c(.95, .99, .999), 3) = 7.814728 11.344867 16.266236 and pchisq(3, 3) = 0.6083748.
  EXPECT_NEAR(chi_square_3_quantile(0.95), 7.814728, 1e-6);
  EXPECT_NEAR(chi_square_3_quantile(0.99), 11.344867, 1e-6);
  EXPECT_NEAR(chi_square_3_quantile(0.999), 16.266236, 1e-6);
  EXPECT_NEAR(chi_square_3_cdf(3.0), 0.6083748, 1e-7);
  EXPECT_EQ(chi_square_3_cdf(0.0), 0.0);
  for (const double p : {1e-6, 0.1, 0.5, 0.9, 0.999999}) EXPECT_NEAR(chi_square_3_cdf(chi_square_3_quantile(p)), p, 1e-12);
}

TEST(GnssOutliers, FlagsJumpsAndListsDropouts) {
  const LocalFrame frame({47.0, 8.0, 400.0});
  GnssFactorOptions factor_options;
  std::vector<GnssFix> fixes;
  std::vector<core::SE3> poses;
  // Fixes at 1 Hz for 0..9 s and 70..79 s (a 61 s gap), the body walking east; fix 4 is 5 sigma off
  // north (25 > 16.27), fix 12 is 3 sigma off up (9 < 16.27).
  for (int i = 0; i < 20; ++i) {
    const double t_s = i < 10 ? i : 60.0 + i;
    const core::SE3 pose(core::SO3(), Vector3(t_s, 0.0, 0.0));
    Vector3 p_enu = pose.translation();
    if (i == 4) p_enu.y() += 5.0 * 2.5;
    if (i == 12) p_enu.z() += 3.0 * 5.0;
    const GeodeticPosition position = frame.reverse(p_enu);
    GnssFix fix;
    fix.stamp = core::Timestamp::from_seconds(100.0 + t_s);
    fix.latitude_deg = position.latitude_deg;
    fix.longitude_deg = position.longitude_deg;
    fix.altitude_m = position.altitude_m;
    fixes.push_back(fix);
    poses.push_back(pose);
  }
  const GnssOutlierReport report = gnss_outlier_report(fixes, poses, frame, factor_options, GnssOutlierOptions{});
  EXPECT_NEAR(report.threshold, 16.266236, 1e-6);
  EXPECT_EQ(report.outliers, 1u);
  EXPECT_TRUE(report.fixes[4].outlier);
  EXPECT_NEAR(report.fixes[4].squared_mahalanobis, 25.0, 1e-6);
  EXPECT_NEAR(report.fixes[4].error_m, 12.5, 1e-6);
  EXPECT_FALSE(report.fixes[12].outlier);
  EXPECT_NEAR(report.fixes[12].squared_mahalanobis, 9.0, 1e-6);
  ASSERT_EQ(report.dropouts.size(), 1u);
  EXPECT_EQ(report.dropouts[0].start.nanoseconds(), core::Timestamp::from_seconds(109.0).nanoseconds());
  EXPECT_NEAR(report.dropouts[0].duration_s, 61.0, 1e-9);
}

// ---- yaw alignment ----

struct YawData {
  std::vector<Vector3> p_world, p_enu;
};

// An S-shaped odometry path of `length_m`, mapped into ENU by yaw and t, with noise and jumps.
YawData yaw_data(double length_m, double yaw_rad, const Vector3& t, double sigma_m, int jump_every, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Matrix3 R = core::SO3::exp(Vector3(0.0, 0.0, yaw_rad)).matrix();
  YawData data;
  for (int i = 0; i < 100; ++i) {
    const double s = length_m * i / 99.0;
    const Vector3 p(s, 0.1 * length_m * std::sin(s / length_m * 2.0 * kPi), 0.01 * s);
    Vector3 q = R * p + t + sigma_m * Vector3(normal(rng), normal(rng), normal(rng));
    if (jump_every > 0 && i % jump_every == 7) q += Vector3(30.0, -20.0, 5.0);
    data.p_world.push_back(p);
    data.p_enu.push_back(q);
  }
  return data;
}

TEST(GnssYaw, RecoversYawAndTranslationExactly) {
  const Vector3 t(100.0, -50.0, 3.0);
  const YawData data = yaw_data(80.0, 2.5, t, 0.0, 0, 1);
  const YawAlignment a = align_world_to_enu(data.p_world, data.p_enu);
  ASSERT_TRUE(a.ok()) << a.message;
  EXPECT_NEAR(a.yaw_rad, 2.5, 1e-12);
  EXPECT_LT((a.T_enu_world.translation() - t).norm(), 1e-9);
  EXPECT_EQ(a.pairs_rejected, 0u);
}

TEST(GnssYaw, NoiseAndJumpsWithinThePredictedSigma) {
  const Vector3 t(100.0, -50.0, 3.0);
  const YawData data = yaw_data(80.0, -1.2, t, 1.0, 20, 2);  // 5 jumps of 36 m among 100
  const YawAlignment a = align_world_to_enu(data.p_world, data.p_enu);
  ASSERT_TRUE(a.ok()) << a.message;
  EXPECT_EQ(a.pairs_rejected, 5u);
  EXPECT_LT(std::abs(a.yaw_rad + 1.2), 4.0 * a.yaw_sigma_rad);
  EXPECT_LT(a.yaw_sigma_rad, 0.01);  // ~1 m noise over 100 fixes spread ~25 m RMS
  EXPECT_LT((a.T_enu_world.translation() - t).head<2>().norm(), 0.5);
}

TEST(GnssYaw, RefusesUntilTheRobotHasMoved) {
  const YawData data = yaw_data(5.0, 0.3, Vector3::Zero(), 0.5, 0, 3);  // 5 m: ~1.5 m RMS spread
  const YawAlignment a = align_world_to_enu(data.p_world, data.p_enu);
  EXPECT_EQ(a.status, YawAlignmentStatus::kTooLittleMotion);
  EXPECT_NE(a.message.find("not yet observable"), std::string::npos);
  const YawAlignment few = align_world_to_enu({Vector3::Zero()}, {Vector3::Zero()});
  EXPECT_EQ(few.status, YawAlignmentStatus::kTooFewPairs);
}

}  // namespace
}  // namespace cairn::gnss
