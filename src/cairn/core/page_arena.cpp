#include "cairn/core/page_arena.hpp"

#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace cairn::core {
namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;  // x86-64's and most arm64 kernels'

// `bytes` on a huge-page boundary, advised onto huge pages, freed with free().
std::shared_ptr<std::uint8_t[]> huge_page_memory(std::size_t bytes) {
  void* memory = nullptr;
  if (::posix_memalign(&memory, kHugePage, bytes) != 0) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  ::madvise(memory, bytes, MADV_HUGEPAGE);  // advice only: declined, the pages stay 4 KiB
#endif
  return std::shared_ptr<std::uint8_t[]>(static_cast<std::uint8_t*>(memory), [](std::uint8_t* p) { std::free(p); });
}

}  // namespace

PageArena::Block PageArena::allocate(std::size_t bytes) {
  const std::size_t rounded = (bytes + 63) & ~std::size_t{63};
  if (rounded > kChunkBytes / 4) {
    Block block;
    block.chunk = huge_page_memory(rounded);
    block.data = block.chunk.get();
    block.size = bytes;
    return block;
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!chunk_ || used_ + rounded > capacity_) {
    chunk_ = huge_page_memory(kChunkBytes);
    used_ = 0;
    capacity_ = kChunkBytes;
  }
  Block block;
  block.chunk = chunk_;
  block.data = chunk_.get() + used_;
  block.size = bytes;
  used_ += rounded;
  return block;
}

}  // namespace cairn::core
