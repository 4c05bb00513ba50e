// The bad-input matrix (issue 4, item 5): every kind of defective mesh file, in
// every format that can express it, through `validate`, `slice` and `fracture`.
// Each run must end with exit 3 (4 for I/O), exactly one printable `error: ` line
// on stderr naming the defect (and, where there is one, the first element at
// fault), no crash, and nothing left behind: no piece, no .shatter file, no
// folder, no temporary file. Every run is under a 1 GB address-space limit, so a
// reader that allocates what a hostile header claims fails here.

#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "shatter/generators/random.hpp"
#include "shatter/generators/solids.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/validate.hpp"
#include "support/binary.hpp"
#include "support/sanitizers.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {

// --- Running the command ------------------------------------------------------

// Address-space limit of every run, in KiB: far above what these tiny meshes need
// (the harness test below proves that), far below a header's multi-gigabyte claim.
constexpr const char* memory_limit_kib = "1000000";

// Under the sanitizers every run of shatter costs about half a second of start-up
// and leak check, and these cases run thousands: there the truncations take a
// fifth of the Release build's cuts and the garbage a third of the seeds, and slice and fracture
// run on a third of the cases (left_to_release_build). The memory safety of the
// readers on such bytes is what the sanitized run adds, and the libFuzzer targets
// (ASan and UBSan, about a million inputs per reader in each CI run) check it far
// more widely; the Release build runs the garbage's full set.
constexpr std::size_t sanitized_thinning = under_address_sanitizer ? 5 : 1;
// The truncations run the command at every third cut of the tetrahedron (every
// fifteenth under the sanitizers): what a run adds to the readers' own property,
// every cut of every format refused or read valid in process (test_io,
// "truncated files are refused or read as valid meshes, never a crash"), is the
// command's one line and exit status, which do not depend on the byte it stops
// at. At every byte these three cases were the Release suite's longest after
// shatter-fuzz (93, 70 and 19 s on a clean clone of fe3da8d, beside the
// sanitized build).
constexpr std::size_t truncation_stride = 3 * sanitized_thinning;
constexpr int garbage_seeds = under_address_sanitizer ? 4 : 12, header_garbage_seeds = under_address_sanitizer ? 3 : 8;

