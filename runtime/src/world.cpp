#include "shatter/runtime/world.hpp"

#include <LinearMath/btConvexHullComputer.h>
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <string>

#include "shapes_impl.hpp"
#include "shatter/kernel/enum_names.hpp"
#include "shatter/kernel/union_find.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/cover.hpp"

namespace shatter::runtime {

// --- names ------------------------------------------------------------------------

std::string_view bond_mode_name(BondMode mode) { return mode == BondMode::discrete ? "discrete" : "accumulating"; }
std::string_view impulse_model_name(ImpulseModel model) { return model == ImpulseModel::applied ? "applied" : "seed"; }
std::string_view break_method_name(BreakMethod method) {
  return method == BreakMethod::incremental ? "incremental" : "seed";
}

std::optional<BondMode> bond_mode_named(std::string_view name) {
  return enum_named(name, {BondMode::discrete, BondMode::accumulating}, &bond_mode_name);
}
std::optional<ImpulseModel> impulse_model_named(std::string_view name) {
  return enum_named(name, {ImpulseModel::applied, ImpulseModel::seed_momentum}, &impulse_model_name);
}
std::optional<BreakMethod> break_method_named(std::string_view name) {
  return enum_named(name, {BreakMethod::incremental, BreakMethod::seed_rebuild}, &break_method_name);
}

void check_parameters(const BreakableParameters& p) {
  const auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(what);
  };
  const auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  const auto non_negative = [](double x) { return std::isfinite(x) && x >= 0; };
  require(positive(p.density), "density must be positive and finite (kg/m^3)");
  require(positive(p.frailty), "frailty must be positive and finite (m^3/(N s))");
  require(non_negative(p.impact_speed), "the impact speed must be finite and not negative (m/s)");
  require(positive(p.hit_points), "hit points must be positive and finite");
  require(positive(p.min_distance), "the minimum distance must be positive and finite (m)");
  require(non_negative(p.friction), "friction must be finite and not negative");
  require(non_negative(p.restitution), "restitution must be finite and not negative");
}

// --- conversions --------------------------------------------------------------------

namespace {

btVector3 to_bt(Vec3 v) { return {v.x, v.y, v.z}; }
Vec3 from_bt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
btTransform to_bt(const RigidTransform& t) {
  return btTransform(btQuaternion(t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w), to_bt(t.translation));
}
RigidTransform from_bt(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  return {from_bt(t.getOrigin()), {q.w(), q.x(), q.y(), q.z()}};
}

constexpr std::uint32_t none = UINT32_MAX;

// The world inertia tensor R diag(moments) R^T applied to w.
Vec3 world_inertia_times(const Quaternion& rotation, Vec3 moments, Vec3 w) {
  const Vec3 local = rotate(conjugate(rotation), w);
  return rotate(rotation, {local.x * moments.x, local.y * moments.y, local.z * moments.z});
}

// A new body's collider and mass: the compound's children (one per cover node)
// and, for the seed's method, the hull shapes it built for them.
struct ClusterShape {
  RigidMass mass;
  std::vector<btCollisionShape*> children;
  std::vector<std::unique_ptr<btConvexHullShape>> built;
};

// The leaves of `cover` (disjoint nodes), increasing when the cover is ordered.
std::vector<LeafIndex> leaves_of_cover(const MeshTree& tree, std::span<const NodeIndex> cover) {
  std::vector<LeafIndex> leaves;
  for (NodeIndex node : cover) {
    const MeshTreeNode& n = tree.nodes[node];
    for (std::uint32_t i = 0; i < n.leaf_count; ++i) leaves.push_back(n.first_leaf + i);
  }
  return leaves;
}

// The minimal cover of (leaves of `cover`) minus `removed` (increasing, all inside
// the cover): a cover node that loses no leaf stays, one that loses leaves is
// replaced by its children's covers. Every kept node's parent loses a leaf, so the
// result is minimal. O(|removed| depth + |cover|).
void cover_without(const MeshTree& tree, NodeIndex node, std::span<const LeafIndex> removed,
                   std::vector<NodeIndex>& out) {
  const MeshTreeNode& n = tree.nodes[node];
  if (removed.empty()) {
    out.push_back(node);
    return;
  }
  if (removed.size() == n.leaf_count) return;  // removed lies inside the node: all of it is gone
  for (NodeIndex child : n.children) {
    const MeshTreeNode& c = tree.nodes[child];
    const auto begin = std::lower_bound(removed.begin(), removed.end(), c.first_leaf);
    const auto end = std::lower_bound(begin, removed.end(), c.first_leaf + c.leaf_count);
    cover_without(tree, child, std::span<const LeafIndex>(begin, end), out);
  }
}

std::vector<NodeIndex> cover_without(const MeshTree& tree, std::span<const NodeIndex> cover,
                                     std::span<const LeafIndex> removed) {
  std::vector<NodeIndex> out;
  for (NodeIndex node : cover) {
    const MeshTreeNode& n = tree.nodes[node];
    const auto begin = std::lower_bound(removed.begin(), removed.end(), n.first_leaf);
    const auto end = std::lower_bound(begin, removed.end(), n.first_leaf + n.leaf_count);
    cover_without(tree, node, std::span<const LeafIndex>(begin, end), out);
  }
  return out;
}

}  // namespace

// --- state --------------------------------------------------------------------------

