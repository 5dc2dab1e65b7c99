#include "cairn/cli/interrupt.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <iostream>

#include "cairn/io/output_file.hpp"

namespace cairn::cli {
namespace {

volatile std::sig_atomic_t g_signal = 0;

extern "C" void on_signal(int signal) {
  if (g_signal != 0) {
    // Second signal: stop now, leaving no temporary behind, and end by the signal itself so the
    // parent sees how the process ended.
    cairn::io::remove_unfinished_outputs();
    ::signal(signal, SIG_DFL);
    ::raise(signal);
    return;
  }
  g_signal = signal;
}

}  // namespace

void install_signal_handlers() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads and writes carry on; the flag is polled at safe points
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  ::signal(SIGPIPE, SIG_IGN);
  ::signal(SIGXFSZ, SIG_IGN);
}

bool interrupted() { return g_signal != 0; }
int interrupt_signal() { return static_cast<int>(g_signal); }
int interrupted_exit_status() { return 128 + static_cast<int>(g_signal); }
std::function<bool()> stop_on_signal() {
  return [] { return interrupted(); };
}

void claim_standard_output(const std::string& path) {
  static bool claimed = false;
  if (claimed || !io::is_standard_output(path)) return;
  claimed = true;
  std::fflush(stdout);
  std::cout.flush();
  const int data = ::fcntl(1, F_DUPFD_CLOEXEC, 3);
  if (data < 0) return;  // standard output is closed: writing the data will report it
  if (::dup2(2, 1) < 0) {
    ::close(data);
    return;
  }
  io::set_standard_output(data);
}

}  // namespace cairn::cli
