// core::PageArena: blocks are distinct, aligned, writable, and outlive the arena.

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>
#include <vector>

#include "cairn/core/page_arena.hpp"

namespace cairn::core {
namespace {

TEST(PageArena, BlocksAreDisjointAlignedAndKeepTheirBytes) {
  std::vector<PageArena::Block> blocks;
  {
    PageArena arena;
    // Small blocks share chunks; 40 of 3 MB overflow the first 64 MiB chunk; one larger than a
    // quarter chunk gets memory of its own.
    for (int b = 0; b < 40; ++b) blocks.push_back(arena.allocate(std::size_t{3} << 20));
    blocks.push_back(arena.allocate(std::size_t{40} << 20));
    blocks.push_back(arena.allocate(1));
  }  // the arena is gone; its blocks must stay valid
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const PageArena::Block& block = blocks[b];
    ASSERT_NE(block.data, nullptr);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(block.data) % 64, 0u) << "block " << b;
    std::fill(block.data, block.data + block.size, static_cast<std::uint8_t>(b));
  }
  // No two blocks overlap: each still holds its own fill after all were written.
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const PageArena::Block& block = blocks[b];
    EXPECT_EQ(block.data[0], static_cast<std::uint8_t>(b));
    EXPECT_EQ(block.data[block.size - 1], static_cast<std::uint8_t>(b));
    for (std::size_t c = 0; c < blocks.size(); ++c) {
      if (c == b) continue;
      const bool apart = blocks[c].data + blocks[c].size <= block.data || block.data + block.size <= blocks[c].data;
      EXPECT_TRUE(apart) << "blocks " << b << " and " << c;
    }
  }
  // The first chunk holds 21 blocks of 3 MB (64 MiB / 3 MiB), so blocks 0 and 21 differ in chunk.
  EXPECT_EQ(blocks[0].chunk, blocks[20].chunk);
  EXPECT_NE(blocks[0].chunk, blocks[21].chunk);
}

}  // namespace
}  // namespace cairn::core
