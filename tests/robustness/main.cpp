// shatter-fuzz: the robustness runner. Draws seeded cases from every degenerate
// class and every mesh, runs slice chains (the one cut call) and fractures (the
// builder), checks every invariant, writes every output piece and
// reads it back, prints a per-class table and writes a reproducer for each
// failure. Also replays reproducers and runs the predicate audit (side_of_plane
// and the plane kernel's predicates).

#include <CLI/CLI.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <cfenv>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "robustness/corpus_export.hpp"
#include "robustness/repair_fuzz.hpp"
#include "robustness/robustness.hpp"
#include "shatter/kernel/implicit.hpp"
#include "shatter/kernel/predicates.hpp"
#include "shatter/meshtree/build.hpp"

namespace {

using namespace shatter;
using namespace shatter::robust;

struct ClassTotals {
  std::size_t cases = 0, slices = 0, fractures = 0, failures = 0, refused = 0, pieces = 0;
  std::size_t written = 0, invalid_written = 0, unroundable = 0, vanished = 0, pinched = 0, separated = 0;
  double seconds = 0;

  void add(const ClassTotals& t) {
    cases += t.cases, slices += t.slices, fractures += t.fractures, failures += t.failures, refused += t.refused;
    pieces += t.pieces, written += t.written, invalid_written += t.invalid_written;
    unroundable += t.unroundable, vanished += t.vanished, pinched += t.pinched, separated += t.separated;
    seconds += t.seconds;
  }
};

double percent(std::size_t part, std::size_t whole) { return whole ? 100.0 * double(part) / double(whole) : 0.0; }

// Columns: cases and operations; failed and refused cases; exact solids
// checked (pieces and tree nodes); output pieces written and read back, and
// those invalid as read back; pieces round_solid refused to write (unround),
// pieces thinner than their rounding that collapsed whole and vanish (vanish),
// and cuts cut_solid refused as pinching (pinch).
ClassTotals print_table(const std::array<ClassTotals, case_class_count>& totals) {
  std::printf("%-19s %6s %5s %5s %6s %7s %7s %7s %7s %7s %6s %6s %7s\n", "class", "cases", "slice", "fract", "failed",
              "refused", "solids", "written", "invalid", "unround", "vanish", "pinch", "ms/case");
  ClassTotals all;
  auto row = [](const char* name, const ClassTotals& t) {
    std::printf("%-19s %6zu %5zu %5zu %6zu %7zu %7zu %7zu %7zu %7zu %6zu %6zu %7.2f\n", name, t.cases, t.slices,
                t.fractures, t.failures, t.refused, t.pieces, t.written, t.invalid_written, t.unroundable, t.vanished,
                t.pinched,
                t.cases ? 1e3 * t.seconds / double(t.cases) : 0.0);
  };
  for (int k = 0; k < case_class_count; ++k) {
    const ClassTotals& t = totals[k];
    if (t.cases == 0) continue;
    row(std::string(class_name(static_cast<CaseClass>(k))).c_str(), t);
    all.add(t);
  }
  row("all", all);
  return all;
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
  std::printf("FAIL %s %s on %s (seed %llu): %s\n     reproducer %s (%s)\n",
              std::string(class_name(c.kind)).c_str(), std::string(operation_name(c.op)).c_str(),
              c.mesh_name.c_str(), (unsigned long long)c.seed,
              failure.c_str(), path.string().c_str(), reproduces ? "reproduces" : "DOES NOT reproduce when replayed");
}

// Ceilings on the documented refusals of a run (none when unset): a run that
// refuses more than its ceiling fails like a run with a failing case, so a change
// that makes the library refuse more cannot pass as "refused, not failed". CTest
// sets them from a measured run of the same seed and case count.
struct RefusalCeilings {
  std::optional<std::size_t> cases;        ///< cases refused (UnsupportedGeometryError): fractures
  std::optional<std::size_t> unroundable;  ///< pieces round_solid could not write validly
  std::optional<std::size_t> pinched;      ///< cuts refused as pinching a piece
};

// Prints each refusal count against its ceiling; false when one is passed.
bool within_ceilings(const RefusalCeilings& ceilings, std::size_t cases, std::size_t unroundable,
                     std::size_t pinched) {
  bool within = true;
  const auto check = [&](const char* what, std::size_t count, const std::optional<std::size_t>& ceiling) {
    if (!ceiling) return;
    const bool ok = count <= *ceiling;
    std::printf("refusal ceiling: %s %zu, ceiling %zu%s\n", what, count, *ceiling, ok ? "" : ": PASSED, a regression");
    within &= ok;
  };
  check("refused cases", cases, ceilings.cases);
  check("unroundable pieces", unroundable, ceilings.unroundable);
  check("pinching cuts", pinched, ceilings.pinched);
  return within;
}

// The indices of the `cases` cases a run draws from `first` on, of the classes
// named in `only` (every class when empty).
std::vector<std::uint64_t> selected_indices(std::uint64_t cases, std::uint64_t first, const std::vector<std::string>& only) {
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
  return indices;
}

int export_cases(std::uint64_t cases, std::uint64_t seed, std::uint64_t first, const std::vector<std::string>& only,
                 const std::filesystem::path& dir) {
  const std::vector<std::uint64_t> indices = selected_indices(cases, first, only);
  const ExportSummary summary = export_corpus(MeshPool::load(), seed, indices, dir);
  std::printf("exported %zu cases (%zu mesh files, %.1f MB) to %s\n", summary.cases, summary.mesh_files,
              double(summary.bytes) / 1e6, dir.string().c_str());
  return 0;
}

int run_cases(std::uint64_t cases, std::uint64_t seed, std::uint64_t first, const std::vector<std::string>& only,
              unsigned threads, const std::filesystem::path& reproducer_dir, const RefusalCeilings& ceilings,
              const std::filesystem::path& refusal_dir) {
  const std::vector<std::uint64_t> indices = selected_indices(cases, first, only);

  const auto start = std::chrono::steady_clock::now();
  const MeshPool pool = MeshPool::load();
  struct Ran {
    Case c;
    CaseOutcome outcome;
    double seconds = 0;
    PredicateCounters predicates;  ///< side-of-plane calls made on the case's own thread
    ImplicitCounters implicit;     ///< plane-kernel predicate calls made on the case's own thread
  };
  std::vector<Ran> ran(indices.size());
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(std::size_t(0), indices.size(), [&](std::size_t i) {
      const auto t0 = std::chrono::steady_clock::now();
      Case c = make_case(pool, seed, indices[i]);
      const PredicateCounters before = predicate_counters();
      const ImplicitCounters implicit_before = implicit_counters();
      CaseOutcome outcome = run_case(c);
      ran[i].predicates = {predicate_counters().side_of_plane_calls - before.side_of_plane_calls,
                           predicate_counters().side_of_plane_exact - before.side_of_plane_exact};
      // The kernel's own calls: the checks' are left out (check_solid asks
      // whether every corner lies on its face's plane, true zeros every one).
      const ImplicitCounters& now = implicit_counters();
      const ImplicitCounters& checks = outcome.checker_predicates;
      ran[i].implicit.side_calls = now.side_calls - implicit_before.side_calls - checks.side_calls;
      ran[i].implicit.side_exact = now.side_exact - implicit_before.side_exact - checks.side_exact;
      ran[i].implicit.orient_calls = now.orient_calls - implicit_before.orient_calls - checks.orient_calls;
      ran[i].implicit.orient_exact = now.orient_exact - implicit_before.orient_exact - checks.orient_exact;
      ran[i].implicit.order_calls = now.order_calls - implicit_before.order_calls - checks.order_calls;
      ran[i].implicit.order_exact = now.order_exact - implicit_before.order_exact - checks.order_exact;
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
  ImplicitCounters implicit;
  for (const Ran& r : ran) {
    predicates.side_of_plane_calls += r.predicates.side_of_plane_calls;
    predicates.side_of_plane_exact += r.predicates.side_of_plane_exact;
    implicit.side_calls += r.implicit.side_calls, implicit.side_exact += r.implicit.side_exact;
    implicit.orient_calls += r.implicit.orient_calls, implicit.orient_exact += r.implicit.orient_exact;
    implicit.order_calls += r.implicit.order_calls, implicit.order_exact += r.implicit.order_exact;
    ClassTotals& t = totals[static_cast<std::size_t>(r.c.kind)];
    ++t.cases;
    (r.c.op == Operation::slice ? t.slices : t.fractures) += 1;
    t.failures += !r.outcome.failures.empty();
    t.refused += r.outcome.refused;
    t.pieces += r.outcome.plane_pieces;
    t.written += r.outcome.written;
    t.invalid_written += r.outcome.invalid_written;
    t.unroundable += r.outcome.plane_unroundable;
    t.vanished += r.outcome.plane_vanished;
    t.separated += r.outcome.plane_separated;
    t.pinched += r.outcome.plane_pinched;
    t.seconds += r.seconds;
    if (!r.outcome.failures.empty()) {
      ++failed;
      report_failure(r.c, r.outcome, reproducer_dir);
    }
    // Refusals are not failures; named on request, each case's with a
    // reproducer of its chain up to the first refused cut.
    if (!refusal_dir.empty() && !r.outcome.refusals.empty()) {
      std::string where;
      if (r.outcome.refused_prefix) {
        where = write_reproducer(refusal_dir, *r.outcome.refused_prefix, r.outcome.refusals.front()).string();
      }
      for (const std::string& refusal : r.outcome.refusals) {
        std::printf("REFUSED %s %s on %s (seed %llu): %s%s%s\n", std::string(class_name(r.c.kind)).c_str(),
                    std::string(operation_name(r.c.op)).c_str(), r.c.mesh_name.c_str(), (unsigned long long)r.c.seed,
                    refusal.c_str(), where.empty() ? "" : "\n     reproducer ", where.c_str());
        where.clear();
      }
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("shatter-fuzz: %zu cases from seed %llu (first index %llu), %.1f s wall\n", ran.size(),
              (unsigned long long)seed, (unsigned long long)first, wall);
  const ClassTotals all = print_table(totals);
  std::printf("output pieces invalid as written: %.2f%% (%zu of %zu); written after separating points where they "
              "touched themselves: %zu\n",
              percent(all.invalid_written, all.written), all.invalid_written, all.written, all.separated);
  std::printf("refused (not failures): fracture cases %zu; pieces round_solid could not write validly %zu; cuts "
              "refused as pinching %zu; pieces that vanished (thinner than their rounding, not refused) %zu\n",
              all.refused, all.unroundable, all.pinched, all.vanished);
  // Counted on each case's own thread: the cuts and checks, not work a fracture
  // hands to other threads.
  std::printf("side_of_plane: %llu calls, %llu fell back to exact arithmetic (%.3f%%)\n",
              (unsigned long long)predicates.side_of_plane_calls, (unsigned long long)predicates.side_of_plane_exact,
              predicates.side_of_plane_calls
                  ? 100.0 * double(predicates.side_of_plane_exact) / double(predicates.side_of_plane_calls)
                  : 0.0);
  auto rate = [](std::uint64_t exact, std::uint64_t calls) { return calls ? 100.0 * double(exact) / double(calls) : 0.0; };
  std::printf("plane kernel predicates (the kernel's calls, not the checks'): side %llu calls (%.3f%% exact), orient_in_plane %llu (%.3f%%), "
              "compare %llu (%.3f%%)\n",
              (unsigned long long)implicit.side_calls, rate(implicit.side_exact, implicit.side_calls),
              (unsigned long long)implicit.orient_calls, rate(implicit.orient_exact, implicit.orient_calls),
              (unsigned long long)implicit.order_calls, rate(implicit.order_exact, implicit.order_calls));
  std::printf("%zu failing case%s\n", failed, failed == 1 ? "" : "s");
  const bool within = within_ceilings(ceilings, all.refused, all.unroundable, all.pinched);
  return failed == 0 && within ? 0 : 1;
}

int replay(const std::vector<std::string>& files) {
  std::size_t failed = 0;
  for (const std::string& file : files) {
    const Case c = read_reproducer(file);
    CaseOutcome outcome = run_case(c);
    if (outcome.failures.empty()) {
      if (std::string unmet = unmet_expectation(c, outcome); !unmet.empty()) outcome.failures.push_back(std::move(unmet));
    }
    std::string result;
    if (!outcome.failures.empty()) {
      result = outcome.failures.front();
      if (outcome.failures.size() > 1) result += " (and " + std::to_string(outcome.failures.size() - 1) + " more)";
    } else {
      result = outcome.refused ? "refused (unsupported)" : "passes";
      if (c.expected != Expected::no_failure) result += " as expected (" + std::string(expected_name(c.expected)) + ")";
      result += "; " + std::to_string(outcome.written) + " pieces written as " + std::string(format_name(c.format)) +
                ", " + std::to_string(outcome.invalid_written) + " invalid as written, " +
                std::to_string(outcome.plane_unroundable) + " not roundable, " +
                std::to_string(outcome.plane_vanished) + " vanished (thinner than their rounding), " +
                std::to_string(outcome.plane_pinched) + " pinching cuts refused";
    }
    std::printf("%s: %s %s on %s: %s\n", file.c_str(), std::string(class_name(c.kind)).c_str(),
                std::string(operation_name(c.op)).c_str(), c.mesh_name.c_str(), result.c_str());
    for (const std::string& refusal : outcome.refusals) std::printf("  refused: %s\n", refusal.c_str());
    failed += !outcome.failures.empty();
  }
  return failed == 0 ? 0 : 1;
}

// --audit-predicates N: half the queries (N / 2) audit side_of_plane (on input
// points); the rest audit the plane kernel's predicates (implicit.hpp).
int audit(std::uint64_t queries, std::uint64_t seed, unsigned threads) {
  const std::uint64_t old_queries = queries / 2, plane_queries = queries - old_queries;
  auto start = std::chrono::steady_clock::now();
  const AuditResult r = audit_side_of_plane(old_queries, seed, threads);
  double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("predicate audit (seed %llu): %llu queries, %llu of side_of_plane and %llu of the plane kernel's\n",
              (unsigned long long)seed, (unsigned long long)queries, (unsigned long long)old_queries,
              (unsigned long long)plane_queries);
  std::printf("side_of_plane: %llu queries\n", (unsigned long long)r.queries);
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

  start = std::chrono::steady_clock::now();
  const PlaneAuditResult p = audit_plane_predicates(plane_queries, seed, threads);
  wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("plane kernel predicates: %llu queries\n", (unsigned long long)p.queries);
  std::printf("  agree with the GMP reference: %llu of %llu (%llu disagreements)\n",
              (unsigned long long)(p.queries - p.disagreements), (unsigned long long)p.queries,
              (unsigned long long)p.disagreements);
  std::printf("  bands: exact = lattice scene as built (hubs exactly on their planes); 1-4 ulps = cut offsets "
              "and a quarter of the input points moved 1-4 ulps; 2^3..2^40 = moved that many ulps\n");
  std::printf("  %-34s | %9s %7s %8s %5s | %9s %7s %8s %5s | %9s %7s %8s %5s\n", "predicate", "exact", "zero",
              "fallback", "dis", "1-4 ulps", "zero", "fallback", "dis", "2^3..2^40", "zero", "fallback", "dis");
  std::array<AuditBand, 3> totals{};
  std::array<std::uint64_t, 3> total_disagreements{};
  auto cells = [](const AuditBand& b, std::uint64_t disagreements) {
    std::printf(" | %9llu %7llu %7.2f%% %5llu", (unsigned long long)b.queries, (unsigned long long)b.on_plane,
                b.queries ? 100.0 * double(b.exact_fallbacks) / double(b.queries) : 0.0,
                (unsigned long long)disagreements);
  };
  for (int row = 0; row < plane_audit_rows; ++row) {
    std::printf("  %-34s", std::string(plane_audit_row_name(row)).c_str());
    for (std::size_t b = 0; b < 3; ++b) {
      const AuditBand& cell = p.bands[std::size_t(row)][b];
      const std::uint64_t disagreements = p.band_disagreements[std::size_t(row)][b];
      cells(cell, disagreements);
      totals[b].queries += cell.queries, totals[b].on_plane += cell.on_plane;
      totals[b].exact_fallbacks += cell.exact_fallbacks, total_disagreements[b] += disagreements;
    }
    std::printf("\n");
  }
  std::printf("  %-34s", "all");
  for (std::size_t b = 0; b < 3; ++b) cells(totals[b], total_disagreements[b]);
  std::printf("\n");
  std::printf("  %.1f s wall\n", wall);
  if (p.disagreements) std::printf("  first disagreement: %s\n", p.first_disagreement.c_str());
  return r.disagreements == 0 && r.queries == old_queries && p.disagreements == 0 && p.queries == plane_queries ? 0 : 1;
}

// The repair cases (repair_fuzz.hpp): a table per damage class of what came
// back valid, what was refused (with the most common defect) and what broke a
// promise. Exit 1 on a failure or on more refusals than `max_refused`.
int run_repair_cases(std::uint64_t cases, std::uint64_t seed, std::uint64_t first, unsigned threads,
                     std::optional<std::size_t> max_refused, bool list_refusals) {
  const auto start = std::chrono::steady_clock::now();
  const MeshPool pool = MeshPool::load();
  struct Ran {
    DamageCase c;
    DamageOutcome outcome;
  };
  std::vector<Ran> ran(cases);
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : int(threads));
  arena.execute([&] {
    tbb::parallel_for(std::uint64_t(0), cases, [&](std::uint64_t i) {
      DamageCase c = make_damage_case(pool, seed, first + i);
      ran[i].outcome = run_damage_case(c);
      c.original = {}, c.damaged = {}, c.kept = {};
      ran[i].c = std::move(c);
    });
  });
  struct Totals {
    std::size_t cases = 0, valid = 0, refused = 0, failed = 0, changes = 0, pieces = 0, unroundable = 0, pinched = 0;
    double worst_volume_change = 0;
    std::map<std::string, std::size_t> refusals;
  };
  std::array<Totals, damage_class_count> totals{};
  std::size_t failed = 0, refused = 0;
  for (const Ran& r : ran) {
    Totals& t = totals[static_cast<std::size_t>(r.c.kind)];
    ++t.cases;
    t.valid += r.outcome.valid;
    t.changes += r.outcome.changes;
    t.pieces += r.outcome.pieces, t.unroundable += r.outcome.unroundable, t.pinched += r.outcome.pinched;
    if (r.outcome.valid) t.worst_volume_change = std::max(t.worst_volume_change, r.outcome.volume_change);
    if (!r.outcome.valid) {
      ++t.refused, ++refused, ++t.refusals[r.outcome.refusal.substr(0, r.outcome.refusal.find(':'))];
      if (list_refusals)
        std::printf("refused %s case seed %016llx (%s): %s\n", std::string(damage_name(r.c.kind)).c_str(),
                    (unsigned long long)r.c.seed, r.c.mesh_name.c_str(), r.outcome.refusal.c_str());
    }
    if (!r.outcome.failures.empty()) {
      ++t.failed, ++failed;
      for (const std::string& f : r.outcome.failures) std::printf("FAIL case seed %016llx: %s\n", (unsigned long long)r.c.seed, f.c_str());
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("shatter-fuzz --repair-cases %llu --seed %llu: repair_mesh on damaged meshes, then one cut of each repaired solid\n",
              (unsigned long long)cases, (unsigned long long)seed);
  std::printf("  %-12s %6s %6s %8s %7s %7s %7s %11s %9s  %s\n", "damage", "cases", "valid", "refused", "failed",
              "pieces", "unround", "pinched", "max dV/V", "most common refusal");
  for (int k = 0; k < damage_class_count; ++k) {
    const Totals& t = totals[std::size_t(k)];
    std::string common;
    std::size_t most = 0;
    for (const auto& [text, n] : t.refusals)
      if (n > most) most = n, common = text + " (" + std::to_string(n) + ")";
    std::printf("  %-12s %6zu %6zu %8zu %7zu %7zu %7zu %11zu %9.2g  %s\n",
                std::string(damage_name(static_cast<DamageClass>(k))).c_str(), t.cases, t.valid, t.refused, t.failed,
                t.pieces, t.unroundable, t.pinched, t.worst_volume_change, common.c_str());
  }
  std::printf("  %zu failed, %zu refused, %.1f s wall\n", failed, refused, wall);
  if (max_refused && refused > *max_refused) {
    std::printf("  more refusals than --max-repair-refused %zu\n", *max_refused);
    return 1;
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  // As the test main does (tests/support/catch_main.cpp): a NaN or an overflow
  // that the library does not hold on purpose stops the run where it is made.
  // The worker threads the run starts inherit the traps.
  feenableexcept(FE_INVALID | FE_DIVBYZERO | FE_OVERFLOW);
  CLI::App app{
      "shatter-fuzz: seeded robustness cases over every degenerate class (planes through vertices, along edges, "
      "holding faces and a few ulps off; grids; coplanar faces; slivers; nested shells; pinches; near-parallel "
      "chains; extreme scales; far from the origin; attribute seams) and every mesh of the test corpus (tests/data/corpus), sliced "
      "and fractured, every invariant of DESIGN.md checked and every output "
      "piece written and read back. Exit 0 when every case passes, 1 on "
      "any failure (each writes a reproducer), 2 on usage errors."};
  std::uint64_t cases = 2000, seed = 1, first = 0, audit_queries = 0;
  unsigned threads = 0;
  std::vector<std::string> only, replays;
  std::string reproducers = "shatter-fuzz-reproducers", refusal_reproducers;
  bool list = false;
  app.add_option("--cases", cases, "How many cases to run (default 2000)");
  app.add_option("--seed", seed, "Seed of the run; case i is drawn from (seed, i) alone (default 1)");
  app.add_option("--first", first, "Index of the first case, to split a long run into parts (default 0)");
  app.add_option("--class", only, "Run only these classes (repeatable; see --list-classes)");
  app.add_option("--threads", threads, "Worker threads, 0 for all (default 0); results do not depend on it");
  app.add_option("--reproducers", reproducers, "Folder for reproducer files (default shatter-fuzz-reproducers)");
  app.add_option("--refusal-reproducers", refusal_reproducers,
                 "Name every refusal (an unroundable piece with its defect, a pinching cut) and write a reproducer of "
                 "each refusing case's chain up to its first refused cut into this folder (default: neither)");
  app.add_option("--replay", replays, "Replay reproducer files instead of drawing cases")->check(CLI::ExistingFile);
  app.add_option("--audit-predicates", audit_queries,
                 "Run the predicate audit with this many queries instead of drawing cases: half of them audit "
                 "side_of_plane, half the plane kernel's predicates");
  app.add_flag("--list-classes", list, "Print the class names and exit");
  std::uint64_t repair_cases = 0;
  std::optional<std::size_t> max_repair_refused;
  app.add_option("--repair-cases", repair_cases,
                 "Run this many repair cases instead of cut cases: meshes of the pool damaged (unwelded, duplicated, "
                 "flipped, holed, nested the wrong way out, touching, overlapping, mixed, stray), repaired by repair_mesh, "
                 "every promise checked and each repaired solid cut once (--seed, --first and --threads apply)");
  bool list_repair_refusals = false;
  app.add_flag("--list-repair-refusals", list_repair_refusals,
               "With --repair-cases: print each damaged mesh left invalid, its defect and the repair's report");
  app.add_option("--max-repair-refused", max_repair_refused,
                 "Fail a repair run when more damaged meshes than this are left invalid after repair");
  std::string export_dir;
  app.add_option("--export-corpus", export_dir,
                 "Write the cases (as --cases, --seed, --first and --class select them) into this new folder instead of "
                 "running them: each mesh as an OBJ file and every case's planes or recipe in manifest.json, with a "
                 "README.md saying how to read them, for fuzzing other geometry code with the same cases");
  RefusalCeilings ceilings;
  app.add_option("--max-refused-cases", ceilings.cases,
                 "Fail the run when more cases than this are refused (UnsupportedGeometryError)");
  app.add_option("--max-unroundable", ceilings.unroundable,
                 "Fail the run when round_solid refuses to write more pieces than this");
  app.add_option("--max-pinched", ceilings.pinched,
                 "Fail the run when cut_solid refuses more cuts than this as pinching a piece");
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
    if (repair_cases > 0) return run_repair_cases(repair_cases, seed, first, threads, max_repair_refused, list_repair_refusals);
    if (!export_dir.empty()) return export_cases(cases, seed, first, only, export_dir);
    return run_cases(cases, seed, first, only, threads, reproducers, ceilings, refusal_reproducers);
  } catch (const CLI::ValidationError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
