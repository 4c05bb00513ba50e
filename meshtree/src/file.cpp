// The .shatter file (layout in file.hpp). The encoder writes every field byte by
// byte; the decoder checks every count against the bytes left before it
// allocates; and one validator serves both, so whatever the encoder accepts the
// decoder accepts, and a decoded tree keeps every MeshTree invariant.

#include "shatter/meshtree/file.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"

namespace shatter {

namespace {

// ---------------------------------------------------------------------------
// Constants of the layout

using Tag = std::array<char, 4>;

constexpr std::array<unsigned char, 8> magic = {0x89, 'S', 'H', 'T', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr std::size_t file_header_size = 12;     // magic, u32 version
constexpr std::size_t section_header_size = 16;  // tag, u64 length, u32 crc

constexpr Tag options_tag = {'O', 'P', 'T', 'S'};
constexpr Tag nodes_tag = {'N', 'O', 'D', 'E'};
constexpr Tag meshes_tag = {'M', 'E', 'S', 'H'};
constexpr Tag hulls_tag = {'H', 'U', 'L', 'L'};
constexpr Tag bonds_tag = {'B', 'O', 'N', 'D'};
constexpr Tag end_tag = {'E', 'N', 'D', ' '};

// Bytes on disk, the least each record can take: counts are checked against these
// before anything is allocated, which bounds memory by a multiple of the input.
constexpr std::size_t options_size = 27;
constexpr std::size_t node_record_min_size = 165;  // without its children
constexpr std::size_t child_size = 4;
constexpr std::size_t mesh_record_min_size = 9;
constexpr std::size_t vertex_size = 24;
constexpr std::size_t triangle_size = 16;  // three indices and the surface id
constexpr std::size_t normal_size = 24;
constexpr std::size_t uv_size = 16;
constexpr std::size_t tangent_size = 32;
constexpr std::size_t bond_size = 68;

constexpr std::uint8_t normals_bit = 1;
constexpr std::uint8_t uvs_bit = 2;
constexpr std::uint8_t tangents_bit = 4;
constexpr std::uint8_t known_channel_bits = normals_bit | uvs_bit | tangents_bit;

// The largest enum values this version knows; a new Strategy or KernelKind must
// be added here (and to the layout comment) to be stored.
constexpr std::uint8_t last_strategy = static_cast<std::uint8_t>(Strategy::axis);
constexpr std::uint8_t last_kernel = static_cast<std::uint8_t>(KernelKind::exact);

constexpr std::uint64_t max_u32 = std::numeric_limits<std::uint32_t>::max();

// ---------------------------------------------------------------------------
// Small helpers

std::uint32_t crc_of(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  // zlib takes a 32-bit length; feed larger payloads in pieces.
  constexpr std::size_t piece = std::size_t{1} << 30;
  while (!bytes.empty()) {
    const std::size_t length = std::min(bytes.size(), piece);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(length));
    bytes.remove_prefix(length);
  }
  return static_cast<std::uint32_t>(crc);
}

std::string hex(std::uint64_t value, int digits) {
  static constexpr char digit_chars[] = "0123456789ABCDEF";
  std::string text = "0x";
  for (int k = digits - 1; k >= 0; --k) text += digit_chars[(value >> (4 * k)) & 0xF];
  return text;
}

/// A tag as it can be printed in a one-line message: printable ASCII as is,
/// anything else (damage, usually) as \xNN.
std::string tag_text(Tag tag) {
  std::string text;
  for (const char c : tag) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7F && byte != '\\') {
      text += c;
    } else {
      text += "\\x" + hex(byte, 2).substr(2);
    }
  }
  return text;
}

/// The name of a section in messages: "END" rather than "END ".
std::string section_name(Tag tag) { return tag == end_tag ? std::string("END") : tag_text(tag); }

std::string str(std::uint64_t value) { return std::to_string(value); }

[[noreturn]] void refuse(const std::string& message) { throw CorruptFileError(message); }

// ---------------------------------------------------------------------------
// Validation, shared by the encoder (a precondition) and the decoder (trust)

/// Where a defect is: which record of which part of the tree.
enum class Part { options, node, leaf_list, mesh, hull, bond };

struct Defect {
  Part part;
  std::size_t index;  ///< node, leaf or bond index; 0 for options
  std::string message;
};

