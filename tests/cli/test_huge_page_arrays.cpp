// The executables' operator new (cli/huge_page_arrays.cpp, linked here with
// jemalloc as the executables take it): every request gives writable memory of
// its size, aligned for any object that fits in it; a request of 2 MiB or more starts on a 2 MiB
// boundary and its mapping is advised for huge pages; a request that cannot be
// met calls the new-handler and then throws std::bad_alloc. And the reading
// commands' switch (cli/huge_page_objects.cpp): small objects made after it,
// on any thread, lie in memory advised for huge pages.

#include <catch2/catch.hpp>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "huge_page_objects.hpp"

namespace {

constexpr std::size_t huge_page = std::size_t{2} << 20;

// The VmFlags line of the mapping in /proc/self/smaps that holds `address`.
std::string vm_flags_of(const void* address) {
  const auto at = reinterpret_cast<std::uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  REQUIRE(smaps);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t begin = 0, end = 0;
    char dash = 0;
    std::istringstream range(line);
    // A mapping's header starts with "begin-end" in hexadecimal.
    if (range >> std::hex >> begin >> dash >> end && dash == '-') {
      inside = begin <= at && at < end;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  FAIL("no mapping of /proc/self/smaps holds the address");
  return {};
}

// Whether `flags` (a VmFlags line) holds the two-letter flag `flag`.
bool has_flag(const std::string& flags, const std::string& flag) {
  std::istringstream words(flags.substr(flags.find(':') + 1));
  std::string word;
  while (words >> word) {
    if (word == flag) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("operator new gives writable, aligned memory of every size", "[allocator]") {
  for (std::uint32_t seed = 1; seed <= 40; ++seed) {
    std::mt19937_64 random(seed);
    // Sizes on either side of the huge-page threshold and of page boundaries.
    const std::size_t scale = std::size_t{1} << std::uniform_int_distribution<int>(0, 24)(random);
    const std::size_t size = std::uniform_int_distribution<std::size_t>(0, 2 * scale)(random);
    auto* bytes = static_cast<unsigned char*>(::operator new(size));
    REQUIRE(bytes != nullptr);
    // Aligned for any object that fits (malloc's rule, which libstdc++'s own
    // operator new keeps): a block of 8 bytes need not start on 16.
    std::size_t fits = alignof(std::max_align_t);
    while (fits > 1 && fits > size) fits /= 2;
    CHECK(reinterpret_cast<std::uintptr_t>(bytes) % fits == 0);
    if (size >= huge_page) CHECK(reinterpret_cast<std::uintptr_t>(bytes) % huge_page == 0);
    // Every byte written, then read back: the block is the size asked for.
    for (std::size_t i = 0; i < size; ++i) bytes[i] = static_cast<unsigned char>(i * 131 + seed);
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < size; ++i) wrong += bytes[i] != static_cast<unsigned char>(i * 131 + seed);
    CHECK(wrong == 0);
    ::operator delete(bytes);
  }
}

TEST_CASE("a large array's mapping is advised for huge pages", "[allocator]") {
  // The advice needs the kernel's transparent huge pages; Debian's kernels have them.
  REQUIRE(std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled"));
  for (const std::size_t size : {huge_page, 3 * huge_page + 12345, 16 * huge_page}) {
    std::vector<std::uint64_t> array;
    array.reserve(size / sizeof(std::uint64_t));
    REQUIRE(reinterpret_cast<std::uintptr_t>(array.data()) % huge_page == 0);
    CHECK(has_flag(vm_flags_of(array.data()), "hg"));
    // A vector growing through the threshold keeps its elements.
    std::vector<std::uint64_t> grown;
    for (std::uint64_t i = 0; i < size / sizeof(std::uint64_t); ++i) grown.push_back(i * i);
    std::size_t wrong = 0;
    for (std::uint64_t i = 0; i < grown.size(); ++i) wrong += grown[i] != i * i;
    CHECK(wrong == 0);
  }
}

namespace {
int handler_calls = 0;
void give_up_on_second_call() {
  if (++handler_calls == 2) std::set_new_handler(nullptr);
}
}  // namespace

TEST_CASE("a request that cannot be met calls the new-handler, then throws", "[allocator]") {
  const std::size_t impossible = std::numeric_limits<std::size_t>::max() / 2;
  handler_calls = 0;
  std::set_new_handler(give_up_on_second_call);
  CHECK_THROWS_AS(::operator new(impossible), std::bad_alloc);
  CHECK(handler_calls == 2);
  // Without a handler: at once, both forms, and the nothrow form gives null.
  handler_calls = 0;
  CHECK_THROWS_AS(::operator new[](impossible), std::bad_alloc);
  CHECK(::operator new(impossible, std::nothrow) == nullptr);
  CHECK(handler_calls == 0);
  // A small request still succeeds afterwards.
  const std::unique_ptr<int> small(new int(7));
  CHECK(*small == 7);
}

TEST_CASE("small objects made after the reading commands' switch lie on memory advised for huge pages", "[allocator]") {
  // Enough small objects that jemalloc maps fresh memory for them after the
  // switch (its arenas hold a few megabytes beforehand): 64 MiB of 48-byte
  // objects, every one written and read back.
  const auto make_small_objects = [](std::vector<std::unique_ptr<std::uint64_t[]>>& objects) {
    for (std::size_t i = 0; i < (std::size_t{64} << 20) / 48; ++i) {
      objects.emplace_back(new std::uint64_t[6]);
      for (std::size_t k = 0; k < 6; ++k) objects.back()[k] = i * 6 + k;
    }
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < objects.size(); ++i) {
      for (std::size_t k = 0; k < 6; ++k) wrong += objects[i][k] != i * 6 + k;
    }
    return wrong;
  };
  shatter::cli::keep_small_objects_on_huge_pages();
  shatter::cli::keep_small_objects_on_huge_pages();  // idempotent
  std::vector<std::unique_ptr<std::uint64_t[]>> here;
  CHECK(make_small_objects(here) == 0);
  CHECK(has_flag(vm_flags_of(here.back().get()), "hg"));
  // Another thread allocates from another of jemalloc's arenas: advised too.
  std::vector<std::unique_ptr<std::uint64_t[]>> there;
  std::size_t wrong_there = 1;
  std::thread([&] { wrong_there = make_small_objects(there); }).join();
  CHECK(wrong_there == 0);
  CHECK(has_flag(vm_flags_of(there.back().get()), "hg"));
}
