// Fuzz target: the .shatter reader (meshtree/include/shatter/meshtree/file.hpp).
// Properties: hostile bytes are refused with CorruptFileError only; a decoded tree
// keeps the invariants decode_shatter promises, encodes without complaint, and
// re-encoding is a fixed point (decode(encode(t)) encodes to the same bytes); when
// the input is laid out as encode_shatter lays a file out (its five sections in
// order, then END, nothing optional), re-encoding gives the input back byte for byte.
// Each input is tried as it is and with its section checksums repaired.

#include <array>
#include <cstring>
#include <string>
#include <typeinfo>

#include <zlib.h>

#include "fuzz_support.hpp"
#include "shatter/meshtree/file.hpp"

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

/// True when the sections of an accepted file are exactly those encode_shatter
/// writes, in its order: OPTS NODE MESH HULL BOND END. Only then can the bytes
/// be expected back from re-encoding (optional sections are skipped by the
/// reader, and the reader accepts the required ones in any order).
bool has_canonical_layout(std::string_view bytes) {
  static constexpr std::array<const char*, 6> order = {"OPTS", "NODE", "MESH", "HULL", "BOND", "END "};
  std::size_t offset = 12;
  for (const char* tag : order) {
    if (bytes.size() - offset < 16) return false;
    if (std::memcmp(bytes.data() + offset, tag, 4) != 0) return false;
    const std::uint64_t length = read_u64(bytes, offset + 4);
    if (length > bytes.size() - offset - 16) return false;
    offset += 16 + static_cast<std::size_t>(length);
  }
  return offset == bytes.size();
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
    for (const shatter::Mesh* mesh : {&node.mesh, &node.hull}) {
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
  if (has_canonical_layout(bytes)) {
    require(encoded == bytes, "a file in encode_shatter's layout does not re-encode to the same bytes");
  }
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
