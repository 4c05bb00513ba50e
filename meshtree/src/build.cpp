#include "shatter/meshtree/build.hpp"

#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/mass.hpp"
#include "shatter/kernel/validate.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/packed_node.hpp"
#include "shatter/meshtree/packed_shapes.hpp"
#include "address_sanitizer.hpp"
#include "populate.hpp"
#include "node_mass.hpp"
#include "tree_hulls.hpp"
#include "shatter/cut/hull.hpp"
#include "shatter/cut/plane_cut.hpp"
#include "shatter/cut/plane_input.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/version.hpp"
#include "validate_tree_certificate.hpp"

namespace shatter {

namespace {

// --- reproducible randomness ------------------------------------------------
// splitmix64: a node's planes come from its own stream, seeded from its parent's
// seed and its place among its siblings, so a subtree never depends on what other
// threads drew. Only +, *, / and sqrt touch the draws (all correctly rounded in
// IEEE arithmetic), never a library transcendental, so every machine agrees.

class NodeRandom {
 public:
  explicit NodeRandom(std::uint64_t seed) : state_(seed) {}
  /// Uniform in [-1, 1).
  double symmetric() { return static_cast<double>(splitmix64(state_) >> 11) * 0x1p-52 - 1.0; }
  /// A unit direction uniform on the sphere (rejection from the cube).
  Vec3 direction() {
    for (;;) {
      const Vec3 v{symmetric(), symmetric(), symmetric()};
      const double length_squared = dot(v, v);
      if (length_squared > 1e-4 && length_squared <= 1.0) return v * (1.0 / std::sqrt(length_squared));
    }
  }

 private:
  std::uint64_t state_;
};

// --- planes -------------------------------------------------------------------

// Axis strategy jitter: the normal leans up to atan(0.27) ≈ 15° off the axis, and
// the plane moves up to 20% of the half-extent off the centroid.
constexpr double axis_lean = 0.27;
constexpr double axis_offset_fraction = 0.2;

Plane plane_through(const Vec3& normal, const Vec3& point) { return {normal, -dot(normal, point)}; }

struct BoundingBox {
  Vec3 lo, hi;
};

BoundingBox bounding_box(const Solid& solid) {
  auto point = [](const ApproxPoint& a) {
    return Vec3{a.x.value / a.w.value, a.y.value / a.w.value, a.z.value / a.w.value};
  };
  BoundingBox box{point(solid.approx.front()), point(solid.approx.front())};
  for (const ApproxPoint& a : solid.approx) {
    const Vec3 p = point(a);
    box.lo = {std::min(box.lo.x, p.x), std::min(box.lo.y, p.y), std::min(box.lo.z, p.z)};
    box.hi = {std::max(box.hi.x, p.x), std::max(box.hi.y, p.y), std::max(box.hi.z, p.z)};
  }
  return box;
}

Plane axis_plane(const BoundingBox& box, const Vec3& centroid, NodeRandom& random) {
  const Vec3 extent = box.hi - box.lo;
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  const double a = random.symmetric() * axis_lean, b = random.symmetric() * axis_lean;
  const double shift = random.symmetric() * axis_offset_fraction * 0.5;
  Vec3 normal, point = centroid;
  if (axis == 0) {
    normal = {1, a, b};
    point.x += shift * extent.x;
  } else if (axis == 1) {
    normal = {b, 1, a};
    point.y += shift * extent.y;
  } else {
    normal = {a, b, 1};
    point.z += shift * extent.z;
  }
  return plane_through(normalized(normal), point);
}

Plane draw_plane(Strategy strategy, const BoundingBox& box, const Vec3& centroid, NodeRandom& random) {
  if (strategy == Strategy::axis) return axis_plane(box, centroid, random);
  return plane_through(random.direction(), centroid);
}

// --- where the build's node records live ------------------------------------------
// Every node is a BuildNode until number_tree moves its contents into the tree's
// preorder array, which is allocated whole while the BuildNodes still exist: at
// 2^20 fragments some 1.0 GB of BuildNodes beside the array's 1.2 GB. Memory
// freed to malloc stays in the process, and could not hold that one large array
// anyway, so BuildNodes come from blocks of their own, taken from the system
// and given back as soon as every node in one is freed: number_tree frees each
// node once its contents have moved, and the blocks leave as the array fills.
//
// A thread takes nodes from its own open block, one after the other; each node
// is preceded by a pointer to its block. A block counts its live nodes plus one
// while it is open; the thread closes it (drops that one) when it moves on to a
// new block, and whoever drops the count to zero, closing or freeing the last
// node, unmaps it. Any thread may free a node. (Not under AddressSanitizer,
// which checks BuildNodes only where malloc makes them.)

#if SHATTER_ADDRESS_SANITIZER
#define SHATTER_NODE_BLOCKS 0
#else
#define SHATTER_NODE_BLOCKS 1
#endif

#if SHATTER_NODE_BLOCKS
constexpr std::size_t node_block_bytes = std::size_t{1} << 20;
// A block's pages are populated with the mapping: a thread fills its block
// node after node, and a page faulted in on first touch costs these virtual
// machines about twice as much (ByteBlocks, packed_shapes.cpp, measured it).
#ifdef MAP_POPULATE
constexpr int node_block_populate = MAP_POPULATE;
#else
constexpr int node_block_populate = 0;
#endif
constexpr std::size_t node_align = alignof(std::max_align_t);
constexpr std::size_t aligned(std::size_t bytes) { return (bytes + node_align - 1) / node_align * node_align; }

// The head of a block; its nodes follow it, from byte node_block_start.
struct NodeBlock {
  std::atomic<std::size_t> holds{1};  // live nodes, plus one while open
  std::size_t used = 0;               // bytes of the block handed out, the head's included
};

constexpr std::size_t node_block_start = aligned(sizeof(NodeBlock));
// Before each node, the pointer to its block.
constexpr std::size_t node_slot_bytes = aligned(sizeof(NodeBlock*));

void drop_hold(NodeBlock* block) {
  if (block->holds.fetch_sub(1, std::memory_order_acq_rel) == 1) {
    block->~NodeBlock();
    ::munmap(block, node_block_bytes);
  }
}

class OpenNodeBlock {
 public:
  OpenNodeBlock() = default;
  OpenNodeBlock(const OpenNodeBlock&) = delete;
  OpenNodeBlock& operator=(const OpenNodeBlock&) = delete;
  ~OpenNodeBlock() {
    if (block_ != nullptr) drop_hold(block_);
  }

