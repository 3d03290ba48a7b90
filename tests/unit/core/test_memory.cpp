#include "mrvs/core/memory.h"

#include <cstdlib>
#include <cstring>

#include <gtest/gtest.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace mrvs {
namespace {

// glibc's default would serve 8 MB with mmap (hblkhd grows) and give the memory back at the
// free (arena shrinks at the trim); after the call both stay on the heap.
TEST(Memory, LargeBlocksStayOnTheHeapAndAreKeptAfterTheFree) {
#if defined(__GLIBC__)
  ASSERT_TRUE(keep_large_blocks_on_the_heap());
  constexpr std::size_t kBytes = 8u << 20;
  const struct mallinfo2 before = mallinfo2();
  void* block = std::malloc(kBytes);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBytes);
  asm volatile("" : : "r"(block) : "memory");  // the block escapes: no malloc/free elision
  const struct mallinfo2 during = mallinfo2();
  EXPECT_EQ(during.hblkhd, before.hblkhd) << "the block was mmapped";
  EXPECT_GE(during.uordblks, before.uordblks + kBytes) << "the block is not on the heap";
  std::free(block);
  const struct mallinfo2 after = mallinfo2();
  EXPECT_GE(after.arena, during.arena) << "the freed memory was given back";
  EXPECT_GE(after.fordblks, kBytes) << "the freed block is not kept for reuse";
#else
  GTEST_SKIP() << "allocator settings are glibc's";
#endif
}

}  // namespace
}  // namespace mrvs
