// Fuzz target: the .shatter reader (meshtree/include/shatter/formats/file.hpp).
// Properties: hostile bytes are refused with CorruptFileError only; a decoded tree
// keeps the invariants decode_shatter promises (the exact representation's
// cross-references and caches included), encodes without complaint, and
// re-encoding is a fixed point (decode(encode(t)) encodes to the same bytes).
// Files of every version are written back as version 3, whose varints may be
// written longer than needed and whose positions may name any source of the
// same bits, so the input's own bytes are not expected back; the unit tests
// check that a file encode_shatter wrote comes back byte for byte. Each input is
// tried as it is and with its section checksums repaired.

#include <cstdint>
#include <string>
#include <typeinfo>

#include <zlib.h>

#include "fuzz_support.hpp"
#include "shatter/meshtree/bonds.hpp"
#include "shatter/formats/file.hpp"

namespace {

using shatter::fuzz::fail;
using shatter::fuzz::require;

/// Decodes `bytes`, or returns false when they are refused with CorruptFileError;
/// any other exception aborts.
bool try_decode(std::string_view bytes, shatter::MeshTree& tree, const char* what) {
  try {
    tree = shatter::decode_shatter(bytes);
    return true;
  } catch (const shatter::CorruptFileError&) {
    return false;
  } catch (const std::exception& error) {
    fail(std::string(what) + ": unexpected " + typeid(error).name() + ": " + error.what());
  }
}

/// Encodes a decoded tree; decode_shatter's guarantee is encode_shatter's
/// precondition, so any exception is a broken promise.
std::string encode_or_fail(const shatter::MeshTree& tree, const char* what) {
  try {
    return shatter::encode_shatter(tree);
  } catch (const std::exception& error) {
    fail(std::string(what) + ": encode_shatter threw " + typeid(error).name() + ": " + error.what());
  }
}

/// The little-endian u64 at `offset`. Precondition: 8 bytes are there.
std::uint64_t read_u64(std::string_view bytes, std::size_t offset) {
  std::uint64_t value = 0;
  for (int k = 7; k >= 0; --k) value = (value << 8) | static_cast<unsigned char>(bytes[offset + k]);
  return value;
}

/// The exact representation's cross-references (a cheap subset of what the
/// reader checks: the indices an out-of-bounds access would follow) and caches.
void check_exact_invariants(const shatter::MeshTree& tree) {
  const shatter::InputGeometry& geometry = tree.geometry;
  require(geometry.plane_approx.size() == geometry.planes.size(), "decoded plane_approx not sized");
  // Every decoded tree, of any kernel, holds one cut plane per node.
  require(tree.cut_planes.size() == tree.nodes.size(), "decoded cut_planes not one per node");
  if (geometry.points.empty()) {
    require(geometry.planes.empty(), "decoded exact representation without input points");
    for (const shatter::MeshTreeNode& node : tree.nodes) {
      require(node.solid->defs.empty() && node.solid->faces.empty() && !node.convex, "decoded solid without input points");
    }
    return;
  }
  for (const auto& plane : geometry.planes) {
    for (const shatter::VertexIndex p : plane) require(p < geometry.points.size(), "decoded input plane point out of range");
  }
  const auto plane_ok = [&](shatter::PlaneRef plane, std::size_t node) {
    return plane.is_cut() ? plane.index() < node && !tree.nodes[plane.index()].is_leaf() : plane.index() < geometry.planes.size();
  };
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {
    const shatter::MeshTreeNode& node = tree.nodes[n];
    const shatter::Solid& solid = node.solid;
    require(!node.convex || node.hull->positions.empty(), "decoded convex node with a hull");
    require(solid.approx.size() == solid.defs.size(), "decoded approx not one per vertex");
    for (const shatter::PointDef& def : solid.defs) {
      if (def.kind == shatter::PointKind::input) require(def.a < geometry.points.size(), "decoded input vertex out of range");
      if (def.kind == shatter::PointKind::segment_plane) {
        require(def.a < geometry.points.size() && def.b < geometry.points.size() && plane_ok(def.planes[0], n), "decoded segment_plane vertex out of range");
      }
      if (def.kind == shatter::PointKind::three_planes) {
        for (const shatter::PlaneRef plane : def.planes) require(plane_ok(plane, n), "decoded three_planes vertex out of range");
      }
      require(static_cast<std::uint8_t>(def.kind) <= 2, "decoded vertex kind out of range");
    }
    for (const shatter::SolidFace& face : solid.faces) {
      require(plane_ok(face.plane, n), "decoded face plane out of range");
      require(face.loop_count >= 1 && std::uint64_t{face.first_loop} + face.loop_count <= solid.loops.size(), "decoded face loops out of range");
    }
    for (const shatter::SolidLoop& loop : solid.loops) {
      require(loop.corner_count >= 3 && std::uint64_t{loop.first_corner} + loop.corner_count <= solid.corners.size(), "decoded loop corners out of range");
    }
    for (const shatter::SolidCorner& corner : solid.corners) {
      require(corner.vertex < solid.defs.size(), "decoded corner vertex out of range");
      require(corner.line.other.bits == shatter::no_index || plane_ok(corner.line.other, n), "decoded corner line plane out of range");
      require(corner.line.p == shatter::no_index ? corner.line.q == shatter::no_index : corner.line.p < corner.line.q && corner.line.q < geometry.points.size(),
              "decoded corner segment out of range");
    }
  }
}

/// Checks the cross-references decode_shatter promises the rest of the library
/// can trust (a cheap subset: the ones an out-of-bounds access would follow).
void check_tree_invariants(const shatter::MeshTree& tree) {
  require(!tree.nodes.empty(), "decoded tree has no node");
  require(tree.nodes[0].parent == shatter::no_node, "decoded root has a parent");
  for (std::size_t n = 0; n < tree.nodes.size(); ++n) {
    const shatter::MeshTreeNode& node = tree.nodes[n];
    for (const shatter::NodeIndex child : node.children) {
      require(child < tree.nodes.size() && tree.nodes[child].parent == n, "decoded child link broken at node " + std::to_string(n));
    }
    for (const shatter::Mesh* mesh : {&*node.mesh, &*node.hull}) {
      require(mesh->surfaces.size() == mesh->triangles.size(), "decoded surfaces size");
      for (const shatter::Triangle& triangle : mesh->triangles) {
        for (const shatter::VertexIndex v : triangle) require(v < mesh->positions.size(), "decoded triangle index out of range");
      }
    }
  }
  for (const shatter::NodeIndex leaf : tree.leaf_nodes) {
    require(leaf < tree.nodes.size() && tree.nodes[leaf].is_leaf(), "decoded leaf_nodes entry is not a leaf");
  }
  for (const shatter::Bond& bond : tree.bonds) {
    require(bond.first < bond.second && bond.second < tree.leaf_count(), "decoded bond leaves out of order or range");
    require(bond.cut_node < tree.nodes.size(), "decoded bond cut node out of range");
  }
  check_exact_invariants(tree);
}

/// The bytes with every section's CRC-32 field set to its payload's checksum, as
/// far as the section headers can be followed. A mutated file almost never keeps
/// valid checksums, so without this the fuzzer would hardly get past them to the
/// structure checks behind them.
std::string with_checksums_repaired(std::string_view bytes) {
  std::string repaired(bytes);
  std::size_t offset = 12;
  while (offset <= repaired.size() && repaired.size() - offset >= 16) {
    const std::uint64_t length = read_u64(repaired, offset + 4);
    if (length > repaired.size() - offset - 16) break;
    const auto* payload = reinterpret_cast<const Bytef*>(repaired.data() + offset + 16);
    const auto checksum = static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0), payload, static_cast<uInt>(length)));
    for (int k = 0; k < 4; ++k) repaired[offset + 12 + k] = static_cast<char>((checksum >> (8 * k)) & 0xFF);
    offset += 16 + static_cast<std::size_t>(length);
  }
  return repaired;
}

/// Checks every property on one candidate file (see the top of this file).
void check_decoding(std::string_view bytes) {
  shatter::MeshTree tree;
  if (!try_decode(bytes, tree, "decode_shatter of the input")) return;
  check_tree_invariants(tree);
  const std::string encoded = encode_or_fail(tree, "first re-encoding");
  shatter::MeshTree again;
  require(try_decode(encoded, again, "decode_shatter of a re-encoded tree"),
          "decode_shatter refused bytes encode_shatter wrote");
  require(encode_or_fail(again, "second re-encoding") == encoded, "re-encoding a decoded tree is not a fixed point");
}

}  // namespace

/// libFuzzer's entry point: one input, decoded as a .shatter file as it is
/// (checksum checks included) and with its checksums repaired.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes = shatter::fuzz::as_bytes(data, size);
  check_decoding(bytes);
  const std::string repaired = with_checksums_repaired(bytes);
  if (repaired != bytes) check_decoding(repaired);
  return 0;
}