  void* allocate(std::size_t size) {
    // The node's block pointer first, then the node, both aligned as malloc would.
    const std::size_t need = node_slot_bytes + aligned(size);
    if (need > node_block_bytes - node_block_start) throw std::bad_alloc();
    if (block_ == nullptr || block_->used + need > node_block_bytes) {
      void* memory = ::mmap(nullptr, node_block_bytes, PROT_READ | PROT_WRITE,
                            MAP_PRIVATE | MAP_ANONYMOUS | node_block_populate, -1, 0);
      if (memory == MAP_FAILED) throw std::bad_alloc();
      if (block_ != nullptr) drop_hold(block_);
      block_ = new (memory) NodeBlock();
      block_->used = node_block_start;
    }
    std::byte* at = reinterpret_cast<std::byte*>(block_) + block_->used;
    block_->used += need;
    block_->holds.fetch_add(1, std::memory_order_relaxed);
    *reinterpret_cast<NodeBlock**>(at) = block_;
    return at + node_slot_bytes;
  }

  static void free(void* node) {
    drop_hold(*reinterpret_cast<NodeBlock**>(static_cast<std::byte*>(node) - node_slot_bytes));
  }

 private:
  NodeBlock* block_ = nullptr;
};

thread_local OpenNodeBlock open_node_block;
#endif  // SHATTER_NODE_BLOCKS

// --- the tree under construction ----------------------------------------------

struct BuildNode {
#if SHATTER_NODE_BLOCKS
  // From the node blocks above, so the records leave the process as they are freed.
  static void* operator new(std::size_t size) { return open_node_block.allocate(size); }
  static void operator delete(void* node) noexcept { OpenNodeBlock::free(node); }
#endif

