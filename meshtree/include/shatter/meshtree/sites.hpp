#pragma once
// Site patterns for Voronoi fracture (voronoi.hpp): where the cells' sites go.
// Every pattern is a pure function of the mesh and its parameters (and seed):
// draws come from splitmix64 (recipe.hpp) and use only + - * / and sqrt, and
// the radial pattern's angles a sine and cosine made of those alone, so every
// machine draws the same sites. Lengths are in the mesh's units.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/vec.hpp"

namespace shatter {

/// `count` sites uniform in the solid's volume: points uniform in its bounding
/// box, kept when strictly inside the solid (PointInSolid, exact).
/// Precondition: a valid closed solid. Throws std::invalid_argument when count
/// is 0, or UnsupportedGeometryError when 1000 count + 1000 draws keep fewer
/// (a solid filling less than a thousandth of its box).
std::vector<Vec3> uniform_sites(const Mesh& mesh, std::uint32_t count, std::uint64_t seed);

/// `clusters` centres uniform in the solid's volume (as uniform_sites), and
/// around each `per_cluster` sites uniform in the ball of `radius` about it
/// (inside the solid or not: a site outside gives the cell around it, which may
/// still reach the solid). Throws std::invalid_argument on a zero count or a
/// radius that is not positive and finite.
std::vector<Vec3> clustered_sites(const Mesh& mesh, std::uint32_t clusters, std::uint32_t per_cluster, double radius,
                                  std::uint64_t seed);

/// A radial pattern about `centre` in the plane through it perpendicular to
/// `direction` (an impact: fine near it, coarse away): the centre, then
/// `rings` rings of `sectors` sites at radii radius (i / rings)^2 (i = 1 ..
/// rings, so rings crowd toward the centre), the sectors of ring i turned by
/// half a sector from ring i - 1; each site moved by up to `variability` (0 to 1)
/// of its ring spacing and sector width at random. All sites lie in one plane:
/// the cells are prisms through the solid along `direction`. Throws
/// std::invalid_argument on zero counts, a zero or non-finite direction, a
/// radius not positive and finite, or variability outside [0, 1].
std::vector<Vec3> radial_sites(const Vec3& centre, const Vec3& direction, std::uint32_t rings, std::uint32_t sectors,
                               double radius, double variability, std::uint64_t seed);

/// A grid of cells[0] x cells[1] x cells[2] sites over the solid's bounding box,
/// one at the centre of each cell; `brick` shifts every other row (along y, and
/// every other layer along z) by `offset` of a cell along x (bricks in a wall);
/// without it the whole lattice shifts by `offset` of a cell along every axis.
/// Each site then moves by up to `jitter` (0 to 1) of half a cell per axis at
/// random. Throws std::invalid_argument on a zero count, offset outside [-1, 1]
/// or jitter outside [0, 1].
std::vector<Vec3> grid_sites(const Mesh& mesh, std::array<std::uint32_t, 3> cells, bool brick, double offset,
                             double jitter, std::uint64_t seed);

/// Sites read from a text file: one site per line as three numbers "x y z"
/// (spaces or tabs; a blank line, or one starting with '#', is skipped).
/// Throws IoError when the file cannot be read, CorruptFileError naming the
/// file and line number of the first line that is not three finite numbers,
/// or of an empty list.
std::vector<Vec3> read_sites_file(const std::filesystem::path& path);

}  // namespace shatter
