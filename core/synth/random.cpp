#include "core/synth/random.h"

#include <algorithm>
#include <cmath>

namespace skinstream::synth {

namespace {
uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
}  // namespace

Random Random::stream(uint64_t seed, uint64_t stream_id) {
  return Random(splitmix64(splitmix64(seed) ^ splitmix64(stream_id + 0x51ED270B2A4B3C1Dull)));
}

double Random::uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

double Random::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

int Random::below(int n) {
  if (n <= 1) return 0;
  // Lemire's multiply-shift on the top 32 bits: bias < n / 2^32, irrelevant here.
  const uint64_t r = engine_() >> 32;
  return static_cast<int>((r * static_cast<uint64_t>(n)) >> 32);
}

bool Random::chance(double p) { return uniform() < p; }

double Random::normal() {
  double u1 = uniform();
  while (u1 <= 0.0) u1 = uniform();
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double Random::exponential(double mean) {
  double u = uniform();
  while (u <= 0.0) u = uniform();
  return -mean * std::log(u);
}

int Random::poisson(double mean) {
  if (mean <= 0.0) return 0;
  if (mean > 50.0) return std::max(0, static_cast<int>(std::lround(normal(mean, std::sqrt(mean)))));
  const double limit = std::exp(-mean);
  int k = 0;
  double p = uniform();
  while (p > limit) {
    ++k;
    p *= uniform();
  }
  return k;
}

int Random::geometric(double mean) {
  if (mean <= 1.0) return 1;
  const double p = 1.0 / mean;  // success probability per trial
  double u = uniform();
  while (u <= 0.0) u = uniform();
  return 1 + static_cast<int>(std::floor(std::log(u) / std::log(1.0 - p)));
}

}  // namespace skinstream::synth
