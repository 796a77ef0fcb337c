#pragma once
// Seeds of independent random streams from one master seed (the reproduction and its experiments
// give each purpose its own stream, so changing one experiment leaves the others' numbers as they were).

#include <cstdint>

namespace errfield::reproduction::detail {

/// splitmix64 of (seed, stream): streams of one master seed are decorrelated and the same on every
/// platform and standard library.
inline std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace errfield::reproduction::detail
