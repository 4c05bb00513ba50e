// The true-contact bonds of a tree without exact solids (find_bonds; trees the
// retired fast and exact kernels wrote, read from older files): the cap
// faces of each cut (contact_polygons.hpp) swept in the cut plane, each pair that
// may touch decided exactly and measured on its rounded overlap. Plane-kernel
// trees go to find_plane_bonds (plane_bonds.cpp); the seed's box rule is in
// bounding_box_bonds.cpp.

#include "shatter/meshtree/bonds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "clip2d.hpp"
#include "contact_polygons.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/kernel/projection.hpp"
#include "shatter/meshtree/tree.hpp"

namespace shatter {
namespace {

using detail::Box2;
using detail::box_of;
using detail::boxes_overlap;
using detail::Clipper;
using detail::Face;
using detail::Faces;
using detail::interiors_intersect;
using detail::orientation;
using detail::strictly_inside;

// --- one cut ------------------------------------------------------------------------

// The bonds of one cut: its faces sorted by min u and swept, each side keeping the
// faces whose u-range still reaches the sweep line; a pair whose closed boxes
// overlap is then decided exactly:
//   1. the centroid of the outlines' overlap (a rounded point, tested exactly)
//      lies inside a triangle of each face: a bond, the common case, settled
//      without looking at the other triangles;
//   2. otherwise hulls whose interiors do not meet: no bond (a face lies in its
//      hull);
//   3. otherwise (faces that touch, or are far from convex) triangle against
//      triangle, until one pair's interiors meet.
// A bond between faces that fill their hulls is measured on the overlap of their
// outlines; otherwise triangle pair by triangle pair. Buffers are kept between
// cuts.
class CutBonds {
 public:
  void run(const MeshTree& tree, const Faces& faces, std::span<const std::uint32_t> cut_faces, const Plane& plane,
           const PlaneProjection& projection, std::vector<Bond>& bonds) {
    tree_ = &tree;
    faces_ = &faces;
    reference_ = faces.hull_corners[faces.faces[cut_faces.front()].first_hull_corner];
    const int dropped = 3 - projection.u_axis - projection.v_axis;
    // Projected area times |n| / |n_dropped| is the area in the plane.
    area_scale_ = norm(plane.normal) / std::fabs(plane.normal[dropped]);
    unit_normal_ = normalized(plane.normal);
    plane_ = plane;
    projection_ = projection;

    order_.assign(cut_faces.begin(), cut_faces.end());
    std::sort(order_.begin(), order_.end(), [&](std::uint32_t a, std::uint32_t b) {
      const double ua = faces.faces[a].min_u, ub = faces.faces[b].min_u;
      return ua < ub || (!(ub < ua) && a < b);
    });
    active_[0].clear();
    active_[1].clear();
    for (const std::uint32_t index : order_) {
      const Face& face = faces.faces[index];
      std::vector<std::uint32_t>& others = active_[face.above ? 0 : 1];
      std::size_t kept = 0;
      for (const std::uint32_t other_index : others) {
        const Face& other = faces.faces[other_index];
        if (other.max_u < face.min_u) continue;  // passed for good: every later min u is larger
        others[kept++] = other_index;
        if (other.max_v < face.min_v || other.min_v > face.max_v) continue;
        add_bond_if_touching(face.above ? other : face, face.above ? face : other, bonds);
      }
      others.resize(kept);
      active_[face.above ? 1 : 0].push_back(index);
    }
  }

 private:
  void add_bond_if_touching(const Face& below, const Face& above, std::vector<Bond>& bonds) {
    const Faces& faces = *faces_;
    const Clipper::Measure outlines = clipper_.overlap(faces.outline_of(below), faces.outline_of(above), reference_);
    bool touching = false;
    if (outlines.area > 0) {
      const Vec2 witness{reference_.x + outlines.area_times_u / outlines.area,
                         reference_.y + outlines.area_times_v / outlines.area};
      touching = inside_a_triangle(below, witness) && inside_a_triangle(above, witness);
    }
    if (!touching) {
      if (!interiors_intersect(faces.hull_of(below), faces.hull_of(above))) return;
      if (!some_triangles_overlap(below, above)) return;
    }

    Clipper::Measure measure = outlines;
    if (!below.fills_hull || !above.fills_hull) measure = triangle_overlaps(below, above);
    double local_u, local_v;
    if (measure.area > 0) {
      local_u = measure.area_times_u / measure.area;
      local_v = measure.area_times_v / measure.area;
    } else {
      // The overlap exists exactly but its area rounds to nothing: the centre of
      // the faces' box overlap still lies in both leaves' boxes.
      local_u = 0.5 * (std::max(below.min_u, above.min_u) + std::min(below.max_u, above.max_u)) - reference_.x;
      local_v = 0.5 * (std::max(below.min_v, above.min_v) + std::min(below.max_v, above.max_v)) - reference_.y;
    }
    Bond bond;
    bond.first = std::min(below.leaf, above.leaf);
    bond.second = std::max(below.leaf, above.leaf);
    bond.cut_node = below.cut;
    bond.area = measure.area * area_scale_;
    bond.centroid = lift(reference_.x + local_u, reference_.y + local_v);
    // From below (n·x + d < 0) into above is along +n.
    bond.normal = bond.first == below.leaf ? unit_normal_ : -unit_normal_;
    bonds.push_back(bond);
  }

