#include "view_original.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <span>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/self_intersections.hpp"

namespace shatter::cli {

namespace {

using json = nlohmann::ordered_json;

struct Box {
  Vec3 low, high;
};

Box box_of(const std::vector<Vec3>& positions) {
  Box box{positions.front(), positions.front()};
  for (const Vec3& p : positions) {
    box.low = {std::min(box.low.x, p.x), std::min(box.low.y, p.y), std::min(box.low.z, p.z)};
    box.high = {std::max(box.high.x, p.x), std::max(box.high.y, p.y), std::max(box.high.z, p.z)};
  }
  return box;
}

std::string box_text(const Box& box) {
  const auto point = [](Vec3 p) {
    return "(" + json(p.x).dump() + ", " + json(p.y).dump() + ", " + json(p.z).dump() + ")";
  };
  return point(box.low) + " to " + point(box.high);
}

bool within(const Box& inner, const Box& outer) {
  for (int axis = 0; axis < 3; ++axis) {
    if (inner.low[axis] < outer.low[axis] || inner.high[axis] > outer.high[axis]) return false;
  }
  return true;
}

bool same(const Box& a, const Box& b) { return within(a, b) && within(b, a); }

// Repeated index, or three exactly collinear corners (every coordinate-plane
// projection of the triangle has zero orientation): what self_intersecting_pairs
// must not be given.
bool degenerate(const Mesh& mesh, const Triangle& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Vec3 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
  return orient2d({a.x, a.y}, {b.x, b.y}, {c.x, c.y}) == Sign::zero &&
         orient2d({a.y, a.z}, {b.y, b.z}, {c.y, c.z}) == Sign::zero &&
         orient2d({a.z, a.x}, {b.z, b.x}, {c.z, c.x}) == Sign::zero;
}

// Boundary and non-manifold edges by index: each undirected edge of a triangle
// without a repeated index, counted after a sort (as validate_mesh counts them).
void find_edge_defects(OriginalInput& original) {
  std::vector<Edge> edges;
  edges.reserve(3 * original.mesh.triangles.size());
  for (const Triangle& t : original.mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    for (int c = 0; c < 3; ++c) edges.push_back({std::min(t[c], t[(c + 1) % 3]), std::max(t[c], t[(c + 1) % 3])});
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) original.boundary_edges.push_back(edges[i]);
    if (j - i >= 3) original.non_manifold_edges.push_back(edges[i]);
    i = j;
  }
}

void find_self_intersections(OriginalInput& original) {
  std::vector<Triangle> tested;
  std::vector<TriangleIndex> index_of;  // in the mesh, of each tested triangle
  for (TriangleIndex t = 0; t < original.mesh.triangles.size(); ++t) {
    if (degenerate(original.mesh, original.mesh.triangles[t])) {
      ++original.degenerate_triangles;
      continue;
    }
    tested.push_back(original.mesh.triangles[t]);
    index_of.push_back(t);
  }
  const std::vector<TrianglePair> pairs = self_intersecting_pairs(original.mesh.positions, tested);
  original.self_intersecting_pairs = pairs.size();
  if (!pairs.empty()) original.first_intersecting_pair = {index_of[pairs.front().first], index_of[pairs.front().second]};
  for (const TrianglePair& pair : pairs) {
    original.self_intersecting_triangles.push_back(index_of[pair.first]);
    original.self_intersecting_triangles.push_back(index_of[pair.second]);
  }
  std::vector<TriangleIndex>& marked = original.self_intersecting_triangles;
  std::sort(marked.begin(), marked.end());
  marked.erase(std::unique(marked.begin(), marked.end()), marked.end());
}

template <class Rows, class Flatten>
json flat(const Rows& rows, Flatten flatten) {
  json out = json::array();
  for (const auto& row : rows) flatten(out, row);
  return out;
}

}  // namespace

