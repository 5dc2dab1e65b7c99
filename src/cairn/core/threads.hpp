#pragma once
/// \file
/// The number of threads a `threads` option gives a TBB arena. Every options struct takes
/// `threads` (0 = every hardware thread); a request above what the machine runs is clamped to
/// its hardware threads: TBB asked for 100,000 workers spends minutes starting them and crashed
/// at arena shutdown (SIGSEGV in `Engine::~Engine`, `cairn ba --threads 100000`).

#include <algorithm>
#include <thread>

namespace cairn::core {

/// `threads` clamped to [1, hardware threads], or -1 (tbb::task_arena::automatic) for
/// `threads` <= 0.
inline int arena_concurrency(int threads) {
  if (threads <= 0) return -1;
  const int machine = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::min(threads, machine);
}

}  // namespace cairn::core
