#pragma once
/// \file Counter-based random numbers for the simulator. Every pixel (or beam) of a frame gets its
/// own stream, derived from (seed, frame, index) by SplitMix64 hashing, so a frame rendered with
/// any number of threads is byte-identical. The generator is our own (not std::*_distribution), so
/// the numbers are also the same with every standard library.

#include <cmath>
#include <cstdint>
#include <numbers>

namespace multicue::sim {

/// SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
constexpr std::uint64_t Mix64(std::uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/// Derives an independent seed from a parent seed and a stream number.
constexpr std::uint64_t SubSeed(std::uint64_t seed, std::uint64_t stream) {
    return Mix64(seed ^ Mix64(stream + 0x632BE59BD9B4E019ull));
}

/// A small, fast generator (SplitMix64 sequence) for one pixel, beam or object.
/// Also a UniformRandomBitGenerator, so it works with std::shuffle.
class StreamRng {
  public:
    using result_type = std::uint64_t;
    explicit constexpr StreamRng(std::uint64_t seed) : state_(seed) {}
    StreamRng(std::uint64_t seed, std::uint64_t stream) : state_(SubSeed(seed, stream)) {}

    static constexpr result_type min() { return 0; }
    static constexpr result_type max() { return ~result_type{0}; }
    result_type operator()() {
        state_ += 0x9E3779B97F4A7C15ull;
        std::uint64_t z = state_;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }

    /// Uniform in [0, 1).
    double Uniform() { return static_cast<double>((*this)() >> 11) * 0x1.0p-53; }
    /// Uniform in [lo, hi).
    double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
    /// Uniform integer in [lo, hi] (hi >= lo).
    int UniformInt(int lo, int hi) {
        const auto span = static_cast<std::uint64_t>(hi - lo) + 1;
        return lo + static_cast<int>((*this)() % span);
    }
    /// Standard normal (Box-Muller in single precision; one value per call).
    double Gaussian() {
        const std::uint64_t x = (*this)();
        const float u1 = 1.0f - static_cast<float>(x >> 40) * 0x1.0p-24f;  // (0, 1]
        const float u2 = static_cast<float>(x & 0xffffffu) * 0x1.0p-24f;   // [0, 1)
        return std::sqrt(-2.0f * std::log(u1)) * std::cos(2.0f * std::numbers::pi_v<float> * u2);
    }
    /// Approximately standard normal from one 64-bit draw: the sum of four 16-bit uniforms
    /// (Irwin-Hall), centred and scaled to unit variance; bounded by +-3.46. Several times cheaper
    /// than Gaussian(); used where the tails do not matter (colour noise, pixel jitter).
    float FastGaussian() {
        const std::uint64_t x = (*this)();
        const auto sum = static_cast<float>((x & 0xffffu) + ((x >> 16) & 0xffffu) +
                                            ((x >> 32) & 0xffffu) + (x >> 48));
        // Mean 4 * 32767.5, variance 4 * (65536^2 - 1) / 12.
        return (sum - 131070.0f) * (1.0f / 37837.23f);
    }

  private:
    std::uint64_t state_;
};

}  // namespace multicue::sim
