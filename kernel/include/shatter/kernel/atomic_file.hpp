#pragma once
// Files written in pieces and published whole: write_file_atomically (io.hpp)
// for output too large to hold in memory at once, such as a .shatter file of a
// million fragments.

#include <cstdint>
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

/// Where a producer hands a file's bytes in order and may go back over bytes it
/// handed earlier: a header whose length and checksum are known only once what
/// follows it has been written can then be written ahead as a placeholder and
/// replaced, so what follows need not be held in memory meanwhile.
struct RewritableSink {
  /// Appends the bytes at the end.
  ByteSink append;
  /// Replaces bytes already appended, from byte `offset` of the file on.
  /// Precondition: offset + bytes.size() is at most the bytes appended so far.
  std::function<void(std::uint64_t offset, std::string_view bytes)> overwrite;
};

/// write_file_atomically_in_pieces with a sink that may also replace bytes it
/// was given (RewritableSink). Same guarantees and exceptions.
void write_file_atomically_rewritable(const std::filesystem::path& path, const std::function<void(const RewritableSink&)>& produce);

}  // namespace shatter
