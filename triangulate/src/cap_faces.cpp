#include "shatter/triangulate/cap_faces.hpp"

#include <vector>

#include "shatter/kernel/face_loops.hpp"
#include "shatter/kernel/index_map.hpp"

namespace shatter {
namespace {

// Appends one region as a face of `caps`, and the same region reversed to
// `reversed_caps`.
void append_region(const Region& region, PlaneRef cut, SurfaceId surface, bool convex, FaceSet& caps,
                   FaceSet& reversed_caps) {
  SolidFace face;
  face.plane = cut;
  face.surface = surface;
  face.convex = convex;
  face.loop_count = static_cast<std::uint32_t>(region.loops.size());
  SolidFace back = face;
  back.reversed = true;
  face.first_loop = static_cast<std::uint32_t>(caps.loops.size());
  back.first_loop = static_cast<std::uint32_t>(reversed_caps.loops.size());
  for (const auto& loop : region.loops) {
    const auto count = static_cast<std::uint32_t>(loop.size());
    caps.loops.push_back({static_cast<std::uint32_t>(caps.corners.size()), count});
    for (const LoopEdge& edge : loop) caps.corners.push_back({edge.from, edge.line});
    // Reversed: the loop runs backwards, each edge keeping its line.
    reversed_caps.loops.push_back({static_cast<std::uint32_t>(reversed_caps.corners.size()), count});
    for (std::uint32_t k = count; k-- > 0;) reversed_caps.corners.push_back({loop[k].to, loop[k].line});
  }
  caps.faces.push_back(face);
  reversed_caps.faces.push_back(back);
}

}  // namespace

void make_caps(const PlaneSet& set, PlaneRef cut, std::span<const PointDef> defs,
               std::span<const ApproxPoint> approx, std::span<const LoopEdge> border, bool convex, SurfaceId surface,
               FaceSet& below_cap, FaceSet& above_cap, std::span<const LoopEdge> below_chords,
               std::span<const LoopEdge> above_chords) {
  below_cap.clear();
  above_cap.clear();
  if (border.empty()) return;
  thread_local std::vector<LoopEdge> edges;
  thread_local std::vector<Region> regions;
  edges.clear();
  for (const LoopEdge& e : border) edges.push_back({e.to, e.from, e.line});  // the below cap runs them reversed
  if (convex) {
    // One convex loop: link by index, nothing to decide.
    thread_local IndexMap next_of;
    next_of.reset(edges.size());
    for (std::uint32_t e = 0; e < edges.size(); ++e) next_of.insert(edges[e].from, e);
    regions.resize(1);
    auto& loop = regions.front().loops;
    loop.resize(1);
    loop.front().clear();
    for (std::uint32_t e = 0; loop.front().size() < edges.size();) {
      loop.front().push_back(edges[e]);
      e = next_of.find(edges[e].to);
    }
    append_region(regions.front(), cut, surface, true, below_cap, above_cap);
    return;
  }
  const FaceGeometry geometry{set, defs, approx, projection_of(set, cut), false};
  // One side's cap, split along that side's chords when it has any; a side
  // without chords takes the regions of the border alone. (Grouping reorders
  // the edges it is given: each side starts from the border again.)
  thread_local std::vector<LoopEdge> reversed_border;
  thread_local FaceSet unused;
  reversed_border.assign(edges.begin(), edges.end());
  const auto add_regions = [&](std::span<const LoopEdge> chords, FaceSet* below, FaceSet* above) {
    edges.assign(reversed_border.begin(), reversed_border.end());
    edges.insert(edges.end(), chords.begin(), chords.end());
    group_into_regions(geometry, edges, regions);
    for (const Region& region : regions) {
      const bool region_convex = region.loops.size() == 1 && is_convex_loop(geometry, region.loops.front());
      unused.clear();
      append_region(region, cut, surface, region_convex, below ? *below : unused, above ? *above : unused);
    }
  };
  if (below_chords.empty() && above_chords.empty()) {
    add_regions({}, &below_cap, &above_cap);
    return;
  }
  add_regions(below_chords, &below_cap, above_chords.empty() ? &above_cap : nullptr);
  if (!above_chords.empty()) add_regions(above_chords, nullptr, &above_cap);
}

}  // namespace shatter