std::optional<Defect> options_defect(const BuildOptions& options) {
  if (options.fragments == 0) return Defect{Part::options, 0, "options.fragments is 0 (must be at least 1)"};
  if (static_cast<std::uint8_t>(options.strategy) > last_strategy) {
    return Defect{Part::options, 0, "options.strategy " + str(static_cast<std::uint8_t>(options.strategy)) + " is not a known strategy"};
  }
  if (static_cast<std::uint8_t>(options.kernel) > last_kernel) {
    return Defect{Part::options, 0, "options.kernel " + str(static_cast<std::uint8_t>(options.kernel)) + " is not a known kernel"};
  }
  return std::nullopt;
}

/// Checks the links, preorder, child counts, depths and leaf ranges. Walks the
/// children lists from the root expecting node indices 1, 2, 3, ... in visiting
/// order, so a cycle, a node with two parents, a gap or a wrong order is caught
/// at the first listing that breaks the sequence, and the walk ends after at most
/// n visits whatever the links are.
std::optional<Defect> structure_defect(const std::vector<MeshTreeNode>& nodes) {
  const std::size_t node_count = nodes.size();
  if (node_count == 0) return Defect{Part::node, 0, "the tree has no nodes (it needs at least its root)"};
  if (node_count > max_u32) {
    return Defect{Part::node, 0, "the tree has " + str(node_count) + " nodes, more than node indices can number"};
  }
  if (nodes[0].parent != no_node) {
    return Defect{Part::node, 0, "node 0 (the root) has parent " + str(nodes[0].parent) + " instead of none"};
  }
  if (nodes[0].depth != 0) return Defect{Part::node, 0, "node 0 (the root) has depth " + str(nodes[0].depth) + " instead of 0"};

  struct Visit {
    NodeIndex node;
    std::size_t next_child;
  };
  std::vector<Visit> stack = {{0, 0}};
  std::size_t next_in_preorder = 1;
  while (!stack.empty()) {
    const NodeIndex node = stack.back().node;
    const std::vector<NodeIndex>& children = nodes[node].children;
    if (children.size() == 1) {
      return Defect{Part::node, node, "node " + str(node) + " has one child (an internal node has two or more)"};
    }
    if (stack.back().next_child == children.size()) {
      stack.pop_back();
      continue;
    }
    const NodeIndex child = children[stack.back().next_child++];
    if (child != next_in_preorder) {
      std::string problem = "node " + str(node) + " lists child " + str(child);
      if (child >= node_count) {
        problem += ", but there are only " + str(node_count) + " nodes";
      } else if (child < next_in_preorder) {
        problem += ", which already has its place in the tree (a cycle, or a node listed twice)";
      } else {
        problem += ", but depth-first preorder puts node " + str(next_in_preorder) + " there";
      }
      return Defect{Part::node, node, problem};
    }
    const MeshTreeNode& child_node = nodes[child];
    if (child_node.parent != node) {
      return Defect{Part::node, child,
                    "node " + str(child) + " has parent " + (child_node.parent == no_node ? std::string("none") : str(child_node.parent)) +
                        ", but node " + str(node) + " lists it as a child"};
    }
    if (std::uint64_t{child_node.depth} != std::uint64_t{nodes[node].depth} + 1) {
      return Defect{Part::node, child,
                    "node " + str(child) + " has depth " + str(child_node.depth) + ", but its parent's depth is " + str(nodes[node].depth)};
    }
    ++next_in_preorder;
    stack.push_back({child, 0});
  }
  if (next_in_preorder != node_count) {
    return Defect{Part::node, next_in_preorder, "node " + str(next_in_preorder) + " is not reachable from the root"};
  }

  // In preorder every subtree is an index range, and so are its leaves: a node's
  // first leaf is the number of leaves before it, its count the sum over its children.
  std::vector<std::uint32_t> leaves_below(node_count, 0);
  for (std::size_t k = node_count; k-- > 0;) {
    if (nodes[k].is_leaf()) {
      leaves_below[k] = 1;
    } else {
      for (const NodeIndex child : nodes[k].children) leaves_below[k] += leaves_below[child];
    }
  }
  std::uint32_t leaves_before = 0;
  for (std::size_t k = 0; k < node_count; ++k) {
    const MeshTreeNode& node = nodes[k];
    if (node.first_leaf != leaves_before || node.leaf_count != leaves_below[k]) {
      return Defect{Part::node, k,
                    "node " + str(k) + " claims leaves [" + str(node.first_leaf) + ", +" + str(node.leaf_count) + "), but its subtree holds [" +
                        str(leaves_before) + ", +" + str(leaves_below[k]) + ")"};
    }
    if (node.is_leaf()) ++leaves_before;
  }
  return std::nullopt;
}

