// What touching fresh memory costs on this machine, three ways, the ratio that
// cli/huge_page_arrays.cpp rests on: a fresh anonymous mapping of N MiB written
// a byte per 4 KiB page (faulted in page by page), populated first with
// madvise(MADV_POPULATE_WRITE), or advised MADV_HUGEPAGE (2 MiB at a fault).
// The three alternate for a number of rounds, each in a fresh mapping, and each
// round's milliseconds are printed (the host backing memory it had not backed
// before shows as the high figures). A benchmark, not a test.
//
//   ./build/bench/shatter-bench-page-faults [MiB=256] [rounds=4]

#include <sys/mman.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

namespace {

constexpr std::size_t huge_page = std::size_t{2} << 20;

enum class Way { pages, populated, huge };

// Milliseconds to map `bytes` fresh, prepare them `way`, and write every page.
double touch(std::size_t bytes, Way way) {
  const auto start = std::chrono::steady_clock::now();
  void* mapping = ::mmap(nullptr, bytes + huge_page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapping == MAP_FAILED) {
    std::perror("mmap");
    std::exit(1);
  }
  // Aligned to 2 MiB, so a huge page can back every part of the range.
  auto* bytes_at = reinterpret_cast<char*>((reinterpret_cast<std::uintptr_t>(mapping) + huge_page - 1) & ~(huge_page - 1));
  if (way == Way::huge) ::madvise(bytes_at, bytes, MADV_HUGEPAGE);
#ifdef MADV_POPULATE_WRITE
  if (way == Way::populated) ::madvise(bytes_at, bytes, MADV_POPULATE_WRITE);
#endif
  for (std::size_t at = 0; at < bytes; at += 4096) bytes_at[at] = 1;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ::munmap(mapping, bytes + huge_page);
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  const long mib = argc > 1 ? std::atol(argv[1]) : 256;
  const long rounds = argc > 2 ? std::atol(argv[2]) : 4;
  if (mib <= 0 || rounds <= 0) {
    std::fprintf(stderr, "usage: shatter-bench-page-faults [MiB > 0] [rounds > 0]\n");
    return 2;
  }
  const std::size_t bytes = static_cast<std::size_t>(mib) << 20;
  std::printf("| round | 4 KiB pages ms | MADV_POPULATE_WRITE ms | MADV_HUGEPAGE ms |\n|---:|---:|---:|---:|\n");
  for (long round = 1; round <= rounds; ++round) {
    const double pages = touch(bytes, Way::pages), populated = touch(bytes, Way::populated), huge = touch(bytes, Way::huge);
    std::printf("| %ld | %.1f | %.1f | %.1f |\n", round, pages, populated, huge);
  }
  std::printf("\n%ld MiB touched a byte per 4 KiB page, each way in a fresh mapping.\n", mib);
  return 0;
}
