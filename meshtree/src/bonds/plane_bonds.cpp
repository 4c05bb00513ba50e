// Bonds of a plane-kernel tree, decided on the exact solids.
//
// A leaf's cap faces on cut k are polygons on plane k with defined vertices. Two
// leaves on opposite sides of k are bonded when a cap face of each has interior
// points in common. Convex faces are tested as they are; others as the triangles
// of an exact triangulation (triangulate_face). Two convex polygons' interiors
// meet iff no edge line of either has the other on its closed outer side (their
// Minkowski difference is a convex polygon whose edges are theirs); that is
// decided with exact orientations. The common case is settled faster: the
// centroid of the rounded clip of the two (a double point) is tested exactly to
// lie strictly inside both. The overlap's area and centroid are measured on the
// rounded clip, a construction that never decides anything (on the corners'
// exact offsets from a point of the cut where the rounded corners are coarse
// next to the part: add_measure_polygon).
//
// A lean tree's solids keep no approximations (BuildRunOptions::lean): each cap
// corner's is computed once per cut it is met on and kept beside its rounded 2D
// point, and a non-convex face is triangulated on a copy of its leaf's solid
// with the approximations filled. Either way the values are approximate()'s, so
// the bonds are the same bit for bit.
//
// A lean tree's leaves are packed (packed_node.hpp): their solids are unpacked
// as the cuts meet them, into a small cache by leaf (the cuts go in preorder,
// or in postorder for packed bonds, so a subtree's cuts, which meet the same
// few leaves, come one after the other; in postorder a cut of at most 256
// leaves finds all of them there, read last), and each cap corner's definition
// is kept beside its approximation, so the pairs are tested without the
// leaves' solids.

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <optional>
#include <utility>
#include <span>
#include <stdexcept>
#include <vector>

#include "../populate.hpp"
#include "clip2d.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/triangulate/solid_mesh.hpp"

namespace shatter {
namespace {

using detail::Clipper;

// The Bond on `plane` (`unit` its unit normal) whose centroid has coordinates
// (u, v) at (axis + 1) % 3 and (axis + 2) % 3: find_plane_bonds makes each bond
// with it, and unpack_bond makes it again from a PackedBond, so the two agree bit
// for bit.
Bond bond_on_plane(const Plane& plane, const Vec3& unit, int axis, LeafIndex first, LeafIndex second,
                   NodeIndex cut_node, bool first_below, double area, double u, double v) {
  Bond bond;
  bond.first = first;
  bond.second = second;
  bond.cut_node = cut_node;
  bond.area = area;
  bond.centroid = point_on_plane_over(plane, axis, u, v);
  bond.normal = first_below ? unit : -unit;  // from below into above is +n
  return bond;
}

// One convex part of a cap face: corners counter-clockwise in the projection's
// raw frame, as their vertices' definitions and as rounded 2D points.
struct Part {
  std::uint32_t first, count;  // into corner_defs_ / points_
  std::uint32_t measure_first, measure_count;  // into measure_points_
  double min_u, max_u, min_v, max_v;
};

struct CapFace {
  LeafIndex leaf;
  bool above;
  std::uint32_t first_part, part_count;
  double min_u, max_u, min_v, max_v;
};

// A rigorous bound on how far a vertex's floating-point quotient x/w lies from
// the exact coordinate (as in rounded_position), so boxes can be grown to hold
// the exact polygons.
double quotient_error(const Estimate& x, const Estimate& w) {
  const double q = x.value / w.value;
  return (x.error + std::fabs(q) * w.error) / (w.value - w.error) * (1 + 0x1p-40) + 0x1p-52 * std::fabs(q);
}

class PlaneBonds {
  struct CachedSolid;  // a leaf's unpacked solid (leaf_solid), defined below

 public:
  struct FaceRef {
    std::uint32_t cut;  // a node's plane, or a cell plane after them (MeshTree::cut_planes)
    LeafIndex leaf;
    std::uint32_t face;
  };

  explicit PlaneBonds(const MeshTree& tree) : tree_(tree), set_(tree.plane_set()) {
    cache_.reserve(cache_slots);
    for (std::size_t i = 0; i < cache_slots; ++i) cache_.push_back({no_leaf, NodeShapes(tree), nullptr, {}, {}});
  }

  std::vector<Bond> run() {
    std::vector<Bond> bonds;
    run_cuts(bonds);
    return bonds;
  }

