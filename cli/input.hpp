#pragma once
// The input mesh of validate, slice and fracture: read, repaired when --repair
// asks, and checked once. The check is the full one (validate_mesh, the
// self-intersection test included) and the most expensive step before the first
// cut, so after it the command tells the library the mesh is trusted
// (BuildRunOptions::input_validated, SolidMeshOptions::trusted) instead of letting it
// check again. Without --repair none of this changes the mesh.

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "shatter/cut/plane_input.hpp"
#include "shatter/kernel/mesh.hpp"
#include "shatter/kernel/repair.hpp"
#include "shatter/kernel/validate.hpp"

namespace shatter::cli {

/// The --help text of a command's --repair flag, with `then`, the command's own
/// consequence, appended.
std::string repair_flag_help(const std::string& then);

/// A mesh as a command received it.
struct InputMesh {
  Mesh mesh;                           ///< as read, or as repaired with --repair
  std::optional<RepairReport> repair;  ///< with --repair: what repair_mesh changed and could not do
  /// What the reader accepted that the format's letter does not (read_mesh's
  /// warnings), one line each; also printed on stderr as "warning: <path>: ...".
  std::vector<std::string> read_warnings;
};

/// The input of slice and fracture: reads `path` (printing the reader's warnings
/// on stderr); with `repair`, repairs it
/// (repair_mesh with the default options and the exact self-intersection step,
/// RepairOptions::round_solid = round_repaired_solid), printing one "repair: ..." line per
/// change and per step not done on stderr; then refuses it unless it is a valid
/// solid, as require_valid_solid(mesh, path, allow_self_intersections) decides.
/// Guarantees: the returned mesh passed that check, so a caller may tell the
/// libraries not to repeat it. (With --repair the input is checked twice, once
/// inside repair_mesh to decide what to repair and once here on the result:
/// repair_mesh does not report what its check found.)
/// Throws IoError or InvalidMeshError from read_mesh; InvalidMeshError "invalid
/// mesh <path>: <summary>" for a mesh that is not a valid solid, with
/// " (after --repair)" appended when it was repaired, or no_volume_refusal's line
/// when repair found that it encloses no volume.
InputMesh read_valid_solid(const std::string& path, bool repair, bool allow_self_intersections);

/// A mesh as read_valid_solid returns it, and made ready for the plane kernel.
struct PreparedSolid {
  InputMesh input;
  PlaneInput plane;  ///< prepare_plane_input(input.mesh)
};

/// read_valid_solid, with the mesh also prepared for the plane kernel beside its
/// check (prepare_plane_input_beside: the two in parallel in the caller's task
/// arena, so on two threads the preparation costs no time after the check), for
/// a caller that hands it to the builder (BuildRunOptions::prepared).
/// Guarantees and failures: read_valid_solid's (its refusal wins over anything
/// the preparation throws), and prepare_plane_input's on a mesh that passed.
PreparedSolid read_prepared_solid(const std::string& path, bool repair, bool allow_self_intersections);

/// The one refusal of a repaired mesh that encloses no volume: "invalid mesh <path>
/// after --repair: encloses no volume: <report.no_volume_reason> (what is left: <defects>)",
/// `defects` being what validation names in the repaired mesh (the
/// self-intersections the exact step could not resolve). Named first since no
/// repair can make a solid of it, whatever else is wrong.
std::string no_volume_refusal(const std::string& path, const RepairReport& report, const std::string& defects);

/// A mesh as a command received it, with its validation report.
struct ValidatedMesh {
  InputMesh input;
  ValidationReport report;  ///< of input.mesh, self-intersections checked
};

/// The input of validate, which reports defects rather than refusing: reads
/// `path`, repairs it when `repair` (as read_valid_solid does), and validates
/// the result once (validate_mesh, self-intersections included).
/// Throws IoError or InvalidMeshError from read_mesh only.
ValidatedMesh read_and_validate(const std::string& path, bool repair);

/// Adds to a command's JSON output "repair" (one {"change", "count", "text"}
/// object per change, in step order) and "repair_not_done" (the texts of the
/// steps not done).
void add_repair_json(nlohmann::ordered_json& out, const RepairReport& report);

}  // namespace shatter::cli
