#pragma once
// The demonstration scenes of `shatter simulate`: a breakable object dropped on the
// floor, shot by a sphere, or stacked as a wall of bricks and shot. Each sets up a
// World from one BreakableShapes (shared by every copy of the object).

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "shatter/runtime/world.hpp"

namespace shatter::runtime {

enum class SceneKind : std::uint8_t {
  /// The object, turned by `tilt_degrees` about the axis (1, 0, 1), falls from
  /// `height` above the floor.
  drop,
  /// The object rests on the floor; a sphere flies at its centre of mass along +x.
  shoot,
  /// Copies of the object stand as a wall of bricks, `wall_rows` high and
  /// `wall_columns` wide, each turned so its thinnest extent faces the shot, its
  /// largest runs along the wall (z) and the middle one is its height; a sphere
  /// flies along +x at the middle brick of the bottom half.
  wall,
};

std::string_view scene_name(SceneKind kind);  ///< "drop", "shoot", "wall"
std::optional<SceneKind> scene_named(std::string_view name);

/// A scene's geometry; the material and damage model are `parameters`.
/// Lengths in m, masses in kg, speeds in m/s.
struct SceneOptions {
  SceneKind kind = SceneKind::drop;
  BreakableParameters parameters;
  double height = 1.0;           ///< drop: gap between the object's lowest point and the floor, >= 0
  double tilt_degrees = 20;      ///< drop: turn about (1, 0, 1), so it lands on an edge
  double projectile_mass = 50;   ///< shoot, wall: > 0
  double projectile_speed = 40;  ///< shoot, wall: >= 0
  /// shoot, wall: > 0; 0 picks 15% of the object's largest bounding-box extent.
  double projectile_radius = 0;
  std::uint32_t wall_rows = 2;     ///< wall: >= 1
  std::uint32_t wall_columns = 3;  ///< wall: >= 1
};

/// What set_up_scene placed.
struct Scene {
  std::vector<ObjectId> objects;  ///< every breakable, in placing order
  BodyId projectile = no_body;    ///< shoot, wall
  /// Extent of the scene's start on the floor: |x| and |z| of every object's
  /// bounding box and the projectile, m (for drawing a floor).
  double footprint = 0;
};

/// Places the scene's objects (and projectile) in `world`, which should have a
/// floor and gravity along -y. Objects rest exactly on the floor where they stand
/// on it (their hulls' lowest point lifted by the collision margin, which Bullet
/// adds around every hull), and stand a margin apart in a wall.
/// Throws std::invalid_argument for an option out of range (naming it) or
/// parameters check_parameters refuses; nothing is added then.
Scene set_up_scene(World& world, const std::shared_ptr<const BreakableShapes>& shapes, const SceneOptions& options);

}  // namespace shatter::runtime
