#pragma once
// The mass properties every node of a tree stores, for both builders (build.cpp,
// voronoi.cpp): the tree checker asks of each a positive, finite volume and
// finite moments, which doubles cannot give a solid of any size.

#include <string_view>

#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::detail {

/// Refuses, with UnsupportedGeometryError, an input whose bounding box is wider
/// than 2^200 (about 1.6e60): its moments of inertia grow as the fifth power of
/// its size and could overflow. Decided on the coordinates alone, before any
/// arithmetic that could overflow. Non-finite positions are passed over (the
/// input check names them).
void require_fracturable_extent(const Mesh& mesh);

/// Whether mass properties are what the tree checker accepts of a node: a
/// positive, finite volume, a finite centroid and finite moments.
bool storable_mass(const MassProperties& mass);

/// Throws UnsupportedGeometryError, naming `what` ("the solid", "a fragment"),
/// when mass properties are not what the tree checker accepts of a node (a
/// positive, finite volume, a finite centroid and inertia): a solid or a
/// fragment too small for its volume to be a positive double (about 1e-108
/// across). Nothing is written then.
void require_representable_mass(const MassProperties& mass, std::string_view what);

}  // namespace shatter::detail