namespace {

struct LiveBody {
  std::unique_ptr<btRigidBody> rigid;
  std::unique_ptr<btCollisionShape> shape;                      ///< compound or sphere
  std::vector<std::unique_ptr<btConvexHullShape>> built_hulls;  ///< seed's method only
  std::vector<BondIndex> seed_graph_edges;                      ///< seed's method only: its rebuilt graph
  std::uint32_t label = none;                                   ///< cluster: its label in the object
  Vec3 start_velocity;                                          ///< at the start of the last step
};

struct ObjectState {
  std::shared_ptr<const BreakableShapes> shapes;
  BreakableParameters parameters;
  std::vector<std::uint8_t> bond_alive;
  std::vector<double> hit_points;
  /// Leaves of one live cluster share a label. After a split the largest part
  /// keeps its parent's label, so only the broken-off leaves are relabelled.
  std::vector<std::uint32_t> leaf_label;
  std::vector<BodyId> label_body;
  /// Scratch of the connectivity search: the search that reached each leaf,
  /// `none` between searches, and the leaf it reached after this one.
  std::vector<std::uint32_t> search_of_leaf;
  std::vector<LeafIndex> next_in_search;

  const BreakableShapes::Impl& data() const { return shapes->impl(); }
  const MeshTree& tree() const { return shapes->tree(); }
};

// A hit cluster's motion as it comes apart, which its parts inherit.
struct ParentMotion {
  RigidTransform tree_to_world;
  Vec3 velocity, angular, centre;
};

// How a hit cluster comes apart: parts found whole, and at most one "rest", the
// part no search finished, which is the cluster without the others.
struct Parts {
  std::vector<std::vector<LeafIndex>> found;  ///< each increasing
  bool has_rest = false;
};

}  // namespace

struct World::Impl {
  WorldOptions options;
  std::unique_ptr<btDefaultCollisionConfiguration> configuration;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::unique_ptr<btStaticPlaneShape> floor_shape;
  std::unique_ptr<btRigidBody> floor_body;

  std::vector<BodyRecord> records;
  std::vector<LiveBody> live;  ///< parallel to records; empty `rigid` once dead
  std::vector<ObjectState> objects;
  std::uint64_t steps = 0;

  explicit Impl(const WorldOptions& world_options);
  ~Impl();

  double now() const { return static_cast<double>(steps) * options.time_step; }
  const LiveBody& live_cluster(BodyId body) const;
  RigidTransform tree_to_world(BodyId body) const;

  BodyId add_body(BodyRecord record, LiveBody body, const RigidTransform& pose, Vec3 velocity, Vec3 angular,
                  double friction, double restitution);
  BodyId add_cluster(ObjectId object, std::vector<NodeIndex> cover, std::uint32_t leaf_count, std::uint32_t label,
                     ClusterShape shape, const RigidTransform& tree_to_world, Vec3 velocity, Vec3 angular,
                     Vec3 velocity_origin, BodyId parent);
  void retire(BodyId body);
  ParentMotion retire_parent(BodyId body);
  // Room for `more` bodies, so a break's new bodies move the records at most
  // once; growth stays geometric, so many small breaks cost amortised O(1) each.
  void reserve_bodies(std::size_t more) {
    const std::size_t needed = records.size() + more;
    if (records.capacity() < needed) records.reserve(std::max(needed, 2 * records.capacity()));
    if (live.capacity() < needed) live.reserve(std::max(needed, 2 * live.capacity()));
  }

  ClusterShape precomputed_shape(const ObjectState& object, std::span<const NodeIndex> cover) const;
  ClusterShape built_shape(const ObjectState& object, std::span<const NodeIndex> cover) const;

  void damage(ObjectState& object, std::uint32_t label, Vec3 tree_point, double impulse,
              std::vector<BondIndex>& broken);
  Parts find_parts(ObjectState& object, std::span<const BondIndex> broken);
  std::vector<BodyId> split_incremental(BodyId body, std::span<const BondIndex> broken);
  std::vector<BodyId> split_seed(BodyId body);
  BreakEvent break_cluster(BodyId body, std::span<const Impact> impacts);
};

World::Impl::Impl(const WorldOptions& world_options) : options(world_options) {
  if (!(options.time_step > 0) || !std::isfinite(options.time_step)) {
    throw std::invalid_argument("the time step must be positive and finite (s)");
  }
  if (options.solver_iterations < 1) throw std::invalid_argument("solver iterations must be at least 1");
  if (!is_finite(options.gravity)) throw std::invalid_argument("gravity must be finite (m/s^2)");
  if (!(options.floor_friction >= 0) || !std::isfinite(options.floor_friction)) {
    throw std::invalid_argument("floor friction must be finite and not negative");
  }
  configuration = std::make_unique<btDefaultCollisionConfiguration>();
  dispatcher = std::make_unique<btCollisionDispatcher>(configuration.get());
  broadphase = std::make_unique<btDbvtBroadphase>();
  // A new body's overlapping pairs are found in the next step's broadphase pass,
  // with every other moved proxy, rather than one query per body as it is added:
  // a break adds its bodies at the cost of tree insertions.
  broadphase->m_deferedcollide = true;
  solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  world =
      std::make_unique<btDiscreteDynamicsWorld>(dispatcher.get(), broadphase.get(), solver.get(), configuration.get());
  world->setGravity(to_bt(options.gravity));
  btContactSolverInfo& info = world->getSolverInfo();
  info.m_numIterations = options.solver_iterations;
  // Penetration is always resolved by split impulse, outside the velocity
  // solve, so the applied impulses the damage model reads are contact
  // impulses only, never a push apart of fragments that touched (margins).
  info.m_splitImpulse = 1;
  info.m_splitImpulsePenetrationThreshold = 0;
  if (options.floor) {
    floor_shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), 0);
    btRigidBody::btRigidBodyConstructionInfo floor_info(0, nullptr, floor_shape.get());
    floor_info.m_friction = options.floor_friction;
    floor_body = std::make_unique<btRigidBody>(floor_info);
    floor_body->setUserIndex(-1);
    world->addRigidBody(floor_body.get());
  }
}