std::vector<NodeIndex> leaves_in_order(const std::vector<MeshTreeNode>& nodes) {
  std::vector<NodeIndex> leaves;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    if (nodes[k].is_leaf()) leaves.push_back(static_cast<NodeIndex>(k));
  }
  return leaves;
}

std::optional<Defect> leaf_list_defect(const MeshTree& tree) {
  const std::vector<NodeIndex> expected = leaves_in_order(tree.nodes);
  if (tree.leaf_nodes.size() != expected.size()) {
    return Defect{Part::leaf_list, 0, "leaf_nodes lists " + str(tree.leaf_nodes.size()) + " leaves, but the tree has " + str(expected.size())};
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (tree.leaf_nodes[i] != expected[i]) {
      return Defect{Part::leaf_list, i, "leaf_nodes[" + str(i) + "] is node " + str(tree.leaf_nodes[i]) + ", but leaf " + str(i) + " is node " + str(expected[i])};
    }
  }
  return std::nullopt;
}

/// The first BasicMesh invariant `mesh` breaks, or nothing.
std::optional<std::string> mesh_defect(const Mesh& mesh) {
  if (mesh.positions.size() > max_u32) return "has " + str(mesh.positions.size()) + " vertices, more than a u32 can count";
  if (mesh.triangles.size() > max_u32) return "has " + str(mesh.triangles.size()) + " triangles, more than a u32 can count";
  const std::size_t triangle_count = mesh.triangles.size();
  if (mesh.surfaces.size() != triangle_count) {
    return "has " + str(mesh.surfaces.size()) + " surface ids for " + str(triangle_count) + " triangles";
  }
  const std::array<std::pair<const char*, std::size_t>, 3> channels = {
      {{"normals", mesh.corners.normals.size()}, {"uvs", mesh.corners.uvs.size()}, {"tangents", mesh.corners.tangents.size()}}};
  for (const auto& [name, size] : channels) {
    if (size != 0 && size != 3 * triangle_count) {
      return std::string("has ") + str(size) + " " + name + " for " + str(triangle_count) + " triangles (need 0 or 3 per triangle)";
    }
  }
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (std::size_t corner = 0; corner < 3; ++corner) {
      const VertexIndex vertex = mesh.triangles[t][corner];
      if (vertex >= mesh.positions.size()) {
        return "triangle " + str(t) + " corner " + str(corner) + " has vertex index " + str(vertex) + ", but there are only " +
               str(mesh.positions.size()) + " vertices";
      }
    }
  }
  return std::nullopt;
}

/// The child of `node` whose leaf range holds `leaf`, or no_node.
NodeIndex child_holding(const std::vector<MeshTreeNode>& nodes, NodeIndex node, LeafIndex leaf) {
  for (const NodeIndex child : nodes[node].children) {
    if (leaf - nodes[child].first_leaf < nodes[child].leaf_count) return child;  // unsigned: also rejects leaf < first_leaf
  }
  return no_node;
}

/// Bonds in range, sorted, each between two leaves its cut_node's cut separates
/// (cut_node is their lowest common ancestor: both below it, under different
/// children). Requires a valid structure.
std::optional<Defect> bonds_defect(const MeshTree& tree) {
  const std::size_t leaf_count = tree.leaf_nodes.size();
  for (std::size_t i = 0; i < tree.bonds.size(); ++i) {
    const Bond& bond = tree.bonds[i];
    const std::string name = "bond " + str(i) + " (" + str(bond.first) + ", " + str(bond.second) + ", cut node " +
                             (bond.cut_node == no_node ? std::string("none") : str(bond.cut_node)) + ")";
    if (bond.first >= bond.second) return Defect{Part::bond, i, name + " does not have first < second"};
    if (bond.second >= leaf_count) return Defect{Part::bond, i, name + " names a leaf beyond the " + str(leaf_count) + " leaves"};
    if (bond.cut_node >= tree.nodes.size() || tree.nodes[bond.cut_node].is_leaf()) {
      return Defect{Part::bond, i, name + " does not name an internal node as its cut"};
    }
    const NodeIndex first_side = child_holding(tree.nodes, bond.cut_node, bond.first);
    const NodeIndex second_side = child_holding(tree.nodes, bond.cut_node, bond.second);
    if (first_side == no_node || second_side == no_node || first_side == second_side) {
      return Defect{Part::bond, i, name + " joins leaves that the cut of its cut node does not separate"};
    }
    if (i > 0) {
      const Bond& previous = tree.bonds[i - 1];
      if (std::tie(previous.first, previous.second, previous.cut_node) > std::tie(bond.first, bond.second, bond.cut_node)) {
        return Defect{Part::bond, i, name + " is out of order (bonds are sorted by first, second, cut node)"};
      }
    }
  }
  return std::nullopt;
}

