// Minimal cover: the seed's Fig 3.3 example, edge cases, and a property test on
// random trees against a brute-force definition of the cover.

#include <catch2/catch.hpp>

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/meshtree/cover.hpp"
#include "support/checks.hpp"

using namespace shatter;
using namespace shatter::test;

namespace {

// Fills leaf ranges, depths and leaf_nodes of a tree whose nodes are already in
// depth-first preorder with parent and children set (meshes stay empty: the
// cover only reads the topology).
void finish_tree(MeshTree& tree) {
  tree.leaf_nodes.clear();
  for (NodeIndex i = 0; i < tree.nodes.size(); ++i) {
    MeshTreeNode& node = tree.nodes[i];
    node.depth = node.parent == no_node ? 0 : tree.nodes[node.parent].depth + 1;
    if (node.is_leaf()) {
      node.first_leaf = static_cast<LeafIndex>(tree.leaf_nodes.size());
      node.leaf_count = 1;
      tree.leaf_nodes.push_back(i);
    }
  }
  // Children come after their parent in preorder, so a backward pass sees every
  // child's range before its parent's.
  for (NodeIndex i = static_cast<NodeIndex>(tree.nodes.size()); i-- > 0;) {
    MeshTreeNode& node = tree.nodes[i];
    if (node.is_leaf()) continue;
    node.first_leaf = tree.nodes[node.children.front()].first_leaf;
    node.leaf_count = 0;
    for (const NodeIndex child : node.children) node.leaf_count += tree.nodes[child].leaf_count;
  }
}

// Appends a node under `parent` (no_node for the root) and returns its index.
NodeIndex add_node(MeshTree& tree, NodeIndex parent) {
  const auto index = static_cast<NodeIndex>(tree.nodes.size());
  tree.nodes.emplace_back();
  tree.nodes.back().parent = parent;
  if (parent != no_node) tree.nodes[parent].children.push_back(index);
  return index;
}

// The seed's Fig 3.3 tree: root -> A2, B2, C2; A2 and B2 with two leaves each;
// C2 with leaves E3 and F3. Node numbers in preorder:
//   0 root, 1 A2, 2 a, 3 a', 4 B2, 5 b, 6 b', 7 C2, 8 E3, 9 F3; leaves 0..5.
struct FigureTree {
  MeshTree tree;
  NodeIndex root = 0, a2 = 0, b2 = 0, c2 = 0, e3 = 0, f3 = 0;
};
FigureTree figure_3_3_tree() {
  FigureTree f;
  f.root = add_node(f.tree, no_node);
  f.a2 = add_node(f.tree, f.root);
  add_node(f.tree, f.a2);
  add_node(f.tree, f.a2);
  f.b2 = add_node(f.tree, f.root);
  add_node(f.tree, f.b2);
  add_node(f.tree, f.b2);
  f.c2 = add_node(f.tree, f.root);
  f.e3 = add_node(f.tree, f.c2);
  f.f3 = add_node(f.tree, f.c2);
  finish_tree(f.tree);
  return f;
}

// A random tree built in preorder: arity 2-4, each node below the root made a
// leaf with a probability that grows with its depth, and never deeper than
// max_depth.
MeshTree random_tree(Random& random, std::uint32_t max_depth) {
  MeshTree tree;
  const std::function<void(NodeIndex, std::uint32_t)> grow = [&](NodeIndex node, std::uint32_t depth) {
    if (depth == max_depth) return;
    if (depth > 0 && random.uniform() < 0.15 + 0.15 * depth) return;
    const std::size_t arity = 2 + random.index(3);
    for (std::size_t c = 0; c < arity; ++c) grow(add_node(tree, node), depth + 1);
  };
  grow(add_node(tree, no_node), 0);
  finish_tree(tree);
  return tree;
}

// The cover by definition: every node all of whose leaves are in the set while
// its parent has one that is not; in preorder, which for disjoint ranges is
// increasing leaf order.
std::vector<NodeIndex> brute_force_cover(const MeshTree& tree, const std::vector<bool>& in_set) {
  const auto all_in = [&](NodeIndex n) {
    const MeshTreeNode& node = tree.nodes[n];
    for (LeafIndex l = node.first_leaf; l < node.first_leaf + node.leaf_count; ++l) {
      if (!in_set[l]) return false;
    }
    return true;
  };
  std::vector<NodeIndex> cover;
  for (NodeIndex n = 0; n < tree.nodes.size(); ++n) {
    if (all_in(n) && (tree.nodes[n].parent == no_node || !all_in(tree.nodes[n].parent))) cover.push_back(n);
  }
  return cover;
}

// The promised properties, checked directly rather than against the reference.
void check_cover_properties(const MeshTree& tree, const std::vector<bool>& in_set,
                            const std::vector<NodeIndex>& cover) {
  std::vector<int> covered(tree.leaf_count(), 0);
  LeafIndex previous_end = 0;
  for (const NodeIndex n : cover) {
    const MeshTreeNode& node = tree.nodes[n];
    REQUIRE(node.first_leaf >= previous_end);  // increasing leaf order, disjoint
    previous_end = node.first_leaf + node.leaf_count;
    for (LeafIndex l = node.first_leaf; l < previous_end; ++l) ++covered[l];
    // Not mergeable: the parent always has a leaf outside the set.
    if (node.parent != no_node) {
      const MeshTreeNode& parent = tree.nodes[node.parent];
      bool parent_all_in = true;
      for (LeafIndex l = parent.first_leaf; l < parent.first_leaf + parent.leaf_count; ++l) {
        parent_all_in = parent_all_in && in_set[l];
      }
      REQUIRE_FALSE(parent_all_in);
    }
  }
  for (LeafIndex l = 0; l < tree.leaf_count(); ++l) REQUIRE(covered[l] == (in_set[l] ? 1 : 0));
}

}  // namespace

