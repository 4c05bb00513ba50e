#pragma once
// The Breakable Composite Rigid Body (BCRB) runtime on Bullet (seed thesis ch. 5,
// DESIGN.md "Bonds and the runtime"). A breakable object made from a mesh tree is
// one rigid body per cluster of bonded leaves; its collider is a compound of the
// precomputed convex hulls of the cluster's minimal cover. After every fixed step
// the contacts of breakable bodies are read; a contact whose applied impulse
// passes a threshold is an impact, and every bond of the hit cluster takes damage
// frailty * p / s^3. Bonds that break are removed, only the hit cluster's
// connectivity is recomputed, and each new component becomes a body of its own,
// moving as the part of the parent it was.
//
// Units are SI throughout: the mesh tree's coordinates are metres, masses kg,
// times s, impulses N s. The world's y axis points up (as glTF's does); the floor
// is the plane y = 0.
//
// Determinism: one thread, a fixed time step, and every list in a defined order,
// so the same calls give the same bodies, poses and events bit for bit.

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "shatter/meshtree/tree.hpp"
#include "shatter/runtime/mass.hpp"
#include "shatter/runtime/shapes.hpp"
#include "shatter/runtime/transform.hpp"

namespace shatter::runtime {

/// Index of a body in World::bodies(): every body that ever existed, in order of creation.
using BodyId = std::uint32_t;
/// Index of a breakable object, in order of World::add_breakable calls.
using ObjectId = std::uint32_t;
inline constexpr BodyId no_body = std::numeric_limits<BodyId>::max();
inline constexpr ObjectId no_object = std::numeric_limits<ObjectId>::max();

/// How bonds take damage (seed thesis ch. 5.2.1).
enum class BondMode : std::uint8_t {
  /// A bond breaks when one impact's damage reaches its hit points; lesser damage
  /// leaves no trace (stone).
  discrete,
  /// Each impact's damage is taken off the bond's hit points; it breaks when
  /// they reach zero or below, so hits add up (a coconut's shell).
  accumulating,
};

/// Where an impact's p comes from.
enum class ImpulseModel : std::uint8_t {
  /// The normal impulse Bullet's solver applied at the contact point this step.
  applied,
  /// The seed's eq. 5.1, p = m1 |v1| + m2 |v2| (the two bodies' masses and their
  /// speeds at the start of the step; a static body counts 0), shared among the
  /// contact points of the pair's manifold in proportion to their applied impulses.
  seed_momentum,
};

/// What happens after a cluster's bonds break.
enum class BreakMethod : std::uint8_t {
  /// This runtime: bonds kept for the body's life, connectivity searched only
  /// from the broken bonds' ends inside the hit cluster, covers of the small
  /// parts by minimal_cover and of the rest by taking the parts out of the
  /// parent's cover, compounds of the precomputed hull shapes.
  incremental,
  /// The seed's method, kept to measure against (ch. 5.2, 6.3): every damage
  /// pass visits every bond of the object; the fragment graph of the hit cluster
  /// is rebuilt from all bonds (one list per fragment, merged per surviving bond)
  /// and every part becomes a new graph with its edges copied out of all bonds;
  /// minimal meshes by a breadth-first walk of the tree per part (Listing 5.2);
  /// each cover node's collider built on demand (a convex hull of its mesh,
  /// computed then) and its mass properties integrated from its mesh then.
  /// The same parts, covers and poses as `incremental`; hull shapes and the last
  /// bits of the masses may differ.
  seed_rebuild,
};

std::string_view bond_mode_name(BondMode mode);           ///< "discrete", "accumulating"
std::string_view impulse_model_name(ImpulseModel model);  ///< "applied", "seed"
std::string_view break_method_name(BreakMethod method);   ///< "incremental", "seed"
/// The enum value with that name, or nullopt.
std::optional<BondMode> bond_mode_named(std::string_view name);
std::optional<ImpulseModel> impulse_model_named(std::string_view name);
std::optional<BreakMethod> break_method_named(std::string_view name);

/// The material and damage model of a breakable object.
struct BreakableParameters {
  double density = 1000;  ///< kg/m^3
  /// f in damage = f * p / s^3, m^3/(N s). With the defaults, an impact of
  /// 2,000 N s (a 50 kg sphere stopped from 40 m/s) breaks bonds within
  /// (f p / hit_points)^(1/3) = 0.46 m of the contact.
  double frailty = 5e-5;
  /// An impact is a contact point whose applied normal impulse in one step
  /// exceeds impact_speed times the hit cluster's mass, in m/s (N s per kg): the
  /// speed the impulse alone would give the cluster. A threshold per kilogram
  /// keeps resting contact, about m g dt per step (0.08 m/s of speed at 1/120 s,
  /// whatever the mass), below it for objects of any size, where a fixed
  /// impulse would let a heavy object break under its own weight.
  double impact_speed = 0.5;
  /// Damage a bond takes before it breaks (damage units: f p / s^3 is
  /// dimensionless with the units above). Every bond starts with the same.
  double hit_points = 1;
  BondMode mode = BondMode::discrete;
  ImpulseModel impulse = ImpulseModel::applied;
  /// s is never taken below this, m: a contact on a bond's centroid would
  /// otherwise do infinite damage. Damage is at most f p / min_distance^3.
  double min_distance = 0.05;
  double friction = 0.6;     ///< Bullet's friction coefficient of every body of the object
  double restitution = 0.0;  ///< Bullet's restitution of every body of the object
  BreakMethod method = BreakMethod::incremental;
};

/// Throws std::invalid_argument naming the first parameter that is not finite or
/// out of range (density, frailty, hit_points, min_distance > 0; impact_speed,
/// friction, restitution >= 0).
void check_parameters(const BreakableParameters& parameters);

/// The world's set-up.
struct WorldOptions {
  double time_step = 1.0 / 120;  ///< s, every step; > 0
  Vec3 gravity{0, -9.81, 0};     ///< m/s^2
  int solver_iterations = 10;    ///< Bullet's sequential impulse iterations, >= 1
  bool floor = true;             ///< a static plane y = 0
  double floor_friction = 0.6;
  /// Let Bullet put resting bodies to sleep (they cost nothing then and report
  /// no contacts; a sleeping body's stale contacts are never read as impacts).
  bool sleeping = true;
};

enum class BodyKind : std::uint8_t { cluster, sphere };

/// Everything known about a body that exists or existed.
struct BodyRecord {
  BodyKind kind = BodyKind::cluster;
  ObjectId object = no_object;  ///< cluster: its object
  BodyId parent = no_body;      ///< cluster: the cluster it broke off (no_body for the first ones)
  /// cluster: the minimal cover of its leaves (increasing first leaf); the leaves
  /// are the union of these nodes' leaf ranges (World::leaves_of).
  std::vector<NodeIndex> cover;
  std::uint32_t leaf_count = 0;  ///< cluster: its number of leaves
  /// Mass properties; for a cluster `frame` places the body frame in tree
  /// coordinates; for a sphere, centroid 0 and identity frame.
  RigidMass mass;
  double radius = 0;             ///< sphere only, m
  std::uint64_t birth_step = 0;  ///< exists in the states after steps >= birth_step
  /// Gone from the states after steps >= death_step (max: still alive).
  std::uint64_t death_step = std::numeric_limits<std::uint64_t>::max();
  /// The tree-to-world transform (cluster) or pose (sphere) at its death.
  RigidTransform death_transform;