// AddressSanitizer reserves terabytes of shadow address space at start-up, so an
// ASan build of shatter cannot run under `ulimit -v`; there the same 1 GB cap is
// ASan's own: an allocation above it is reported and aborts (a signal, which
// every check below fails on), as the address-space limit would refuse it.
std::string memory_limit_prefix() {
  if (!under_address_sanitizer) return std::string("ulimit -v ") + memory_limit_kib + " && ";
  return "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}max_allocation_size_mb=1000\" && export ASAN_OPTIONS && ";
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

// The folder all cases run in, one per test process, removed when it exits.
fs::path scratch_root() {
  struct Root {
    fs::path path = fs::temp_directory_path() / ("shatter-bad-input-" + std::to_string(::getpid()));
    Root() {
      fs::remove_all(path);
      fs::create_directories(path);
    }
    ~Root() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  };
  static const Root root;
  return root.path;
}

struct Run {
  int exit_code = -1;  ///< -1 when killed by a signal
  int signal = 0;
  std::string out, err;
};

// Runs `shell_command` (with stdout and stderr captured) under the memory limit;
// `exec` makes the command the process whose status system() reports, so a crash
// shows as a signal, not as a shell's exit code.
Run run_limited(const std::string& shell_command) {
  const fs::path out = scratch_root() / "stdout.txt", err = scratch_root() / "stderr.txt";
  const std::string command = memory_limit_prefix() + "exec " + shell_command + " >" +
                              quoted(out) + " 2>" + quoted(err) + " </dev/null";
  const int status = std::system(command.c_str());
  Run run;
  if (WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) run.signal = WTERMSIG(status);
  run.out = slurp(out);
  run.err = slurp(err);
  return run;
}

Run run_shatter(const std::string& arguments) { return run_limited(quoted(SHATTER_EXE) + " " + arguments); }

enum class Command { validate, slice, fracture };
constexpr std::array<Command, 3> all_commands = {Command::validate, Command::slice, Command::fracture};

std::string command_name(Command command) {
  switch (command) {
    case Command::validate: return "validate";
    case Command::slice: return "slice";
    case Command::fracture: return "fracture";
  }
  return "?";
}

// The arguments of `command` on `input`, writing (if at all) into `folder`.
std::string arguments_of(Command command, const fs::path& input, const fs::path& folder) {
  switch (command) {
    case Command::validate: return "validate " + quoted(input);
    case Command::slice: return "slice " + quoted(input) + " --plane 0,0,1,-0.5 --out " + quoted(folder / "pieces");
    case Command::fracture:
      return "fracture " + quoted(input) + " --fragments 4 --out " + quoted(folder / "tree.shatter") + " --export " +
             quoted(folder / "leaves");
  }
  return "";
}

// Every path under `folder`, relative to it, sorted.
std::vector<std::string> contents_of(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    names.push_back(fs::relative(entry.path(), folder).string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// What a refusal must say besides "error: ": every keyword (the defect), and the
// element at fault where the defect has one.
struct Expected {
  Expected(int code, std::vector<std::string> words, std::string element_named = "",
           std::vector<std::string> one_of = {})
      : exit_code(code), keywords(std::move(words)), element(std::move(element_named)), any_of(std::move(one_of)) {}

  int exit_code;
  std::vector<std::string> keywords;
  std::string element;              ///< e.g. "edge (0, 3)", "face 2 at line 9"; empty: none checked
  std::vector<std::string> any_of;  ///< at least one of these, when given
};

// The first way `run` falls short of a clean refusal, or "" if it does not.
// `folder` must then hold exactly `kept` (the input and anything the test put there).
std::string refusal_problem(Command command, const Run& run, const Expected& expected, const fs::path& folder,
                            const std::vector<std::string>& kept) {
  if (run.signal != 0) return "killed by signal " + std::to_string(run.signal) + "; stderr: " + run.err;
  if (run.exit_code != expected.exit_code) {
    return "exit " + std::to_string(run.exit_code) + ", expected " + std::to_string(expected.exit_code) +
           "; stderr: " + run.err.substr(0, 300);
  }
  if (run.err.rfind("error: ", 0) != 0 || run.err.find('\n') != run.err.size() - 1) {
    return "stderr is not one 'error: ' line: " + run.err.substr(0, 300);
  }
  // A line a terminal shows as written and a log keeps whole: printable ASCII,
  // and no echo of a megabyte of garbage.
  const std::string_view line(run.err.data(), run.err.size() - 1);
  for (const char c : line) {
    if (c < 0x20 || c > 0x7e) return "stderr holds a non-printable byte " + std::to_string(static_cast<unsigned char>(c));
  }
  if (line.size() > 600) return "stderr line is " + std::to_string(line.size()) + " bytes long";
  for (const std::string& keyword : expected.keywords) {
    if (line.find(keyword) == std::string_view::npos) return "stderr does not name '" + keyword + "': " + run.err;
  }
  if (!expected.any_of.empty() && std::none_of(expected.any_of.begin(), expected.any_of.end(), [&](const std::string& word) {
        return line.find(word) != std::string_view::npos;
      })) {
    return "stderr names none of '" + expected.any_of.front() + "', ...: " + run.err;
  }
  if (!expected.element.empty() && line.find(expected.element) == std::string_view::npos) {
    return "stderr does not name the element '" + expected.element + "': " + run.err;
  }
  // validate prints its report of an invalid mesh on stdout (README); the
  // commands that write files print nothing when they write nothing.
  if (command != Command::validate && !run.out.empty()) return "stdout not empty: " + run.out.substr(0, 300);
  if (contents_of(folder) != kept) {
    std::string found;
    for (const std::string& name : contents_of(folder)) found += " " + name;
    return "left behind:" + found;
  }
  return "";
}

// One case of the matrix: `bytes` written to a fresh folder as input.<extension>,
// run through `command`; returns refusal_problem's verdict. The folder goes again.
// Under the sanitizers, slice and fracture (which read and refuse through the
// same code as validate) run on every sixth case that reaches them, and
// validate on every case: so each case's bytes still go through the readers
// sanitized, at a sixth of the runs of the two longer commands (a run of the
// sanitized command costs some 0.13 s before it reads a byte).
bool left_to_release_build(Command command) {
  static std::size_t cases_of_later_commands = 0;
  return under_address_sanitizer && command != Command::validate && cases_of_later_commands++ % 6 != 0;
}

std::string refusal_problem_of_file(Command command, const std::string& bytes, const std::string& extension,
                                    const Expected& expected) {
  if (left_to_release_build(command)) return "";
  static std::size_t case_number = 0;
  const fs::path folder = scratch_root() / ("case-" + std::to_string(case_number++));
  fs::create_directories(folder);
  const std::string input_name = "input." + extension;
  std::ofstream(folder / input_name, std::ios::binary) << bytes;
  const Run run = run_shatter(arguments_of(command, folder / input_name, folder));
  const std::string problem = refusal_problem(command, run, expected, folder, {input_name});
  fs::remove_all(folder);
  return problem;
}

// --- Writing files in every format, defects included ----------------------------

enum class FileFormat { off, obj, ply_ascii, ply_little_endian, ply_big_endian, stl_ascii, stl_binary };
constexpr std::array<FileFormat, 7> all_file_formats = {
    FileFormat::off,       FileFormat::obj,        FileFormat::ply_ascii, FileFormat::ply_little_endian,
    FileFormat::ply_big_endian, FileFormat::stl_ascii, FileFormat::stl_binary};

std::string label(FileFormat format) {
  switch (format) {
    case FileFormat::off: return "OFF";
    case FileFormat::obj: return "OBJ";
    case FileFormat::ply_ascii: return "PLY ascii";
    case FileFormat::ply_little_endian: return "PLY binary little-endian";
    case FileFormat::ply_big_endian: return "PLY binary big-endian";
    case FileFormat::stl_ascii: return "STL ascii";
    case FileFormat::stl_binary: return "STL binary";
  }
  return "?";
}

std::string extension_of(FileFormat format) {
  switch (format) {
    case FileFormat::off: return "off";
    case FileFormat::obj: return "obj";
    case FileFormat::ply_ascii:
    case FileFormat::ply_little_endian:
    case FileFormat::ply_big_endian: return "ply";
    case FileFormat::stl_ascii:
    case FileFormat::stl_binary: return "stl";
  }
  return "?";
}

bool is_stl(FileFormat format) { return format == FileFormat::stl_ascii || format == FileFormat::stl_binary; }
bool is_binary(FileFormat format) {
  return format == FileFormat::ply_little_endian || format == FileFormat::ply_big_endian ||
         format == FileFormat::stl_binary;
}

/// A mesh as a file spells it: each coordinate as text for the text formats (so
/// "nan" or "1e999" can be written) and as a double for the binary ones; faces as
/// 0-based indices, which may be out of range. A negative index stands for one
/// before the first vertex, in each format's own way (OBJ's relative indices).
struct Spelling {
  std::vector<Vec3> positions;
  std::vector<std::array<std::string, 3>> coordinate_text;
  std::vector<std::array<std::int64_t, 3>> faces;
};

std::string shortest(double value) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

Spelling spelling_of(const Mesh& mesh) {
  Spelling spelling;
  spelling.positions = mesh.positions;
  for (const Vec3& p : mesh.positions) spelling.coordinate_text.push_back({shortest(p.x), shortest(p.y), shortest(p.z)});
  for (const Triangle& t : mesh.triangles) spelling.faces.push_back({t[0], t[1], t[2]});
  return spelling;
}

/// A written file and, for the text formats, the 1-based line of each vertex and face.
struct Written {
  std::string bytes;
  std::vector<std::size_t> vertex_line, face_line;
};

std::string coordinates_line(const std::array<std::string, 3>& text) { return text[0] + ' ' + text[1] + ' ' + text[2]; }

Written write_file(const Spelling& mesh, FileFormat format) {
  Written file;
  const std::int64_t vertex_count = static_cast<std::int64_t>(mesh.positions.size());
  std::size_t line = 1;
  const auto add_line = [&](const std::string& text) {
    file.bytes += text + '\n';
    return line++;
  };
  switch (format) {
    case FileFormat::off: {
      add_line("OFF");
      add_line(std::to_string(vertex_count) + ' ' + std::to_string(mesh.faces.size()) + " 0");
      for (const auto& text : mesh.coordinate_text) file.vertex_line.push_back(add_line(coordinates_line(text)));
      for (const auto& face : mesh.faces) {
        file.face_line.push_back(add_line("3 " + std::to_string(face[0]) + ' ' + std::to_string(face[1]) + ' ' +
                                          std::to_string(face[2])));
      }
      return file;
    }
    case FileFormat::obj: {
      for (const auto& text : mesh.coordinate_text) file.vertex_line.push_back(add_line("v " + coordinates_line(text)));
      const auto reference = [&](std::int64_t index) {
        return std::to_string(index >= 0 ? index + 1 : -(vertex_count + 1));  // -(n+1) reaches before the first
      };
      for (const auto& face : mesh.faces) {
        file.face_line.push_back(add_line("f " + reference(face[0]) + ' ' + reference(face[1]) + ' ' + reference(face[2])));
      }
      return file;
    }
    case FileFormat::ply_ascii:
    case FileFormat::ply_little_endian:
    case FileFormat::ply_big_endian: {
      const std::string encoding = format == FileFormat::ply_ascii           ? "ascii"
                                   : format == FileFormat::ply_little_endian ? "binary_little_endian"
                                                                             : "binary_big_endian";
      for (const std::string& header_line :
           {std::string("ply"), "format " + encoding + " 1.0", "element vertex " + std::to_string(vertex_count),
            std::string("property double x"), std::string("property double y"), std::string("property double z"),
            "element face " + std::to_string(mesh.faces.size()), std::string("property list uchar int vertex_indices"),
            std::string("end_header")}) {
        add_line(header_line);
      }
      if (format == FileFormat::ply_ascii) {
        for (const auto& text : mesh.coordinate_text) file.vertex_line.push_back(add_line(coordinates_line(text)));
        for (const auto& face : mesh.faces) {
          file.face_line.push_back(add_line("3 " + std::to_string(face[0]) + ' ' + std::to_string(face[1]) + ' ' +
                                            std::to_string(face[2])));
        }
        return file;
      }
      const bool big = format == FileFormat::ply_big_endian;
      for (const Vec3& p : mesh.positions) {
        for (const double value : {p.x, p.y, p.z}) append_binary(file.bytes, value, big);
      }
      for (const auto& face : mesh.faces) {
        append_binary(file.bytes, std::uint8_t{3}, big);
        for (const std::int64_t index : face) append_binary(file.bytes, static_cast<std::int32_t>(index), big);
      }
      return file;
    }
    case FileFormat::stl_ascii: {
      add_line("solid bad-input");
      for (const auto& face : mesh.faces) {
        file.face_line.push_back(add_line("facet normal 0 0 0"));
        add_line("outer loop");
        for (const std::int64_t index : face) {
          add_line("vertex " + coordinates_line(mesh.coordinate_text.at(static_cast<std::size_t>(index))));
        }
        add_line("endloop");
        add_line("endfacet");
      }
      add_line("endsolid bad-input");
      return file;
    }
    case FileFormat::stl_binary: {
      file.bytes = "binary STL written by test_bad_input";
      file.bytes.resize(80, ' ');
      append_binary(file.bytes, static_cast<std::uint32_t>(mesh.faces.size()), false);
      for (const auto& face : mesh.faces) {
        for (int k = 0; k < 3; ++k) append_binary(file.bytes, 0.0f, false);
        for (const std::int64_t index : face) {
          const Vec3 p = mesh.positions.at(static_cast<std::size_t>(index));
          for (const double value : {p.x, p.y, p.z}) append_binary(file.bytes, static_cast<float>(value), false);
        }
        append_binary(file.bytes, std::uint16_t{0}, false);
      }
      return file;
    }
  }
  return file;
}

// --- The meshes -------------------------------------------------------------------

/// The mesh with its vertices numbered by first use, as every reader numbers
/// them (io.hpp), so an element named in a message is the element written.
Mesh numbered_by_first_use(const Mesh& mesh) {
  return read_mesh_from_bytes(write_mesh_to_bytes(mesh, MeshFormat::off), MeshFormat::off);
}

/// A tetrahedron on four points, its faces oriented outward whatever their order.
Mesh outward_tetrahedron(Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
  Mesh mesh = mesh_from({a, b, c, d}, {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}});
  if (dot(cross(b - a, c - a), d - a) > 0) mesh = flipped(std::move(mesh));  // d above (a, b, c): reversed
  return mesh;
}

Mesh corner_tetrahedron() { return numbered_by_first_use(outward_tetrahedron({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1})); }

VertexIndex index_of(const Mesh& mesh, Vec3 position) {
  const auto found = std::find(mesh.positions.begin(), mesh.positions.end(), position);
  REQUIRE(found != mesh.positions.end());
  return static_cast<VertexIndex>(found - mesh.positions.begin());
}

std::pair<VertexIndex, VertexIndex> undirected(VertexIndex a, VertexIndex b) { return {std::min(a, b), std::max(a, b)}; }

std::string edge_text(std::pair<VertexIndex, VertexIndex> edge) {
  return "edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) + ")";
}

/// Of the edges a case broke by construction, the one validate.hpp calls first:
/// met first scanning triangles in order, each from corner c to c + 1.
std::string first_in_scan_order(const Mesh& mesh, const std::set<std::pair<VertexIndex, VertexIndex>>& broken) {
  for (const Triangle& t : mesh.triangles) {
    for (int c = 0; c < 3; ++c) {
      const auto edge = undirected(t[c], t[(c + 1) % 3]);
      if (broken.count(edge)) return edge_text(edge);
    }
  }
  FAIL("no broken edge in the mesh");
  return "";
}

std::set<std::pair<VertexIndex, VertexIndex>> edges_between(const Mesh& mesh, const std::vector<std::pair<Vec3, Vec3>>& ends) {
  std::set<std::pair<VertexIndex, VertexIndex>> edges;
  for (const auto& [a, b] : ends) edges.insert(undirected(index_of(mesh, a), index_of(mesh, b)));
  return edges;
}

/// A mesh with one defect, and what its refusal must say.
struct DefectCase {
  std::string name;
  Mesh mesh;
  Expected expected;
};

std::vector<DefectCase> topological_and_geometric_defects() {
  std::vector<DefectCase> cases;
  const Mesh cube = numbered_by_first_use(unit_cube());
  const Vec3 p000{0, 0, 0}, p100{1, 0, 0}, p010{0, 1, 0}, p001{0, 0, 1};

  {  // A cube missing its top face: the four edges around it are open.
    Mesh open = unit_cube();
    open.triangles.erase(open.triangles.begin() + 2, open.triangles.begin() + 4);  // the z = 1 face
    open = numbered_by_first_use(mesh_from(open.positions, open.triangles));
    const auto top = edges_between(open, {{{0, 0, 1}, {1, 0, 1}}, {{1, 0, 1}, {1, 1, 1}}, {{1, 1, 1}, {0, 1, 1}},
                                          {{0, 1, 1}, {0, 0, 1}}});
    cases.push_back({"open cube", open, {3, {"open mesh", "4 boundary edges"}, first_in_scan_order(open, top)}});
  }
  {  // One face turned over: its three edges are each traversed twice the same way.
    for (const std::size_t turned : {std::size_t{0}, std::size_t{7}, std::size_t{11}}) {
      Mesh inconsistent = cube;
      std::swap(inconsistent.triangles[turned][1], inconsistent.triangles[turned][2]);
      inconsistent = numbered_by_first_use(inconsistent);
      const Triangle& t = inconsistent.triangles[turned];
      const std::set broken = {undirected(t[0], t[1]), undirected(t[1], t[2]), undirected(t[2], t[0])};
      cases.push_back({"cube with triangle " + std::to_string(turned) + " flipped", inconsistent,
                       {3, {"inconsistent orientation", "3 edges"}, first_in_scan_order(inconsistent, broken)}});
    }
  }
  cases.push_back({"cube facing inward", numbered_by_first_use(flipped(cube)), {3, {"inward-facing", "negative volume"}, ""}});
  cases.push_back({"tetrahedron facing inward", numbered_by_first_use(flipped(corner_tetrahedron())), {3, {"inward-facing"}, ""}});
  {  // Two tetrahedra on either side of one triangle, and that triangle: three triangles on each of its edges.
    const Vec3 below{0.25, 0.25, -1};
    const Mesh upper = outward_tetrahedron(p000, p100, p010, p001), lower = outward_tetrahedron(p000, p100, p010, below);
    const auto has_apex = [](const Triangle& t) { return std::find(t.begin(), t.end(), VertexIndex{3}) != t.end(); };
    std::vector<Triangle> triangles;
    for (const Triangle& t : upper.triangles) {
      if (has_apex(t)) triangles.push_back(t);
    }
    for (Triangle t : lower.triangles) {
      if (!has_apex(t)) continue;
      for (VertexIndex& v : t) v = v == 3 ? 4 : v;  // the lower apex is vertex 4; vertices 0-2 are shared
      triangles.push_back(t);
    }
    triangles.insert(triangles.begin() + 2, Triangle{0, 1, 2});  // the shared face, among the others
    const std::vector<Vec3> positions = {p000, p100, p010, p001, below};
    const Mesh fin = numbered_by_first_use(mesh_from(positions, triangles));
    const auto shared = edges_between(fin, {{p000, p100}, {p100, p010}, {p010, p000}});
    cases.push_back({"three triangles on each edge of a shared face", fin,
                     {3, {"non-manifold", "3 edges shared by three or more triangles"}, first_in_scan_order(fin, shared)}});
  }
  {  // Two tetrahedra sharing one edge (four triangles on it).
    Mesh pair = merge({outward_tetrahedron(p000, p100, p010, p001), outward_tetrahedron(p000, p100, {0, -1, 0}, {0, 0, -1})});
    for (Triangle& t : pair.triangles) {
      for (VertexIndex& v : t) v = v == 4 ? 0 : v == 5 ? 1 : v;  // weld the shared edge's ends by index too
    }
    pair = numbered_by_first_use(mesh_from(pair.positions, pair.triangles));
    cases.push_back({"two tetrahedra sharing an edge", pair,
                     {3, {"non-manifold", "1 edge shared by three or more triangles"},
                      edge_text(undirected(index_of(pair, p000), index_of(pair, p100)))}});
  }
  {  // Two tetrahedra touching at one vertex, listed with the touching one in the middle of the file.
    const Vec3 touch{1, 1, 1};
    const Mesh pair = numbered_by_first_use(merge({outward_tetrahedron({2, 1, 1}, {1, 2, 1}, touch, {1, 1, 2}),
                                                   outward_tetrahedron({0, 1, 1}, touch, {1, 0, 1}, {1, 1, 0})}));
    cases.push_back({"two tetrahedra sharing a vertex", pair,
                     {3, {"non-manifold", "1 vertex where separate fans of triangles meet"},
                      "vertex " + std::to_string(index_of(pair, touch))}});
  }
  for (const std::size_t at : {std::size_t{0}, std::size_t{5}, std::size_t{12}}) {
    // A triangle with a repeated index: a point, not a surface (STL: two equal corners).
    Mesh repeated = cube;
    repeated.triangles.insert(repeated.triangles.begin() + static_cast<std::ptrdiff_t>(at), Triangle{6, 6, 2});
    repeated = numbered_by_first_use(mesh_from(repeated.positions, repeated.triangles));
    cases.push_back({"cube with a repeated-index triangle at " + std::to_string(at), repeated,
                     {3, {"zero-area triangle"}, "first triangle " + std::to_string(at)}});
  }
  {  // A cube face split at an edge midpoint, the split closed by a triangle on three collinear corners.
    Mesh split = unit_cube();
    const Triangle face = split.triangles[4];  // (0, 1, 5): corners a, b, c on y = 0
    const VertexIndex a = face[0], b = face[1], c = face[2];
    split.positions.push_back({0.5, 0, 0});  // the midpoint of a and b, exactly
    const VertexIndex m = 8;
    split.triangles[4] = {a, b, m};  // zero area: a, b, m on one line
    split.triangles.push_back({a, m, c});
    split.triangles.push_back({m, b, c});
    split = numbered_by_first_use(mesh_from(split.positions, split.triangles));
    cases.push_back({"cube with a triangle on collinear corners", split,
                     {3, {"zero-area triangle"}, "first triangle 4"}});
  }
  {  // Two closed tetrahedra, the second poking through the first.
    const Mesh overlapping = numbered_by_first_use(
        merge({outward_tetrahedron(p000, p100, p010, p001),
               outward_tetrahedron({0.25, 0.25, 0.25}, {1.25, 0.25, 0.25}, {0.25, 1.25, 0.25}, {0.25, 0.25, 1.25})}));
    // Which pair CGAL meets first is its business; the pair must join the two solids.
    cases.push_back({"two overlapping tetrahedra", overlapping, {3, {"self-intersecting", "first triangles "}, ""}});
  }
  return cases;
}

// "first triangles a and b" with a in the first solid (triangles 0-3) and b in the second.
std::string pair_problem(const std::string& err) {
  const std::size_t at = err.find("first triangles ");
  if (at == std::string::npos) return "no pair named";
  unsigned a = 0, b = 0;
  if (std::sscanf(err.c_str() + at, "first triangles %u and %u", &a, &b) != 2) return "pair unreadable";
  if (a >= 4 || b < 4 || b >= 8) return "pair " + std::to_string(a) + ", " + std::to_string(b) + " is not across the two solids";
  return "";
}

// --- Seeded garbage ----------------------------------------------------------------

std::string random_bytes(Random& random, std::size_t size) {
  std::string bytes(size, '\0');
  for (char& c : bytes) c = static_cast<char>(random.next() >> 56);
  return bytes;
}

// Text that looks like mesh files without being one: the readers' keywords,
// numbers and separators in random order, so parsing goes deep before it fails.
std::string random_mesh_like_text(Random& random, std::size_t token_count) {
  static const std::vector<std::string> tokens = {
      "v", "f", "vt", "vn", "OFF", "3", "4", "0", "1", "2", "-1", "1/1", "1//1", "-0.5", "1e300", "nan", "inf",
      "facet", "normal", "outer", "loop", "vertex", "endloop", "endfacet", "solid", "endsolid", "element", "face",
      "property", "list", "uchar", "int", "double", "end_header", "ply", "format", "ascii", "1.0", "#", "\n", "\n",
      "\r\n", "\t", "99999999999", "2147483648", "/", "//"};
  std::string text;
  for (std::size_t k = 0; k < token_count; ++k) {
    text += tokens[random.index(tokens.size())];
    text += random.index(4) == 0 ? "\n" : " ";
  }
  return text;
}

// The part of a valid file before its first vertex or facet: its header, or for
// OBJ (which has none) its first vertex line.
std::string header_of(const Written& file, FileFormat format) {
  if (format == FileFormat::stl_binary) return file.bytes.substr(0, 84);
  if (is_binary(format)) return file.bytes.substr(0, file.bytes.find("end_header\n") + 11);
  const std::size_t lines = format == FileFormat::obj || format == FileFormat::stl_ascii ? 1 : file.vertex_line.at(0) - 1;
  std::size_t end = 0;
  for (std::size_t line = 0; line < lines; ++line) end = file.bytes.find('\n', end) + 1;
  return file.bytes.substr(0, end);
}

// Where the content of a valid file ends: a cut before it loses content the file
// needs (so must be refused); a cut after it only drops trailing blanks or, in
// ascii STL, the solid's name after "endsolid", which no reader needs.
std::size_t end_of_content(const std::string& bytes, FileFormat format) {
  if (is_binary(format)) return bytes.size();
  if (format == FileFormat::stl_ascii) return bytes.rfind("endsolid") + std::string("endsolid").size();
  return bytes.find_last_not_of(" \t\r\n") + 1;
}

std::string case_label(const std::string& what, FileFormat format, Command command) {
  return what + " | " + label(format) + " | " + command_name(command);
}

}  // namespace

