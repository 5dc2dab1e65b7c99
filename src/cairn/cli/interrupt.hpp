#pragma once
/// \file
/// SIGINT and SIGTERM for the `cairn` binary (docs/conventions.md, "Interrupted runs"). The first
/// signal only raises a flag: long commands poll interrupted() at their safe points (between
/// scans, between solver iterations), stop there, write what they have as a complete result
/// marked `interrupted` and exit with 128 + the signal (130 for SIGINT, 143 for SIGTERM). A
/// second signal stops at once: the temporaries of unfinished outputs are removed and the
/// process ends by the signal, so no half-written file is ever left at an output path.

#include <cstdio>
#include <functional>
#include <string>

namespace cairn::cli {

/// Installs the handlers, and ignores SIGPIPE and SIGXFSZ so that a closed pipe or a file-size
/// limit surfaces as a write error (EPIPE, EFBIG) naming the output, not as a silent death.
void install_signal_handlers();

/// Called by the commands that poll interrupted() (slam2d, optimize, landmarks): without it the
/// first signal ends the process at once, as the second does (removing temporaries), since a
/// command without safe points would otherwise ignore it until its end.
void use_stop_points();

/// True once SIGINT or SIGTERM arrived.
bool interrupted();
/// The signal that arrived (0 if none).
int interrupt_signal();
/// "SIGINT" or "SIGTERM" (for messages and reports).
const char* interrupt_signal_name();
/// 128 + interrupt_signal().
int interrupted_exit_status();
/// A should_stop callback for library options: returns interrupted().
std::function<bool()> stop_on_signal();

/// Call for every output path before anything is printed: when `path` is standard output ("-",
/// /dev/stdout, /dev/fd/1), the data keeps the real standard output (io::set_standard_output())
/// and descriptor 1 is pointed at standard error, so every message, table and progress line the
/// command prints goes to standard error and standard output carries only the data.
void claim_standard_output(const std::string& path);

}  // namespace cairn::cli