  bool alive_at(std::uint64_t step) const { return birth_step <= step && step < death_step; }
};

/// A body's motion now.
struct BodyState {
  /// The body frame in world coordinates: translation = centre of mass.
  RigidTransform pose;
  Vec3 linear_velocity;   ///< of the centre of mass, m/s
  Vec3 angular_velocity;  ///< rad/s, world axes
  bool awake = true;
};

/// One contact point that passed the impact threshold.
struct Impact {
  BodyId body = no_body;       ///< the breakable body hit
  BodyId other = no_body;      ///< what hit it; no_body for the floor
  Vec3 world_point;            ///< on the hit body's surface
  Vec3 tree_point;             ///< the same point in tree coordinates
  double applied_impulse = 0;  ///< Bullet's normal impulse at the point, N s
  double impulse = 0;          ///< p, by the object's ImpulseModel, N s
};

/// A hit cluster that lost bonds in one step (or one apply_impact call).
struct BreakEvent {
  std::uint64_t step = 0;
  double time = 0;  ///< s
  ObjectId object = no_object;
  BodyId body = no_body;    ///< the hit cluster
  std::size_t impacts = 0;  ///< impacts on it that step
  std::size_t bonds_broken = 0;
  /// The bodies its parts became, ordered by their smallest leaf; empty when it
  /// lost bonds but stayed connected (it then lives on as it was).
  std::vector<BodyId> created;
};

struct StepReport {
  std::uint64_t step = 0;          ///< steps done, this one included
  double time = 0;                 ///< s, step * time_step
  std::vector<Impact> impacts;     ///< in Bullet's manifold order
  std::vector<BreakEvent> breaks;  ///< ordered by hit body
};

/// Linear momentum (kg m/s) and angular momentum about the world origin
/// (kg m^2/s) of every live dynamic body.
struct Momentum {
  Vec3 linear;
  Vec3 angular;
};

/// A body's Bullet compound, read back from Bullet.
struct CompoundView {
  std::vector<NodeIndex> nodes;  ///< the tree node of each child shape, in child order
  /// Every child is the shape BreakableShapes made for its node at load (no hull
  /// built since); false under BreakMethod::seed_rebuild after a break.
  bool uses_precomputed_shapes = false;
};

/// The simulation: Bullet's discrete dynamics world, the floor, spheres and
/// breakable objects. Not copyable; one thread at a time.
class World {
 public:
  /// Throws std::invalid_argument for a time step or iteration count out of range.
  explicit World(const WorldOptions& options = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  /// Places a breakable object: tree coordinates map to world coordinates by
  /// `placement`; one body per initial cluster of `shapes` (one for a connected
  /// bond graph, whose compound is the root's hull alone); every point of the
  /// object moves with velocity `linear_velocity` + `angular_velocity` x (x - c),
  /// c the object's centre of mass. Throws std::invalid_argument for bad
  /// parameters (check_parameters) or a null `shapes`. The shapes are shared,
  /// never copied.
  ObjectId add_breakable(std::shared_ptr<const BreakableShapes> shapes, const RigidTransform& placement,
                         const BreakableParameters& parameters, Vec3 linear_velocity = {}, Vec3 angular_velocity = {});

  /// Adds a solid sphere (a projectile): radius m > 0, mass kg > 0, centre and
  /// velocity in world coordinates; continuous collision detection is on for it,
  /// so a fast sphere does not pass through thin fragments. Throws
  /// std::invalid_argument for a radius or mass out of range.
  BodyId add_sphere(double radius, double mass, Vec3 position, Vec3 velocity);

  /// advance() then resolve_damage().
  StepReport step();
  /// One fixed Bullet step (stepSimulation with no sub-stepping): gravity,
  /// collisions, the contact solver, integration. Records each body's start
  /// velocity for ImpulseModel::seed_momentum.
  void advance();
  /// Reads the contact manifolds of the last step, turns contact points of awake
  /// breakable bodies whose applied impulse exceeds their object's impact_speed
  /// times their mass into impacts, damages the hit clusters' bonds, and splits every hit cluster whose
  /// surviving bonds no longer connect it (BreakMethod). Calling it twice for one
  /// step finds the same contacts again; step() calls it once.
  StepReport resolve_damage();

  /// Applies one impact of impulse `impulse` (N s, > 0) at `world_point` to the
  /// cluster body `body`, as resolve_damage would for a contact there (no threshold
  /// test), then splits the body if it came apart. Returns the event (bonds_broken
  /// 0 and nothing created when no bond broke). Throws std::invalid_argument when
  /// `body` is not a live cluster or the impulse is not positive and finite.
  BreakEvent apply_impact(BodyId body, Vec3 world_point, double impulse);

  const WorldOptions& options() const;
  std::uint64_t step_count() const;
  double time() const;  ///< step_count() * time_step, s

  /// Every body that ever existed, indexed by BodyId.
  std::span<const BodyRecord> bodies() const;
  bool alive(BodyId body) const;
  /// The live bodies, increasing.
  std::vector<BodyId> live_bodies() const;
  /// Motion of a live body. Throws std::invalid_argument for a dead or unknown one.
  BodyState state(BodyId body) const;
  /// A cluster's tree-to-world transform (a point of the tree is at
  /// apply(object_transform, point)); a sphere's pose. For a dead body its
  /// transform at death. Throws std::invalid_argument for an unknown body.
  RigidTransform object_transform(BodyId body) const;
  /// A cluster's leaves, increasing (expanded from its cover). Empty for a sphere.
  std::vector<LeafIndex> leaves_of(BodyId body) const;
  /// The live body holding `leaf` of `object`. Throws std::invalid_argument for
  /// an unknown object or leaf.
  BodyId body_of_leaf(ObjectId object, LeafIndex leaf) const;
  /// The compound Bullet holds for a live cluster. Throws std::invalid_argument
  /// for a dead body or a sphere.
  CompoundView compound_of(BodyId body) const;

  std::size_t object_count() const;
  const BreakableShapes& shapes_of(ObjectId object) const;
  const BreakableParameters& parameters_of(ObjectId object) const;
  /// Per bond of the object's tree: 1 while it holds, 0 once broken.
  std::span<const std::uint8_t> bonds_alive(ObjectId object) const;
  /// Per bond: hit points left (accumulating); the starting hit points otherwise.
  std::span<const double> bond_hit_points(ObjectId object) const;

  /// Momentum of all live dynamic bodies, from their masses, inertia and velocities.
  Momentum momentum() const;
  /// Kinetic energy of all live dynamic bodies, J.
  double kinetic_energy() const;
  /// Total mass of the live bodies of `object`, kg.
  double object_mass(ObjectId object) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace shatter::runtime
