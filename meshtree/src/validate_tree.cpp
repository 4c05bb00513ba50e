// The tree checker (validate_tree.hpp). The structural checks come first and in
// a fixed order, because each later one indexes through what the earlier ones
// proved: links before leaf ranges, leaf ranges before bonds, the structure
// before the exact representation. The .shatter reader and encoder call these
// same checks (through validate_tree and tree_checks.hpp), so whatever the
// encoder accepts the reader accepts.

#include "shatter/meshtree/validate_tree.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "shatter/kernel/certify.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/kernel/validate.hpp"
#include "node_mass.hpp"
#include "validate_tree_certificate.hpp"

namespace shatter {

std::vector<NodeIndex> leaves_in_order(const std::vector<MeshTreeNode>& nodes) {
  std::vector<NodeIndex> leaves;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    if (nodes[k].is_leaf()) leaves.push_back(static_cast<NodeIndex>(k));
  }
  return leaves;
}

namespace detail {

// `value` as "0x" and `digits` upper-case hexadecimal digits (the low ones).
std::string hex(std::uint64_t value, int digits) {
  static constexpr char digit_chars[] = "0123456789ABCDEF";
  std::string text = "0x";
  for (int k = digits - 1; k >= 0; --k) text += digit_chars[(value >> (4 * k)) & 0xF];
  return text;
}

// The checks, in detail's own unnamed namespace.
namespace {

constexpr std::uint64_t max_u32 = std::numeric_limits<std::uint32_t>::max();

/// The defect `check(k)` finds at the lowest k of [0, count), or nothing.
/// Nodes are checked in parallel, in blocks; a block stops at its first defect,
/// none goes on past the lowest found so far, and the lowest is checked again
/// for its message: the answer a loop in node order gives, on any number of
/// threads, without a defect held per node (a tree of 2^21 nodes would hold
/// over 100 MB of them). `check` must be safe to call concurrently for
/// different nodes, and again for the same one.
template <class Check>
std::optional<TreeDefect> lowest_node_defect(std::size_t count, const Check& check) {
  std::atomic<std::size_t> lowest{count};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t k = range.begin(); k != range.end() && k < lowest.load(std::memory_order_relaxed); ++k) {
      if (!check(k)) continue;
      std::size_t seen = lowest.load();
      while (k < seen && !lowest.compare_exchange_weak(seen, k)) {
      }
      return;
    }
  });
  if (lowest.load() == count) return std::nullopt;
  return check(lowest.load());
}

std::string str(std::uint64_t value) { return std::to_string(value); }

// A double in full (17 significant digits): a message must not round a tiny
// volume to 0.
std::string full_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// --- the structure ----------------------------------------------------------------

std::optional<TreeDefect> recipe_defect(const TreeRecipe& recipe) {
  if (recipe.fragments == 0) return TreeDefect{TreePart::recipe, 0, "recipe.fragments is 0 (must be at least 1)"};
  if (recipe.strategy > last_strategy) {
    return TreeDefect{
        TreePart::recipe, 0,
        "recipe.strategy " + str(static_cast<std::uint8_t>(recipe.strategy)) + " is not a known strategy"};
  }
  if (recipe.kernel > last_kernel) {
    return TreeDefect{TreePart::recipe, 0,
                      "recipe.kernel " + str(static_cast<std::uint8_t>(recipe.kernel)) + " is not a known kernel"};
  }
  return std::nullopt;
}

/// Checks the links, preorder, child counts, depths and leaf ranges. Walks the
/// children lists from the root expecting node indices 1, 2, 3, ... in visiting
/// order, so a cycle, a node with two parents, a gap or a wrong order is caught
/// at the first listing that breaks the sequence, and the walk ends after at most
/// n visits whatever the links are.
std::optional<TreeDefect> structure_defect(const std::vector<MeshTreeNode>& nodes) {
  const std::size_t node_count = nodes.size();
  if (node_count == 0) return TreeDefect{TreePart::node, 0, "the tree has no nodes (it needs at least its root)"};
  if (node_count > max_u32) {
    return TreeDefect{TreePart::node, 0,
                      "the tree has " + str(node_count) + " nodes, more than node indices can number"};
  }
  if (nodes[0].parent != no_node) {
    return TreeDefect{TreePart::node, 0, "node 0 (the root) has parent " + str(nodes[0].parent) + " instead of none"};
  }
  if (nodes[0].depth != 0)
    return TreeDefect{TreePart::node, 0, "node 0 (the root) has depth " + str(nodes[0].depth) + " instead of 0"};

  struct Visit {
    NodeIndex node;
    std::size_t next_child;
  };
  std::vector<Visit> stack = {{0, 0}};
  std::size_t next_in_preorder = 1;
  while (!stack.empty()) {
    const NodeIndex node = stack.back().node;
    const std::vector<NodeIndex>& children = nodes[node].children;
    if (children.size() == 1) {
      return TreeDefect{TreePart::node, node,
                        "node " + str(node) + " has one child (an internal node has two or more)"};
    }
    if (stack.back().next_child == children.size()) {
      stack.pop_back();
      continue;
    }
    const NodeIndex child = children[stack.back().next_child++];
    if (child != next_in_preorder) {
      std::string problem = "node " + str(node) + " lists child " + str(child);
      if (child >= node_count) {
        problem += ", but there are only " + str(node_count) + " nodes";
      } else if (child < next_in_preorder) {
        problem += ", which already has its place in the tree (a cycle, or a node listed twice)";
      } else {
        problem += ", but depth-first preorder puts node " + str(next_in_preorder) + " there";
      }
      return TreeDefect{TreePart::node, node, problem};
    }
    const MeshTreeNode& child_node = nodes[child];
    if (child_node.parent != node) {
      return TreeDefect{TreePart::node, child,
                        "node " + str(child) + " has parent " +
                            (child_node.parent == no_node ? std::string("none") : str(child_node.parent)) +
                            ", but node " + str(node) + " lists it as a child"};
    }
    if (std::uint64_t{child_node.depth} != std::uint64_t{nodes[node].depth} + 1) {
      return TreeDefect{TreePart::node, child,
                        "node " + str(child) + " has depth " + str(child_node.depth) + ", but its parent's depth is " +
                            str(nodes[node].depth)};
    }
    ++next_in_preorder;
    stack.push_back({child, 0});
  }
  if (next_in_preorder != node_count) {
    return TreeDefect{TreePart::node, next_in_preorder,
                      "node " + str(next_in_preorder) + " is not reachable from the root"};
  }

  // In preorder every subtree is an index range, and so are its leaves: a node's
  // first leaf is the number of leaves before it, its count the sum over its children.
  std::vector<std::uint32_t> leaves_below(node_count, 0);
  for (std::size_t k = node_count; k-- > 0;) {
    if (nodes[k].is_leaf()) {
      leaves_below[k] = 1;
    } else {
      for (const NodeIndex child : nodes[k].children) leaves_below[k] += leaves_below[child];
    }
  }
  std::uint32_t leaves_before = 0;
  for (std::size_t k = 0; k < node_count; ++k) {
    const MeshTreeNode& node = nodes[k];
    if (node.first_leaf != leaves_before || node.leaf_count != leaves_below[k]) {
      return TreeDefect{TreePart::leaf_range, k,
                        "node " + str(k) + " claims leaves [" + str(node.first_leaf) + ", +" + str(node.leaf_count) +
                            "), but its subtree holds [" + str(leaves_before) + ", +" + str(leaves_below[k]) + ")"};
    }
    if (node.is_leaf()) ++leaves_before;
  }
  return std::nullopt;
}

