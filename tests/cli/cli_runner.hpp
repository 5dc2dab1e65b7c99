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