std::optional<Defect> first_defect(const MeshTree& tree) {
  if (auto defect = options_defect(tree.options)) return defect;
  if (auto defect = structure_defect(tree.nodes)) return defect;
  if (auto defect = leaf_list_defect(tree)) return defect;
  for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
    if (auto problem = mesh_defect(tree.nodes[k].mesh)) return Defect{Part::mesh, k, "the mesh of node " + str(k) + " " + *problem};
    if (auto problem = mesh_defect(tree.nodes[k].hull)) return Defect{Part::hull, k, "the hull of node " + str(k) + " " + *problem};
  }
  return bonds_defect(tree);
}

// ---------------------------------------------------------------------------
// Encoding

class ByteWriter {
 public:
  void u8(std::uint8_t value) { bytes_.push_back(static_cast<char>(value)); }
  void u32(std::uint32_t value) {
    for (int k = 0; k < 4; ++k) u8(static_cast<std::uint8_t>(value >> (8 * k)));
  }
  void u64(std::uint64_t value) {
    for (int k = 0; k < 8; ++k) u8(static_cast<std::uint8_t>(value >> (8 * k)));
  }
  /// A count the validator has already checked to fit 32 bits.
  void count32(std::size_t value) { u32(static_cast<std::uint32_t>(value)); }
  void f64(double value) { u64(std::bit_cast<std::uint64_t>(value)); }
  void vec2(Vec2 v) {
    f64(v.x);
    f64(v.y);
  }
  void vec3(Vec3 v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
  }
  void vec4(Vec4 v) {
    f64(v.x);
    f64(v.y);
    f64(v.z);
    f64(v.w);
  }
  void tag(Tag tag) {
    for (const char c : tag) bytes_.push_back(c);
  }
  void append(std::string_view bytes) { bytes_.append(bytes); }

  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

std::string options_payload(const BuildOptions& options) {
  ByteWriter out;
  out.u32(options.fragments);
  out.u64(options.seed);
  out.u8(static_cast<std::uint8_t>(options.strategy));
  out.u8(static_cast<std::uint8_t>(options.kernel));
  out.f64(options.interior_uv_scale);
  out.u32(options.max_plane_tries);
  out.u8(options.allow_self_intersections ? 1 : 0);
  return out.take();
}

std::string nodes_payload(const std::vector<MeshTreeNode>& nodes) {
  ByteWriter out;
  out.count32(nodes.size());
  for (const MeshTreeNode& node : nodes) {
    out.u32(node.parent);
    out.u32(node.depth);
    out.u32(node.first_leaf);
    out.u32(node.leaf_count);
    out.u64(node.seed);
    out.u8(node.above_parent_plane ? 1 : 0);
    out.vec3(node.plane.normal);
    out.f64(node.plane.offset);
    out.f64(node.mass.volume);
    out.vec3(node.mass.centroid);
    for (const double entry : node.mass.inertia) out.f64(entry);
    out.count32(node.children.size());
    for (const NodeIndex child : node.children) out.u32(child);
  }
  return out.take();
}

void write_mesh_record(ByteWriter& out, const Mesh& mesh) {
  out.count32(mesh.positions.size());
  out.count32(mesh.triangles.size());
  out.u8(static_cast<std::uint8_t>((mesh.corners.has_normals() ? normals_bit : 0) | (mesh.corners.has_uvs() ? uvs_bit : 0) |
                                   (mesh.corners.has_tangents() ? tangents_bit : 0)));
  for (const Vec3& position : mesh.positions) out.vec3(position);
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex vertex : triangle) out.u32(vertex);
  }
  for (const SurfaceId surface : mesh.surfaces) out.u32(surface);
  for (const Vec3& normal : mesh.corners.normals) out.vec3(normal);
  for (const Vec2& uv : mesh.corners.uvs) out.vec2(uv);
  for (const Vec4& tangent : mesh.corners.tangents) out.vec4(tangent);
}

std::string meshes_payload(const std::vector<MeshTreeNode>& nodes, Mesh MeshTreeNode::*which) {
  ByteWriter out;
  out.count32(nodes.size());
  for (const MeshTreeNode& node : nodes) write_mesh_record(out, node.*which);
  return out.take();
}