World::Impl::~Impl() {
  // Bodies leave the world before it goes, so Bullet frees their contacts.
  for (LiveBody& body : live) {
    if (body.rigid) world->removeRigidBody(body.rigid.get());
  }
  if (floor_body) world->removeRigidBody(floor_body.get());
  // Compounds go before the objects whose shared hull shapes they point to.
  live.clear();
  world.reset();
}

const LiveBody& World::Impl::live_cluster(BodyId body) const {
  if (body >= records.size() || !live[body].rigid || records[body].kind != BodyKind::cluster) {
    throw std::invalid_argument("body " + std::to_string(body) + " is not a live cluster");
  }
  return live[body];
}

RigidTransform World::Impl::tree_to_world(BodyId body) const {
  const BodyRecord& record = records[body];
  if (!live[body].rigid) return record.death_transform;
  const RigidTransform pose = from_bt(live[body].rigid->getCenterOfMassTransform());
  if (record.kind == BodyKind::sphere) return pose;
  return compose(pose, inverse(record.mass.frame));
}

BodyId World::Impl::add_body(BodyRecord record, LiveBody body, const RigidTransform& pose, Vec3 velocity, Vec3 angular,
                             double friction, double restitution) {
  const auto id = static_cast<BodyId>(records.size());
  btRigidBody::btRigidBodyConstructionInfo info(record.mass.mass, nullptr, body.shape.get(),
                                                to_bt(record.mass.principal_moments));
  info.m_startWorldTransform = to_bt(pose);
  info.m_friction = friction;
  info.m_restitution = restitution;
  body.rigid = std::make_unique<btRigidBody>(info);
  body.rigid->setUserIndex(static_cast<int>(id));
  body.rigid->setLinearVelocity(to_bt(velocity));
  body.rigid->setAngularVelocity(to_bt(angular));
  if (!options.sleeping) body.rigid->setActivationState(DISABLE_DEACTIVATION);
  body.start_velocity = velocity;
  record.birth_step = steps;
  world->addRigidBody(body.rigid.get());
  records.push_back(std::move(record));
  live.push_back(std::move(body));
  return id;
}

BodyId World::Impl::add_cluster(ObjectId object, std::vector<NodeIndex> cover, std::uint32_t leaf_count,
                                std::uint32_t label, ClusterShape shape, const RigidTransform& tree_to_world,
                                Vec3 velocity, Vec3 angular, Vec3 velocity_origin, BodyId parent) {
  // The compound's frame is the body frame (centroid, principal axes), as
  // Bullet requires; each hull shape sits at its node's centroid in it.
  const RigidTransform body_from_tree = inverse(shape.mass.frame);
  const MeshTree& tree = objects[object].tree();
  const bool many_children = cover.size() > 4;  // a child tree pays off only beyond a few children
  auto compound = std::make_unique<btCompoundShape>(many_children, static_cast<int>(cover.size()));
  const btTransform body_from_tree_bt = to_bt(body_from_tree);
  for (std::size_t i = 0; i < cover.size(); ++i) {
    // Every child turns as the body frame does; only its offset differs.
    const btVector3 offset = body_from_tree_bt(to_bt(tree.nodes[cover[i]].mass.centroid));
    compound->addChildShape(btTransform(body_from_tree_bt.getBasis(), offset), shape.children[i]);
  }
  BodyRecord record;
  record.kind = BodyKind::cluster;
  record.object = object;
  record.parent = parent;
  record.cover = std::move(cover);
  record.leaf_count = leaf_count;
  record.mass = shape.mass;
  LiveBody body;
  body.shape = std::move(compound);
  body.built_hulls = std::move(shape.built);
  body.label = label;
  const RigidTransform pose = compose(tree_to_world, shape.mass.frame);
  // The part moves as it did inside its parent: v + w x r, w kept.
  const Vec3 part_velocity = velocity + cross(angular, pose.translation - velocity_origin);
  const BreakableParameters& parameters = objects[object].parameters;
  const BodyId id = add_body(std::move(record), std::move(body), pose, part_velocity, angular, parameters.friction,
                             parameters.restitution);
  ObjectState& state = objects[object];
  if (label >= state.label_body.size()) state.label_body.resize(label + 1, no_body);
  state.label_body[label] = id;
  return id;
}

void World::Impl::retire(BodyId body) {
  records[body].death_transform = tree_to_world(body);
  records[body].death_step = steps;
  world->removeRigidBody(live[body].rigid.get());
  live[body] = LiveBody{};
}

// Retires a cluster that came apart, returning the motion its parts take over.
ParentMotion World::Impl::retire_parent(BodyId body) {
  const btRigidBody& rigid = *live[body].rigid;
  const ParentMotion motion{tree_to_world(body), from_bt(rigid.getLinearVelocity()),
                            from_bt(rigid.getAngularVelocity()), from_bt(rigid.getCenterOfMassPosition())};
  retire(body);
  return motion;
}

ClusterShape World::Impl::precomputed_shape(const ObjectState& object, std::span<const NodeIndex> cover) const {
  ClusterShape shape;
  const double density = object.parameters.density;
  if (cover.size() == 1) {
    // One node: its unit-density mass properties, computed at load, scaled.
    shape.mass = object.data().node_masses[cover[0]];
    shape.mass.mass *= density;
    for (double& value : shape.mass.inertia) value *= density;
    shape.mass.principal_moments = shape.mass.principal_moments * density;
  } else {
    shape.mass = cluster_mass(object.tree(), cover, density);
  }
  shape.children.reserve(cover.size());
  for (NodeIndex node : cover) shape.children.push_back(object.data().node_shapes[node].get());
  return shape;
}