  // The solid rounded to doubles, certified valid (round_solid); absent when
  // packed. Boxed (mesh and solid both), as MeshTreeNode's are: a lean build
  // packs every node, and two million records of a million-fragment build
  // would otherwise hold 272 bytes of empty arrays each (0.54 GB, most of the
  // build's own peak) until number_tree frees them.
  Boxed<Mesh> mesh;
  // The exact solid; its vertices refer to the cut plane of the ancestor at
  // depth k as PlaneRef::cut(k). A node's index in the tree is its place in
  // depth-first preorder, unknown until every subtree before it is finished
  // (they grow in parallel, and cuts may be undone), so the depth names the
  // plane until number_tree gives the node its index.
  Boxed<Solid> solid;
  // A lean build's non-convex leaf's hull, taken as it finishes (leaf_finished);
  // tree_hulls makes every other node's.
  Boxed<Mesh> hull;
  const BuildNode* parent = nullptr;
  MassProperties mass;
  Plane plane;  // the plane that cut this node; zero while it is a leaf
  bool above_parent_plane = false;
  std::uint32_t depth = 0;
  std::uint64_t seed = 0;
  std::vector<std::unique_ptr<BuildNode>> children;
  // Pieces of this node's cut that vanished (thinner than the rounding of their
  // coordinates: no children), with their exact volume and its bound, summed.
  std::uint64_t vanished_pieces = 0;
  double vanished_volume = 0, vanished_volume_bound = 0;
  // A lean build's cut node: its mesh and solid packed (packed_node.hpp), in
  // the builder's blocks (Builder::take_packed_bytes), with the solid's convex
  // flag, which the tree's node keeps (MeshTreeNode::convex).
  std::span<const std::uint8_t> packed;
  bool packed_convex = false;
};

// The cut grows its pieces' arrays by doubling, so they hold about a third more
// than they use (cube -> 65,536: 334 MB held for 247 MB of meshes and solids),
// and every node keeps its arrays to the end of the build. Fitting each child's
// arrays once, when it is made, costs a copy of a small piece and changes no
// value. (Capacity is no part of the tree.)
template <class T>
void fit(std::vector<T>& values) {
  if (values.capacity() > values.size()) values.shrink_to_fit();
}

void fit_to_size(BuildNode& node) {
  fit(node.mesh->positions);
  fit(node.mesh->triangles);
  fit(node.mesh->surfaces);
  fit(node.mesh->corners.normals);
  fit(node.mesh->corners.uvs);
  fit(node.mesh->corners.tangents);
  fit(node.solid->defs);
  fit(node.solid->approx);
  fit(node.solid->faces);
  fit(node.solid->loops);
  fit(node.solid->corners);
}

class Builder {
 public:
  Builder(const TreeRecipe& recipe, const LeafProgressFn& progress, bool lean)
      : recipe_(recipe), progress_(progress), lean_(lean) {}

  // The root: `mesh` as given, over `input`, which is prepare_plane_input(mesh)
  // and outlives the builder.
  std::unique_ptr<BuildNode> root(const Mesh& mesh, const PlaneInput& input) {
    auto node = std::make_unique<BuildNode>();
    plane_input_ = &input;
    node->solid = plane_input_->solid;
    node->mesh = mesh;  // the root is the input as given (validated on the way in)
    node->mass = mass_properties(node->mesh);
    detail::require_representable_mass(node->mass, "the solid");
    node->seed = root_node_seed(recipe_.seed);
    return node;
  }

  /// Cuts `node` and attaches its children. A pure function of the node (its
  /// solid, seed and depth) and the options: which thread runs it, and when,
  /// never shows. The cut is exact, so nothing about the solids is checked: each
  /// child is rounded to doubles at once and certified (cut_by_plane). A plane is
  /// redrawn only when it misses the node: it leaves the node whole, or every
  /// piece but one is thinner than the rounding of its coordinates and vanishes
  /// (as written, the node is not cut). Otherwise the pieces that vanish are no
  /// children (their volume, which moves to their neighbours, is counted with its
  /// bound), and the others are. One case is left where a plane is redrawn for
  /// its pieces: a piece round_solid cannot write validly (the few folds at the
  /// rounding's scale it does not repair yet, README "Robustness"; never met by a
  /// random plane in the corpus builds). Failing the build there would refuse a
  /// valid input; the redraw is counted (BuildReport::planes_rejected), so it is
  /// never silent. A cut that would pinch a piece throws UnsupportedGeometryError.
  void cut(BuildNode& node) const {
    NodeRandom random(node.seed);
    const BoundingBox box = bounding_box(node.solid);
    // The ancestors' planes by depth, then this node's (drawn below).
    thread_local std::vector<Plane> path;
    path.resize(node.depth + 1);
    for (const BuildNode* a = node.parent; a != nullptr; a = a->parent) path[a->depth] = a->plane;
    const PlaneRef cut = PlaneRef::cut(node.depth);
    const PlaneSet set = plane_input_->geometry.plane_set(path);
    PlaneCutOptions cutting;
    cutting.cap_surface = node.depth + 1;
    cutting.interior_uv_scale = recipe_.interior_uv_scale;
    cutting.allow_self_intersections = recipe_.allow_self_intersections;
    std::uint32_t missed = 0, missed_as_written = 0, unroundable = 0;
    std::string last_defect;
    for (std::uint32_t attempt = 0; attempt < recipe_.max_plane_tries; ++attempt) {
      path.back() = draw_plane(recipe_.strategy, box, node.mass.centroid, random);
      // node.mesh is certified (the root: the validated input). A pinch throws.
      PlaneCut result = cut_by_plane(*plane_input_, set, *node.solid, &*node.mesh, cut, cutting);
      if (result.plane_missed) {
        ++missed;
        continue;
      }
      const auto cannot_write = std::find_if(result.pieces.begin(), result.pieces.end(), [](const CutPiece& piece) {
        return !piece.vanished && !piece.defect.empty();
      });
      if (cannot_write != result.pieces.end()) {
        ++unroundable;
        last_defect = cannot_write->defect;
        continue;
      }
      if (result.misses_as_written()) {
        ++missed_as_written;
        continue;
      }
      double vanished_volume = 0, vanished_bound = 0;
      std::uint64_t vanished = 0;
      for (CutPiece& piece : result.pieces) {
        if (piece.vanished) {
          ++vanished;
          vanished_volume += piece.moved_volume;
          vanished_bound += piece.moved_volume_bound;
          continue;
        }
        auto child = std::make_unique<BuildNode>();
        child->mesh = std::move(piece.mesh);
        child->mass = mass_properties(child->mesh);
        detail::require_representable_mass(child->mass, "a fragment");
        child->solid = std::move(piece.solid);
        // A lean build packs the child (its arrays go) as soon as it is cut or
        // found a leaf, except the balanced strategy's leaves, which wait for
        // the end: only arrays that stay are worth fitting.
        if (!lean_ || recipe_.strategy == Strategy::balanced) fit_to_size(*child);
        child->parent = &node;
        child->above_parent_plane = piece.above;
        child->depth = node.depth + 1;
        child->seed = child_node_seed(node.seed, node.children.size());
        node.children.push_back(std::move(child));
      }
      node.plane = path.back();
      node.vanished_pieces = vanished;
      node.vanished_volume = vanished_volume;
      node.vanished_volume_bound = vanished_bound;
      planes_missed_ += missed + missed_as_written;
      planes_rejected_ += unroundable;
      return;
    }
    throw UnsupportedGeometryError(
        "cannot cut a fragment at depth " + std::to_string(node.depth) + ": of " +
        std::to_string(recipe_.max_plane_tries) + " planes, " + std::to_string(missed) + " left it whole, " +
        std::to_string(missed_as_written) + " left only pieces thinner than the rounding of their coordinates "
        "besides one, and " + std::to_string(unroundable) + " gave a piece that cannot be written as a valid mesh" +
        (last_defect.empty() ? std::string() : " (" + last_defect + ")") + near_resolution(box));
  }

