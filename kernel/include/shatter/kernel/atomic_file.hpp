#pragma once
// Files written in pieces and published whole: write_file_atomically (io.hpp)
// for output too large to hold in memory at once, such as a .shatter file of a
// million fragments.

#include <filesystem>
#include <functional>
#include <string_view>

namespace shatter {

/// Where a producer hands the bytes of a file, piece by piece, in order.
using ByteSink = std::function<void(std::string_view)>;

/// Writes to `path` atomically what `produce` hands its sink: the pieces go to a
/// temporary file beside `path`, renamed over it once `produce` returns, so
/// `path` is either untouched or complete, and no piece need outlive its call.
/// Throws IoError ("cannot write <path>: <reason>") when the file cannot be
/// created, written or renamed, and rethrows whatever `produce` throws; either
/// way the temporary is removed and `path` is as it was.
void write_file_atomically_in_pieces(const std::filesystem::path& path, const std::function<void(const ByteSink&)>& produce);

}  // namespace shatter
