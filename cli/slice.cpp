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
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "errors.hpp"
#include "input.hpp"
#include "output_transaction.hpp"
#include "json_text.hpp"

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

struct Piece {
  std::string side;
  std::string name;  ///< <side>-<index>, the index counted per side in the cut's order
  Mesh mesh;
  std::size_t separated_vertices = 0;  ///< where the exact piece touched itself (CutPiece)
  double moved_volume = 0, moved_volume_bound = 0;
};

/// A piece thinner than the rounding of its coordinates: not written.
struct VanishedPiece {
  std::string name;
  double volume = 0;
};

struct SliceResult {
  std::vector<Piece> pieces;
  std::vector<VanishedPiece> vanished;
  bool plane_missed = false;
  std::size_t cap_loops = 0, cap_triangles = 0;
};

// Exact cut, then every piece rounded once and certified: a piece that cannot
// be written as a valid mesh fails the command before anything is written, but
// for a piece thinner than the rounding of its coordinates, which vanishes (it
// is named, with its volume, and not written).
SliceResult cut_into_pieces(const Mesh& mesh, const PlaneInput& prepared, const Plane& plane, const SliceArgs& args,
                            SurfaceId cap_surface) {
  PlaneCutOptions options;
  options.cap_surface = cap_surface;
  options.interior_uv_scale = args.interior_uv_scale;
  options.allow_self_intersections = args.allow_self_intersections;
  PlaneCut cut = cut_mesh_by_plane(prepared, plane, options);
  SliceResult result;
  result.plane_missed = cut.plane_missed;
  result.cap_loops = cut.cap_loops;
  // Whole: the input as it was read, on the side it lies on.
  if (cut.plane_missed) {
    const std::string side_name = cut.whole_above ? "above" : "below";
    result.pieces.push_back({side_name, side_name + "-0", mesh, 0, 0, 0});
  }
  std::size_t index[2] = {0, 0};
  for (CutPiece& piece : cut.pieces) {
    const std::string side_name = piece.above ? "above" : "below";
    const std::string name = side_name + "-" + std::to_string(index[piece.above]++);
    if (piece.vanished) {
      result.vanished.push_back({name, piece.moved_volume});
      continue;
    }
    if (!piece.defect.empty()) {
      throw UnsupportedGeometryError("piece " + name + " cannot be rounded to doubles as a valid mesh: " + piece.defect);
    }
    const auto& surfaces = piece.mesh.surfaces;
    if (!piece.above) result.cap_triangles += std::size_t(std::count(surfaces.begin(), surfaces.end(), cap_surface));
    result.pieces.push_back(
        {side_name, name, std::move(piece.mesh), piece.separated_vertices, piece.moved_volume, piece.moved_volume_bound});
  }
  if (result.pieces.empty()) {
    throw UnsupportedGeometryError("every piece is thinner than the rounding of its coordinates: nothing to write");
  }
  return result;
}

// The file name of every piece, in piece order: <side>-<index>.<format>, each
// side counted from 0 in the cut's order (a vanished piece keeps its number, so
// the numbers of the others do not depend on the rounding).
std::vector<std::string> piece_names(const std::vector<Piece>& pieces, MeshFormat format) {
  std::vector<std::string> names;
  for (const Piece& piece : pieces) names.push_back(piece.name + "." + std::string(format_name(format)));
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
  // Prepared for the cut beside its check (read_prepared_solid).
  const PreparedSolid prepared = read_prepared_solid(args.mesh, args.repair, args.allow_self_intersections);
  const InputMesh& input = prepared.input;
  const Mesh& mesh = input.mesh;

  SurfaceId cap_surface = 1;
  for (SurfaceId s : mesh.surfaces) cap_surface = std::max(cap_surface, s + 1);
  // Every piece is certified as it is rounded (cut_mesh_by_plane): what is
  // written validates when read back, and is not checked again here.
  const SliceResult result = cut_into_pieces(mesh, prepared.plane, plane, args, cap_surface);
  const std::vector<Piece>& pieces = result.pieces;
  const std::vector<std::string> names = piece_names(pieces, *format);
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
                           {"volume", volume},
                           {"separated_vertices", pieces[i].separated_vertices},
                           {"moved_volume", pieces[i].moved_volume},
                           {"moved_volume_bound", pieces[i].moved_volume_bound}});
  }
  json vanished_json = json::array();
  for (const VanishedPiece& piece : result.vanished) vanished_json.push_back({{"piece", piece.name}, {"volume", piece.volume}});
  if (args.json) {
    json out{{"input", args.mesh},
             {"plane", {plane.normal.x, plane.normal.y, plane.normal.z, plane.offset}},
             {"plane_missed", result.plane_missed},
             {"cap", {{"method", "polygon"}, {"loops", result.cap_loops}, {"triangles", result.cap_triangles}}},
             {"input_volume", signed_volume(mesh)},
             {"total_volume", total_volume},
             {"pieces", pieces_json},
             {"vanished", vanished_json}};
    if (input.repair) add_repair_json(out, *input.repair);
    std::cout << json_text(out, 2) << '\n';
  } else {
    if (result.plane_missed) std::cout << "the plane misses or only touches the mesh: it is returned whole\n";
    std::cout << pieces.size() << " piece(s) written to " << args.out << '\n';
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      // Printed from the double, not the JSON value: a volume beyond the double
      // range (coordinates near 1e300) is JSON null; here it is named.
      const json& piece = pieces_json[i];
      const double volume = piece["volume"].get<double>();
      std::cout << "  " << piece["file"].get<std::string>() << ": " << piece["triangles"] << " triangles, volume "
                << volume << (std::isfinite(volume) ? "" : " (beyond the double range)");
      if (pieces[i].separated_vertices > 0) {
        // The exact piece touched itself at a point (a saddle vertex or a cavity's
        // corner on the plane): round_solid moved the copies there apart.
        std::cout << "; touched itself: " << pieces[i].separated_vertices << " vertex copies moved apart, volume moved "
                  << pieces[i].moved_volume << " (at most " << pieces[i].moved_volume_bound << ")";
      }
      std::cout << '\n';
    }
    for (const VanishedPiece& piece : result.vanished) {
      std::cout << "  " << piece.name << ": vanished, thinner than the rounding of its coordinates (volume "
                << piece.volume << " moved to its neighbours)\n";
    }
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
