// Loop linking (triangulate/cap.hpp, link_loops): border edges into closed loops
// of vertex indices. Properties over generated cycle sets, shuffled and sparsely
// numbered, with and without pinch vertices (several loops through one vertex),
// and over the border edges of real cuts in both kernels. No floating-point value
// is involved: linking is by index alone, which is what these tests pin down.

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "shatter/kernel/exact.hpp"
#include "shatter/oracle/slice.hpp"
#include "shatter/triangulate/cap.hpp"
#include "support/cut_cases.hpp"
#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"

using namespace shatter;
using namespace shatter::oracle;
using namespace shatter::test;

namespace {

using Loop = std::vector<VertexIndex>;

// A loop as a cyclic sequence, rotated to start at its smallest vertex: two
// loops are the same cycle exactly when their canonical forms are equal.
// Precondition: no vertex repeats in the loop.
Loop canonical(Loop loop) {
  std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());
  return loop;
}

std::multiset<std::pair<VertexIndex, VertexIndex>> edge_multiset(const std::vector<Edge>& border) {
  std::multiset<std::pair<VertexIndex, VertexIndex>> edges;
  for (const Edge& e : border) edges.insert({e[0], e[1]});
  return edges;
}

// Empty when the loops use every border edge exactly once, each loop a closed
// walk along border edges (its last vertex joined to its first); else what is wrong.
std::string partition_problem(const std::vector<Loop>& loops, const std::vector<Edge>& border) {
  std::multiset<std::pair<VertexIndex, VertexIndex>> walked;
  for (const Loop& loop : loops) {
    if (loop.empty()) return "an empty loop";
    for (std::size_t i = 0; i < loop.size(); ++i) walked.insert({loop[i], loop[(i + 1) % loop.size()]});
  }
  if (walked != edge_multiset(border)) return "the loops' edges are not the border edges, each once";
  return {};
}

// Vertices with more than one border edge leaving them: the only places a loop
// may pass twice.
std::set<VertexIndex> pinch_vertices(const std::vector<Edge>& border) {
  std::map<VertexIndex, int> out_degree;
  for (const Edge& e : border) ++out_degree[e[0]];
  std::set<VertexIndex> pinches;
  for (const auto& [v, degree] : out_degree) {
    if (degree > 1) pinches.insert(v);
  }
  return pinches;
}

// A vertex numbering far from 0..n: sparse, large indices, so that linking can
// rely on nothing but equality of indices.
VertexIndex sparse_label(Random& random, std::set<VertexIndex>& used) {
  for (;;) {
    const auto v = static_cast<VertexIndex>(random.next() % 0xFFFFFFF0u);
    if (used.insert(v).second) return v;
  }
}

template <class T>
void shuffle(std::vector<T>& items, Random& random) {
  for (std::size_t i = items.size(); i > 1; --i) std::swap(items[i - 1], items[random.index(i)]);
}

// Disjoint cycles of 3 to 40 vertices, with their edges in random order.
struct Cycles {
  std::vector<Loop> cycles;
  std::vector<Edge> border;
};
Cycles disjoint_cycles(Random& random, std::size_t count) {
  Cycles out;
  std::set<VertexIndex> used;
  for (std::size_t c = 0; c < count; ++c) {
    Loop cycle(3 + random.index(38));
    for (VertexIndex& v : cycle) v = sparse_label(random, used);
    for (std::size_t i = 0; i < cycle.size(); ++i) out.border.push_back({cycle[i], cycle[(i + 1) % cycle.size()]});
    out.cycles.push_back(canonical(cycle));
  }
  shuffle(out.border, random);
  return out;
}

}  // namespace

TEST_CASE("link_loops returns each disjoint cycle once, whatever the edge order and numbering", "[loops]") {
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    Random random(seed);
    const Cycles input = disjoint_cycles(random, 1 + random.index(12));
    INFO("seed " << seed << ": " << input.cycles.size() << " cycles, " << input.border.size() << " edges");
    const std::vector<Loop> loops = link_loops(input.border);
    CHECK(partition_problem(loops, input.border) == "");
    std::vector<Loop> found;
    for (const Loop& loop : loops) found.push_back(canonical(loop));
    std::vector<Loop> expected = input.cycles;
    std::sort(found.begin(), found.end());
    std::sort(expected.begin(), expected.end());
    CHECK(found == expected);
    // Each loop starts where one of its edges does and runs in the edges' direction:
    // reversing every edge reverses every loop.
    std::vector<Edge> reversed = input.border;
    for (Edge& e : reversed) std::swap(e[0], e[1]);
    std::vector<Loop> back;
    for (Loop loop : link_loops(reversed)) {
      std::reverse(loop.begin(), loop.end());
      back.push_back(canonical(loop));
    }
    std::sort(back.begin(), back.end());
    CHECK(back == expected);
  }
}

