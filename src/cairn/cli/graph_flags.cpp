#include "cairn/cli/commands.hpp"

#include <iostream>

namespace cairn::cli {

void GraphReadFlags::add_to(CLI::App& command) {
  command.add_flag("--strict", strict,
                   "Refuse the file on any indefinite information matrix and on "
                   "any unknown record type");
  command.add_option("--info-policy", info_policy,
                     "What to do with information matrices that are not positive definite: project "
                     "(to the nearest positive semi-definite matrix), keep, reject")
      ->check(CLI::IsMember({"project", "keep", "reject"}))
      ->capture_default_str();
  command.add_option("--toro-info-order", toro_info_order,
                     "Order of the six TORO EDGE2 information numbers: toro (Ixx Ixy Iyy Itt Ixt Iyt), "
                     "g2o (I11 I12 I13 I22 I23 I33), or auto (toro unless only g2o order gives valid "
                     "matrices)")
      ->check(CLI::IsMember({"auto", "toro", "g2o"}))
      ->capture_default_str();
}

io::GraphReadOptions GraphReadFlags::options() const {
  io::GraphReadOptions options;
  options.information_policy = info_policy == "keep"     ? io::InformationPolicy::kKeep
                               : info_policy == "reject" ? io::InformationPolicy::kReject
                                                         : io::InformationPolicy::kProject;
  if (strict) {
    options.information_policy = io::InformationPolicy::kReject;
    options.reject_unknown_records = true;
  }
  options.toro_information_order = toro_info_order == "toro"  ? io::ToroInformationOrder::kToro
                                   : toro_info_order == "g2o" ? io::ToroInformationOrder::kG2o
                                                              : io::ToroInformationOrder::kAuto;
  return options;
}

void warn(const std::string& text) { std::cerr << "cairn: warning: " << text << '\n'; }

}  // namespace cairn::cli
