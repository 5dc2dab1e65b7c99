#pragma once
/// \file
/// Running the `cairn` binary from a test: its exit status, standard output and standard error.
/// CAIRN_BINARY is the binary's path (a compile definition of each CLI test).

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace cairn::test {

struct CliResult {
  int status = -1;  // exit code, or -1 when killed by a signal
  std::string out;
  std::string err;
};

/// A scratch folder for one test program: temp / cairn_<name>_<pid>, created if missing.
inline std::filesystem::path scratch_folder(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("cairn_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

inline std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The comma-separated fields of every line of `file` (no quoting), '#' lines left out unless
/// `keep_comments`, empty lines always.
inline std::vector<std::vector<std::string>> csv_rows(const std::filesystem::path& file, bool keep_comments = true) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(slurp(file));
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || (!keep_comments && line[0] == '#')) continue;
    std::vector<std::string> fields;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) fields.push_back(cell);
    rows.push_back(fields);
  }
  return rows;
}

/// `path` in single quotes, for a shell command line.
inline std::string quoted(const std::filesystem::path& path) { return "'" + path.string() + "'"; }

/// Runs `binary args` through the shell, standard error going to `stderr_path`.
inline CliResult run_command(const std::string& binary, const std::string& args, const std::filesystem::path& stderr_path) {
  const std::string command = binary + " " + args + " 2>" + stderr_path.string();
  CliResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) result.out.append(buffer, n);
  const int status = ::pclose(pipe);
  result.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.err = slurp(stderr_path);
  return result;
}

}  // namespace cairn::test
