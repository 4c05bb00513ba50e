#include "shatter/meshtree/sites.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/inside.hpp"
#include "shatter/meshtree/recipe.hpp"

namespace shatter {

namespace {

class Draws {
 public:
  explicit Draws(std::uint64_t seed) : state_(seed) {}
  /// Uniform in [0, 1).
  double unit() { return static_cast<double>(splitmix64(state_) >> 11) * 0x1p-53; }
  /// Uniform in [-1, 1).
  double symmetric() { return 2 * unit() - 1; }

 private:
  std::uint64_t state_;
};

struct Bounds {
  Vec3 lo, hi;
};

Bounds bounds_of(const Mesh& mesh) {
  if (mesh.positions.empty()) throw std::invalid_argument("site patterns need a mesh with vertices");
  Bounds b{mesh.positions.front(), mesh.positions.front()};
  for (const Vec3& p : mesh.positions) {
    b.lo = {std::min(b.lo.x, p.x), std::min(b.lo.y, p.y), std::min(b.lo.z, p.z)};
    b.hi = {std::max(b.hi.x, p.x), std::max(b.hi.y, p.y), std::max(b.hi.z, p.z)};
  }
  return b;
}

std::vector<Vec3> inside_points(const Mesh& mesh, std::uint32_t count, Draws& draws) {
  const Bounds b = bounds_of(mesh);
  const PointInSolid inside(mesh);
  std::vector<Vec3> points;
  points.reserve(count);
  const std::uint64_t limit = 1000 * std::uint64_t{count} + 1000;
  for (std::uint64_t tries = 0; points.size() < count; ++tries) {
    if (tries == limit) {
      throw UnsupportedGeometryError("drew " + std::to_string(limit) + " points in the bounding box and only " +
                                     std::to_string(points.size()) + " fell inside the solid");
    }
    const Vec3 p{b.lo.x + draws.unit() * (b.hi.x - b.lo.x), b.lo.y + draws.unit() * (b.hi.y - b.lo.y),
                 b.lo.z + draws.unit() * (b.hi.z - b.lo.z)};
    if (inside.strictly_inside(p)) points.push_back(p);
  }
  return points;
}

// sin and cos of x in [0, 2 pi) from + - * / only (range reduction to
// |r| <= pi / 4, then Taylor series to x^21: error below 1e-16), so every
// machine gets the same bits (a library sin may differ between machines).
void deterministic_sincos(double x, double& sine, double& cosine) {
  constexpr double half_pi = 1.5707963267948966;
  const double quarter_turns = std::nearbyint(x / half_pi);
  const double r = x - quarter_turns * half_pi;
  const double r2 = r * r;
  double s = 0, c = 0, term_s = r, term_c = 1;
  for (int k = 1; k <= 11; ++k) {
    s += term_s;
    c += term_c;
    term_s = -term_s * r2 / ((2.0 * k) * (2.0 * k + 1));
    term_c = -term_c * r2 / ((2.0 * k - 1) * (2.0 * k));
  }
  switch (static_cast<int>(quarter_turns) & 3) {
    case 0: sine = s, cosine = c; break;
    case 1: sine = c, cosine = -s; break;
    case 2: sine = -s, cosine = -c; break;
    default: sine = -c, cosine = s; break;
  }
}

bool positive_finite(double value) { return value > 0 && std::isfinite(value); }

}  // namespace

std::vector<Vec3> uniform_sites(const Mesh& mesh, std::uint32_t count, std::uint64_t seed) {
  if (count == 0) throw std::invalid_argument("uniform_sites: count must be at least 1");
  Draws draws(seed);
  return inside_points(mesh, count, draws);
}

std::vector<Vec3> clustered_sites(const Mesh& mesh, std::uint32_t clusters, std::uint32_t per_cluster, double radius,
                                  std::uint64_t seed) {
  if (clusters == 0 || per_cluster == 0) throw std::invalid_argument("clustered_sites: counts must be at least 1");
  if (!positive_finite(radius)) throw std::invalid_argument("clustered_sites: the radius must be positive and finite");
  Draws draws(seed);
  const std::vector<Vec3> centres = inside_points(mesh, clusters, draws);
  std::vector<Vec3> sites;
  sites.reserve(std::size_t{clusters} * per_cluster);
  for (const Vec3& centre : centres) {
    for (std::uint32_t i = 0; i < per_cluster;) {
      const Vec3 v{draws.symmetric(), draws.symmetric(), draws.symmetric()};
      if (dot(v, v) > 1) continue;  // uniform in the ball: rejection from the cube
      sites.push_back(centre + v * radius);
      ++i;
    }
  }
  return sites;
}

std::vector<Vec3> radial_sites(const Vec3& centre, const Vec3& direction, std::uint32_t rings, std::uint32_t sectors,
                               double radius, double variability, std::uint64_t seed) {
  if (rings == 0 || sectors == 0) throw std::invalid_argument("radial_sites: rings and sectors must be at least 1");
  // Divided by its largest component before its length is taken: the squares
  // of a direction like 1e-200,0,1e-200 underflow to zero and of 1e200,0,0
  // overflow, though any finite non-zero direction names a plane.
  const double largest = std::max({std::fabs(direction.x), std::fabs(direction.y), std::fabs(direction.z)});
  if (!positive_finite(largest)) throw std::invalid_argument("radial_sites: the direction must be non-zero and finite");
  const Vec3 scaled{direction.x / largest, direction.y / largest, direction.z / largest};
  const double length = std::sqrt(dot(scaled, scaled));
  if (!positive_finite(radius)) throw std::invalid_argument("radial_sites: the radius must be positive and finite");
  if (!(variability >= 0 && variability <= 1)) throw std::invalid_argument("radial_sites: variability must be in [0, 1]");
  const Vec3 n = scaled * (1 / length);
  // A frame (u, v) of the plane: u across the smallest component of n.
  const Vec3 axis = std::fabs(n.x) <= std::fabs(n.y) && std::fabs(n.x) <= std::fabs(n.z) ? Vec3{1, 0, 0}
                    : std::fabs(n.y) <= std::fabs(n.z)                                     ? Vec3{0, 1, 0}
                                                                                           : Vec3{0, 0, 1};
  Vec3 u = cross(n, axis);
  u = u * (1 / std::sqrt(dot(u, u)));
  const Vec3 v = cross(n, u);
  constexpr double two_pi = 6.283185307179586;
  Draws draws(seed);
  std::vector<Vec3> sites{centre};
  for (std::uint32_t ring = 1; ring <= rings; ++ring) {
    const double t = static_cast<double>(ring) / rings, t_inner = static_cast<double>(ring - 1) / rings;
    const double r = radius * t * t;
    const double spacing = radius * (t * t - t_inner * t_inner);
    for (std::uint32_t sector = 0; sector < sectors; ++sector) {
      double turn = (sector + 0.5 * (ring - 1) + variability * 0.5 * draws.symmetric()) / sectors;
      turn -= std::floor(turn);
      const double rr = r + variability * 0.5 * spacing * draws.symmetric();
      double s, c;
      deterministic_sincos(turn * two_pi, s, c);
      sites.push_back(centre + u * (rr * c) + v * (rr * s));
    }
  }
  return sites;
}

std::vector<Vec3> grid_sites(const Mesh& mesh, std::array<std::uint32_t, 3> cells, bool brick, double offset,
                             double jitter, std::uint64_t seed) {
  if (cells[0] == 0 || cells[1] == 0 || cells[2] == 0) throw std::invalid_argument("grid_sites: cell counts must be at least 1");
  if (!(offset >= -1 && offset <= 1)) throw std::invalid_argument("grid_sites: offset must be in [-1, 1]");
  if (!(jitter >= 0 && jitter <= 1)) throw std::invalid_argument("grid_sites: jitter must be in [0, 1]");
  const Bounds b = bounds_of(mesh);
  const Vec3 size{(b.hi.x - b.lo.x) / cells[0], (b.hi.y - b.lo.y) / cells[1], (b.hi.z - b.lo.z) / cells[2]};
  Draws draws(seed);
  std::vector<Vec3> sites;
  sites.reserve(std::size_t{cells[0]} * cells[1] * cells[2]);
  for (std::uint32_t k = 0; k < cells[2]; ++k) {
    for (std::uint32_t j = 0; j < cells[1]; ++j) {
      for (std::uint32_t i = 0; i < cells[0]; ++i) {
        Vec3 shift{offset, offset, offset};
        if (brick) shift = {((j + k) % 2 == 1) ? offset : 0.0, 0, 0};
        const Vec3 p{b.lo.x + (i + 0.5 + shift.x + 0.5 * jitter * draws.symmetric()) * size.x,
                     b.lo.y + (j + 0.5 + shift.y + 0.5 * jitter * draws.symmetric()) * size.y,
                     b.lo.z + (k + 0.5 + shift.z + 0.5 * jitter * draws.symmetric()) * size.z};
        sites.push_back(p);
      }
    }
  }
  return sites;
}

std::vector<Vec3> read_sites_file(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) throw IoError("cannot read the sites file " + path.string());
  std::vector<Vec3> sites;
  std::string line;
  std::size_t number = 0;
  while (std::getline(file, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    double values[3];
    const char* at = line.data() + first;
    const char* end = line.data() + line.size();
    int read = 0;
    for (; read < 3; ++read) {
      while (at < end && (*at == ' ' || *at == '\t')) ++at;
      if (at < end && *at == '+') ++at;  // from_chars takes no plus sign
      const auto [next, error] = std::from_chars(at, end, values[read]);
      if (error != std::errc() || !std::isfinite(values[read]) || (next < end && *next != ' ' && *next != '\t')) break;
      at = next;
    }
    while (at < end && (*at == ' ' || *at == '\t')) ++at;
    if (read < 3 || at != end) {
      const std::string shown = line.size() > 60 ? line.substr(0, 60) + "..." : line;
      throw CorruptFileError(path.string() + " line " + std::to_string(number) +
                             ": expected three finite numbers \"x y z\", got \"" + shown + "\"");
    }
    sites.push_back({values[0], values[1], values[2]});
  }
  if (file.bad()) throw IoError("cannot read the sites file " + path.string());
  if (sites.empty()) throw CorruptFileError(path.string() + " line " + std::to_string(number) + ": no sites in the file");
  return sites;
}

}  // namespace shatter
