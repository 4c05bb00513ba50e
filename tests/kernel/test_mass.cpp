// Mass properties against analytic values, invariance under rigid motion and
// reversal, and the exact sign of the signed volume where doubles cannot decide.

#include <catch2/catch.hpp>
#include <gmpxx.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "shatter/generators/corpus.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"

using namespace shatter;

namespace {

constexpr double pi = 3.14159265358979323846;

using Matrix3 = std::array<double, 9>;  // row-major

Vec3 apply(const Matrix3& m, Vec3 v) {
  return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[3] * v.x + m[4] * v.y + m[5] * v.z,
          m[6] * v.x + m[7] * v.y + m[8] * v.z};
}

Matrix3 multiply(const Matrix3& a, const Matrix3& b) {
  Matrix3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) r[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return r;
}

Matrix3 transpose(const Matrix3& a) { return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]}; }

// Rotation by `angle` about the unit axis (Rodrigues).
Matrix3 rotation(Vec3 axis, double angle) {
  axis = normalized(axis);
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const double x = axis.x, y = axis.y, z = axis.z;
  return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,  //
          t * x * y + s * z, t * y * y + c,     t * y * z - s * x,  //
          t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}

Mesh transformed(Mesh mesh, const Matrix3& linear, Vec3 shift) {
  for (Vec3& p : mesh.positions) p = apply(linear, p) + shift;
  return mesh;
}

Mesh translated(Mesh mesh, Vec3 shift) {
  for (Vec3& p : mesh.positions) p = p + shift;
  return mesh;
}

