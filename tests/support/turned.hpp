#pragma once
// A mesh turned about the three axes and shifted: solids in general position
// for the tests that overlap them (the arrangement and its union).

#include <cmath>

#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

/// `mesh` turned by angles (a, b, c), in radians, about x, then y, then z, and
/// shifted by `shift`, each coordinate rounded as doubles round: only inputs are
/// made this way, nothing is compared with the turn computed again.
inline Mesh turned(Mesh mesh, double a, double b, double c, Vec3 shift) {
  for (Vec3& p : mesh.positions) {
    Vec3 q{p.x, std::cos(a) * p.y - std::sin(a) * p.z, std::sin(a) * p.y + std::cos(a) * p.z};
    q = {std::cos(b) * q.x + std::sin(b) * q.z, q.y, -std::sin(b) * q.x + std::cos(b) * q.z};
    q = {std::cos(c) * q.x - std::sin(c) * q.y, std::sin(c) * q.x + std::cos(c) * q.y, q.z};
    p = {q.x + shift.x, q.y + shift.y, q.z + shift.z};
  }
  return mesh;
}

}  // namespace shatter::test