// The seed's colliders: each cover node's convex hull computed now from its mesh,
// and its mass properties integrated now, as the seed's engine did when a
// fragment's collider was set up (ch. 5.2.3-5.2.4, 6.3).
ClusterShape World::Impl::built_shape(const ObjectState& object, std::span<const NodeIndex> cover) const {
  ClusterShape shape;
  const MeshTree& tree = object.tree();
  std::vector<MassProperties> parts;
  for (NodeIndex node : cover) {
    const Mesh& mesh = tree.nodes[node].mesh;
    const Vec3 centre = tree.nodes[node].mass.centroid;
    btConvexHullComputer hull;
    hull.compute(&mesh.positions[0].x, static_cast<int>(sizeof(Vec3)), static_cast<int>(mesh.positions.size()), 0, 0);
    auto built = std::make_unique<btConvexHullShape>();
    for (int i = 0; i < hull.vertices.size(); ++i) {
      built->addPoint(hull.vertices[i] - to_bt(centre), false);
    }
    built->recalcLocalAabb();
    built->setMargin(object.shapes->options().collision_margin);
    built->setUserIndex(static_cast<int>(node));
    shape.children.push_back(built.get());
    shape.built.push_back(std::move(built));
    parts.push_back(mass_properties(mesh));
  }
  shape.mass = combine_masses(parts, object.parameters.density);
  return shape;
}

// --- damage -------------------------------------------------------------------------

// Damage f p / max(s, min)^3 to every surviving bond of the cluster `label`;
// appends the bonds that break to `broken`. A discrete impact can only break bonds
// within its breaking radius (f p / hit_points)^(1/3), so the incremental method
// asks the bond search tree for those (the radius is widened by 1e-9 so rounding
// never hides one; every candidate is judged by the formula itself). Accumulating
// bonds all lose hit points, and the seed's method visits every bond, so those
// walk the object's bond array.
void World::Impl::damage(ObjectState& object, std::uint32_t label, Vec3 tree_point, double impulse,
                         std::vector<BondIndex>& broken) {
  const BreakableParameters& p = object.parameters;
  const BreakableShapes::Impl& data = object.data();
  const double strength = p.frailty * impulse;
  const double min_cube = p.min_distance * p.min_distance * p.min_distance;
  // `distance2` is the squared distance from the contact to the bond's centroid.
  const auto hit = [&](BondIndex b, double distance2) {
    if (!object.bond_alive[b] || object.leaf_label[data.bond_first[b]] != label) return;
    const double s = std::sqrt(distance2);
    const double amount = s > p.min_distance ? strength / (s * s * s) : strength / min_cube;
    if (p.mode == BondMode::discrete) {
      if (amount < object.hit_points[b]) return;
    } else {
      object.hit_points[b] -= amount;
      if (object.hit_points[b] > 0) return;
    }
    object.bond_alive[b] = 0;
    broken.push_back(b);
  };
  const std::size_t first_broken = broken.size();
  if (p.mode == BondMode::discrete && p.method == BreakMethod::incremental) {
    const double radius = std::cbrt(strength / p.hit_points);
    if (!(radius * (1 + 1e-9) >= p.min_distance)) return;  // even a bond at the contact takes less than its hit points
    data.bond_search.for_each_within(tree_point, radius * (1 + 1e-9), hit);
    std::sort(broken.begin() + static_cast<std::ptrdiff_t>(first_broken), broken.end());
  } else {
    for (BondIndex b = 0; b < object.bond_alive.size(); ++b) {
      const Vec3 d = data.bond_centroids[b] - tree_point;
      hit(b, dot(d, d));
    }
  }
}

// --- connectivity -------------------------------------------------------------------

