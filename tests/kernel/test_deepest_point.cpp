// The star-shaped certificate's third centre (kernel/internal/.../deepest_point.hpp):
// the linear program against a brute force over the vertices of small random
// programs, and the point it proposes on star-shaped meshes whose vertex average
// and volume centroid both fail, which only the exact certificate then accepts.

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "shatter/generators/solids.hpp"
#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/deepest_point.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"

using namespace shatter;
using namespace shatter::test;
using shatter::kernel_detail::HalfSpace;

namespace {

// Solves the d x d system rows · x = rhs by Gaussian elimination with partial
// pivoting; nullopt when (nearly) singular.
std::optional<std::array<double, 4>> solve_system(int d, std::array<std::array<double, 4>, 4> rows,
                                                  std::array<double, 4> rhs) {
  for (int col = 0; col < d; ++col) {
    int pivot = col;
    for (int r = col + 1; r < d; ++r) {
      if (std::fabs(rows[r][col]) > std::fabs(rows[pivot][col])) pivot = r;
    }
    if (std::fabs(rows[pivot][col]) < 1e-9) return std::nullopt;
    std::swap(rows[col], rows[pivot]);
    std::swap(rhs[col], rhs[pivot]);
    for (int r = 0; r < d; ++r) {
      if (r == col) continue;
      const double f = rows[r][col] / rows[col][col];
      for (int c = 0; c < d; ++c) rows[r][c] -= f * rows[col][c];
      rhs[r] -= f * rhs[col];
    }
  }
  std::array<double, 4> x{};
  for (int r = 0; r < d; ++r) x[r] = rhs[r] / rows[r][r];
  return x;
}

// The optimum value of max c·x over the box and the constraints, by trying
// every vertex: each choice of d tight planes among the constraints and the
// box's faces (the optimum of a bounded feasible program is at one).
std::optional<double> brute_force_optimum(int d, const std::vector<HalfSpace>& constraints,
                                          const std::array<double, 4>& c, double box) {
  std::vector<HalfSpace> all = constraints;
  for (int j = 0; j < d; ++j) {
    HalfSpace up, down;
    up.a[j] = 1;
    up.b = box;
    down.a[j] = -1;
    down.b = box;
    all.push_back(up);
    all.push_back(down);
  }
  std::optional<double> best;
  const std::size_t n = all.size();
  std::vector<std::size_t> pick(static_cast<std::size_t>(d));
  for (std::size_t i = 0; i < static_cast<std::size_t>(d); ++i) pick[i] = i;
  while (true) {
    std::array<std::array<double, 4>, 4> rows{};
    std::array<double, 4> rhs{};
    for (int r = 0; r < d; ++r) {
      rows[r] = all[pick[r]].a;
      rhs[r] = all[pick[r]].b;
    }
    if (const std::optional<std::array<double, 4>> x = solve_system(d, rows, rhs)) {
      bool feasible = true;
      for (const HalfSpace& h : all) {
        double value = 0;
        for (int j = 0; j < d; ++j) value += h.a[j] * (*x)[j];
        feasible = feasible && value <= h.b + 1e-9;
      }
      if (feasible) {
        double value = 0;
        for (int j = 0; j < d; ++j) value += c[j] * (*x)[j];
        if (!best || value > *best) best = value;
      }
    }
    // The next d-subset in lexicographic order.
    int i = d - 1;
    while (i >= 0 && pick[i] == n - static_cast<std::size_t>(d - i)) --i;
    if (i < 0) break;
    ++pick[i];
    for (int j = i + 1; j < d; ++j) pick[j] = pick[j - 1] + 1;
  }
  return best;
}

// A triangulated sphere around the origin with every vertex moved along its
// ray by its own factor: the triangles' orientations against the origin are
// the sphere's times the three factors, so the mesh stays star-shaped around it.
Mesh radially_scaled(const Mesh& sphere, const std::vector<double>& factors) {
  Mesh mesh = sphere;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) mesh.positions[v] = mesh.positions[v] * factors[v];
  return mesh;
}

Vec3 vertex_average(const Mesh& mesh) {
  Vec3 sum;
  for (const Vec3& p : mesh.positions) sum = sum + p;
  return sum * (1.0 / static_cast<double>(mesh.positions.size()));
}

}  // namespace

