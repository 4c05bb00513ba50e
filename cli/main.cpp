// The shatter command: parses flags, calls the libraries, prints one `error:` line
// on failure. Exit codes: 0 ok, 1 internal error, 2 usage, 3 invalid input (a mesh
// that is not a valid solid, geometry the cut refuses, a damaged .shatter file),
// 4 I/O error.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/cut.hpp"
#include "shatter/meshtree/cut_solid.hpp"
#include "shatter/meshtree/plane_input.hpp"
#include "shatter/triangulate/solid_mesh.hpp"
#include "shatter/version.hpp"
#include "repair_option.hpp"
#include "tree_commands.hpp"

namespace {

using namespace shatter;
using json = nlohmann::ordered_json;

enum ExitCode : int { ok = 0, internal_error = 1, usage_error = 2, invalid_input = 3, io_error = 4 };

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A bad mesh that the command refuses: exit 3.
struct RefusedInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

json defects_json(const ValidationReport& report) {
  json defects = json::array();
  for (const Defect& d : report.defects) {
    defects.push_back({{"defect", defect_name(d.kind)}, {"count", d.count}, {"first", d.first}});
  }
  return defects;
}

// --- validate ---------------------------------------------------------------

struct ValidateArgs {
  std::string mesh;
  bool json = false;
  bool repair = false;
  std::string out;  ///< with --repair: where to write the repaired mesh
};

int run_validate(const ValidateArgs& args) {
  std::optional<MeshFormat> out_format;
  if (!args.out.empty()) {
    if (!args.repair) throw UsageError("--out writes the repaired mesh: it needs --repair");
    out_format = format_from_extension(args.out);
    if (!out_format) throw UsageError("--out " + args.out + ": the extension must be .off, .obj, .ply or .stl");
  }
  Mesh mesh = read_mesh(args.mesh);
  std::optional<RepairReport> repair;
  if (args.repair) repair = cli::repair_and_print(mesh, args.mesh);
  const ValidationReport report = validate_mesh(mesh);
  if (args.json) {
    json out{{"file", args.mesh},
             {"vertices", report.vertex_count},
             {"triangles", report.triangle_count},
             {"valid", report.valid()},
             {"self_intersections_checked", report.self_intersections_checked},
             {"defects", defects_json(report)}};
    if (repair) {
      out["repair"] = cli::repair_changes_json(*repair);
      out["repair_not_done"] = cli::repair_notes_json(*repair);
    }
    if (report.valid()) {
      const MassProperties mass = mass_properties(mesh);
      out["volume"] = mass.volume;
      out["centroid"] = {mass.centroid.x, mass.centroid.y, mass.centroid.z};
    }
    std::cout << out.dump(2) << '\n';
  } else if (report.valid()) {
    std::cout << args.mesh << ": valid closed oriented 2-manifold, " << report.vertex_count << " vertices, "
              << report.triangle_count << " triangles, volume " << signed_volume(mesh) << '\n';
  } else {
    std::cout << args.mesh << ": " << report.vertex_count << " vertices, " << report.triangle_count
              << " triangles\n";
    for (const Defect& d : report.defects) {
      std::cout << "  " << defect_name(d.kind) << ": " << d.count << ", first " << d.first << '\n';
    }
  }
  if (!report.valid()) {
    throw RefusedInput("invalid mesh " + args.mesh + (repair ? " after --repair: " : ": ") + report.summary());
  }
  if (out_format) {
    write_mesh(mesh, args.out, *out_format);
    if (!args.json) std::cout << "wrote " << args.out << '\n';
  }
  return ok;
}

// --- slice ------------------------------------------------------------------

struct SliceArgs {
  std::string mesh;
  std::string plane;
  std::string kernel = "plane";
  bool allow_self_intersections = false;
  std::string out;
  std::string format = "off";
  double interior_uv_scale = 1.0;
  bool json = false;
  bool repair = false;
};

Plane parse_plane(const std::string& text) {
  std::vector<double> values;
  const char* p = text.data();
  const char* end = p + text.size();
  while (p < end) {
    double value = 0;
    const auto [next, error] = std::from_chars(p, end, value);
    if (error != std::errc() || !std::isfinite(value)) break;
    values.push_back(value);
    p = next;
    if (p == end) break;
    if (*p != ',') {
      values.clear();
      break;
    }
    ++p;
  }
  if (values.size() != 4 || p != end) {
    throw UsageError("--plane takes four finite numbers nx,ny,nz,d (the plane n.x + d = 0), got '" + text + "'");
  }
  const Plane plane{{values[0], values[1], values[2]}, values[3]};
  if (plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0) {
    throw UsageError("--plane normal must not be zero");
  }
  return plane;
}

std::string_view cap_method_name(CapMethod method) {
  switch (method) {
    case CapMethod::none: return "none";
    case CapMethod::fan: return "fan";
    case CapMethod::cdt: return "cdt";
    case CapMethod::exact_cdt: return "exact-cdt";
    case CapMethod::steiner_fan: return "steiner-fan";
  }
  return "unknown";
}

struct Piece {
  std::string side;
  Mesh mesh;
};

// Output is always doubles: the exact kernel's pieces are rounded once, here.
Mesh as_output(Mesh& mesh) { return std::move(mesh); }
Mesh as_output(const ExactMesh& mesh) { return to_fast(mesh); }

template <class Point>
std::vector<Piece> pieces_of(CutResult<Point>& result) {
  std::vector<Piece> pieces;
  for (auto& solid : result.below) pieces.push_back({"below", as_output(solid)});
  for (auto& solid : result.above) pieces.push_back({"above", as_output(solid)});
  return pieces;
}

// Writes every piece, each atomically; if one fails, removes the ones written,
// so the folder holds all pieces or none of this run's.
std::vector<std::string> write_pieces(const std::vector<Piece>& pieces, const std::filesystem::path& dir,
                                      MeshFormat format) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw IoError("cannot create output folder " + dir.string() + ": " + error.message());
  std::vector<std::string> names;
  std::vector<std::filesystem::path> written;
  std::size_t below = 0, above = 0;
  try {
    for (const Piece& piece : pieces) {
      const std::size_t index = piece.side == "below" ? below++ : above++;
      const std::string name = piece.side + "-" + std::to_string(index) + "." + std::string(format_name(format));
      write_mesh(piece.mesh, dir / name, format);
      written.push_back(dir / name);
      names.push_back(name);
    }
  } catch (...) {
    for (const auto& path : written) std::filesystem::remove(path, error);
    throw;
  }
  return names;
}

