// The seed's bond rule, bounding boxes that overlap, kept to measure how many
// false bonds it makes against true contact (bonds.hpp).

#include "shatter/meshtree/bonds.hpp"

#include <CGAL/box_intersection_d.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "shatter/meshtree/tree.hpp"

namespace shatter {
namespace {

struct LeafBox {
  std::array<double, 3> lo, hi;
  LeafIndex leaf;
};

// CGAL's box-intersection traits over LeafBox, with the leaf index as the box id
// (CGAL's own explicit ids come from a global counter).
struct LeafBoxTraits {
  using Box_parameter = const LeafBox&;
  using NT = double;
  using ID = std::size_t;
  static NT min_coord(Box_parameter box, int axis) { return box.lo[static_cast<std::size_t>(axis)]; }
  static NT max_coord(Box_parameter box, int axis) { return box.hi[static_cast<std::size_t>(axis)]; }
  static ID id(Box_parameter box) { return box.leaf; }
  static int dimension() { return 3; }
};

}  // namespace

std::vector<std::pair<LeafIndex, LeafIndex>> find_bounding_box_bonds(const MeshTree& tree) {
  std::vector<LeafBox> boxes;
  boxes.reserve(tree.leaf_count());
  for (LeafIndex leaf = 0; leaf < tree.leaf_count(); ++leaf) {
    const Mesh& mesh = tree.leaf(leaf).mesh;
    if (mesh.positions.empty()) continue;
    LeafBox box{{mesh.positions[0].x, mesh.positions[0].y, mesh.positions[0].z},
                {mesh.positions[0].x, mesh.positions[0].y, mesh.positions[0].z},
                leaf};
    for (const Vec3& p : mesh.positions) {
      for (int axis = 0; axis < 3; ++axis) {
        const auto a = static_cast<std::size_t>(axis);
        box.lo[a] = std::min(box.lo[a], p[axis]);
        box.hi[a] = std::max(box.hi[a], p[axis]);
      }
    }
    boxes.push_back(box);
  }

  std::vector<std::pair<LeafIndex, LeafIndex>> pairs;
  CGAL::box_self_intersection_d<CGAL::Sequential_tag>(
      boxes.begin(), boxes.end(),
      [&pairs](const LeafBox& a, const LeafBox& b) {
        pairs.emplace_back(std::min(a.leaf, b.leaf), std::max(a.leaf, b.leaf));
      },
      LeafBoxTraits(), std::ptrdiff_t{10}, CGAL::Box_intersection_d::CLOSED);
  std::sort(pairs.begin(), pairs.end());
  // The self-intersection reports each pair once; unique() only guards the promise.
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

BondRuleComparison compare_bond_rules(const MeshTree& tree) {
  std::vector<std::pair<LeafIndex, LeafIndex>> true_pairs;
  for (const Bond& bond : find_bonds(tree)) {
    // Bonds are sorted by pair, so a pair bonded on several cuts is adjacent.
    if (true_pairs.empty() || true_pairs.back() != std::pair{bond.first, bond.second}) {
      true_pairs.emplace_back(bond.first, bond.second);
    }
  }
  const std::vector<std::pair<LeafIndex, LeafIndex>> box_pairs = find_bounding_box_bonds(tree);

  BondRuleComparison comparison;
  comparison.true_bonds = true_pairs.size();
  comparison.box_bonds = box_pairs.size();
  std::size_t both = 0;
  for (std::size_t t = 0, b = 0; t < true_pairs.size() && b < box_pairs.size();) {
    if (true_pairs[t] < box_pairs[b]) {
      ++t;
    } else if (box_pairs[b] < true_pairs[t]) {
      ++b;
    } else {
      ++both, ++t, ++b;
    }
  }
  comparison.false_box_bonds = box_pairs.size() - both;
  comparison.missed_true_bonds = true_pairs.size() - both;
  return comparison;
}

}  // namespace shatter
