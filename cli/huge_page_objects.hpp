#pragma once
// Small objects on transparent huge pages, for the commands that read a whole
// tree and keep it (cli/huge_page_objects.cpp says why these and not the others).

namespace shatter::cli {

/// From this call on, the memory the allocator maps for small objects (every
/// arena jemalloc uses for them) is advised MADV_HUGEPAGE, so the kernel backs
/// it 2 MiB at a fault where the system's mode is "madvise". Call it before a
/// command reads a tree it keeps to the end (`info`, `export`, `view`,
/// `simulate`): a million small arrays, never freed until the command ends,
/// which faulted in 4 KiB at a time. Idempotent; memory mapped before the call
/// stays as it was. Precondition: none. Never fails: where the executable does
/// not allocate through jemalloc (the sanitized builds, -DSHATTER_JEMALLOC=OFF)
/// or jemalloc refuses the settings, it does nothing and the command runs as
/// before, only slower.
void keep_small_objects_on_huge_pages() noexcept;

}  // namespace shatter::cli