// Any tree, of any kernel: the plane of every node, kept beside the nodes
// (MeshTree::cut_planes), so a node without one would be indexed past the end.
// A cell tree (voronoi.hpp) keeps its cell planes after the nodes' (MeshTree::
// cut_planes): each finite with a non-zero normal.
std::optional<TreeDefect> cut_planes_defect(const MeshTree& tree) {
  if (tree.cut_planes.size() < tree.nodes.size()) {
    return TreeDefect{TreePart::cut_planes, 0,
                      "cut_planes has " + str(tree.cut_planes.size()) + " planes for " + str(tree.nodes.size()) +
                          " nodes (one per node)"};
  }
  if (tree.cut_planes.size() > PlaneRef::cut_bit) {
    return TreeDefect{TreePart::cut_planes, tree.nodes.size(),
                      "cut_planes has " + str(tree.cut_planes.size()) + " planes, more than a plane reference can name"};
  }
  for (std::size_t k = tree.nodes.size(); k < tree.cut_planes.size(); ++k) {
    const Plane& plane = tree.cut_planes[k];
    const Vec3& n = plane.normal;
    if (!(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) && std::isfinite(plane.offset)) ||
        (plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0)) {
      return TreeDefect{TreePart::cut_planes, k,
                        "cell plane " + str(k) + " has a NaN or infinite coefficient or a zero normal"};
    }
  }
  return std::nullopt;
}

/// A node whose children are cells (voronoi.hpp): in a cell tree, an internal
/// node whose own plane is all zero. A cell tree is one built as one
/// (recipe.strategy voronoi) or one with cell planes: a Voronoi build whose
/// every fragment is a whole shell of the input, its cell cutting nothing (two
/// disjoint solids, a site beside each), uses no bisector and keeps none.
bool is_cell_node(const MeshTree& tree, NodeIndex k) {
  const Plane& plane = tree.cut_planes[k];
  const bool cell_tree = tree.recipe.strategy == Strategy::voronoi || tree.cut_planes.size() > tree.nodes.size();
  return cell_tree && !tree.nodes[k].is_leaf() && plane.normal.x == 0 && plane.normal.y == 0 &&
         plane.normal.z == 0 && plane.offset == 0;
}

std::optional<TreeDefect> leaf_list_defect(const MeshTree& tree) {
  const std::vector<NodeIndex> expected = leaves_in_order(tree.nodes);
  if (tree.leaf_nodes.size() != expected.size()) {
    return TreeDefect{
        TreePart::leaf_list, 0,
        "leaf_nodes lists " + str(tree.leaf_nodes.size()) + " leaves, but the tree has " + str(expected.size())};
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (tree.leaf_nodes[i] != expected[i]) {
      return TreeDefect{TreePart::leaf_list, i,
                        "leaf_nodes[" + str(i) + "] is node " + str(tree.leaf_nodes[i]) + ", but leaf " + str(i) +
                            " is node " + str(expected[i])};
    }
  }
  return std::nullopt;
}

/// The first BasicMesh invariant `mesh` breaks, or nothing.
std::optional<std::string> mesh_defect(const Mesh& mesh) {
  if (mesh.positions.size() > max_u32)
    return "has " + str(mesh.positions.size()) + " vertices, more than a u32 can count";
  if (mesh.triangles.size() > max_u32)
    return "has " + str(mesh.triangles.size()) + " triangles, more than a u32 can count";
  const std::size_t triangle_count = mesh.triangles.size();
  if (mesh.surfaces.size() != triangle_count) {
    return "has " + str(mesh.surfaces.size()) + " surface ids for " + str(triangle_count) + " triangles";
  }
  const std::array<std::pair<const char*, std::size_t>, 3> channels = {{{"normals", mesh.corners.normals.size()},
                                                                        {"uvs", mesh.corners.uvs.size()},
                                                                        {"tangents", mesh.corners.tangents.size()}}};
  for (const auto& [name, size] : channels) {
    if (size != 0 && size != 3 * triangle_count) {
      return std::string("has ") + str(size) + " " + name + " for " + str(triangle_count) +
             " triangles (need 0 or 3 per triangle)";
    }
  }
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (std::size_t corner = 0; corner < 3; ++corner) {
      const VertexIndex vertex = mesh.triangles[t][corner];
      if (vertex >= mesh.positions.size()) {
        return "triangle " + str(t) + " corner " + str(corner) + " has vertex index " + str(vertex) +
               ", but there are only " + str(mesh.positions.size()) + " vertices";
      }
    }
  }
  return std::nullopt;
}

/// The child of `node` whose leaf range holds `leaf`, or no_node.
// The children's leaf ranges follow each other in order (a valid structure), so
// the child is found by binary search: a cell node has thousands of children.
NodeIndex child_holding(const std::vector<MeshTreeNode>& nodes, NodeIndex node, LeafIndex leaf) {
  const std::vector<NodeIndex>& children = nodes[node].children;
  auto after = std::upper_bound(children.begin(), children.end(), leaf,
                                [&](LeafIndex l, NodeIndex child) { return l < nodes[child].first_leaf; });
  if (after == children.begin()) return no_node;
  const NodeIndex child = *(after - 1);
  return leaf - nodes[child].first_leaf < nodes[child].leaf_count ? child : no_node;  // unsigned: also rejects leaf < first_leaf
}

