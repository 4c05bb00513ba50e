#include "validate.hpp"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <optional>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"
#include "errors.hpp"
#include "input.hpp"
#include "output_transaction.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

using json = nlohmann::ordered_json;

// validate_mesh finds no defect in a mesh with no triangles, but no triangles is no
// solid: the readers refuse such a file, and --repair can leave one (a mesh made
// only of degenerate triangles, or of triangles back to back with reversed copies).
constexpr const char* empty_after_repair = "no triangle left after --repair (the input encloses no volume)";

// The exact step of --repair found the surface encloses no volume (a flat or
// back-to-back surface): that, not the self-intersections it leaves, is why no
// repair makes a solid of it.
bool encloses_no_volume(const ValidatedMesh& checked) {
  return checked.input.repair && checked.input.repair->encloses_no_volume() &&
         (!checked.report.valid() || checked.input.mesh.triangles.empty());
}

bool is_valid_solid(const ValidatedMesh& checked) {
  return checked.report.valid() && !checked.input.mesh.triangles.empty();
}

json defects_json(const ValidatedMesh& checked) {
  json defects = json::array();
  if (checked.input.mesh.triangles.empty()) defects.push_back({{"defect", "empty"}, {"count", 0}, {"first", empty_after_repair}});
  if (encloses_no_volume(checked)) defects.push_back({{"defect", "no volume"}, {"count", 0}, {"first", checked.input.repair->no_volume_reason}});
  for (const Defect& d : checked.report.defects) {
    defects.push_back({{"defect", defect_name(d.kind)}, {"count", d.count}, {"first", d.first}});
  }
  return defects;
}

void print_json(const ValidateArgs& args, const ValidatedMesh& checked) {
  const ValidationReport& report = checked.report;
  json out{{"file", args.mesh},
           {"vertices", report.vertex_count},
           {"triangles", report.triangle_count},
           {"valid", is_valid_solid(checked)},
           {"self_intersections_checked", report.self_intersections_checked},
           {"defects", defects_json(checked)}};
  out["read_warnings"] = checked.input.read_warnings;
  if (checked.input.repair) add_repair_json(out, *checked.input.repair);
  if (is_valid_solid(checked)) {
    const MassProperties mass = mass_properties(checked.input.mesh);
    out["volume"] = mass.volume;
    out["centroid"] = {mass.centroid.x, mass.centroid.y, mass.centroid.z};
  }
  std::cout << json_text(out, 2) << '\n';
}

void print_text(const ValidateArgs& args, const ValidatedMesh& checked) {
  const ValidationReport& report = checked.report;
  if (is_valid_solid(checked)) {
    std::cout << args.mesh << ": valid closed oriented 2-manifold, " << report.vertex_count << " vertices, "
              << report.triangle_count << " triangles, volume " << signed_volume(checked.input.mesh) << '\n';
    return;
  }
  std::cout << args.mesh << ": " << report.vertex_count << " vertices, " << report.triangle_count << " triangles\n";
  if (checked.input.mesh.triangles.empty()) std::cout << "  empty: " << empty_after_repair << '\n';
  if (encloses_no_volume(checked)) std::cout << "  no volume: " << checked.input.repair->no_volume_reason << '\n';
  for (const Defect& d : report.defects) {
    std::cout << "  " << defect_name(d.kind) << ": " << d.count << ", first " << d.first << '\n';
  }
}

}  // namespace

Command add_validate_command(CLI::App& app) {
  auto args = std::make_shared<ValidateArgs>();
  CLI::App* command = app.add_subcommand(
      "validate", "Check that a mesh is a closed, oriented 2-manifold solid; name every defect with its count and "
                  "first element. Exit 3 if it is not.");
  command->add_option("mesh", args->mesh, "Mesh file (.off, .obj, .ply, .stl)")->required();
  command->add_flag("--json", args->json, "Print the report as JSON");
  command->add_flag("--repair", args->repair,
                    repair_flag_help("The report is then of the repaired mesh (JSON: \"repair\" lists the "
                                     "changes, \"repair_not_done\" what could not be done)."));
  command->add_option("--out", args->out,
                      "With --repair: write the repaired mesh to this file (format from its extension: .off, "
                      ".obj, .ply, .stl), atomically, only if it is valid");
  return {command, [args] { return run_validate(*args); }};
}

int run_validate(const ValidateArgs& args) {
  std::optional<MeshFormat> out_format;
  if (!args.out.empty()) {
    if (!args.repair) throw UsageError("--out writes the repaired mesh: it needs --repair");
    out_format = format_from_extension(args.out);
    if (!out_format) throw UsageError("--out " + args.out + ": the extension must be .off, .obj, .ply or .stl");
  }
  const ValidatedMesh checked = read_and_validate(args.mesh, args.repair);
  if (args.json) {
    print_json(args, checked);
  } else {
    print_text(args, checked);
  }
  // Named first: no repair makes a solid of it, whatever else is wrong.
  if (encloses_no_volume(checked)) {
    throw InvalidMeshError(no_volume_refusal(args.mesh, *checked.input.repair,
                                             checked.input.mesh.triangles.empty() ? std::string("no triangle")
                                                                                  : checked.report.summary()));
  }
  if (checked.input.mesh.triangles.empty()) {
    throw InvalidMeshError("invalid mesh " + args.mesh + ": empty: " + empty_after_repair);
  }
  if (!checked.report.valid()) {
    throw InvalidMeshError("invalid mesh " + args.mesh + (checked.input.repair ? " after --repair: " : ": ") +
                           checked.report.summary());
  }
  if (out_format) {
    OutputTransaction output;
    output.write_mesh(args.out, checked.input.mesh, *out_format);
    output.commit();
    if (!args.json) std::cout << "wrote " << args.out << '\n';
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