  // run() on the arena's threads: the faces gathered by cut once, then the
  // cuts shared out among workers of their own (a cut's bonds are a function
  // of its faces in leaf order alone), handed over in any order and sorted as
  // run() sorts them (no two bonds share a sort key): the same list on any
  // number of threads. A Voronoi tree's bonds lie on some 35,000 cell planes at
  // 10^4 sites, which one thread read while the other waited.
  static std::vector<Bond> run_parallel(const MeshTree& tree) {
    PlaneBonds gatherer(tree);
    gatherer.gather_faces_by_cut();
    std::vector<Bond> bonds;
    bonds.reserve(2 * gatherer.refs_.size());  // as run_cuts
    std::mutex bonds_mutex;
    tbb::enumerable_thread_specific<std::optional<PlaneBonds>> workers;
    const std::size_t cuts = tree.cut_planes.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cuts, 64), [&](const tbb::blocked_range<std::size_t>& range) {
      std::optional<PlaneBonds>& mine = workers.local();
      if (!mine) mine.emplace(tree);
      std::vector<Bond> found;
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        const std::size_t begin = gatherer.start_[k], end = gatherer.start_[k + 1];
        if (end - begin < 2) continue;
        mine->run_cut(
            static_cast<std::uint32_t>(k),
            [&](const auto& visit) {
              for (std::size_t i = begin; i < end; ++i) visit(gatherer.refs_[gatherer.order_[i]]);
            },
            found);
      }
      const std::lock_guard lock(bonds_mutex);
      bonds.insert(bonds.end(), found.begin(), found.end());
    });
    sort_bonds(bonds);
    return bonds;
  }

  // The bonds as find_packed_plane_bonds gives them: packed as they are found.
  // Every cut is a node's, and a node's cap faces lie on leaves of its own
  // range, so its faces are all known once its last leaf is read: the leaves
  // are read once, in order, each cut's faces gathered as they come and its
  // bonds found as soon as its range ends (postorder, not preorder: a cut's
  // bonds are a function of its faces in leaf order alone, and no two bonds
  // share a sort key, as no leaf lies on both sides of a node's cut, so the
  // sorted list is the same). Only the open cuts' faces are held, those on the
  // current leaf's ancestors' planes: some thousands, where gathering them all
  // first held 0.14 GB at cube -> 2^20, beside the finished bonds at the peak.
  std::vector<PackedBond> run_packed() {
    check_packable();
    std::vector<PackedBond> bonds;
    // The array is the bonds' one copy, so it is sized ahead rather than grown
    // by doubling (which touches the old and the new array at once). The faces
    // are not counted before they are read, so it is sized by the leaves:
    // sixteen bonds a leaf, where the trees measured have at most 9.2 (cube ->
    // 2^20); a tree with more grows the array. Capacity never written is
    // address space, not memory: its pages are never touched.
    bonds.reserve(16 * tree_.leaf_count());
    // Its pages populated a few mebibytes ahead of the bonds, where each took a
    // fault on first touch (a fifth of the search's time at cube -> 65,536).
    detail::PopulatedAhead ahead(bonds, std::size_t{4} << 20);
    bonds_ahead_ = &ahead;
    run_leaves(0, static_cast<LeafIndex>(tree_.leaf_count()), nullptr, nullptr, bonds);
    bonds_ahead_ = nullptr;
    sort_bonds(bonds);
    return bonds;
  }

  // find_packed_plane_bonds split into runs of about `chunk_leaves` leaves
  // (0: not split), each read by run_leaves on its own: a cut whose range lies
  // within one run is that run's; the cuts whose range holds more leaves (the
  // "outer" ones, the top of the tree) are run once every run has handed over
  // their faces, joined in run order, so each cut sees its faces in leaf order
  // as the unsplit reading does. Every cut's bonds are then the same, and the
  // sort (of keys no two bonds share) orders them the same, on any split and
  // any schedule.
  static std::vector<PackedBond> run_packed_split(const MeshTree& tree, std::uint32_t chunk_leaves) {
    const auto leaves = static_cast<LeafIndex>(tree.leaf_count());
    if (chunk_leaves == 0 || leaves <= chunk_leaves) return PlaneBonds(tree).run_packed();
    PlaneBonds(tree).check_packable();
    std::vector<std::uint8_t> outer(tree.nodes.size(), 0);
    std::vector<NodeIndex> outer_cuts;
    std::vector<std::pair<LeafIndex, LeafIndex>> runs;  // [first, end) leaves
    // Nodes are in preorder: the nodes below the outer ones come in leaf order,
    // their ranges one after the other; neighbours are joined up to the size.
    for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
      const MeshTreeNode& node = tree.nodes[k];
      if (!node.is_leaf() && node.leaf_count > chunk_leaves) {
        outer[k] = 1;
        outer_cuts.push_back(k);
        continue;
      }
      if (node.parent == no_node || outer[node.parent] == 0) continue;
      const LeafIndex end = node.first_leaf + node.leaf_count;
      if (!runs.empty() && end - runs.back().first <= chunk_leaves) {
        runs.back().second = end;
      } else {
        runs.emplace_back(node.first_leaf, end);
      }
    }
    std::vector<PackedBond> bonds;
    bonds.reserve(16 * std::size_t{leaves});  // as run_packed
    std::mutex bonds_mutex;
    const auto hand_over = [&](const std::vector<PackedBond>& found) {
      const std::lock_guard lock(bonds_mutex);
      // Populated in one call, not a fault a page under the lock (within the capacity reserved).
      if (bonds.size() + found.size() <= bonds.capacity()) {
        detail::populate_for_writing(bonds.data() + bonds.size(), found.size() * sizeof(PackedBond));
      }
      bonds.insert(bonds.end(), found.begin(), found.end());
    };
    tbb::enumerable_thread_specific<std::optional<PlaneBonds>> workers;
    const auto worker = [&]() -> PlaneBonds& {
      std::optional<PlaneBonds>& mine = workers.local();
      if (!mine) mine.emplace(tree);
      return *mine;
    };
    std::vector<std::vector<FaceRef>> outer_refs(runs.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, runs.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t r = range.begin(); r != range.end(); ++r) {
        std::vector<PackedBond> found;
        worker().run_leaves(runs[r].first, runs[r].second, &outer, &outer_refs[r], found);
        hand_over(found);
      }
    });
    // Each outer cut's faces, in run order (so in leaf order).
    std::vector<std::uint32_t> slot(tree.nodes.size(), 0);
    for (std::uint32_t i = 0; i < outer_cuts.size(); ++i) slot[outer_cuts[i]] = i;
    std::vector<std::vector<FaceRef>> faces_of(outer_cuts.size());
    for (std::vector<FaceRef>& refs : outer_refs) {
      for (const FaceRef& ref : refs) faces_of[slot[ref.cut]].push_back(ref);
      std::vector<FaceRef>().swap(refs);
    }
    // The largest cuts first, so the last to finish is a small one.
    std::vector<std::uint32_t> order(outer_cuts.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return faces_of[a].size() > faces_of[b].size(); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        std::vector<PackedBond> found;
        worker().run_refs(outer_cuts[order[i]], faces_of[order[i]], found);
        hand_over(found);
      }
    });
    tbb::parallel_sort(bonds.begin(), bonds.end(), bond_before<PackedBond>);
    return bonds;
  }

  void check_packable() const {
    if (tree_.cut_planes.size() > tree_.nodes.size()) {
      throw std::invalid_argument("find_packed_plane_bonds: a cell plane's bonds cannot be packed");
    }
  }

  // Leaves lo..hi-1 read once, in order, each cut's faces gathered as they
  // come and its bonds found as soon as its range ends (postorder, not
  // preorder: a cut's bonds are a function of its faces in leaf order alone,
  // and no two bonds share a sort key, as no leaf lies on both sides of a
  // node's cut, so the sorted list is the same). Only the open cuts' faces are
  // held, those on the current leaf's ancestors' planes: some thousands, where
  // gathering them all first held 0.14 GB at cube -> 2^20, beside the finished
  // bonds at the peak. A cut marked in `outer` (whose range reaches past these
  // leaves: find_packed_plane_bonds' split) is not run: its faces go to
  // `outer_refs`, in leaf order.
  void run_leaves(LeafIndex lo, LeafIndex hi, const std::vector<std::uint8_t>* outer, std::vector<FaceRef>* outer_refs,
                  std::vector<PackedBond>& bonds) {
    std::vector<std::vector<FaceRef>> open;  // by depth: the faces on the plane of the current leaf's ancestor there
    for (LeafIndex leaf = lo; leaf < hi; ++leaf) {
      const Solid& solid = leaf_solid(leaf);
      for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
        const std::uint32_t cut = cut_of(solid.faces[f]);
        if (cut == no_cut) continue;
        const MeshTreeNode& node = tree_.nodes[cut];
        if (node.is_leaf() || leaf < node.first_leaf || leaf - node.first_leaf >= node.leaf_count) continue;
        if (outer != nullptr && (*outer)[cut] != 0) {
          outer_refs->push_back({cut, leaf, f});
          continue;
        }
        if (open.size() <= node.depth) open.resize(std::size_t{node.depth} + 1);
        open[node.depth].push_back({cut, leaf, f});
      }
      // The cuts whose range ends here: the leaf's last ancestors, deepest first.
      for (NodeIndex a = tree_.nodes[tree_.leaf_nodes[leaf]].parent; a != no_node; a = tree_.nodes[a].parent) {
        const MeshTreeNode& node = tree_.nodes[a];
        if (leaf + 1 != node.first_leaf + node.leaf_count) break;
        if (outer != nullptr && (*outer)[a] != 0) break;  // and so are the ones above it
        if (open.size() <= node.depth) continue;
        std::vector<FaceRef>& refs = open[node.depth];
        run_refs(a, refs, bonds);
        refs.clear();
        if (bonds_ahead_ != nullptr) bonds_ahead_->ensure();
      }
    }
  }

  // The bonds of cut `k`, whose faces `refs` lists in leaf order.
  void run_refs(std::uint32_t k, const std::vector<FaceRef>& refs, std::vector<PackedBond>& bonds) {
    if (refs.size() < 2) return;
    run_cut(
        k,
        [&](const auto& visit) {
          for (const FaceRef& ref : refs) visit(ref);
        },
        bonds);
  }

  // Bond or PackedBond: the same keys in the same order either way, so the
  // same permutation.
  template <class Record>
  static bool bond_before(const Record& a, const Record& b) {
    if (a.first != b.first) return a.first < b.first;
    if (a.second != b.second) return a.second < b.second;
    return a.cut_node < b.cut_node;
  }
  template <class Record>
  static void sort_bonds(std::vector<Record>& bonds) {
    std::sort(bonds.begin(), bonds.end(), bond_before<Record>);
  }

 private:
  // The cuts in order, every cut's faces gathered first (find_plane_bonds: a
  // cell plane's faces are all known only once every leaf is read).
  void run_cuts(std::vector<Bond>& bonds) {
    gather_faces_by_cut();
    // The array is the bonds' one copy, so it is sized ahead rather than grown
    // by doubling and shrunk to fit, which touched some three times its size at
    // once (+54 MB over the 44 MB of bonds of cube -> 65,536, the command's
    // peak). Two bonds per cap face holds every tree measured (1.15 to 1.41:
    // cube -> 65,536, elephant, knot1, fandisk, spool and hand at 1,000 to
    // 4,096, every strategy); a tree with more grows the array, as before. Capacity
    // reserved but never written is address space, not memory: its pages are
    // never touched.
    bonds.reserve(2 * refs_.size());
    for (std::uint32_t k = 0; k < tree_.cut_planes.size(); ++k) {
      if (start_[k + 1] - start_[k] < 2) continue;
      const std::span<const std::uint32_t> order(order_.data() + start_[k], start_[k + 1] - start_[k]);
      run_cut(
          k,
          [&](const auto& visit) {
            for (const std::uint32_t r : order) visit(refs_[r]);
          },
          bonds);
    }
    sort_bonds(bonds);
  }

  void add_bond(std::vector<Bond>& bonds, std::uint32_t k, LeafIndex below, LeafIndex above, double area, double u,
                double v) const {
    const LeafIndex first = std::min(below, above), second = std::max(below, above);
    const NodeIndex cut_node = k < tree_.nodes.size() ? k : separating_node(first, second);
    bonds.push_back(bond_on_plane(plane_, unit_, axis_, first, second, cut_node, first == below, area, u, v));
  }

  // What unpack_bond makes the Bond above from (run_packed: k is a node).
  void add_bond(std::vector<PackedBond>& bonds, std::uint32_t k, LeafIndex below, LeafIndex above, double area,
                double u, double v) const {
    PackedBond bond;
    bond.first = std::min(below, above);
    bond.second = std::max(below, above);
    bond.cut_node = k;
    bond.axis = static_cast<std::uint8_t>(axis_);
    bond.first_below = bond.first == below;
    bond.area = area;
    bond.u = u;
    bond.v = v;
    bonds.push_back(bond);
  }

  // Which side of cut `k` a leaf lies on: the side of the child whose range holds
  // it; for a cell plane (no node's, see MeshTree::cut_planes), the side its
  // face there faces away from (a face reversed, facing -n, lies above).
  bool leaf_is_above(std::uint32_t cut, LeafIndex leaf, const SolidFace& face) const {
    if (cut >= tree_.nodes.size()) return face.reversed;
    for (const NodeIndex child : tree_.nodes[cut].children) {
      const MeshTreeNode& c = tree_.nodes[child];
      if (leaf >= c.first_leaf && leaf - c.first_leaf < c.leaf_count) return c.above_parent_plane;
    }
    return false;
  }

  void gather_faces_by_cut() {
    refs_.clear();
    for (LeafIndex leaf = 0; leaf < tree_.leaf_count(); ++leaf) {
      const Solid& solid = leaf_solid(leaf);
      for (std::uint32_t f = 0; f < solid.faces.size(); ++f) {
        const std::uint32_t cut = cut_of(solid.faces[f]);
        if (cut == no_cut) continue;
        // A cell plane's faces lie on it (a cell tree's caps carry their plane's id).
        if (cut >= tree_.nodes.size()) {
          if (solid.faces[f].plane == PlaneRef::cut(cut)) refs_.push_back({cut, leaf, f});
          continue;
        }
        const MeshTreeNode& node = tree_.nodes[cut];
        if (node.is_leaf() || leaf < node.first_leaf || leaf - node.first_leaf >= node.leaf_count) continue;
        refs_.push_back({cut, leaf, f});
      }
    }
    // Counting sort by cut, keeping leaf order within a cut.
    start_.assign(tree_.cut_planes.size() + 1, 0);
    for (const FaceRef& ref : refs_) ++start_[ref.cut + 1];
    for (std::size_t k = 0; k < tree_.cut_planes.size(); ++k) start_[k + 1] += start_[k];
    order_.resize(refs_.size());
    std::vector<std::size_t> next(start_.begin(), start_.end() - 1);
    for (std::uint32_t r = 0; r < refs_.size(); ++r) order_[next[refs_[r].cut]++] = r;
  }

  Vec2 project(const ApproxPoint& a) const {
    const double w = a.w.value;
    const double c[3] = {a.x.value / w, a.y.value / w, a.z.value / w};
    return {c[(axis_ + 1) % 3], c[(axis_ + 2) % 3]};
  }
  double project_error(const ApproxPoint& a) const {
    const Estimate c[3] = {a.x, a.y, a.z};
    return std::max(quotient_error(c[(axis_ + 1) % 3], a.w), quotient_error(c[(axis_ + 2) % 3], a.w));
  }

  // The face's convex parts, counter-clockwise in the raw projection frame.
  void add_face(const FaceRef& ref) {
    const Solid& solid = leaf_solid(ref.leaf);
    const SolidFace& face = solid.faces[ref.face];
    CapFace cap{ref.leaf, leaf_is_above(ref.cut, ref.leaf, face), static_cast<std::uint32_t>(parts_.size()), 0,
                INFINITY, -INFINITY, INFINITY, -INFINITY};
    // Faces run counter-clockwise seen from outside; seen in the raw frame that is
    // clockwise when exactly one of (reversed face, mirrored frame) holds.
    const bool reverse = face.reversed != flipped_;
    triangles_.clear();
    if (face.loop_count == 1 && face.convex) {
      const SolidLoop& loop = solid.loops[face.first_loop];
      part_vertices_.clear();
      for (std::uint32_t i = 0; i < loop.corner_count; ++i) part_vertices_.push_back(solid.corners[loop.first_corner + i].vertex);
      add_part(solid, part_vertices_, reverse, cap, cached_slot(ref.leaf));
    } else {
      points3_.clear();
      const Solid& cached = with_approximations(ref.leaf, solid);
      for (const ApproxPoint& a : cached.approx) {
        points3_.push_back({a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value});
      }
      triangulate_face(set_, cached, ref.face, points3_, triangles_);
      for (const Triangle& t : triangles_) {
        part_vertices_.assign(t.begin(), t.end());
        add_part(cached, part_vertices_, reverse, cap);
      }
    }
    cap.part_count = static_cast<std::uint32_t>(parts_.size()) - cap.first_part;
    faces_.push_back(cap);
  }

  // The cut plane (an index into tree_.cut_planes) a face of a leaf lies on, or
  // no_cut for a face of the input's surface or of a surface the tree did not cut.
  std::uint32_t cut_of(const SolidFace& face) const {
    const SurfaceId surface = face.surface;
    if (surface == original_surface || surface - 1 >= tree_.cut_planes.size()) return no_cut;
    return surface - 1;
  }

  // The solid of `leaf`: its own, or unpacked into the cache's slot for it
  // (valid until the next call).
  const Solid& leaf_solid(LeafIndex leaf) {
    const NodeIndex node = tree_.leaf_nodes[leaf];
    if (!tree_.is_packed(node)) return tree_.nodes[node].solid;
    CachedSolid& slot = cache_[leaf % cache_slots];
    if (slot.leaf != leaf) {
      slot.leaf = no_leaf;  // until it unpacks
      slot.solid = &slot.shapes.solid(node);
      slot.known.assign(slot.solid->defs.size(), 0);
      slot.approx.resize(slot.solid->defs.size());
      slot.leaf = leaf;
    }
    return *slot.solid;
  }

  // The cached slot of `leaf`, whose approximations are kept there as they are
  // computed (a packed leaf's solid keeps none, and a vertex of a convex leaf is
  // a corner of two or three of its caps, each met on its own cut), or nullptr
  // when the leaf is not packed. Valid after leaf_solid(leaf), until the next.
  CachedSolid* cached_slot(LeafIndex leaf) {
    if (!tree_.is_packed(tree_.leaf_nodes[leaf])) return nullptr;
    CachedSolid& slot = cache_[leaf % cache_slots];
    return slot.leaf == leaf ? &slot : nullptr;
  }

  // The solid of `leaf` with every approximation there: itself when it keeps
  // them; else a copy with them computed, made once for the leaf whose faces
  // are being added (they come in leaf order within a cut) and only for a face
  // that needs its triangulation.
  const Solid& with_approximations(LeafIndex leaf, const Solid& solid) {
    if (!solid.approx.empty() || solid.defs.empty()) return solid;
    if (filled_leaf_ != leaf) {
      filled_ = solid;
      filled_.approx.resize(solid.defs.size());
      CachedSolid* slot = cached_slot(leaf);  // the convex faces' approximations, where met
      for (VertexIndex v = 0; v < solid.defs.size(); ++v) filled_.approx[v] = approximation(solid, v, slot);
      filled_leaf_ = leaf;
    }
    return filled_;
  }

  // Vertex v's approximation: the solid's own, or else the one cached in
  // `slot` (the leaf's cache slot, when the solid is its solid), computed at the
  // first need; approximate()'s value either way.
  ApproxPoint approximation(const Solid& solid, VertexIndex v, CachedSolid* slot) const {
    if (!solid.approx.empty()) return solid.approx[v];
    if (slot == nullptr) return approximate(set_, solid.defs[v]);
    if (!slot->known[v]) {
      slot->approx[v] = approximate(set_, solid.defs[v]);
      slot->known[v] = 1;
    }
    return slot->approx[v];
  }

  void add_part(const Solid& solid, std::vector<VertexIndex>& vertices, bool reverse, CapFace& cap,
                CachedSolid* slot = nullptr) {
    if (reverse) std::reverse(vertices.begin(), vertices.end());
    Part part{static_cast<std::uint32_t>(corner_defs_.size()), static_cast<std::uint32_t>(vertices.size()), 0, 0,
              INFINITY, -INFINITY, INFINITY, -INFINITY};
    for (VertexIndex v : vertices) {
      const ApproxPoint a = approximation(solid, v, slot);
      const Vec2 p = project(a);
      const double e = project_error(a);
      corner_defs_.push_back(solid.defs[v]);
      corner_approx_.push_back(a);
      points_.push_back(p);
      errors_.push_back(e);
      part.min_u = std::min(part.min_u, p.x - e);
      part.max_u = std::max(part.max_u, p.x + e);
      part.min_v = std::min(part.min_v, p.y - e);
      part.max_v = std::max(part.max_v, p.y + e);
    }
    cap.min_u = std::min(cap.min_u, part.min_u);
    cap.max_u = std::max(cap.max_u, part.max_u);
    cap.min_v = std::min(cap.min_v, part.min_v);
    cap.max_v = std::max(cap.max_v, part.max_v);
    parts_.push_back(part);
  }

  // The polygon a part's overlaps are measured on (issue 22), relative to
  // reference_: its rounded corners, less each corner within 32 ulps (of the
  // pair's largest coordinate) of the corner kept before it, in both
  // coordinates. The clipper cuts along every edge's line, and the rounded
  // direction of an edge a few ulps long is noise: the line through it,
  // extended across the other polygon, cut a 0.0388 overlap to 0.0007 (regular
  // Voronoi grid on torus_quad, where a mesh edge crosses a cell plane a few
  // ulps from a cell edge). Leaving such a corner out moves the boundary by at
  // most those 32 ulps, so the area by at most that times the perimeter, inside
  // what rounding the corners already allows (bond_reference.hpp's tolerance);
  // nothing is decided on this polygon.
  //
  // A part spanning fewer than 2^23 of its corners' ulps is measured on its
  // exact corners' offsets from reference_ instead (position_relative_to): far
  // from the origin the rounded corners are coarse next to the part, and the
  // 32 ulps dropped whole parts (a unit cube at 1e14 cut into 64 measured a
  // total bond area of 0, where 12.73 is right). Elsewhere the offsets are the
  // rounded corners' differences, as the clipper took them, so the same bits;
  // a corner's ulp or two there is at most 2^-22 of the part, and the dropped
  // corners' 32 ulps 2^-18 (the exact offsets cost a microsecond a corner: at
  // 2^26 they were a third of `fracture` for a unit cube at 1e7).
  void add_measure_polygon(Part& part) {
    part.measure_first = static_cast<std::uint32_t>(measure_points_.size());
    const std::uint32_t end = part.first + part.count;
    double magnitude = 0, lo_u = INFINITY, hi_u = -INFINITY, lo_v = INFINITY, hi_v = -INFINITY;
    for (std::uint32_t i = part.first; i < end; ++i) {
      const Vec2 p = points_[i];
      magnitude = std::max({magnitude, std::fabs(p.x), std::fabs(p.y)});
      lo_u = std::min(lo_u, p.x);
      hi_u = std::max(hi_u, p.x);
      lo_v = std::min(lo_v, p.y);
      hi_v = std::max(hi_v, p.y);
    }
    const bool far = std::max(hi_u - lo_u, hi_v - lo_v) < 0x1p-29 * magnitude;
    double origin[3] = {0, 0, 0};  // reference_ in 3D (the dropped axis's coordinate is not read)
    origin[(axis_ + 1) % 3] = reference_.x;
    origin[(axis_ + 2) % 3] = reference_.y;
    local_.clear();
    for (std::uint32_t i = part.first; i < end; ++i) {
      if (far) {
        const Vec3 offset = position_relative_to(set_, corner_defs_[i], Vec3{origin[0], origin[1], origin[2]});
        const double c[3] = {offset.x, offset.y, offset.z};
        local_.push_back({c[(axis_ + 1) % 3], c[(axis_ + 2) % 3]});
      } else {
        local_.push_back({points_[i].x - reference_.x, points_[i].y - reference_.y});
      }
    }
    // The drop rule on the coordinates the polygon is measured in: the rounded
    // corners (absolute), or the exact offsets.
    const std::span<const Vec2> judged = far ? std::span<const Vec2>(local_)
                                             : std::span<const Vec2>(points_).subspan(part.first, part.count);
    const auto indistinct = [&](std::uint32_t i, std::uint32_t j) {
      const Vec2 a = judged[i], b = judged[j];
      const double largest = std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(b.x), std::fabs(b.y)});
      const double bound = 0x1p-47 * largest;
      return std::fabs(a.x - b.x) <= bound && std::fabs(a.y - b.y) <= bound;
    };
    std::uint32_t kept = 0;
    measure_points_.push_back(local_[kept]);
    for (std::uint32_t i = 1; i < part.count; ++i) {
      if (indistinct(i, kept) || (i + 1 == part.count && indistinct(i, 0))) continue;
      measure_points_.push_back(local_[i]);
      kept = i;
    }
    part.measure_count = static_cast<std::uint32_t>(measure_points_.size()) - part.measure_first;
  }

  // The node whose subtrees hold both leaves apart: their lowest common ancestor.
  NodeIndex separating_node(LeafIndex a, LeafIndex b) const {
    NodeIndex node = tree_.nodes[tree_.leaf_nodes[a]].parent;
    while (!(tree_.nodes[node].first_leaf <= b && b - tree_.nodes[node].first_leaf < tree_.nodes[node].leaf_count)) {
      node = tree_.nodes[node].parent;
    }
    return node;
  }

  // The bonds of cut `k` between the leaves of its cap faces, which
  // `for_each_ref(visit)` hands to `visit` in leaf order (a callable, not a
  // range view: clang 14, the sanitized build's compiler, rejects libstdc++
  // 12's std::views::transform over a span).
  template <class Record, class ForEachRef>
  void run_cut(std::uint32_t k, const ForEachRef& for_each_ref, std::vector<Record>& bonds) {
    const Projection projection = projection_of(set_, PlaneRef::cut(k));
    axis_ = projection.axis;
    flipped_ = projection.flipped;
    raw_ = Projection{axis_, false};
    faces_.clear();
    parts_.clear();
    corner_defs_.clear();
    corner_approx_.clear();
    points_.clear();
    measure_points_.clear();
    errors_.clear();
    for_each_ref([this](const FaceRef& ref) { add_face(ref); });
    const Plane& plane = tree_.cut_planes[k];
    const double n[3] = {plane.normal.x, plane.normal.y, plane.normal.z};
    area_scale_ = norm(plane.normal) / std::fabs(n[axis_]);
    plane_ = plane;
    unit_ = normalized(plane.normal);
    reference_ = points_.front();
    for (Part& part : parts_) add_measure_polygon(part);

    // Sweep the faces by min u; each side keeps the faces still reaching the line.
    sweep_.resize(faces_.size());
    for (std::uint32_t i = 0; i < faces_.size(); ++i) sweep_[i] = i;
    std::sort(sweep_.begin(), sweep_.end(), [&](std::uint32_t a, std::uint32_t b) {
      return faces_[a].min_u < faces_[b].min_u || (!(faces_[b].min_u < faces_[a].min_u) && a < b);
    });
    active_[0].clear();
    active_[1].clear();
    pending_.clear();
    for (const std::uint32_t index : sweep_) {
      const CapFace& face = faces_[index];
      auto& others = active_[face.above ? 0 : 1];
      std::size_t kept = 0;
      for (const std::uint32_t other_index : others) {
        const CapFace& other = faces_[other_index];
        if (other.max_u < face.min_u) continue;
        others[kept++] = other_index;
        if (other.max_v < face.min_v || other.min_v > face.max_v) continue;
        const CapFace& below = face.above ? other : face;
        const CapFace& above = face.above ? face : other;
        measure_pair(below, above);
      }
      others.resize(kept);
      active_[face.above ? 1 : 0].push_back(index);
    }
    // Leaves may meet on a cut through several faces (non-convex leaves): sum them.
    std::sort(pending_.begin(), pending_.end(), [](const Pending& a, const Pending& b) {
      return a.below != b.below ? a.below < b.below : a.above < b.above;
    });
    for (std::size_t i = 0; i < pending_.size();) {
      std::size_t j = i;
      Clipper::Measure total;
      bool touching = false;
      double box[4] = {INFINITY, -INFINITY, INFINITY, -INFINITY};
      for (; j < pending_.size() && pending_[j].below == pending_[i].below && pending_[j].above == pending_[i].above;
           ++j) {
        touching |= pending_[j].touching;
        total.area += pending_[j].measure.area;
        total.area_times_u += pending_[j].measure.area_times_u;
        total.area_times_v += pending_[j].measure.area_times_v;
        box[0] = std::min(box[0], pending_[j].box[0]);
        box[1] = std::max(box[1], pending_[j].box[1]);
        box[2] = std::min(box[2], pending_[j].box[2]);
        box[3] = std::max(box[3], pending_[j].box[3]);
      }
      if (touching) {
        const LeafIndex below = pending_[i].below, above = pending_[i].above;
        double u, v;
        if (total.area > 0) {
          u = reference_.x + total.area_times_u / total.area;
          v = reference_.y + total.area_times_v / total.area;
        } else {
          // The overlap exists exactly but its area rounds to nothing: the centre
          // of the overlapping parts' box overlap.
          u = 0.5 * (box[0] + box[1]);
          v = 0.5 * (box[2] + box[3]);
        }
        add_bond(bonds, k, below, above, total.area * area_scale_, u, v);
      }
      i = j;
    }
  }

  struct Pending {
    LeafIndex below, above;
    bool touching;
    Clipper::Measure measure;
    double box[4];
  };

  std::span<const Vec2> measure_points_of(const Part& p) const {
    return {measure_points_.data() + p.measure_first, p.measure_count};
  }

  void measure_pair(const CapFace& below, const CapFace& above) {
    Pending pending{below.leaf, above.leaf, false, {}, {INFINITY, -INFINITY, INFINITY, -INFINITY}};
    bool any_box = false;
    for (std::uint32_t i = below.first_part; i < below.first_part + below.part_count; ++i) {
      for (std::uint32_t j = above.first_part; j < above.first_part + above.part_count; ++j) {
        const Part& a = parts_[i];
        const Part& b = parts_[j];
        if (a.max_u < b.min_u || b.max_u < a.min_u || a.max_v < b.min_v || b.max_v < a.min_v) continue;
        any_box = true;
        const Clipper::Measure m = clipper_.overlap(measure_points_of(a), measure_points_of(b), Vec2{0, 0});
        bool overlap = false;
        if (m.area > 0) {
          const Vec2 witness{reference_.x + m.area_times_u / m.area, reference_.y + m.area_times_v / m.area};
          overlap = strictly_inside(a, witness) && strictly_inside(b, witness);
        }
        if (!overlap) overlap = !separated(a, b) && !separated(b, a);
        if (!overlap) continue;
        pending.touching = true;
        pending.measure.area += m.area;
        pending.measure.area_times_u += m.area_times_u;
        pending.measure.area_times_v += m.area_times_v;
        pending.box[0] = std::min(pending.box[0], std::max(a.min_u, b.min_u));
        pending.box[1] = std::max(pending.box[1], std::min(a.max_u, b.max_u));
        pending.box[2] = std::min(pending.box[2], std::max(a.min_v, b.min_v));
        pending.box[3] = std::max(pending.box[3], std::min(a.max_v, b.max_v));
      }
    }
    if (any_box && pending.touching) pending_.push_back(pending);
  }

  // Whether a double point of the projection lies strictly inside a convex part:
  // strictly left of every edge, exactly. Each edge is first tried on the rounded
  // corners: (b - a) x (p - a) computed in doubles, with a bound on what the
  // corners' errors (ea, eb: each coordinate within them of the exact one) and
  // the arithmetic can change; only an edge that bound cannot settle goes to the
  // exact predicate on the defined points.
  bool strictly_inside(const Part& part, Vec2 p) const {
    for (std::uint32_t e = 0; e < part.count; ++e) {
      const std::uint32_t i = part.first + e, j = part.first + (e + 1) % part.count;
      const Vec2 a = points_[i], b = points_[j];
      const double ea = errors_[i], eb = errors_[j];
      const double bx = b.x - a.x, by = b.y - a.y, px = p.x - a.x, py = p.y - a.y;
      const double value = bx * py - by * px;
      // |Δ(b - a)| <= ea + eb and |Δ(p - a)| <= ea per coordinate; the products
      // and differences round four more times.
      const double span = std::fabs(bx) + std::fabs(by) + std::fabs(px) + std::fabs(py) + 2 * (ea + eb);
      const double bound = (ea + eb) * (std::fabs(px) + std::fabs(py) + ea) * 2 + ea * (std::fabs(bx) + std::fabs(by)) * 2 +
                           0x1p-50 * span * span;
      if (value > bound) continue;
      if (value < -bound) return false;
      if (orient_in_plane(set_, raw_, corner_defs_[i], corner_approx_[i], corner_defs_[j], corner_approx_[j], p) !=
          Sign::positive) {
        return false;
      }
    }
    return true;
  }

  // Whether an edge line of `part` has all of `other` on its closed outer side.
  bool separated(const Part& part, const Part& other) const {
    for (std::uint32_t e = 0; e < part.count; ++e) {
      const std::uint32_t i = part.first + e, j = part.first + (e + 1) % part.count;
      bool all_outside = true;
      for (std::uint32_t c = 0; c < other.count && all_outside; ++c) {
        all_outside = !strictly_left(i, j, other.first + c);
      }
      if (all_outside) return true;
    }
    return false;
  }

  // Whether corner z lies strictly left of the line from corner i to corner j,
  // exactly. Tried first on the rounded corners, as in strictly_inside: each
  // coordinate of b - a is within ea + eb of the exact difference, of p - a
  // within ea + ez; a value the bound cannot settle (a corner on the line, as
  // where two parts share an edge of their node's cap) goes to the exact
  // predicate on the defined points.
  bool strictly_left(std::uint32_t i, std::uint32_t j, std::uint32_t z) const {
    const Vec2 a = points_[i], b = points_[j], p = points_[z];
    const double e_edge = errors_[i] + errors_[j], e_point = errors_[i] + errors_[z];
    const double bx = b.x - a.x, by = b.y - a.y, px = p.x - a.x, py = p.y - a.y;
    const double value = bx * py - by * px;
    const double span = std::fabs(bx) + std::fabs(by) + std::fabs(px) + std::fabs(py) + 2 * (e_edge + e_point);
    const double bound = 2 * (e_edge * (std::fabs(px) + std::fabs(py) + e_point) + e_point * (std::fabs(bx) + std::fabs(by))) +
                         0x1p-50 * span * span;
    if (value > bound) return true;
    if (value < -bound) return false;
    return orient_in_plane(set_, raw_, corner_defs_[i], corner_approx_[i], corner_defs_[j], corner_approx_[j],
                           corner_defs_[z], corner_approx_[z]) == Sign::positive;
  }

  struct CachedSolid {
    LeafIndex leaf;      // whose solid `solid` is; no_leaf: none
    NodeShapes shapes;   // owns what `solid` points to
    const Solid* solid = nullptr;
    std::vector<ApproxPoint> approx;  // per vertex of `solid`, where `known`
    std::vector<std::uint8_t> known;
  };
  static constexpr LeafIndex no_leaf = ~LeafIndex{0};
  static constexpr std::uint32_t no_cut = ~std::uint32_t{0};
  static constexpr std::size_t cache_slots = 256;

  const MeshTree& tree_;
  const PlaneSet set_;
  std::vector<CachedSolid> cache_;  ///< by leaf % cache_slots (leaf_solid)
  std::vector<FaceRef> refs_;
  std::vector<std::size_t> start_;
  std::vector<std::uint32_t> order_;
  int axis_ = 2;
  bool flipped_ = false;
  Projection raw_;
  std::vector<CapFace> faces_;
  std::vector<Part> parts_;
  std::vector<PointDef> corner_defs_;       ///< per corner: its vertex's definition
  std::vector<ApproxPoint> corner_approx_;  ///< per corner: its vertex's approximation
  std::vector<Vec2> points_;
  std::vector<double> errors_;  ///< per corner: how far the rounded 2D point may be from the exact one
  std::vector<Vec2> measure_points_;  ///< per part: the polygon overlaps are measured on (add_measure_polygon)
  std::vector<Vec2> local_;           ///< add_measure_polygon's corners relative to reference_
  std::vector<VertexIndex> part_vertices_;
  std::vector<Triangle> triangles_;
  std::vector<Vec3> points3_;
  Solid filled_;  ///< with_approximations' copy, of leaf filled_leaf_
  LeafIndex filled_leaf_ = ~LeafIndex{0};
  std::vector<std::uint32_t> sweep_;
  std::array<std::vector<std::uint32_t>, 2> active_;
  std::vector<Pending> pending_;
  detail::PopulatedAhead<std::vector<PackedBond>>* bonds_ahead_ = nullptr;  ///< run_packed's, while it runs
  Clipper clipper_;
  double area_scale_ = 1;
  Plane plane_;
  Vec3 unit_;  ///< plane_'s unit normal
  Vec2 reference_;
};

}  // namespace