/// Bonds in range, sorted, each between two leaves its cut_node's cut separates
/// (cut_node is their lowest common ancestor: both below it, under different
/// children). Requires a valid structure.
std::optional<TreeDefect> bonds_defect(const MeshTree& tree) {
  const std::size_t leaf_count = tree.leaf_nodes.size();
  // Packed bonds (a lean build's) are checked as what they unpack to, once
  // unpack_bond's precondition holds.
  if (!tree.bonds.empty() && !tree.packed_bonds.empty()) {
    return TreeDefect{TreePart::bond, 0, "the tree keeps bonds both packed and not"};
  }
  for (std::size_t i = 0; i < tree.packed_bonds.size(); ++i) {
    const PackedBond& packed = tree.packed_bonds[i];
    if (packed.cut_node >= tree.cut_planes.size() || packed.axis > 2) {
      return TreeDefect{TreePart::bond, i, "packed bond " + str(i) + " names no cut plane or no axis"};
    }
  }
  for (std::size_t i = 0; i < tree.bond_count(); ++i) {
    const Bond bond = tree.bond(i);
    // Named only when refused: made for every bond, the names were a tenth of reading a file back.
    const auto name = [&] {
      return "bond " + str(i) + " (" + str(bond.first) + ", " + str(bond.second) + ", cut node " +
             (bond.cut_node == no_node ? std::string("none") : str(bond.cut_node)) + ")";
    };
    if (bond.first >= bond.second) return TreeDefect{TreePart::bond, i, name() + " does not have first < second"};
    if (bond.second >= leaf_count)
      return TreeDefect{TreePart::bond, i, name() + " names a leaf beyond the " + str(leaf_count) + " leaves"};
    if (bond.cut_node >= tree.nodes.size() || tree.nodes[bond.cut_node].is_leaf()) {
      return TreeDefect{TreePart::bond, i, name() + " does not name an internal node as its cut"};
    }
    const NodeIndex first_side = child_holding(tree.nodes, bond.cut_node, bond.first);
    const NodeIndex second_side = child_holding(tree.nodes, bond.cut_node, bond.second);
    if (first_side == no_node || second_side == no_node || first_side == second_side) {
      return TreeDefect{TreePart::bond, i, name() + " joins leaves that the cut of its cut node does not separate"};
    }
    if (i > 0) {
      const Bond previous = tree.bond(i - 1);
      if (std::tie(previous.first, previous.second, previous.cut_node) >
          std::tie(bond.first, bond.second, bond.cut_node)) {
        return TreeDefect{TreePart::bond, i, name() + " is out of order (bonds are sorted by first, second, cut node)"};
      }
    }
  }
  return std::nullopt;
}

// --- the exact representation (plane kernel) ---------------------------------

