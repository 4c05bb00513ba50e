#pragma once
// Mass properties of a closed, oriented triangle mesh, by the divergence theorem
// (exact polynomial integrals over the enclosed volume, unit density).

#include <array>
#include <span>

#include "shatter/kernel/mesh.hpp"

namespace shatter {

struct MassProperties {
  double volume = 0;  ///< signed: negative when the faces point inward
  Vec3 centroid;      ///< centre of mass (of volume)
  /// Inertia tensor about the centroid for unit density, row-major 3x3, symmetric:
  /// I = integral of (|r|^2 Id - r r^T), so the diagonal holds the moments of
  /// inertia and the off-diagonal entries the negated products of inertia.
  /// For a flat (zero-volume) mesh the centroid is the first vertex.
  std::array<double, 9> inertia{};
};

/// Volume, centroid and inertia tensor of the solid the mesh bounds.
/// Preconditions: closed and consistently oriented (validate_mesh); otherwise the
/// numbers are meaningless but finite for finite input. Evaluated relative to the
/// first vertex, so far-from-origin meshes keep their precision, and, for a mesh
/// far from unit size (beyond 2^60 or below 2^-60 across), in coordinates scaled
/// by a power of two, so that a value is lost (0, or infinite) only where it is
/// itself beyond the range of doubles (the volume grows as the size cubed, the
/// inertia as its fifth power); within that size the results are the unscaled
/// computation's, bit for bit.
MassProperties mass_properties(const Mesh& mesh);

/// The same for a closed oriented surface given as positions and triangles over
/// them (the triangles may be any oriented decomposition of the surface, e.g. fans
/// of polygon faces including flat ones). Same preconditions.
MassProperties mass_properties(std::span<const Vec3> positions, std::span<const Triangle> triangles);

/// Signed volume only (cheaper). Same preconditions.
double signed_volume(const Mesh& mesh);

}  // namespace shatter

namespace shatter {

/// The sign of the enclosed volume, decided exactly (floating-point filter, GMP
/// fallback): positive for an outward-oriented closed mesh, negative for an
/// inward one (a cavity), zero only for a degenerate (flat) one. It is the exact
/// sign of the sum over triangles of det(a, b, c); an empty mesh gives zero.
/// Throws InvalidMeshError on a non-finite coordinate; skips triangles whose
/// indices are out of range.
Sign signed_volume_sign(const Mesh& mesh);

}  // namespace shatter
