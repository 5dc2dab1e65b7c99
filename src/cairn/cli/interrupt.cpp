#include "cairn/cli/interrupt.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <iostream>

#include "cairn/io/output_file.hpp"

namespace cairn::cli {
namespace {

std::atomic<int> g_signal{0};
std::atomic<bool> g_stop_points{false};
pid_t g_main_thread = 0;  // kernel thread id of the main thread
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

extern "C" void on_signal(int signal) {
  // Handled on the main thread only (the one that commits outputs and blocks these signals
  // while it does): a worker thread (TBB, OpenMP, CHOLMOD) that receives it passes it on.
  // Only raw system calls here: all async-signal-safe.
  if (static_cast<pid_t>(::syscall(SYS_gettid)) != g_main_thread) {
    ::syscall(SYS_tgkill, ::getpid(), g_main_thread, signal);
    return;
  }
  if (g_signal.load() != 0 || !g_stop_points.load()) {
    // A second signal, or a command without safe points: stop now, leaving no temporary
    // behind, and end by the signal itself so the parent sees how the process ended.
    cairn::io::remove_unfinished_outputs();
    ::signal(signal, SIG_DFL);
    ::raise(signal);
    return;
  }
  g_signal.store(signal);
}

}  // namespace

void install_signal_handlers() {
  g_main_thread = static_cast<pid_t>(::syscall(SYS_gettid));
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads and writes carry on; the flag is polled at safe points
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  ::signal(SIGPIPE, SIG_IGN);
  ::signal(SIGXFSZ, SIG_IGN);
}

void use_stop_points() { g_stop_points.store(true); }
bool interrupted() { return g_signal.load() != 0; }
int interrupt_signal() { return g_signal.load(); }
const char* interrupt_signal_name() { return g_signal.load() == SIGTERM ? "SIGTERM" : "SIGINT"; }
int interrupted_exit_status() { return 128 + g_signal.load(); }
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
  // Messages now reach stderr through stdout's buffer: line by line, in order with stderr's own.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
}

}  // namespace cairn::cli
