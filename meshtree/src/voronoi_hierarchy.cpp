// The hierarchy of a Voronoi tree (voronoi_hierarchy.hpp).

#include "voronoi_hierarchy.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/meshtree/voronoi.hpp"
#include "shatter/version.hpp"
#include "node_mass.hpp"

namespace shatter::detail {

void VoronoiPart::drop_hints() {
  face_regions = {};
  solid_vertex_of = {};
  face_first_triangle = {};
}

namespace {

// The hierarchy glues the lowest k-d groups and every second level above them
// (so a node has up to 8 fragments, or up to 4 parts, as children): every node
// is rounded and certified once glued, which costs about the whole surface per
// level glued; at 1,000 sites every level cost 2.5 to 4.5 times main's build,
// every second level 2 to 3.4 times (shatter-bench-voronoi, README), before
// the certification tested only pairs across parts (it now takes 0.3 to 0.45
// of the gluing's former time).
constexpr std::uint32_t glue_every_levels = 2;

// Where each face's triangles start in a plain triangulation of `solid` with
// `triangles` triangles (RoundedSolid::attempt >= 0), one more for the end:
// triangulate_solid writes each face's triangles together, in face order,
// k - 2 + 2h of them for a face of k corners and h holes. Empty when the count
// does not add up.
std::vector<std::uint32_t> face_first_triangle_of(const Solid& solid, std::size_t triangles) {
  std::vector<std::uint32_t> first(solid.faces.size() + 1, 0);
  for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
    const SolidFace& face = solid.faces[f];
    std::size_t corners = 0;
    for (std::uint32_t l = face.first_loop; l < face.first_loop + face.loop_count; ++l) corners += solid.loops[l].corner_count;
    if (corners + 2 * face.loop_count < 4) return {};
    first[f + 1] = first[f] + static_cast<std::uint32_t>(corners + 2 * face.loop_count - 4);
  }
  if (first.back() != triangles) return {};
  return first;
}

// Per triangle of `part`'s mesh, its fragment (PartRegions::region_of), into
// `out`: a fragment's own number throughout, or each face's over its
// triangles; empty when neither is known (a union not plainly triangulated).
void triangle_regions_of(const VoronoiPart& part, std::vector<std::uint32_t>& out) {
  out.clear();
  if (part.sole_region != no_index) {
    out.assign(part.mesh.triangles.size(), part.sole_region);
  } else if (!part.face_first_triangle.empty()) {
    for (std::size_t f = 0; f + 1 < part.face_first_triangle.size(); ++f) {
      out.insert(out.end(), part.face_first_triangle[f + 1] - part.face_first_triangle[f], part.face_regions[f]);
    }
  }
}

// The hints of a part made of `solid` and its rounding `rounded` (VoronoiPart's
// face_regions, solid_vertex_of, face_first_triangle; the face regions given):
// what a union of it needs to certify it by regions and to write its faces again.
void set_part_hints(VoronoiPart& part, const Solid& solid, const RoundedSolid& rounded, std::vector<std::uint32_t> face_regions) {
  part.face_regions = std::move(face_regions);
  part.solid_vertex_of.clear();
  part.face_first_triangle.clear();
  if (rounded.attempt < 0) return;
  std::vector<std::uint32_t> first = face_first_triangle_of(solid, rounded.mesh.triangles.size());
  if (first.empty()) return;
  // The mesh's vertices back to the solid's: every vertex of a plain
  // triangulation is one of the solid's, each once.
  part.face_first_triangle = std::move(first);  // for the regions (triangle_regions_of), map or not
  const std::vector<VertexIndex>& mesh_vertex_of = rounded.mesh_vertex_of;
  if (mesh_vertex_of.size() != solid.defs.size()) return;
  std::vector<VertexIndex> solid_vertex_of(rounded.mesh.positions.size(), no_index);
  for (VertexIndex v = 0; v < mesh_vertex_of.size(); ++v) {
    if (mesh_vertex_of[v] < solid_vertex_of.size()) solid_vertex_of[mesh_vertex_of[v]] = v;
  }
  if (std::find(solid_vertex_of.begin(), solid_vertex_of.end(), no_index) != solid_vertex_of.end()) return;
  part.solid_vertex_of = std::move(solid_vertex_of);
}

// The triangles a union's faces are written with (SolidMeshOptions::
// face_triangles and face_triangles_first, over the union's vertices): each
// face's part's triangles, where the part kept them (VoronoiPart::solid_vertex_of) and
// every corner keeps its part's definition, so rounds to the same bits and
// triangulate_face would write the same ones again (the same loops over the same
// points: a triangulation of the face over its own corners); an empty range
// otherwise (a corner defined as another part's equal point may round
// elsewhere; that face is triangulated as before). `members`: the parts glued,
// in glue_parts' order; `face_origin` and `vertex_of` as glue_parts gave them.
// `origins`: per triangle, the member (its index in `members`, as the union's
// certification numbers its parts) << 32 | its triangle in that member's mesh
// (SolidMeshOptions::face_triangle_origins).
void face_triangles_from_parts(const Solid& glued, std::span<const VoronoiPart* const> members,
                               std::span<const std::array<std::uint32_t, 2>> face_origin,
                               std::span<const std::uint32_t> vertex_of, std::vector<Triangle>& triangles,
                               std::vector<std::uint32_t>& first, std::vector<std::uint64_t>& origins) {
  std::vector<std::uint32_t> first_vertex_of_member(members.size() + 1, 0);
  for (std::size_t k = 0; k < members.size(); ++k) {
    first_vertex_of_member[k + 1] = first_vertex_of_member[k] + static_cast<std::uint32_t>(members[k]->solid.defs.size());
  }
  triangles.clear();
  origins.clear();
  first.assign(glued.faces.size() + 1, 0);
  for (std::size_t f = 0; f < face_origin.size(); ++f) {
    const auto [member, part_face] = face_origin[f];
    const VoronoiPart& from = *members[member];
    const std::size_t before = triangles.size();
    bool same = !from.solid_vertex_of.empty();
    for (std::uint32_t t = same ? from.face_first_triangle[part_face] : 0;
         same && t < from.face_first_triangle[part_face + 1]; ++t) {
      Triangle mapped;
      for (int k = 0; k < 3 && same; ++k) {
        const VertexIndex v = from.solid_vertex_of[from.mesh.triangles[t][k]];
        mapped[k] = vertex_of[first_vertex_of_member[member] + v];
        same = mapped[k] != no_index && glued.defs[mapped[k]] == from.solid.defs[v];
      }
      if (same) {
        triangles.push_back(mapped);
        origins.push_back(std::uint64_t{member} << 32 | t);
      }
    }
    if (!same) {
      triangles.resize(before);
      origins.resize(before);
    }
    first[f + 1] = static_cast<std::uint32_t>(triangles.size());
  }
}

// Per face of `solid`, the attempt each face took in `rounded` (RoundedSolid::
// attempt, with `given` the face_attempts round_solid was given); empty when
// the mesh is no plain triangulation.
std::vector<std::uint8_t> face_attempts_of(const Solid& solid, const RoundedSolid& rounded,
                                           std::span<const std::uint8_t> given) {
  if (rounded.attempt < 0) return {};
  if (rounded.attempt == 0 && !given.empty()) return {given.begin(), given.end()};
  return std::vector<std::uint8_t>(solid.faces.size(), static_cast<std::uint8_t>(rounded.attempt));
}

// The hierarchy's walk: a group's parts are its halves' (or, for a lowest group,
// its sites' fragments), glued at the levels that glue.
class Hierarchy {
 public:
  Hierarchy(const VoronoiHierarchyInput& in, HierarchyCounts& counts) : in_(in), counts_(counts) {
    // The fragments numbered as regions for certifying the unions
    // (PartRegions): site s's kept fragments are first_region_[s] onward.
    const std::size_t site_count = in.kept_of.size();
    first_region_.assign(site_count + 1, 0);
    for (std::uint32_t s = 0; s < site_count; ++s) {
      first_region_[s + 1] = first_region_[s] + static_cast<std::uint32_t>(in.kept_of[s].size());
      site_of_region_.insert(site_of_region_.end(), in.kept_of[s].size(), s);
    }
    height_.assign(in.groups.size(), 0);  // above the lowest groups; children follow parents
    for (std::size_t g = in.groups.size(); g-- > 0;) {
      if (in.groups[g].left >= 0) height_[g] = 1 + std::max(height_[in.groups[g].left], height_[in.groups[g].right]);
    }
  }

