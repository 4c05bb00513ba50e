// Large arrays on transparent huge pages. The replaceable global operator new
// (and new[]): a request of 2 MiB or more is aligned to 2 MiB and its whole huge
// pages marked MADV_HUGEPAGE before anything touches them, so the kernel backs
// them 2 MiB at a fault; smaller requests go to malloc as before. Linked only
// into the executables that take jemalloc (cmake/shatter_allocator.cmake), never
// into the libraries or the sanitized builds, whose runtimes bring their own
// operator new.
//
// Why: on these virtual machines every page fault is a trip through the
// hypervisor. Faulting in a fresh 4 KiB page costs about 10 us; a 2 MiB page
// whose frame the host has backed before costs about what 4 KiB pages cost for
// 40 KiB of it (256 MiB touched page by page: 682-721 ms on 4 KiB pages,
// 377-390 ms with MADV_POPULATE_WRITE, 17-416 ms on huge pages;
// bench/page_faults_bench.cpp, 2026-12-06). jemalloc hands its arrays of 8 MiB and more back to the system
// when they are freed (its oversize arena), so the large arrays a command makes
// one after another (the file read, the welded mesh, the plane solid, each cut's
// sides, the pieces' meshes, the encoded file) each fault in fresh memory; on
// a 1.3 M-triangle mesh that was two fifths of `shatter slice`'s time. Only
// large arrays: they are filled front to back, so a huge page holds little that
// is not used (at most one partly used page per array), where jemalloc's own
// `thp:always` puts every small object's slab on huge pages too and cost 1.2x
// the CPU on a fresh machine (cli/jemalloc_options.cpp).
//
// operator delete needs no replacement: libstdc++'s calls free(), which takes
// what posix_memalign and malloc gave alike.

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t huge_page = std::size_t{2} << 20;

void* allocate_or_null(std::size_t size) {
  if (size < huge_page) return std::malloc(size == 0 ? 1 : size);
  void* memory = nullptr;
  if (::posix_memalign(&memory, huge_page, size) != 0) return nullptr;
#ifdef MADV_HUGEPAGE
  // Advice only: refused (a kernel without transparent huge pages), the array
  // is backed page by page as before.
  ::madvise(memory, size & ~(huge_page - 1), MADV_HUGEPAGE);
#endif
  return memory;
}

// As the standard asks of a replacement: on failure call the new-handler while
// there is one, then throw std::bad_alloc.
void* allocate(std::size_t size) {
  for (;;) {
    if (void* memory = allocate_or_null(size)) return memory;
    const std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
