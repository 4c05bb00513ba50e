#include "fuzz_support.hpp"

#include <typeinfo>
#include <vector>

namespace shatter::fuzz {
namespace {

/// Aborts with the exception's dynamic type and message: only the documented
/// error types may escape the library, and the caller has caught those.
[[noreturn]] void fail_on_exception(const std::string& where) {
  try {
    throw;
  } catch (const std::exception& error) {
    fail(where + ": unexpected " + typeid(error).name() + ": " + error.what());
  } catch (...) {
    fail(where + ": unexpected non-standard exception");
  }
}

/// True when the two channels hold the same values bit for bit.
template <class Value, class Same>
bool same_channel(const std::vector<Value>& a, const std::vector<Value>& b, Same&& same) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same(a[i], b[i])) return false;
  }
  return true;
}

}  // namespace

void check_mesh_invariants(const Mesh& mesh, const std::string& where) {
  const std::size_t triangles = mesh.triangles.size();
  require(triangles > 0, where + ": a mesh without triangles was accepted");
  require(mesh.surfaces.size() == triangles, where + ": surface ids do not match the triangles");
  const auto channel_ok = [&](std::size_t size) { return size == 0 || size == 3 * triangles; };
  require(channel_ok(mesh.corners.normals.size()), where + ": normals channel size");
  require(channel_ok(mesh.corners.uvs.size()), where + ": uv channel size");
  require(channel_ok(mesh.corners.tangents.size()), where + ": tangent channel size");
  std::vector<bool> used(mesh.positions.size(), false);
  for (const Triangle& triangle : mesh.triangles) {
    for (const VertexIndex v : triangle) {
      require(v < mesh.positions.size(), where + ": triangle index out of range");
      used[v] = true;
    }
  }
  for (std::size_t v = 0; v < used.size(); ++v) {
    require(used[v], where + ": vertex " + std::to_string(v) + " is unused");
  }
}

bool try_read(std::string_view bytes, MeshFormat format, Mesh& mesh) {
  const std::string where = "read " + std::string(format_name(format));
  try {
    mesh = read_mesh_from_bytes(bytes, format);
  } catch (const InvalidMeshError&) {
    return false;
  } catch (...) {
    fail_on_exception(where);
  }
  check_mesh_invariants(mesh, where);
  return true;
}

void check_read_round_trip(std::string_view bytes, MeshFormat format) {
  Mesh mesh;
  if (!try_read(bytes, format, mesh)) return;
  const std::string name(format_name(format));
  std::string written;
  try {
    written = write_mesh_to_bytes(mesh, format);
  } catch (...) {
    fail_on_exception("write " + name + " of a mesh the reader accepted");
  }
  Mesh reread;
  try {
    reread = read_mesh_from_bytes(written, format);
  } catch (...) {
    fail_on_exception("reading back the " + name + " written from an accepted mesh");
  }
  const std::string where = name + " round trip";
  require(reread.triangles == mesh.triangles, where + ": triangles differ");
  require(same_channel(reread.positions, mesh.positions, [](const Vec3& a, const Vec3& b) { return same_bits(a, b); }),
          where + ": positions differ");
  if (format == MeshFormat::obj) {
    // io.hpp promises positions bit for bit; attributes are written "each distinct
    // value once", so a -0.0 may come back as 0.0: compare them as numbers.
    const auto same_value = [](double a, double b) { return a == b || same_bits(a, b); };
    require(same_channel(reread.corners.normals, mesh.corners.normals,
                         [&](const Vec3& a, const Vec3& b) {
                           return same_value(a.x, b.x) && same_value(a.y, b.y) && same_value(a.z, b.z);
                         }),
            where + ": normals differ");
    require(same_channel(reread.corners.uvs, mesh.corners.uvs,
                         [&](const Vec2& a, const Vec2& b) { return same_value(a.x, b.x) && same_value(a.y, b.y); }),
            where + ": uvs differ");
  }
}

}  // namespace shatter::fuzz
