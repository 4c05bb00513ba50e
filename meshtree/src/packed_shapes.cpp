#include "shatter/meshtree/packed_shapes.hpp"

#include <sys/mman.h>

#include <cstring>
#include <new>
#include <utility>

#include "address_sanitizer.hpp"

// Full-size blocks are mapped with their pages populated at once (Linux's
// MAP_POPULATE): every byte of such a block is written (but the last open
// block's rest), and on the virtual machines this runs on a page faulted in on
// first touch costs about twice what populating it with the mapping does
// (96 MiB written in 1 MiB blocks a 1.5 KB copy at a time: 0.74 s faulted,
// 0.40 s populated, 2026-12-05; cube -> 65,536 packs some 40 MB). Not under
// AddressSanitizer, which checks only what malloc makes.
#if !SHATTER_ADDRESS_SANITIZER && defined(MAP_POPULATE)
#define SHATTER_MAPPED_BLOCKS 1
#else
#define SHATTER_MAPPED_BLOCKS 0
#endif

namespace shatter {

void ByteBlocks::BlockRelease::operator()(std::uint8_t* block) const noexcept {
  if (mapped != 0) {
    ::munmap(block, mapped);
  } else {
    delete[] block;
  }
}

std::span<const std::uint8_t> ByteBlocks::append(std::span<const std::uint8_t> bytes) {
  if (bytes.empty()) return {};
  if (bytes.size() > room_) {
    const bool own_block = bytes.size() > block_size / 4;
    const std::size_t size = own_block ? bytes.size() : block_size;
    // Left uninitialised: every byte handed out is written first, and a page
    // never written is never touched.
    std::unique_ptr<std::uint8_t[], BlockRelease> block;
#if SHATTER_MAPPED_BLOCKS
    if (!own_block) {
      void* memory = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
      if (memory == MAP_FAILED) throw std::bad_alloc();
      block = {static_cast<std::uint8_t*>(memory), BlockRelease{size}};
    }
#endif
    if (block == nullptr) block.reset(new std::uint8_t[size]);
    blocks_.push_back(std::move(block));
    capacity_ += size;
    if (own_block) {
      // The open block stays open: it may have room for the next bytes.
      std::uint8_t* at = blocks_.back().get();
      std::memcpy(at, bytes.data(), bytes.size());
      return {at, bytes.size()};
    }
    free_ = blocks_.back().get();
    room_ = size;
  }
  std::uint8_t* at = free_;
  std::memcpy(at, bytes.data(), bytes.size());
  free_ += bytes.size();
  room_ -= bytes.size();
  return {at, bytes.size()};
}

void ByteBlocks::splice(ByteBlocks&& other) {
  if (this == &other || other.blocks_.empty()) return;
  if (blocks_.empty()) {
    *this = std::move(other);  // its open block stays open
    return;
  }
  blocks_.reserve(blocks_.size() + other.blocks_.size());  // the only throw, before anything moves
  for (auto& block : other.blocks_) blocks_.push_back(std::move(block));
  capacity_ += std::exchange(other.capacity_, 0);
  other.blocks_.clear();
  other.free_ = nullptr;
  other.room_ = 0;
}

ByteBlocks& ByteBlocks::operator=(ByteBlocks&& other) noexcept {
  if (this == &other) return *this;
  // The open block's free end goes with it (appending to the moved-from
  // blocks must not write into the other's).
  blocks_ = std::move(other.blocks_);
  other.blocks_.clear();
  free_ = std::exchange(other.free_, nullptr);
  room_ = std::exchange(other.room_, 0);
  capacity_ = std::exchange(other.capacity_, 0);
  return *this;
}

PackedShapes::PackedShapes(ByteBlocks blocks, std::size_t count) : blocks_(std::move(blocks)), entries_(count) {}

PackedShapes::PackedShapes(const PackedShapes& other) : entries_(other.entries_.size()) {
  for (std::size_t k = 0; k < entries_.size(); ++k) entries_[k] = blocks_.append(other.entries_[k]);
}

PackedShapes& PackedShapes::operator=(const PackedShapes& other) {
  if (this != &other) *this = PackedShapes(other);
  return *this;
}

void PackedShapes::assign(std::size_t node, std::span<const std::uint8_t> bytes) {
  entries_[node] = blocks_.append(bytes);
}

}  // namespace shatter
