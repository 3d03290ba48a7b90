#pragma once
// Process-wide allocator settings. Programs call these from main(); library code never
// does (they change the whole process).
namespace mrvs {

/// glibc serves blocks over 128 kB with mmap and unmaps them at every free, so a loop that
/// allocates the same large temporaries again and again (the estimator's n x m update
/// matrices: P H^T, the whitened gain, Eigen's GEMM packing) pays page faults for fresh zeroed
/// pages at every call: with 100 points in the state that was half the EKF update (the demo
/// clip's median update 22.1 -> 12-13 ms, frame 29.3 -> 16-18 ms). This raises the mmap
/// threshold to glibc's largest (32 MB) and keeps freed memory for reuse (trim threshold
/// 512 MB); the peak is what the program needs anyway. Returns false when glibc refused a
/// setting (the program then runs as before, only slower). No-op elsewhere than glibc.
bool keep_large_blocks_on_the_heap();

}  // namespace mrvs
