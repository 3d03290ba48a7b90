#pragma once
// Small, stable (not cryptographic) 64-bit hashing: the same input gives the same value on
// every platform and build, so it can key random streams and identify contents.
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace mrvs {

/// splitmix64 finaliser: a bijective 64-bit mix with good avalanche.
constexpr std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace mrvs
