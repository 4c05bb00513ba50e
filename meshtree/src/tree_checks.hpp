#pragma once
// What the .shatter reader (file.cpp) shares with the tree checker
// (validate_tree.cpp): the enum ranges this version knows, the fields the reader
// derives instead of storing, and the filling of the caches. Private to the
// library, never installed.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "shatter/kernel/implicit.hpp"
#include "shatter/meshtree/recipe.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/validate_tree.hpp"

namespace shatter::detail {

// The largest enum values this version knows; a new Strategy or KernelKind must
// be added here (and to the layout comment in file.hpp) to be stored.
inline constexpr std::uint8_t last_strategy = static_cast<std::uint8_t>(Strategy::axis);
inline constexpr std::uint8_t last_kernel = static_cast<std::uint8_t>(KernelKind::plane);
inline constexpr std::uint8_t last_point_kind = static_cast<std::uint8_t>(PointKind::three_planes);

/// `value` as "0x" and `digits` upper-case hexadecimal digits (the low ones).
std::string hex(std::uint64_t value, int digits);

/// The leaves of a tree in node order: what MeshTree::leaf_nodes must be.
std::vector<NodeIndex> leaves_in_order(const std::vector<MeshTreeNode>& nodes);

/// Computes the caches a .shatter file does not store (see
/// TreeValidationOptions::caches) and stores them in `tree`.
/// Precondition: `tree` passed validate_tree without caches.
/// Returns the first vertex whose definition is degenerate (its planes meet in no
/// single point), a TreePart::solid defect; the caches are then incomplete.
std::optional<TreeDefect> fill_caches(MeshTree& tree);

}  // namespace shatter::detail