bool finite(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

bool solid_is_empty(const Solid& solid) {
  return solid.defs.empty() && solid.approx.empty() && solid.faces.empty() && solid.loops.empty() &&
         solid.corners.empty() && !solid.convex;
}

std::string point_kind_name(PointKind kind) {
  switch (kind) {
    case PointKind::input:
      return "input";
    case PointKind::segment_plane:
      return "segment_plane";
    case PointKind::three_planes:
      return "three_planes";
  }
  return "kind " + str(static_cast<std::uint8_t>(kind));
}

/// What the plane kernel's checks need to know about the tree, computed once.
struct ExactContext {
  std::size_t point_count = 0;
  std::size_t input_plane_count = 0;
  /// Cut planes from node_count on are cell planes, which any node may use.
  std::size_t node_count = 0, cut_plane_count = 0;
  /// In preorder node a's subtree is [a, subtree_end[a]), so a is a strict
  /// ancestor of k exactly when a < k < subtree_end[a].
  std::vector<NodeIndex> subtree_end;
};

/// Buffers reused from one solid to the next, so that checking every node's
/// solid allocates about as much as checking the largest.
struct SolidScratch {
  std::vector<std::uint64_t> edges;
  std::vector<char> used;
};

/// Why `plane` may not appear in node `node`'s solid, or nothing: it must be an
/// input plane in range, or the cut plane of a strict ancestor of the node.
std::optional<std::string> plane_defect(PlaneRef plane, std::size_t node, const ExactContext& context) {
  if (plane.is_cut()) {
    const std::uint32_t owner = plane.index();
    if (owner >= context.node_count && owner < context.cut_plane_count) return std::nullopt;  // a cell plane
    if (owner < node && node < context.subtree_end[owner]) return std::nullopt;
    return "names cut plane " + str(owner) + " (" + hex(plane.bits, 8) + "), but node " + str(owner) +
           " is not an ancestor of node " + str(node) + " (a solid only lies on its ancestors' cut planes)";
  }
  if (plane.index() < context.input_plane_count) return std::nullopt;
  return "names input plane " + str(plane.index()) + ", but there are only " + str(context.input_plane_count) +
         " input planes";
}

std::optional<std::string> point_defect(std::uint32_t point, const ExactContext& context) {
  if (point < context.point_count) return std::nullopt;
  return "names input point " + str(point) + ", but there are only " + str(context.point_count) + " input points";
}

/// The first structural defect of node `node`'s solid (file.hpp lists the checks),
/// or nothing. `caches`: also require one approx per vertex or none (a lean
/// build's; the encoder's precondition; the decoder computes them after these
/// checks).
std::optional<std::string> solid_defect(const Solid& solid, std::size_t node, const ExactContext& context, bool caches,
                                        SolidScratch& scratch) {
  const std::size_t vertex_count = solid.defs.size(), loop_count = solid.loops.size(),
                    corner_count = solid.corners.size();
  for (const auto& [name, size] : std::array<std::pair<const char*, std::size_t>, 4>{{{"vertices", vertex_count},
                                                                                      {"faces", solid.faces.size()},
                                                                                      {"loops", loop_count},
                                                                                      {"corners", corner_count}}}) {
    if (size > max_u32) return "has " + str(size) + " " + name + ", more than a u32 can count";
  }
  if (caches && !solid.approx.empty() && solid.approx.size() != vertex_count) {
    return "has " + str(solid.approx.size()) + " approx entries for " + str(vertex_count) + " vertices";
  }

  for (std::size_t v = 0; v < vertex_count; ++v) {
    const PointDef& def = solid.defs[v];
    const auto kind = static_cast<std::uint8_t>(def.kind);
    if (kind > static_cast<std::uint8_t>(last_point_kind)) return "vertex " + str(v) + " has unknown kind " + str(kind);
    const auto name = [&] { return "vertex " + str(v) + " (" + point_kind_name(def.kind) + ") "; };
    // How many of a, b and planes[] the kind uses; the rest must be zero.
    const int points_used = def.kind == PointKind::input ? 1 : def.kind == PointKind::segment_plane ? 2 : 0;
    const int planes_used = def.kind == PointKind::input ? 0 : def.kind == PointKind::segment_plane ? 1 : 3;
    const std::array<std::uint32_t, 2> points = {def.a, def.b};
    for (int k = 0; k < 2; ++k) {
      if (k < points_used) {
        if (auto problem = point_defect(points[k], context)) return name() + *problem;
      } else if (points[k] != 0) {
        return name() + "has " + (k == 0 ? "a" : "b") + " = " + str(points[k]) +
               ", a field its kind does not use (must be 0)";
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (k < planes_used) {
        if (auto problem = plane_defect(def.planes[k], node, context))
          return name() + "plane " + str(k) + " " + *problem;
      } else if (def.planes[k].bits != 0) {
        return name() + "has plane " + str(k) + " = " + hex(def.planes[k].bits, 8) +
               ", a field its kind does not use (must be 0)";
      }
    }
  }

  std::uint64_t next_loop = 0;
  for (std::size_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    const auto name = [&] { return "face " + str(f) + " "; };
    if (auto problem = plane_defect(face.plane, node, context)) return name() + *problem;
    if (face.loop_count == 0) return name() + "has no loop";
    if (face.first_loop != next_loop) {
      return name() + "starts at loop " + str(face.first_loop) + ", but the faces before it end at loop " +
             str(next_loop) + " (faces take the loops in order)";
    }
    next_loop += face.loop_count;
    if (next_loop > loop_count)
      return name() + "has loops up to " + str(next_loop) + ", but there are only " + str(loop_count) + " loops";
  }
  if (next_loop != loop_count) return "has " + str(loop_count) + " loops, but its faces hold " + str(next_loop);

  std::uint64_t next_corner = 0;
  for (std::size_t l = 0; l < loop_count; ++l) {
    const SolidLoop& loop = solid.loops[l];
    const auto name = [&] { return "loop " + str(l) + " "; };
    if (loop.corner_count < 3) return name() + "has " + str(loop.corner_count) + " corners (a loop has at least 3)";
    if (loop.first_corner != next_corner) {
      return name() + "starts at corner " + str(loop.first_corner) + ", but the loops before it end at corner " +
             str(next_corner) + " (loops take the corners in order)";
    }
    next_corner += loop.corner_count;
    if (next_corner > corner_count) {
      return name() + "has corners up to " + str(next_corner) + ", but there are only " + str(corner_count) +
             " corners";
    }
  }
  if (next_corner != corner_count)
    return "has " + str(corner_count) + " corners, but its loops hold " + str(next_corner);

  for (std::size_t c = 0; c < corner_count; ++c) {
    const SolidCorner& corner = solid.corners[c];
    const auto name = [&] { return "corner " + str(c) + " "; };
    if (corner.vertex >= vertex_count) {
      return name() + "has vertex " + str(corner.vertex) + ", but there are only " + str(vertex_count) + " vertices";
    }
    if (corner.line.other.bits != no_index) {
      if (auto problem = plane_defect(corner.line.other, node, context)) return name() + "line " + *problem;
    }
    const EdgeLine& line = corner.line;
    if (line.p != no_index || line.q != no_index) {
      if (!(line.p < line.q && line.q < context.point_count)) {
        return name() + "has segment (" + str(line.p) + ", " + str(line.q) + "), not two input points p < q < " +
               str(context.point_count) + " nor none (both " + hex(no_index, 8) + ")";
      }
    }
  }

  // Closed: every directed edge used once, and its reverse used too.
  scratch.edges.clear();
  scratch.used.assign(vertex_count, 0);
  for (const SolidLoop& loop : solid.loops) {
    for (const CornerEdge& edge : loop_edges(solid.corners, loop)) {
      const VertexIndex from = edge.from, to = edge.to;
      if (from == to)
        return "corner " + str(edge.corner) + " repeats vertex " + str(from) + " of the corner after it";
      scratch.used[from] = 1;
      scratch.edges.push_back((std::uint64_t{from} << 32) | to);
    }
  }
  std::sort(scratch.edges.begin(), scratch.edges.end());
  const auto edge_name = [](std::uint64_t edge) {
    return "edge (" + str(edge >> 32) + ", " + str(edge & 0xFFFFFFFFu) + ") ";
  };
  if (const auto twice = std::adjacent_find(scratch.edges.begin(), scratch.edges.end()); twice != scratch.edges.end()) {
    return edge_name(*twice) + "is used twice";
  }
  for (const std::uint64_t edge : scratch.edges) {
    const std::uint64_t reverse = (edge << 32) | (edge >> 32);
    if (!std::binary_search(scratch.edges.begin(), scratch.edges.end(), reverse))
      return edge_name(edge) + "has no reverse: the solid is open";
  }
  for (std::size_t v = 0; v < vertex_count; ++v) {
    if (scratch.used[v] == 0) return "vertex " + str(v) + " is used by no corner";
  }
  return std::nullopt;
}

/// The exact representation's defects: geometry, cut planes, convex flags and
/// solids (file.hpp, decode_shatter). Requires a valid structure.
std::optional<TreeDefect> exact_defect(const MeshTree& tree, bool caches) {
  const InputGeometry& geometry = tree.geometry;
  const std::size_t node_count = tree.nodes.size();
  if (caches && geometry.plane_approx.size() != geometry.planes.size()) {
    return TreeDefect{TreePart::input_plane, 0,
                      "geometry has " + str(geometry.plane_approx.size()) + " plane_approx entries for " +
                          str(geometry.planes.size()) + " input planes"};
  }
  if (geometry.points.empty()) {
    // No exact representation: nothing of it may be present.
    if (!geometry.planes.empty()) {
      return TreeDefect{TreePart::input_plane, 0,
                        "geometry has " + str(geometry.planes.size()) + " input planes but no input points"};
    }
    for (std::size_t k = 0; k < node_count; ++k) {
      if (!solid_is_empty(tree.nodes[k].solid)) {
        return TreeDefect{TreePart::solid, k,
                          "node " + str(k) + " has a solid, but the tree has no geometry (no input points)"};
      }
      if (tree.nodes[k].convex) {
        return TreeDefect{
            TreePart::solid, k,
            "node " + str(k) + " is marked convex, but the tree has no exact representation (no input points)"};
      }
    }
    return std::nullopt;
  }

  ExactContext context;
  context.point_count = geometry.points.size();
  context.input_plane_count = geometry.planes.size();
  context.node_count = tree.nodes.size();
  context.cut_plane_count = tree.cut_planes.size();
  if (context.point_count > max_u32) {
    return TreeDefect{TreePart::input_point, 0,
                      "geometry has " + str(context.point_count) + " input points, more than a u32 can count"};
  }
  if (context.input_plane_count > PlaneRef::cut_bit) {
    return TreeDefect{TreePart::input_plane, 0,
                      "geometry has " + str(context.input_plane_count) +
                          " input planes, more than a plane reference can name (2^31)"};
  }
  for (std::size_t i = 0; i < context.point_count; ++i) {
    if (!finite(geometry.points[i]))
      return TreeDefect{TreePart::input_point, i,
                        "input point " + str(i) + " has a coordinate that is NaN or infinite"};
  }
  for (std::size_t j = 0; j < context.input_plane_count; ++j) {
    for (const VertexIndex point : geometry.planes[j]) {
      if (point >= context.point_count) {
        return TreeDefect{TreePart::input_plane, j,
                          "input plane " + str(j) + " names input point " + str(point) + ", but there are only " +
                              str(context.point_count) + " input points"};
      }
    }
  }
  for (std::size_t k = 0; k < node_count; ++k) {
    const Plane& plane = tree.cut_planes[k];
    if (!tree.nodes[k].is_leaf() && !(finite(plane.normal) && std::isfinite(plane.offset))) {
      return TreeDefect{
          TreePart::node, k,
          "node " + str(k) +
              " has a plane with a NaN or infinite coefficient (a cut plane of the exact representation)"};
    }
  }

  context.subtree_end.resize(node_count);
  for (std::size_t k = node_count; k-- > 0;) {
    const MeshTreeNode& node = tree.nodes[k];
    context.subtree_end[k] = node.is_leaf() ? static_cast<NodeIndex>(k + 1) : context.subtree_end[node.children.back()];
  }
  return lowest_node_defect(node_count, [&](std::size_t k) -> std::optional<TreeDefect> {
    const MeshTreeNode& node = tree.nodes[k];
    if (node.convex && !(node.hull->positions.empty() && node.hull->triangles.empty())) {
      return TreeDefect{
          TreePart::hull, k,
          "node " + str(k) + " is convex, so its hull must be empty (its mesh is its hull), but the hull has " +
              str(node.hull->positions.size()) + " vertices and " + str(node.hull->triangles.size()) + " triangles"};
    }
    thread_local SolidScratch scratch;
    NodeShapes shapes(tree);  // first_defect has unpacked every packed node
    if (auto problem = solid_defect(shapes(static_cast<NodeIndex>(k)).solid, k, context, caches, scratch)) {
      return TreeDefect{TreePart::solid, k, "the solid of node " + str(k) + " " + *problem};
    }
    return std::nullopt;
  });
}

/// A lean build's packed nodes (MeshTree::packed_shapes): one entry per node or
/// none, only in a tree with an exact representation, and a packed node keeps
/// no mesh or solid of its own. (Whether the bytes unpack, first_defect finds.)
std::optional<TreeDefect> packed_defect(const MeshTree& tree) {
  if (tree.packed_shapes.empty()) return std::nullopt;
  if (tree.packed_shapes.size() != tree.nodes.size()) {
    return TreeDefect{TreePart::mesh, 0,
                      "the tree has " + str(tree.packed_shapes.size()) + " packed node entries for " +
                          str(tree.nodes.size()) + " nodes"};
  }
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    if (!tree.is_packed(static_cast<NodeIndex>(k))) continue;
    const MeshTreeNode& node = tree.nodes[k];
    if (!tree.has_exact_representation()) {
      return TreeDefect{TreePart::mesh, k,
                        "node " + str(k) + " has a packed mesh and solid, but the tree has no exact representation"};
    }
    if (!node.mesh->positions.empty() || !node.mesh->triangles.empty() || !solid_is_empty(node.solid)) {
      return TreeDefect{TreePart::mesh, k, "node " + str(k) + " has a packed mesh and solid and keeps others of its own"};
    }
  }
  return std::nullopt;
}

/// The first defect of `tree`, or nothing. `caches`: also check that the
/// exact representation's caches are sized (the encoder's precondition).
std::optional<TreeDefect> first_defect(const MeshTree& tree, bool caches) {
  if (auto defect = recipe_defect(tree.recipe)) return defect;
  if (auto defect = structure_defect(tree.nodes)) return defect;
  if (auto defect = leaf_list_defect(tree)) return defect;
  if (auto defect = cut_planes_defect(tree)) return defect;
  if (auto defect = packed_defect(tree)) return defect;
  const auto node_defect = [&](std::size_t k) -> std::optional<TreeDefect> {
    NodeShapes shapes(tree);
    const Mesh* mesh = nullptr;
    try {
      mesh = &shapes(static_cast<NodeIndex>(k)).mesh;
    } catch (const std::invalid_argument& error) {
      return TreeDefect{TreePart::mesh, k, "the packed mesh and solid of node " + str(k) + " do not unpack: " + error.what()};
    }
    if (auto problem = mesh_defect(*mesh))
      return TreeDefect{TreePart::mesh, k, "the mesh of node " + str(k) + " " + *problem};
    if (auto problem = mesh_defect(*tree.nodes[k].hull))
      return TreeDefect{TreePart::hull, k, "the hull of node " + str(k) + " " + *problem};
    return std::nullopt;
  };
  if (auto defect = lowest_node_defect(tree.nodes.size(), node_defect)) return defect;
  if (auto defect = bonds_defect(tree)) return defect;
  return exact_defect(tree, caches);
}

// --- the caches --------------------------------------------------------------------

/// The caches the file does not store, computed from what it does store: input
/// planes' approximations (approximate_input_plane) and every solid vertex's
/// (approximate() over the tree's PlaneSet). `fill`: store them in the tree (the
/// decoder; `fill` is `&tree`); otherwise compare them with the tree's, bit for bit (the encoder:
/// equal caches are what makes decode(encode(tree)) equal to the tree).
/// Requires a tree that passed first_defect. Returns the first vertex whose
/// definition is degenerate (its planes meet in no single point), or, when
/// comparing, the first cache entry that differs. A solid without approx (a lean
/// build's) has nothing to compare; its definitions are approximated all the
/// same, since a degenerate one is what the reader would refuse.
std::optional<TreeDefect> caches_defect(const MeshTree& tree, MeshTree* fill) {
  const InputGeometry& geometry = tree.geometry;
  if (geometry.points.empty()) return std::nullopt;
  if (fill) fill->geometry.plane_approx.resize(geometry.planes.size());
  for (std::size_t j = 0; j < geometry.planes.size(); ++j) {
    const auto& plane = geometry.planes[j];
    const ApproxPlane approx =
        approximate_input_plane(geometry.points[plane[0]], geometry.points[plane[1]], geometry.points[plane[2]]);
    if (fill) {
      fill->geometry.plane_approx[j] = approx;
    } else if (std::memcmp(&approx, &geometry.plane_approx[j], sizeof approx) != 0) {
      return TreeDefect{TreePart::input_plane, j,
                        "geometry.plane_approx[" + str(j) + "] is not approximate_input_plane of input plane " +
                            str(j) + " (a stale cache)"};
    }
  }
  // Made after plane_approx is filled: the set views it.
  const PlaneSet set = tree.plane_set();
  // Nodes in parallel, each on its own (its own approximations filled).
  const auto node_defect = [&](std::size_t k) -> std::optional<TreeDefect> {
    NodeShapes shapes(tree);  // fill_tree_caches unpacks every node first
    const Solid& solid = shapes(static_cast<NodeIndex>(k)).solid;
    // Appended rather than resized and overwritten: reading a tree fills every
    // node's approximations once, and zeroing them first was a tenth of `info`.
    std::vector<ApproxPoint>* filled = fill ? &fill->nodes[k].solid->approx : nullptr;
    if (filled) {
      filled->clear();
      filled->reserve(solid.defs.size());
    }
    for (std::size_t v = 0; v < solid.defs.size(); ++v) {
      const auto vertex = [&] {
        return "the solid of node " + str(k) + " vertex " + str(v) + " (" + point_kind_name(solid.defs[v].kind) + ")";
      };
      ApproxPoint approx;
      try {
        approx = approximate(set, solid.defs[v]);
      } catch (const std::domain_error& error) {
        return TreeDefect{TreePart::solid, k, vertex() + ": " + error.what()};
      }
      if (filled) {
        filled->push_back(approx);
      } else if (!solid.approx.empty() && std::memcmp(&approx, &solid.approx[v], sizeof approx) != 0) {
        return TreeDefect{TreePart::solid, k,
                          vertex() + ": approx is not approximate() of its definition (a stale cache)"};
      }
    }
    return std::nullopt;
  };
  return lowest_node_defect(tree.nodes.size(), node_defect);
}

// --- the geometry (TreeValidationOptions::geometry) -------------------------------

// Defects a tree built with allow_self_intersections may have: its pieces are
// promised closed and oriented, manifold along every edge (TreeRecipe). A vertex
// where separate fans meet is let through with the flag, as the input check lets
// it through (require_valid_solid: a surface touching itself at a point is the
// point case of a self-intersection): the root is that input, and a cut carries
// the vertex into its pieces. (Until 2026-12-07 the checker refused it, so
// `fracture --allow-self-intersections` of CGAL's cow wrote a file `info --check`
// refused.)
bool embedding_defect(DefectKind kind) {
  return kind == DefectKind::zero_area_triangle || kind == DefectKind::inward_orientation ||
         kind == DefectKind::self_intersection || kind == DefectKind::non_manifold_vertex;
}

/// The first geometric defect of node `k`: its plane and children's sides, its
/// mass, its mesh, its hull. Requires a tree that passed first_defect.
std::optional<TreeDefect> node_geometry_defect(const MeshTree& tree, NodeIndex k, bool certificates) {
  const MeshTreeNode& node = tree.nodes[k];
  NodeShapes shapes(tree);
  const Mesh& mesh = shapes(k).mesh;  // first_defect has unpacked every packed node
  const std::string name = "node " + str(k);
  if (!node.is_leaf() && !is_cell_node(tree, k)) {
    const Plane& plane = tree.cut_planes[k];
    if (!(finite(plane.normal) && std::isfinite(plane.offset))) {
      return TreeDefect{TreePart::node, k, name + " is cut by a plane with a NaN or infinite coefficient"};
    }
    if (plane.normal.x == 0 && plane.normal.y == 0 && plane.normal.z == 0) {
      return TreeDefect{TreePart::node, k, name + " is cut by a plane with a zero normal"};
    }
    // A plane that leaves the whole node on one side has not cut it.
    const auto above = [&](NodeIndex child) { return tree.nodes[child].above_parent_plane; };
    if (std::all_of(node.children.begin(), node.children.end(), above) ||
        std::none_of(node.children.begin(), node.children.end(), above)) {
      return TreeDefect{TreePart::node, k,
                        name + " has all its " + str(node.children.size()) + " children on one side of its plane"};
    }
  }
  const MassProperties& mass = node.mass;
  if (!storable_mass(mass)) {
    return TreeDefect{TreePart::node, k,
                      name + " has mass properties that are not finite or a volume that is not positive (volume " +
                          full_digits(mass.volume) + ")"};
  }

  // validate_mesh finds nothing wrong with no triangles at all.
  if (mesh.triangles.empty()) return TreeDefect{TreePart::mesh, k, "the mesh of " + name + " is empty"};
  const bool topology_only = tree.recipe.allow_self_intersections;
  // A certified mesh is one validate_mesh finds valid; a declined one proves
  // nothing and is checked in full.
  if (!(certificates && !topology_only && certify_piece(mesh))) {
    ValidationReport mesh_report = validate_mesh(mesh, {.check_self_intersections = !topology_only});
    if (topology_only) {
      std::erase_if(mesh_report.defects, [](const Defect& defect) { return embedding_defect(defect.kind); });
    }
    if (!mesh_report.valid()) {
      return TreeDefect{TreePart::mesh, k, "the mesh of " + name + " is not a valid solid: " + mesh_report.summary()};
    }
  }
  // A convex node is its own hull (the structure checked that none is stored).
  if (!node.convex) {
    if (node.hull->triangles.empty()) {
      return TreeDefect{TreePart::hull, k, "the hull of " + name + " is empty, and the node is not marked convex"};
    }
    const ValidationReport hull_report = validate_mesh(*node.hull, {.check_self_intersections = false});
    if (!hull_report.valid()) {
      return TreeDefect{TreePart::hull, k, "the hull of " + name + " is not a valid solid: " + hull_report.summary()};
    }
  }
  return std::nullopt;
}

/// The geometric defect of the lowest-numbered node that has one. Nodes are
/// checked in parallel, each on its own, so the answer never depends on threads.
std::optional<TreeDefect> geometry_defect(const MeshTree& tree, bool certificates) {
  return lowest_node_defect(tree.nodes.size(), [&](std::size_t k) {
    return node_geometry_defect(tree, static_cast<NodeIndex>(k), certificates);
  });
}

}  // namespace

