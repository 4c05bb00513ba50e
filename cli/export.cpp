#include "export.hpp"

#include <algorithm>
#include <cctype>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "shatter/formats/file.hpp"
#include "shatter/meshtree/tree.hpp"
#include "errors.hpp"
#include "huge_page_objects.hpp"
#include "view_original.hpp"
#include "viewer_page.hpp"

namespace shatter::cli {

namespace {

namespace fs = std::filesystem;

// What export writes: a folder of mesh files, one GLB, or one self-contained
// viewer page.
struct ExportFormat {
  enum class Kind { mesh_files, glb, html } kind = Kind::mesh_files;
  MeshFormat mesh = MeshFormat::off;  ///< for mesh_files
};

std::string lower_extension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

// The output format: --format if given, else glb for a .glb --out, html for an
// .html or .htm --out, else off.
ExportFormat export_format(const ExportArgs& args) {
  using Kind = ExportFormat::Kind;
  const std::string extension = lower_extension(args.out);
  const bool out_is_glb = extension == ".glb";
  const bool out_is_html = extension == ".html" || extension == ".htm";
  if (args.format.empty()) {
    if (out_is_glb) return {Kind::glb};
    if (out_is_html) return {Kind::html};
    return {Kind::mesh_files, MeshFormat::off};
  }
  if (args.format == "glb" || args.format == "html") {
    if (fs::is_directory(args.out)) {
      throw UsageError("--format " + args.format + " writes one file, but --out " + args.out + " is a folder");
    }
    if (args.format == "glb" && out_is_html) {
      throw UsageError("--out " + args.out + " names an HTML file but --format is glb");
    }
    if (args.format == "html" && out_is_glb) {
      throw UsageError("--out " + args.out + " names a .glb file but --format is html");
    }
    return {args.format == "glb" ? Kind::glb : Kind::html};
  }
  const std::optional<MeshFormat> format = parse_mesh_format(args.format);
  if (!format) throw UsageError("--format must be off, obj, ply, stl, glb or html, got '" + args.format + "'");
  if (out_is_glb || out_is_html) {
    throw UsageError("--out " + args.out + " names " + (out_is_glb ? "a .glb" : "an HTML") + " file but --format is " +
                     args.format + ", which writes a folder of mesh files");
  }
  return {Kind::mesh_files, *format};
}

NodeSelection selection_of(const std::string& text) {
  try {
    return parse_node_selection(text);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--nodes: ") + e.what());
  }
}

std::size_t triangles_of(const MeshTree& tree, const std::vector<NodeIndex>& nodes) {
  std::size_t triangles = 0;
  NodeShapes shapes(tree);
  for (NodeIndex node : nodes) triangles += shapes(node).mesh.triangle_count();
  return triangles;
}

}  // namespace

std::vector<fs::path> write_node_mesh_files(OutputTransaction& output, const MeshTree& tree,
                                            std::span<const NodeIndex> nodes, const fs::path& folder,
                                            MeshFormat format, FileNaming naming) {
  std::vector<fs::path> paths;
  paths.reserve(nodes.size());
  for (NodeIndex node : nodes) paths.push_back(folder / mesh_file_name(tree, node, naming, format));
  output.create_folder(folder);
  NodeShapes shapes(tree);  // `fracture` exports a lean build's packed leaves
  for (std::size_t i = 0; i < nodes.size(); ++i) output.write_mesh(paths[i], shapes(nodes[i]).mesh, format);
  return paths;
}

Command add_export_command(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* command = app.add_subcommand(
      "export",
      "Write the nodes of a .shatter mesh tree as mesh files (one per node, into a folder), as one glTF binary "
      "(.glb) holding the whole tree as a node hierarchy, or as one self-contained HTML page: the viewer with the "
      "tree inline, which opens from disk in a browser with no server (see `shatter view`).");
  command->add_option("tree", args->input, "Mesh tree file (.shatter)")->required();
  command->add_option("--out", args->out,
                      "Output folder for mesh files (created if missing; leaf-0000.off, ... for --nodes leaves, "
                      "node-00012.off, ... by node index otherwise), a .glb file, or an .html file")
      ->required();
  command->add_option("--format", args->format,
                      "off, obj, ply, stl (as `slice` writes them, coordinates kept exactly), glb (float32 "
                      "vertices: for viewing) or html (the viewer page with the GLB inline). Default: glb when --out "
                      "ends in .glb, html when it ends in .html, else off")
      ->check(CLI::IsMember({"off", "obj", "ply", "stl", "glb", "html"}));
  command->add_option("--nodes", args->nodes,
                      "Which nodes: leaves (the fragments), all (every level, overlapping), or depth:K (the nodes "
                      "at depth K and the leaves above it: the solid cut at that level; the root is depth 0). "
                      "Default: leaves; all for html, whose depth slider shows every level")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            try {
              parse_node_selection(text);
              return {};
            } catch (const std::invalid_argument& e) {
              return e.what();
            }
          },
          "leaves|all|depth:K", "node selection"));
  command->add_option("--original", args->original,
                      "html only: the mesh file the tree was built from (read as fracture reads it), put on the "
                      "page as `view --original` serves it: an \"Original input\" panel with the repair report and "
                      "a switch that draws the file as it is beside the tree's root, its boundary edges, "
                      "non-manifold edges and self-intersecting triangles highlighted. Needs the root on the page "
                      "(--nodes all, the default for html, or depth:0). Refused with one line, nothing written, "
                      "when the file cannot be read or drawn, or its bounding box does not hold the root's (equals "
                      "it, for a tree built without --repair)");
  return {command, [args] { return run_export(*args); }};
}