  /// Group g's parts, glued where its level glues.
  std::vector<VoronoiPart> parts_of_group(std::uint32_t g);

 private:
  // The face-connected sets of `items` glued into nodes, each set that cannot
  // be glued or certified left as its parts.
  std::vector<VoronoiPart> glue_level(std::vector<VoronoiPart> items);
  std::optional<VoronoiPart> glue_set(std::vector<VoronoiPart>& items, std::span<const std::uint32_t> members,
                                      std::span<const GluePart> parts);

  const VoronoiHierarchyInput& in_;
  HierarchyCounts& counts_;
  std::vector<std::uint32_t> first_region_, site_of_region_, height_;
};

// The union of items[members] (a face-connected set of two or more; `parts`
// their glue_parts views), rounded and certified, with the members moved in as
// its children; nothing, the items untouched, when glue_parts declines the set
// or its union is not certified (or collapses) once rounded.
std::optional<VoronoiPart> Hierarchy::glue_set(std::vector<VoronoiPart>& items, std::span<const std::uint32_t> members,
                                               std::span<const GluePart> parts) {
  const PlaneSet& set = in_.set;
  std::vector<GluePart> chosen;
  for (const std::uint32_t m : members) chosen.push_back(parts[m]);
  std::string why;
  std::vector<std::array<std::uint32_t, 2>> face_origin;
  std::vector<std::uint32_t> vertex_of;
  std::optional<Solid> glued = glue_parts(set, chosen, in_.site_pairs, why, &face_origin, &vertex_of);
  if (!glued) return std::nullopt;
  // Two fragments of different sites lie on either side of their sites'
  // bisector, but for what rounding moved; two of one site have no plane
  // between them.
  const auto plane_between_regions = [this](std::uint32_t a, std::uint32_t b) -> std::optional<Plane> {
    const std::uint32_t sa = site_of_region_[a], sb = site_of_region_[b];
    if (sa == sb) return std::nullopt;
    return exact_bisector(in_.points[sa], in_.points[sb], in_.step);
  };
  // Certified knowing its parts (validate_mesh_of_parts): the union keeps
  // every face of every part but the twins, each face's loops as they were
  // over the same definitions, so where a vertex rounds where the part
  // rounded it (the same definition: the same bits) the face's triangles
  // are the part's, already certified against each other; only pairs
  // across parts, and every triangle the union writes differently (a
  // vertex whose definition another part's replaced, a face triangulated
  // or repaired otherwise), are tested. The check accepts the meshes the
  // full one does. The pairs across parts are sought fragment pair by
  // fragment pair (PartRegions): two fragments of different sites lie on
  // either side of the sites' bisector, so only their triangles within
  // rounding's reach of it, at a shared face, are paired, where a
  // search by boxes paired nearly every triangle of a large union.
  std::vector<const Mesh*> part_meshes;
  // (Not kept per thread: round_solid may wait on parallel work, and the
  // thread run another union meanwhile.)
  std::vector<std::vector<std::uint32_t>> region_buffers(members.size());
  std::vector<std::span<const std::uint32_t>> part_triangle_regions;
  for (std::size_t k = 0; k < members.size(); ++k) {
    part_meshes.push_back(&items[members[k]].mesh);
    triangle_regions_of(items[members[k]], region_buffers[k]);
    part_triangle_regions.push_back(region_buffers[k]);
  }
  PartRegions regions{part_triangle_regions, plane_between_regions};
  SolidMeshOptions union_meshing = in_.meshing;
  union_meshing.parts = part_meshes;
  union_meshing.part_regions = &regions;
  // Each face triangulated at the attempt its part was certified at: a
  // part certified only at a later attempt (a fold its first one made)
  // would make the union's first attempt fail the same way, and every
  // later attempt retriangulates every face, which certification must
  // then test against all others (on fandisk subdivided to 52k
  // triangles at 10^4 sites, 185 such unions took 80 % of the gluing).
  // So the union's first attempt writes its parts' triangles again.
  std::vector<std::uint8_t> face_attempts(glued->faces.size(), 0);
  bool any_later = false;
  for (std::size_t f = 0; f < face_origin.size(); ++f) {
    const VoronoiPart& from = items[members[face_origin[f][0]]];
    if (!from.face_attempts.empty()) face_attempts[f] = from.face_attempts[face_origin[f][1]];
    any_later |= face_attempts[f] != 0;
  }
  if (any_later) union_meshing.face_attempts = face_attempts;
  // Each face written with its part's triangles (face_triangles_from_parts).
  std::vector<const VoronoiPart*> member_parts;
  for (const std::uint32_t m : members) member_parts.push_back(&items[m]);
  std::vector<Triangle> face_triangles;
  std::vector<std::uint32_t> face_triangles_first;
  std::vector<std::uint64_t> face_triangle_origins;
  face_triangles_from_parts(*glued, member_parts, face_origin, vertex_of, face_triangles, face_triangles_first,
                            face_triangle_origins);
  union_meshing.face_triangles = face_triangles;
  union_meshing.face_triangles_first = face_triangles_first;
  // Certification then finds each triangle's part from where it came
  // (checked), not by matching every part's triangles by position.
  union_meshing.face_triangle_origins = face_triangle_origins;
  // A union round_solid cannot place is left unglued, as one it cannot certify.
  RoundedSolid r;
  try {
    r = round_solid(set, *glued, union_meshing);
  } catch (const UnsupportedGeometryError&) {
    r.valid = false;
  }
  if (!r.valid || r.collapsed) return std::nullopt;
  if (r.attempt != 0) ++counts_.nodes_retried;
  VoronoiPart node;
  node.face_attempts = face_attempts_of(*glued, r, union_meshing.face_attempts);
  std::vector<std::uint32_t> face_regions(glued->faces.size());
  for (std::size_t f = 0; f < face_origin.size(); ++f) {
    face_regions[f] = items[members[face_origin[f][0]]].face_regions[face_origin[f][1]];
  }
  set_part_hints(node, *glued, r, std::move(face_regions));
  node.solid = std::move(*glued);
  node.mesh = std::move(r.mesh);
  for (const std::uint32_t m : members) {
    node.sites.insert(node.sites.end(), items[m].sites.begin(), items[m].sites.end());
    node.children.push_back(std::move(items[m]));
    node.children.back().drop_hints();  // glued: no union needs them again
    // A lean tree's solids keep no approximations (every node's are
    // dropped once the bonds are found); a glued part's go now, as no
    // union reads them again: on the cube at 10^5 sites the build's
    // peak went from 2.65 to 2.12 GB, the same bytes. find_bonds
    // computes the leaves' where it needs them (approximate(), the
    // same values).
    if (in_.lean) std::vector<ApproxPoint>().swap(node.children.back().solid.approx);
  }
  std::sort(node.sites.begin(), node.sites.end());
  node.sites.erase(std::unique(node.sites.begin(), node.sites.end()), node.sites.end());
  return node;
}

std::vector<VoronoiPart> Hierarchy::glue_level(std::vector<VoronoiPart> items) {
  std::vector<GluePart> parts;
  parts.reserve(items.size());
  for (const VoronoiPart& item : items) parts.push_back({&item.solid, item.sites});
  std::vector<VoronoiPart> out;
  for (const std::vector<std::uint32_t>& members : face_connected_groups(parts, in_.site_pairs)) {
    if (members.size() > 1) {
      if (std::optional<VoronoiPart> node = glue_set(items, members, parts)) {
        out.push_back(std::move(*node));
        ++counts_.nodes_glued;
        continue;
      }
      ++counts_.sets_unglued;
    }
    for (const std::uint32_t m : members) out.push_back(std::move(items[m]));
  }
  return out;
}

std::vector<VoronoiPart> Hierarchy::parts_of_group(std::uint32_t g) {
  const SiteGroup& group = in_.groups[g];
  std::vector<VoronoiPart> items;
  if (group.left < 0) {
    for (std::uint32_t i = group.begin; i < group.end; ++i) {
      const std::uint32_t s = in_.order[i];
      for (std::size_t k = 0; k < in_.kept_of[s].size(); ++k) {
        VoronoiFragment* r = in_.kept_of[s][k];
        VoronoiPart leaf;
        leaf.face_attempts = face_attempts_of(r->solid, r->rounded, {});
        // Every face of a fragment is the fragment's; so is every triangle,
        // plain triangulation or not.
        const std::uint32_t region = first_region_[s] + static_cast<std::uint32_t>(k);
        set_part_hints(leaf, r->solid, r->rounded, std::vector<std::uint32_t>(r->solid.faces.size(), region));
        leaf.sole_region = region;
        r->rounded.mesh_vertex_of = {};
        leaf.solid = std::move(r->solid);
        leaf.mesh = std::move(r->rounded.mesh);
        leaf.sites = {s};
        items.push_back(std::move(leaf));
      }
    }
  } else {
    std::vector<VoronoiPart> right;
    tbb::parallel_invoke([&] { items = parts_of_group(static_cast<std::uint32_t>(group.left)); },
                         [&] { right = parts_of_group(static_cast<std::uint32_t>(group.right)); });
    for (VoronoiPart& part : right) items.push_back(std::move(part));
  }
  // The root group is the input itself.
  if (g == 0 || items.size() < 2 || height_[g] % glue_every_levels != 0) return items;
  return glue_level(std::move(items));
}

}  // namespace

