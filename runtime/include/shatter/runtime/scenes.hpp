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

/// The relative defaults: what an option left unset comes to, in terms of the
/// object's size L (the largest extent of its bounding box, as it lies in the
/// tree) and its mass M (density times the root's volume). Lengths scale with L
/// and speeds with sqrt(g L), as a fall's do, so the pieces slide and roll about
/// as many object sizes whatever the size. The frailty scales too: the default
/// blow gives the object about half the sphere's speed, an impulse of about
/// M sqrt(g L), and the frailty is the one at which that impulse breaks bonds
/// within break_radius_in_sizes object sizes of the contact, so a light object
/// and a heavy one break alike. A faster sphere would break more but throw the
/// pieces farther (README, Runtime).
namespace scene_defaults {
/// Standard gravity, m/s^2, which the speeds are scaled by.
inline constexpr double gravity = 9.81;
/// drop: the fall, in object sizes (1 m for an object of 0.5 m).
inline constexpr double height_in_sizes = 2;
/// shoot, wall: the sphere's radius, in object sizes.
inline constexpr double radius_in_sizes = 0.15;
/// shoot, wall: the sphere's mass, in object masses (of one brick in a wall).
inline constexpr double mass_in_object_masses = 1;
/// shoot, wall: the sphere's speed in units of sqrt(g L): 2 is the speed of a
/// fall from twice the object's size, 6.3 m/s for an object of 1 m.
inline constexpr double speed_in_sqrt_g_size = 2;
/// The frailty f = hit_points (c L)^3 / (M sqrt(g L)), c this: the damage radius
/// (f p / hit_points)^(1/3) of an impulse p = M sqrt(g L) is c L. Chosen so the
/// default shot breaks a typical object into many pieces (README, Runtime).
inline constexpr double break_radius_in_sizes = 0.45;
}  // namespace scene_defaults

namespace scene_limits {
/// The largest magnitude scene_sizes lets a scene's mass, length or speed (SI
/// units) reach, and its energies: Bullet's solver multiplies them together,
/// which must stay far inside the doubles' range.
inline constexpr double largest_magnitude = 1e60;
inline constexpr double largest_energy = 1e120;
}  // namespace scene_limits

/// A scene's geometry; the material and damage model are `parameters`.
/// Lengths in m, masses in kg, speeds in m/s. An option left unset takes its
/// relative default (scene_defaults, resolved by scene_sizes); a value that is
/// set is used as it is, whatever the object.
struct SceneOptions {
  SceneKind kind = SceneKind::drop;
  /// The material and damage model; its frailty is not used: the objects get the
  /// resolved `frailty` below.
  BreakableParameters parameters;
  /// m^3/(N s), > 0; unset: scene_defaults::break_radius_in_sizes's rule.
  std::optional<double> frailty;
  /// drop: gap between the object's lowest point and the floor, >= 0; unset:
  /// height_in_sizes object sizes.
  std::optional<double> height;
  double tilt_degrees = 20;  ///< drop: turn about (1, 0, 1), so it lands on an edge
  /// shoot, wall: > 0; unset: mass_in_object_masses times the object's mass.
  std::optional<double> projectile_mass;
  /// shoot, wall: >= 0; unset: speed_in_sqrt_g_size times sqrt(gravity * size).
  std::optional<double> projectile_speed;
  /// shoot, wall: > 0; unset (or 0, as before it could be unset): radius_in_sizes
  /// object sizes.
  std::optional<double> projectile_radius;
  std::uint32_t wall_rows = 2;     ///< wall: >= 1
  std::uint32_t wall_columns = 3;  ///< wall: >= 1
};

/// A scene's options resolved for one object: the object's size and mass, and
/// every length, mass and speed set_up_scene uses (m, kg, m/s).
struct SceneSizes {
  double object_size = 0;  ///< the largest extent of the object's bounding box in the tree, m
  double object_mass = 0;  ///< density times the root's volume, kg
  double height = 0;
  double projectile_mass = 0;
  double projectile_speed = 0;
  double projectile_radius = 0;
  double frailty = 0;  ///< m^3/(N s), the objects' (BreakableParameters::frailty)
};

/// The values `options` comes to for an object cut as `tree`: each set option as
/// it is, each unset one its relative default. Throws std::invalid_argument for
/// an option out of range (naming it), parameters check_parameters refuses, or
/// a mass, length, speed or energy of the scene beyond scene_limits (naming
/// it), as set_up_scene does.
SceneSizes scene_sizes(const MeshTree& tree, const SceneOptions& options);

/// What set_up_scene placed.
struct Scene {
  std::vector<ObjectId> objects;  ///< every breakable, in placing order
  BodyId projectile = no_body;    ///< shoot, wall
  SceneSizes sizes;               ///< the options as resolved for the object (scene_sizes)
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