// --- The harness ------------------------------------------------------------------------

TEST_CASE("bad input: the harness passes valid files of every format through every command", "[bad-input]") {
  // Were the memory limit too tight, or a writer here wrong, every refusal below
  // could pass for the wrong reason; valid files must go through untouched.
  if (under_address_sanitizer) {
    const Run limit = run_limited("sh -c 'echo $ASAN_OPTIONS'");
    CHECK(limit.out.find("max_allocation_size_mb=1000") != std::string::npos);
  } else {
    const Run limit = run_limited("sh -c 'ulimit -v'");
    CHECK(limit.out == std::string(memory_limit_kib) + "\n");
  }
  for (const Mesh& mesh : {corner_tetrahedron(), numbered_by_first_use(unit_cube())}) {
    for (const FileFormat format : all_file_formats) {
      const Written file = write_file(spelling_of(mesh), format);
      // The writers here spell the mesh as shatter reads it: same numbering, same triangles.
      const Mesh read = read_mesh_from_bytes(file.bytes, *parse_mesh_format(extension_of(format)));
      REQUIRE(read.positions == mesh.positions);
      REQUIRE(read.triangles == mesh.triangles);
      for (const Command command : all_commands) {
        INFO(case_label(std::to_string(mesh.triangle_count()) + "-triangle valid mesh", format, command));
        const fs::path folder = scratch_root() / "valid";
        fs::remove_all(folder);
        fs::create_directories(folder);
        std::ofstream(folder / ("input." + extension_of(format)), std::ios::binary) << file.bytes;
        const Run run = run_shatter(arguments_of(command, folder / ("input." + extension_of(format)), folder));
        CHECK(run.signal == 0);
        CHECK(run.exit_code == 0);
        CHECK(run.err == "");
        if (command == Command::slice) CHECK(contents_of(folder / "pieces").size() >= 2);
        if (command == Command::fracture) CHECK(fs::is_regular_file(folder / "tree.shatter"));
        fs::remove_all(folder);
      }
    }
  }
}