  // Why planes miss a fragment whose size nears the spacing of doubles at its
  // coordinates (a unit cube at 1e15, where doubles are 0.125 apart: a plane's
  // offset, about 1e15, is itself rounded by that much), said when it is so:
  // within 1024 spacings. Empty otherwise.
  static std::string near_resolution(const BoundingBox& box) {
    const double largest = std::max({std::fabs(box.lo.x), std::fabs(box.lo.y), std::fabs(box.lo.z), std::fabs(box.hi.x),
                                     std::fabs(box.hi.y), std::fabs(box.hi.z)});
    const double spacing = std::nextafter(largest, INFINITY) - largest;
    const double across = std::max({box.hi.x - box.lo.x, box.hi.y - box.lo.y, box.hi.z - box.lo.z});
    if (!(across < 1024 * spacing)) return {};
    char text[160];
    std::snprintf(text, sizeof text,
                  "; the fragment is %.3g across where its coordinates reach %.3g and doubles are %.3g apart: "
                  "finer fragments cannot be written",
                  across, largest, spacing);
    return text;
  }

  /// A lean build's `node`, whose cut is kept (its children are final, unless
  /// a surplus cut is undone: the node is then a leaf packed as leaf_finished
  /// packs one, and its children's bytes stay in the blocks, unused): its mesh
  /// and solid are packed, for nothing below it reads them (the cuts of its
  /// descendants need only its plane, depth and mass) and the writer unpacks
  /// them one at a time.
  void cut_kept(BuildNode& node) {
    if (!lean_ || node.children.empty()) return;
    pack(node);
  }

  /// `node` is a leaf of the finished tree (a cut undone later leaves another).
  /// A lean build packs it, as a cut node: what reads it later (hulls, bonds,
  /// the writer) unpacks it (NodeShapes), and a million leaves' arrays would
  /// otherwise be the largest part of the tree (README "Lean memory").
  void leaf_finished(BuildNode& node) {
    if (lean_) {
      // A non-convex leaf's hull while its mesh is at hand: tree_hulls would
      // unpack the mesh again, computing every position from its definition.
      if (node.mesh.present() && !node.solid->convex) node.hull = convex_hull_of(*node.mesh);
      pack(node);
    }
    const std::size_t done = ++leaves_done_;
    if (progress_) progress_(done);
  }

  bool lean() const { return lean_; }

  /// What a lean build packed (BuildNode::packed), for the tree's
  /// PackedShapes; the builder's blocks are left empty.
  ByteBlocks take_packed_bytes() {
    ByteBlocks all;
    for (ByteBlocks& blocks : packed_bytes_) all.splice(std::move(blocks));
    packed_bytes_.clear();
    return all;
  }

