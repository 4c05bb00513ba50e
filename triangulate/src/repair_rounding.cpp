// The rounding repair's exact self-intersection step asks for
// (RepairOptions::round_solid): round_solid under the kernel's hook type.
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter {

RepairRounding round_repaired_solid(const PlaneSet& set, const Solid& solid, const Mesh& attributes) {
  SolidMeshOptions options;
  options.attributes = &attributes;
  RoundedSolid rounded = round_solid(set, solid, options);
  RepairRounding out;
  out.valid = rounded.valid && !rounded.collapsed && !rounded.mesh.triangles.empty();
  out.defect = rounded.collapsed ? "the solid is thinner than its rounding" : rounded.defect;
  out.moved_volume = rounded.moved_volume;
  out.moved_volume_bound = rounded.moved_volume_bound;
  out.separated_vertices = rounded.separated_vertices;
  out.mesh = std::move(rounded.mesh);
  return out;
}

}  // namespace shatter