// --- The matrix -------------------------------------------------------------------------

TEST_CASE("bad input: empty and whitespace-only files", "[bad-input]") {
  const std::vector<std::string> contents = {"", " ", "\n", "\r\n", "\t \n  \r\n\n", std::string(4096, '\n'),
                                             std::string(100, ' ')};
  std::size_t cases = 0;
  for (const std::string extension : {"off", "obj", "ply", "stl"}) {
    for (const std::string& bytes : contents) {
      for (const Command command : all_commands) {
        INFO(command_name(command) << " on ." << extension << " holding " << bytes.size() << " blank bytes");
        CHECK(refusal_problem_of_file(command, bytes, extension, {3, {bytes.empty() ? "empty" : "blank"}, ""}) == "");
        ++cases;
      }
    }
  }
  CHECK(cases == 4 * 7 * 3);
}

namespace {

// Every third cut of the tetrahedron (truncation_stride); 24 spread cuts of the cube. validate at every cut,
// slice and fracture at every fifth (the same reader runs first). Returns the runs.
std::size_t check_truncations(FileFormat format) {
  const Mesh tetrahedron = corner_tetrahedron();
  const Mesh cube = numbered_by_first_use(unit_cube());
  std::size_t refused = 0;
  for (const Mesh* mesh : {&tetrahedron, &cube}) {
    const std::string bytes = write_file(spelling_of(*mesh), format).bytes;
    const std::size_t content_end = end_of_content(bytes, format);
    const std::size_t step =
        mesh == &tetrahedron ? truncation_stride : std::max<std::size_t>(1, content_end / 24) * sanitized_thinning;
    for (std::size_t cut = 0, k = 0; cut < content_end; cut += step, ++k) {
      for (const Command command : all_commands) {
        if (command != Command::validate && k % 5 != 0) continue;
        INFO(case_label("cut at byte " + std::to_string(cut) + " of " + std::to_string(bytes.size()) + " (" +
                            std::to_string(mesh->triangle_count()) + " triangles)",
                        format, command));
        CHECK(refusal_problem_of_file(command, bytes.substr(0, cut), extension_of(format), {3, {"input."}, ""}) == "");
        ++refused;
      }
    }
  }
  return refused;
}

}  // namespace