std::vector<VoronoiPart> glue_voronoi_hierarchy(const VoronoiHierarchyInput& in, HierarchyCounts& counts) {
  std::size_t kept_count = 0;
  for (const std::vector<VoronoiFragment*>& kept : in.kept_of) kept_count += kept.size();
  std::vector<VoronoiPart> top;
  if (kept_count < 2 || in.groups.empty()) return top;
  top = Hierarchy(in, counts).parts_of_group(0);
  // A group holding every fragment is the root again: its children take its place.
  while (top.size() == 1 && !top[0].children.empty()) top = std::move(top[0].children);
  return top;
}

MeshTree voronoi_tree_of_parts(const Mesh& mesh, const PlaneInput& input, const TreeRecipe& recipe,
                               std::vector<VoronoiPart>& top, std::span<const Plane> planes, SitePairs site_pairs) {
  const auto is_bisector = [&](PlaneRef ref) {
    return ref.bits != no_index && ref.is_cut() && site_pairs[ref.index()][0] != no_index;
  };
  MeshTree tree;
  tree.recipe = recipe;
  tree.shatter_version = std::string(version_string);
  tree.geometry = input.geometry;
  MeshTreeNode root;
  root.mesh = mesh;
  root.mass = mass_properties(root.mesh);
  require_representable_mass(root.mass, "the solid");
  root.solid = input.solid;
  root.convex = root.solid->convex;
  root.seed = root_node_seed(recipe.seed);
  root.first_leaf = 0;
  root.leaf_count = 1;
  tree.nodes.push_back(std::move(root));
  tree.cut_planes.push_back({});
  if (top.size() < 2) {
    tree.leaf_nodes.push_back(0);
  } else {
    std::size_t node_count = 1;
    const std::function<void(const VoronoiPart&)> count_nodes = [&](const VoronoiPart& part) {
      ++node_count;
      for (const VoronoiPart& child : part.children) count_nodes(child);
    };
    for (const VoronoiPart& part : top) count_nodes(part);
    // The bisectors the fragments use, in the order of their site pairs (a
    // glued node's planes are its fragments').
    std::vector<char> used(planes.size(), 0);
    const auto use = [&](PlaneRef ref) {
      if (ref.bits == no_index || !ref.is_cut()) return;
      if (!is_bisector(ref)) throw std::logic_error("build_voronoi_tree: a container box cut into a cell's part of the solid");
      used[ref.index()] = 1;
    };
    const std::function<void(const VoronoiPart&)> use_planes = [&](const VoronoiPart& part) {
      for (const VoronoiPart& child : part.children) use_planes(child);
      if (!part.children.empty()) return;
      for (const SolidFace& face : part.solid.faces) use(face.plane);
      for (const SolidCorner& corner : part.solid.corners) use(corner.line.other);
      for (const PointDef& def : part.solid.defs) {
        const int count = def.kind == PointKind::segment_plane ? 1 : def.kind == PointKind::three_planes ? 3 : 0;
        for (int k = 0; k < count; ++k) use(def.planes[k]);
      }
    };
    for (const VoronoiPart& part : top) use_planes(part);
    std::vector<std::uint32_t> used_planes;
    for (std::uint32_t p = 0; p < planes.size(); ++p) {
      if (used[p]) used_planes.push_back(p);
    }
    std::sort(used_planes.begin(), used_planes.end(), [&](std::uint32_t a, std::uint32_t b) { return site_pairs[a] < site_pairs[b]; });
    std::vector<std::uint32_t> final_index(planes.size(), no_index);
    for (std::uint32_t r = 0; r < used_planes.size(); ++r) final_index[used_planes[r]] = static_cast<std::uint32_t>(node_count) + r;
    const auto remap = [&](PlaneRef& ref) {
      if (ref.bits != no_index && ref.is_cut()) ref = PlaneRef::cut(final_index[ref.index()]);
    };
    const auto remap_surface = [&](SurfaceId& surface) {
      if (surface != original_surface) surface = cap_surface_of(final_index[surface - 1]);
    };
    // Nodes in preorder, leaves numbered in that order.
    tree.nodes.reserve(node_count);
    const std::function<void(VoronoiPart&, NodeIndex, std::size_t)> add = [&](VoronoiPart& part, NodeIndex parent, std::size_t index) {
      const auto k = static_cast<NodeIndex>(tree.nodes.size());
      MeshTreeNode node;
      node.solid = std::move(part.solid);
      for (SolidFace& face : node.solid->faces) {
        remap(face.plane);
        remap_surface(face.surface);
      }
      for (SolidCorner& corner : node.solid->corners) remap(corner.line.other);
      for (PointDef& def : node.solid->defs) {
        const int count = def.kind == PointKind::segment_plane ? 1 : def.kind == PointKind::three_planes ? 3 : 0;
        for (int c = 0; c < count; ++c) remap(def.planes[c]);
      }
      node.mesh = std::move(part.mesh);
      for (SurfaceId& surface : node.mesh->surfaces) remap_surface(surface);
      node.mass = mass_properties(node.mesh);
      require_representable_mass(node.mass, "a fragment");
      node.convex = node.solid->convex;
      node.parent = parent;
      node.depth = tree.nodes[parent].depth + 1;
      node.first_leaf = static_cast<LeafIndex>(tree.leaf_nodes.size());
      node.seed = child_node_seed(tree.nodes[parent].seed, index);
      tree.nodes[parent].children.push_back(k);
      tree.nodes.push_back(std::move(node));
      tree.cut_planes.push_back({});
      if (part.children.empty()) tree.leaf_nodes.push_back(k);
      for (std::size_t c = 0; c < part.children.size(); ++c) add(part.children[c], k, c);
      tree.nodes[k].leaf_count = static_cast<std::uint32_t>(tree.leaf_nodes.size() - tree.nodes[k].first_leaf);
    };
    for (std::size_t c = 0; c < top.size(); ++c) add(top[c], 0, c);
    tree.nodes[0].leaf_count = static_cast<std::uint32_t>(tree.leaf_nodes.size());
    for (const std::uint32_t p : used_planes) tree.cut_planes.push_back(planes[p]);
  }

  return tree;
}

}  // namespace shatter::detail