int run_slice(const SliceArgs& args) {
  const Plane plane = parse_plane(args.plane);
  const auto format = parse_mesh_format(args.format);
  if (!format) throw UsageError("--format must be off, obj, ply or stl");
  Mesh mesh = read_mesh(args.mesh);
  const std::optional<RepairReport> repair =
      cli::repair_if_asked_then_require_valid(mesh, args.mesh, args.repair, args.allow_self_intersections);

  CutOptions options;
  options.interior_uv_scale = args.interior_uv_scale;
  for (SurfaceId s : mesh.surfaces) options.cap_surface = std::max(options.cap_surface, s + 1);

  std::vector<Piece> pieces;
  bool plane_missed = false;
  CapMethod cap_method = CapMethod::none;
  std::size_t cap_loops = 0, cap_triangles = 0;
  std::string cap_method_text;
  auto take = [&](auto&& result) {
    plane_missed = result.plane_missed;
    cap_method = result.cap_method;
    cap_method_text = cap_method_name(cap_method);
    cap_loops = result.cap_loops;
    cap_triangles = result.cap_triangles;
    if (plane_missed) {
      // Whole: the input as it was read, on the side it lies on.
      pieces.push_back({result.above.empty() ? "below" : "above", mesh});
    } else {
      pieces = pieces_of(result);
    }
  };
  if (args.kernel == "plane") {
    // Exact cut, then every piece rounded once and certified: a piece that cannot
    // be written as a valid mesh fails the command before anything is written.
    const PlaneInput input = prepare_plane_input(mesh);
    const std::vector<Plane> cuts{plane};
    const PlaneSet set = input.geometry.plane_set(cuts);
    const SolidCut result = cut_solid(set, input.solid, PlaneRef::cut(0), options.cap_surface, input.shells);
    plane_missed = result.plane_missed;
    cap_method_text = "polygon";
    cap_loops = result.cap_loops;
    if (plane_missed) {
      Sign s = Sign::zero;
      for (std::size_t v = 0; v < input.solid.defs.size() && s == Sign::zero; ++v) {
        s = side(set, PlaneRef::cut(0), input.solid.defs[v], input.solid.approx[v]);
      }
      pieces.push_back({s == Sign::positive ? "above" : "below", mesh});
    }
    SolidMeshOptions meshing;
    meshing.attributes = &input.mesh;
    meshing.interior_uv_scale = args.interior_uv_scale;
    meshing.allow_self_intersections = args.allow_self_intersections;
    meshing.trusted = &input.mesh;  // validated on the way in: certification tests only what the cut changed
    meshing.cut = &plane;
    for (const auto* side_solids : {&result.below, &result.above}) {
      const std::string side_name = side_solids == &result.below ? "below" : "above";
      for (std::size_t i = 0; i < side_solids->size(); ++i) {
        RoundedSolid rounded = round_solid(set, (*side_solids)[i], meshing);
        if (!rounded.valid) {
          throw RefusedInput("piece " + side_name + "-" + std::to_string(i) +
                             " cannot be rounded to doubles as a valid mesh: " + rounded.defect);
        }
        for (SurfaceId surface : rounded.mesh.surfaces) {
          if (side_solids == &result.below && surface == options.cap_surface) ++cap_triangles;
        }
        pieces.push_back({side_name, std::move(rounded.mesh)});
      }
    }
  } else if (args.kernel == "fast") {
    take(cut_mesh(mesh, plane, options));
  } else {
    take(cut_mesh(to_exact(mesh), plane, options));
  }

  // The fast kernel promises topology; count the pieces whose rounded embedding
  // is degenerate or self-intersecting instead of hiding them.
  std::size_t invalid_embeddings = 0;
  json pieces_json = json::array();
  double total_volume = 0;
  const std::vector<std::string> names = write_pieces(pieces, args.out, *format);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const ValidationReport report = validate_mesh(pieces[i].mesh);
    const bool embedding_valid = report.valid();
    invalid_embeddings += embedding_valid ? 0 : 1;
    const double volume = signed_volume(pieces[i].mesh);
    total_volume += volume;
    pieces_json.push_back({{"file", names[i]},
                           {"side", pieces[i].side},
                           {"vertices", pieces[i].mesh.vertex_count()},
                           {"triangles", pieces[i].mesh.triangle_count()},
                           {"volume", volume},
                           {"valid", embedding_valid}});
  }
  if (args.json) {
    json out{{"input", args.mesh},
             {"kernel", args.kernel},
             {"plane", {plane.normal.x, plane.normal.y, plane.normal.z, plane.offset}},
             {"plane_missed", plane_missed},
             {"cap", {{"method", cap_method_text}, {"loops", cap_loops}, {"triangles", cap_triangles}}},
             {"input_volume", signed_volume(mesh)},
             {"total_volume", total_volume},
             {"invalid_embeddings", invalid_embeddings},
             {"pieces", pieces_json}};
    if (repair) {
      out["repair"] = cli::repair_changes_json(*repair);
      out["repair_not_done"] = cli::repair_notes_json(*repair);
    }
    std::cout << out.dump(2) << '\n';
  } else {
    if (plane_missed) std::cout << "the plane misses or only touches the mesh: it is returned whole\n";
    std::cout << pieces.size() << " piece(s) written to " << args.out << '\n';
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      // Printed from the double, not the JSON value: a volume beyond the double
      // range (coordinates near 1e300) is JSON null; here it is named.
      const json& piece = pieces_json[i];
      const double volume = piece["volume"].get<double>();
      std::cout << "  " << piece["file"].get<std::string>() << ": " << piece["triangles"] << " triangles, volume "
                << volume << (std::isfinite(volume) ? "" : " (beyond the double range)")
                << (piece["valid"].get<bool>() ? "" : " (embedding not valid after rounding)") << '\n';
    }
  }
  if (invalid_embeddings > 0) {
    std::cerr << "warning: " << invalid_embeddings
              << " piece(s) have a degenerate or self-intersecting embedding (closed and oriented all the same)\n";
  }
  return ok;
}

