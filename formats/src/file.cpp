// The .shatter file (layout in file.hpp). The encoder writes every field byte by
// byte; the decoder checks every count against the bytes left before it
// allocates; and one validator, validate_tree, serves both, so whatever the
// encoder accepts the decoder accepts, and a decoded tree keeps every MeshTree
// invariant.

#include "shatter/formats/file.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <system_error>
#include <utility>
#include <vector>

#include "shatter/kernel/atomic_file.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/solid.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/meshtree/tree.hpp"
#include "shatter/meshtree/validate_tree.hpp"
#include "file_layout.hpp"

namespace shatter {

namespace {

using namespace file_layout;


// ---------------------------------------------------------------------------
// Decoding: the section table

/// Checks the magic and returns the version, one this reader knows.
std::uint32_t check_file_header(std::string_view bytes) {
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
  if (version < shatter_oldest_format_version || version > shatter_format_version) {
    refuse("unsupported .shatter format version " + str(version) + " at byte " + str(magic.size()) + " (this build reads versions " +
           str(shatter_oldest_format_version) + " to " + str(shatter_format_version) +
           (version > shatter_format_version ? ": the file is from a newer shatter, or damaged)" : ")"));
  }
  return version;
}

/// Splits the file into its sections, checking every checksum, and keeps the
/// ones this version reads (see the reading rules in file.hpp).
SectionTable read_section_table(std::string_view bytes) {
  SectionTable table;
  table.version = check_file_header(bytes);
  // Version 1 knows the first five; GEOM and SOLD are unknown tags there.
  const std::array<std::pair<Tag, std::optional<Section>*>, 7> all_known = {{{recipe_tag, &table.recipe},
                                                                             {nodes_tag, &table.nodes},
                                                                             {meshes_tag, &table.meshes},
                                                                             {hulls_tag, &table.hulls},
                                                                             {bonds_tag, &table.bonds},
                                                                             {geometry_tag, &table.geometry},
                                                                             {solids_tag, &table.solids}}};
  const std::span<const std::pair<Tag, std::optional<Section>*>> known(all_known.data(), table.version == 1 ? 5 : 7);
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
    if (section.tag == cell_planes_tag && table.version >= 3) {
      if (table.cell_planes) {
        refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " repeats the one at byte " +
               str(table.cell_planes->offset));
      }
      table.cell_planes = section;
    } else if (section.tag == version_tag || section.tag == repair_tag || section.tag == pattern_tag) {
      std::optional<Section>& slot_of_optional = section.tag == version_tag  ? table.shatter_version
                                                 : section.tag == repair_tag ? table.input_repair
                                                                             : table.pattern;
      if (slot_of_optional) {
        refuse("damaged .shatter file: " + section_name(section.tag) + " section at byte " + str(position) + " repeats the one at byte " +
               str(slot_of_optional->offset));
      }
      slot_of_optional = section;
    } else if (slot != known.end()) {
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


TreeRecipe read_recipe(const Section& section) {
  PayloadReader in(section);
  TreeRecipe recipe;
  recipe.fragments = in.u32("fragments");
  recipe.seed = in.u64("seed");
  const std::size_t strategy_at = in.offset();
  const std::uint8_t strategy = in.u8("strategy");
  if (strategy > static_cast<std::uint8_t>(last_strategy)) in.fail_at(strategy_at, "strategy " + str(strategy) + " is unknown");
  recipe.strategy = static_cast<Strategy>(strategy);
  const std::size_t kernel_at = in.offset();
  const std::uint8_t kernel = in.u8("kernel");
  if (kernel > static_cast<std::uint8_t>(last_kernel)) in.fail_at(kernel_at, "kernel " + str(kernel) + " is unknown");
  recipe.kernel = static_cast<KernelKind>(kernel);
  recipe.interior_uv_scale = in.f64("interior_uv_scale");
  recipe.max_plane_tries = in.u32("max_plane_tries");
  recipe.allow_self_intersections = in.boolean("allow_self_intersections");
  in.expect_end();
  static_assert(recipe_size == 27);
  return recipe;
}

/// Reads the nodes without their meshes, and their cut planes into
/// tree.cut_planes; `record_offsets` gets each record's offset.
void read_nodes(const Section& section, MeshTree& tree, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t node_count = in.u32("the node count");
  if (node_count == 0) in.fail("node count 0 (a tree has at least its root)");
  in.check_room(node_count, node_record_min_size, "nodes");
  std::vector<MeshTreeNode>& nodes = tree.nodes;
  nodes.resize(node_count);
  tree.cut_planes.resize(node_count);
  record_offsets.resize(node_count);
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    MeshTreeNode& node = nodes[k];
    record_offsets[k] = in.offset();
    in.set_record("node", k);
    node.parent = in.u32("parent");
    node.depth = in.u32("depth");
    node.first_leaf = in.u32("first_leaf");
    node.leaf_count = in.u32("leaf_count");
    node.seed = in.u64("seed");
    node.above_parent_plane = in.boolean("above_parent_plane");
    tree.cut_planes[k].normal = in.vec3("plane normal");
    tree.cut_planes[k].offset = in.f64("plane offset");
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
}

Mesh read_mesh_record(PayloadReader& in) {
  Mesh mesh;
  const std::uint32_t vertex_count = in.u32("vertex count");
  const std::uint32_t triangle_count = in.u32("triangle count");
  const std::uint8_t channels = read_channel_flags(in, triangle_count);

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

  read_corner_channels(in, channels, triangle_count, mesh);
  return mesh;
}

/// Reads one mesh per node into each node's mesh, or its hull when `hulls`.
void read_meshes(const Section& section, std::vector<MeshTreeNode>& nodes, bool hulls, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t mesh_count = in.u32("the mesh count");
  if (mesh_count != nodes.size()) in.fail(str(mesh_count) + " meshes for " + str(nodes.size()) + " nodes");
  in.check_room(mesh_count, mesh_record_min_size, "meshes");
  record_offsets.resize(nodes.size());
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node", k);
    Mesh mesh = read_mesh_record(in);
    if (!hulls) {
      nodes[k].mesh = std::move(mesh);
    } else if (!mesh.positions.empty() || !mesh.triangles.empty()) {
      nodes[k].hull = std::move(mesh);  // a convex node's stays absent (Boxed)
    }
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
    in.set_record("bond", i);
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

InputGeometry read_geometry(const Section& section) {
  PayloadReader in(section);
  InputGeometry geometry;
  const std::uint32_t point_count = in.u32("the point count");
  const std::uint32_t plane_count = in.u32("the input plane count");
  in.check_room(point_count, point_size, "input points");
  geometry.points.resize(point_count);
  for (Vec3& point : geometry.points) point = in.vec3("input point");
  in.check_room(plane_count, input_plane_size, "input planes");
  geometry.planes.resize(plane_count);
  for (auto& plane : geometry.planes) {
    for (VertexIndex& point : plane) point = in.u32("input plane");
  }
  in.expect_end();
  return geometry;
}

/// Reads each node's exact solid and convex flag; `exact`: GEOM holds input
/// points, so there is one record per node (else none). Faces' first loops and
/// loops' first corners are the running sums of the counts before them.
void read_solids(const Section& section, std::vector<MeshTreeNode>& nodes, bool exact, std::vector<std::size_t>& record_offsets) {
  PayloadReader in(section);
  const std::uint32_t record_count = in.u32("the solid count");
  if (!exact && record_count != 0) {
    in.fail(str(record_count) + " solids, but GEOM holds no input points (a tree without an exact representation stores none)");
  }
  if (exact && record_count != nodes.size()) in.fail(str(record_count) + " solids for " + str(nodes.size()) + " nodes");
  in.check_room(record_count, solid_record_min_size, "solids");
  record_offsets.resize(record_count);
  for (std::size_t k = 0; k < record_count; ++k) {
    record_offsets[k] = in.offset();
    in.set_record("node", k);
    MeshTreeNode& node = nodes[k];
    Solid& solid = *node.solid;
    read_solid_flags(in, node);
    const std::uint32_t vertex_count = in.u32("vertex count");
    const std::uint32_t face_count = in.u32("face count");
    const std::uint32_t loop_count = in.u32("loop count");
    const std::uint32_t corner_count = in.u32("corner count");

    in.check_room(vertex_count, point_def_size, "vertex definitions");
    solid.defs.resize(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
      PointDef& def = solid.defs[v];
      def.kind = read_point_kind(in, v);
      // Fields a kind does not use land where the validator refuses non-zero ones.
      if (def.kind == PointKind::three_planes) {
        for (PlaneRef& plane : def.planes) plane.bits = in.u32("vertex plane");
      } else {
        def.a = in.u32("vertex point");
        def.b = in.u32("vertex point");
        def.planes[0].bits = in.u32("vertex plane");
      }
    }

    in.check_room(face_count, face_size, "faces");
    solid.faces.resize(face_count);
    std::uint64_t next_loop = 0;
    for (SolidFace& face : solid.faces) {
      face.plane.bits = in.u32("face plane");
      read_face_flags(in, face);
      face.surface = in.u32("face surface");
      face.source = in.u32("face source");
      const std::size_t count_at = in.offset();
      face.loop_count = in.u32("face loop count");
      face.first_loop = next_range(in, count_at, face.loop_count, next_loop, loop_count, "faces", "loops");
    }

    in.check_room(loop_count, loop_size, "loops");
    solid.loops.resize(loop_count);
    std::uint64_t next_corner = 0;
    for (SolidLoop& loop : solid.loops) {
      const std::size_t count_at = in.offset();
      loop.corner_count = in.u32("loop corner count");
      loop.first_corner = next_range(in, count_at, loop.corner_count, next_corner, corner_count, "loops", "corners");
    }

    in.check_room(corner_count, corner_min_size, "corners");
    solid.corners.resize(corner_count);
    for (std::size_t c = 0; c < corner_count; ++c) {
      SolidCorner& corner = solid.corners[c];
      corner.vertex = in.u32("corner vertex");
      corner.line.other.bits = in.u32("corner line plane");
      const std::size_t segment_at = in.offset();
      const bool segment = in.boolean("corner segment flag");
      if (segment) {
        in.need(segment_size, "corner segment");
        corner.line.p = in.u32("corner segment");
        corner.line.q = in.u32("corner segment");
        // A segment of two "none" points would come back as no segment (flag 0).
        if (corner.line.p == no_index) in.fail_at(segment_at, "corner " + str(c) + " has a segment flag, but its segment is none");
      }
    }
  }
  in.set_record("");
  in.expect_end();
}


std::string located(const TreeDefect& defect, const SectionTable& sections, const RecordOffsets& offsets) {
  Tag tag = nodes_tag;
  std::size_t at = sections.nodes->payload_offset;
  switch (defect.part) {
    case TreePart::recipe:
      tag = recipe_tag;
      at = sections.recipe->payload_offset;
      break;
    case TreePart::node:
    case TreePart::leaf_range:
    case TreePart::cut_planes:  // each node's record holds its plane
      if (defect.index < offsets.nodes.size()) at = offsets.nodes[defect.index];
      break;
    case TreePart::leaf_list: break;  // recomputed by the reader, so never at fault
    case TreePart::mesh:
      tag = meshes_tag;
      at = offsets.meshes[defect.index];
      break;
    case TreePart::hull:
      tag = hulls_tag;
      at = offsets.hulls[defect.index];
      break;
    case TreePart::bond:
      tag = bonds_tag;
      at = defect.index < offsets.bonds.size() ? offsets.bonds[defect.index]
                                               : sections.bonds->payload_offset + 8 + bond_size * defect.index;
      break;
    // The exact representation's parts exist only in version 2 files.
    case TreePart::input_point:
    case TreePart::input_plane:
      if (sections.geometry) {
        tag = geometry_tag;
        at = sections.geometry->payload_offset;
        if (defect.part == TreePart::input_point) at += geometry_header_size + point_size * defect.index;
        if (defect.part == TreePart::input_plane) {
          at += geometry_header_size + point_size * offsets.point_count + input_plane_size * defect.index;
        }
      }
      break;
    case TreePart::solid:
      if (sections.solids) {
        tag = solids_tag;
        at = defect.index < offsets.solids.size() ? offsets.solids[defect.index] : sections.solids->payload_offset;
      }
      break;
  }
  return "invalid tree in .shatter file: " + section_name(tag) + " section, byte " + str(at) + ": " + defect.message;
}

std::string read_whole_file(const std::filesystem::path& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError("cannot open " + path.string() + ": " + std::strerror(errno));
  std::string bytes;
  // Sized once from the file's size (read to its end all the same, should it
  // change): grown by doubling, a 41 MB file was copied and faulted in twice over.
  std::error_code size_unknown;
  const std::uintmax_t size = std::filesystem::file_size(path, size_unknown);
  if (!size_unknown && size < bytes.max_size()) bytes.reserve(static_cast<std::size_t>(size) + 1);
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

namespace {

/// Refuses, before any byte is written, a tree encode_shatter cannot write.
/// Returns whether every node's mass is known to be mass_properties of its
/// mesh (a certificate that holds says so), which spares the writer
/// recomputing them.
bool check_before_writing(const MeshTree& tree) {
  // A tree whose certificate still holds (validate_tree.hpp, certificate_holds:
  // made by the code that built or checked it, and the tree's content digest
  // unchanged since) passes validate_tree by what that code established; any
  // other tree, one assembled by hand or changed since, is checked in full
  // here. Either way no file is written that the reader would refuse.
  const bool certified = certificate_holds(tree);
  if (!certified) {
    if (const TreeValidationReport report = validate_tree(tree); !report.valid()) {
      throw std::invalid_argument("encode_shatter: invalid tree: " + report.defect->message);
    }
  }
  if (!tree.shatter_version.empty()) {
    if (const std::optional<std::string> problem = version_text_problem(tree.shatter_version)) {
      throw std::invalid_argument("encode_shatter: invalid tree: shatter_version: " + *problem);
    }
  }
  if (!tree.recipe.pattern.empty()) {
    if (const std::optional<std::string> problem = pattern_text_problem(tree.recipe.pattern)) {
      throw std::invalid_argument("encode_shatter: invalid tree: recipe.pattern: " + *problem);
    }
  }
  for (const RepairChange& change : tree.input_repair.changes) {
    if (const std::optional<std::string> problem = repair_text_problem(change.text)) {
      throw std::invalid_argument("encode_shatter: invalid tree: input_repair: " + *problem);
    }
  }
  for (const RepairNote& note : tree.input_repair.notes) {
    if (const std::optional<std::string> problem = repair_text_problem(note.text)) {
      throw std::invalid_argument("encode_shatter: invalid tree: input_repair: " + *problem);
    }
  }
  return certified && tree.certificate.masses_derived();
}

/// The file's bytes handed to `append`, a section at a time. With `overwrite`,
/// a payload goes out in pieces as it is made (ByteWriter's flush), after a
/// header holding a zero length and checksum that is replaced once they are
/// known: the file is then never held more than a piece at a time. Without it,
/// each payload is held, in pieces, until its header is written.
/// `masses_derived`: what check_before_writing returned.
void write_checked_shatter(const MeshTree& tree, bool masses_derived, const ByteSink& append,
                           const std::function<void(std::uint64_t, std::string_view)>& overwrite) {
  std::uint64_t written = 0;
  const auto out = [&](std::string_view bytes) {
    append(bytes);
    written += bytes.size();
  };
  ByteWriter header;
  for (const unsigned char byte : magic) header.u8(byte);
  header.u32(shatter_format_version);
  out(header.take());
  const auto section_header = [](Tag tag, std::uint64_t size, std::uint32_t crc) {
    ByteWriter bytes;
    bytes.tag(tag);
    bytes.u64(size);
    bytes.u32(crc);
    return bytes.take();
  };
  write_version3_sections(tree, masses_derived, [&](Tag tag, const SectionPayload& payload) {
    std::uint64_t size = 0;
    std::uint32_t crc = 0;
    if (overwrite) {
      const std::uint64_t header_at = written;
      out(section_header(tag, 0, 0));
      const auto piece_out = [&](std::string_view piece) {
        if (piece.empty()) return;
        size += piece.size();
        crc = crc_of(piece, crc);
        out(piece);
      };
      ByteWriter streamed(piece_out);
      payload(streamed);
      for (const std::string& rest : streamed.take_pieces()) piece_out(rest);
      overwrite(header_at, section_header(tag, size, crc));
      return;
    }
    ByteWriter held;
    payload(held);
    std::vector<std::string> pieces = held.take_pieces();
    for (const std::string& piece : pieces) {
      size += piece.size();
      crc = crc_of(piece, crc);
    }
    out(section_header(tag, size, crc));
    // Each piece is freed once written, so the section shrinks as it goes out.
    for (std::string& piece : pieces) {
      if (!piece.empty()) out(piece);
      std::string().swap(piece);
    }
  });
}

}  // namespace

void write_shatter(const MeshTree& tree, const ByteSink& sink) {
  const bool masses_derived = check_before_writing(tree);
  write_checked_shatter(tree, masses_derived, sink, {});
}

void write_shatter(const MeshTree& tree, const RewritableSink& sink) {
  const bool masses_derived = check_before_writing(tree);
  write_checked_shatter(tree, masses_derived, sink.append, sink.overwrite);
}

std::string encode_shatter(const MeshTree& tree) {
  std::string bytes;
  write_shatter(tree, RewritableSink{[&](std::string_view piece) { bytes.append(piece); },
                                     [&](std::uint64_t offset, std::string_view piece) {
                                       bytes.replace(static_cast<std::size_t>(offset), piece.size(), piece);
                                     }});
  return bytes;
}

MeshTree decode_shatter(std::string_view bytes) {
  const SectionTable sections = read_section_table(bytes);
  MeshTree tree;
  RecordOffsets offsets;
  if (const std::optional<Section>& version = sections.shatter_version) {
    if (const std::optional<std::string> problem = version_text_problem(version->payload)) {
      refuse("damaged .shatter file: " + section_name(version_tag) + " section at byte " + str(version->offset) + ": " + *problem);
    }
    tree.shatter_version = version->payload;
  }
  if (sections.input_repair) tree.input_repair = read_repair(*sections.input_repair);
  tree.recipe = read_recipe(*sections.recipe);
  if (const std::optional<Section>& pattern = sections.pattern) {
    if (const std::optional<std::string> problem = pattern_text_problem(pattern->payload)) {
      refuse("damaged .shatter file: " + section_name(pattern_tag) + " section at byte " + str(pattern->offset) + ": " + *problem);
    }
    tree.recipe.pattern = pattern->payload;
  }
  Version3Pending pending;
  if (sections.version >= 3) {
    read_version3_nodes(*sections.nodes, tree, pending, offsets);
    if (sections.cell_planes) read_cell_planes(*sections.cell_planes, tree);
    tree.geometry = read_geometry(*sections.geometry);
    offsets.point_count = tree.geometry.points.size();
    read_version3_shapes(sections, tree, pending, offsets);
  } else {
    read_nodes(*sections.nodes, tree, offsets.nodes);
    read_meshes(*sections.meshes, tree.nodes, false, offsets.meshes);
    read_meshes(*sections.hulls, tree.nodes, true, offsets.hulls);
    tree.bonds = read_bonds(*sections.bonds);
    if (sections.version >= 2) {
      tree.geometry = read_geometry(*sections.geometry);
      offsets.point_count = tree.geometry.points.size();
      read_solids(*sections.solids, tree.nodes, !tree.geometry.points.empty(), offsets.solids);
    }
    tree.leaf_nodes = leaves_in_order(tree.nodes);
  }
  // The caches are not stored: the structure is checked without them, then they are computed.
  if (const std::optional<TreeDefect> defect = validate_tree(tree, {.caches = false}).defect) {
    refuse(located(*defect, sections, offsets));
  }
  if (const std::optional<TreeDefect> defect = fill_tree_caches(tree)) refuse(located(*defect, sections, offsets));
  if (sections.version >= 3) finish_version3(tree, pending);
  return tree;
}

void write_shatter_file(const std::filesystem::path& path, const MeshTree& tree) {
  write_file_atomically_rewritable(path, [&](const RewritableSink& sink) { write_shatter(tree, sink); });
}

MeshTree read_shatter_file(const std::filesystem::path& path) {
  const std::string bytes = read_whole_file(path);
  try {
    return decode_shatter(bytes);
  } catch (const CorruptFileError& error) {
    throw CorruptFileError(path.string() + ": " + error.what());
  }
}

namespace file_layout {

std::optional<std::string> repair_text_problem(std::string_view text) {
  if (text.empty()) return "a repair text is empty";
  if (text.size() > max_repair_text_size) {
    return "a repair text is " + str(text.size()) + " bytes long (at most " + str(max_repair_text_size) + ")";
  }
  for (std::size_t k = 0; k < text.size(); ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c < 0x20 || c == 0x7F) return "byte " + str(k) + " of a repair text is " + hex(c, 2) + " (a control character)";
  }
  return std::nullopt;
}

std::string repair_payload(const RepairReport& report) {
  ByteWriter out;
  out.u64(report.vertices_before);
  out.u64(report.triangles_before);
  out.u64(report.vertices_after);
  out.u64(report.triangles_after);
  const auto text = [&](const std::string& line) {
    out.count32(line.size());
    out.append(line);
  };
  out.count32(report.changes.size());
  for (const RepairChange& change : report.changes) {
    const auto kind = std::find(all_repair_kinds.begin(), all_repair_kinds.end(), change.kind);
    out.u8(static_cast<std::uint8_t>(kind - all_repair_kinds.begin()));
    out.u64(change.count);
    text(change.text);
  }
  out.count32(report.notes.size());
  for (const RepairNote& note : report.notes) text(note.text);
  return out.take();
}

RepairReport read_repair(const Section& section) {
  PayloadReader in(section);
  RepairReport report;
  report.vertices_before = in.u64("the vertex count before");
  report.triangles_before = in.u64("the triangle count before");
  report.vertices_after = in.u64("the vertex count after");
  report.triangles_after = in.u64("the triangle count after");
  const auto text = [&](const char* field) {
    const std::uint32_t length = in.u32(field);
    const std::size_t at = in.offset();
    in.check_room(length, 1, "text bytes");
    std::string line;
    line.reserve(length);
    for (std::uint32_t k = 0; k < length; ++k) line.push_back(static_cast<char>(in.u8(field)));
    if (const std::optional<std::string> problem = repair_text_problem(line)) in.fail_at(at, *problem);
    return line;
  };
  const std::uint32_t change_count = in.u32("the change count");
  in.check_room(change_count, 13, "changes");
  for (std::uint32_t k = 0; k < change_count; ++k) {
    in.set_record("change", k);
    const std::size_t at = in.offset();
    const std::uint8_t kind = in.u8("the change kind");
    if (kind >= all_repair_kinds.size()) in.fail_at(at, "unknown repair kind " + str(kind));
    RepairChange change{all_repair_kinds[kind], 0, {}};
    change.count = in.u64("the change count");
    change.text = text("the change text");
    report.changes.push_back(std::move(change));
  }
  in.set_record("");
  const std::uint32_t note_count = in.u32("the note count");
  in.check_room(note_count, 4, "notes");
  for (std::uint32_t k = 0; k < note_count; ++k) {
    in.set_record("note", k);
    report.notes.push_back({text("the note text")});
  }
  in.expect_end();
  if (report.empty()) in.fail("no change and no note (a tree built as read has no rpar section)");
  return report;
}

}  // namespace file_layout

}  // namespace shatter
