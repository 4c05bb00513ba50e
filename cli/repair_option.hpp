#pragma once
// `--repair` on validate, slice and fracture: one way to run repair_mesh and to
// say what it changed, shared by main.cpp and tree_commands.cpp. Without the flag
// none of this runs, and a command never changes its input.

#include <nlohmann/json.hpp>

#include <iostream>
#include <optional>
#include <string>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter::cli {

/// The --help text of the flag, with the command's own consequence appended.
inline std::string repair_flag_help(const std::string& then) {
  return "Repair the mesh before using it, printing each change on stderr (`repair: ...`): merge vertices at "
         "equal positions, remove repeated-vertex, duplicate and zero-area triangles, orient consistently and "
         "outward, stitch and fill holes of up to " +
         std::to_string(RepairOptions{}.max_hole_edges) +
         " edges; self-intersections are named, not resolved. A mesh still invalid after repair is refused as "
         "without the flag. " +
         then;
}

inline std::string_view repair_kind_name(RepairKind kind) {
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
  }
  return "unknown";
}

/// Repairs `mesh` with the default options and prints one stderr line per change
/// and per step not done ("repair: not done: ..."), or "repair: no change". The
/// lines go to stderr in every mode, so a run that then refuses the mesh (no JSON
/// printed) still shows what was done.
inline RepairReport repair_and_print(Mesh& mesh, const std::string& name) {
  const RepairReport report = repair_mesh(mesh);
  if (!report.changed() && report.notes.empty()) std::cerr << "repair: " << name << ": no change\n";
  for (const RepairChange& change : report.changes) std::cerr << "repair: " << change.text << '\n';
  for (const RepairNote& note : report.notes) std::cerr << "repair: not done: " << note.text << '\n';
  return report;
}

/// The input check of slice and fracture: with `repair`, repairs the mesh
/// (printing each change) and returns the report; then refuses a mesh that is not
/// a valid solid with InvalidMeshError, marked "(after --repair)" when repaired.
inline std::optional<RepairReport> repair_if_asked_then_require_valid(Mesh& mesh, const std::string& name, bool repair,
                                                                       bool allow_self_intersections) {
  if (!repair) {
    require_valid_solid(mesh, name, allow_self_intersections);
    return std::nullopt;
  }
  RepairReport report = repair_and_print(mesh, name);
  try {
    require_valid_solid(mesh, name, allow_self_intersections);
  } catch (const InvalidMeshError& e) {
    throw InvalidMeshError(std::string(e.what()) + " (after --repair)");
  }
  return report;
}

/// The `"repair"` array of a command's JSON output: one object per change.
inline nlohmann::ordered_json repair_changes_json(const RepairReport& report) {
  nlohmann::ordered_json changes = nlohmann::ordered_json::array();
  for (const RepairChange& change : report.changes) {
    changes.push_back({{"change", repair_kind_name(change.kind)}, {"count", change.count}, {"text", change.text}});
  }
  return changes;
}

/// The `"repair_not_done"` array: what repair attempted but could not do.
inline nlohmann::ordered_json repair_notes_json(const RepairReport& report) {
  nlohmann::ordered_json notes = nlohmann::ordered_json::array();
  for (const RepairNote& note : report.notes) notes.push_back(note.text);
  return notes;
}

}  // namespace shatter::cli
