#pragma once
// What both benchmarks share: the peer's mesh type and conversion, the median of
// repeated timings, and number formatting for the Markdown tables.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <cstdint>
#include <string>
#include <vector>

#include "shatter/kernel/mesh.hpp"

namespace shatter::bench {

using Epick = CGAL::Epick;
/// The peer's mesh: CGAL's Surface_mesh over doubles with exact predicates.
using CgalMesh = CGAL::Surface_mesh<Epick::Point_3>;

/// The same triangles as a Surface_mesh. Throws std::runtime_error when a face
/// cannot be added (the mesh is not an oriented 2-manifold).
CgalMesh to_cgal(const Mesh& mesh);

/// The median; `empty_value` when there is nothing to take it of.
double median(std::vector<double> values, double empty_value);

/// `value` with `digits` digits after the point, never in exponent form.
std::string fixed(double value, int digits);

/// 65536 -> "65,536".
std::string with_thousands(std::uint64_t value);

}  // namespace shatter::bench
