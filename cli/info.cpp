#include "info.hpp"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "shatter/kernel/error.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/meshtree/stats.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "errors.hpp"
#include "huge_page_objects.hpp"
#include "input.hpp"
#include "node_json.hpp"
#include "tree_stats_json.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

using json = nlohmann::ordered_json;

// What --check found to say: the checks it made, every one of which held (a
// failed check throws before anything is printed).
constexpr const char* check_scope = "structure, and every node's plane, mass, mesh and hull";

json info_json(const InfoArgs& args, const MeshTree& tree, const TreeStats& stats,
               const std::optional<BondRuleComparison>& rules) {
  json out{{"file", args.input}};
  out["shatter_version"] = tree.shatter_version.empty() ? json(nullptr) : json(tree.shatter_version);
  if (tree.input_repair.empty()) {
    out["input_repair"] = nullptr;
  } else {
    const RepairReport& report = tree.input_repair;
    json repair{{"vertices_before", report.vertices_before},
                {"triangles_before", report.triangles_before},
                {"vertices_after", report.vertices_after},
                {"triangles_after", report.triangles_after}};
    add_repair_json(repair, report);
    out["input_repair"] = std::move(repair);
  }
  append_stats_json(out, recipe_json(tree.recipe), stats);
  if (args.check) out["check"] = "valid";
  if (rules) {
    out["bounding_box_rule"] = {{"true_bonds", rules->true_bonds},
                                {"box_bonds", rules->box_bonds},
                                {"false_box_bonds", rules->false_box_bonds},
                                {"missed_true_bonds", rules->missed_true_bonds}};
  }
  return out;
}

void print_info_text(const InfoArgs& args, const MeshTree& tree, const TreeStats& stats) {
  const TreeRecipe& recipe = tree.recipe;
  const VolumeSpread& volume = stats.fragment_volume;
  std::cout << args.input << ": mesh tree of " << stats.node_count << " nodes, " << stats.leaf_count
            << " leaves (fragments), " << stats.internal_count << " internal; leaves at depth " << stats.min_leaf_depth
            << " to " << stats.max_depth << '\n';
  if (!tree.shatter_version.empty()) std::cout << "  built by shatter " << tree.shatter_version << '\n';
  if (const RepairReport& repair = tree.input_repair; !repair.empty()) {
    std::cout << "  input repaired before the build (" << repair.triangles_before << " triangles, "
              << repair.triangles_after << " after): " << repair.summary() << '\n';
    for (const RepairNote& note : repair.notes) std::cout << "  input repair, not done: " << note.text << '\n';
  }
  if (!recipe.pattern.empty()) std::cout << "  sites: --pattern " << recipe.pattern << '\n';
  std::cout << "  built with: fragments " << recipe.fragments << ", seed " << recipe.seed << ", strategy "
            << strategy_name(recipe.strategy) << ", kernel " << kernel_name(recipe.kernel)
            << (recipe.kernel == KernelKind::plane ? "" : " (retired: the tree reads, but cannot be re-cut exactly)")
            << ", interior UV scale " << recipe.interior_uv_scale << ", max plane tries " << recipe.max_plane_tries
            << (recipe.allow_self_intersections ? ", self-intersections allowed" : "") << '\n'
            << "  volume: root " << stats.root_volume << ", leaves together " << stats.total_leaf_volume
            << " (relative difference " << leaf_volume_relative_error(stats) << ")\n"
            << "  fragment volume: min " << volume.min << ", median " << volume.median << ", max " << volume.max
            << ", mean " << volume.mean << ", coefficient of variation " << volume.coefficient_of_variation
            << '\n'
            << "  bonds: " << stats.bond_count << ", total area " << stats.total_bond_area << '\n'
            << "  leaves hold " << stats.leaf_triangles << " triangles (" << stats.leaf_cap_triangles
            << " on caps) over " << stats.leaf_vertices << " vertices\n";
  if (args.check) std::cout << "  check: valid (" << check_scope << ")\n";
}

