// Seeded random streams that give the same numbers on every platform and thread count.
// std::uniform_real_distribution and std::normal_distribution are implementation-defined,
// so the conversions from raw 64-bit draws are written here. Streams for parallel work
// are derived from (seed, indices...) alone, never from the clock or the thread.
#pragma once

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <random>

namespace cablecal {

// SplitMix64 finaliser: a bijective mix used to derive independent stream seeds.
inline std::uint64_t MixSeed(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Seed of the stream for (seed, i0, i1, ...); e.g. (seed, n, design, trial).
inline std::uint64_t StreamSeed(std::uint64_t seed, std::initializer_list<std::uint64_t> indices) {
  std::uint64_t s = MixSeed(seed);
  for (std::uint64_t i : indices) s = MixSeed(s ^ MixSeed(i + 0x632be59bd9b4e019ULL));
  return s;
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}

  // Uniform on [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }

  // Standard normal by the Marsaglia polar method; deterministic given the stream.
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2.0 * Uniform() - 1.0;
      v = 2.0 * Uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double factor = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * factor;
    has_spare_ = true;
    return u * factor;
  }
  double Normal(double mean, double sigma) { return mean + sigma * Normal(); }

 private:
  std::mt19937_64 engine_;  // fully specified by the standard: same sequence everywhere
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace cablecal