  const TreeRecipe& recipe() const { return recipe_; }
  const PlaneInput& plane_input() const { return *plane_input_; }
  std::uint64_t planes_missed() const { return planes_missed_; }
  std::uint64_t planes_rejected() const { return planes_rejected_; }

 private:
  // A lean build's packing of `node`'s mesh and solid (its approximations go),
  // into the blocks every worker appends to. The mesh's positions are coded
  // against the solid's (output_position of each definition, which the
  // approximations the cut left make cheap): 24 bytes a vertex become one or
  // two, and the file's MESH record takes the codes as they are, where it
  // computed every definition's approximation and position again.
  void pack(BuildNode& node) {
    node.packed_convex = node.solid->convex;
    // The planes the node's definitions name: its ancestors' by depth, as in cut().
    thread_local std::vector<Plane> path;
    path.assign(std::size_t{node.depth} + 1, Plane{});
    for (const BuildNode* a = node.parent; a != nullptr; a = a->parent) path[a->depth] = a->plane;
    const PlaneSet set = plane_input_->geometry.plane_set(path);
    // One buffer a thread, the bytes copied on into the blocks (a fresh array
    // a node grew by doubling, a dozen times for a small piece); one that a
    // large node made large is not kept for the rest of the build.
    thread_local std::vector<std::uint8_t> bytes;
    pack_node_shape(node.mesh, node.solid, false, bytes, &set);
    node.packed = packed_bytes_.local().append(bytes);
    if (bytes.capacity() > ByteBlocks::block_size) std::vector<std::uint8_t>().swap(bytes);
    node.mesh.reset();
    node.solid.reset();
  }

  const TreeRecipe& recipe_;  // what to build
  const PlaneInput* plane_input_ = nullptr;  // Builder::root's
  const LeafProgressFn& progress_;
  const bool lean_;  // BuildRunOptions::lean
  // Every BuildNode::packed, in blocks of the thread that packed it. One set of
  // blocks under a lock made the workers queue on it (the copy into a fresh
  // block's pages takes a page fault each 4 KiB): at cube -> 65,536 on two
  // threads, a tenth of the build's CPU seconds went to waiting and waking. Which
  // thread holds a node's bytes, and where, is no part of the tree.
  tbb::enumerable_thread_specific<ByteBlocks> packed_bytes_;
  std::atomic<std::size_t> leaves_done_{0};
  // Counted from every worker; cut() is const because it is a pure function of
  // its node, and these tallies never feed back into a decision.
  mutable std::atomic<std::uint64_t> planes_missed_{0};
  mutable std::atomic<std::uint64_t> planes_rejected_{0};
};

// --- budgets: thesis and axis ---------------------------------------------------
// A node asked for n fragments is cut, and n is shared among its children; a child
// with a share of 1 or less is a leaf. The shares depend only on the node, so
// subtrees grow independently, in parallel.

std::vector<std::uint32_t> share_evenly(std::uint32_t budget, std::size_t children) {
  std::vector<std::uint32_t> shares(children);
  const auto k = static_cast<std::uint32_t>(children);
  for (std::uint32_t i = 0; i < k; ++i) shares[i] = budget / k + (i < budget % k ? 1 : 0);
  return shares;
}

// Each child gets one, and the rest goes by volume (largest remainder, ties to
// the earlier child), so big pieces are cut more and fragments come out even.
std::vector<std::uint32_t> share_by_volume(std::uint32_t budget, const BuildNode& node) {
  const std::size_t k = node.children.size();
  std::vector<std::uint32_t> shares(k, 1);
  if (budget <= k) return shares;
  const std::uint32_t rest = budget - static_cast<std::uint32_t>(k);
  double total = 0;
  for (const auto& child : node.children) total += std::max(child->mass.volume, 0.0);
  std::vector<double> remainder(k);
  std::uint32_t given = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double exact_share =
        total > 0 ? rest * (std::max(node.children[i]->mass.volume, 0.0) / total) : double(rest) / double(k);
    const auto whole = std::min(rest - given, static_cast<std::uint32_t>(std::floor(exact_share)));
    shares[i] += whole;
    given += whole;
    remainder[i] = exact_share - whole;
  }
  std::vector<std::size_t> order(k);
  for (std::size_t i = 0; i < k; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return remainder[a] > remainder[b]; });
  for (std::size_t i = 0; given < rest; i = (i + 1) % k, ++given) ++shares[order[i]];
  return shares;
}

// Below this budget a subtree is grown on the current thread: the work is too
// small to pay for a task.
constexpr std::uint32_t parallel_budget = 32;