Mesh reversed(Mesh mesh) {
  for (Triangle& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

// Icosahedron subdivided `levels` times, vertices projected on the unit sphere.
Mesh icosphere(int levels) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> positions = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<Triangle> triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                     {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                     {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                     {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Vec3& p : positions) p = normalized(p);
  for (int level = 0; level < levels; ++level) {
    std::map<std::uint64_t, VertexIndex> midpoint_of;
    auto midpoint = [&](VertexIndex a, VertexIndex b) {
      const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
      const auto [it, inserted] = midpoint_of.try_emplace(key, static_cast<VertexIndex>(positions.size()));
      if (inserted) positions.push_back(normalized((positions[a] + positions[b]) * 0.5));
      return it->second;
    };
    std::vector<Triangle> finer;
    for (const Triangle& t : triangles) {
      const VertexIndex ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      finer.push_back({t[0], ab, ca});
      finer.push_back({t[1], bc, ab});
      finer.push_back({t[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    triangles = std::move(finer);
  }
  return test::mesh_from(std::move(positions), std::move(triangles));
}

void check_close(Vec3 actual, Vec3 expected, double margin) {
  CHECK(actual.x == Approx(expected.x).margin(margin));
  CHECK(actual.y == Approx(expected.y).margin(margin));
  CHECK(actual.z == Approx(expected.z).margin(margin));
}

void check_close(const Matrix3& actual, const Matrix3& expected, double margin) {
  for (int i = 0; i < 9; ++i) {
    INFO("inertia entry " << i);
    CHECK(actual[static_cast<std::size_t>(i)] == Approx(expected[static_cast<std::size_t>(i)]).margin(margin));
  }
}

// Independent exact evaluation of sum det(a, b, c), for cross-checking the sign.
Sign exact_sign_reference(const Mesh& mesh) {
  mpq_class total = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    // det by the rule of Sarrus, a different expansion from the library's.
    total += mpq_class(a.x) * b.y * c.z + mpq_class(b.x) * c.y * a.z + mpq_class(c.x) * a.y * b.z -
             mpq_class(c.x) * b.y * a.z - mpq_class(b.x) * a.y * c.z - mpq_class(a.x) * c.y * b.z;
  }
  const int s = sgn(total);
  return s < 0 ? Sign::negative : s > 0 ? Sign::positive : Sign::zero;
}

// The plain double sum of det(a, b, c): what the filter must not trust blindly.
double naive_determinant_sum(const Mesh& mesh) {
  double sum = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    sum += dot(a, cross(b, c));
  }
  return sum;
}

// A flat closed "pillow" in the plane z = 0.7: the top quad (outward +z) split on
// diagonal 0-2, the bottom (outward -z) on diagonal 1-3, so the triangles' terms
// do not cancel bit for bit. Its volume is exactly zero.
Mesh flat_pillow(Vec3 shift) {
  return test::mesh_from({Vec3{0.1, 0.1, 0.7} + shift, Vec3{1.3, 0.2, 0.7} + shift, Vec3{1.1, 1.7, 0.7} + shift,
                    Vec3{0.3, 0.9, 0.7} + shift},
                   {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}});
}

}  // namespace

TEST_CASE("unit cube: volume, centroid and inertia", "[mass]") {
  const MassProperties props = mass_properties(test::unit_cube());
  CHECK(props.volume == Approx(1.0).epsilon(1e-15));
  check_close(props.centroid, {0.5, 0.5, 0.5}, 1e-15);
  const double d = 1.0 / 6;  // (1^2 + 1^2) / 12
  check_close(props.inertia, {d, 0, 0, 0, d, 0, 0, 0, d}, 1e-15);
  CHECK(signed_volume(test::unit_cube()) == Approx(1.0).epsilon(1e-15));
  CHECK(signed_volume_sign(test::unit_cube()) == Sign::positive);
}

TEST_CASE("a scaled, rotated and translated box matches the analytic values", "[mass]") {
  const double a = 2, b = 3, c = 5;  // edge lengths
  const Matrix3 scale{a, 0, 0, 0, b, 0, 0, 0, c};
  const Matrix3 turn = rotation({1, 2, 3}, 0.7);
  const Vec3 shift{10, -20, 30};
  // The cube's corner (0,0,0) maps to shift; its centre (0.5,0.5,0.5) to:
  const Vec3 centre = apply(turn, Vec3{a / 2, b / 2, c / 2}) + shift;
  const Mesh box = transformed(test::unit_cube(), multiply(turn, scale), shift);

  const MassProperties props = mass_properties(box);
  const double volume = a * b * c;
  CHECK(props.volume == Approx(volume).epsilon(1e-13));
  check_close(props.centroid, centre, 1e-12);
  // Body frame: diag(m (b^2 + c^2) / 12, ...); world frame: R D R^T.
  const Matrix3 body{volume * (b * b + c * c) / 12, 0, 0, 0, volume * (a * a + c * c) / 12, 0,
                     0, 0, volume * (a * a + b * b) / 12};
  const Matrix3 world = multiply(multiply(turn, body), transpose(turn));
  check_close(props.inertia, world, 1e-11);
  // The tensor is symmetric to the last bit: each mixed entry is stored once.
  CHECK(props.inertia[1] == props.inertia[3]);
  CHECK(props.inertia[2] == props.inertia[6]);
  CHECK(props.inertia[5] == props.inertia[7]);
}

TEST_CASE("an icosphere approaches the inertia of a solid sphere", "[mass]") {
  const double sphere_volume = 4 * pi / 3;
  const double sphere_inertia = 2.0 / 5 * sphere_volume;  // (2/5) m r^2, r = 1
  double previous_error = 1;
  for (int levels = 1; levels <= 5; ++levels) {
    INFO("subdivision levels " << levels);
    const Mesh sphere = icosphere(levels);
    REQUIRE(validate_mesh(sphere).valid());
    const MassProperties props = mass_properties(sphere);
    // Inscribed: always a little smaller than the sphere, and closer each level.
    CHECK(props.volume < sphere_volume);
    const double volume_error = (sphere_volume - props.volume) / sphere_volume;
    CHECK(volume_error < previous_error / 3);
    previous_error = volume_error;
    check_close(props.centroid, {0, 0, 0}, 1e-12);
    for (int i = 0; i < 3; ++i) {
      CHECK(props.inertia[static_cast<std::size_t>(4 * i)] < sphere_inertia);
      for (int j = 0; j < 3; ++j) {
        if (i != j) CHECK(props.inertia[static_cast<std::size_t>(3 * i + j)] == Approx(0).margin(1e-12));
      }
    }
    if (levels == 5) {  // 20480 triangles
      CHECK(volume_error < 1e-3);
      for (int i = 0; i < 3; ++i) {
        CHECK(props.inertia[static_cast<std::size_t>(4 * i)] == Approx(sphere_inertia).epsilon(2e-3));
      }
    }
  }
}

TEST_CASE("far from the origin the properties keep their precision", "[mass]") {
  const Mesh sphere = icosphere(3);
  const MassProperties here = mass_properties(sphere);
  const Vec3 far{1e6, -1e6, 1e6};
  const Mesh moved = translated(sphere, far);
  const MassProperties there = mass_properties(moved);
  CHECK(there.volume == Approx(here.volume).epsilon(1e-9));
  CHECK(signed_volume(moved) == Approx(signed_volume(sphere)).epsilon(1e-9));
  check_close(there.centroid, here.centroid + far, 1e-8);
  check_close(there.inertia, here.inertia, 1e-8);
  CHECK(signed_volume_sign(moved) == Sign::positive);
}

// Found by a sweep of `fracture` over scaled cubes (2026-12-07): a cube 1e-105
// across had a NaN centroid (its first moments underflowed, then times
// 1 / volume, infinite), and fragments of one 1e-100 across a volume of 0,
// though every true value was a normal double. Scaled by a power of two, a
// mesh's properties scale exactly, as long as the results are in range.
TEST_CASE("far from unit size the properties scale exactly with the mesh", "[mass]") {
  const Mesh sphere = translated(icosphere(2), {0.3, -0.2, 0.1});
  const MassProperties unit = mass_properties(sphere);
  for (const int exponent : {-340, -200, -61, -20, 20, 61, 150, 200}) {
    INFO("scaled by 2^" << exponent);
    Mesh scaled = sphere;
    for (Vec3& p : scaled.positions) p = {std::ldexp(p.x, exponent), std::ldexp(p.y, exponent), std::ldexp(p.z, exponent)};
    const MassProperties props = mass_properties(scaled);
    CHECK(props.volume == std::ldexp(unit.volume, 3 * exponent));
    CHECK(props.centroid.x == std::ldexp(unit.centroid.x, exponent));
    CHECK(props.centroid.y == std::ldexp(unit.centroid.y, exponent));
    CHECK(props.centroid.z == std::ldexp(unit.centroid.z, exponent));
    for (std::size_t k = 0; k < 9; ++k) {
      // A moment below the doubles' range (2^-340: 2^-1700 times the unit's) is 0, never NaN.
      const double expected = std::ldexp(unit.inertia[k], 5 * exponent);
      if (std::fabs(expected) >= 0x1p-1000) {
        CHECK(props.inertia[k] == expected);
      } else {
        CHECK(std::fabs(props.inertia[k]) <= 0x1p-1000);
      }
    }
  }
}

TEST_CASE("reversing every triangle negates the volume", "[mass]") {
  for (const Mesh& mesh : {test::unit_cube(), icosphere(2), translated(icosphere(2), {1e6, 2e6, -3e6})}) {
    const Mesh inward = reversed(mesh);
    const MassProperties out = mass_properties(mesh), in = mass_properties(inward);
    CHECK(out.volume > 0);
    CHECK(in.volume == Approx(-out.volume).epsilon(1e-12));
    CHECK(signed_volume(inward) == -signed_volume(mesh));
    CHECK(signed_volume_sign(mesh) == Sign::positive);
    CHECK(signed_volume_sign(inward) == Sign::negative);
    // The centroid does not depend on orientation, the inertia flips with the volume.
    check_close(in.centroid, out.centroid, 1e-6);
    for (std::size_t i = 0; i < 9; ++i) CHECK(in.inertia[i] == Approx(-out.inertia[i]).margin(1e-9));
  }
}

TEST_CASE("the empty mesh has zero volume", "[mass]") {
  const Mesh empty;
  CHECK(signed_volume(empty) == 0);
  CHECK(signed_volume_sign(empty) == Sign::zero);
  const MassProperties props = mass_properties(empty);
  CHECK(props.volume == 0);
  CHECK(props.inertia == Matrix3{});
}

TEST_CASE("signed_volume_sign is exact on a flat closed mesh", "[mass][exact]") {
  for (const Vec3 shift : {Vec3{0, 0, 0}, Vec3{1000.1, 500.05, 0}, Vec3{123456.789, 61728.3945, 0}}) {
    INFO("shift " << shift.x);
    const Mesh flat = flat_pillow(shift);
    REQUIRE(exact_sign_reference(flat) == Sign::zero);
    CHECK(signed_volume_sign(flat) == Sign::zero);
    CHECK(signed_volume_sign(reversed(flat)) == Sign::zero);
    // Finite but meaningless: no centroid for a flat solid, and nothing NaN.
    const MassProperties props = mass_properties(flat);
    CHECK(std::isfinite(props.centroid.x));
    CHECK(std::isfinite(props.inertia[0]));
  }
  // The plain double sum gets this wrong (observed with IEEE doubles, no FMA);
  // reported, not required, as it depends on how the compiler evaluates it.
  CHECK_NOFAIL(naive_determinant_sum(flat_pillow({0, 0, 0})) != 0);
}

TEST_CASE("signed_volume_sign is exact on a tiny volume the double sum gets wrong", "[mass][exact]") {
  for (const Vec3 shift : {Vec3{0, 0, 0}, Vec3{1000.1, 500.05, 0}, Vec3{123456.789, 61728.3945, 0}}) {
    INFO("shift " << shift.x);
    // Lifting vertex 0 by one ulp makes the top, folded along 0-2, lie above the
    // bottom, folded along 1-3: volume h/3 * area(1,2,3) > 0, about 2.5e-17.
    Mesh tent = flat_pillow(shift);
    tent.positions[0].z = std::nextafter(tent.positions[0].z, 1.0);
    REQUIRE(exact_sign_reference(tent) == Sign::positive);
    CHECK(signed_volume_sign(tent) == Sign::positive);
    CHECK(signed_volume_sign(reversed(tent)) == Sign::negative);
    // Dropping it by one ulp instead turns the volume negative.
    Mesh dent = flat_pillow(shift);
    dent.positions[0].z = std::nextafter(dent.positions[0].z, 0.0);
    REQUIRE(exact_sign_reference(dent) == Sign::negative);
    CHECK(signed_volume_sign(dent) == Sign::negative);
  }
  Mesh far_tent = flat_pillow({123456.789, 61728.3945, 0});
  far_tent.positions[0].z = std::nextafter(far_tent.positions[0].z, 1.0);
  CHECK_NOFAIL(naive_determinant_sum(far_tent) < 0);  // the wrong sign, when evaluated as written
}

// A closed disk nearly flat: an n-gon in a tilted plane (its corners rounded
// off the plane), fanned from corner 0 on one side and from corner `other` on
// the other. Its volume is the few ulps its rounding leaves, either sign.
Mesh tilted_disk(std::uint64_t seed, int n, int other) {
  std::uint64_t state = seed * 0x9E3779B97F4A7C15ull + 1;
  const auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1p-53;
  };
  const Vec3 u = normalized({uniform() - 0.5, uniform() - 0.5, uniform() - 0.5});
  const Vec3 w = normalized(cross(u, {uniform() - 0.5, uniform() - 0.5, uniform() - 0.5}));
  const Vec3 centre{uniform() * 2 - 1, uniform() * 2 - 1, uniform() * 2 - 1};
  std::vector<Vec3> corners;
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * pi * (i + 0.4 * uniform()) / n;
    corners.push_back(centre + u * std::cos(angle) + w * std::sin(angle));
  }
  std::vector<Triangle> triangles;
  for (int i = 1; i + 1 < n; ++i) triangles.push_back({0, static_cast<VertexIndex>(i), static_cast<VertexIndex>(i + 1)});
  for (int i = 1; i + 1 < n; ++i) {
    const auto a = static_cast<VertexIndex>((other + i) % n), b = static_cast<VertexIndex>((other + i + 1) % n);
    triangles.push_back({static_cast<VertexIndex>(other), b, a});
  }
  return test::mesh_from(corners, triangles);
}

TEST_CASE("nearly flat solids: the mass has a positive volume whenever the exact volume is positive", "[mass][exact]") {
  // The double integrals of such a disk cancel to nothing, or below (an open
  // disk that --repair closed, volume 1e-17 exactly, came out -3.7e-17: validate,
  // deciding the sign exactly, accepted it, and fracture refused it for its
  // mass). Where they do, the integrals are taken again exactly.
  std::size_t positive = 0, doubles_wrong = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    const int n = 4 + static_cast<int>(seed % 5);
    const Mesh disk = tilted_disk(seed, n, 1 + static_cast<int>(seed % (n - 2)));
    INFO("seed " << seed << ", " << n << " corners");
    const MassProperties mass = mass_properties(disk);
    REQUIRE(std::isfinite(mass.volume));
    // (A solid of negative exact volume is no valid input; nothing is promised.)
    if (exact_sign_reference(disk) != Sign::positive) continue;
    ++positive;
    doubles_wrong += naive_determinant_sum(disk) <= 0;
    CHECK(mass.volume > 0);
    CHECK((std::isfinite(mass.centroid.x) && std::isfinite(mass.centroid.y) && std::isfinite(mass.centroid.z)));
    for (const double entry : mass.inertia) CHECK(std::isfinite(entry));
  }
  CHECK(positive >= 50);
  CHECK(doubles_wrong >= 10);  // the cases the exact integrals are for
}