// --- the certificate's digest (validate_tree_certificate.hpp) ----------------------

namespace {

/// Four lanes over 64-bit words, word k going to lane k mod 4. Each step,
/// lane' = rotl((lane ^ word) * K, r) with K odd, is a bijection of the lane for
/// a fixed word and of the word for a fixed lane, so two inputs that differ in
/// one word leave different lanes after it, and every later step keeps them
/// different. The two outputs fold the lanes in turn, each fold a bijection of
/// the lane it takes for the others fixed, then MurmurHash3's fmix64 (itself a
/// bijection) spreads them: a change confined to one word is always seen.
/// (Two lanes that both took every word ran one word per multiply-rotate
/// latency: 5 % of `fracture cube.off --fragments 65536`, which digests the tree
/// twice; four independent chains overlap.) Not a cryptographic hash
/// (TreeCertifier::digest says why none is needed).
class ContentDigest {
 public:
  void word(std::uint64_t w) {
    std::uint64_t& lane = lanes_[words_ & 3];
    lane = std::rotl((lane ^ w) * multipliers[words_ & 3], 27);
    ++words_;
  }
  /// `count` bytes, with the count first, so arrays of different lengths never
  /// run into each other.
  void bytes(const void* data, std::size_t count) {
    word(count);
    const auto* at = static_cast<const unsigned char*>(data);
    std::size_t k = 0;
    for (; k + 8 <= count; k += 8) {
      std::uint64_t w;
      std::memcpy(&w, at + k, 8);
      word(w);
    }
    if (k < count) {
      std::uint64_t w = 0;
      std::memcpy(&w, at + k, count - k);
      word(w);
    }
  }
  /// A vector of a type without padding (its bytes are its value).
  template <class T>
  void values(const std::vector<T>& vector) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(vector.data(), vector.size() * sizeof(T));
  }
  void real(double value) { word(std::bit_cast<std::uint64_t>(value)); }
  /// Another digest's state (its word count, then its four lanes) as five
  /// words of this one. Its lanes are all it passes on: a change confined to
  /// one of its words changes one of its lanes (each step a bijection of the
  /// lane), so one word here, and so this digest's lanes and outputs.
  void state_of(const ContentDigest& part) {
    word(part.words_);
    for (const std::uint64_t lane : part.lanes_) word(lane);
  }
  std::array<std::uint64_t, 2> finish() const {
    std::uint64_t first = words_, second = ~words_;
    for (int i = 0; i < 4; ++i) {
      first = (first ^ lanes_[i]) * 0x9E3779B97F4A7C15ull;
      second = (second + lanes_[3 - i]) * 0xC2B2AE3D27D4EB4Full;
    }
    return {fmix(first), fmix(second)};
  }

