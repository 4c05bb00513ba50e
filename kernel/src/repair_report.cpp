// The repair report (shatter/kernel/repair.hpp) apart from the repair itself:
// the .shatter reader and writer keep a report (MeshTree::input_repair) without
// linking CGAL's repair functions (the shatter::repair library).
#include <string>
#include <string_view>

#include "shatter/kernel/repair.hpp"

namespace shatter {

const RepairChange* RepairReport::find(RepairKind kind) const {
  for (const RepairChange& c : changes) {
    if (c.kind == kind) return &c;
  }
  return nullptr;
}

std::string RepairReport::summary() const {
  if (changes.empty()) return "no change";
  std::string line;
  for (const RepairChange& c : changes) line += (line.empty() ? "" : "; ") + c.text;
  return line;
}

std::string_view repair_kind_name(RepairKind kind) {
  switch (kind) {
    case RepairKind::merged_duplicate_vertices: return "merged_duplicate_vertices";
    case RepairKind::removed_repeated_index_triangles: return "removed_repeated_index_triangles";
    case RepairKind::removed_duplicate_triangles: return "removed_duplicate_triangles";
    case RepairKind::removed_opposite_triangle_pairs: return "removed_opposite_triangle_pairs";
    case RepairKind::reversed_triangles: return "reversed_triangles";
    case RepairKind::stitched_border_edges: return "stitched_border_edges";
    case RepairKind::fixed_zero_area_triangles: return "fixed_zero_area_triangles";
    case RepairKind::filled_holes: return "filled_holes";
    case RepairKind::resolved_self_intersections: return "resolved_self_intersections";
    case RepairKind::removed_unused_vertices: return "removed_unused_vertices";
    case RepairKind::separated_touching_parts: return "separated_touching_parts";
    case RepairKind::resolved_self_intersections_exactly: return "resolved_self_intersections_exactly";
    case RepairKind::removed_flat_pieces: return "removed_flat_pieces";
    case RepairKind::split_edges_at_vertices: return "split_edges_at_vertices";
    case RepairKind::removed_hanging_triangles: return "removed_hanging_triangles";
  }
  return "unknown";
}

}  // namespace shatter