std::string bonds_payload(const std::vector<Bond>& bonds) {
  ByteWriter out;
  out.u64(bonds.size());
  for (const Bond& bond : bonds) {
    out.u32(bond.first);
    out.u32(bond.second);
    out.u32(bond.cut_node);
    out.f64(bond.area);
    out.vec3(bond.centroid);
    out.vec3(bond.normal);
  }
  return out.take();
}

void append_section(ByteWriter& file, Tag tag, std::string_view payload) {
  file.tag(tag);
  file.u64(payload.size());
  file.u32(crc_of(payload));
  file.append(payload);
}

// ---------------------------------------------------------------------------
// Decoding: the section table

std::uint32_t load_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t value = 0;
  for (std::size_t k = 0; k < 4; ++k) value |= std::uint32_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
  return value;
}

std::uint64_t load_u64(std::string_view bytes, std::size_t at) {
  std::uint64_t value = 0;
  for (std::size_t k = 0; k < 8; ++k) value |= std::uint64_t{static_cast<unsigned char>(bytes[at + k])} << (8 * k);
  return value;
}

struct Section {
  Tag tag{};
  std::size_t offset = 0;          ///< of the section header in the file
  std::size_t payload_offset = 0;  ///< of the payload in the file
  std::string_view payload;
};

struct SectionTable {
  std::optional<Section> options, nodes, meshes, hulls, bonds;
};

void check_file_header(std::string_view bytes) {
  const std::size_t magic_bytes_present = std::min(bytes.size(), magic.size());
  for (std::size_t k = 0; k < magic_bytes_present; ++k) {
    if (static_cast<unsigned char>(bytes[k]) != magic[k]) {
      refuse("not a .shatter file: byte " + str(k) + " differs from the magic 89 53 48 54 0D 0A 1A 0A (\"\\x89SHT\\r\\n\\x1a\\n\")");
    }
  }
  if (bytes.size() < file_header_size) {
    refuse("truncated .shatter file: " + str(bytes.size()) + " bytes, shorter than the " + str(file_header_size) + "-byte header");
  }
  const std::uint32_t version = load_u32(bytes, magic.size());
  if (version != shatter_format_version) {
    refuse("unsupported .shatter format version " + str(version) + " at byte " + str(magic.size()) + " (this build reads version " +
           str(shatter_format_version) + (version > shatter_format_version ? ": the file is from a newer shatter, or damaged)" : ")"));
  }
}

/// Splits the file into its sections, checking every checksum, and keeps the
/// ones this version reads (see the reading rules in file.hpp).
SectionTable read_section_table(std::string_view bytes) {
  check_file_header(bytes);
  SectionTable table;
  const std::array<std::pair<Tag, std::optional<Section>*>, 5> known = {{{options_tag, &table.options},
                                                                         {nodes_tag, &table.nodes},
                                                                         {meshes_tag, &table.meshes},
                                                                         {hulls_tag, &table.hulls},
                                                                         {bonds_tag, &table.bonds}}};
  std::size_t position = file_header_size;
  while (true) {
    if (position == bytes.size()) refuse("truncated .shatter file: ends at byte " + str(position) + " without the END section");
    if (bytes.size() - position < section_header_size) {
      refuse("truncated .shatter file: ends at byte " + str(bytes.size()) + " inside the 16-byte section header at byte " + str(position));
    }
    Section section;
    std::copy_n(bytes.data() + position, section.tag.size(), section.tag.begin());
    section.offset = position;
    section.payload_offset = position + section_header_size;
    const std::uint64_t length = load_u64(bytes, position + 4);
    const std::uint32_t stored_crc = load_u32(bytes, position + 12);
    const std::size_t available = bytes.size() - section.payload_offset;
    if (length > available) {
      refuse("truncated .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " declares " + str(length) +
             " payload bytes, but only " + str(available) + " remain");
    }
    section.payload = bytes.substr(section.payload_offset, static_cast<std::size_t>(length));
    if (const std::uint32_t crc = crc_of(section.payload); crc != stored_crc) {
      refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " fails its checksum (stored " +
             hex(stored_crc, 8) + ", computed " + hex(crc, 8) + ")");
    }
    const std::size_t section_end = section.payload_offset + section.payload.size();

    if (section.tag == end_tag) {
      if (!section.payload.empty()) {
        refuse("damaged .shatter file: END section at byte " + str(position) + " has a " + str(length) + "-byte payload (must be empty)");
      }
      if (section_end != bytes.size()) {
        refuse("damaged .shatter file: " + str(bytes.size() - section_end) + " bytes follow the END section at byte " + str(position));
      }
      break;
    }
    const auto slot = std::find_if(known.begin(), known.end(), [&](const auto& entry) { return entry.first == section.tag; });
    if (slot != known.end()) {
      if (*slot->second) {
        refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " repeats the one at byte " +
               str((*slot->second)->offset));
      }
      *slot->second = section;
    } else if (!(section.tag[0] >= 'a' && section.tag[0] <= 'z')) {
      // Optional sections start with a lower-case letter; any other unknown tag
      // holds data this reader would misunderstand, or is damage.
      refuse("unsupported or damaged .shatter file: unknown section '" + tag_text(section.tag) + "' at byte " + str(position) +
             " (only tags starting with a lower-case letter may be skipped)");
    }
    position = section_end;
  }
  for (const auto& [tag, slot] : known) {
    if (!*slot) refuse("damaged .shatter file: no " + section_name(tag) + " section");
  }
  return table;
}