int run_export(const ExportArgs& args) {
  using Kind = ExportFormat::Kind;
  const ExportFormat format = export_format(args);
  if (format.kind == Kind::html) require_viewer("export --format html");
  if (!args.original.empty() && format.kind != Kind::html) {
    throw UsageError("--original goes with --format html (the viewer page draws it beside the root), not with --out " +
                     args.out);
  }
  // The viewer's depth slider needs every level, so a page holds all nodes unless told otherwise.
  const NodeSelection selection = selection_of(args.nodes.empty() ? (format.kind == Kind::html ? "all" : "leaves")
                                                                  : args.nodes);
  // The page draws the original beside the root, so the root must be on it.
  if (!args.original.empty() && selection.kind != NodeSelectionKind::all &&
      !(selection.kind == NodeSelectionKind::depth && selection.depth == 0)) {
    throw UsageError("--original is drawn beside the tree's root, which is not on the page with --nodes " +
                     node_selection_name(selection) + "; use --nodes all (the default for html) or depth:0");
  }
  keep_small_objects_on_huge_pages();
  const MeshTree tree = read_shatter_file(args.input);
  const std::vector<NodeIndex> nodes = select_nodes(tree, selection);
  std::optional<nlohmann::ordered_json> original;
  if (!args.original.empty()) {
    if (tree.nodes.empty()) throw CorruptFileError(args.input + ": the tree has no nodes");
    original = original_json(read_original_input(args.original, tree.nodes[0].mesh, tree.input_repair),
                             tree.input_repair);
  }

  OutputTransaction output;
  if (format.kind != Kind::mesh_files) {
    std::string bytes = encode_glb(tree, nodes);
    if (format.kind == Kind::html) {
      bytes = self_contained_viewer_page(fs::path(args.input).filename().string(), bytes,
                                         original ? &*original : nullptr);
    }
    if (const fs::path folder = fs::path(args.out).parent_path(); !folder.empty()) output.create_folder(folder);
    output.write_file(args.out, bytes);
    output.commit();
    std::cout << "wrote " << args.out
              << (format.kind != Kind::html ? ""
                  : original               ? " (the viewer with the tree and the original input inline)"
                                           : " (the viewer with the tree inline)")
              << ": " << tree.nodes.size() << " tree nodes, meshes on " << nodes.size() << " ("
              << node_selection_name(selection) << "), " << triangles_of(tree, nodes) << " triangles\n";
    return static_cast<int>(ExitCode::ok);
  }
  const MeshFormat mesh_format = format.mesh;
  const std::vector<fs::path> paths =
      write_node_mesh_files(output, tree, nodes, args.out, mesh_format, file_naming_for(selection));
  output.commit();
  std::cout << "wrote " << paths.size() << " " << format_name(mesh_format) << " file(s) ("
            << node_selection_name(selection) << ") to " << args.out;
  if (!paths.empty()) {
    std::cout << ": " << paths.front().filename().string();
    if (paths.size() > 1) std::cout << " ... " << paths.back().filename().string();
  }
  std::cout << ", " << triangles_of(tree, nodes) << " triangles\n";
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
