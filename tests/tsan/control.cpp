// The controls of tests/tsan/run-tsan, built with -fsanitize=thread against the
// system's TBB headers, run on two threads:
//   control race   the two tasks of a tbb::parallel_invoke both increment one int
//                  with no synchronisation: ThreadSanitizer must report it (it is live);
//   control clean  a tbb::parallel_for writes one element per index and the main
//                  thread reads them after the join: no race, so 0 reports with an
//                  instrumented libtbb, but false reports with Debian's, where TSan
//                  cannot see the join's ordering (so a clean run shows which one is loaded).
// Each task sleeps a little, so that the second thread takes part.
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

namespace {
void nap() { std::this_thread::sleep_for(std::chrono::milliseconds(1)); }
}  // namespace

int main(int argc, char** argv) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  if (argc > 1 && std::strcmp(argv[1], "race") == 0) {
    int shared = 0;
    const auto task = [&] {
      for (int i = 0; i < 50; ++i) nap();
      ++shared;  // the deliberate data race
    };
    tbb::parallel_invoke(task, task);
    std::printf("%d\n", shared);
  } else {
    std::vector<int> values(256);
    tbb::parallel_for(std::size_t{0}, values.size(), [&](std::size_t i) {
      nap();
      values[i] = static_cast<int>(i);
    });
    long sum = 0;
    for (int v : values) sum += v;
    std::printf("%ld\n", sum);
  }
}