// The parts of cluster `body` after `broken` bonds broke, found by searching only
// from the broken bonds' ends: one breadth-first search per end, all advanced one
// leaf at a time in turn over surviving bonds; searches that meet merge. A group
// of searches that runs out of leaves is a whole part. As soon as at most one
// group is still running, that group is the rest of the cluster and is not walked
// further, so the cost follows the size of the parts that break off, not of the
// cluster. Every part holds an end of a broken bond (the cluster was connected),
// so no part is missed.
Parts World::Impl::find_parts(ObjectState& object, std::span<const BondIndex> broken) {
  const BreakableShapes::Impl& data = object.data();
  const MeshTree& tree = object.tree();
  // Each search's leaves form a list threaded through object.next_in_search (no
  // allocation per search): `first` .. `last` in the order reached, `next` the
  // first not yet expanded (none when the search has run out).
  struct Search {
    LeafIndex first = 0, last = 0, next = 0;
    bool running() const { return next != none; }
  };
  std::vector<Search> searches;
  const auto reach = [&](std::uint32_t s, LeafIndex leaf) {
    object.search_of_leaf[leaf] = s;
    object.next_in_search[leaf] = none;
    Search& search = searches[s];
    object.next_in_search[search.last] = leaf;
    search.last = leaf;
    if (search.next == none) search.next = leaf;
  };
  for (BondIndex b : broken) {
    for (LeafIndex end : {tree.bonds[b].first, tree.bonds[b].second}) {
      if (object.search_of_leaf[end] != none) continue;
      object.search_of_leaf[end] = static_cast<std::uint32_t>(searches.size());
      object.next_in_search[end] = none;
      searches.push_back({end, end, end});
    }
  }
  UnionFind groups(searches.size());
  std::vector<std::uint32_t> running_in_group(searches.size(), 1);  // valid at group representatives
  std::size_t running_groups = searches.size();

  while (running_groups > 1) {
    for (std::uint32_t s = 0; s < searches.size() && running_groups > 1; ++s) {
      if (!searches[s].running()) continue;
      const LeafIndex leaf = searches[s].next;
      searches[s].next = object.next_in_search[leaf];
      for (std::uint32_t k = data.adjacency_begin[leaf]; k < data.adjacency_begin[leaf + 1]; ++k) {
        if (!object.bond_alive[data.adjacent_bond[k]]) continue;
        const LeafIndex other = data.adjacent_leaf[k];
        const std::uint32_t owner = object.search_of_leaf[other];
        if (owner == none) {
          reach(s, other);
          continue;
        }
        const std::uint32_t a = groups.find(owner), b = groups.find(s);
        if (a == b) continue;
        groups.unite(a, b);
        const std::uint32_t merged = groups.find(a);
        running_in_group[merged] = running_in_group[a] + running_in_group[b];
        --running_groups;  // both were running: a search only meets running ones
      }
      if (!searches[s].running()) {
        const std::uint32_t group = groups.find(s);
        if (--running_in_group[group] == 0) --running_groups;
      }
    }
  }

  Parts parts;
  std::vector<std::uint32_t> part_of_group(searches.size(), none);
  for (std::uint32_t s = 0; s < searches.size(); ++s) {
    const std::uint32_t group = groups.find(s);
    const bool rest = running_in_group[group] > 0;
    if (rest) {
      parts.has_rest = true;
    } else if (part_of_group[group] == none) {
      part_of_group[group] = static_cast<std::uint32_t>(parts.found.size());
      parts.found.emplace_back();
    }
    for (LeafIndex leaf = searches[s].first; leaf != none; leaf = object.next_in_search[leaf]) {
      object.search_of_leaf[leaf] = none;
      if (!rest) parts.found[part_of_group[group]].push_back(leaf);
    }
  }
  for (std::vector<LeafIndex>& part : parts.found) std::sort(part.begin(), part.end());
  return parts;
}

std::vector<BodyId> World::Impl::split_incremental(BodyId body, std::span<const BondIndex> broken) {
  const ObjectId object_id = records[body].object;
  ObjectState& object = objects[object_id];
  Parts parts = find_parts(object, broken);
  if (parts.found.size() + (parts.has_rest ? 1 : 0) <= 1) return {};

  const MeshTree& tree = object.tree();
  const std::uint32_t parent_label = live[body].label;
  // The part that keeps the parent's label (and so needs no relabelling): the
  // rest when there is one, else the largest part found.
  std::size_t keeper = parts.found.size();
  if (!parts.has_rest) {
    keeper = 0;
    for (std::size_t i = 1; i < parts.found.size(); ++i) {
      if (parts.found[i].size() > parts.found[keeper].size()) keeper = i;
    }
  }
  struct NewPart {
    std::vector<NodeIndex> cover;
    std::uint32_t leaf_count = 0;
    std::uint32_t label = none;
  };
  std::vector<NewPart> made;
  for (std::size_t i = 0; i < parts.found.size(); ++i) {
    NewPart part;
    // A lone fragment is its own leaf node; larger parts take the general cover.
    part.cover = parts.found[i].size() == 1 ? std::vector<NodeIndex>{tree.leaf_nodes[parts.found[i][0]]}
                                            : minimal_cover(tree, parts.found[i]);
    part.leaf_count = static_cast<std::uint32_t>(parts.found[i].size());
    if (i == keeper) {
      part.label = parent_label;
    } else {
      part.label = static_cast<std::uint32_t>(object.label_body.size());
      object.label_body.push_back(no_body);
      for (LeafIndex leaf : parts.found[i]) object.leaf_label[leaf] = part.label;
    }
    made.push_back(std::move(part));
  }
  if (parts.has_rest) {
    std::vector<LeafIndex> removed;
    for (const std::vector<LeafIndex>& part : parts.found) removed.insert(removed.end(), part.begin(), part.end());
    std::sort(removed.begin(), removed.end());
    NewPart rest;
    rest.cover = cover_without(tree, records[body].cover, removed);
    rest.leaf_count = records[body].leaf_count - static_cast<std::uint32_t>(removed.size());
    rest.label = parent_label;
    made.push_back(std::move(rest));
  }
  // Bodies are made in order of their smallest leaf, whatever found them.
  std::sort(made.begin(), made.end(), [&](const NewPart& a, const NewPart& b) {
    return tree.nodes[a.cover.front()].first_leaf < tree.nodes[b.cover.front()].first_leaf;
  });

  const ParentMotion parent = retire_parent(body);
  reserve_bodies(made.size());
  std::vector<BodyId> created;
  for (NewPart& part : made) {
    ClusterShape shape = precomputed_shape(object, part.cover);
    created.push_back(add_cluster(object_id, std::move(part.cover), part.leaf_count, part.label, std::move(shape),
                                  parent.tree_to_world, parent.velocity, parent.angular, parent.centre, body));
  }
  return created;
}