// One line per node: what the viewer shows when the node is clicked.
void print_nodes_text(const nlohmann::ordered_json& nodes) {
  for (const nlohmann::ordered_json& node : nodes) {
    std::cout << "  node " << node["node"];
    if (node.contains("leaf")) std::cout << " (leaf " << node["leaf"] << ")";
    std::cout << ", depth " << node["depth"] << ": volume " << node["volume"].get<double>() << ", "
              << node["triangles"] << " triangles (" << node["cap_triangles"] << " on caps), "
              << node["bonds"].size() << " bonds\n";
  }
}

void print_bond_rules_text(const BondRuleComparison& rules) {
  std::cout << "  the seed's bounding-box rule: " << rules.box_bonds << " bonded pairs, " << rules.false_box_bonds
            << " of them false (no cap contact); " << rules.missed_true_bonds << " of the " << rules.true_bonds
            << " truly touching pairs missed\n";
}

}  // namespace

Command add_info_command(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* command = app.add_subcommand(
      "info",
      "Describe a .shatter mesh tree: node, leaf and depth counts, the shatter version and build options that made "
      "it, fragment volume statistics (min, median, max, coefficient of variation), bonds and their total area; "
      "with --check, check it in full first.");
  command->add_option("tree", args->input, "Mesh tree file (.shatter)")->required();
  command->add_flag("--json", args->json, "Print the description as JSON");
  command->add_flag("--check", args->check,
                    "Also check the tree in full before describing it: every node's mesh a valid solid "
                    "(self-intersections included, proved by a piece certificate where one applies and searched for "
                    "otherwise; topology only for a tree built with "
                    "--allow-self-intersections), every hull a closed outward solid, every cut plane finite with "
                    "children on both sides, every mass finite and positive. The structure is checked on every "
                    "read anyway. Prints \"check: valid\" (\"check\": \"valid\" with --json), or exits 3 with one "
                    "error line naming the part and index at fault");
  command->add_flag("--compare-bond-rules", args->compare_bond_rules,
                    "Also apply the seed's bond rule (leaves whose bounding boxes overlap) and count its false "
                    "bonds (pairs with no cap contact) and the true bonds it misses, against the stored true-contact "
                    "bonds recomputed from the meshes");
  command->add_option("--nodes", args->nodes,
                    "Also describe these nodes one by one: leaves (the fragments), all, or depth:K (the solid cut at "
                    "depth K), each with its depth, leaf range, volume, centroid, triangles and the bonds that cross "
                    "its boundary: what the viewer shows when a fragment is clicked");
  return {command, [args] { return run_info(*args); }};
}

int run_info(const InfoArgs& args) {
  std::optional<NodeSelection> selection;
  if (!args.nodes.empty()) {
    try {
      selection = parse_node_selection(args.nodes);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--nodes: ") + e.what());
    }
  }
  keep_small_objects_on_huge_pages();
  const MeshTree tree = read_shatter_file(args.input);
  if (args.check) {
    // The reader checked the structure and computed the caches from the file,
    // so what is left to check is the geometry.
    const TreeValidationReport report = validate_tree(tree, {.caches = false, .geometry = true, .certificates = true});
    if (!report.valid()) throw CorruptFileError(args.input + ": invalid tree: " + report.summary());
  }
  const TreeStats stats = tree_stats(tree);
  std::optional<BondRuleComparison> rules;
  if (args.compare_bond_rules) rules = compare_bond_rules(tree);
  nlohmann::ordered_json nodes;
  if (selection) nodes = nodes_json(tree, select_nodes(tree, *selection));
  if (args.json) {
    json out = info_json(args, tree, stats, rules);
    if (selection) {
      out["node_selection"] = node_selection_name(*selection);
      out["node_details"] = std::move(nodes);
    }
    std::cout << json_text(out, 2) << '\n';
  } else {
    print_info_text(args, tree, stats);
    if (rules) print_bond_rules_text(*rules);
    if (selection) print_nodes_text(nodes);
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