OriginalInput read_original_input(const std::string& path, const Mesh& root, const RepairReport& repair) {
  OriginalInput original;
  original.name = std::filesystem::path(path).filename().string();
  try {
    original.mesh = read_mesh(path, &original.read_warnings);
  } catch (const IoError& e) {
    throw IoError("--original " + path + ": " + e.what());
  } catch (const InvalidMeshError& e) {
    throw InvalidMeshError("--original " + path + ": " + e.what());
  } catch (const CorruptFileError& e) {
    throw CorruptFileError("--original " + path + ": " + e.what());
  }
  for (const std::string& warning : original.read_warnings) std::cerr << "warning: " << path << ": " << warning << '\n';
  const Mesh& mesh = original.mesh;
  if (mesh.positions.empty() || mesh.triangles.empty()) {
    throw InvalidMeshError("--original " + path + ": no triangles to show");
  }
  for (const Vec3& p : mesh.positions) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw InvalidMeshError("--original " + path + ": cannot be shown: it has a NaN or infinite coordinate");
    }
  }
  for (const Triangle& t : mesh.triangles) {
    if (t[0] >= mesh.positions.size() || t[1] >= mesh.positions.size() || t[2] >= mesh.positions.size()) {
      throw InvalidMeshError("--original " + path + ": cannot be shown: a triangle index is out of range");
    }
  }
  if (root.positions.empty()) throw InvalidMeshError("--original " + path + ": the tree's root has no vertices");
  const Box input_box = box_of(mesh.positions), root_box = box_of(root.positions);
  const bool repaired = !repair.empty();
  if (repaired ? !within(root_box, input_box) : !same(root_box, input_box)) {
    throw InvalidMeshError("--original " + path + " is not the input of this tree: the tree's root spans " +
                           box_text(root_box) + ", the file " + box_text(input_box) +
                           (repaired ? " (a repaired root lies within its input's bounding box)"
                                     : " (the tree records no repair, so its root is its input as read)"));
  }
  original.report = validate_mesh(mesh);
  find_edge_defects(original);
  // A closed mesh validate_mesh tested and found free of crossings needs no second test.
  const bool none_crossing =
      original.report.self_intersections_checked && !original.report.find(DefectKind::self_intersection);
  if (!none_crossing) find_self_intersections(original);
  return original;
}

json original_json(const OriginalInput& original, const RepairReport& repair) {
  const Mesh& mesh = original.mesh;
  json out{{"file", original.name}, {"vertices", mesh.positions.size()}, {"triangles", mesh.triangles.size()}};
  out["positions"] = flat(mesh.positions, [](json& a, const Vec3& p) {
    a.push_back(p.x);
    a.push_back(p.y);
    a.push_back(p.z);
  });
  out["indices"] = flat(mesh.triangles, [](json& a, const Triangle& t) {
    for (VertexIndex v : t) a.push_back(v);
  });
  std::string validation = original.report.valid() ? "" : original.report.summary();
  json defects = json::array();
  for (const Defect& defect : original.report.defects) {
    defects.push_back({{"kind", defect_name(defect.kind)}, {"count", defect.count}, {"first", defect.first}});
  }
  // validate_mesh names the self-intersections of a mesh it tested; those of another (open, say) are added.
  if (original.self_intersecting_pairs > 0 && !original.report.self_intersections_checked) {
    defects.push_back({{"kind", defect_name(DefectKind::self_intersection)},
                       {"count", original.self_intersecting_pairs},
                       {"first", "triangles " + std::to_string(original.first_intersecting_pair[0]) + " and " +
                                     std::to_string(original.first_intersecting_pair[1])}});
    validation += std::string(validation.empty() ? "" : "; ") + "self-intersecting: " +
                  std::to_string(original.self_intersecting_pairs) + " triangle pairs";
  }
  out["validation"] = validation.empty() ? "valid" : validation;
  out["defects"] = std::move(defects);
  const auto edge_pairs = [](json& a, const Edge& e) {
    a.push_back(e[0]);
    a.push_back(e[1]);
  };
  out["boundary_edges"] = flat(original.boundary_edges, edge_pairs);
  out["non_manifold_edges"] = flat(original.non_manifold_edges, edge_pairs);
  out["self_intersecting_triangles"] = original.self_intersecting_triangles;
  out["degenerate_triangles"] = original.degenerate_triangles;
  out["read_warnings"] = original.read_warnings;
  if (repair.empty()) {
    out["repair"] = nullptr;
  } else {
    json changes = json::array(), not_done = json::array();
    for (const RepairChange& change : repair.changes) changes.push_back(change.text);
    for (const RepairNote& note : repair.notes) not_done.push_back(note.text);
    out["repair"] = {{"changes", std::move(changes)},      {"not_done", std::move(not_done)},
                     {"vertices_before", repair.vertices_before}, {"triangles_before", repair.triangles_before},
                     {"vertices_after", repair.vertices_after},   {"triangles_after", repair.triangles_after}};
  }
  return out;
}

}  // namespace shatter::cli
