// The blocks a lean build keeps its packed nodes in (packed_shapes.hpp): every
// append gives back its bytes and keeps them while the blocks live, whatever
// follows (appends, moves, copies); little of a block is left unused.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <cstddef>
#include <cstring>
#include <iterator>
#include <span>
#include <utility>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/meshtree/packed_shapes.hpp"
#include "../../meshtree/src/populate.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;
using test::Random;

namespace {

// Byte strings of sizes around the block's thresholds and between them.
std::vector<std::vector<std::uint8_t>> random_strings(Random& random, std::size_t count) {
  constexpr std::size_t quarter = ByteBlocks::block_size / 4;
  const std::size_t sizes[] = {0, 1, 7, 600, quarter - 1, quarter, quarter + 1, ByteBlocks::block_size + 3};
  std::vector<std::vector<std::uint8_t>> strings(count);
  for (std::vector<std::uint8_t>& s : strings) {
    // Mostly small, as packed nodes are; now and then one of the sizes above.
    const std::size_t size = random.index(32) != 0 ? random.index(2000) : sizes[random.index(std::size(sizes))];
    s.resize(size);
    for (std::size_t i = 0; i < size; i += 8) {
      const std::uint64_t bits = random.next();
      std::memcpy(s.data() + i, &bits, std::min<std::size_t>(8, size - i));
    }
  }
  return strings;
}

bool equal(std::span<const std::uint8_t> a, const std::vector<std::uint8_t>& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
}

}  // namespace

TEST_CASE("byte blocks keep every string appended, moved or not", "[packed_shapes][property]") {
  for (std::uint64_t seed = 1; seed <= test::sized(12, 4); ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    const auto strings = random_strings(random, 1500);
    ByteBlocks blocks;
    std::vector<std::span<const std::uint8_t>> copies;
    std::size_t small = 0, large = 0;
    for (const auto& s : strings) {
      copies.push_back(blocks.append(s));
      REQUIRE(equal(copies.back(), s));
      (s.size() > ByteBlocks::block_size / 4 ? large : small) += s.size();
    }
    // Each full-size block but the last is more than three quarters used.
    CHECK(blocks.capacity() <= large + small * 4 / 3 + ByteBlocks::block_size);
    // Appending a copy's own bytes, and moving the blocks, leave them all as they were.
    const std::size_t i = random.index(copies.size());
    CHECK(equal(blocks.append(copies[i]), strings[i]));
    ByteBlocks moved = std::move(blocks);
    CHECK(blocks.capacity() == 0);
    // What the moved-from blocks take now is their own, not in `moved`'s.
    CHECK(equal(blocks.append(strings[i]), strings[i]));
    CHECK(equal(moved.append(strings[0]), strings[0]));
    for (std::size_t k = 0; k < strings.size(); ++k) CHECK(equal(copies[k], strings[k]));
  }
}

TEST_CASE("spliced byte blocks keep every string of both, appending on", "[packed_shapes][property]") {
  // As a lean build joins its threads' blocks (Builder::take_packed_bytes).
  for (std::uint64_t seed = 1; seed <= test::sized(12, 4); ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    const auto strings = random_strings(random, 900);
    ByteBlocks parts[3];
    std::vector<std::span<const std::uint8_t>> copies;
    for (const auto& s : strings) copies.push_back(parts[random.index(3)].append(s));
    ByteBlocks all;
    std::size_t capacity = 0;
    for (ByteBlocks& part : parts) {
      capacity += part.capacity();
      all.splice(std::move(part));
      CHECK(part.capacity() == 0);
    }
    CHECK(all.capacity() == capacity);
    all.splice(std::move(parts[0]));  // empty: nothing changes
    CHECK(all.capacity() == capacity);
    // Appending on, to the joined blocks and to an emptied part, overwrites nothing.
    const std::size_t i = random.index(strings.size());
    CHECK(equal(all.append(strings[i]), strings[i]));
    CHECK(equal(parts[1].append(strings[i]), strings[i]));
    for (std::size_t k = 0; k < strings.size(); ++k) CHECK(equal(copies[k], strings[k]));
  }
}

TEST_CASE("packed shapes are entries in blocks, copied with their bytes", "[packed_shapes][property]") {
  for (std::uint64_t seed = 1; seed <= test::sized(12, 4); ++seed) {
    INFO("seed " << seed);
    Random random(seed);
    const auto strings = random_strings(random, 500);
    // Entries adopted from the blocks they were appended to, as number_tree
    // adopts the builder's, then some assigned anew.
    ByteBlocks blocks;
    std::vector<std::span<const std::uint8_t>> appended;
    for (const auto& s : strings) appended.push_back(blocks.append(s));
    PackedShapes shapes(std::move(blocks), strings.size() + 1);
    for (std::size_t k = 0; k < strings.size(); ++k) shapes.adopt(k, appended[k]);
    std::vector<std::vector<std::uint8_t>> expected = strings;
    expected.emplace_back();  // the last entry was left empty
    for (int n = 0; n < 100; ++n) {
      const std::size_t k = random.index(expected.size()), from = random.index(expected.size());
      shapes.assign(k, shapes[from]);  // an entry's own bytes
      expected[k] = expected[from];
    }
    REQUIRE(shapes.size() == expected.size());
    for (std::size_t k = 0; k < expected.size(); ++k) REQUIRE(equal(shapes[k], expected[k]));
    // A copy is equal and apart: changing one leaves the other.
    PackedShapes copy = shapes;
    REQUIRE(copy.size() == shapes.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
      REQUIRE(equal(copy[k], expected[k]));
      CHECK((expected[k].empty() || copy[k].data() != shapes[k].data()));
    }
    copy.assign(0, strings[1]);
    copy.resize(copy.size() - 1);
    CHECK(shapes.size() == expected.size());
    CHECK(equal(shapes[0], expected[0]));
    copy = shapes;
    for (std::size_t k = 0; k < expected.size(); ++k) REQUIRE(equal(copy[k], expected[k]));
  }
}

TEST_CASE("populating pages ahead changes no byte written and nothing past the room reserved",
          "[packed_shapes][property]") {
  // number_tree and the bond search populate their arrays' reserved room ahead
  // of the fill (meshtree/src/populate.hpp): what was written before must stay
  // (a wrong advice, MADV_DONTNEED say, would zero it), at any alignment, and
  // the fill must read back whole.
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    shatter::test::Random random(seed);
    std::vector<std::uint64_t> values;
    values.reserve(300'000 + random.index(100'000));
    shatter::detail::PopulatedAhead ahead(values, std::size_t{1} << 16);
    std::uint64_t state = seed;
    while (values.size() < values.capacity()) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      values.push_back(state);
      ahead.ensure();
      // Now and then the whole of what is written, from an odd address on.
      if (values.size() % 50'000 == 0) {
        shatter::detail::populate_for_writing(reinterpret_cast<std::byte*>(values.data()) + 3,
                                              values.size() * sizeof(std::uint64_t) - 3);
      }
    }
    std::uint64_t check = seed;
    std::size_t changed = 0;
    for (const std::uint64_t value : values) {
      check = check * 6364136223846793005ull + 1442695040888963407ull;
      changed += value != check;
    }
    CHECK(changed == 0);
  }
}
