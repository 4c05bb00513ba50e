// shatter-fuzz: the robustness runner. Draws seeded cases from every degenerate
// class and every mesh, runs slice chains and fractures in both kernels, checks
// every invariant, prints a per-class table and writes a reproducer for each
// failure. Also replays reproducers and runs the side-of-plane predicate audit.

#include <CLI/CLI.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "robustness/robustness.hpp"
#include "shatter/kernel/predicates.hpp"

namespace {

using namespace shatter;
using namespace shatter::robust;

struct ClassTotals {
  std::size_t cases = 0, slices = 0, fractures = 0, exact = 0, failures = 0, refused = 0;
  std::size_t fast_pieces = 0, fast_self_intersecting = 0, fast_degenerate = 0, exact_pieces = 0;
  double seconds = 0;
};

void print_table(const std::array<ClassTotals, case_class_count>& totals) {
  std::printf("%-20s %7s %6s %6s %6s %6s %7s %9s %8s %8s %9s %8s\n", "class", "cases", "slice", "fract", "exact",
              "failed", "refused", "fast-pcs", "self-int", "degener", "exact-pcs", "ms/case");
  ClassTotals all;
  auto row = [](const char* name, const ClassTotals& t) {
    std::printf("%-20s %7zu %6zu %6zu %6zu %6zu %7zu %9zu %8zu %8zu %9zu %8.2f\n", name, t.cases, t.slices, t.fractures,
                t.exact, t.failures, t.refused, t.fast_pieces, t.fast_self_intersecting, t.fast_degenerate,
                t.exact_pieces, t.cases ? 1e3 * t.seconds / double(t.cases) : 0.0);
  };
  for (int k = 0; k < case_class_count; ++k) {
    const ClassTotals& t = totals[k];
    if (t.cases == 0) continue;
    row(std::string(class_name(static_cast<CaseClass>(k))).c_str(), t);
    all.cases += t.cases, all.slices += t.slices, all.fractures += t.fractures, all.exact += t.exact;
    all.failures += t.failures, all.refused += t.refused, all.fast_pieces += t.fast_pieces;
    all.fast_self_intersecting += t.fast_self_intersecting, all.fast_degenerate += t.fast_degenerate;
    all.exact_pieces += t.exact_pieces, all.seconds += t.seconds;
  }
  row("all", all);
}

// Writes the smallest failing form of the case and replays the file, so a
// reproducer that does not reproduce is reported as such.
void report_failure(const Case& c, const CaseOutcome& outcome, const std::filesystem::path& dir) {
  Case smallest = c;
  std::string failure = outcome.failures.front();
  if (outcome.shrunk) {
    const CaseOutcome again = run_case(*outcome.shrunk);
    if (!again.failures.empty()) smallest = *outcome.shrunk, failure = again.failures.front();
  }
  const std::filesystem::path path = write_reproducer(dir, smallest, failure);
  const bool reproduces = !run_case(read_reproducer(path)).failures.empty();
  std::printf("FAIL %s %s %s on %s (seed %llu): %s\n     reproducer %s (%s)\n",
              std::string(class_name(c.kind)).c_str(), std::string(operation_name(c.op)).c_str(),
              std::string(kernel_name(c.kernel)).c_str(), c.mesh_name.c_str(), (unsigned long long)c.seed,
              failure.c_str(), path.string().c_str(), reproduces ? "reproduces" : "DOES NOT reproduce when replayed");
}

int run_cases(std::uint64_t cases, std::uint64_t seed, std::uint64_t first, const std::vector<std::string>& only,
              unsigned threads, const std::filesystem::path& reproducer_dir) {
  std::array<bool, case_class_count> wanted{};
  for (const std::string& name : only) {
    const auto kind = parse_class(name);
    if (!kind) throw CLI::ValidationError("--class", "unknown class '" + name + "' (see --list-classes)");
    wanted[static_cast<std::size_t>(*kind)] = true;
  }
  if (only.empty()) wanted.fill(true);
  std::vector<std::uint64_t> indices;
  for (std::uint64_t i = first; indices.size() < cases; ++i) {
    if (wanted[i % case_class_count]) indices.push_back(i);
  }

  const auto start = std::chrono::steady_clock::now();
  const MeshPool pool = MeshPool::load();
  struct Ran {
    Case c;
    CaseOutcome outcome;
    double seconds = 0;
    PredicateCounters predicates;  ///< side-of-plane calls made on the case's own thread
  };
  std::vector<Ran> ran(indices.size());
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(std::size_t(0), indices.size(), [&](std::size_t i) {
      const auto t0 = std::chrono::steady_clock::now();
      Case c = make_case(pool, seed, indices[i]);
      const PredicateCounters before = predicate_counters();
      CaseOutcome outcome = run_case(c);
      ran[i].predicates = {predicate_counters().side_of_plane_calls - before.side_of_plane_calls,
                           predicate_counters().side_of_plane_exact - before.side_of_plane_exact};
      ran[i].seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      // Keep the mesh only where a reproducer needs it.
      if (outcome.failures.empty()) c.mesh = {};
      ran[i].c = std::move(c);
      ran[i].outcome = std::move(outcome);
    });
  });

  std::array<ClassTotals, case_class_count> totals{};
  std::size_t failed = 0;
  PredicateCounters predicates;
  for (const Ran& r : ran) {
    predicates.side_of_plane_calls += r.predicates.side_of_plane_calls;
    predicates.side_of_plane_exact += r.predicates.side_of_plane_exact;
    ClassTotals& t = totals[static_cast<std::size_t>(r.c.kind)];
    ++t.cases;
    (r.c.op == Operation::slice ? t.slices : t.fractures) += 1;
    t.exact += r.c.kernel == KernelKind::exact;
    t.failures += !r.outcome.failures.empty();
    t.refused += r.outcome.refused;
    t.fast_pieces += r.outcome.fast_pieces;
    t.fast_self_intersecting += r.outcome.fast_self_intersecting;
    t.fast_degenerate += r.outcome.fast_degenerate;
    t.exact_pieces += r.outcome.exact_pieces;
    t.seconds += r.seconds;
    if (!r.outcome.failures.empty()) {
      ++failed;
      report_failure(r.c, r.outcome, reproducer_dir);
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("shatter-fuzz: %zu cases from seed %llu (first index %llu), %.1f s wall\n", ran.size(),
              (unsigned long long)seed, (unsigned long long)first, wall);
  print_table(totals);
  // Counted on each case's own thread: the cuts and checks, not work a fracture
  // hands to other threads.
  std::printf("side_of_plane: %llu calls, %llu fell back to exact arithmetic (%.3f%%)\n",
              (unsigned long long)predicates.side_of_plane_calls, (unsigned long long)predicates.side_of_plane_exact,
              predicates.side_of_plane_calls
                  ? 100.0 * double(predicates.side_of_plane_exact) / double(predicates.side_of_plane_calls)
                  : 0.0);
  std::printf("%zu failing case%s\n", failed, failed == 1 ? "" : "s");
  return failed == 0 ? 0 : 1;
}

int replay(const std::vector<std::string>& files) {
  std::size_t failed = 0;
  for (const std::string& file : files) {
    const Case c = read_reproducer(file);
    const CaseOutcome outcome = run_case(c);
    std::printf("%s: %s %s %s on %s: %s\n", file.c_str(), std::string(class_name(c.kind)).c_str(),
                std::string(operation_name(c.op)).c_str(), std::string(kernel_name(c.kernel)).c_str(),
                c.mesh_name.c_str(), outcome.failures.empty() ? (outcome.refused ? "refused (unsupported)" : "passes")
                                                               : outcome.failures.front().c_str());
    failed += !outcome.failures.empty();
  }
  return failed == 0 ? 0 : 1;
}

int audit(std::uint64_t queries, std::uint64_t seed, unsigned threads) {
  const auto start = std::chrono::steady_clock::now();
  const AuditResult r = audit_side_of_plane(queries, seed, threads);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("predicate audit: %llu side-of-plane queries (seed %llu)\n", (unsigned long long)r.queries,
              (unsigned long long)seed);
  std::printf("  agree with the GMP reference: %llu of %llu (%llu disagreements)\n",
              (unsigned long long)(r.queries - r.disagreements), (unsigned long long)r.queries,
              (unsigned long long)r.disagreements);
  std::printf("  %-32s %12s %12s %16s\n", "points", "queries", "on plane", "exact fall-back");
  auto band = [](const char* name, const AuditBand& b) {
    std::printf("  %-32s %12llu %12llu %15.2f%%\n", name, (unsigned long long)b.queries,
                (unsigned long long)b.on_plane, b.queries ? 100.0 * double(b.exact_fallbacks) / double(b.queries) : 0.0);
  };
  band("exactly on the plane", r.exact_on_plane);
  band("moved -4..4 ulps per coordinate", r.within_4_ulps);
  band("moved 2^3..2^40 ulps on one axis", r.far_8_to_2e40_ulps);
  std::printf("  %.1f s wall\n", wall);
  if (r.disagreements) std::printf("  first disagreement: %s\n", r.first_disagreement.c_str());
  return r.disagreements == 0 && r.queries == queries ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "shatter-fuzz: seeded robustness cases over every degenerate class (planes through vertices, along edges, "
      "holding faces and a few ulps off; grids; coplanar faces; slivers; nested shells; pinches; near-parallel "
      "chains; extreme scales; far from the origin; attribute seams) and every mesh of ../shared/meshes, sliced "
      "and fractured in both kernels, every invariant of DESIGN.md checked. Exit 0 when every case passes, 1 on "
      "any failure (each writes a reproducer), 2 on usage errors."};
  std::uint64_t cases = 2000, seed = 1, first = 0, audit_queries = 0;
  unsigned threads = 0;
  std::vector<std::string> only, replays;
  std::string reproducers = "shatter-fuzz-reproducers";
  bool list = false;
  app.add_option("--cases", cases, "How many cases to run (default 2000)");
  app.add_option("--seed", seed, "Seed of the run; case i is drawn from (seed, i) alone (default 1)");
  app.add_option("--first", first, "Index of the first case, to split a long run into parts (default 0)");
  app.add_option("--class", only, "Run only these classes (repeatable; see --list-classes)");
  app.add_option("--threads", threads, "Worker threads, 0 for all (default 0); results do not depend on it");
  app.add_option("--reproducers", reproducers, "Folder for reproducer files (default shatter-fuzz-reproducers)");
  app.add_option("--replay", replays, "Replay reproducer files instead of drawing cases")->check(CLI::ExistingFile);
  app.add_option("--audit-predicates", audit_queries,
                 "Run the side-of-plane audit with this many queries instead of drawing cases");
  app.add_flag("--list-classes", list, "Print the class names and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    if (list) {
      for (int k = 0; k < case_class_count; ++k) std::printf("%s\n", std::string(class_name(static_cast<CaseClass>(k))).c_str());
      return 0;
    }
    if (!replays.empty()) return replay(replays);
    if (audit_queries > 0) return audit(audit_queries, seed, threads);
    return run_cases(cases, seed, first, only, threads, reproducers);
  } catch (const CLI::ValidationError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
