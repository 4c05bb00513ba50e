#pragma once
// A run recorded as an animated glTF 2.0 binary: one glTF node per body that ever
// existed, moved by translation and rotation channels, shown from its birth to its
// death by a scale channel (stepped between 0 and 1: glTF 2.0 has no visibility
// channel, and a zero scale is what Blender and three.js both play as hidden).
// A cluster's node holds one child per cover node with that tree node's mesh,
// exactly as `shatter export --format glb` writes it (exterior and interior
// materials), in tree coordinates: the node's transform is the cluster's
// tree-to-world transform. Spheres are unit spheres scaled to their radius; the
// floor is a thin slab under y = 0.

#include <cstdint>
#include <string>
#include <vector>

#include "shatter/runtime/world.hpp"

namespace shatter::runtime {

class Recording {
 public:
  /// Keeps every `every_steps`-th state (steps 0, k, 2k, ...), plus the state in
  /// which each body first appears and its pose at death, so no body is missed.
  /// Throws std::invalid_argument for 0.
  explicit Recording(std::uint32_t every_steps = 1);

  /// Records the current state of `world` (call it once before the first step
  /// and after every step). Precondition: always the same world, its steps
  /// increasing between calls; throws std::invalid_argument for a step already
  /// recorded or earlier.
  void capture(const World& world);

  /// The GLB bytes of everything captured, with a floor slab reaching
  /// `floor_half_size` m (> 0) from the origin along x and z. Deterministic: the
  /// same captures give the same bytes. Throws std::invalid_argument for a bad
  /// floor size or when nothing was captured, std::runtime_error when tinygltf
  /// cannot decode or encode (never for a valid tree), std::length_error past
  /// GLB's 4 GiB.
  std::string encode_glb(const World& world, double floor_half_size) const;

 private:
  struct Sample {
    std::uint64_t step = 0;
    RigidTransform pose;  ///< tree-to-world (cluster) or pose (sphere)
  };
  std::uint32_t every_steps_;
  bool captured_ = false;
  std::uint64_t last_step_ = 0;
  std::vector<std::vector<Sample>> samples_;  ///< per body
};

}  // namespace shatter::runtime
