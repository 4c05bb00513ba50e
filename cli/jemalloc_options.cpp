// jemalloc's compiled-in options (read once, at its first allocation). jemalloc
// is here for its speed on the builder's many small, short-lived arrays (cube
// -> 65,536 end to end: 8.2 s with glibc's malloc, 4.0 s with jemalloc; README
// "Dependencies"). jemalloc itself leaves transparent huge pages to the system (`thp:default`:
// with the kernel's mode "madvise", Debian's default, none are used): on these
// virtual machines a fresh 2 MiB page costs far more to fault in than the 4 KiB
// pages it replaces, because the host backs the guest's untouched memory on
// first touch, page by page. Paired in one session (farm-bench, cpu seconds,
// 2026-12-04, `shatter fracture --threads 1`): `thp:always` over `thp:default`
// 1.22x for cube -> 65,536 and 1.30x for cube -> 2^18 (system seconds 5x), and
// (one run each, /usr/bin/time) 2.1x for `shatter slice` of a 1.3 M-triangle
// sphere; but 1.03x for cube -> 65,536 once most of the guest's memory had been
// touched (user time 4 % lower, system time higher). Arrays of 2 MiB and more
// do go on huge pages, advised one by one by operator new (cli/huge_page_arrays.cpp: filled front to
// back, they waste at most one partly used page each). Linked only into executables
// (cmake/shatter_allocator.cmake); the libraries leave the allocator to whoever
// links them.
extern "C" {
// NOLINTNEXTLINE: the name and type are jemalloc's interface.
const char* malloc_conf = "thp:default,metadata_thp:disabled";
}