void grow(Builder& builder, BuildNode& node, std::uint32_t budget) {
  if (budget <= 1) {
    builder.leaf_finished(node);
    return;
  }
  builder.cut(node);
  builder.cut_kept(node);
  const std::vector<std::uint32_t> shares = builder.recipe().strategy == Strategy::axis
                                                ? share_by_volume(budget, node)
                                                : share_evenly(budget, node.children.size());
  if (budget < parallel_budget) {
    for (std::size_t i = 0; i < node.children.size(); ++i) grow(builder, *node.children[i], shares[i]);
  } else {
    tbb::parallel_for(std::size_t{0}, node.children.size(),
                      [&](std::size_t i) { grow(builder, *node.children[i], shares[i]); });
  }
}

// A cut whose node falls into three or more solids spends more leaves than its
// budget, and subtrees spend their budgets without seeing each other, so the
// count can pass N by more than one cut's worth. Undoing last cuts (nodes whose
// children are all leaves), the last in depth-first order first, while the count
// stays >= N makes the tree the one that stops at the first count >= N.
void undo_surplus_cuts(BuildNode& root, std::uint32_t target) {
  std::vector<BuildNode*> preorder;
  std::vector<BuildNode*> stack{&root};
  while (!stack.empty()) {
    BuildNode* node = stack.back();
    stack.pop_back();
    preorder.push_back(node);
    for (auto child = node->children.rbegin(); child != node->children.rend(); ++child) stack.push_back(child->get());
  }
  std::size_t leaves = 0;
  for (const BuildNode* node : preorder) leaves += node->children.empty() ? 1 : 0;
  // Children come after their parent in preorder, so one backward pass also sees
  // a parent whose last child cut was just undone.
  for (auto it = preorder.rbegin(); it != preorder.rend() && leaves > target; ++it) {
    BuildNode& node = **it;
    if (node.children.empty()) continue;
    const bool last_cut = std::all_of(node.children.begin(), node.children.end(),
                                      [](const auto& child) { return child->children.empty(); });
    const std::size_t spent = node.children.size() - 1;
    if (!last_cut || leaves - spent < target) continue;
    node.children.clear();
    node.plane = {};
    node.vanished_pieces = 0, node.vanished_volume = 0, node.vanished_volume_bound = 0;
    leaves -= spent;
  }
}

// --- balanced: the largest leaf next -------------------------------------------
// The order is global, so the decisions are taken one at a time; the cuts, being
// pure functions of their node, are computed ahead for the next few largest
// leaves in parallel. A cut computed ahead that is never needed is dropped, so the
// tree is the one the one-at-a-time loop makes, on any number of threads.

struct LargestFirst {
  bool operator()(const std::pair<BuildNode*, std::uint64_t>& a,
                  const std::pair<BuildNode*, std::uint64_t>& b) const {
    if (a.first->mass.volume != b.first->mass.volume) return a.first->mass.volume > b.first->mass.volume;
    return a.second < b.second;  // equal volumes: the older leaf first
  }
};

void grow_balanced(Builder& builder, BuildNode& root, std::uint32_t target, unsigned threads) {
  std::set<std::pair<BuildNode*, std::uint64_t>, LargestFirst> leaves;
  std::uint64_t created = 0;
  leaves.insert({&root, created++});
  std::vector<BuildNode*> ahead;
  while (leaves.size() < target) {
    ahead.clear();
    for (auto it = leaves.begin(); it != leaves.end() && ahead.size() < threads; ++it) {
      if (it->first->children.empty()) ahead.push_back(it->first);
    }
    if (ahead.size() > 1) {
      tbb::parallel_for(std::size_t{0}, ahead.size(), [&](std::size_t i) { builder.cut(*ahead[i]); });
    } else {
      builder.cut(*ahead.front());
    }
    // Apply the decisions in order; stop at the first leaf whose cut was not made
    // ahead (its turn comes in the next round).
    while (leaves.size() < target) {
      auto largest = leaves.begin();
      BuildNode* node = largest->first;
      if (node->children.empty()) break;
      leaves.erase(largest);
      for (auto& child : node->children) leaves.insert({child.get(), created++});
      builder.cut_kept(*node);
    }
  }
  // Cuts made ahead but never reached are undone: those nodes stay leaves.
  for (const auto& [node, order] : leaves) {
    node->children.clear();
    node->plane = {};
    node->vanished_pieces = 0, node->vanished_volume = 0, node->vanished_volume_bound = 0;
    builder.leaf_finished(*node);
  }
}

// --- numbering ------------------------------------------------------------------

std::size_t count_nodes(const BuildNode& root) {
  std::size_t count = 0;
  std::vector<const BuildNode*> stack{&root};
  while (!stack.empty()) {
    const BuildNode* node = stack.back();
    stack.pop_back();
    ++count;
    for (const auto& child : node->children) stack.push_back(child.get());
  }
  return count;
}