TEST_CASE("signed_volume_sign takes the exact path for coordinates outside the filter range", "[mass][exact]") {
  // Tiny and huge scales: products would underflow or overflow in the filter.
  for (const double scale : {0x1p-520, 0x1p-230, 0x1p230, 0x1p330}) {
    INFO("scale " << scale);
    const Matrix3 scaling{scale, 0, 0, 0, scale, 0, 0, 0, scale};
    const Mesh cube = transformed(test::unit_cube(), scaling, {0, 0, 0});
    CHECK(signed_volume_sign(cube) == Sign::positive);
    CHECK(signed_volume_sign(reversed(cube)) == Sign::negative);
    Mesh tent = transformed(flat_pillow({0, 0, 0}), scaling, {0, 0, 0});
    tent.positions[0].z = std::nextafter(tent.positions[0].z, 2 * tent.positions[0].z);
    CHECK(signed_volume_sign(tent) == exact_sign_reference(tent));
    CHECK(signed_volume_sign(tent) == Sign::positive);
  }
}

TEST_CASE("corpus meshes: positive volume, and mass properties agree with signed_volume", "[mass][corpus]") {
  for (const auto& path : shatter::test::valid_meshes()) {
    INFO(path.filename().string());
    const Mesh mesh = read_mesh(path);
    CHECK(signed_volume_sign(mesh) == Sign::positive);
    const MassProperties props = mass_properties(mesh);
    CHECK(props.volume > 0);
    CHECK(props.volume == Approx(signed_volume(mesh)).epsilon(1e-10));
    // Inertia about the centroid of a real solid: positive diagonal, triangle inequality.
    const double ixx = props.inertia[0], iyy = props.inertia[4], izz = props.inertia[8];
    CHECK(ixx > 0);
    CHECK(iyy > 0);
    CHECK(izz > 0);
    CHECK(ixx <= iyy + izz);
    CHECK(iyy <= ixx + izz);
    CHECK(izz <= ixx + iyy);
    // Moving the mesh moves the centroid and leaves volume and inertia.
    const Vec3 shift{250.5, -1e3, 4e4};
    const MassProperties moved = mass_properties(translated(mesh, shift));
    CHECK(moved.volume == Approx(props.volume).epsilon(1e-9));
    check_close(moved.centroid, props.centroid + shift, 1e-9 * (1 + norm(shift)));
  }
  const Mesh inward = read_mesh(shatter::test::mesh_dir() / "bad" / "tetrahedron.off");
  CHECK(signed_volume_sign(inward) == Sign::negative);
  CHECK(signed_volume(inward) == Approx(-1.0 / 6).epsilon(1e-15));
}
