// jemalloc's compiled-in options (read once, at its first allocation): back its
// memory with transparent huge pages, for the data and for its own metadata.
// A build of a mesh tree writes gigabytes of fresh memory, and on these
// machines a 4 KiB page fault costs more than the geometry done on the page:
// cube -> 65,536 fragments builds in about 1.8-2.3 s with huge pages and 3.5 s
// without (shatter-bench-plane, README "Benchmark"). With the kernel's THP mode
// "madvise" (Debian's default) jemalloc asks for them; with "never" this does
// nothing. Linked only into executables (cmake/shatter_allocator.cmake); the
// libraries leave the allocator to whoever links them.
extern "C" {
// NOLINTNEXTLINE: the name and type are jemalloc's interface.
const char* malloc_conf = "thp:always,metadata_thp:auto";
}