// ---------------------------------------------------------------------------
// Decoding: payloads

/// Reads one section's payload front to back. Every read is bounds-checked, and
/// every count is checked against the bytes left before anything is sized by it.
/// Failures name the section, the file offset and the record being read.
class PayloadReader {
 public:
  explicit PayloadReader(const Section& section) : payload_(section.payload), payload_offset_(section.payload_offset), tag_(section.tag) {}

  /// The file offset of the next byte.
  std::size_t offset() const { return payload_offset_ + position_; }
  std::size_t remaining() const { return payload_.size() - position_; }

  /// Names the record being read in failure messages ("node 3", ...).
  void set_record(std::string record) { record_ = std::move(record); }

  std::uint8_t u8(const char* field) {
    need(1, field);
    return static_cast<std::uint8_t>(payload_[position_++]);
  }
  std::uint32_t u32(const char* field) {
    need(4, field);
    const std::uint32_t value = load_u32(payload_, position_);
    position_ += 4;
    return value;
  }
  std::uint64_t u64(const char* field) {
    need(8, field);
    const std::uint64_t value = load_u64(payload_, position_);
    position_ += 8;
    return value;
  }
  double f64(const char* field) { return std::bit_cast<double>(u64(field)); }
  Vec2 vec2(const char* field) {
    need(16, field);
    Vec2 v;
    v.x = f64(field);
    v.y = f64(field);
    return v;
  }
  Vec3 vec3(const char* field) {
    need(24, field);
    Vec3 v;
    v.x = f64(field);
    v.y = f64(field);
    v.z = f64(field);
    return v;
  }
  Vec4 vec4(const char* field) {
    need(32, field);
    Vec4 v;
    v.x = f64(field);
    v.y = f64(field);
    v.z = f64(field);
    v.w = f64(field);
    return v;
  }
  bool boolean(const char* field) {
    const std::size_t at = offset();
    const std::uint8_t value = u8(field);
    if (value > 1) fail_at(at, std::string(field) + " is " + str(value) + " (must be 0 or 1)");
    return value == 1;
  }

  /// Refuses `count` records of at least `record_size` bytes each if they
  /// cannot fit in what is left, before the caller allocates for them.
  void check_room(std::uint64_t count, std::size_t record_size, const char* what) const {
    if (count > remaining() / record_size) {
      fail(str(count) + " " + what + " need at least " + str(record_size) + " bytes each, but only " + str(remaining()) + " bytes remain");
    }
  }

  void expect_end() const {
    if (remaining() != 0) fail(str(remaining()) + " unexpected bytes after the last record");
  }

  [[noreturn]] void fail(const std::string& problem) const { fail_at(offset(), problem); }
  [[noreturn]] void fail_at(std::size_t at, const std::string& problem) const {
    refuse("damaged .shatter file: " + section_name(tag_) + " section, byte " + str(at) + (record_.empty() ? "" : ", " + record_) + ": " + problem);
  }

 private:
  void need(std::size_t size, const char* field) const {
    if (remaining() < size) fail("the payload ends inside " + std::string(field));
  }

  std::string_view payload_;
  std::size_t payload_offset_;
  std::size_t position_ = 0;
  Tag tag_;
  std::string record_;
};