// Prints the one `error:` line. A message that spans lines (a library's or
// CLI11's) is joined with "; ", so scripts can rely on exactly one line.
int report_error(std::string message, int code) {
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  for (std::size_t at = message.find_first_of("\r\n"); at != std::string::npos;
       at = message.find_first_of("\r\n", at)) {
    const std::size_t end = message.find_first_not_of("\r\n", at);
    message.replace(at, end == std::string::npos ? std::string::npos : end - at, "; ");
  }
  std::cerr << "error: " << message << '\n';
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "shatter: exact plane slicing of closed triangle meshes into breakable objects.\n"
      "Exit codes: 0 ok, 1 internal error, 2 usage error, 3 invalid input (mesh, geometry or .shatter file), "
      "4 I/O error."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "shatter " + std::string(version_string));

  ValidateArgs validate_args;
  CLI::App* validate = app.add_subcommand(
      "validate", "Check that a mesh is a closed, oriented 2-manifold solid; name every defect with its count and "
                  "first element. Exit 3 if it is not.");
  validate->add_option("mesh", validate_args.mesh, "Mesh file (.off, .obj, .ply, .stl)")->required();
  validate->add_flag("--json", validate_args.json, "Print the report as JSON");
  validate->add_flag("--repair", validate_args.repair,
                     cli::repair_flag_help("The report is then of the repaired mesh (JSON: \"repair\" lists the "
                                           "changes, \"repair_not_done\" what could not be done)."));
  validate->add_option("--out", validate_args.out,
                       "With --repair: write the repaired mesh to this file (format from its extension: .off, "
                       ".obj, .ply, .stl), atomically, only if it is valid");

  SliceArgs slice_args;
  CLI::App* slice = app.add_subcommand(
      "slice", "Cut a closed mesh by one plane; write one file per resulting solid (below-0, above-0, ...).");
  slice->add_option("mesh", slice_args.mesh, "Mesh file (.off, .obj, .ply, .stl)")->required();
  slice->add_option("--plane", slice_args.plane, "The plane n.x + d = 0 as nx,ny,nz,d (n need not be unit length)")
      ->required();
  slice->add_option("--kernel", slice_args.kernel,
                    "plane (default): vertices defined as meets of planes, never constructed; the cut is exact and "
                    "each piece is rounded once and certified valid (a piece that cannot be written valid fails "
                    "with exit 3). exact: CGAL exact rationals, rounded once to doubles. fast: rounded intersection "
                    "points (topology always valid; pieces whose rounded embedding is not are counted)")
      ->check(CLI::IsMember({"plane", "exact", "fast"}))
      ->capture_default_str();
  slice->add_flag("--allow-self-intersections", slice_args.allow_self_intersections,
                  "Cut a self-intersecting (or self-touching) mesh instead of refusing it; pieces are closed and "
                  "oriented, their embedding may overlap");
  slice->add_option("--out", slice_args.out, "Output folder (created if missing)")->required();
  slice->add_option("--format", slice_args.format, "Output format: off, obj, ply (binary, doubles) or stl (ascii)")
      ->check(CLI::IsMember({"off", "obj", "ply", "stl"}))
      ->capture_default_str();
  slice->add_option("--interior-uv-scale", slice_args.interior_uv_scale,
                    "Cap UVs are the cap's plane coordinates times this (used when the mesh has UVs)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  slice->add_flag("--json", slice_args.json, "Print pieces, triangles and volumes as JSON");
  slice->add_flag("--repair", slice_args.repair,
                  cli::repair_flag_help("The repaired mesh is cut (JSON: \"repair\" lists the changes)."));

  FractureArgs fracture_args;
  CLI::App* fracture = add_fracture_command(app, fracture_args);
  InfoArgs info_args;
  CLI::App* info = add_info_command(app, info_args);
  ExportArgs export_args;
  CLI::App* export_command = add_export_command(app, export_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return report_error(std::string(e.what()) + " (see --help)", usage_error);
  }

  try {
    if (validate->parsed()) return run_validate(validate_args);
    if (slice->parsed()) return run_slice(slice_args);
    if (fracture->parsed()) return run_fracture(fracture_args);
    if (info->parsed()) return run_info(info_args);
    if (export_command->parsed()) return run_export(export_args);
    return report_error("no command given (see --help)", usage_error);
  } catch (const UsageError& e) {
    return report_error(e.what(), usage_error);
  } catch (const CommandUsageError& e) {
    return report_error(e.what(), usage_error);
  } catch (const RefusedInput& e) {
    return report_error(e.what(), invalid_input);
  } catch (const InvalidMeshError& e) {
    return report_error(e.what(), invalid_input);
  } catch (const UnsupportedGeometryError& e) {
    return report_error(e.what(), invalid_input);
  } catch (const CorruptFileError& e) {
    return report_error(e.what(), invalid_input);
  } catch (const IoError& e) {
    return report_error(e.what(), io_error);
  } catch (const std::exception& e) {
    return report_error(std::string("internal error: ") + e.what(), internal_error);
  }
}
