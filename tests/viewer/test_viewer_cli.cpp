// The commands around the viewer, run as a user runs them: `info --nodes`
// (what the viewer shows for a clicked fragment, checked against the tree read
// with the library and bonds found by brute force), `export --format html`
// (one self-contained page holding exactly the GLB `export` writes, all or
// nothing), and what a build without the viewer says. The browser tests of the
// page itself are viewer/test/browser.mjs.

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/generators/corpus.hpp"
#include "support/run_shatter.hpp"

using namespace shatter;
using namespace shatter::test;
using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

// knot1 in 12 fragments, made once per process.
const fs::path& knot_tree() {
  static const fs::path path = [] {
    const fs::path out = scratch("knot.shatter");
    const Run run = run_shatter("fracture " + quoted(mesh_dir() / "knot1.off") + " --fragments 12 --seed 4 --out " +
                                quoted(out));
    REQUIRE(run.exit_code == 0);
    return out;
  }();
  return path;
}

#if SHATTER_VIEWER_BUILT  // the page's parts, for the tests of a built viewer below
std::string decode_base64(const std::string& text) {
  const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  unsigned value = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    const std::size_t digit = digits.find(c);
    REQUIRE(digit != std::string::npos);
    value = value << 6 | static_cast<unsigned>(digit);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((value >> bits) & 0xFF);
    }
  }
  return out;
}

// The text between `open` and the next `close` after it.
std::string between(const std::string& text, const std::string& open, const std::string& close) {
  const std::size_t start = text.find(open);
  REQUIRE(start != std::string::npos);
  const std::size_t end = text.find(close, start + open.size());
  REQUIRE(end != std::string::npos);
  return text.substr(start + open.size(), end - start - open.size());
}
#endif

}  // namespace

TEST_CASE("info --nodes describes each node as the viewer shows it, bonds crossing its boundary included") {
  const MeshTree tree = read_shatter_file(knot_tree());
  const Run run = run_shatter("info " + quoted(knot_tree()) + " --json --nodes all");
  REQUIRE(run.exit_code == 0);
  const json out = json::parse(run.out);
  CHECK(out["node_selection"] == "all");
  const json& details = out["node_details"];
  REQUIRE(details.size() == tree.nodes.size());
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    const MeshTreeNode& node = tree.nodes[i];
    const json& d = details[i];
    INFO("node " << i);
    CHECK(d["node"] == i);
    CHECK(d["depth"] == node.depth);
    CHECK(d.contains("leaf") == node.is_leaf());
    CHECK(d["first_leaf"] == node.first_leaf);
    CHECK(d["leaf_count"] == node.leaf_count);
    CHECK(d["volume"].get<double>() == node.mass.volume);
    CHECK(d["centroid"][1].get<double>() == node.mass.centroid.y);
    CHECK(d["triangles"] == node.mesh->triangle_count());
    // Brute force: every bond with exactly one leaf inside the node, in bond order.
    json expected = json::array();
    const auto inside = [&](LeafIndex leaf) { return leaf >= node.first_leaf && leaf < node.first_leaf + node.leaf_count; };
    for (const Bond& bond : tree.bonds) {
      if (inside(bond.first) == inside(bond.second)) continue;
      const bool first = inside(bond.first);
      expected.push_back({{"leaf", first ? bond.first : bond.second},
                          {"other", first ? bond.second : bond.first},
                          {"area", bond.area}});
    }
    CHECK(d["bonds"] == expected);
  }
  CHECK(details[0]["bonds"].empty());  // the root has no outside

  const Run leaves = run_shatter("info " + quoted(knot_tree()) + " --json --nodes depth:2");
  REQUIRE(leaves.exit_code == 0);
  CHECK(json::parse(leaves.out)["node_details"].size() ==
        select_nodes(tree, parse_node_selection("depth:2")).size());

  const Run text = run_shatter("info " + quoted(knot_tree()) + " --nodes leaves");
  REQUIRE(text.exit_code == 0);
  CHECK(text.out.find("node " + std::to_string(tree.leaf_nodes[0]) + " (leaf 0), depth ") != std::string::npos);

  const Run bad = run_shatter("info " + quoted(knot_tree()) + " --nodes some");
  CHECK(bad.exit_code == 2);
  CHECK(bad.err.rfind("error: --nodes: node selection 'some'", 0) == 0);
}