// The seed's method (ch. 5.2.1-5.2.2, Listings 5.1 and 5.2), on the same data:
// the hit cluster's fragment graph is rebuilt from scratch from all bonds, every
// part becomes a new graph whose edges are copied out of all bonds again, its
// minimal meshes are found by a breadth-first walk from the root, and its
// colliders and masses are made on demand (built_shape).
std::vector<BodyId> World::Impl::split_seed(BodyId body) {
  const ObjectId object_id = records[body].object;
  ObjectState& object = objects[object_id];
  const MeshTree& tree = object.tree();
  const std::vector<LeafIndex> leaves = leaves_of_cover(tree, records[body].cover);

  // Listing 5.1: one list per fragment, merged along every surviving bond.
  std::vector<std::vector<LeafIndex>> lists(leaves.size());
  std::vector<std::uint32_t> list_of(tree.leaf_count(), none);
  for (std::uint32_t i = 0; i < leaves.size(); ++i) {
    lists[i].push_back(leaves[i]);
    list_of[leaves[i]] = i;
  }
  for (BondIndex b = 0; b < tree.bonds.size(); ++b) {
    const Bond& bond = tree.bonds[b];
    if (!object.bond_alive[b] || list_of[bond.first] == none) continue;
    std::uint32_t keep = list_of[bond.first], gone = list_of[bond.second];
    if (keep == gone) continue;
    if (lists[keep].size() < lists[gone].size()) std::swap(keep, gone);
    for (LeafIndex leaf : lists[gone]) list_of[leaf] = keep;
    lists[keep].insert(lists[keep].end(), lists[gone].begin(), lists[gone].end());
    lists[gone].clear();
  }
  std::vector<std::vector<LeafIndex>> parts;
  for (std::vector<LeafIndex>& list : lists) {
    if (list.empty()) continue;
    std::sort(list.begin(), list.end());
    parts.push_back(std::move(list));
  }
  if (parts.size() <= 1) return {};
  std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.front() < b.front(); });
  std::vector<std::uint32_t> part_of(tree.leaf_count(), none);
  for (std::uint32_t k = 0; k < parts.size(); ++k) {
    for (LeafIndex leaf : parts[k]) part_of[leaf] = k;
  }

  const ParentMotion parent = retire_parent(body);
  reserve_bodies(parts.size());
  std::vector<BodyId> created;
  for (std::uint32_t k = 0; k < parts.size(); ++k) {
    // A new graph for the part: its edges copied out of all bonds.
    std::vector<BondIndex> edges;
    for (BondIndex b = 0; b < tree.bonds.size(); ++b) {
      if (object.bond_alive[b] && part_of[tree.bonds[b].first] == k) edges.push_back(b);
    }
    // Listing 5.2: breadth first from the root; a node whose leaves all lie in
    // the part is taken whole, any other is opened.
    std::vector<NodeIndex> cover;
    std::vector<NodeIndex> queue{0};
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const MeshTreeNode& node = tree.nodes[queue[head]];
      bool whole = true;
      for (std::uint32_t i = 0; i < node.leaf_count && whole; ++i) whole = part_of[node.first_leaf + i] == k;
      if (whole) {
        cover.push_back(queue[head]);
      } else {
        queue.insert(queue.end(), node.children.begin(), node.children.end());
      }
    }
    std::sort(cover.begin(), cover.end(),
              [&](NodeIndex a, NodeIndex b) { return tree.nodes[a].first_leaf < tree.nodes[b].first_leaf; });
    const auto label = static_cast<std::uint32_t>(object.label_body.size());
    object.label_body.push_back(no_body);
    for (LeafIndex leaf : parts[k]) object.leaf_label[leaf] = label;
    ClusterShape shape = built_shape(object, cover);
    const BodyId id = add_cluster(object_id, std::move(cover), static_cast<std::uint32_t>(parts[k].size()), label,
                                  std::move(shape), parent.tree_to_world, parent.velocity, parent.angular,
                                  parent.centre, body);
    live[id].seed_graph_edges = std::move(edges);
    created.push_back(id);
  }
  return created;
}

BreakEvent World::Impl::break_cluster(BodyId body, std::span<const Impact> impacts) {
  const ObjectId object_id = records[body].object;
  ObjectState& object = objects[object_id];
  BreakEvent event;
  event.step = steps;
  event.time = now();
  event.object = object_id;
  event.body = body;
  event.impacts = impacts.size();
  std::vector<BondIndex> broken;
  for (std::size_t i = 0; i < impacts.size(); ++i) {
    damage(object, live[body].label, impacts[i].tree_point, impacts[i].impulse, broken);
  }
  event.bonds_broken = broken.size();
  if (broken.empty()) return event;
  std::sort(broken.begin(), broken.end());
  event.created =
      object.parameters.method == BreakMethod::incremental ? split_incremental(body, broken) : split_seed(body);
  return event;
}

// --- World --------------------------------------------------------------------------

World::World(const WorldOptions& options) : impl_(std::make_unique<Impl>(options)) {}
World::~World() = default;

ObjectId World::add_breakable(std::shared_ptr<const BreakableShapes> shapes, const RigidTransform& placement,
                              const BreakableParameters& parameters, Vec3 linear_velocity, Vec3 angular_velocity) {
  if (!shapes) throw std::invalid_argument("add_breakable: no shapes");
  check_parameters(parameters);
  Impl& w = *impl_;
  const auto object_id = static_cast<ObjectId>(w.objects.size());
  ObjectState object;
  const MeshTree& tree = shapes->tree();
  const BreakableShapes::Impl& data = shapes->impl();
  object.shapes = std::move(shapes);
  object.parameters = parameters;
  object.bond_alive.assign(tree.bonds.size(), 1);
  object.hit_points.assign(tree.bonds.size(), parameters.hit_points);
  object.leaf_label = data.initial_cluster_of_leaf;
  object.search_of_leaf.assign(tree.leaf_count(), none);
  object.next_in_search.assign(tree.leaf_count(), none);
  w.objects.push_back(std::move(object));
  const Vec3 centre = apply(placement, tree.nodes[0].mass.centroid);
  for (std::uint32_t k = 0; k < data.initial_clusters.size(); ++k) {
    ClusterShape shape = w.precomputed_shape(w.objects[object_id], data.initial_covers[k]);
    w.add_cluster(object_id, data.initial_covers[k], static_cast<std::uint32_t>(data.initial_clusters[k].leaves.size()),
                  k, std::move(shape), placement, linear_velocity, angular_velocity, centre, no_body);
  }
  return object_id;
}

