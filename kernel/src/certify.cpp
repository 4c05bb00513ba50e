#include "shatter/kernel/certify.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>

#include "shatter/kernel/deepest_point.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/kernel/star_shaped.hpp"

namespace shatter {

namespace {

// Process-wide: the build cuts on several threads.
std::atomic<std::uint64_t> attempt_count{0}, star_count{0}, declined_count{0};

}  // namespace

CertifyCounts certify_counts() {
  return {attempt_count.load(std::memory_order_relaxed), star_count.load(std::memory_order_relaxed),
          declined_count.load(std::memory_order_relaxed)};
}

void reset_certify_counts() {
  attempt_count.store(0, std::memory_order_relaxed);
  star_count.store(0, std::memory_order_relaxed);
  declined_count.store(0, std::memory_order_relaxed);
}

bool connected_surface(const Mesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (n == 0) return false;
  thread_local UnionFind components;
  components.reset(n);
  std::size_t sets = n;
  thread_local std::vector<std::uint8_t> used;
  used.assign(n, 0);
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      used[t[k]] = 1;
      if (components.unite(t[k], t[(k + 1) % 3])) --sets;
    }
  }
  return sets == 1 && std::all_of(used.begin(), used.end(), [](std::uint8_t u) { return u != 0; });
}

namespace {

// The centres certify_piece tries, in order. Any point would do for soundness
// (the certificate is exact for whatever double point it is given); these are
// where a piece is most often seen whole: the vertex average (what the convex
// path uses) and the volume centroid, which an elongated or unevenly
// triangulated piece pulls less than its vertices do.
Vec3 vertex_average(const Mesh& mesh) {
  Vec3 sum;
  for (const Vec3& p : mesh.positions) sum = sum + p;
  return sum * (1.0 / static_cast<double>(mesh.positions.size()));
}

// The volume centroid in doubles, relative to the first vertex so a piece far
// from the origin keeps its precision; none (false) when the piece's extent is
// out of the range where these products cannot overflow (tests trap floating-
// point overflow) or its volume is not positive and above 2^-100 of its extent
// cubed as computed (a centre is only a guess: any point gives a sound test).
bool volume_centroid(const Mesh& mesh, Vec3& centroid) {
  const Vec3 origin = mesh.positions.front();
  double extent = 0;
  for (const Vec3& p : mesh.positions) {
    extent = std::max({extent, std::fabs(p.x - origin.x), std::fabs(p.y - origin.y), std::fabs(p.z - origin.z)});
  }
  if (!(extent > 0x1p-200 && extent < 0x1p200)) return false;
  double six_volume = 0;
  Vec3 moment;
  for (const Triangle& t : mesh.triangles) {
    const Vec3 a = mesh.positions[t[0]] - origin, b = mesh.positions[t[1]] - origin, c = mesh.positions[t[2]] - origin;
    const double det = dot(a, cross(b, c));
    six_volume += det;
    moment = moment + (a + b + c) * det;
  }
  if (!(six_volume > 0x1p-100 * extent * extent * extent)) return false;
  centroid = origin + moment * (1.0 / (4 * six_volume));
  return is_finite(centroid);
}

}  // namespace

bool certify_piece(const Mesh& mesh, bool topology_sound) {
  attempt_count.fetch_add(1, std::memory_order_relaxed);
  const auto decline = [] {
    declined_count.fetch_add(1, std::memory_order_relaxed);
    return false;
  };
  if (mesh.triangles.empty()) return decline();
  // Non-finite coordinates, and coordinates so large that the centres' sums could
  // overflow (tests trap it), are left to the full check. Compared quietly
  // (std::isless): `<` on a NaN raises the invalid-operation flag, which the
  // tests also trap.
  if (!std::all_of(mesh.positions.begin(), mesh.positions.end(), [](const Vec3& p) {
        return std::isless(std::fabs(p.x), 0x1p500) && std::isless(std::fabs(p.y), 0x1p500) &&
               std::isless(std::fabs(p.z), 0x1p500);
      })) {
    return decline();
  }
  // The centres and the facing test read positions before the topology check.
  const std::size_t n = mesh.positions.size();
  if (!std::all_of(mesh.triangles.begin(), mesh.triangles.end(),
                   [n](const Triangle& t) { return t[0] < n && t[1] < n && t[2] < n; })) {
    return decline();
  }
  Vec3 centres[3];
  std::size_t centre_count = 0;
  centres[centre_count++] = vertex_average(mesh);
  if (volume_centroid(mesh, centres[centre_count])) ++centre_count;
  bool topology_checked = false;
  std::optional<bool> connected;  // connected_surface, once asked
  bool deepest_tried = false;
  for (std::size_t k = 0;; ++k) {
    if (k == centre_count) {
      // Last, once the cheap centres have failed: the kernel's deepest point,
      // which a linear program finds for a piece that is star-shaped around
      // some point (most of the pieces of curved meshes they miss); O(T)
      // expected, against the full check's search.
      if (deepest_tried) break;
      deepest_tried = true;
      const std::optional<Vec3> deepest = kernel_detail::deepest_inner_point(mesh);
      if (!deepest) break;
      centres[centre_count++] = *deepest;
    }
    // A piece that is not star-shaped around the centre usually shows it within
    // a few triangles: that test goes first, so a declined piece costs little
    // before the full check.
    if (!kernel_detail::faces_away_from(mesh, centres[k])) continue;
    // The covering tests take the topology as given: it is checked here
    // unless the caller knows it sound by construction.
    if (!topology_checked) {
      if (!topology_sound && !is_closed_oriented_manifold(mesh)) return decline();
      topology_checked = true;
    }
    // One ray's count proves one component too; the walk around every vertex,
    // where the ray decides nothing, needs connectivity shown apart (two
    // star-shaped shells around one centre each wind once, yet may cross).
    std::optional<bool> once = kernel_detail::covered_once_along_a_ray(mesh, centres[k]);
    if (!once) {
      if (!connected) connected = connected_surface(mesh);
      if (!*connected) return decline();
      once = kernel_detail::winds_once_around(mesh, centres[k]);
    }
    if (*once) {
      star_count.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
  }
  return decline();
}

}  // namespace shatter