TEST_CASE("minimal cover reproduces the seed's Fig 3.3", "[cover]") {
  const FigureTree f = figure_3_3_tree();
  const MeshTree& tree = f.tree;
  REQUIRE(tree.leaf_count() == 6);
  REQUIRE(tree.nodes[f.e3].first_leaf == 4);

  SECTION("E3 broken off: A2, B2 and F3 instead of five leaves") {
    const std::vector<LeafIndex> remaining{0, 1, 2, 3, 5};
    CHECK(minimal_cover(tree, remaining) == std::vector<NodeIndex>{f.a2, f.b2, f.f3});
  }
  SECTION("the fragment that broke off is its own cover") {
    const std::vector<LeafIndex> broken{4};
    CHECK(minimal_cover(tree, broken) == std::vector<NodeIndex>{f.e3});
  }
  SECTION("all leaves: the root") {
    const std::vector<LeafIndex> all{0, 1, 2, 3, 4, 5};
    CHECK(minimal_cover(tree, all) == std::vector<NodeIndex>{f.root});
  }
  SECTION("empty set: no node") {
    CHECK(minimal_cover(tree, std::span<const LeafIndex>{}).empty());
  }
  SECTION("order and duplicates do not matter") {
    const std::vector<LeafIndex> shuffled{5, 3, 0, 3, 2, 1, 5, 0};
    CHECK(minimal_cover(tree, shuffled) == std::vector<NodeIndex>{f.a2, f.b2, f.f3});
  }
  SECTION("ranges split by a gap are covered separately") {
    const std::vector<LeafIndex> gap{1, 2, 3, 5};  // A2 lost its first leaf
    CHECK(minimal_cover(tree, gap) == std::vector<NodeIndex>{3, f.b2, f.f3});
  }
  SECTION("an out-of-range leaf is refused") {
    const std::vector<LeafIndex> bad{0, 6};
    CHECK_THROWS_AS(minimal_cover(tree, bad), std::invalid_argument);
  }
}

TEST_CASE("minimal cover of a single-leaf tree", "[cover]") {
  MeshTree tree;
  add_node(tree, no_node);
  finish_tree(tree);
  const std::vector<LeafIndex> only{0};
  CHECK(minimal_cover(tree, only) == std::vector<NodeIndex>{0});
  CHECK(minimal_cover(tree, std::span<const LeafIndex>{}).empty());
  const std::vector<LeafIndex> bad{1};
  CHECK_THROWS_AS(minimal_cover(tree, bad), std::invalid_argument);
}