 private:
  static constexpr std::uint64_t multipliers[4] = {0x9E3779B97F4A7C15ull, 0xC2B2AE3D27D4EB4Full,
                                                   0x165667B19E3779F9ull, 0xD6E8FEB86659FD93ull};
  static std::uint64_t fmix(std::uint64_t k) {
    k ^= k >> 33;
    k *= 0xFF51AFD7ED558CCDull;
    k ^= k >> 33;
    k *= 0xC4CEB9FE1A85EC53ull;
    k ^= k >> 33;
    return k;
  }
  std::uint64_t lanes_[4] = {0x243F6A8885A308D3ull, 0x13198A2E03707344ull, 0xA4093822299F31D0ull,
                             0x082EFA98EC4E6C89ull};
  std::uint64_t words_ = 0;
};

// The arrays hashed as bytes have no padding: every byte is part of a value.
// (Structs with padding, PointDef, SolidFace and Bond, are hashed field by
// field, and so are the records below.) A new field in a record hashed field by
// field changes its size: the asserts say where to add it.
static_assert(sizeof(Vec2) == 16 && sizeof(Vec3) == 24 && sizeof(Vec4) == 32 && sizeof(Plane) == 32);
static_assert(sizeof(ApproxPoint) == 64 && sizeof(ApproxPlane) == 64);
static_assert(sizeof(MassProperties) == 13 * sizeof(double));
static_assert(std::has_unique_object_representations_v<SolidCorner> &&
              std::has_unique_object_representations_v<SolidLoop> &&
              std::has_unique_object_representations_v<std::array<VertexIndex, 3>>);
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(PointDef) == 24, "a new PointDef field: add it to hash_solid");
static_assert(sizeof(SolidFace) == 24, "a new SolidFace field: add it to hash_solid");
static_assert(sizeof(Solid) == 128, "a new Solid field: add it to hash_solid");
static_assert(sizeof(Mesh) == 144, "a new Mesh field: add it to hash_mesh");
static_assert(sizeof(Bond) == 72, "a new Bond field: add it to TreeCertifier::digest");
static_assert(sizeof(MeshTreeNode) == 184, "a new MeshTreeNode field: add it to TreeCertifier::digest");
static_assert(sizeof(InputGeometry) == 72, "a new InputGeometry field: add it to TreeCertifier::digest");
static_assert(sizeof(TreeRecipe) == 72, "a new TreeRecipe field: add it to TreeCertifier::digest");
#endif

