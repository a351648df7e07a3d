#pragma once
// Reproducible random numbers for the synthetic capture generator: std::mt19937_64 with our
// own distribution maths, because the standard distributions (normal, poisson...) are not
// specified bit for bit and would give different captures on different standard libraries.
#include <cstdint>
#include <random>

namespace skinstream::synth {

class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}

  // An independent stream for one part of the generator (layout, noise, ghosts...), so that
  // changing how much one part draws does not change the others.
  static Random stream(uint64_t seed, uint64_t stream_id);

  uint64_t bits() { return engine_(); }
  double uniform();                      // [0, 1), 53 random bits
  double uniform(double lo, double hi);  // [lo, hi)
  int below(int n);                      // integer in [0, n); n >= 1
  bool chance(double p);                 // true with probability p
  double normal();                       // standard normal (Box-Muller, no cached pair)
  double normal(double mean, double sigma) { return mean + sigma * normal(); }
  double exponential(double mean);
  int poisson(double mean);    // Knuth's product method; mean <= ~50
  int geometric(double mean);  // >= 1, mean `mean` (>= 1)

 private:
  std::mt19937_64 engine_;
};

}  // namespace skinstream::synth
