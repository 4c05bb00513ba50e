#pragma once
// Synthetic meshes for property tests: closed, outward-oriented solids with known
// volumes, and the thesis's shapes (torus, hollow egg shell), plus transforms that
// stress the arithmetic (tiny, huge, far from the origin).

#include <cstdint>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter::test {

/// A mesh from positions and triangles, every triangle on the original surface.
Mesh mesh_from(std::vector<Vec3> positions, std::vector<Triangle> triangles);
/// The unit cube [0,1]^3, outward, with a fixed numbering the validator tests
/// refer to: vertices 0-3 the z = 0 square counter-clockwise from the origin, 4-7 above them.
Mesh unit_cube();
/// Axis-aligned box [lo, hi], 12 triangles. Volume (hi-lo).x*(hi-lo).y*(hi-lo).z.
Mesh box(Vec3 lo, Vec3 hi);
/// The box with each face split into n x n squares (2 n^2 triangles a face), so
/// axis planes through grid lines hit many vertices, edges and faces at once.
Mesh grid_box(Vec3 lo, Vec3 hi, int n);
/// A torus around the z axis: `segments` x `rings` quads, 2 triangles each.
Mesh torus(double major_radius, double minor_radius, int segments, int rings);
/// A UV sphere (ellipsoid with radii r): 2 * slices * (stacks - 1) triangles.
Mesh ellipsoid(Vec3 centre, Vec3 radii, int slices, int stacks);
/// The thesis's hollow egg: an outer egg and an inward-facing inner one (a cavity),
/// 1,520 triangles.
Mesh hollow_egg();
/// A box with a box-shaped cavity holding a box island: three nested shells.
Mesh nested_shells_with_island();
/// Two disjoint boxes in one mesh.
Mesh two_boxes();
/// A long thin wedge and a needle-like box: slivers.
Mesh sliver();
/// Concatenates meshes (vertex indices offset, no welding).
Mesh merge(const std::vector<Mesh>& parts);
/// Every position scaled by s then moved by t.
Mesh transformed(Mesh mesh, double scale, Vec3 shift);
/// Every triangle reversed (outward becomes inward).
Mesh flipped(Mesh mesh);

struct NamedMesh {
  std::string name;
  Mesh mesh;
};
/// The generated catalogue used by the property tests, including far/tiny/huge
/// variants; never empty.
std::vector<NamedMesh> generated_meshes();

/// splitmix64: the tests' own reproducible random numbers.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  std::size_t index(std::size_t n) { return static_cast<std::size_t>(next() % n); }
  /// A direction uniform on the sphere.
  Vec3 direction();

 private:
  std::uint64_t state_;
};

}  // namespace shatter::test