TEST_CASE("export --format html checks its flags before reading anything") {
  const fs::path out = scratch("flags");
  const Run glb_out = run_shatter("export " + quoted(knot_tree()) + " --format html --out " + quoted(out / "t.glb"));
  CHECK(glb_out.exit_code == 2);
  CHECK(glb_out.err == "error: --out " + (out / "t.glb").string() + " names a .glb file but --format is html\n");
  const Run mesh_out = run_shatter("export " + quoted(knot_tree()) + " --format off --out " + quoted(out / "t.html"));
  CHECK(mesh_out.exit_code == 2);
  CHECK(mesh_out.err.find("names an HTML file but --format is off") != std::string::npos);
  fs::create_directories(out / "folder");
  const Run folder = run_shatter("export " + quoted(knot_tree()) + " --format html --out " + quoted(out / "folder"));
  CHECK(folder.exit_code == 2);
  CHECK(!fs::exists(out / "t.glb"));
  CHECK(!fs::exists(out / "t.html"));
}

#if SHATTER_VIEWER_BUILT

TEST_CASE("export --format html writes one page holding the GLB export writes, and nothing on failure") {
  const fs::path folder = scratch("html");
  const fs::path page_path = folder / "sub" / "tree.html";
  const Run run = run_shatter("export " + quoted(knot_tree()) + " --out " + quoted(page_path));
  REQUIRE(run.exit_code == 0);
  CHECK(run.out.find("(the viewer with the tree inline)") != std::string::npos);
  const std::string page = slurp(page_path);
  CHECK(page.rfind("<!doctype html>", 0) == 0);
  CHECK(page.find("<!--shatter:data-->") == std::string::npos);  // the marker was filled in
  CHECK(page.find("<script src") == std::string::npos);          // nothing loaded from elsewhere
  const json config = json::parse(between(page, "<script id=\"shatter-config\" type=\"application/json\">", "</script>"));
  CHECK(config == json{{"mode", "file"}, {"name", "knot.shatter"}});
  // The inline model is the GLB of every node, byte for byte.
  const std::string glb = decode_base64(between(page, "<script id=\"shatter-model\" type=\"application/octet-stream\">",
                                                "</script>"));
  const MeshTree tree = read_shatter_file(knot_tree());
  CHECK(glb == encode_glb(tree, select_nodes(tree, parse_node_selection("all"))));

  const Run leaves = run_shatter("export " + quoted(knot_tree()) + " --format html --nodes leaves --out " +
                                 quoted(folder / "leaves.html"));
  REQUIRE(leaves.exit_code == 0);
  const std::string leaves_glb = decode_base64(between(
      slurp(folder / "leaves.html"), "<script id=\"shatter-model\" type=\"application/octet-stream\">", "</script>"));
  CHECK(leaves_glb == encode_glb(tree, tree.leaf_nodes));

  // A damaged tree: exit 3, and no page, no folder.
  const fs::path damaged = folder / "damaged.shatter";
  {
    std::string bytes = slurp(knot_tree());
    bytes[bytes.size() / 2] ^= 0x40;
    std::FILE* f = std::fopen(damaged.c_str(), "wb");
    REQUIRE(f != nullptr);
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
  }
  const Run refused = run_shatter("export " + quoted(damaged) + " --out " + quoted(folder / "new" / "x.html"));
  CHECK(refused.exit_code == 3);
  CHECK(!fs::exists(folder / "new"));
}

TEST_CASE("view --help explains the command") {
  const Run help = run_shatter("view --help");
  REQUIRE(help.exit_code == 0);
  for (const char* words : {"127.0.0.1", "Ctrl-C", "--port", "editor", "export --format html", ".glb"}) {
    INFO(words);
    CHECK(help.out.find(words) != std::string::npos);
  }
}

#else

TEST_CASE("a build without the viewer says so, in one line, for both commands that need it") {
  const Run view = run_shatter("view " + quoted(knot_tree()));
  CHECK(view.exit_code == 2);
  CHECK(view.err.rfind("error: view: this shatter was built without the viewer", 0) == 0);
  const fs::path out = scratch("no-viewer") / "tree.html";
  const Run html = run_shatter("export " + quoted(knot_tree()) + " --out " + quoted(out));
  CHECK(html.exit_code == 2);
  CHECK(html.err.rfind("error: export --format html: this shatter was built without the viewer", 0) == 0);
  CHECK(!fs::exists(out));
}

#endif