// One case per family of formats, so the runs (about 2,000 processes of shatter,
// the suite's longest test when it was one case) spread over CTest's jobs.
TEST_CASE("bad input: truncated files, at every third byte of a small file: OFF and OBJ", "[bad-input]") {
  for (const FileFormat format : {FileFormat::off, FileFormat::obj}) {
    CHECK(check_truncations(format) > 30 / sanitized_thinning);
  }
}

TEST_CASE("bad input: truncated files, at every third byte of a small file: PLY", "[bad-input]") {
  for (const FileFormat format : {FileFormat::ply_ascii, FileFormat::ply_little_endian, FileFormat::ply_big_endian}) {
    CHECK(check_truncations(format) > 30 / sanitized_thinning);
  }
}

TEST_CASE("bad input: truncated files, at every third byte of a small file: STL", "[bad-input]") {
  for (const FileFormat format : {FileFormat::stl_ascii, FileFormat::stl_binary}) {
    CHECK(check_truncations(format) > 30 / sanitized_thinning);
  }
}

TEST_CASE("bad input: binary garbage, alone and after a valid header", "[bad-input]") {
  Random random(0x5eedba5e);
  for (int seed = 0; seed < garbage_seeds; ++seed) {
    const std::string noise = random_bytes(random, 1 + random.index(3000));
    const std::string text = random_mesh_like_text(random, 1 + random.index(400));
    for (const std::string extension : {"off", "obj", "ply", "stl"}) {
      for (const Command command : all_commands) {
        INFO(command_name(command) << " on ." << extension << ", garbage " << seed);
        CHECK(refusal_problem_of_file(command, noise, extension, {3, {"input."}, ""}) == "");
        CHECK(refusal_problem_of_file(command, text, extension, {3, {"input."}, ""}) == "");
      }
    }
  }
  for (const FileFormat format : all_file_formats) {
    const std::string header = header_of(write_file(spelling_of(corner_tetrahedron()), format), format);
    for (int seed = 0; seed < header_garbage_seeds; ++seed) {
      // Binary STL only reads as binary at 84 + 50 n bytes: whole facets of garbage.
      const std::size_t size = format == FileFormat::stl_binary ? 50 * (1 + random.index(40)) : 1 + random.index(2000);
      std::string bytes = header + random_bytes(random, size);
      if (format == FileFormat::stl_binary) {
        const std::uint32_t facets = static_cast<std::uint32_t>(size / 50);
        std::memcpy(bytes.data() + 80, &facets, 4);  // little-endian hosts only, as the STL reader's tests
      }
      for (const Command command : all_commands) {
        INFO(case_label("valid header then garbage " + std::to_string(seed), format, command));
        CHECK(refusal_problem_of_file(command, bytes, extension_of(format), {3, {"input."}, ""}) == "");
      }
    }
  }
}