BodyId World::add_sphere(double radius, double mass, Vec3 position, Vec3 velocity) {
  if (!(radius > 0) || !std::isfinite(radius)) throw std::invalid_argument("a sphere's radius must be positive (m)");
  if (!(mass > 0) || !std::isfinite(mass)) throw std::invalid_argument("a sphere's mass must be positive (kg)");
  if (!is_finite(position) || !is_finite(velocity)) throw std::invalid_argument("a sphere's motion must be finite");
  BodyRecord record;
  record.kind = BodyKind::sphere;
  record.radius = radius;
  record.mass.mass = mass;
  const double moment = 0.4 * mass * radius * radius;
  record.mass.principal_moments = {moment, moment, moment};
  record.mass.inertia = {moment, 0, 0, 0, moment, 0, 0, 0, moment};
  LiveBody body;
  body.shape = std::make_unique<btSphereShape>(radius);
  const BodyId id = impl_->add_body(std::move(record), std::move(body), {position, {}}, velocity, {}, 0.6, 0.0);
  btRigidBody& rigid = *impl_->live[id].rigid;
  // Continuous collision: a fast sphere is swept each step, so it cannot tunnel
  // through a fragment thinner than its step's travel.
  rigid.setCcdMotionThreshold(radius * 0.5);
  rigid.setCcdSweptSphereRadius(radius * 0.9);
  return id;
}

StepReport World::step() {
  advance();
  return resolve_damage();
}

void World::advance() {
  Impl& w = *impl_;
  for (LiveBody& body : w.live) {
    if (body.rigid) body.start_velocity = from_bt(body.rigid->getLinearVelocity());
  }
  // No sub-stepping and no interpolation: exactly one internal step of the fixed size.
  w.world->stepSimulation(w.options.time_step, 0, w.options.time_step);
  ++w.steps;
}

StepReport World::resolve_damage() {
  Impl& w = *impl_;
  StepReport report;
  report.step = w.steps;
  report.time = w.now();
  const auto awake = [](const btCollisionObject* o) {
    return !o->isStaticOrKinematicObject() && o->getActivationState() != ISLAND_SLEEPING;
  };
  const int manifolds = w.dispatcher->getNumManifolds();
  for (int i = 0; i < manifolds; ++i) {
    const btPersistentManifold* manifold = w.dispatcher->getManifoldByIndexInternal(i);
    const btCollisionObject* bodies[2] = {manifold->getBody0(), manifold->getBody1()};
    // A sleeping island was not solved this step: its impulses are old news.
    if (!awake(bodies[0]) && !awake(bodies[1])) continue;
    const int contacts = manifold->getNumContacts();
    double total = 0;
    for (int c = 0; c < contacts; ++c) total += std::max<double>(0, manifold->getContactPoint(c).getAppliedImpulse());
    for (int side = 0; side < 2; ++side) {
      const int index = bodies[side]->getUserIndex();
      if (index < 0) continue;
      const auto body = static_cast<BodyId>(index);
      if (w.records[body].kind != BodyKind::cluster) continue;
      const BreakableParameters& parameters = w.objects[w.records[body].object].parameters;
      const double threshold = parameters.impact_speed * w.records[body].mass.mass;
      const int other_index = bodies[1 - side]->getUserIndex();
      const BodyId other = other_index < 0 ? no_body : static_cast<BodyId>(other_index);
      for (int c = 0; c < contacts; ++c) {
        const btManifoldPoint& point = manifold->getContactPoint(c);
        const double applied = point.getAppliedImpulse();
        if (!(applied > threshold)) continue;
        Impact impact;
        impact.body = body;
        impact.other = other;
        impact.world_point = from_bt(side == 0 ? point.getPositionWorldOnA() : point.getPositionWorldOnB());
        impact.tree_point = apply(inverse(w.tree_to_world(body)), impact.world_point);
        impact.applied_impulse = applied;
        if (parameters.impulse == ImpulseModel::applied) {
          impact.impulse = applied;
        } else {
          // Eq. 5.1 for the pair, shared among its contact points by their impulses.
          double momentum = w.records[body].mass.mass * norm(w.live[body].start_velocity);
          if (other != no_body) momentum += w.records[other].mass.mass * norm(w.live[other].start_velocity);
          impact.impulse = momentum * applied / total;
        }
        report.impacts.push_back(impact);
      }
    }
  }
  // Each hit cluster takes all its impacts, then comes apart once.
  std::vector<std::size_t> order(report.impacts.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return report.impacts[a].body < report.impacts[b].body; });
  for (std::size_t i = 0; i < order.size();) {
    const BodyId body = report.impacts[order[i]].body;
    std::vector<Impact> hits;
    for (; i < order.size() && report.impacts[order[i]].body == body; ++i) hits.push_back(report.impacts[order[i]]);
    BreakEvent event = w.break_cluster(body, hits);
    if (event.bonds_broken > 0) report.breaks.push_back(std::move(event));
  }
  return report;
}

