#pragma once
// Shared by the fuzz targets: how a broken property is reported, and the
// round-trip property every mesh reader promises (kernel/include/shatter/kernel/io.hpp).
//
// A target returns normally for any input the library refuses with its documented
// error type; every other outcome (a broken promise, another exception, a crash,
// a sanitizer report) stops the process so libFuzzer, or the replay driver, fails.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>

#include "shatter/kernel/error.hpp"
#include "shatter/kernel/io.hpp"
#include "shatter/kernel/mesh.hpp"

namespace shatter::fuzz {

/// Largest mesh a target works on further than reading it: bigger inputs cost
/// time without reaching code a smaller one cannot.
inline constexpr std::size_t max_triangles = 400;

/// Inputs a target turned away as a documented known limitation
/// (UnsupportedGeometryError), not as malformed input: counted, so that the
/// replay of a committed corpus holds them to a ceiling (replay_main.cpp).
inline std::size_t known_limitation_refusals = 0;

/// Reports a broken property and aborts, so the input is kept as a crash.
[[noreturn]] inline void fail(const std::string& what) {
  std::fprintf(stderr, "shatter fuzz property violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

/// Aborts with `what` unless `holds`.
inline void require(bool holds, const std::string& what) {
  if (!holds) fail(what);
}

/// The input as a string_view, without copying.
inline std::string_view as_bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// True when the two doubles have the same bit pattern (so -0.0 differs from
/// 0.0, and a NaN equals itself).
inline bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// True when every coordinate of the two points has the same bit pattern.
inline bool same_bits(const Vec3& a, const Vec3& b) {
  return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
}

/// Checks the BasicMesh invariants every reader guarantees: one surface id per
/// triangle, three entries per triangle in every present channel, every index in
/// range, every vertex used, and at least one triangle.
void check_mesh_invariants(const Mesh& mesh, const std::string& where);

/// Reads `bytes` as `format`. Returns false when the reader refuses them with
/// InvalidMeshError (the documented refusal); aborts on any other exception.
bool try_read(std::string_view bytes, MeshFormat format, Mesh& mesh);

/// The property of every reader target: a mesh read from `bytes` keeps the
/// reader's invariants, and writing it then reading that back gives the same
/// positions bit for bit, the same triangles, and for OBJ the same per-corner
/// normals and uvs (the channels OBJ writes). Refused input is fine.
void check_read_round_trip(std::string_view bytes, MeshFormat format);

}  // namespace shatter::fuzz
