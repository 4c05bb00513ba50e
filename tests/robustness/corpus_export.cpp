#include "corpus_export.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <system_error>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"

namespace shatter::robust {

namespace {

std::string hex_double(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

// A file name from a mesh name: letters, digits, '-' and '_' kept, the rest '_'.
std::string file_stem(const std::string& name) {
  std::string stem;
  for (const char c : name) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    stem += plain ? c : '_';
  }
  return stem.empty() ? "mesh" : stem;
}

nlohmann::ordered_json case_entry(const Case& c, std::uint64_t id, const std::string& mesh_file) {
  nlohmann::ordered_json entry;
  entry["id"] = id;
  entry["class"] = std::string(class_name(c.kind));
  entry["seed"] = c.seed;
  entry["mesh"] = mesh_file;
  entry["mesh_name"] = c.mesh_name;
  entry["operation"] = std::string(operation_name(c.op));
  if (c.op == Operation::slice) {
    nlohmann::ordered_json planes = nlohmann::ordered_json::array(), planes_hex = nlohmann::ordered_json::array();
    for (const Plane& p : c.planes) {
      planes.push_back({p.normal.x, p.normal.y, p.normal.z, p.offset});
      planes_hex.push_back({hex_double(p.normal.x), hex_double(p.normal.y), hex_double(p.normal.z), hex_double(p.offset)});
    }
    entry["planes"] = std::move(planes);
    entry["planes_hex"] = std::move(planes_hex);
  } else {
    entry["fragments"] = c.recipe.fragments;
    entry["build_seed"] = c.recipe.seed;
    entry["strategy"] = std::string(strategy_name(c.recipe.strategy));
  }
  return entry;
}

// The README.md an export holds: the manifest's fields, the plane convention,
// what shatter promises for each case, and how the cases were drawn.
std::string corpus_readme() {
  return R"(# shatter-fuzz robustness corpus

Seeded degenerate cases for geometry code that cuts closed triangle meshes by
planes, written by `shatter-fuzz --export-corpus` (shatter's robustness runner).
Every mesh is a valid solid: closed, consistently oriented outward, 2-manifold,
no self-intersection, positive volume. The degeneracy is in the planes: through
vertices, along edges, holding faces, a few ulps off each of those, dozens of
vertices on one plane, coplanar faces, slivers and needles down to 2^-40 thick,
nested shells, pinches, chains of near-parallel cuts, coordinates scaled to 1e-9
.. 1e9 or shifted 1e9 from the origin.

## Files

- `manifest.json`: `{"generator", "seed", "cases": [...]}`, one entry
  per case, in the order drawn.
- `meshes/*.obj`: the meshes, positions as shortest round-trip decimals (each
  reads back to the same doubles), faces as triangles; per-corner normals and
  texture coordinates where the case has them (class `attribute_seams`). Cases
  that share a mesh share its file.

## A case

- `id`: its index in the run seeded with the manifest's `seed` (`shatter-fuzz
  --seed SEED --first ID --cases 1` runs it again); `seed`: the number it was
  drawn from; `class`: its degenerate class.
- `mesh`: the OBJ file, relative to this folder; `mesh_name`: where it came from.
- `operation` `"slice"`: cut the mesh by `planes[0]`, then every piece by
  `planes[1]`, and so on (a chain). A plane `[a, b, c, d]` is the set
  a x + b y + c z + d = 0; a point is above it when a x + b y + c z + d > 0,
  evaluated exactly. `planes_hex` holds the same doubles as C99 hex literals.
- `operation` `"fracture"`: recursive cuts to `fragments` pieces by shatter's
  recipe (`strategy`, `build_seed`); a peer may use its own recursion.

## What shatter promises for every case

Every piece is a valid closed solid as written (read back from its file), the
pieces' volumes sum to the input's within what rounding moves (reported), and no
case is refused. A tool is robust on a case when it does the same; a crash, a
hang, an invalid piece or a refusal are what to count.
)";
}

}  // namespace

ExportSummary export_corpus(const MeshPool& pool, std::uint64_t seed, const std::vector<std::uint64_t>& indices,
                            const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (fs::exists(dir)) throw std::invalid_argument("the export folder " + dir.string() + " exists already");
  fs::path staging = dir;
  staging += ".partial";
  std::error_code ignored;
  fs::remove_all(staging, ignored);
  ExportSummary summary;
  try {
    fs::create_directories(staging / "meshes");
    // Meshes by content: a hash finds the candidates, the bytes already written
    // decide (read back from the file, so the corpus need not stay in memory).
    std::multimap<std::size_t, std::string> files_by_hash;
    std::map<std::string, std::size_t> stem_uses;
    nlohmann::ordered_json manifest;
    manifest["generator"] = "shatter-fuzz --export-corpus";
    manifest["seed"] = seed;
    manifest["cases"] = nlohmann::ordered_json::array();
    for (const std::uint64_t index : indices) {
      const Case c = make_case(pool, seed, index);
      const std::string bytes = write_mesh_to_bytes(c.mesh, MeshFormat::obj);
      const std::size_t hash = std::hash<std::string>{}(bytes);
      std::string file;
      for (auto [at, end] = files_by_hash.equal_range(hash); at != end && file.empty(); ++at) {
        std::ifstream in(staging / at->second, std::ios::binary);
        const std::string stored((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (stored == bytes) file = at->second;
      }
      if (file.empty()) {
        const std::string stem = file_stem(c.mesh_name);
        const std::size_t use = stem_uses[stem]++;
        // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on
        // "-" + std::to_string(use) inlined here.
        file = "meshes/";
        file += stem;
        if (use != 0) {
          file += '-';
          file += std::to_string(use);
        }
        file += ".obj";
        write_file_atomically(staging / file, bytes);
        files_by_hash.emplace(hash, file);
        summary.bytes += bytes.size();
        ++summary.mesh_files;
      }
      manifest["cases"].push_back(case_entry(c, index, file));
    }
    const std::string manifest_text = manifest.dump(1) + "\n";
    write_file_atomically(staging / "manifest.json", manifest_text);
    const std::string readme = corpus_readme();
    write_file_atomically(staging / "README.md", readme);
    summary.bytes += manifest_text.size() + readme.size();
    summary.cases = indices.size();
    fs::rename(staging, dir);
  } catch (...) {
    fs::remove_all(staging, ignored);
    throw;
  }
  return summary;
}

}  // namespace shatter::robust