TEST_CASE("bad input: a token quoted from the file is short and printable, and the line is kept", "[bad-input]") {
  // Readers quote the token at fault. A NUL inside it once cut the message short
  // (dropping the line number), control bytes reached the terminal raw, and a
  // 100 KB token was echoed whole.
  const std::string huge(100000, '7');
  const std::string tetrahedron_vertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string ply_start = "ply\nformat ascii 1.0\n";
  const std::string ply_rest = "property double x\nproperty double y\nproperty double z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n";
  const std::vector<std::tuple<std::string, std::string, std::string>> files = {  // extension, bytes, element
      {"off", "OFF\n" + huge + "x 1 0\n", "line 2"},
      {"off", "OFF\n4\x01\x02 1 0\n", "line 2"},
      {"off", "OFF\n4 1 0\n" + tetrahedron_vertices + "3 0 1 " + huge + "x\n", "face 0 at line 7"},
      {"off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1e9" + huge + "\n3 0 1 2\n", "vertex 3 at line 6"},
      {"off", std::string("OFF\n4 1 0\n0 0 0\n1 0 \0\x7f\n", 20), "line 4"},
      {"obj", "v 0 0 0\nv 1 0 0\nv 0 1 " + huge + "x\nf 1 2 3\n", "vertex 3 at line 3"},
      {"obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3" + huge + "x\n", "face 1 at line 4"},
      {"ply", ply_start + "element vertex 4" + huge + "x\n" + ply_rest, "line 3"},
      {"ply", ply_start + std::string("element vertex 4\0\n", 18) + ply_rest, "line 3"},
      {"ply", ply_start + "element vertex 1\n" + ply_rest + "0 0 \x01\x02\n3 0 0 0\n", "vertex 0 at line 10"},
      {"ply", ply_start + "element vertex 1\n" + ply_rest + "0 0 " + huge + "x\n3 0 0 0\n", "vertex 0 at line 10"},
      {"stl", "solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 " + huge + "x\n", "facet 0"},
      {"stl", "solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0 \x01\x02\n", "facet 0"},
  };
  for (const auto& [extension, bytes, element] : files) {
    for (const Command command : all_commands) {
      INFO(command_name(command) << " on ." << extension << " " << bytes.substr(0, 60) << ", expecting " << element);
      CHECK(refusal_problem_of_file(command, bytes, extension, {3, {"input."}, element}) == "");
    }
  }
}

