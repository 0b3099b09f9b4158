#pragma once
// The world's own random engine for sensor noise: xoshiro256** (Blackman and
// Vigna), seeded through splitmix64. Its whole state is four integers, so it
// is part of snapshots, and nothing in sim/ touches global random state.

#include <array>
#include <cmath>
#include <cstdint>

namespace sp {

/// Deterministic on every platform; a plain value, not thread-safe.
class Random {
 public:
  explicit Random(uint64_t seed = 1) { reseed(seed); }

  void reseed(uint64_t seed) {
    for (uint64_t& word : s_) {
      seed += 0x9e3779b97f4a7c15ULL;
      uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      word = z ^ (z >> 31);
    }
  }

  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform in (0, 1): never 0, so log() below is safe.
  double uniform() { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }

  /// Standard normal by Box-Muller. Draws two uniforms per call and keeps
  /// no cached second value, so the state is only the four words.
  double normal() {
    const double r = std::sqrt(-2.0 * std::log(uniform()));
    return r * std::cos(6.283185307179586 * uniform());
  }

  const std::array<uint64_t, 4>& state() const { return s_; }
  void setState(const std::array<uint64_t, 4>& s) { s_ = s; }
  friend bool operator==(const Random&, const Random&) = default;

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<uint64_t, 4> s_{};
};

}  // namespace sp
