#include "repair_touching.hpp"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "shatter/kernel/non_manifold.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/self_intersections.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter::kernel_detail {
namespace {

// Edges used by more than two triangles.
std::size_t count_crowded_edges(const Mesh& mesh) {
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    for (int c = 0; c < 3; ++c) {
      const VertexIndex a = t[c], b = t[(c + 1) % 3];
      keys.push_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  }
  std::sort(keys.begin(), keys.end());
  std::size_t crowded = 0;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    crowded += j - i > 2 ? 1 : 0;
    i = j;
  }
  return crowded;
}

// Six times the signed volume of the tetrahedron (origin, a, b, c), exactly.
mpq_class six_volume(const Vec3& a, const Vec3& b, const Vec3& c) {
  const mpq_class ax(a.x), ay(a.y), az(a.z), bx(b.x), by(b.y), bz(b.z), cx(c.x), cy(c.y), cz(c.z);
  return ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
}

// How a copy moves into its own wedge: the way its edges point on average (into
// a convex corner), or against its fan's area-weighted normal (into the solid
// when the corner is not convex and the mean of the edges leaves it).
enum class Heading { mean_edge, inward_normal };

}  // namespace

TouchingSeparation separate_touching_parts(Mesh& mesh, double scale) {
  TouchingSeparation result;
  const std::size_t crowded = count_crowded_edges(mesh);
  const std::optional<std::vector<std::uint32_t>> partner = pair_around_non_manifold_edges(mesh);
  if (!partner) {
    result.failure = "did not split " + std::to_string(crowded) + (crowded == 1 ? " edge" : " edges") +
                     " with more than two triangles: around one, the triangles do not alternate in direction or "
                     "two share an angle, so they cannot be paired into wedges";
    return result;
  }
  Mesh work = mesh;
  const std::vector<VertexFan> fans = split_vertex_fans(work, *partner);
  if (fans.empty()) {
    if (crowded > 0) result.failure = "the triangles paired around edges with more than two triangles left no vertex to split";
    return result;
  }
  result.edges = crowded;
  for (const VertexFan& fan : fans) (fan.vertex == fan.split_from ? result.vertices : result.copies) += 1;
  if (!is_closed_oriented_manifold(work)) {
    result.failure = "splitting " + std::to_string(result.vertices) +
                     (result.vertices == 1 ? " vertex" : " vertices") +
                     " into one per fan left an edge or vertex that is still not manifold";
    return result;
  }

  // The copies that move (every fan but a vertex's first), and for each triangle
  // the moving copies at its corners.
  std::vector<const VertexFan*> moving;
  for (const VertexFan& fan : fans) {
    if (fan.vertex != fan.split_from) moving.push_back(&fan);
  }
  std::vector<std::vector<std::uint32_t>> movers_of(work.triangles.size());
  for (std::uint32_t k = 0; k < moving.size(); ++k) {
    for (const std::uint32_t corner : moving[k]->corners) movers_of[corner / 3].push_back(k);
  }
  std::vector<std::uint32_t> touched;  // triangles with a moving corner
  for (std::uint32_t t = 0; t < work.triangles.size(); ++t) {
    if (!movers_of[t].empty()) touched.push_back(t);
  }

  std::vector<Heading> heading(moving.size(), Heading::mean_edge);
  for (int attempt = 0; attempt < 2; ++attempt) {
    for (const VertexFan* fan : moving) work.positions[fan->vertex] = mesh.positions[fan->split_from];
    std::vector<std::uint8_t> bad(moving.size(), 0);
    double bound = 0, largest = 0;
    for (std::uint32_t k = 0; k < moving.size(); ++k) {
      const VertexFan& fan = *moving[k];
      const Vec3 p = work.positions[fan.vertex];
      Vec3 mean_edge, normal_sum;
      double nearest = INFINITY, area = 0;
      for (const std::uint32_t corner : fan.corners) {
        const Triangle& t = work.triangles[corner / 3];
        const Vec3 b = work.positions[t[(corner + 1) % 3]] - p, c = work.positions[t[(corner + 2) % 3]] - p;
        for (const Vec3& d : {b, c}) {
          const double length = norm(d);
          if (length > 0) mean_edge = mean_edge + d * (1 / length), nearest = std::min(nearest, length);
        }
        normal_sum = normal_sum + cross(b, c);
        area += 0.5 * norm(cross(b, c));
      }
      const Vec3 direction = heading[k] == Heading::mean_edge ? mean_edge : -normal_sum;
      const double length = norm(direction);
      if (!(length > 0) || !std::isfinite(length) || !std::isfinite(nearest)) {
        bad[k] = 1;
        continue;
      }
      const double distance = scale * nearest;
      const Vec3 moved = p + direction * (distance / length);
      if (moved == p) {  // a move below the coordinates' resolution
        bad[k] = 1;
        continue;
      }
      work.positions[fan.vertex] = moved;
      bound += distance * area / 3;
      largest = std::max(largest, distance);
    }
    // Every moved triangle keeps a shape, and none meets another beyond the
    // indices they share (the parts no longer touch, nothing new crosses).
    bool shaped = true;
    for (const std::uint32_t t : touched) {
      const Triangle& tri = work.triangles[t];
      if (!collinear(work.positions[tri[0]], work.positions[tri[1]], work.positions[tri[2]])) continue;
      shaped = false;
      for (const std::uint32_t k : movers_of[t]) bad[k] = 1;
    }
    if (shaped) {
      for (const TrianglePair& pair : self_intersecting_pairs(work.positions, work.triangles)) {
        for (const std::size_t t : {pair.first, pair.second}) {
          for (const std::uint32_t k : movers_of[t]) bad[k] = 1;
        }
      }
    }
    if (std::find(bad.begin(), bad.end(), 1) == bad.end()) {
      mpq_class six_change = 0;
      for (const std::uint32_t t : touched) {
        const Triangle& after = work.triangles[t];
        const Triangle& before = mesh.triangles[t];
        six_change += six_volume(work.positions[after[0]], work.positions[after[1]], work.positions[after[2]]) -
                      six_volume(mesh.positions[before[0]], mesh.positions[before[1]], mesh.positions[before[2]]);
      }
      result.separated = true;
      result.volume_change = mpq_class(six_change / 6).get_d();
      result.volume_bound = bound;
      result.largest_move = largest;
      mesh = std::move(work);
      return result;
    }
    bool retry = false;
    for (std::uint32_t k = 0; k < moving.size(); ++k) {
      if (!bad[k]) continue;
      if (heading[k] == Heading::inward_normal) {
        retry = false;
        break;
      }
      heading[k] = Heading::inward_normal;
      retry = true;
    }
    if (!retry) break;
  }
  result.failure = "did not separate the parts touching at " + std::to_string(result.vertices) +
                   (result.vertices == 1 ? " vertex" : " vertices") +
                   ": moving a copy into its own wedge made triangles cross or lose their shape";
  result.separated = false;
  return result;
}

}  // namespace shatter::kernel_detail
