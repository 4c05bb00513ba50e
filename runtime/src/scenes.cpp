#include "shatter/runtime/scenes.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "shatter/kernel/enum_names.hpp"

namespace shatter::runtime {

std::string_view scene_name(SceneKind kind) {
  switch (kind) {
    case SceneKind::drop:
      return "drop";
    case SceneKind::shoot:
      return "shoot";
    case SceneKind::wall:
      return "wall";
  }
  return "unknown";
}

std::optional<SceneKind> scene_named(std::string_view name) {
  return enum_named(name, {SceneKind::drop, SceneKind::shoot, SceneKind::wall}, &scene_name);
}

namespace {

struct Box {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -lo;
  Vec3 extent() const { return hi - lo; }
};

// The bounding box of the object turned by `rotation`: the root's hull bounds
// every fragment.
Box rotated_box(const MeshTree& tree, const Quaternion& rotation) {
  Box box;
  for (const Vec3& p : tree.hull_of(0).positions) {
    const Vec3 q = rotate(rotation, p);
    box.lo = {std::min(box.lo.x, q.x), std::min(box.lo.y, q.y), std::min(box.lo.z, q.z)};
    box.hi = {std::max(box.hi.x, q.x), std::max(box.hi.y, q.y), std::max(box.hi.z, q.z)};
  }
  return box;
}

// The rotation that lays the object's bounding-box axes out as a brick in a wall:
// thinnest along x, middle along y, largest along z, kept proper by turning the
// thinnest axis around when the permutation alone would mirror.
Quaternion brick_rotation(const MeshTree& tree) {
  const Vec3 extent = rotated_box(tree, {}).extent();
  std::array<int, 3> axes{0, 1, 2};
  std::stable_sort(axes.begin(), axes.end(), [&](int a, int b) { return extent[a] < extent[b]; });
  Matrix3 rotation{};  // column j is where tree axis j goes
  for (int world_axis = 0; world_axis < 3; ++world_axis) {
    rotation[static_cast<std::size_t>(3 * world_axis + axes[static_cast<std::size_t>(world_axis)])] = 1;
  }
  const double determinant = rotation[0] * (rotation[4] * rotation[8] - rotation[5] * rotation[7]) -
                             rotation[1] * (rotation[3] * rotation[8] - rotation[5] * rotation[6]) +
                             rotation[2] * (rotation[3] * rotation[7] - rotation[4] * rotation[6]);
  if (determinant < 0) {
    for (std::size_t c = 0; c < 3; ++c) rotation[c] = -rotation[c];
  }
  return quaternion_of(rotation);
}

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(what);
}

// Checks every option that is set; unset ones are resolved by scene_sizes.
void check_options(const SceneOptions& o) {
  check_parameters(o.parameters);
  require(!o.height || (std::isfinite(*o.height) && *o.height >= 0),
          "the drop height must be finite and not negative (m)");
  require(std::isfinite(o.tilt_degrees), "the tilt must be finite (degrees)");
  require(!o.projectile_mass || (std::isfinite(*o.projectile_mass) && *o.projectile_mass > 0),
          "the projectile mass must be positive (kg)");
  require(!o.projectile_speed || (std::isfinite(*o.projectile_speed) && *o.projectile_speed >= 0),
          "the projectile speed must be finite and not negative (m/s)");
  require(!o.projectile_radius || (std::isfinite(*o.projectile_radius) && *o.projectile_radius >= 0),
          "the projectile radius must be finite and not negative (m; 0 or unset picks one)");
  require(!o.frailty || (std::isfinite(*o.frailty) && *o.frailty > 0),
          "frailty must be positive and finite (m^3/(N s))");
  require(o.wall_rows >= 1 && o.wall_columns >= 1, "a wall needs at least one row and one column");
}

double footprint_of(const Box& box) {
  return std::max({std::abs(box.lo.x), std::abs(box.hi.x), std::abs(box.lo.z), std::abs(box.hi.z)});
}

}  // namespace