BuildOptions read_options(const Section& section) {
  PayloadReader in(section);
  BuildOptions options;
  options.fragments = in.u32("fragments");
  options.seed = in.u64("seed");
  const std::size_t strategy_at = in.offset();
  const std::uint8_t strategy = in.u8("strategy");
  if (strategy > last_strategy) in.fail_at(strategy_at, "strategy " + str(strategy) + " is unknown");
  options.strategy = static_cast<Strategy>(strategy);
  const std::size_t kernel_at = in.offset();
  const std::uint8_t kernel = in.u8("kernel");
  if (kernel > last_kernel) in.fail_at(kernel_at, "kernel " + str(kernel) + " is unknown");
  options.kernel = static_cast<KernelKind>(kernel);
  options.interior_uv_scale = in.f64("interior_uv_scale");
  options.max_plane_tries = in.u32("max_plane_tries");
  options.allow_self_intersections = in.boolean("allow_self_intersections");
  options.threads = 0;
  in.expect_end();
  static_assert(options_size == 27);
  return options;
}

/// Reads the nodes without their meshes; `record_offsets` gets each record's offset.
std::vector<MeshTreeNode> read_nodes(const Section& section, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t node_count = in.u32("the node count");
  if (node_count == 0) in.fail("node count 0 (a tree has at least its root)");
  in.check_room(node_count, node_record_min_size, "nodes");
  std::vector<MeshTreeNode> nodes(node_count);
  record_offsets.resize(node_count);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    MeshTreeNode& node = nodes[k];
    record_offsets[k] = in.offset();
    in.set_record("node " + str(k));
    node.parent = in.u32("parent");
    node.depth = in.u32("depth");
    node.first_leaf = in.u32("first_leaf");
    node.leaf_count = in.u32("leaf_count");
    node.seed = in.u64("seed");
    node.above_parent_plane = in.boolean("above_parent_plane");
    node.plane.normal = in.vec3("plane normal");
    node.plane.offset = in.f64("plane offset");
    node.mass.volume = in.f64("volume");
    node.mass.centroid = in.vec3("centroid");
    for (double& entry : node.mass.inertia) entry = in.f64("inertia");
    const std::uint32_t child_count = in.u32("child count");
    in.check_room(child_count, child_size, "children");
    node.children.resize(child_count);
    for (NodeIndex& child : node.children) child = in.u32("child");
  }
  in.set_record("");
  in.expect_end();
  return nodes;
}

Mesh read_mesh_record(PayloadReader& in) {
  Mesh mesh;
  const std::uint32_t vertex_count = in.u32("vertex count");
  const std::uint32_t triangle_count = in.u32("triangle count");
  const std::size_t channels_at = in.offset();
  const std::uint8_t channels = in.u8("channel flags");
  if ((channels & ~known_channel_bits) != 0) in.fail_at(channels_at, "unknown attribute channel bits " + hex(channels, 2));

  in.check_room(vertex_count, vertex_size, "vertices");
  mesh.positions.resize(vertex_count);
  for (Vec3& position : mesh.positions) position = in.vec3("position");

  in.check_room(triangle_count, triangle_size, "triangles");
  mesh.triangles.resize(triangle_count);
  for (Triangle& triangle : mesh.triangles) {
    for (VertexIndex& vertex : triangle) vertex = in.u32("triangle");
  }
  mesh.surfaces.resize(triangle_count);
  for (SurfaceId& surface : mesh.surfaces) surface = in.u32("surface id");

  const std::uint64_t corner_count = 3 * std::uint64_t{triangle_count};
  if ((channels & normals_bit) != 0) {
    in.check_room(corner_count, normal_size, "corner normals");
    mesh.corners.normals.resize(static_cast<std::size_t>(corner_count));
    for (Vec3& normal : mesh.corners.normals) normal = in.vec3("normal");
  }
  if ((channels & uvs_bit) != 0) {
    in.check_room(corner_count, uv_size, "corner uvs");
    mesh.corners.uvs.resize(static_cast<std::size_t>(corner_count));
    for (Vec2& uv : mesh.corners.uvs) uv = in.vec2("uv");
  }
  if ((channels & tangents_bit) != 0) {
    in.check_room(corner_count, tangent_size, "corner tangents");
    mesh.corners.tangents.resize(static_cast<std::size_t>(corner_count));
    for (Vec4& tangent : mesh.corners.tangents) tangent = in.vec4("tangent");
  }
  return mesh;
}

/// Reads one mesh per node into `which` of each node.
void read_meshes(const Section& section, std::vector<MeshTreeNode>& nodes, Mesh MeshTreeNode::*which, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t mesh_count = in.u32("the mesh count");
  if (mesh_count != nodes.size()) in.fail(str(mesh_count) + " meshes for " + str(nodes.size()) + " nodes");
  in.check_room(mesh_count, mesh_record_min_size, "meshes");
  record_offsets.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node " + str(k));
    nodes[k].*which = read_mesh_record(in);
  }
  in.set_record("");
  in.expect_end();
}

