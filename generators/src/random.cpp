#include "shatter/generators/random.hpp"

#include <algorithm>
#include <cmath>

namespace shatter::test {

Vec3 Random::direction() {
  // Archimedes: z uniform in [-1, 1] and the longitude uniform give a uniform point
  // on the sphere.
  constexpr double pi = 3.141592653589793;
  const double z = uniform(-1, 1);
  const double phi = uniform(0, 2 * pi);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace shatter::test