SceneSizes scene_sizes(const MeshTree& tree, const SceneOptions& options) {
  check_options(options);
  if (tree.nodes.empty()) throw std::invalid_argument("scene_sizes: the tree has no nodes");
  const Vec3 extent = rotated_box(tree, {}).extent();
  SceneSizes sizes;
  sizes.object_size = std::max({extent.x, extent.y, extent.z});
  sizes.object_mass = options.parameters.density * std::abs(tree.nodes[0].mass.volume);
  sizes.height = options.height.value_or(scene_defaults::height_in_sizes * sizes.object_size);
  sizes.projectile_mass =
      options.projectile_mass.value_or(scene_defaults::mass_in_object_masses * sizes.object_mass);
  sizes.projectile_speed =
      options.projectile_speed.value_or(scene_defaults::speed_in_sqrt_g_size *
                                        std::sqrt(scene_defaults::gravity * sizes.object_size));
  sizes.projectile_radius = options.projectile_radius.value_or(0) > 0
                                ? *options.projectile_radius
                                : scene_defaults::radius_in_sizes * sizes.object_size;
  // The impulse the default blow gives the object, about M sqrt(g L), breaks
  // bonds within break_radius_in_sizes object sizes.
  const double radius = scene_defaults::break_radius_in_sizes * sizes.object_size;
  sizes.frailty = options.frailty.value_or(
      options.parameters.hit_points * radius * radius * radius /
      (sizes.object_mass * std::sqrt(scene_defaults::gravity * sizes.object_size)));
  // A flat or empty object gives no mass or size to scale by: refuse rather than
  // hand Bullet a massless sphere.
  if (!(sizes.projectile_mass > 0)) {
    throw std::invalid_argument("the object has no volume, so the projectile mass must be given (kg)");
  }
  if (!(sizes.projectile_radius > 0)) {
    throw std::invalid_argument("the object has no extent, so the projectile radius must be given (m)");
  }
  if (!(sizes.frailty > 0 && std::isfinite(sizes.frailty))) {
    throw std::invalid_argument("the object has no volume or no extent, so the frailty must be given (m^3/(N s))");
  }
  // Bullet's solver multiplies masses, lengths and speeds together (inertia
  // m L^2, energies m v^2, and their products with inverses), so a scene whose
  // magnitudes are finite can still overflow there: `simulate --density 1e300`
  // printed a kinetic energy of NaN at every step (found by a sweep, 2026-12-07;
  // 1e150 ran clean). Masses, lengths and speeds are held to 1e60 and energies
  // to 1e120, where such products stay far inside the doubles' range.
  const auto within = [](double value, double limit, const char* what, const char* unit) {
    if (std::isfinite(value) && std::fabs(value) <= limit) return;
    char text[200];
    std::snprintf(text, sizeof text, "the scene's %s would be %.3g %s, beyond the %.0e %s a simulation keeps to", what,
                  value, unit, limit, unit);
    throw std::invalid_argument(text);
  };
  using scene_limits::largest_energy;
  using scene_limits::largest_magnitude;
  within(sizes.object_mass, largest_magnitude, "object mass", "kg");
  within(sizes.object_size, largest_magnitude, "object size", "m");
  within(sizes.height, largest_magnitude, "drop height", "m");
  within(sizes.projectile_mass, largest_magnitude, "projectile mass", "kg");
  within(sizes.projectile_radius, largest_magnitude, "projectile radius", "m");
  within(sizes.projectile_speed, largest_magnitude, "projectile speed", "m/s");
  within(0.5 * sizes.projectile_mass * sizes.projectile_speed * sizes.projectile_speed, largest_energy,
         "projectile's kinetic energy", "J");
  within(sizes.object_mass * scene_defaults::gravity * (sizes.height + sizes.object_size), largest_energy,
         "object's potential energy", "J");
  return sizes;
}

Scene set_up_scene(World& world, const std::shared_ptr<const BreakableShapes>& shapes, const SceneOptions& options) {
  if (!shapes) throw std::invalid_argument("set_up_scene: no shapes");
  const MeshTree& tree = shapes->tree();
  const SceneSizes sizes = scene_sizes(tree, options);
  const double margin = shapes->options().collision_margin;
  const Vec3 centroid = tree.nodes[0].mass.centroid;
  Scene scene;
  scene.sizes = sizes;
  BreakableParameters parameters = options.parameters;
  parameters.frailty = sizes.frailty;

  if (options.kind == SceneKind::drop) {
    const Quaternion rotation = axis_angle({1, 0, 1}, options.tilt_degrees * std::numbers::pi / 180);
    const Box box = rotated_box(tree, rotation);
    const Vec3 turned = rotate(rotation, centroid);
    const RigidTransform placement{{-turned.x, sizes.height + margin - box.lo.y, -turned.z}, rotation};
    scene.objects.push_back(world.add_breakable(shapes, placement, parameters));
    scene.footprint = footprint_of({box.lo + placement.translation, box.hi + placement.translation});
    return scene;
  }

  const double radius = sizes.projectile_radius;
  Vec3 target;
  double front = 0;  // the smallest x of the objects
  if (options.kind == SceneKind::shoot) {
    const Box box = rotated_box(tree, {});
    const RigidTransform placement{{-centroid.x, margin - box.lo.y, -centroid.z}, {}};
    scene.objects.push_back(world.add_breakable(shapes, placement, parameters));
    target = apply(placement, centroid);
    front = box.lo.x + placement.translation.x;
    scene.footprint = footprint_of({box.lo + placement.translation, box.hi + placement.translation});
  } else {
    const Quaternion rotation = brick_rotation(tree);
    const Box box = rotated_box(tree, rotation);
    const Vec3 size = box.extent();
    const double gap = 2 * margin;  // bricks touch only through their margins
    const double width = static_cast<double>(options.wall_columns) * (size.z + gap) - gap;
    const std::uint32_t target_row = (options.wall_rows - 1) / 2, target_column = (options.wall_columns - 1) / 2;
    for (std::uint32_t row = 0; row < options.wall_rows; ++row) {
      for (std::uint32_t column = 0; column < options.wall_columns; ++column) {
        const Vec3 corner{-size.x / 2, margin + static_cast<double>(row) * (size.y + gap),
                          -width / 2 + static_cast<double>(column) * (size.z + gap)};
        const RigidTransform placement{corner - box.lo, rotation};
        scene.objects.push_back(world.add_breakable(shapes, placement, parameters));
        if (row == target_row && column == target_column) target = apply(placement, centroid);
      }
    }
    front = -size.x / 2;
    const double height = static_cast<double>(options.wall_rows) * (size.y + gap);
    scene.footprint = std::max({size.x / 2, width / 2, height});
  }
  // The sphere starts with its surface a diameter in front of the object and
  // flies straight at the target point.
  const Vec3 start{front - 3 * radius, target.y, target.z};
  scene.projectile = world.add_sphere(radius, sizes.projectile_mass, start, Vec3{sizes.projectile_speed, 0, 0});
  scene.footprint = std::max(scene.footprint, std::abs(start.x) + radius);
  return scene;
}

}  // namespace shatter::runtime