std::vector<Bond> find_plane_bonds(const MeshTree& tree) {
  if (tbb::this_task_arena::max_concurrency() <= 1) return PlaneBonds(tree).run();
  return PlaneBonds::run_parallel(tree);
}

std::vector<PackedBond> find_packed_plane_bonds(const MeshTree& tree) {
  const auto threads = static_cast<std::uint32_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  if (threads == 1) return PlaneBonds(tree).run_packed();
  // Eight runs a thread or more, so a few slow ones still leave the threads
  // evenly loaded; none under 64 leaves, where a run's setup would show.
  const auto per_run = static_cast<std::uint32_t>((tree.leaf_count() + 8 * threads - 1) / (8 * threads));
  return PlaneBonds::run_packed_split(tree, std::max<std::uint32_t>(64, per_run));
}

std::vector<PackedBond> find_packed_plane_bonds(const MeshTree& tree, std::uint32_t run_leaves) {
  return PlaneBonds::run_packed_split(tree, run_leaves);
}

Bond unpack_bond(const MeshTree& tree, const PackedBond& packed) {
  const Plane& plane = tree.cut_planes[packed.cut_node];
  return bond_on_plane(plane, normalized(plane.normal), packed.axis, packed.first, packed.second, packed.cut_node,
                       packed.first_below, packed.area, packed.u, packed.v);
}

}  // namespace shatter
