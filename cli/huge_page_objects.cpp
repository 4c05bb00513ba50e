// Small objects on huge pages, for the commands that read a tree and keep it.
//
// jemalloc leaves transparent huge pages to the system for its small objects
// (cli/jemalloc_options.cpp: `thp:default`), because for the builder, which
// makes and frees millions of small arrays, huge pages cost more than they
// save on these virtual machines (a fresh 2 MiB page is backed by the host on
// first touch, and freed memory purged from a huge page splits it). Reading a
// .shatter file is the other case: some 130,000 solids, meshes and hulls for
// cube -> 65,536, about 0.4 GB of small arrays allocated once and kept to the
// end, which faulted in 4 KiB at a time (each fault a trip through the
// hypervisor; README "Lean memory" and bench/page_faults_bench.cpp). `shatter
// info` of that file with jemalloc's `thp:always`: 0.69 s against 1.22 s wall,
// 0.52x the CPU (farm-bench -n 7, 2026-12-06); `fracture` with it, 1.05x slower.
// jemalloc reads `thp` once, at its first allocation, for the whole process, so
// the advice is given here instead, per command: each arena's extent hooks (the
// functions jemalloc maps memory with) are replaced by jemalloc's own with one
// step added, madvise(MADV_HUGEPAGE) on what they map. jemalloc's interface for
// it: mallctl("arena.<i>.extent_hooks"), which on an arena not yet in use
// creates it with the hooks given (jemalloc(3), "arena.<i>.extent_hooks").

#include "huge_page_objects.hpp"

#if SHATTER_WITH_JEMALLOC

#include <jemalloc/jemalloc.h>
#include <sys/mman.h>

#include <cstddef>
#include <mutex>
#include <string>

namespace shatter::cli {
namespace {

extent_hooks_t* jemalloc_hooks = nullptr;  // jemalloc's own, which ours hand every call to
extent_hooks_t advising_hooks;             // theirs, but for `alloc`

void* allocate_advised(extent_hooks_t*, void* new_address, std::size_t size, std::size_t alignment, bool* zero,
                       bool* commit, unsigned arena) {
  void* memory = jemalloc_hooks->alloc(jemalloc_hooks, new_address, size, alignment, zero, commit, arena);
#ifdef MADV_HUGEPAGE
  // Advice only: a kernel without transparent huge pages refuses it, and the
  // memory is backed page by page as before.
  if (memory != nullptr) ::madvise(memory, size, MADV_HUGEPAGE);
#endif
  return memory;
}

void install() {  // std::to_string may throw: keep_small_objects_on_huge_pages catches it
  unsigned arenas = 0;
  std::size_t length = sizeof arenas;
  if (mallctl("arenas.narenas", &arenas, &length, nullptr, 0) != 0) return;
  for (unsigned i = 0; i < arenas; ++i) {
    const std::string name = "arena." + std::to_string(i) + ".extent_hooks";
    extent_hooks_t* current = nullptr;
    length = sizeof current;
    if (mallctl(name.c_str(), &current, &length, nullptr, 0) != 0 || current == nullptr) continue;
    if (jemalloc_hooks == nullptr) {
      jemalloc_hooks = current;
      advising_hooks = *current;
      advising_hooks.alloc = allocate_advised;
    }
    // Hooks someone else installed are left alone (ours forward to jemalloc's only).
    if (current != jemalloc_hooks) continue;
    extent_hooks_t* ours = &advising_hooks;
    mallctl(name.c_str(), nullptr, nullptr, &ours, sizeof ours);
  }
}

}  // namespace

void keep_small_objects_on_huge_pages() noexcept {
  static std::once_flag once;
  try {
    std::call_once(once, install);
  } catch (...) {
    // std::to_string's allocation failed: the command runs without the advice.
  }
}

}  // namespace shatter::cli

#else

namespace shatter::cli {

void keep_small_objects_on_huge_pages() noexcept {}

}  // namespace shatter::cli

#endif