TEST_CASE("maximize_in_box finds the optimum a brute force over the vertices finds", "[certify][property]") {
  std::mt19937_64 random(20261206);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::size_t feasible = 0, infeasible = 0;
  for (int round = 0; round < 400; ++round) {
    const int d = 1 + round % 4;
    const int count = 1 + static_cast<int>(random() % 9);
    std::vector<HalfSpace> constraints;
    for (int i = 0; i < count; ++i) {
      HalfSpace h;
      for (int j = 0; j < d; ++j) h.a[j] = unit(random);
      // Mostly through points near the origin; every fifth program may be empty.
      h.b = round % 5 == 0 ? unit(random) - 0.8 : std::fabs(unit(random)) + 0.05;
      constraints.push_back(h);
    }
    std::array<double, 4> c{};
    for (int j = 0; j < d; ++j) c[j] = unit(random);
    INFO("round " << round << " d " << d << " constraints " << count);
    const std::optional<double> expected = brute_force_optimum(d, constraints, c, 3);
    const std::optional<std::array<double, 4>> found = kernel_detail::maximize_in_box(d, constraints, c, 3, 1e-12);
    REQUIRE(found.has_value() == expected.has_value());
    if (!found) {
      ++infeasible;
      continue;
    }
    ++feasible;
    double value = 0;
    for (int j = 0; j < d; ++j) {
      value += c[j] * (*found)[j];
      CHECK(std::fabs((*found)[j]) <= 3 + 1e-9);
    }
    CHECK(value == Approx(*expected).margin(1e-7));
    for (const HalfSpace& h : constraints) {
      double lhs = 0;
      for (int j = 0; j < d; ++j) lhs += h.a[j] * (*found)[j];
      CHECK(lhs <= h.b + 1e-7);
    }
  }
  // Both kinds met, so neither branch passes vacuously.
  CHECK(feasible > 200);
  CHECK(infeasible > 10);
}

TEST_CASE("deepest_inner_point proposes a centre the exact certificate accepts where the cheap centres fail",
          "[certify][property]") {
  // A box's deepest point is its centre.
  const Mesh cube = box({1, 2, 3}, {3, 4, 5});
  const std::optional<Vec3> centre = kernel_detail::deepest_inner_point(cube);
  REQUIRE(centre.has_value());
  CHECK(centre->x == Approx(2).margin(1e-9));
  CHECK(centre->y == Approx(3).margin(1e-9));
  CHECK(centre->z == Approx(4).margin(1e-9));
  // A torus has an empty kernel; a mesh turned inside out has none either.
  CHECK_FALSE(kernel_detail::deepest_inner_point(torus(3, 1, 16, 8)).has_value());
  CHECK_FALSE(kernel_detail::deepest_inner_point(flipped(ellipsoid({0, 0, 0}, {1, 2, 3}, 12, 8))).has_value());
  CHECK_FALSE(kernel_detail::deepest_inner_point(Mesh{}).has_value());

  // Hourglasses: a sphere's vertices moved along their rays, far out above,
  // close in around the waist, in between below (each with some jitter). Star-
  // shaped around the origin by construction, but the big upper lobe draws the
  // vertex average and the volume centroid up, where the lower lobe's shoulder
  // hides part of it: neither cheap centre certifies most of them.
  const Mesh sphere = ellipsoid({0, 0, 0}, {1, 1, 1}, 24, 16);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> jitter(0.9, 1.1), upper(3, 8), waist(0.3, 0.6), lower(0.8, 1.6);
  std::size_t proposed = 0, cheap_centres_fail = 0;
  for (int round = 0; round < 60; ++round) {
    const double top = upper(random), middle = waist(random), bottom = lower(random);
    std::vector<double> factors(sphere.positions.size());
    for (std::size_t v = 0; v < factors.size(); ++v) {
      const double z = sphere.positions[v].z;
      factors[v] = (z > 0.5 ? top : z < -0.5 ? bottom : middle) * jitter(random);
    }
    const Mesh mesh = radially_scaled(sphere, factors);
    INFO("round " << round);
    REQUIRE(certify_star_shaped(mesh, {0, 0, 0}));
    const std::optional<Vec3> deepest = kernel_detail::deepest_inner_point(mesh);
    if (!deepest) continue;
    ++proposed;
    // The proposal is tested exactly; it is strictly inside the kernel here.
    CHECK(certify_star_shaped(mesh, *deepest));
    CHECK(certify_piece(mesh));
    const MassProperties mass = mass_properties(mesh);
    if (!certify_star_shaped(mesh, vertex_average(mesh)) && !certify_star_shaped(mesh, mass.centroid)) {
      ++cheap_centres_fail;
    }
  }
  INFO(proposed << " proposed, " << cheap_centres_fail << " of them certified by neither cheap centre");
  // Measured 2026-12-06: a centre proposed for 60 of 60, none of which either
  // cheap centre certifies; floors below that, so the property is not vacuous.
  CHECK(proposed >= 55);
  CHECK(cheap_centres_fail >= 40);
}
