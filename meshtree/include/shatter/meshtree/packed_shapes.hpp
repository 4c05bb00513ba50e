#pragma once
// Where a lean build (BuildRunOptions::lean) keeps its nodes' packed meshes and
// solids (packed_node.hpp): the bytes of every node in a few large blocks, and
// one view per node into them. Two million small arrays of a million-fragment
// tree cost a 24-byte header each and the allocator's rounding of each size up
// to its class (some 0.12 GB at cube -> 2^20, README "Lean memory"); blocks
// cost neither.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

namespace shatter {

/// Bytes copied into blocks that never move: what append returns stays valid
/// as long as the blocks live (moving them moves no byte). Nothing is freed
/// before the whole is. Not thread-safe: a caller appending from several
/// threads locks around append.
class ByteBlocks {
 public:
  /// The size of a block; bytes larger than a quarter of it get a block of
  /// their own, so at most a quarter of any block is left unused.
  static constexpr std::size_t block_size = std::size_t{1} << 20;

  ByteBlocks() = default;
  /// The moved-from blocks are left empty.
  ByteBlocks(ByteBlocks&& other) noexcept { *this = std::move(other); }
  ByteBlocks& operator=(ByteBlocks&& other) noexcept;
  ByteBlocks(const ByteBlocks&) = delete;
  ByteBlocks& operator=(const ByteBlocks&) = delete;

  /// Copies `bytes` into the blocks and returns the copy (empty for no bytes).
  /// `bytes` may lie in these blocks. Throws std::bad_alloc as new does,
  /// the blocks then unchanged.
  std::span<const std::uint8_t> append(std::span<const std::uint8_t> bytes);
  /// Takes `other`'s blocks, whose bytes stay where they are (what append on
  /// `other` returned stays valid, now owned here); `other` is left empty.
  /// Appending here goes on in this one's open block: the rest of `other`'s
  /// stays unused. Throws std::bad_alloc, both then unchanged.
  void splice(ByteBlocks&& other);
  /// The bytes the blocks take, used or not.
  std::size_t capacity() const { return capacity_; }

 private:
  // A block is either mapped from the system (`mapped` its length) or an
  // array from new[] (`mapped` zero): see append.
  struct BlockRelease {
    std::size_t mapped = 0;
    void operator()(std::uint8_t* block) const noexcept;
  };
  std::vector<std::unique_ptr<std::uint8_t[], BlockRelease>> blocks_;
  std::uint8_t* free_ = nullptr;  // the rest of the last full-size block
  std::size_t room_ = 0;          // bytes at free_
  std::size_t capacity_ = 0;
};

/// The packed shape of each node of a tree (MeshTree::packed_shapes): entry k
/// is node k's bytes, as pack_node_shape made them, or empty for a node that
/// keeps its own mesh and solid. A copy holds copies of the bytes (and its
/// blocks only the entries' bytes); bytes an entry no longer names stay in the
/// blocks until the whole is freed.
class PackedShapes {
 public:
  PackedShapes() = default;
  /// `count` empty entries, whose bytes will be in `blocks` (adopt).
  PackedShapes(ByteBlocks blocks, std::size_t count);
  PackedShapes(const PackedShapes& other);
  PackedShapes& operator=(const PackedShapes& other);
  PackedShapes(PackedShapes&&) noexcept = default;
  PackedShapes& operator=(PackedShapes&&) noexcept = default;

  /// The number of entries: 0, or the tree's node count.
  std::size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  /// Entry `node`'s bytes (precondition: node < size()), valid until this is
  /// destroyed or assigned to (a move hands the bytes on, unmoved).
  std::span<const std::uint8_t> operator[](std::size_t node) const { return entries_[node]; }
  /// Keeps the first `count` entries, adding empty ones.
  void resize(std::size_t count) { entries_.resize(count); }
  /// Entry `node` (< size()) becomes a copy of `bytes`, which may be an
  /// entry's own. Throws std::bad_alloc, the entries then unchanged.
  void assign(std::size_t node, std::span<const std::uint8_t> bytes);
  /// Entry `node` (< size()) becomes `bytes`, not copied. Precondition:
  /// `bytes` is what append on the blocks this was made with returned.
  void adopt(std::size_t node, std::span<const std::uint8_t> bytes) { entries_[node] = bytes; }

 private:
  ByteBlocks blocks_;
  std::vector<std::span<const std::uint8_t>> entries_;
};

}  // namespace shatter