TEST_CASE("minimal cover equals the brute-force cover on random trees", "[cover][property]") {
  Random random(0xC0FE12);
  std::size_t trees = 0, subsets = 0;
  for (int t = 0; t < 300; ++t) {
    const MeshTree tree = random_tree(random, 1 + static_cast<std::uint32_t>(random.index(7)));
    ++trees;
    const std::size_t n = tree.leaf_count();
    for (int s = 0; s < 12; ++s) {
      // Densities from sparse to full, so both many small runs and long runs occur.
      const double density = s == 0 ? 1.0 : s == 1 ? 0.0 : random.uniform();
      std::vector<bool> in_set(n, false);
      std::vector<LeafIndex> leaves;
      for (LeafIndex l = 0; l < n; ++l) {
        if (random.uniform() < density) {
          in_set[l] = true;
          leaves.push_back(l);
          if (random.uniform() < 0.1) leaves.push_back(l);  // a duplicate
        }
      }
      for (std::size_t i = leaves.size(); i > 1; --i) std::swap(leaves[i - 1], leaves[random.index(i)]);

      const std::vector<NodeIndex> cover = minimal_cover(tree, leaves);
      INFO("tree " << t << " subset " << s << " leaves " << n);
      REQUIRE(cover == brute_force_cover(tree, in_set));
      check_cover_properties(tree, in_set, cover);
      ++subsets;
    }
  }
  CHECK(trees == 300);
  CHECK(subsets == 3600);
}

TEST_CASE("minimal cover on wide and deep trees uses every radix digit", "[cover]") {
  SECTION("a root with 70,000 leaf children: indices need three bytes") {
    MeshTree tree;
    const NodeIndex root = add_node(tree, no_node);
    for (int i = 0; i < 70000; ++i) add_node(tree, root);
    finish_tree(tree);
    std::vector<LeafIndex> all(tree.leaf_count());
    for (LeafIndex l = 0; l < all.size(); ++l) all[l] = static_cast<LeafIndex>(all.size() - 1 - l);
    CHECK(minimal_cover(tree, all) == std::vector<NodeIndex>{root});

    std::vector<LeafIndex> some{69999, 256, 65536, 257, 65535, 0};
    CHECK(minimal_cover(tree, some) == std::vector<NodeIndex>{1, 257, 258, 65536, 65537, 70000});
  }
  SECTION("a comb 2,000 levels deep") {
    // Each internal node has a leaf and the next internal node as children.
    MeshTree tree;
    NodeIndex spine = add_node(tree, no_node);
    for (int level = 0; level < 2000; ++level) {
      add_node(tree, spine);
      spine = add_node(tree, spine);
    }
    finish_tree(tree);
    const std::size_t n = tree.leaf_count();
    REQUIRE(n == 2001);
    std::vector<LeafIndex> all_but_first;
    for (LeafIndex l = 1; l < n; ++l) all_but_first.push_back(l);
    // Leaf 0 is the root's first child, so the rest is exactly the root's second child.
    CHECK(minimal_cover(tree, all_but_first) == std::vector<NodeIndex>{2});
    std::vector<bool> in_set(n, true);
    in_set[0] = false;
    check_cover_properties(tree, in_set, minimal_cover(tree, all_but_first));

    std::vector<LeafIndex> all_but_last(n - 1);
    for (LeafIndex l = 0; l + 1 < n; ++l) all_but_last[l] = l;
    std::vector<bool> in_set_last(n, true);
    in_set_last[n - 1] = false;
    const std::vector<NodeIndex> cover = minimal_cover(tree, all_but_last);
    CHECK(cover.size() == n - 1);  // no internal node fits: each holds the last leaf
    CHECK(cover == brute_force_cover(tree, in_set_last));
  }
}

TEST_CASE("minimal cover on a built tree", "[cover][build]") {
  TreeRecipe recipe;
  recipe.fragments = 24;
  recipe.strategy = Strategy::thesis;
  recipe.seed = 5;
  const MeshTree tree = build_mesh_tree(unit_cube(), recipe);
  CHECK(tree_problem(tree, true) == "");
  const std::size_t n = tree.leaf_count();
  REQUIRE(n >= 24);
  std::vector<LeafIndex> all(n);
  for (LeafIndex l = 0; l < n; ++l) all[l] = l;
  CHECK(minimal_cover(tree, all) == std::vector<NodeIndex>{0});
  // Every leaf broken off in turn: the rest is covered by the siblings along its
  // path to the root, and by nothing else.
  for (LeafIndex broken = 0; broken < n; ++broken) {
    std::vector<LeafIndex> rest;
    std::vector<bool> in_set(n, true);
    in_set[broken] = false;
    for (LeafIndex l = 0; l < n; ++l) {
      if (l != broken) rest.push_back(l);
    }
    const std::vector<NodeIndex> cover = minimal_cover(tree, rest);
    CHECK(cover == brute_force_cover(tree, in_set));
    std::size_t siblings = 0;
    for (NodeIndex node = tree.leaf_nodes[broken]; tree.nodes[node].parent != no_node; node = tree.nodes[node].parent) {
      siblings += tree.nodes[tree.nodes[node].parent].children.size() - 1;
    }
    CHECK(cover.size() == siblings);
  }
}