TEST_CASE("bad input: NaN and infinite coordinates, naming the vertex", "[bad-input]") {
  const Mesh tetrahedron = corner_tetrahedron();
  const std::vector<std::string> text_spellings = {"nan", "-nan", "NaN", "inf", "-inf", "Infinity", "1e999", "-1e999"};
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const std::vector<double> binary_values = {nan, -nan, inf, -inf};
  Random random(77);
  std::size_t cases = 0;
  for (const FileFormat format : all_file_formats) {
    const std::size_t spelling_count = is_binary(format) ? binary_values.size() : text_spellings.size();
    for (std::size_t s = 0; s < spelling_count; ++s) {
      Spelling spelling = spelling_of(tetrahedron);
      const std::size_t vertex = random.index(4), axis = random.index(3);
      spelling.coordinate_text[vertex][axis] = is_binary(format) ? "" : text_spellings[s];
      const double value = is_binary(format) ? binary_values[s] : (text_spellings[s][0] == '-' ? -inf : inf);
      (axis == 0 ? spelling.positions[vertex].x : axis == 1 ? spelling.positions[vertex].y : spelling.positions[vertex].z) = value;
      const Written file = write_file(spelling, format);
      const std::string spelled = is_binary(format) ? "" : text_spellings[s];
      const bool overflows = spelled.find("1e999") != std::string::npos;
      // Each format numbers vertices its own way: OBJ from 1, STL only by facet.
      std::string element;
      if (is_stl(format)) {
        std::size_t facet = 0;
        while (std::find(tetrahedron.triangles[facet].begin(), tetrahedron.triangles[facet].end(), vertex) ==
               tetrahedron.triangles[facet].end()) {
          ++facet;
        }
        element = "facet " + std::to_string(facet);
      } else {
        element = "vertex " + std::to_string(format == FileFormat::obj ? vertex + 1 : vertex);
        if (!is_binary(format)) element += " at line " + std::to_string(file.vertex_line[vertex]);
      }
      for (const Command command : all_commands) {
        INFO(case_label("coordinate " + (is_binary(format) ? std::to_string(binary_values[s]) : text_spellings[s]) +
                            " at vertex " + std::to_string(vertex),
                        format, command));
        // A decimal beyond the range of double ("1e999") is no NaN or infinity in the
        // file, but it is no finite double either: named as non-finite, or quoted.
        const Expected expected = overflows ? Expected{3, {}, element, {"non-finite", "'" + spelled + "'"}}
                                            : Expected{3, {"non-finite"}, element, {}};
        CHECK(refusal_problem_of_file(command, file.bytes, extension_of(format), expected) == "");
        ++cases;
      }
    }
  }
  CHECK(cases == (4 * 8 + 3 * 4) * 3);
}

TEST_CASE("bad input: vertex indices out of range, naming the face", "[bad-input]") {
  const Mesh tetrahedron = corner_tetrahedron();
  std::size_t cases = 0;
  for (const FileFormat format : all_file_formats) {
    if (is_stl(format)) continue;  // STL spells corners by position: no index to get wrong
    for (const std::int64_t bad_index : {std::int64_t{4}, std::int64_t{5}, std::int64_t{1000}, std::int64_t{-1}}) {
      for (const std::size_t face : {std::size_t{0}, std::size_t{2}, std::size_t{3}}) {
        Spelling spelling = spelling_of(tetrahedron);
        spelling.faces[face][face % 3] = bad_index;
        const Written file = write_file(spelling, format);
        std::string element = "face " + std::to_string(format == FileFormat::obj ? face + 1 : face);
        if (!is_binary(format)) element += " at line " + std::to_string(file.face_line[face]);
        for (const Command command : all_commands) {
          INFO(case_label("index " + std::to_string(bad_index) + " in face " + std::to_string(face), format, command));
          CHECK(refusal_problem_of_file(command, file.bytes, extension_of(format), {3, {"out of range"}, element}) == "");
          ++cases;
        }
      }
    }
  }
  CHECK(cases == 5 * 4 * 3 * 3);
}

