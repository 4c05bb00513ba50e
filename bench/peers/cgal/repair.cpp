// CGAL 5.5's repair of a damaged mesh, the peer of `shatter validate --repair` in
// bench/repair-rate (issue 21: the share of real inputs repaired into valid solids,
// against CGAL's and Manifold's handling of the same files in the same run).
//
//   shatter-peer-cgal-repair IN OUT.off      repair IN, write the result to OUT.off
//   shatter-peer-cgal-repair --soup IN OUT.off   write IN's polygons as read (no repair),
//                                             so that a peer reading only OFF gets the
//                                             same soup
//
// The repair is the pipeline CGAL's manual gives for a polygon soup (Polygon Mesh
// Processing, "Combinatorial Repairing" and "Geometric Repair"), each step as CGAL 5.5
// ships it, with its default parameters:
//   repair_polygon_soup, orient_polygon_soup, polygon_soup_to_polygon_mesh,
//   stitch_borders, duplicate_non_manifold_vertices, remove_degenerate_faces,
//   triangulate_hole on every border cycle, then, if the mesh still intersects itself,
//   experimental::autorefine_and_remove_self_intersections (and, if that gives up,
//   experimental::remove_self_intersections), and orient_to_bound_a_volume once closed.
// Whether the result is a valid solid is not this program's call: bench/repair-rate
// judges every tool's output with shatter's exact validator, so that one judge rules
// on all of them. One JSON line goes to stdout: the steps that changed something, the
// seconds of the repair alone (reading and writing excluded), and an error if CGAL
// could not read the file or threw.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/manifoldness.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_mesh_to_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_degeneracies.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/repair_self_intersections.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/version.h>
#include <CGAL/boost/graph/helpers.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Polygon = std::vector<std::size_t>;

// OFF with every coordinate at 17 significant digits, so that the judge reads back
// the doubles CGAL computed.
bool write_off(const std::string& path, const std::vector<Point>& points, const std::vector<Polygon>& polygons) {
  std::ofstream out(path);
  out.precision(17);
  out << "OFF\n" << points.size() << ' ' << polygons.size() << " 0\n";
  for (const Point& p : points) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const Polygon& polygon : polygons) {
    out << polygon.size();
    for (std::size_t v : polygon) out << ' ' << v;
    out << '\n';
  }
  return static_cast<bool>(out);
}

bool write_mesh(const std::string& path, const SurfaceMesh& mesh) {
  std::vector<Point> points;
  std::vector<Polygon> polygons;
  PMP::polygon_mesh_to_polygon_soup(mesh, points, polygons);
  return write_off(path, points, polygons);
}

// The repair, recording in `steps` what each step changed (nothing recorded for a
// step that changed nothing).
void repair(std::vector<Point>& points, std::vector<Polygon>& polygons, SurfaceMesh& mesh, nlohmann::json& steps) {
  const std::size_t points_before = points.size(), polygons_before = polygons.size();
  PMP::repair_polygon_soup(points, polygons);
  if (points.size() != points_before || polygons.size() != polygons_before) {
    steps.push_back({{"repair_polygon_soup", {{"points_removed", points_before - points.size()},
                                              {"polygons_removed", polygons_before - polygons.size()}}}});
  }
  if (!PMP::orient_polygon_soup(points, polygons)) steps.push_back({{"orient_polygon_soup", "duplicated points"}});
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  if (!CGAL::is_triangle_mesh(mesh)) {
    PMP::triangulate_faces(mesh);
    steps.push_back({{"triangulate_faces", true}});
  }
  if (const std::size_t stitched = PMP::stitch_borders(mesh); stitched > 0) steps.push_back({{"stitch_borders", stitched}});
  if (const std::size_t split = PMP::duplicate_non_manifold_vertices(mesh); split > 0) {
    steps.push_back({{"duplicate_non_manifold_vertices", split}});
  }
  const std::size_t faces_before = num_faces(mesh);
  if (!PMP::remove_degenerate_faces(mesh)) steps.push_back({{"remove_degenerate_faces", "not all removed"}});
  mesh.collect_garbage();
  if (num_faces(mesh) != faces_before) steps.push_back({{"remove_degenerate_faces", faces_before - num_faces(mesh)}});

  std::vector<SurfaceMesh::Halfedge_index> borders;
  PMP::extract_boundary_cycles(mesh, std::back_inserter(borders));
  std::size_t filled = 0;
  for (SurfaceMesh::Halfedge_index h : borders) {
    std::vector<SurfaceMesh::Face_index> lid;
    PMP::triangulate_hole(mesh, h, std::back_inserter(lid));
    filled += !lid.empty();
  }
  if (!borders.empty()) steps.push_back({{"triangulate_hole", filled}, {"holes", borders.size()}});

  if (PMP::does_self_intersect(mesh)) {
    if (PMP::experimental::autorefine_and_remove_self_intersections(mesh)) {
      steps.push_back({{"autorefine_and_remove_self_intersections", true}});
    } else {
      const bool removed_all = PMP::experimental::remove_self_intersections(mesh);
      steps.push_back({{"autorefine_and_remove_self_intersections", false},
                       {"remove_self_intersections", removed_all}});
    }
  }
  if (CGAL::is_closed(mesh) && !PMP::does_self_intersect(mesh)) PMP::orient_to_bound_a_volume(mesh);
}

}  // namespace

int main(int argc, char** argv) {
  const bool soup_only = argc == 4 && std::string(argv[1]) == "--soup";
  if (argc != 3 && !soup_only) {
    std::cerr << "usage: shatter-peer-cgal-repair [--soup] IN OUT.off\n";
    return 2;
  }
  const std::string in = argv[argc - 2], out = argv[argc - 1];
  nlohmann::json line{{"tool", "CGAL " CGAL_STRINGIZE(CGAL_VERSION)}, {"steps", nlohmann::json::array()}};
  std::vector<Point> points;
  std::vector<Polygon> polygons;
  if (!CGAL::IO::read_polygon_soup(in, points, polygons, CGAL::parameters::verbose(false)) || polygons.empty()) {
    line["error"] = "CGAL could not read the file (or it holds no polygon)";
    std::cout << line.dump() << '\n';
    return 1;
  }
  if (soup_only) return write_off(out, points, polygons) ? 0 : 1;
  SurfaceMesh mesh;
  const auto start = std::chrono::steady_clock::now();
  try {
    repair(points, polygons, mesh, line["steps"]);
  } catch (const std::exception& e) {
    line["error"] = std::string("CGAL threw: ") + e.what();
  }
  line["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (line.contains("error") || !write_mesh(out, mesh)) {
    if (!line.contains("error")) line["error"] = "could not write " + out;
    std::cout << line.dump() << '\n';
    return 1;
  }
  std::cout << line.dump() << '\n';
  return 0;
}
