#include "input.hpp"

#include <iostream>
#include <string_view>

#include "shatter/cut/plane_input.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter::cli {

namespace {

// The lines go to stderr in every mode, JSON included, so a run that then
// refuses the mesh (and prints no JSON) still shows what was done.
RepairReport repair_and_print(Mesh& mesh, const std::string& name) {
  RepairOptions options;
  options.round_solid = round_repaired_solid;
  const RepairReport report = repair_mesh(mesh, options);
  if (!report.changed() && report.notes.empty()) std::cerr << "repair: " << name << ": no change\n";
  for (const RepairChange& change : report.changes) std::cerr << "repair: " << change.text << '\n';
  for (const RepairNote& note : report.notes) std::cerr << "repair: not done: " << note.text << '\n';
  return report;
}

// Reads `path`, printing each of the reader's warnings on stderr (in every mode,
// JSON included, as the repair lines are).
InputMesh read_input(const std::string& path) {
  InputMesh input;
  input.mesh = read_mesh(path, &input.read_warnings);
  for (const std::string& warning : input.read_warnings) std::cerr << "warning: " << path << ": " << warning << '\n';
  return input;
}

}  // namespace

std::string repair_flag_help(const std::string& then) {
  return "Repair the mesh before using it, printing each change on stderr (`repair: ...`): merge vertices at "
         "equal positions, remove repeated-vertex, duplicate and zero-area triangles, orient consistently and "
         "outward, stitch and fill every hole (over its own vertices, whatever its size), then resolve "
         "self-intersections exactly (the surface split along its intersections, the solid it winds around at "
         "least once kept, rounded and certified once). A mesh still invalid after repair is refused as "
         "without the flag. " +
         then;
}

std::string no_volume_refusal(const std::string& path, const RepairReport& report, const std::string& defects) {
  return "invalid mesh " + path + " after --repair: encloses no volume: " + report.no_volume_reason + " (what is left: " +
         defects + ")";
}

namespace {

InputMesh read_and_repair(const std::string& path, bool repair) {
  InputMesh input = read_input(path);
  if (repair) input.repair = repair_and_print(input.mesh, path);
  return input;
}

// read_valid_solid's check of a mesh read, and repaired when input.repair says so.
void require_valid_input(const InputMesh& input, const std::string& path, bool allow_self_intersections) {
  if (!input.repair) {
    require_valid_solid(input.mesh, path, allow_self_intersections);
    return;
  }
  try {
    require_valid_solid(input.mesh, path, allow_self_intersections);
  } catch (const InvalidMeshError& e) {
    std::string message = e.what();
    if (input.repair->encloses_no_volume()) {
      // require_valid_solid's line is "invalid mesh <path>: <defects>"; only the
      // defects go into the parenthesis.
      const std::string prefix = "invalid mesh " + path + ": ";
      if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
      throw InvalidMeshError(no_volume_refusal(path, *input.repair, message));
    }
    throw InvalidMeshError(message + " (after --repair)");
  }
}

}  // namespace

InputMesh read_valid_solid(const std::string& path, bool repair, bool allow_self_intersections) {
  InputMesh input = read_and_repair(path, repair);
  require_valid_input(input, path, allow_self_intersections);
  return input;
}

PreparedSolid read_prepared_solid(const std::string& path, bool repair, bool allow_self_intersections) {
  PreparedSolid solid;
  solid.input = read_and_repair(path, repair);
  solid.plane = prepare_plane_input_beside(solid.input.mesh,
                                           [&] { require_valid_input(solid.input, path, allow_self_intersections); });
  return solid;
}

ValidatedMesh read_and_validate(const std::string& path, bool repair) {
  InputMesh input = read_input(path);
  if (repair) input.repair = repair_and_print(input.mesh, path);
  const ValidationReport report = validate_mesh(input.mesh);
  return {std::move(input), report};
}

void add_repair_json(nlohmann::ordered_json& out, const RepairReport& report) {
  nlohmann::ordered_json changes = nlohmann::ordered_json::array();
  for (const RepairChange& change : report.changes) {
    changes.push_back({{"change", repair_kind_name(change.kind)}, {"count", change.count}, {"text", change.text}});
  }
  nlohmann::ordered_json notes = nlohmann::ordered_json::array();
  for (const RepairNote& note : report.notes) notes.push_back(note.text);
  out["repair"] = std::move(changes);
  out["repair_not_done"] = std::move(notes);
}

}  // namespace shatter::cli