void hash_mesh(ContentDigest& digest, const Mesh& mesh) {
  digest.values(mesh.positions);
  digest.values(mesh.triangles);
  digest.values(mesh.surfaces);
  digest.values(mesh.corners.normals);
  digest.values(mesh.corners.uvs);
  digest.values(mesh.corners.tangents);
}

std::uint64_t pair_of(std::uint32_t low, std::uint32_t high) { return std::uint64_t{low} | std::uint64_t{high} << 32; }

void hash_solid(ContentDigest& digest, const Solid& solid) {
  digest.word(solid.defs.size());
  for (const PointDef& def : solid.defs) {
    digest.word(static_cast<std::uint64_t>(def.kind) | std::uint64_t{def.a} << 8);
    digest.word(pair_of(def.b, def.planes[0].bits));
    digest.word(pair_of(def.planes[1].bits, def.planes[2].bits));
  }
  digest.values(solid.approx);
  digest.word(solid.faces.size());
  for (const SolidFace& face : solid.faces) {
    digest.word(pair_of(face.plane.bits, (face.reversed ? 1u : 0u) | (face.convex ? 2u : 0u)));
    digest.word(pair_of(face.surface, face.source));
    digest.word(pair_of(face.first_loop, face.loop_count));
  }
  digest.values(solid.loops);
  digest.values(solid.corners);
  digest.word(solid.convex ? 1 : 0);
}