TEST_CASE("bad input: absurd element counts allocate nothing for the claim", "[bad-input]") {
  // Every run is under the memory limit: reserving what one of these headers
  // claims would die of bad_alloc (exit 1) or a signal, not refuse with exit 3.
  const std::string tetrahedron_vertices = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  std::vector<std::pair<std::string, std::string>> files = {  // extension, bytes
      {"off", "OFF\n4000000000 4000000000 0\n"},
      {"off", "OFF\n4 4000000000 0\n" + tetrahedron_vertices + "3 0 1 2\n"},
      {"off", "OFF\n4000000000 1 0\n" + tetrahedron_vertices + "3 0 1 2\n"},
      {"off", "OFF\n4 1 0\n" + tetrahedron_vertices + "4000000000 0 1 2\n"},
      {"off", "OFF 18446744073709551615 18446744073709551615 0\n"},
      {"obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4000000000\n"},
      {"obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4000000000\n"},
  };
  for (const std::string encoding : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const std::string start = "ply\nformat " + encoding + " 1.0\n";
    const std::string face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    files.push_back({"ply", start + "element vertex 4294967295\n" + xyz + face + "0 0 0 1 0 0"});
    files.push_back({"ply", start + "element vertex 18446744073709551615\n" + xyz + face});
    files.push_back({"ply", start + "element vertex 3\n" + xyz +
                                "element face 4294967295\nproperty list uint int vertex_indices\nend_header\n" +
                                std::string(36, '\0') + "\xff\xff\xff\xff"});
    files.push_back({"ply", start + "element vertex 3\n" + xyz +
                                "element face 1\nproperty list uint int vertex_indices\nend_header\n" +
                                (encoding == "ascii" ? "0 0 0\n1 0 0\n0 1 0\n4294967295 0 1 2\n"
                                                     : std::string(36, '\0') + "\xff\xff\xff\xff" + std::string(12, '\0'))});
  }
  std::string stl_count_only(80, ' ');
  stl_count_only += std::string("\x00\x28\x6b\xee", 4);  // 4,000,000,000 facets, little-endian, in an 84-byte file
  files.push_back({"stl", stl_count_only});
  std::string solid_header = "solid claims four billion facets";
  solid_header.resize(80, ' ');
  files.push_back({"stl", solid_header + std::string("\x00\x28\x6b\xee", 4) + std::string(50, '\0')});
  files.push_back({"stl", std::string(80, '\0') + "\xff\xff\xff\xff" + std::string(100, '\0')});
  for (std::size_t k = 0; k < files.size(); ++k) {
    for (const Command command : all_commands) {
      INFO(command_name(command) << " on absurd-count file " << k << " (." << files[k].first << ")");
      CHECK(refusal_problem_of_file(command, files[k].second, files[k].first, {3, {"input."}, ""}) == "");
    }
  }
}

TEST_CASE("bad input: topological and geometric defects, naming the first element", "[bad-input]") {
  std::size_t cases = 0;
  for (const DefectCase& defect : topological_and_geometric_defects()) {
    // The test's own premise: the library sees exactly this defect first.
    const ValidationReport report = validate_mesh(defect.mesh);
    INFO(defect.name << ": " << report.summary());
    REQUIRE_FALSE(report.valid());
    for (const FileFormat format : all_file_formats) {
      const Written file = write_file(spelling_of(defect.mesh), format);
      // And every file holds this mesh as numbered here, so the elements expected are the ones written.
      const Mesh read = read_mesh_from_bytes(file.bytes, *parse_mesh_format(extension_of(format)));
      REQUIRE(read.positions == defect.mesh.positions);
      REQUIRE(read.triangles == defect.mesh.triangles);
      for (const Command command : all_commands) {
        INFO(case_label(defect.name, format, command));
        std::string problem = refusal_problem_of_file(command, file.bytes, extension_of(format), defect.expected);
        CHECK(problem == "");
        ++cases;
      }
    }
  }
  CHECK(cases == 14 * 7 * 3);
}

TEST_CASE("bad input: the self-intersecting pair named is across the two solids", "[bad-input]") {
  for (const DefectCase& defect : topological_and_geometric_defects()) {
    if (defect.name != "two overlapping tetrahedra") continue;
    for (const FileFormat format : all_file_formats) {
      const fs::path folder = scratch_root() / "pair";
      fs::remove_all(folder);
      fs::create_directories(folder);
      const fs::path input = folder / ("input." + extension_of(format));
      std::ofstream(input, std::ios::binary) << write_file(spelling_of(defect.mesh), format).bytes;
      for (const Command command : all_commands) {
        INFO(case_label(defect.name, format, command));
        const Run run = run_shatter(arguments_of(command, input, folder));
        CHECK(pair_problem(run.err) == "");
      }
      fs::remove_all(folder);
    }
  }
}

TEST_CASE("bad input: I/O failures exit 4 and leave nothing behind", "[bad-input]") {
  const fs::path folder = scratch_root() / "io";
  fs::remove_all(folder);
  fs::create_directories(folder);
  for (const std::string extension : {"off", "obj", "ply", "stl"}) {
    for (const Command command : all_commands) {
      INFO(command_name(command) << " on a missing ." << extension);
      const Run missing = run_shatter(arguments_of(command, folder / ("no-such-mesh." + extension), folder));
      CHECK(refusal_problem(command, missing, {4, {"no-such-mesh." + extension, "No such file"}, ""}, folder, {}) == "");
    }
  }
  fs::create_directories(folder / "a-folder.off");
  for (const Command command : all_commands) {
    INFO(command_name(command) << " on a folder named like a mesh");
    const Run run = run_shatter(arguments_of(command, folder / "a-folder.off", folder));
    CHECK(refusal_problem(command, run, {4, {"a-folder.off"}, ""}, folder, {"a-folder.off"}) == "");
  }
  fs::remove_all(folder / "a-folder.off");

  // Outputs that cannot be written: a folder wanted where a regular file is.
  const fs::path mesh = folder / "cube.off";
  std::ofstream(mesh) << write_mesh_to_bytes(unit_cube(), MeshFormat::off);
  const fs::path blocker = folder / "a-file";
  std::ofstream(blocker) << "x";
  const std::vector<std::pair<Command, std::string>> blocked_runs = {
      {Command::slice, "slice " + quoted(mesh) + " --plane 0,0,1,-0.5 --out " + quoted(blocker)},
      {Command::slice, "slice " + quoted(mesh) + " --plane 0,0,1,-0.5 --out " + quoted(blocker / "pieces")},
      {Command::fracture, "fracture " + quoted(mesh) + " --fragments 4 --out " + quoted(blocker / "tree.shatter")},
      {Command::fracture, "fracture " + quoted(mesh) + " --fragments 4 --out " + quoted(folder / "tree.shatter") +
                              " --export " + quoted(blocker / "leaves")},
      {Command::fracture, "fracture " + quoted(mesh) + " --fragments 4 --out " + quoted(blocker / "t" / "tree.shatter") +
                              " --export " + quoted(folder / "new" / "leaves")},
  };
  for (const auto& [command, arguments] : blocked_runs) {
    INFO(arguments);
    const Run run = run_shatter(arguments);
    CHECK(refusal_problem(command, run, {4, {"a-file"}, ""}, folder, {"a-file", "cube.off"}) == "");
  }
  fs::remove_all(folder);
}
