#include "slice.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/exact.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/cut.hpp"
#include "shatter/meshtree/plane_cut.hpp"
#include "errors.hpp"
#include "input.hpp"
#include "output_transaction.hpp"

namespace shatter::cli {

namespace {

using json = nlohmann::ordered_json;

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

// What a cut gave, whichever kernel made it.
struct SliceResult {
  std::vector<Piece> pieces;
  bool plane_missed = false;
  std::string cap_method;
  std::size_t cap_loops = 0, cap_triangles = 0;
};

template <class Point>
SliceResult result_of(CutResult<Point>&& cut, const Mesh& mesh) {
  SliceResult result;
  result.plane_missed = cut.plane_missed;
  result.cap_method = cap_method_name(cut.cap_method);
  result.cap_loops = cut.cap_loops;
  result.cap_triangles = cut.cap_triangles;
  if (cut.plane_missed) {
    // Whole: the input as it was read, on the side it lies on.
    result.pieces.push_back({cut.above.empty() ? "below" : "above", mesh});
  } else {
    result.pieces = pieces_of(cut);
  }
  return result;
}

// Exact cut, then every piece rounded once and certified: a piece that cannot
// be written as a valid mesh fails the command before anything is written.
SliceResult cut_with_plane_kernel(const Mesh& mesh, const Plane& plane, const SliceArgs& args, SurfaceId cap_surface) {
  PlaneCutOptions options;
  options.cap_surface = cap_surface;
  options.interior_uv_scale = args.interior_uv_scale;
  options.allow_self_intersections = args.allow_self_intersections;
  PlaneCut cut = cut_mesh_by_plane(mesh, plane, options);
  SliceResult result;
  result.plane_missed = cut.plane_missed;
  result.cap_method = "polygon";
  result.cap_loops = cut.cap_loops;
  // Whole: the input as it was read, on the side it lies on.
  if (cut.plane_missed) result.pieces.push_back({cut.whole_above ? "above" : "below", mesh});
  std::size_t index[2] = {0, 0};
  for (CutPiece& piece : cut.pieces) {
    const std::string side_name = piece.above ? "above" : "below";
    const std::size_t i = index[piece.above]++;
    if (!piece.defect.empty()) {
      throw UnsupportedGeometryError("piece " + side_name + "-" + std::to_string(i) +
                                     " cannot be rounded to doubles as a valid mesh: " + piece.defect);
    }
    const auto& surfaces = piece.mesh.surfaces;
    if (!piece.above) result.cap_triangles += std::size_t(std::count(surfaces.begin(), surfaces.end(), cap_surface));
    result.pieces.push_back({side_name, std::move(piece.mesh)});
  }
  return result;
}

// The file name of every piece, in piece order: <side>-<index>.<format>, each
// side counted from 0.
std::vector<std::string> piece_names(const std::vector<Piece>& pieces, MeshFormat format) {
  std::vector<std::string> names;
  std::size_t below = 0, above = 0;
  for (const Piece& piece : pieces) {
    const std::size_t index = piece.side == "below" ? below++ : above++;
    names.push_back(piece.side + "-" + std::to_string(index) + "." + std::string(format_name(format)));
  }
  return names;
}

// Writes every piece into `folder` under its name, all or none.
void write_pieces(const std::vector<Piece>& pieces, const std::vector<std::string>& names,
                  const std::filesystem::path& folder, MeshFormat format) {
  OutputTransaction output;
  output.create_folder(folder);
  for (std::size_t i = 0; i < pieces.size(); ++i) output.write_mesh(folder / names[i], pieces[i].mesh, format);
  output.commit();
}

}  // namespace

Command add_slice_command(CLI::App& app) {
  auto args = std::make_shared<SliceArgs>();
  CLI::App* command = app.add_subcommand(
      "slice", "Cut a closed mesh by one plane; write one file per resulting solid (below-0, above-0, ...).");
  command->add_option("mesh", args->mesh, "Mesh file (.off, .obj, .ply, .stl)")->required();
  command->add_option("--plane", args->plane, "The plane n.x + d = 0 as nx,ny,nz,d (n need not be unit length)")
      ->required();
  command->add_option("--kernel", args->kernel,
                      "plane (default): vertices defined as meets of planes, never constructed; the cut is exact and "
                      "each piece is rounded once and certified valid (a piece that cannot be written valid fails "
                      "with exit 3). exact: CGAL exact rationals, rounded once to doubles. fast: rounded intersection "
                      "points. exact and fast pieces are validated after rounding; if one is not a valid mesh as "
                      "written, the command fails with exit 3 and writes nothing")
      ->check(CLI::IsMember({"plane", "exact", "fast"}))
      ->capture_default_str();
  command->add_flag("--allow-self-intersections", args->allow_self_intersections,
                    "Cut a self-intersecting (or self-touching) mesh instead of refusing it; pieces are closed and "
                    "oriented, their embedding may overlap");
  command->add_option("--out", args->out, "Output folder (created if missing)")->required();
  command->add_option("--format", args->format, "Output format: off, obj, ply (binary, doubles) or stl (ascii)")
      ->check(CLI::IsMember({"off", "obj", "ply", "stl"}))
      ->capture_default_str();
  command->add_option("--interior-uv-scale", args->interior_uv_scale,
                      "Cap UVs are the cap's plane coordinates times this (used when the mesh has UVs)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_flag("--json", args->json, "Print pieces, triangles and volumes as JSON");
  command->add_flag("--repair", args->repair,
                    repair_flag_help("The repaired mesh is cut (JSON: \"repair\" lists the changes)."));
  return {command, [args] { return run_slice(*args); }};
}

int run_slice(const SliceArgs& args) {
  const Plane plane = parse_plane(args.plane);
  const auto format = parse_mesh_format(args.format);
  if (!format) throw UsageError("--format must be off, obj, ply or stl");
  const InputMesh input = read_valid_solid(args.mesh, args.repair, args.allow_self_intersections);
  const Mesh& mesh = input.mesh;

  CutOptions options;
  options.interior_uv_scale = args.interior_uv_scale;
  for (SurfaceId s : mesh.surfaces) options.cap_surface = std::max(options.cap_surface, s + 1);

  SliceResult result;
  if (args.kernel == "plane") {
    result = cut_with_plane_kernel(mesh, plane, args, options.cap_surface);
  } else if (args.kernel == "fast") {
    result = result_of(cut_mesh(mesh, plane, options), mesh);
  } else {
    result = result_of(cut_mesh(to_exact(mesh), plane, options), mesh);
  }
  const std::vector<Piece>& pieces = result.pieces;

  // What is written validates when read back, whatever the kernel: the plane
  // kernel certified its pieces already; fast and exact round after the cut, so
  // a piece whose rounded mesh is degenerate or self-intersecting fails the
  // command before anything is written. The check is validate_mesh on the
  // bytes' own doubles: what `shatter validate` does to the file. With
  // --allow-self-intersections the promise is closed and oriented: a piece may
  // overlap itself, and where the input touched itself the file welds the two
  // sides into one non-manifold vertex.
  ValidationOptions piece_checks;
  piece_checks.check_self_intersections = !args.allow_self_intersections;
  const std::vector<std::string> names = piece_names(pieces, *format);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    ValidationReport report = validate_mesh(pieces[i].mesh, piece_checks);
    if (args.allow_self_intersections) {
      std::erase_if(report.defects, [](const Defect& d) { return d.kind == DefectKind::non_manifold_vertex; });
    }
    if (!report.valid()) {
      throw UnsupportedGeometryError("piece " + names[i] + " of the " + args.kernel +
                                     " kernel is not a valid mesh as written (" + report.summary() +
                                     "); nothing was written. The plane kernel (the default) certifies its pieces");
    }
  }
  json pieces_json = json::array();
  double total_volume = 0;
  write_pieces(pieces, names, args.out, *format);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const double volume = signed_volume(pieces[i].mesh);
    total_volume += volume;
    pieces_json.push_back({{"file", names[i]},
                           {"side", pieces[i].side},
                           {"vertices", pieces[i].mesh.vertex_count()},
                           {"triangles", pieces[i].mesh.triangle_count()},
                           {"volume", volume}});
  }
  if (args.json) {
    json out{{"input", args.mesh},
             {"kernel", args.kernel},
             {"plane", {plane.normal.x, plane.normal.y, plane.normal.z, plane.offset}},
             {"plane_missed", result.plane_missed},
             {"cap", {{"method", result.cap_method}, {"loops", result.cap_loops}, {"triangles", result.cap_triangles}}},
             {"input_volume", signed_volume(mesh)},
             {"total_volume", total_volume},
             {"pieces", pieces_json}};
    if (input.repair) add_repair_json(out, *input.repair);
    std::cout << out.dump(2) << '\n';
  } else {
    if (result.plane_missed) std::cout << "the plane misses or only touches the mesh: it is returned whole\n";
    std::cout << pieces.size() << " piece(s) written to " << args.out << '\n';
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      // Printed from the double, not the JSON value: a volume beyond the double
      // range (coordinates near 1e300) is JSON null; here it is named.
      const json& piece = pieces_json[i];
      const double volume = piece["volume"].get<double>();
      std::cout << "  " << piece["file"].get<std::string>() << ": " << piece["triangles"] << " triangles, volume "
                << volume << (std::isfinite(volume) ? "" : " (beyond the double range)") << '\n';
    }
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