  // The projected corners of a face's triangle, as stored (either turn).
  std::array<Vec2, 3> corners_of(const Face& face, TriangleIndex t) const {
    const Mesh& mesh = tree_->leaf(face.leaf).mesh;
    const Triangle& triangle = mesh.triangles[t];
    return {projection_(mesh.positions[triangle[0]]), projection_(mesh.positions[triangle[1]]),
            projection_(mesh.positions[triangle[2]])};
  }

  bool inside_a_triangle(const Face& face, Vec2 p) const {
    const auto triangles = faces_->triangles_of(face);
    return std::any_of(triangles.begin(), triangles.end(),
                       [&](TriangleIndex t) { return strictly_inside(corners_of(face, t), p); });
  }

  // The face's triangles with an interior, counter-clockwise, with their boxes.
  void ccw_triangles(const Face& face, std::vector<std::array<Vec2, 3>>& triangles, std::vector<Box2>& boxes) const {
    triangles.clear();
    boxes.clear();
    for (const TriangleIndex t : faces_->triangles_of(face)) {
      std::array<Vec2, 3> corners = corners_of(face, t);
      const Sign turn = orientation(corners[0], corners[1], corners[2]);
      if (turn == Sign::zero) continue;
      if (turn == Sign::negative) std::swap(corners[1], corners[2]);
      triangles.push_back(corners);
      boxes.push_back(box_of(corners));
    }
  }

  bool some_triangles_overlap(const Face& below, const Face& above) {
    ccw_triangles(below, below_triangles_, below_boxes_);
    ccw_triangles(above, above_triangles_, above_boxes_);
    for (std::size_t i = 0; i < below_triangles_.size(); ++i) {
      for (std::size_t j = 0; j < above_triangles_.size(); ++j) {
        if (boxes_overlap(below_boxes_[i], above_boxes_[j]) &&
            interiors_intersect(below_triangles_[i], above_triangles_[j])) {
          return true;
        }
      }
    }
    return false;
  }

  Clipper::Measure triangle_overlaps(const Face& below, const Face& above) {
    ccw_triangles(below, below_triangles_, below_boxes_);
    ccw_triangles(above, above_triangles_, above_boxes_);
    Clipper::Measure total;
    for (std::size_t i = 0; i < below_triangles_.size(); ++i) {
      for (std::size_t j = 0; j < above_triangles_.size(); ++j) {
        if (!boxes_overlap(below_boxes_[i], above_boxes_[j])) continue;
        const Clipper::Measure m = clipper_.overlap(below_triangles_[i], above_triangles_[j], reference_);
        total.area += m.area;
        total.area_times_u += m.area_times_u;
        total.area_times_v += m.area_times_v;
      }
    }
    return total;
  }

  // The point of the plane over (u, v) of its projection.
  Vec3 lift(double u, double v) const {
    const int dropped = 3 - projection_.u_axis - projection_.v_axis;
    const double w = -(plane_.offset + plane_.normal[projection_.u_axis] * u + plane_.normal[projection_.v_axis] * v) /
                     plane_.normal[dropped];
    std::array<double, 3> xyz{};
    xyz[static_cast<std::size_t>(projection_.u_axis)] = u;
    xyz[static_cast<std::size_t>(projection_.v_axis)] = v;
    xyz[static_cast<std::size_t>(dropped)] = w;
    return {xyz[0], xyz[1], xyz[2]};
  }

  const MeshTree* tree_ = nullptr;
  const Faces* faces_ = nullptr;
  Vec2 reference_;
  double area_scale_ = 1;
  Vec3 unit_normal_;
  Plane plane_;
  PlaneProjection projection_;
  std::vector<std::uint32_t> order_;
  std::array<std::vector<std::uint32_t>, 2> active_;  // [0] below, [1] above
  Clipper clipper_;
  std::vector<std::array<Vec2, 3>> below_triangles_, above_triangles_;
  std::vector<Box2> below_boxes_, above_boxes_;
};

}  // namespace

std::vector<Bond> find_bonds(const MeshTree& tree) {
  if (tree.has_exact_representation()) return find_plane_bonds(tree);
  std::vector<PlaneProjection> projections(tree.nodes.size());
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    if (!tree.nodes[k].is_leaf()) projections[k] = PlaneProjection::of(tree.cut_planes[k]);
  }
  const Faces faces = detail::gather_cap_faces(tree, projections);

  std::vector<Bond> bonds;
  CutBonds cut_bonds;
  for (NodeIndex k = 0; k < tree.nodes.size(); ++k) {
    const std::span<const std::uint32_t> cut_faces(faces.order.data() + faces.start[k],
                                                   faces.start[k + 1] - faces.start[k]);
    if (cut_faces.size() < 2) continue;
    cut_bonds.run(tree, faces, cut_faces, tree.cut_planes[k], projections[k], bonds);
  }
  std::sort(bonds.begin(), bonds.end(), [](const Bond& a, const Bond& b) {
    if (a.first != b.first) return a.first < b.first;
    if (a.second != b.second) return a.second < b.second;
    return a.cut_node < b.cut_node;
  });
  return bonds;
}

}  // namespace shatter
