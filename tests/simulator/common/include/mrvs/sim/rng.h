#pragma once
// Counter-based random numbers for the simulator.
//
// Every random value is a pure function of (seed, stream, index...): no generator state is
// shared between threads, so output does not depend on the thread count or on the order
// in which work is done, and changing one stream (e.g. image noise) never changes another
// (e.g. IMU noise). std::*_distribution is avoided on purpose: its output differs between
// standard libraries.
#include <cmath>
#include <cstdint>
#include <utility>

#include "mrvs/core/hash.h"

namespace mrvs::sim {

/// Independent random streams. Add new ones at the end; never renumber (it would change
/// every generated dataset).
enum class Stream : std::uint64_t {
  kImuNoise = 1,
  kBiasWalk = 2,
  kImageNoise = 3,
  kMapNoise = 4,
  kMapSampling = 5,
  kScene = 6,
  kTexture = 7,
  kExposure = 8,
  kMapHoles = 9,
  kMisalignment = 10,
  kRoute = 11,
  kGnss = 12,
  kIllumination = 13,
  kCalibration = 14,
  kPeople = 15,
};

using mrvs::mix64;

/// Stateless generator for one (seed, stream): value = f(seed, stream, a, b, c).
class CounterRng {
 public:
  constexpr CounterRng(std::uint64_t seed, Stream stream)
      : key_(mix64(mix64(seed) ^ (static_cast<std::uint64_t>(stream) * 0xD1B54A32D192ED03ULL))) {}

  /// 64 random bits for the index tuple (a, b, c).
  constexpr std::uint64_t bits(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0) const {
    return mix64(key_ ^ mix64(a ^ mix64(b ^ mix64(c + 0x632BE59BD9B4E019ULL))));
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0) const {
    return static_cast<double>(bits(a, b, c) >> 11) * 0x1.0p-53;
  }

  /// Uniform in [lo, hi).
  double uniform(double lo, double hi, std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0) const {
    return lo + (hi - lo) * uniform(a, b, c);
  }

  /// Standard normal (Box-Muller on two independent uniforms derived from the tuple).
  double normal(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0) const {
    const std::uint64_t h = bits(a, b, c);
    const double u1 = (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;  // (0, 1)
    const double u2 = static_cast<double>(mix64(h) >> 11) * 0x1.0p-53;   // [0, 1)
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

  /// Two independent standard normals for the tuple (both Box-Muller outputs, for the cost
  /// of one): first == normal(a, b, c).
  std::pair<double, double> normal_pair(std::uint64_t a, std::uint64_t b = 0, std::uint64_t c = 0) const {
    const std::uint64_t h = bits(a, b, c);
    const double u1 = (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;
    const double u2 = static_cast<double>(mix64(h) >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1)), theta = 6.283185307179586 * u2;
    return {r * std::cos(theta), r * std::sin(theta)};
  }

 private:
  std::uint64_t key_;
};

/// Sequential draws from one stream for single-threaded set-up work (scene layout, route):
/// draw k is CounterRng(seed, stream).*(k), so the sequence is reproducible.
class SequenceRng {
 public:
  SequenceRng(std::uint64_t seed, Stream stream) : rng_(seed, stream) {}
  double uniform() { return rng_.uniform(next_++); }
  double uniform(double lo, double hi) { return rng_.uniform(lo, hi, next_++); }
  double normal() { return rng_.normal(next_++); }
  /// Integer in [lo, hi] (inclusive).
  int integer(int lo, int hi) {
    return lo + static_cast<int>(rng_.bits(next_++) % static_cast<std::uint64_t>(hi - lo + 1));
  }

 private:
  CounterRng rng_;
  std::uint64_t next_ = 0;
};

}  // namespace mrvs::sim
