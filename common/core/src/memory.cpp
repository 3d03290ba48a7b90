#include "mrvs/core/memory.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace mrvs {

bool keep_large_blocks_on_the_heap() {
#if defined(__GLIBC__)
  const bool mmap_ok = mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1;  // glibc's largest
  const bool trim_ok = mallopt(M_TRIM_THRESHOLD, 512 << 20) == 1;
  return mmap_ok && trim_ok;
#else
  return true;
#endif
}

}  // namespace mrvs