TEST_CASE("link_loops at pinch vertices: every edge once, a loop revisits only a pinch", "[loops]") {
  // Cycles that share vertices: each new cycle runs through 1 to 3 vertices of
  // earlier ones (as caps do where a plane touches a saddle vertex or an edge
  // shared by two loops' corners). In- and out-degrees stay equal, as the cap's
  // precondition requires; which cycles a loop strings together at a pinch is
  // left to link_loops, so only the partition and the revisits are pinned down.
  std::size_t pinched_inputs = 0, loops_through_a_pinch_twice = 0;
  for (std::uint64_t seed = 1; seed <= 300; ++seed) {
    Random random(seed * 7919);
    std::set<VertexIndex> used;
    std::vector<VertexIndex> earlier;
    std::vector<Edge> border;
    const std::size_t cycle_count = 2 + random.index(8);
    for (std::size_t c = 0; c < cycle_count; ++c) {
      Loop cycle(3 + random.index(10));
      for (VertexIndex& v : cycle) v = sparse_label(random, used);
      if (!earlier.empty()) {
        // Replace 1 to 3 of its vertices, not adjacent to one another, by earlier vertices.
        const std::size_t shared = 1 + random.index(3);
        std::set<VertexIndex> taken;
        for (std::size_t k = 0; k < shared && 2 * k < cycle.size(); ++k) {
          const VertexIndex pinch = earlier[random.index(earlier.size())];
          if (!taken.insert(pinch).second) continue;
          cycle[2 * k] = pinch;
        }
      }
      earlier.insert(earlier.end(), cycle.begin(), cycle.end());
      for (std::size_t i = 0; i < cycle.size(); ++i) border.push_back({cycle[i], cycle[(i + 1) % cycle.size()]});
    }
    shuffle(border, random);
    const std::set<VertexIndex> pinches = pinch_vertices(border);
    pinched_inputs += pinches.empty() ? 0 : 1;
    INFO("seed " << seed << ": " << border.size() << " edges, " << pinches.size() << " pinch vertices");
    const std::vector<Loop> loops = link_loops(border);
    CHECK(partition_problem(loops, border) == "");
    for (const Loop& loop : loops) {
      std::map<VertexIndex, int> visits;
      for (const VertexIndex v : loop) ++visits[v];
      for (const auto& [v, count] : visits) {
        if (count > 1) {
          CHECK(pinches.count(v) == 1);
          ++loops_through_a_pinch_twice;
        }
      }
    }
  }
  CHECK(pinched_inputs > 250);
  CHECK(loops_through_a_pinch_twice > 0);  // the generator does make loops pass a pinch twice
}

TEST_CASE("link_loops of the border edges of real cuts, both kernels", "[loops][slice]") {
  // Every cut of the generated catalogue and of the corpus meshes by planes of
  // every kind (support/cut_cases.hpp): the border of each cut is partitioned
  // into closed loops, and a loop passes a vertex twice only where the border
  // is pinched there.
  std::vector<NamedMesh> meshes = generated_meshes();
  for (NamedMesh& m : corpus_meshes()) meshes.push_back(std::move(m));
  REQUIRE(meshes.size() > 15);
  std::size_t cuts = 0, loops_found = 0;
  for (const NamedMesh& m : meshes) {
    const ExactMesh exact = to_exact(m.mesh);
    for (const TestPlane& test_plane : planes_for(m.mesh, 17, 3)) {
      const Plane& plane = test_plane.plane;
      INFO(m.name << " plane (" << plane.normal.x << ", " << plane.normal.y << ", " << plane.normal.z << "; "
                  << plane.offset << ")");
      for (const std::vector<Edge>& border :
           {slice_mesh(m.mesh, plane).border_edges, slice_mesh(exact, plane).border_edges}) {
        const std::vector<Loop> loops = link_loops(border);
        CHECK(partition_problem(loops, border) == "");
        const std::set<VertexIndex> pinches = pinch_vertices(border);
        for (const Loop& loop : loops) {
          std::set<VertexIndex> seen;
          for (const VertexIndex v : loop) {
            if (!seen.insert(v).second) CHECK(pinches.count(v) == 1);
          }
        }
        loops_found += loops.size();
        ++cuts;
      }
    }
  }
  CHECK(cuts == 2 * 7 * meshes.size());
  CHECK(loops_found > cuts / 2);
}

TEST_CASE("link_loops: no edges, no loops, and a million edges in one shuffled loop in linear time", "[loops]") {
  CHECK(link_loops({}).empty());
  // A quadratic search for each next edge would take minutes here (10^12 probes);
  // the hash map from start vertex to edge takes milliseconds.
  constexpr VertexIndex n = 1u << 20;
  Random random(5);
  std::vector<VertexIndex> order(n);
  for (VertexIndex i = 0; i < n; ++i) order[i] = i * 2654435761u;  // distinct: odd multiplier mod 2^32
  shuffle(order, random);
  std::vector<Edge> border;
  border.reserve(n);
  for (VertexIndex i = 0; i < n; ++i) border.push_back({order[i], order[(i + 1) % n]});
  shuffle(border, random);
  const std::vector<Loop> loops = link_loops(border);
  REQUIRE(loops.size() == 1);
  REQUIRE(loops[0].size() == n);
  const auto start = std::find(order.begin(), order.end(), loops[0][0]) - order.begin();
  std::size_t mismatches = 0;
  for (VertexIndex i = 0; i < n; ++i) mismatches += loops[0][i] != order[(static_cast<std::size_t>(start) + i) % n];
  CHECK(mismatches == 0);
}
