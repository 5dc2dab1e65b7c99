#pragma once
/// \file
/// Orders of file names shared by the folder readers (image sequences, scan folders).

#include <string>

namespace cairn::io {

/// Natural order of names: runs of digits compare by value, everything else by bytes ("scan_9"
/// before "scan_10"; "01" after "1", so the order is total and deterministic).
bool natural_less(const std::string& a, const std::string& b);

}  // namespace cairn::io