BreakEvent World::apply_impact(BodyId body, Vec3 world_point, double impulse) {
  Impl& w = *impl_;
  w.live_cluster(body);
  if (!(impulse > 0) || !std::isfinite(impulse) || !is_finite(world_point)) {
    throw std::invalid_argument("apply_impact: the impulse must be positive and finite, the point finite");
  }
  Impact impact;
  impact.body = body;
  impact.world_point = world_point;
  impact.tree_point = apply(inverse(w.tree_to_world(body)), world_point);
  impact.applied_impulse = impulse;
  impact.impulse = impulse;
  return w.break_cluster(body, std::span<const Impact>(&impact, 1));
}

const WorldOptions& World::options() const { return impl_->options; }
std::uint64_t World::step_count() const { return impl_->steps; }
double World::time() const { return impl_->now(); }
std::span<const BodyRecord> World::bodies() const { return impl_->records; }

bool World::alive(BodyId body) const { return body < impl_->live.size() && impl_->live[body].rigid != nullptr; }

std::vector<BodyId> World::live_bodies() const {
  std::vector<BodyId> bodies;
  for (BodyId b = 0; b < impl_->live.size(); ++b) {
    if (impl_->live[b].rigid) bodies.push_back(b);
  }
  return bodies;
}

BodyState World::state(BodyId body) const {
  if (!alive(body)) throw std::invalid_argument("body " + std::to_string(body) + " is not alive");
  const btRigidBody& rigid = *impl_->live[body].rigid;
  return {from_bt(rigid.getCenterOfMassTransform()), from_bt(rigid.getLinearVelocity()),
          from_bt(rigid.getAngularVelocity()), rigid.getActivationState() != ISLAND_SLEEPING};
}

RigidTransform World::object_transform(BodyId body) const {
  if (body >= impl_->records.size()) throw std::invalid_argument("no body " + std::to_string(body));
  return impl_->tree_to_world(body);
}

std::vector<LeafIndex> World::leaves_of(BodyId body) const {
  if (body >= impl_->records.size()) throw std::invalid_argument("no body " + std::to_string(body));
  const BodyRecord& record = impl_->records[body];
  if (record.kind != BodyKind::cluster) return {};
  return leaves_of_cover(impl_->objects[record.object].tree(), record.cover);
}

BodyId World::body_of_leaf(ObjectId object, LeafIndex leaf) const {
  if (object >= impl_->objects.size()) throw std::invalid_argument("no object " + std::to_string(object));
  const ObjectState& state = impl_->objects[object];
  if (leaf >= state.leaf_label.size()) throw std::invalid_argument("no leaf " + std::to_string(leaf));
  return state.label_body[state.leaf_label[leaf]];
}

CompoundView World::compound_of(BodyId body) const {
  const LiveBody& live = impl_->live_cluster(body);
  const auto& compound = static_cast<const btCompoundShape&>(*live.shape);
  const BreakableShapes::Impl& data = impl_->objects[impl_->records[body].object].data();
  CompoundView view;
  view.uses_precomputed_shapes = true;
  for (int i = 0; i < compound.getNumChildShapes(); ++i) {
    const btCollisionShape* child = compound.getChildShape(i);
    const auto node = static_cast<NodeIndex>(child->getUserIndex());
    view.nodes.push_back(node);
    if (node >= data.node_shapes.size() || child != data.node_shapes[node].get()) view.uses_precomputed_shapes = false;
  }
  return view;
}

std::size_t World::object_count() const { return impl_->objects.size(); }

namespace {
void require_object(std::size_t count, ObjectId object) {
  if (object >= count) throw std::invalid_argument("no object " + std::to_string(object));
}
}  // namespace

const BreakableShapes& World::shapes_of(ObjectId object) const {
  require_object(impl_->objects.size(), object);
  return *impl_->objects[object].shapes;
}
const BreakableParameters& World::parameters_of(ObjectId object) const {
  require_object(impl_->objects.size(), object);
  return impl_->objects[object].parameters;
}
std::span<const std::uint8_t> World::bonds_alive(ObjectId object) const {
  require_object(impl_->objects.size(), object);
  return impl_->objects[object].bond_alive;
}
std::span<const double> World::bond_hit_points(ObjectId object) const {
  require_object(impl_->objects.size(), object);
  return impl_->objects[object].hit_points;
}

Momentum World::momentum() const {
  Momentum total;
  for (BodyId b = 0; b < impl_->live.size(); ++b) {
    if (!impl_->live[b].rigid) continue;
    const BodyState s = state(b);
    const RigidMass& mass = impl_->records[b].mass;
    const Vec3 p = s.linear_velocity * mass.mass;
    total.linear = total.linear + p;
    total.angular = total.angular + cross(s.pose.translation, p) +
                    world_inertia_times(s.pose.rotation, mass.principal_moments, s.angular_velocity);
  }
  return total;
}

double World::kinetic_energy() const {
  double energy = 0;
  for (BodyId b = 0; b < impl_->live.size(); ++b) {
    if (!impl_->live[b].rigid) continue;
    const BodyState s = state(b);
    const RigidMass& mass = impl_->records[b].mass;
    energy +=
        0.5 * mass.mass * dot(s.linear_velocity, s.linear_velocity) +
        0.5 * dot(s.angular_velocity, world_inertia_times(s.pose.rotation, mass.principal_moments, s.angular_velocity));
  }
  return energy;
}

double World::object_mass(ObjectId object) const {
  require_object(impl_->objects.size(), object);
  double mass = 0;
  for (BodyId b = 0; b < impl_->live.size(); ++b) {
    if (impl_->live[b].rigid && impl_->records[b].object == object) mass += impl_->records[b].mass.mass;
  }
  return mass;
}

}  // namespace shatter::runtime