// Consumes the built tree: each node is freed as soon as its contents have moved
// into `tree` (iteratively: a chain of cuts can be long), so its record's block
// can leave the process while the tree's array fills (see the node blocks). A
// lean build's packed bytes stay where they are: `packed` holds them all.
void number_tree(std::unique_ptr<BuildNode> root, ByteBlocks packed, MeshTree& tree) {
  struct Pending {
    std::unique_ptr<BuildNode> node;
    NodeIndex parent;
  };
  // Sized once: a tree of a million fragments has two million nodes of some
  // 600 bytes each, and growing by doubling would hold the old and new arrays.
  const std::size_t node_count = count_nodes(*root);
  tree.nodes.reserve(node_count);
  tree.cut_planes.reserve(node_count);
  // Their pages populated a few mebibytes ahead of the fill, where each took a
  // fault on first touch (a tenth of this loop's time at cube -> 65,536), but
  // not all at once: the build's nodes leave as the array fills.
  constexpr std::size_t populate_ahead = std::size_t{4} << 20;
  detail::PopulatedAhead nodes_ahead(tree.nodes, populate_ahead);
  detail::PopulatedAhead planes_ahead(tree.cut_planes, populate_ahead);
  // A lean build packed its cut nodes (the root first, when it was cut).
  if (!root->packed.empty()) tree.packed_shapes = PackedShapes(std::move(packed), node_count);
  std::vector<Pending> stack;
  stack.push_back({std::move(root), no_node});
  std::vector<NodeIndex> path;  // path[d]: the node at depth d above the current one
  while (!stack.empty()) {
    const Pending pending = std::move(stack.back());
    stack.pop_back();
    BuildNode& built = *pending.node;
    const auto index = static_cast<NodeIndex>(tree.nodes.size());
    path.resize(built.depth + 1);
    path[built.depth] = index;

    MeshTreeNode node;
    if (!built.packed.empty()) {
      // Packed as the builder names planes and caps; NodeShapes renames them
      // by the node's path when it unpacks.
      node.convex = built.packed_convex;
      tree.packed_shapes.adopt(index, built.packed);
    } else {
      node.mesh = std::move(built.mesh);
      node.solid = std::move(built.solid);
      node.convex = node.solid->convex;
      // Caps were labelled by the depth of their cut, and the plane kernel's
      // cut planes referred to by depth (BuildNode::solid says why); now that
      // every node has its index, each becomes that ancestor's.
      rename_by_path(path, *node.mesh, *node.solid);
    }
    node.mass = built.mass;
    node.hull = std::move(built.hull);
    node.parent = pending.parent;
    tree.cut_planes.push_back(built.plane);
    node.above_parent_plane = built.above_parent_plane;
    node.depth = built.depth;
    node.seed = built.seed;
    if (built.children.empty()) {
      node.first_leaf = static_cast<LeafIndex>(tree.leaf_nodes.size());
      node.leaf_count = 1;
      tree.leaf_nodes.push_back(index);
    }
    if (pending.parent != no_node) tree.nodes[pending.parent].children.push_back(index);
    node.children.reserve(built.children.size());  // one allocation, not one a child
    tree.nodes.push_back(std::move(node));
    nodes_ahead.ensure();
    planes_ahead.ensure();
    for (auto child = built.children.rbegin(); child != built.children.rend(); ++child) {
      stack.push_back({std::move(*child), index});
    }
  }
  // Children follow their parent in preorder: fill ranges from the back.
  for (std::size_t i = tree.nodes.size(); i-- > 0;) {
    MeshTreeNode& node = tree.nodes[i];
    if (node.children.empty()) continue;
    node.first_leaf = tree.nodes[node.children.front()].first_leaf;
    node.leaf_count = 0;
    for (NodeIndex child : node.children) node.leaf_count += tree.nodes[child].leaf_count;
  }
}

