#pragma once
// The whole public API of shatter::cut, one include, in pipeline order: a closed
// mesh comes in, is separated into solids and made the plane kernel's first
// solid, is cut by a plane into certified pieces, and each piece gets its hull.
//
//   input
//     separate.hpp      separate_solids: a closed triangle set into solids (shells, cavities placed exactly)
//     plane_input.hpp   prepare_plane_input: an input mesh as the plane kernel's first solid
//   cut
//     cut_solid.hpp     cut_solid: one plane cut of a plane-based solid, capped and separated
//     plane_cut.hpp     cut_by_plane, cut_mesh_by_plane: the plane kernel's one cut call, pieces certified
//   hulls
//     hull.hpp          convex_hull_of, convex_hull_of_points: canonical convex hulls, the colliders

// The includes follow the pipeline, not the alphabet.
// clang-format off
#include "shatter/cut/separate.hpp"
#include "shatter/cut/plane_input.hpp"

#include "shatter/cut/cut_solid.hpp"
#include "shatter/cut/plane_cut.hpp"

#include "shatter/cut/hull.hpp"
// clang-format on
