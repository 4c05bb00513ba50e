// Gathering the cap faces of a tree without exact solids (contact_polygons.hpp): one
// pass over the leaves' triangles, a hull per face, then a counting sort by cut.

#include "contact_polygons.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "clip2d.hpp"

namespace shatter::detail {
namespace {

// Twice the area of a counter-clockwise polygon, fanned from its first corner so
// that no large products are summed.
double twice_area_of(std::span<const Vec2> polygon) {
  double twice = 0;
  for (std::size_t i = 1; i + 1 < polygon.size(); ++i) twice += cross(polygon[0], polygon[i], polygon[i + 1]);
  return twice;
}

// The relative shortfall below which a face's triangles count as filling its
// hull. It only chooses how an overlap is measured, never whether one exists:
// rounding moves the cut points that subdivide a face's edges by an ulp or so,
// which makes a convex face non-convex by areas near 1e-16 of its own; a face
// that is truly non-convex misses its hull by far more.
constexpr double hull_fill_tolerance = 1e-12;

// A hull corner whose turn spans less than this fraction of the hull's area is
// left out of the outline the overlaps are measured on. Rounded cut points make
// hulls of sliced faces carry such corners by the handful; each changes a measured
// area by no more than that fraction, and dropping them halves the clipping work.
constexpr double outline_tolerance = 1e-13;

// Builds faces from the leaves, then groups them by cut (a counting sort).
class FaceBuilder {
 public:
  Faces build(const MeshTree& tree, const std::vector<PlaneProjection>& projections) {
    Faces result;
    std::size_t triangle_count = 0;
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) triangle_count += tree.leaf(leaf).mesh->triangle_count();
    result.triangles.reserve(triangle_count);
    for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
      const Mesh& mesh = tree.leaf(leaf).mesh;
      // (cut, triangle) packed in one integer: sorting them groups a face.
      caps_.clear();
      // A leaf has a few surfaces over many triangles: looking each up once
      // spares a visit to a (large, far away) tree node per triangle.
      SurfaceId cached_surface = original_surface;
      NodeIndex cached_cut = no_node;
      for (TriangleIndex t = 0; t < mesh.triangles.size(); ++t) {
        const SurfaceId surface = mesh.surfaces[t];
        if (surface == original_surface) continue;
        if (surface != cached_surface) {
          cached_surface = surface;
          cached_cut = cut_of(tree, surface, leaf);
        }
        if (cached_cut != no_node) caps_.push_back(std::uint64_t{cached_cut} << 32 | t);
      }
      std::sort(caps_.begin(), caps_.end());
      vertex_stamp_.assign(mesh.vertex_count(), no_stamp);
      for (std::size_t i = 0; i < caps_.size();) {
        const auto cut = static_cast<NodeIndex>(caps_[i] >> 32);
        std::size_t end = i;
        while (end < caps_.size() && caps_[end] >> 32 == cut) ++end;
        add_face(mesh, std::span(caps_).subspan(i, end - i), projections[cut], cut, leaf,
                 leaf_is_above(tree, cut, leaf), result);
        i = end;
      }
    }
    result.start.assign(tree.nodes.size() + 1, 0);
    for (const Face& face : result.faces) ++result.start[face.cut + 1];
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) result.start[k + 1] += result.start[k];
    result.order.resize(result.faces.size());
    std::vector<std::size_t> next(result.start.begin(), result.start.end() - 1);
    for (std::uint32_t f = 0; f < result.faces.size(); ++f) result.order[next[result.faces[f].cut]++] = f;
    return result;
  }

 private:
  // Which side of internal node `cut`'s plane `leaf` lies on: the side of the
  // child whose range holds it. Children are scanned, not searched, so that no
  // order of the children list is assumed; a cut rarely makes more than a few.
  static bool leaf_is_above(const MeshTree& tree, NodeIndex cut, LeafIndex leaf) {
    for (const NodeIndex child : tree.nodes[cut].children) {
      const MeshTreeNode& c = tree.nodes[child];
      if (leaf >= c.first_leaf && leaf - c.first_leaf < c.leaf_count) return c.above_parent_plane;
    }
    return false;  // unreachable in a well-formed tree: the leaf is in the cut's range
  }

  // The cut a triangle's surface id names, when that node is an internal ancestor
  // of `leaf`; otherwise no_node (an input surface id, which bonds ignore).
  static NodeIndex cut_of(const MeshTree& tree, SurfaceId surface, LeafIndex leaf) {
    if (surface == original_surface || surface - 1 >= tree.nodes.size()) return no_node;
    const NodeIndex cut = surface - 1;
    const MeshTreeNode& node = tree.nodes[cut];
    if (node.is_leaf() || leaf < node.first_leaf || leaf - node.first_leaf >= node.leaf_count) return no_node;
    return cut;
  }

  void add_face(const Mesh& mesh, std::span<const std::uint64_t> caps, const PlaneProjection& projection, NodeIndex cut,
                LeafIndex leaf, bool above, Faces& out) {
    const auto face_number = static_cast<std::uint32_t>(out.faces.size());
    Face face{cut,
              leaf,
              above,
              false,
              static_cast<std::uint32_t>(out.triangles.size()),
              static_cast<std::uint32_t>(caps.size()),
              static_cast<std::uint32_t>(out.hull_corners.size()),
              0,
              static_cast<std::uint32_t>(out.outline_corners.size()),
              0,
              0,
              0,
              0,
              0};
    points_.clear();
    // Summed unsigned: a triangle's orientation is decided where it matters.
    double twice_triangle_area = 0;
    for (const std::uint64_t cap : caps) {
      const auto t = static_cast<TriangleIndex>(cap & 0xffffffffu);
      out.triangles.push_back(t);
      const Triangle& triangle = mesh.triangles[t];
      std::array<Vec2, 3> corners;
      for (int c = 0; c < 3; ++c) {
        corners[c] = projection(mesh.positions[triangle[c]]);
        if (vertex_stamp_[triangle[c]] != face_number) {
          vertex_stamp_[triangle[c]] = face_number;
          points_.push_back(corners[c]);
        }
      }
      twice_triangle_area += std::fabs(cross(corners[0], corners[1], corners[2]));
    }
    convex_hull(points_, hull_);
    // Collinear points only: no triangle of the face has an interior.
    if (hull_.size() < 3) {
      out.triangles.resize(face.first_triangle);
      return;
    }
    for (const Vec2 p : hull_) out.hull_corners.push_back(p);
    face.hull_corner_count = static_cast<std::uint32_t>(hull_.size());
    face.min_u = face.max_u = hull_[0].x;
    face.min_v = face.max_v = hull_[0].y;
    for (const Vec2 p : hull_) {
      face.min_u = std::min(face.min_u, p.x);
      face.max_u = std::max(face.max_u, p.x);
      face.min_v = std::min(face.min_v, p.y);
      face.max_v = std::max(face.max_v, p.y);
    }
    const double twice_hull_area = twice_area_of(hull_);
    face.fills_hull = twice_triangle_area >= twice_hull_area * (1 - hull_fill_tolerance);
    // The first corner (lowest x, then y) is a true corner and always stays; each
    // later one goes if the triangle it adds to the outline kept so far is thin,
    // so the area given up is at most the tolerance per corner.
    out.outline_corners.push_back(hull_[0]);
    for (std::size_t i = 1; i < hull_.size(); ++i) {
      const Vec2 next = hull_[(i + 1) % hull_.size()];
      if (cross(out.outline_corners.back(), hull_[i], next) > outline_tolerance * twice_hull_area) {
        out.outline_corners.push_back(hull_[i]);
      }
    }
    face.outline_corner_count = static_cast<std::uint32_t>(out.outline_corners.size()) - face.first_outline_corner;
    if (face.outline_corner_count < 3) {  // too thin to thin out: the hull as it is
      out.outline_corners.resize(face.first_outline_corner);
      out.outline_corners.insert(out.outline_corners.end(), hull_.begin(), hull_.end());
      face.outline_corner_count = static_cast<std::uint32_t>(hull_.size());
    }
    out.faces.push_back(face);
  }

  // Andrew's monotone chain, counter-clockwise, collinear points dropped; fewer
  // than three corners when the points are collinear.
  static void convex_hull(std::vector<Vec2>& points, std::vector<Vec2>& hull) {
    if (points.size() < 3) {
      hull.clear();
      return;
    }
    std::sort(points.begin(), points.end(), [](Vec2 a, Vec2 b) { return a.x < b.x || (!(b.x < a.x) && a.y < b.y); });
    hull.assign(2 * points.size(), Vec2{});
    std::size_t k = 0;
    for (const Vec2 p : points) {  // lower chain
      while (k >= 2 && orientation(hull[k - 2], hull[k - 1], p) != Sign::positive) --k;
      hull[k++] = p;
    }
    const std::size_t lower = k + 1;
    for (std::size_t i = points.size() - 1; i-- > 0;) {  // upper chain
      while (k >= lower && orientation(hull[k - 2], hull[k - 1], points[i]) != Sign::positive) --k;
      hull[k++] = points[i];
    }
    hull.resize(k - 1);  // the last point repeats the first
  }

  static constexpr std::uint32_t no_stamp = 0xffffffffu;
  std::vector<std::uint64_t> caps_;
  std::vector<std::uint32_t> vertex_stamp_;  // the last face that took each vertex of the leaf
  std::vector<Vec2> points_, hull_;
};

}  // namespace

Faces gather_cap_faces(const MeshTree& tree, const std::vector<PlaneProjection>& projections) {
  return FaceBuilder().build(tree, projections);
}

}  // namespace shatter::detail