/// Hashes items [0, count) into `digest`: runs of `run` items (a fixed
/// length, so the value never depends on the threads), each hashed by
/// `hash(item, part)` into a digest of its own, in parallel, then each run's
/// state in order (state_of). Without this one pass was serial: some 2 % of
/// `fracture cube.off --fragments 65536` (the build's certificate, then the
/// writer's check of it), alone on one thread while the others waited. The
/// runs go a batch at a time through an array on the stack: nothing is
/// allocated here, and if the threads cannot be had (bad_alloc from the
/// scheduler) the batch is hashed on this thread, to the same value.
template <class Hash>
void hash_in_runs(ContentDigest& digest, std::size_t count, std::size_t run, const Hash& hash) {
  constexpr std::size_t batch = 64;
  std::array<ContentDigest, batch> parts;
  const std::size_t runs = (count + run - 1) / run;
  for (std::size_t first_run = 0; first_run < runs; first_run += batch) {
    const std::size_t in_batch = std::min(batch, runs - first_run);
    const auto hash_run = [&](std::size_t r) {
      ContentDigest part;
      const std::size_t first = (first_run + r) * run, end = std::min(count, first + run);
      for (std::size_t item = first; item < end; ++item) hash(item, part);
      parts[r] = part;
    };
    try {
      tbb::parallel_for(std::size_t{0}, in_batch, hash_run);
    } catch (...) {
      for (std::size_t r = 0; r < in_batch; ++r) hash_run(r);
    }
    for (std::size_t r = 0; r < in_batch; ++r) digest.state_of(parts[r]);
  }
}

}  // namespace

std::array<std::uint64_t, 2> TreeCertifier::digest(const MeshTree& tree) {
  ContentDigest digest;
  const TreeRecipe& recipe = tree.recipe;
  digest.word(pair_of(recipe.fragments, recipe.max_plane_tries));
  digest.word(recipe.seed);
  digest.word(static_cast<std::uint64_t>(recipe.strategy) | static_cast<std::uint64_t>(recipe.kernel) << 8 |
              std::uint64_t{recipe.allow_self_intersections} << 16);
  digest.real(recipe.interior_uv_scale);
  digest.bytes(recipe.pattern.data(), recipe.pattern.size());
  digest.word(tree.nodes.size());
  hash_in_runs(digest, tree.nodes.size(), 256, [&](std::size_t k, ContentDigest& part) {
    const MeshTreeNode& node = tree.nodes[k];
    hash_mesh(part, node.mesh);
    part.bytes(&node.mass, sizeof node.mass);
    hash_mesh(part, node.hull);
    hash_solid(part, node.solid);
    part.word(pair_of(node.parent, node.depth));
    part.values(node.children);
    part.word(std::uint64_t{node.convex} | std::uint64_t{node.above_parent_plane} << 1);
    part.word(pair_of(node.first_leaf, node.leaf_count));
    part.word(node.seed);
  });
  digest.values(tree.leaf_nodes);
  // The bonds as Bonds, whether kept packed or not: packing changes no value.
  digest.word(tree.bond_count());
  hash_in_runs(digest, tree.bond_count(), 4096, [&](std::size_t i, ContentDigest& part) {
    const Bond bond = tree.bond(i);
    part.word(pair_of(bond.first, bond.second));
    part.word(bond.cut_node);
    part.real(bond.area);
    part.bytes(&bond.centroid, sizeof bond.centroid);
    part.bytes(&bond.normal, sizeof bond.normal);
  });
  digest.values(tree.geometry.points);
  digest.values(tree.geometry.planes);
  digest.values(tree.geometry.plane_approx);
  digest.values(tree.cut_planes);
  digest.word(tree.packed_shapes.size());
  hash_in_runs(digest, tree.packed_shapes.size(), 256, [&](std::size_t k, ContentDigest& part) {
    const std::span<const std::uint8_t> packed = tree.packed_shapes[k];
    part.bytes(packed.data(), packed.size());
  });
  return digest.finish();
}

void TreeCertifier::certify(MeshTree& tree, bool masses_derived) {
  const std::array<std::uint64_t, 2> value = digest(tree);
  tree.certificate.present_ = true;
  tree.certificate.masses_derived_ = masses_derived;
  tree.certificate.digest_[0] = value[0];
  tree.certificate.digest_[1] = value[1];
}

bool TreeCertifier::holds(const MeshTree& tree) {
  if (!tree.certificate.present_) return false;
  const std::array<std::uint64_t, 2> value = digest(tree);
  return value[0] == tree.certificate.digest_[0] && value[1] == tree.certificate.digest_[1];
}

}  // namespace detail

bool certificate_holds(const MeshTree& tree) { return detail::TreeCertifier::holds(tree); }

TreeValidationReport certify_tree(MeshTree& tree) {
  TreeValidationReport report = validate_tree(tree);
  if (report.valid()) {
    detail::TreeCertifier::certify(tree, false);  // validate_tree does not compare masses
  } else {
    detail::TreeCertifier::clear(tree);
  }
  return report;
}

std::optional<TreeDefect> fill_tree_caches(MeshTree& tree) {
  // A lean build's packed nodes get their meshes and solids back first.
  if (!tree.packed_shapes.empty()) {
    NodeShapes shapes(tree);
    for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
      if (!tree.is_packed(k)) continue;
      const NodeShape shape = shapes(k);
      tree.nodes[k].mesh = shape.mesh;
      tree.nodes[k].solid = shape.solid;
    }
    tree.packed_shapes = PackedShapes();
  }
  // And its packed bonds theirs (a tree keeps them one way: `bonds` is empty).
  if (!tree.packed_bonds.empty() && tree.bonds.empty()) {
    tree.bonds.reserve(tree.packed_bonds.size());
    for (const PackedBond& packed : tree.packed_bonds) tree.bonds.push_back(unpack_bond(tree, packed));
    std::vector<PackedBond>().swap(tree.packed_bonds);
  }
  return detail::caches_defect(tree, &tree);
}

std::string_view tree_part_name(TreePart part) {
  switch (part) {
    case TreePart::recipe:
      return "recipe";
    case TreePart::node:
      return "node";
    case TreePart::leaf_range:
      return "leaf range";
    case TreePart::leaf_list:
      return "leaf list";
    case TreePart::mesh:
      return "mesh";
    case TreePart::hull:
      return "hull";
    case TreePart::bond:
      return "bond";
    case TreePart::input_point:
      return "input point";
    case TreePart::input_plane:
      return "input plane";
    case TreePart::cut_planes:
      return "cut planes";
    case TreePart::solid:
      return "solid";
  }
  return "unknown";
}

std::string TreeValidationReport::summary() const {
  if (!defect) return "valid";
  std::string where(tree_part_name(defect->part));
  if (defect->part != TreePart::recipe) where.append(" ").append(detail::str(defect->index));
  return where + ": " + defect->message;
}

TreeValidationReport validate_tree(const MeshTree& tree, const TreeValidationOptions& options) {
  TreeValidationReport report;
  report.defect = detail::first_defect(tree, options.caches);
  if (!report.defect && options.caches) report.defect = detail::caches_defect(tree, nullptr);
  if (!report.defect && options.geometry) {
    report.geometry_checked = true;
    report.defect = detail::geometry_defect(tree, options.certificates);
  }
  return report;
}

}  // namespace shatter