std::vector<Bond> read_bonds(const Section& section) {
  PayloadReader in(section);
  const std::uint64_t bond_count = in.u64("the bond count");
  in.check_room(bond_count, bond_size, "bonds");
  std::vector<Bond> bonds(static_cast<std::size_t>(bond_count));
  for (std::size_t i = 0; i < bonds.size(); ++i) {
    Bond& bond = bonds[i];
    in.set_record("bond " + str(i));
    bond.first = in.u32("first");
    bond.second = in.u32("second");
    bond.cut_node = in.u32("cut_node");
    bond.area = in.f64("area");
    bond.centroid = in.vec3("centroid");
    bond.normal = in.vec3("normal");
  }
  in.set_record("");
  in.expect_end();
  return bonds;
}

/// Where each record of a decoded tree came from, to place a defect in the file.
struct RecordOffsets {
  std::vector<std::size_t> nodes, meshes, hulls;
};

std::string located(const Defect& defect, const SectionTable& sections, const RecordOffsets& offsets) {
  Tag tag = nodes_tag;
  std::size_t at = sections.nodes->payload_offset;
  switch (defect.part) {
    case Part::options:
      tag = options_tag;
      at = sections.options->payload_offset;
      break;
    case Part::node:
      if (defect.index < offsets.nodes.size()) at = offsets.nodes[defect.index];
      break;
    case Part::leaf_list: break;  // recomputed by the reader, so never at fault
    case Part::mesh:
      tag = meshes_tag;
      at = offsets.meshes[defect.index];
      break;
    case Part::hull:
      tag = hulls_tag;
      at = offsets.hulls[defect.index];
      break;
    case Part::bond:
      tag = bonds_tag;
      at = sections.bonds->payload_offset + 8 + bond_size * defect.index;
      break;
  }
  return "invalid tree in .shatter file: " + section_name(tag) + " section, byte " + str(at) + ": " + defect.message;
}

std::string read_whole_file(const std::filesystem::path& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError("cannot open " + path.string() + ": " + std::strerror(errno));
  std::string bytes;
  std::array<char, 1 << 16> buffer;
  while (true) {
    const std::size_t read = std::fread(buffer.data(), 1, buffer.size(), file.get());
    bytes.append(buffer.data(), read);
    if (read < buffer.size()) break;
  }
  // A directory opens but fails to read (EISDIR).
  if (std::ferror(file.get())) throw IoError("cannot read " + path.string() + ": " + std::strerror(errno));
  return bytes;
}

}  // namespace

std::string encode_shatter(const MeshTree& tree) {
  if (const std::optional<Defect> defect = first_defect(tree)) {
    throw std::invalid_argument("encode_shatter: invalid tree: " + defect->message);
  }
  ByteWriter file;
  for (const unsigned char byte : magic) file.u8(byte);
  file.u32(shatter_format_version);
  append_section(file, options_tag, options_payload(tree.options));
  append_section(file, nodes_tag, nodes_payload(tree.nodes));
  append_section(file, meshes_tag, meshes_payload(tree.nodes, &MeshTreeNode::mesh));
  append_section(file, hulls_tag, meshes_payload(tree.nodes, &MeshTreeNode::hull));
  append_section(file, bonds_tag, bonds_payload(tree.bonds));
  append_section(file, end_tag, {});
  return file.take();
}

MeshTree decode_shatter(std::string_view bytes) {
  const SectionTable sections = read_section_table(bytes);
  MeshTree tree;
  RecordOffsets offsets;
  tree.options = read_options(*sections.options);
  tree.nodes = read_nodes(*sections.nodes, offsets.nodes);
  read_meshes(*sections.meshes, tree.nodes, &MeshTreeNode::mesh, offsets.meshes);
  read_meshes(*sections.hulls, tree.nodes, &MeshTreeNode::hull, offsets.hulls);
  tree.bonds = read_bonds(*sections.bonds);
  tree.leaf_nodes = leaves_in_order(tree.nodes);
  if (const std::optional<Defect> defect = first_defect(tree)) refuse(located(*defect, sections, offsets));
  return tree;
}

void write_shatter_file(const std::filesystem::path& path, const MeshTree& tree) { write_file_atomically(path, encode_shatter(tree)); }

MeshTree read_shatter_file(const std::filesystem::path& path) {
  const std::string bytes = read_whole_file(path);
  try {
    return decode_shatter(bytes);
  } catch (const CorruptFileError& error) {
    throw CorruptFileError(path.string() + ": " + error.what());
  }
}

}  // namespace shatter