// The pieces that vanished in the cuts the tree keeps, with their volume and its
// bound, summed in preorder (so the doubles add up alike on every run).
void count_vanished(const BuildNode& root, BuildReport& report) {
  std::vector<const BuildNode*> stack{&root};
  while (!stack.empty()) {
    const BuildNode* node = stack.back();
    stack.pop_back();
    report.pieces_vanished += node->vanished_pieces;
    report.vanished_volume += node->vanished_volume;
    report.vanished_volume_bound += node->vanished_volume_bound;
    for (auto child = node->children.rbegin(); child != node->children.rend(); ++child) stack.push_back(child->get());
  }
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

MeshTree build_mesh_tree(const Mesh& mesh, const TreeRecipe& recipe, const BuildRunOptions& run) {
  if (recipe.fragments < 1) throw std::invalid_argument("fragments must be at least 1");
  if (recipe.max_plane_tries < 1) throw std::invalid_argument("max_plane_tries must be at least 1");
  if (recipe.strategy == Strategy::voronoi) {
    throw std::invalid_argument("the voronoi strategy needs its sites: build_voronoi_tree (voronoi.hpp) builds it");
  }
  if (recipe.kernel != KernelKind::plane) {
    throw std::invalid_argument("recipe.kernel must be plane: the " + std::string(kernel_name(recipe.kernel)) +
                                " kernel was retired (its trees still read)");
  }
  for (SurfaceId surface : mesh.surfaces) {
    if (surface != original_surface) {
      throw std::invalid_argument("build_mesh_tree needs every input triangle on surface 0 (caps are numbered by cut)");
    }
  }
  detail::require_fracturable_extent(mesh);
  const unsigned threads = run.threads == 0 ? static_cast<unsigned>(tbb::info::default_concurrency()) : run.threads;
  tbb::task_arena arena(static_cast<int>(threads));
  auto phase_start = std::chrono::steady_clock::now();
  // The input checked (unless the caller did) and prepared (unless the caller
  // did), the two side by side when the build does both.
  const auto check = [&] { require_valid_solid(mesh, "input", recipe.allow_self_intersections); };
  std::optional<PlaneInput> prepared_here;
  if (run.prepared != nullptr) {
    if (!run.input_validated) arena.execute(check);
  } else if (run.input_validated) {
    prepared_here = prepare_plane_input(mesh);
  } else {
    arena.execute([&] { prepared_here = prepare_plane_input_beside(mesh, check); });
  }
  const PlaneInput& input = run.prepared != nullptr ? *run.prepared : *prepared_here;
  Builder builder(recipe, run.progress, run.lean);
  std::unique_ptr<BuildNode> root = builder.root(mesh, input);
  arena.execute([&] {
    if (recipe.strategy == Strategy::balanced) {
      grow_balanced(builder, *root, recipe.fragments, threads);
    } else {
      grow(builder, *root, recipe.fragments);
      undo_surplus_cuts(*root, recipe.fragments);
    }
  });

  MeshTree tree;
  tree.recipe = recipe;
  tree.shatter_version = std::string(version_string);
  BuildReport timing;
  count_vanished(*root, timing);
  number_tree(std::move(root), builder.take_packed_bytes(), tree);
  timing.cutting_seconds = seconds_since(phase_start);
  timing.planes_missed = builder.planes_missed();
  timing.planes_rejected = builder.planes_rejected();
  // The input points and planes the nodes' exact solids are defined over, beside
  // the cut planes number_tree stored.
  tree.geometry = builder.plane_input().geometry;
  phase_start = std::chrono::steady_clock::now();
  detail::tree_hulls(arena, tree);
  timing.hull_seconds = seconds_since(phase_start);
  phase_start = std::chrono::steady_clock::now();
  // A lean build keeps its bonds packed, found so (40 bytes a bond instead of
  // 72: 0.3 GB of a million-fragment cube's peak, which is here).
  if (builder.lean()) {
    // On the build's threads: the same bonds on any number (bonds.hpp).
    arena.execute([&] { tree.packed_bonds = find_packed_plane_bonds(tree); });
  } else {
    arena.execute([&] { tree.bonds = find_bonds(tree); });
  }
  timing.bond_seconds = seconds_since(phase_start);
  // The tree passes validate_tree, caches included, by construction (README
  // "Certificates carried, not re-checked"): number_tree made the links, depths,
  // leaf ranges, leaf list and one cut plane per node in preorder; every mesh
  // is one the cut certified a valid solid as written (round_solid: closed,
  // manifold, oriented, its indices in range), or the input read_valid_solid /
  // require_valid_solid checked; every hull is one convex_hull_of built
  // (tree_hulls) over a leaf's positions or an internal node's children's
  // hulls' points; find_bonds lists bonds sorted, between leaves its cut node
  // separates; every solid is what the exact cut made of its parent's, closed,
  // its vertices' definitions approximated by the cut itself (so none is
  // degenerate), its planes input planes or its ancestors' (named by depth,
  // renamed by path); the packed nodes unpack to what was packed. The writer
  // would re-check all of that; the certificate carries it there instead, bound
  // to the content by a digest, so any later change makes it check again.
  // Every mass is mass_properties of the mesh its node keeps (Builder::root,
  // Builder::cut; renaming caps moves no position), so the certificate says so
  // too and the writer need not recompute each to leave them out of the file.
  detail::TreeCertifier::certify(tree, true);
  if (run.report) *run.report = timing;
  return tree;
}

}  // namespace shatter
